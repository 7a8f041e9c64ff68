"""Rigid vs flexible model on identical inputs (:cite:`seed000,seed001`'s comparison).

>>> from flexrv.studies.compare import run_compare                      # doctest: +SKIP
>>> cmp = run_compare("rv221", t_end=0.4, parts=("main_bearing",))    # doctest: +SKIP
>>> cmp.numbers["flexible"]["te_pp_arcsec"]                         # doctest: +SKIP

Both runs use the same design, drive, load program and step; they differ only in
the model (``"rigid"``: 5-DOF main-bearing element, rigid crankshafts;
``"flexible"``: the parts named in ``parts`` flexible, see
:func:`flexrv.model.factory.build_flexible`). Written under ``out_dir``: the two
result folders (``rigid/``, ``flexible/``: NetCDF, config, PNGs, summary.md),
``te_overlay.png``, ``te_spectrum.png`` (characteristic frequencies marked),
``ball_loads.png`` and ``ring_deformation.png`` (if the flexible model has a
ball-resolved bearing), ``summary.md`` (rigid vs flexible table in the style of
:cite:`seed000,seed001`) and ``compare.json``.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_write_text, to_jsonable

#: the reducer :cite:`seed000,seed001` simulate (their TE values are a reference for this preset only)
SEED_REDUCER = "rv221"
#: :cite:`seed000,seed001`: TE range [arcsec] and period [s] of the rigid and the flexible-bearing model
SEED_TE = {
    "rigid": {"te_min_arcsec": -25.2, "te_max_arcsec": 21.6, "period_s": 0.15},
    "flexible": {"te_min_arcsec": -43.2, "te_max_arcsec": 45.0, "period_s": 0.28},
}


@dataclass
class CompareResult:
    """Outputs of :func:`run_compare`."""

    out_dir: Path
    rigid: object  #: Results
    flexible: object  #: Results
    numbers: dict = field(default_factory=dict)
    files: list = field(default_factory=list)


def seed_reference(reducer) -> dict | None:
    """:cite:`seed000,seed001`'s TE ranges and periods if ``reducer`` is the reducer they simulate
    (preset :data:`SEED_REDUCER`, RV-221), else None: another design has no seed reference."""
    name = getattr(reducer, "name", reducer)
    return SEED_TE if str(name) == SEED_REDUCER else None


def te_numbers(res) -> dict:
    """TE statistics over the steady window, dominant TE frequency/period from the
    amplitude spectrum, and the bearing extremes of one run (JSON-ready)."""
    from flexrv.post.spectra import te_spectrum

    s = res.summary()
    freq, amp, marks = te_spectrum(res)
    out = {
        key: s[key]
        for key in (
            "te_min_arcsec",
            "te_max_arcsec",
            "te_pp_arcsec",
            "te_mean_arcsec",
            "te_rms_fluctuation_arcsec",
            "ratio_simulated_over_theoretical",
            "steady_window_s",
            "steady_state",
            "steady_note",
        )
    }
    out["spectrum_window_s"] = float(s["steady_window_s"][1] - s["steady_window_s"][0])
    out["spectrum_resolution_hz"] = float(freq[1] - freq[0]) if len(freq) > 1 else None
    if len(freq) > 2:
        k = 1 + int(np.argmax(amp[1:]))
        out["dominant_frequency_hz"] = float(freq[k])
        out["dominant_period_s"] = float(1.0 / freq[k]) if freq[k] > 0 else None
        out["dominant_amplitude_arcsec"] = float(amp[k])
    out["characteristic_frequencies_hz"] = marks
    for key in (
        "max_ball_load_N",
        "max_ring_deformation_m",
        "max_inner_ring_deformation_m",
        "min_film_thickness_m",
        "max_ball_pressure_Pa",
    ):
        if key in s:
            out[key] = s[key]
    te = res["te"].values
    out["te_whole_run_min_arcsec"] = float(te.min())
    out["te_whole_run_max_arcsec"] = float(te.max())
    return out


def compare_numbers(rigid, flexible, seed: dict | None = None) -> dict:
    """Numbers of both runs and their differences; ``seed``: the seeds' reference
    (:func:`seed_reference`) or None."""
    nr, nf = te_numbers(rigid), te_numbers(flexible)
    return {
        "rigid": nr,
        "flexible": nf,
        "difference": {
            "te_pp_arcsec": nf["te_pp_arcsec"] - nr["te_pp_arcsec"],
            "te_mean_arcsec": nf["te_mean_arcsec"] - nr["te_mean_arcsec"],
        },
        "seed": seed,
    }


def period_note(periods: dict, tolerance: float = 0.1, seed: dict | None = SEED_TE) -> str:
    """Which characteristic period (or its double/half) each seed period matches (within ``tolerance``)."""
    out = []
    for model, seed in (seed or {}).items():
        best = None
        for name, t in periods.items():
            for factor, label in ((1.0, ""), (2.0, "2 x "), (0.5, "1/2 x ")):
                err = abs(seed["period_s"] / (factor * t) - 1.0)
                if best is None or err < best[0]:
                    best = (err, f"{label}{name} period {factor * t:.4g} s")
        if best is not None and best[0] <= tolerance:
            out.append(
                f"The seed's {model}-model period {seed['period_s']} s matches the {best[1]} ({100 * best[0]:.0f} %)."
            )
        else:
            out.append(
                f"The seed's {model}-model period {seed['period_s']} s matches no characteristic period of the drive."
            )
    return " ".join(out)


def summary_markdown(reducer, parts, numbers: dict, timing: dict) -> str:
    """summary.md: rigid vs flexible table, with :cite:`seed000,seed001`'s values only for their
    reducer (``numbers["seed"]``), and notes computed from the numbers in the table."""
    nr, nf = numbers["rigid"], numbers["flexible"]
    seed_ref = numbers.get("seed")

    def f(x, fmt=".2f"):
        return "–" if x is None else format(x, fmt)

    lines = [f"# Rigid vs flexible model: {reducer.name}", ""]
    if not (nr.get("steady_state", True) and nf.get("steady_state", True)):
        lines += [f"> **NOT STEADY**: {nr.get('steady_note') or nf.get('steady_note')}", ""]
    lines += [
        f"Flexible parts: {', '.join(parts)}. Identical design, drive, load program and step. "
        f"Steady window: {nr['steady_window_s'][0]:.3f}-{nr['steady_window_s'][1]:.3f} s"
        + (f" ({nr['steady_note']})" if nr.get("steady_state", True) and nr.get("steady_note") else "")
        + ".",
        "",
    ]
    head = "| model | TE min [arcsec] | TE max [arcsec] | TE p-p [arcsec] | TE mean [arcsec] | dominant period [s] |"
    rule = "|---|---|---|---|---|---|"
    if seed_ref:
        head += " seed000/seed001 TE range [arcsec] | seed period [s] |"
        rule += "---|---|"
    lines += [head, rule]
    for name, n in (("rigid", nr), ("flexible", nf)):
        row = (
            f"| {name} | {f(n['te_min_arcsec'])} | {f(n['te_max_arcsec'])} | {f(n['te_pp_arcsec'])} | "
            f"{f(n['te_mean_arcsec'])} | {f(n.get('dominant_period_s'), '.4g')} |"
        )
        if seed_ref:
            seed = seed_ref[name]
            row += f" {seed['te_min_arcsec']} .. {seed['te_max_arcsec']} | {seed['period_s']} |"
        lines.append(row)
    lines.append("")
    if "max_ball_load_N" in nf:
        lines += [
            "| flexible bearing (steady window) | value |",
            "|---|---|",
            f"| max ball load [N] | {f(nf['max_ball_load_N'], '.1f')} |",
        ]
        if "max_ring_deformation_m" in nf:
            lines.append(
                f"| max outer-ring deflection at the most-loaded ball [µm] | "
                f"{f(1e6 * nf['max_ring_deformation_m'], '.3f')} |"
            )
        if "max_inner_ring_deformation_m" in nf:
            lines.append(
                f"| max inner-ring deflection at the most-loaded ball [µm] | "
                f"{f(1e6 * nf['max_inner_ring_deformation_m'], '.3f')} |"
            )
        if nf.get("min_film_thickness_m") is not None:
            lines.append(
                f"| min central EHL film of the loaded balls [µm] | {f(1e6 * nf['min_film_thickness_m'], '.3f')} |"
            )
        lines.append("")
    marks = nr["characteristic_frequencies_hz"]
    lines += [
        "Characteristic frequencies [Hz]: "
        + ", ".join(f"{k.replace('_', ' ')} {v:.4g}" for k, v in marks.items())
        + ".",
        "",
    ]
    if nr.get("spectrum_resolution_hz"):
        lines += [
            f"Spectrum: steady window of {nr['spectrum_window_s']:.4g} s, resolution "
            f"{nr['spectrum_resolution_hz']:.3g} Hz (Hann window).",
            "",
        ]
    periods = {k: 1.0 / v for k, v in marks.items() if v > 0}
    d_mean = nf["te_mean_arcsec"] - nr["te_mean_arcsec"]
    d_pp = nf["te_pp_arcsec"] - nr["te_pp_arcsec"]
    text = (
        f"TE mean {f(nr['te_mean_arcsec'])} arcsec rigid, {f(nf['te_mean_arcsec'])} arcsec flexible "
        f"({d_mean:+.3g} arcsec); ripple {f(nr['te_pp_arcsec'])} / {f(nf['te_pp_arcsec'])} arcsec "
        f"peak-to-peak ({d_pp:+.3g} arcsec). In flexrv the loaded TE is the offset of the torque path "
        "(clearances closed in the load direction plus the elastic wind-up) with a ripple about it."
    )
    if "max_ring_deformation_m" in nf:
        text += (
            f" The ring deflection under the most-loaded ball is {1e6 * nf['max_ring_deformation_m']:.3g} µm "
            "(outer ring) in this run."
        )
    if seed_ref:
        text += (
            " seed000/seed001 report TE ranges of "
            f"{seed_ref['rigid']['te_min_arcsec']} .. {seed_ref['rigid']['te_max_arcsec']} arcsec (rigid) and "
            f"{seed_ref['flexible']['te_min_arcsec']} .. {seed_ref['flexible']['te_max_arcsec']} arcsec "
            "(flexible main bearing) for this reducer. " + period_note(periods, seed=seed_ref)
        )
    else:
        text += f" No seed reference: seed000/seed001 simulate the {SEED_REDUCER} only, not {reducer.name}."
    lines += [
        text,
        "",
        f"Wall time: rigid {timing.get('rigid_s', 0):.1f} s, flexible {timing.get('flexible_s', 0):.1f} s "
        f"(including model build: meshing and CMS if not cached).",
        "",
        "## References",
        "",
        "Seed studies: keys `seed000` and `seed001` of `docs/references.md` in the flexrv repository.",
        "",
    ]
    return "\n".join(lines)


def run_compare(
    preset_or_reducer,
    t_end: float | None = None,
    parts=("main_bearing",),
    out_dir=None,
    dt: float | None = None,
    progress=False,
    flexible_options: dict | None = None,
) -> CompareResult:
    """Run the rigid and the flexible model on identical inputs; write plots,
    summary.md and compare.json under ``out_dir`` (see module docstring).
    ``flexible_options``: further builder options of the flexible model, e.g.
    ``{"ring_options": {"size": 0.006}}`` (:func:`flexrv.model.factory.build_flexible`)."""
    from flexrv.design import load
    from flexrv.model.factory import parse_parts
    from flexrv.simulation import DEFAULT_DT, Simulation
    from flexrv.viz import compare_plots

    reducer = load(preset_or_reducer)
    parts = parse_parts(parts)
    dt = DEFAULT_DT if dt is None else dt
    out = (
        Path(out_dir)
        if out_dir is not None
        else Path("results") / f"{reducer.name}_compare_{time.strftime('%Y%m%d-%H%M%S')}"
    )
    out.mkdir(parents=True, exist_ok=True)
    runs, timing = {}, {}
    flex_opts = {"parts": parts, **(flexible_options or {})}
    # the rigid reference has no elastic part at all: --parts names every elastic part of the flexible run
    for name, model, options in (("rigid", "rigid", {"bodies": ()}), ("flexible", "flexible", flex_opts)):
        t0, c0 = time.perf_counter(), time.process_time()
        sim = Simulation(reducer, model=model, model_options=options)
        res = sim.run(t_end=t_end, dt=dt, progress=progress, save_to=out / name)
        res.save(out / name)
        timing[f"{name}_s"] = time.perf_counter() - t0
        timing[f"{name}_cpu_s"] = time.process_time() - c0  # this process's CPU (BLAS pinned to one thread)
        for key in ("build_s", "solve_s", "solve_cpu_s"):  # model build (meshing + CMS if not cached), integration
            timing[f"{name}_{key}"] = float(sim.timing.get(key, 0.0))
        runs[name] = res
    numbers = compare_numbers(runs["rigid"], runs["flexible"], seed=seed_reference(reducer))
    numbers["parts"] = list(parts)
    numbers["timing"] = timing
    files = [
        compare_plots.plot_te_overlay(runs["rigid"], runs["flexible"], out / "te_overlay.png"),
        compare_plots.plot_te_spectra(runs["rigid"], runs["flexible"], out / "te_spectrum.png"),
    ]
    if "ball_load_inner" in runs["flexible"]:
        files.append(compare_plots.plot_ball_loads(runs["flexible"], out / "ball_loads.png"))
    if "ring_deformation_outer" in runs["flexible"]:
        files.append(compare_plots.plot_ring_deformation(runs["flexible"], out / "ring_deformation.png"))
    atomic_write_text(out / "summary.md", summary_markdown(reducer, parts, numbers, timing))
    atomic_write_text(out / "compare.json", json.dumps(to_jsonable(numbers), indent=2))
    files += [out / "summary.md", out / "compare.json"]
    return CompareResult(out_dir=out, rigid=runs["rigid"], flexible=runs["flexible"], numbers=numbers, files=files)
