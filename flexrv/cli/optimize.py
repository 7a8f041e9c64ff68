"""CLI: ``flexrv optimize DESIGN`` — profile-modification design: a Pareto front of batch
figures over the production tolerances (NSGA-II on dask)."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table, split_unit

PRESET_HELP = "Preset name or design TOML (its [tolerances] table is used unless --tolerances is given)."


def optimize(
    design: str = typer.Argument(..., help=PRESET_HELP),
    vary: Optional[List[str]] = typer.Option(
        None, "--vary", help="FIELD=LO:HI, a numeric design field and its range (repeatable)."
    ),
    objective: Optional[List[str]] = typer.Option(
        None,
        "--objective",
        help="NAME[:min|max], a batch metric <quantity>_<stat>_<unit>, e.g. lost_motion_p95_arcmin:min (repeatable).",
    ),
    constraint: Optional[List[str]] = typer.Option(
        None, "--constraint", help='Inequality of metrics, e.g. "pin_contact_pressure_p95_MPa <= 1900" (repeatable).'
    ),
    spec: Optional[List[str]] = typer.Option(
        None, "--spec", help="Per-build spec of the metric spec_yield, e.g. lost_motion_arcmin<=1 (repeatable)."
    ),
    tolerances: Optional[str] = typer.Option(
        None, "--tolerances", help="TOML file with a [tolerances] table (or preset name, e.g. rv40e)."
    ),
    samples_per_design: int = typer.Option(
        32, "--samples-per-design", help="Tolerance draws per design (the same draws for every design)."
    ),
    budget: int = typer.Option(200, "--budget", help="Number of designs the search evaluates."),
    population: int = typer.Option(20, "--population", help="NSGA-II population (designs per generation)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the draws and of the search (same seed -> same run)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Address of a running dask scheduler."),
    workers: Optional[int] = typer.Option(
        None, "--workers", help="LocalCluster worker processes (default min(2, CPUs))."
    ),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Output directory (default results/<design>_optimize_s<seed>); a rerun resumes."
    ),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Search a box of design fields (e.g. the disc's equidistant, shift and rotation modifications)
    for the Pareto front of batch objectives (P95 lost motion, median rigidity, P95 pin contact
    pressure, yields) under constraints, over tolerance draws shared by every design. Writes the
    Pareto set (CSV, NetCDF), a plot, the recommended designs' TOML and summary.md. A killed run
    resumes where it stopped (same command)."""
    from flexrv.studies.optimize import OptimizeConfig, run_optimize

    cfg = OptimizeConfig(
        design=design,
        vary=list(vary or []),
        objectives=list(objective or []),
        constraints=list(constraint or []),
        specs=list(spec or []),
        tolerances=tolerances,
        samples_per_design=samples_per_design,
        budget=budget,
        population=population,
        seed=seed,
        scheduler=scheduler,
        workers=workers,
        out=str(out) if out else None,
    )
    result = run_optimize(cfg, progress=not json)
    keys = (
        "design",
        "output_dir",
        "objectives",
        "constraints",
        "variables",
        "samples_per_design",
        "evaluations",
        "feasible",
        "computed_now",
        "reused",
        "wall_time_s",
        "cpu",
        "cheap_error",
        "preset",
        "pareto",
        "recommended",
        "lost_motion_target",
        "yield_gain",
        "designs",
    )
    emit({k: result.get(k) for k in keys}, json, _render)


def _render(d: dict) -> None:
    rows = [(k, d[k], "") for k in ("evaluations", "feasible", "computed_now", "reused", "samples_per_design")]
    rows.append(("wall time", d["wall_time_s"], "s"))
    console.print(kv_table(f"optimize {d['design']} -> {d['output_dir']}", rows))
    objs = [o.split(":")[0] for o in d["objectives"]]
    fields = [v["field"] for v in d["variables"]]
    for label, p in [("as given", d["preset"])] + list(d["recommended"].items()):
        full = p.get("full", {})
        prow = [(f, p.get(f), "") for f in fields]
        prow += [(o + (" (full)" if o in full else ""), full.get(o, p.get(o)), split_unit(o)[1]) for o in objs]
        console.print(kv_table(label, prow))
    lm = d.get("lost_motion_target")
    if lm:
        console.print(lm["verdict"])


def register(app: typer.Typer) -> None:
    """Add ``optimize`` to the app."""
    app.command("optimize")(optimize)
