"""Profile-modification design of rv40e over its ISO grade-5 tolerance set.

The disc's equidistant and shift modifications of rv40e are searched
(:func:`flexrv.studies.optimize.run_optimize`, NSGA-II on dask) for the Pareto front of
three batch figures over the tolerance set ``flexrv/design/presets/tolerances/rv40e.toml``
(ISO 286-2 IT5 and ISO 1328-1 grade 5, every entry with its source), the same draws for
every design:

* P95 lost motion (+-3 % rated torque) against the catalog's 1 arcmin (Nabtesco RV-E);
* median torsional rigidity at rated torque;
* P95 of the largest Hertz pressure of the pin-disc contacts at rated torque, beside the
  fatigue-limit contact stress 1500 MPa of ISO 281 (:cite:`iso281`, the stress at a
  bearing steel's fatigue load limit);

under the constraint that no pin is preloaded at assembly in at least 99 % of the builds
(``no_preload_yield >= 0.99``: the assembly interference of
:func:`flexrv.geometry.as_built.assembly_penetration` is <= 0). The preset's own point
(5 um equidistant, no shift) is evaluated with the same draws and marked; the recommended
designs are re-evaluated at the full resolution and their yields (no preload; lost motion
<= 1 arcmin) are set against the preset's.

The full run (80 designs x 16 draws) took 25 min on 2 cores shared with other jobs (load
average 10-20; docs/optimize.md gives its result); ``--smoke`` runs 4
designs x 2 draws (a check that the workflow runs, not a result).

Run: ``flexrv workflow modification_design`` or ``python -m flexrv.workflows.modification_design``.
"""

from __future__ import annotations

from flexrv.workflows._common import WorkflowResult

NAME = "modification_design"
PRESET = "rv40e"
VARY = ["second_stage.modification_equidistant_mm=0:0.015", "second_stage.modification_shift_mm=-0.015:0.015"]
OBJECTIVES = ["lost_motion_p95_arcmin:min", "rigidity_median_Nm_per_arcmin:max", "pin_contact_pressure_p95_MPa:min"]
CONSTRAINTS = ["no_preload_yield >= 0.99"]
SPECS = ["lost_motion_arcmin<=1"]
#: catalog lost-motion limit [arcmin] (Nabtesco RV-E catalog, as the tolerance_study workflow)
CATALOG_LOST_MOTION_ARCMIN = 1.0
#: contact stress at the fatigue load limit of bearing steel [MPa] (ISO 281:2007)
ISO281_FATIGUE_STRESS_MPA = 1500.0
FULL = {"budget": 80, "samples": 16, "population": 20}
SMOKE = {"budget": 4, "samples": 2, "population": 2}


def run(
    out_dir=None,
    smoke: bool = False,
    budget: int | None = None,
    samples: int | None = None,
    workers: int | None = None,
    seed: int = 0,
    mode: str = "dask",
) -> WorkflowResult:
    """The modification design of rv40e; saves to ``results/modification_design`` (the search's
    own files under ``search/`` there)."""
    from pathlib import Path

    from flexrv.errors import InputError
    from flexrv.studies.optimize import OptimizeConfig, run_optimize
    from flexrv.workflows._common import default_out

    size = dict(SMOKE if smoke else FULL)
    if budget is not None:
        size["budget"] = budget
    if samples is not None:
        size["samples"] = samples
    out = Path(out_dir) if out_dir else default_out(NAME, smoke)
    r = WorkflowResult(
        NAME,
        "Profile-modification design: lost motion, rigidity and pin contact pressure of an rv40e batch",
        ["Nabtesco RV-E catalog (lost motion)", "ISO 281:2007 (iso281, fatigue-limit contact stress)"],
        smoke=smoke,
    )
    cfg = OptimizeConfig(
        design=PRESET,
        tolerances=PRESET,
        vary=list(VARY),
        objectives=list(OBJECTIVES),
        constraints=list(CONSTRAINTS),
        specs=list(SPECS),
        samples_per_design=size["samples"],
        budget=size["budget"],
        population=size["population"],
        seed=seed,
        workers=workers,
        out=str(out / "search"),
    )
    try:
        res = run_optimize(cfg, progress=False, mode=mode)
        infeasible = None
    except InputError as exc:  # no design meets the constraint: the outputs are written, say which
        import json

        res = json.loads((out / "search" / "summary.json").read_text())
        infeasible = str(exc)
    _report(r, res, infeasible, size)
    r.numbers = {
        "preset": res["preset"],
        "recommended": res["recommended"],
        "pareto_points": len(res["pareto"]),
        "lost_motion_target": res.get("lost_motion_target"),
        "yield_gain": res.get("yield_gain"),
        "infeasible": infeasible,
    }
    r.save(out)
    return r


def _report(r: WorkflowResult, res: dict, infeasible: str | None, size: dict) -> None:
    """Comparison rows, the recommended-design table and the verdicts."""
    pre = res["preset"]
    pre_full = pre.get("full", pre)
    lm, k, p = "lost_motion_p95_arcmin", "rigidity_median_Nm_per_arcmin", "pin_contact_pressure_p95_MPa"
    r.compare(
        "P95 lost motion of the preset's batch",
        "arcmin",
        f"<= {CATALOG_LOST_MOTION_ARCMIN:g} (catalog)",
        pre_full.get(lm),
        f"rv40e as given (5 um equidistant), {size['samples']} draws, full resolution",
    )
    r.compare(
        "P95 pin contact pressure of the preset's batch",
        "MPa",
        f"{ISO281_FATIGUE_STRESS_MPA:g} (ISO 281 fatigue-limit stress)",
        pre_full.get(p),
        "Hertz line contact of the most loaded pin at rated torque",
    )
    rows = [("as given", pre)] + list(res["recommended"].items())
    r.tables["recommended designs (search / full re-evaluation, same draws)"] = [
        {
            "design": label,
            "equidistant [mm]": q.get("second_stage.modification_equidistant_mm"),
            "shift [mm]": q.get("second_stage.modification_shift_mm"),
            "P95 lost motion [arcmin]": q.get(lm),
            "P95 LM, full": q.get("full", {}).get(lm),
            "median rigidity [N m/arcmin]": q.get(k),
            "rigidity, full": q.get("full", {}).get(k),
            "P95 pin pressure [MPa]": q.get(p),
            "pressure, full": q.get("full", {}).get(p),
            "no-preload yield": q.get("full", q).get("no_preload_yield"),
            "yield LM <= 1'": q.get("full", q).get("spec_yield"),
            "nominal lost motion [arcmin]": q.get("lost_motion_nominal_arcmin"),
        }
        for label, q in rows
    ]
    r.tables["Pareto set"] = [
        {
            "equidistant [mm]": q.get("second_stage.modification_equidistant_mm"),
            "shift [mm]": q.get("second_stage.modification_shift_mm"),
            "P95 lost motion [arcmin]": q.get(lm),
            "median rigidity [N m/arcmin]": q.get(k),
            "P95 pin pressure [MPa]": q.get(p),
            "no-preload yield": q.get("no_preload_yield"),
        }
        for q in res["pareto"]
    ]
    text = (
        f"{res['evaluations']} modifications evaluated ({res['feasible']} meet no_preload_yield >= 0.99), "
        f"{size['samples']} builds each from the grade-5 tolerance set, the same draws for every design."
    )
    if infeasible:
        text += f" No design meets the constraints: {infeasible}."
    target = res.get("lost_motion_target")
    if target:
        text += f" Lost-motion target: {target['verdict']}."
    gain = res.get("yield_gain", {}).get("balanced")
    if gain:
        text += " Yields of the balanced design against the preset: " + ", ".join(
            f"{y} {v['preset']:.3f} -> {v['design']:.3f}" for y, v in gain.items() if v["preset"] is not None
        )
        text += "."
    r.text.append(text)
    if res.get("plots"):
        r.text.append(f"Pareto plot: {res['plots'][0]} (the preset marked by a star).")


if __name__ == "__main__":
    import sys

    smoke = "--smoke" in sys.argv
    print(run(smoke=smoke).save())
