"""Rigid vs flexible main bearing: TE ranges, periods and spectra (:cite:`seed000,seed001`, rv221).

:cite:`seed000,seed001` compare a fully rigid RV reducer model with one whose main-bearing
rings are flexible (and lubricated): TE from -25.2..21.6 arcsec (period 0.15 s)
to -43.2..45.0 arcsec (period 0.28 s). flexrv runs :func:`flexrv.studies.compare.
run_compare` on the rv221 preset — the rigid model (5-DOF main-bearing element)
and the flexible model (ball-resolved bearing, reduced flexible inner and outer
rings of both rows, Hamrock–Dowson EHL contacts) on identical inputs — and puts
its numbers beside the seeds'.

Run: ``python -m flexrv.workflows.rigid_vs_flexible`` or ``flexrv workflow rigid_vs_flexible``.
"""

from __future__ import annotations

from flexrv.workflows._common import WorkflowResult

NAME = "rigid_vs_flexible"
PRESET = "rv221"
#: :cite:`seed001`: main-bearing ball contact force at start-up (< 200 N) and steady mean (93.7 N)
SEED_BALL_FORCE = {"startup_max_N": 200.0, "steady_mean_N": 93.7}
SMOKE = {"t_end": 0.01, "flexible_options": {"ring_options": {"size": 0.015}}}
#: full run [s]: ramps end at 0.2 s; 0.6 s of steady state resolve the crank rotation (6.8 Hz) in the spectrum
T_END = 0.8


def run(out_dir=None, smoke: bool = False, preset: str = PRESET, t_end: float | None = None) -> WorkflowResult:
    """:cite:`seed000,seed001` rigid-vs-flexible comparison; saves to ``results/rigid_vs_flexible``."""
    import numpy as np

    from flexrv.design import load
    from flexrv.studies.compare import run_compare, seed_reference
    from flexrv.workflows._common import default_out

    red = load(preset)
    out = default_out(NAME, smoke) if out_dir is None else out_dir
    options = SMOKE["flexible_options"] if smoke else None
    if t_end is None:
        t_end = SMOKE["t_end"] if smoke else T_END
    cmp = run_compare(red, t_end=t_end, out_dir=out, flexible_options=options)
    nr, nf = cmp.numbers["rigid"], cmp.numbers["flexible"]
    r = WorkflowResult(
        NAME,
        f"Rigid vs flexible main bearing: TE of the {red.name}",
        ["000 (rigid vs compliant-bearing TE)", "001 (flexible main bearing, contact forces)"],
        smoke=smoke,
    )
    ref = seed_reference(red)  # the seeds' values only for their reducer (rv221)
    for model in ("rigid", "flexible"):
        n, seed = cmp.numbers[model], (ref or {}).get(model)
        r.compare(
            f"TE range, {model} model",
            "arcsec",
            f"{seed['te_min_arcsec']} .. {seed['te_max_arcsec']}" if seed else None,
            f"{n['te_min_arcsec']:.2f} .. {n['te_max_arcsec']:.2f}",
            "flexrv: steady window after the speed and load ramps"
            + ("" if seed else f"; no seed value: seed000/seed001 simulate the rv221, not {red.name}"),
        )
        r.compare(
            f"TE period, {model} model",
            "s",
            seed["period_s"] if seed else None,
            n.get("dominant_period_s"),
            "flexrv: period of the largest TE spectral peak",
        )
    loads = cmp.flexible["ball_load_inner"]
    t0, _ = cmp.flexible.steady_window()
    startup = loads.sel(time=slice(None, t0)).values
    steady = loads.sel(time=slice(t0, None)).values
    r.compare(
        "ball contact force at start-up (max)",
        "N",
        f"< {SEED_BALL_FORCE['startup_max_N']:.0f}",
        float(startup.max()) if startup.size else None,
        "inner raceway, all balls of both rows",
    )
    r.compare(
        "ball contact force, steady (mean of the loaded balls)",
        "N",
        SEED_BALL_FORCE["steady_mean_N"],
        float(steady[steady > 0].mean()) if (steady > 0).any() else None,
        "flexrv: the preload plus the 20 N m load share; no external load in this case",
    )
    r.text.append((cmp.out_dir / "summary.md").read_text().split("\n", 2)[2])
    r.text.append(
        "flexrv: the flexible main bearing changes the steady TE range by "
        f"{nf['te_pp_arcsec'] - nr['te_pp_arcsec']:+.2f} arcsec peak-to-peak and its mean by "
        f"{nf['te_mean_arcsec'] - nr['te_mean_arcsec']:+.2f} arcsec; the seeds' "
        "near-doubling of the TE range is not reproduced (see the ring_deformation workflow for why: fit-clamped "
        "rings deform locally by ~1 um; what moves TE is the carrier's shift under external load)."
    )
    r.text.append("\n\n".join(f"![{p.stem}]({p.name})" for p in cmp.files if p.suffix == ".png"))
    r.numbers = {k: cmp.numbers[k] for k in ("rigid", "flexible", "difference")}
    import xarray as xr

    r.datasets["te_rigid_vs_flexible"] = xr.Dataset(
        {"te_rigid": cmp.rigid["te"], "te_flexible": cmp.flexible["te"].interp(time=cmp.rigid.time)}
    )
    r.numbers["te_rms_difference_arcsec"] = float(
        np.sqrt(
            np.mean(
                (r.datasets["te_rigid_vs_flexible"]["te_flexible"] - r.datasets["te_rigid_vs_flexible"]["te_rigid"])
                ** 2
            )
        )
    )
    r.save(out)
    return r


if __name__ == "__main__":
    print(run().out_dir)
