"""CLI: ``flexrv tolerance DESIGN`` — Monte Carlo tolerance analysis on dask."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table

PRESET_HELP = "Preset name or design TOML (its [tolerances] table is used unless --tolerances is given)."


def tolerance(
    design: str = typer.Argument(..., help=PRESET_HELP),
    samples: int = typer.Option(..., "--samples", help="Number of sampled reducers (Saltelli base N with --sobol)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the sampler (same seed -> identical samples)."),
    sampler: str = typer.Option("sobol", "--sampler", help="random | sobol | lhs."),
    spec: Optional[List[str]] = typer.Option(None, "--spec", help="Spec limit, e.g. te_pp_arcsec<=60 (repeatable)."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Address of a running dask scheduler."),
    workers: Optional[int] = typer.Option(
        None, "--workers", help="LocalCluster worker processes (default min(2, CPUs))."
    ),
    tolerances: Optional[str] = typer.Option(
        None, "--tolerances", help="TOML file with a [tolerances] table (or preset name, e.g. rv40e)."
    ),
    sobol: bool = typer.Option(False, "--sobol", help="Sobol' indices (SALib) on a Saltelli design."),
    what_if_samples: int = typer.Option(
        16, "--what-if-samples", help="Samples re-evaluated per halved/doubled tolerance (0: no what-if table)."
    ),
    crank_revolutions: Optional[float] = typer.Option(
        None, "--crank-revolutions", help="Evaluation range in crank revolutions (default 1)."
    ),
    output_revolutions: Optional[float] = typer.Option(
        None, "--output-revolutions", help="Evaluation range in output revolutions (instead of crank revolutions)."
    ),
    points_per_mesh: int = typer.Option(2, "--points-per-mesh", help="Positions per pin-mesh period (default 2)."),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Output directory (default results/<design>_tolerance_s<seed>)."
    ),
    force: bool = typer.Option(False, "--force", help="Allow more local workers than the machine has CPU cores."),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Distribution of TE p-p, mean TE, lost motion, backlash and rigidity over a batch drawn from the
    tolerances; yield against --spec with its confidence interval; sensitivities and a what-if table.
    A killed study resumes where it stopped (same command). Exit code 1 if any evaluation failed."""
    from flexrv.errors import InputError
    from flexrv.studies.tolerance import DEFAULT_RESOLUTION, StudyConfig, run_study

    if crank_revolutions is not None and output_revolutions is not None:
        raise InputError("--crank-revolutions and --output-revolutions exclude each other: give one")
    res = dict(DEFAULT_RESOLUTION)
    if output_revolutions is not None:
        res["output_revolutions"], res["crank_revolutions"] = output_revolutions, None
    elif crank_revolutions is not None:
        res["crank_revolutions"] = crank_revolutions
    res["points_per_mesh"] = points_per_mesh
    cfg = StudyConfig(
        design=design,
        samples=samples,
        seed=seed,
        sampler=sampler,
        specs=list(spec or []),
        tolerances=tolerances,
        scheduler=scheduler,
        workers=workers,
        sobol=sobol,
        out=str(out) if out else None,
        what_if_samples=what_if_samples,
        resolution=res,
        force=force,
    )
    result = run_study(cfg, progress=not json)
    data = {
        k: result[k]
        for k in (
            "design",
            "output_dir",
            "samples",
            "sampler",
            "seed",
            "variables",
            "evaluations",
            "computed_now",
            "skipped_existing",
            "failed",
            "wall_time_s",
            "resolution",
            "cpu",
            "percentiles",
            "yield",
            "ranked_sensitivities",
            "what_if",
        )
    }

    def render(d):
        rows = [
            (k, d[k], "")
            for k in ("samples", "sampler", "variables", "evaluations", "computed_now", "skipped_existing", "failed")
        ]
        rows.append(("wall time", d["wall_time_s"], "s"))
        c = d["cpu"]
        if c["workers_cpu_s"] > 0:
            rows.append(
                ("CPU: workers / this process", f"{c['workers_cpu_s']:.4g} / {c['client_study_cpu_s']:.4g}", "s")
            )
        console.print(kv_table(f"tolerance study {d['design']} -> {d['output_dir']}", rows))
        prow = [
            (f"{k} P50 / P95 / P99.7", f"{p['P50']:.4g} / {p['P95']:.4g} / {p['P99.7']:.4g}", "")
            for k, p in d["percentiles"].items()
            if p.get("n")
        ]
        if prow:
            console.print(kv_table("distribution", prow))
        y = d["yield"]
        if y and y["yield"] is not None:
            console.print(
                kv_table(
                    "yield",
                    [
                        ("specs", ", ".join(y["specs"]), ""),
                        ("yield", y["yield"], "-"),
                        ("95 % CI (Clopper-Pearson)", f"{y['ci_low']:.4g}..{y['ci_high']:.4g}", ""),
                    ],
                )
            )
        rank = d["ranked_sensitivities"].get("te_pp_arcsec", [])
        console.print(
            kv_table(
                "TE p-p sensitivities",
                [
                    (r["tolerance"], r.get("ST", r.get("src2")), "ST" if r["method"] == "sobol" else "SRC^2")
                    for r in rank[:8]
                ],
            )
        )

    emit(data, json, render)
    if result["failed"]:
        from flexrv.cli import print_error

        print_error(
            f"{result['failed']} of {result['evaluations']} evaluations failed "
            f"(see the error of each in {Path(result['output_dir']) / 'runs' / 'table.csv'})"
        )
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add ``tolerance`` to the app."""
    app.command("tolerance")(tolerance)
