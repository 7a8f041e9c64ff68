"""Crankshaft flexibility and the TE spectrum (:cite:`seed002`, RV-40E).

:cite:`seed002` runs the RV-40E at 1215 r/min input with a 412 N m load ramp for 0.8 s,
once fully rigid and once with flexible crankshafts (and discs, pins), and finds
in the flexible model's TE spectrum peaks at 2, 3, 4 x the crank rotation
frequency (10 Hz), at the first-stage mesh frequency (320 Hz) and its harmonics
and near the cycloid mesh frequency (390 Hz), while the rigid model shows mainly
the first-stage mesh. flexrv runs :func:`flexrv.studies.compare.run_compare` with the
crankshafts flexible (:mod:`flexrv.model.flexible_crank`: FE-condensed torsion and
gear-seat bending) and compares the spectra at the Table 4 frequencies.

Run: ``python -m flexrv.workflows.crankshaft_flexibility`` or ``flexrv workflow crankshaft_flexibility``.
"""

from __future__ import annotations

import numpy as np

from flexrv.workflows._common import WorkflowResult, new_figure

NAME = "crankshaft_flexibility"
PRESET = "rv40e"
T_END = 0.8  #: :cite:`seed002`'s run length [s]; TE evaluated over 0.2-0.8 s as in the seed
#: :cite:`seed002` Table 4 [Hz]
SEED_TABLE4 = {
    "input shaft": 20.25,
    "crank rotation": 10.0,
    "carrier (crank revolution)": 0.25,
    "first-stage mesh": 320.0,
    "cycloid mesh": 390.0,
    "cycloid gear": 400.0,
    "pin gear": 400.0,
}
SMOKE = {"t_end": 0.03, "crank_options": {"size": 0.004}}


def amplitude_at(freq, amp, f0: float, halfwidth: int = 2) -> float:
    """Largest spectral amplitude within +/- ``halfwidth`` bins of ``f0`` [Hz]."""
    if len(freq) < 3 or f0 > freq[-1]:
        return float("nan")
    k = int(np.argmin(np.abs(freq - f0)))
    return float(amp[max(k - halfwidth, 1) : k + halfwidth + 1].max())


def run(out_dir=None, smoke: bool = False, preset: str = PRESET, t_end: float | None = None) -> WorkflowResult:
    """:cite:`seed002` crankshaft-flexibility study; saves to ``results/crankshaft_flexibility``."""
    import xarray as xr

    from flexrv.design import load
    from flexrv.geometry.kinematics import reducer_kinematics
    from flexrv.post.spectra import te_spectrum
    from flexrv.studies.compare import run_compare
    from flexrv.workflows._common import default_out

    red = load(preset)
    out = default_out(NAME, smoke) if out_dir is None else out_dir
    t_end = (SMOKE["t_end"] if smoke else T_END) if t_end is None else t_end
    options = {"crank_options": SMOKE["crank_options"]} if smoke else None
    cmp = run_compare(red, t_end=t_end, parts=("crankshaft",), out_dir=out, flexible_options=options)
    kin = reducer_kinematics(red)
    cf = kin.frequencies
    r = WorkflowResult(
        NAME,
        f"Crankshaft flexibility and the TE spectrum ({red.name})",
        ["002 (RV-40E rigid-flexible coupling, Table 4, TE spectrum)"],
        smoke=smoke,
    )
    ours = {
        "input shaft": float(cf.input),
        "crank rotation": float(cf.crank_rotation),
        "carrier (crank revolution)": float(cf.carrier),
        "first-stage mesh": float(cf.first_stage_mesh),
        "cycloid mesh": float(cf.cycloid_mesh),
    }
    for name, f0 in ours.items():
        r.compare(f"{name} frequency", "Hz", SEED_TABLE4[name], f0, "kinematics at the rated input speed")
    spectra = {name: te_spectrum(res)[:2] for name, res in (("rigid", cmp.rigid), ("flexible", cmp.flexible))}
    lines = [
        ("crank rotation", cf.crank_rotation),
        ("2 x crank rotation", 2 * cf.crank_rotation),
        ("3 x crank rotation", 3 * cf.crank_rotation),
        ("4 x crank rotation", 4 * cf.crank_rotation),
        ("6 x crank rotation", 6 * cf.crank_rotation),
        ("first-stage mesh", cf.first_stage_mesh),
        ("2 x first-stage mesh", 2 * cf.first_stage_mesh),
        ("cycloid mesh", cf.cycloid_mesh),
    ]
    rows = []
    for label, f0 in lines:
        a_r = amplitude_at(*spectra["rigid"], float(f0))
        a_f = amplitude_at(*spectra["flexible"], float(f0))
        rows.append(
            {
                "line": label,
                "frequency [Hz]": float(f0),
                "rigid [arcsec]": a_r,
                "flexible crank [arcsec]": a_f,
                "flexible/rigid": a_f / a_r if a_r and np.isfinite(a_r) and a_r > 0 else None,
            }
        )
    r.tables["TE amplitude at the characteristic frequencies (steady window)"] = rows
    nr, nf = cmp.numbers["rigid"], cmp.numbers["flexible"]
    if not nr.get("steady_state", True):
        r.text.append(f"**{nr['steady_note']}: the spectra below are not steady-state spectra.**")
    twist = cmp.flexible.steady("crank_twist").values
    r.compare(
        "TE, rigid model (steady)",
        "arcsec",
        "periodic, smaller",
        f"{nr['te_min_arcsec']:.2f} .. {nr['te_max_arcsec']:.2f}",
        "seed002 gives no numbers, only plots",
    )
    r.compare(
        "TE, flexible crankshafts (steady)",
        "arcsec",
        "periodic, larger",
        f"{nf['te_min_arcsec']:.2f} .. {nf['te_max_arcsec']:.2f}",
        f"mean shift {nf['te_mean_arcsec'] - nr['te_mean_arcsec']:+.3f} arcsec",
    )
    info = cmp.flexible.attrs
    r.text.append(
        f"flexrv's crankshaft (FE, gmsh Tet10, condensed): torsional stiffness gear seat -> eccentrics "
        f"{float(info.get('crank_torsional_stiffness_Nm_per_rad', float('nan'))):.4g} N m/rad, lateral "
        f"{float(info.get('crank_lateral_stiffness_N_per_m', float('nan'))):.4g} N/m; lowest shaft mode with its "
        f"interfaces clamped {float(info.get('crank_lowest_clamped_mode_hz', float('nan'))):.4g} Hz (Guyan "
        f"condensation exact below it). Mean crank twist in the steady window "
        f"{1e6 * float(np.mean(twist)):.1f} urad, seen at the output divided by z_c = {red.second_stage.disc_teeth}: "
        f"{float(np.mean(twist)) / red.second_stage.disc_teeth * 180 / np.pi * 3600:.3f} arcsec — the TE mean "
        f"shift of the flexible model ({nf['te_mean_arcsec'] - nr['te_mean_arcsec']:+.3f} arcsec)."
    )
    r.text.append(
        "seed002 attributes the crank-harmonic peaks of its flexible model to crank torsion. In flexrv the crank "
        "twist is a quasi-static wind-up proportional to the crank torque; it changes the TE level by a fraction of "
        "an arcsec and the spectral lines only where the crank torque itself fluctuates (table above: the ratio "
        "flexible/rigid per line). The crank harmonics in flexrv's TE come from the needle-bearing and pin "
        "load cycle that both models share; the first-stage mesh line is present in both. seed002's Table 4 "
        "frequencies are reproduced exactly by the kinematics."
    )
    finite = [row for row in rows if np.isfinite(row["rigid [arcsec]"])]
    if finite:
        top = max(finite, key=lambda row: row["rigid [arcsec]"])
        r.text.append(
            f"Largest of the marked lines in both models: {top['line']} ({top['frequency [Hz]']:.4g} Hz), "
            f"{top['rigid [arcsec]']:.3g} arcsec rigid vs {top['flexible crank [arcsec]']:.3g} arcsec with "
            "flexible crankshafts — the pins entering and leaving the load zone, which the crank twist does "
            "not change; seed002's rigid model shows mainly the first-stage mesh, flexrv's the cycloid "
            "mesh (its involute mesh ripple is filtered by the second-stage ratio)."
        )
    r.text.append(
        f"Largest TE line over the whole steady spectrum: {nr['dominant_frequency_hz']:.4g} Hz "
        f"({nr['dominant_amplitude_arcsec']:.3g} arcsec) rigid, {nf['dominant_frequency_hz']:.4g} Hz "
        f"({nf['dominant_amplitude_arcsec']:.3g} arcsec) with flexible crankshafts."
    )
    r.numbers = {"rigid": nr, "flexible": nf, "lines": rows}
    f_r, a_r = spectra["rigid"]
    f_f, a_f = spectra["flexible"]
    r.datasets["te_spectra"] = xr.Dataset(
        {"amplitude_rigid": ("frequency_rigid", a_r), "amplitude_flexible": ("frequency_flexible", a_f)},
        coords={"frequency_rigid": f_r, "frequency_flexible": f_f},
    )
    fig, ax = new_figure(figsize=(10, 4))
    top = max([float(a[1:].max()) for a in (a_r, a_f) if len(a) > 1] or [1.0])
    floor = top * 1e-4  # four decades below the largest line: the meaningful range
    if len(f_r) > 1:
        ax.semilogy(f_r[1:], np.maximum(a_r[1:], floor), lw=0.8, label="rigid")
    if len(f_f) > 1:
        ax.semilogy(f_f[1:], np.maximum(a_f[1:], floor), lw=0.8, label="flexible crankshafts")
    ax.set_ylim(floor, 3 * top)
    for label, f0 in lines:
        ax.axvline(f0, ls="--", lw=0.6, color="0.4")
        ax.text(f0, 1.0, f" {label}", rotation=90, va="top", fontsize=7, transform=ax.get_xaxis_transform())
    ax.set_xlim(0, 1.3 * max(cf.cycloid_mesh, 2 * cf.first_stage_mesh))
    window = float(np.diff(cmp.rigid.steady_window())[0])
    ax.set_title(
        f"TE spectra: steady window {window:.3g} s, resolution "
        f"{(f_r[1] - f_r[0]) if len(f_r) > 1 else float('nan'):.3g} Hz (Hann)",
        fontsize=9,
    )
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("TE amplitude [arcsec]")
    ax.legend(loc="lower left")
    fig.tight_layout()
    r.figures["te_spectra_table4"] = fig
    r.text.append("\n\n".join(f"![{p.stem}]({p.name})" for p in cmp.files if p.suffix == ".png"))
    r.save(out)
    return r


if __name__ == "__main__":
    print(run().out_dir)
