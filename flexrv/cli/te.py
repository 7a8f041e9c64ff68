"""CLI: ``flexrv te DESIGN`` — quasi-static loaded transmission error."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import typer

from flexrv.cli._common import (
    JSON_HELP,
    OVERWRITE_HELP,
    PRESET_HELP,
    check_output_dir,
    console,
    emit,
    kv_table,
    skip_final_collection,
)
from flexrv.cli.design import analytic_budget, budget_table
from flexrv.post.definitions import DEFINITIONS, PLAY_FRACTIONS
from flexrv.post.te import TE_ROWS
from flexrv.units import RAD_PER_ARCMIN


def te(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    torque_nm: float = typer.Option(None, "--torque-nm", help="Output torque in N m (default: the rated torque)."),
    output_revolutions: float = typer.Option(
        None, "--output-revolutions", help="Range in output revolutions (default 1)."
    ),
    crank_revolutions: float = typer.Option(
        None, "--crank-revolutions", help="Range in crank revolutions relative to the carrier."
    ),
    points_per_mesh: int = typer.Option(
        8, "--points-per-mesh", help="Positions per cycloid-mesh (pin-mesh) period, 2-1000."
    ),
    out: Path = typer.Option(None, "--out", help="Output directory (default results/<design>_te_<time>/)."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    csv: Path = typer.Option(None, "--csv", help="Also write the loaded TE as a measured-data CSV (flexrv measured)."),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
    uncertainty: int = typer.Option(
        None,
        "--uncertainty",
        help="Also propagate the design's [ranges] (estimated inputs) with N samples: median, 90 % interval and "
        "top contributors of the rigidities, lost motion, backlash and TE p-p (uncertainty.json).",
    ),
) -> None:
    """Static equilibrium of discs, cranks and carrier at a sequence of input positions under the
    output torque: loaded and no-load TE, lost motion, backlash, torsional rigidity, contact forces,
    TE spectrum; NetCDF, summary.md and PNGs."""
    from flexrv.cli._precompile import start_te
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.model.quasi_static import loaded_te
    from flexrv.post.io import xarray_without_dask
    from flexrv.post.te import save_te, te_dataset, te_summary
    from flexrv.viz.te_plots import te_plots

    xarray_without_dask()
    skip_final_collection()
    if output_revolutions is not None and crank_revolutions is not None:
        raise InputError("--output-revolutions and --crank-revolutions exclude each other: give one")
    reducer = load(preset)
    start_te(reducer)  # a first run: its kernels compile in a second process
    out = check_output_dir(
        out or Path("results") / f"{Path(preset).stem}_te_{time.strftime('%Y%m%d-%H%M%S')}",
        "--out",
        overwrite=overwrite,
    )
    announce_positions(reducer, output_revolutions, crank_revolutions, points_per_mesh)
    bar = progress_bar(not json)
    try:
        result = loaded_te(
            reducer,
            torque=torque_nm,
            output_revolutions=output_revolutions,
            crank_revolutions=crank_revolutions,
            points_per_mesh=points_per_mesh,
            play_fractions=PLAY_FRACTIONS,
            progress=bar,
        )
    finally:
        if bar is not None:
            bar.stop()
    ds = te_dataset(result, reducer)
    summary = te_summary(ds)
    budget = quasi_static_budget(summary, result.outputs, reducer)
    save_te(budget.merged_into(ds), summary, reducer, out)
    te_plots(ds, summary, out)
    data = {"output_dir": str(out), **summary, "stiffness_budget": budget.to_dict()}
    if csv is not None:  # the loaded TE in the measured-data format (flexrv.measured.writer)
        from flexrv.measured.writer import export_te

        data["csv"] = str(export_te(csv, result, reducer.name, f"flexrv te {preset} --torque-nm {result.torque:.17g}"))
    if uncertainty is not None:
        data["uncertainty"] = uncertainty_report(reducer, uncertainty, out, quiet=json)
    analytic = analytic_budget(reducer, summary["torque_Nm"])
    data["stiffness_budget"]["analytic_budget_rigidity_Nm_per_arcmin"] = analytic["rigidity_Nm_per_arcmin"]
    data["stiffness_budget"]["analytic_difference_percent"] = 100.0 * (
        analytic["total_compliance_arcsec_per_Nm"] / data["stiffness_budget"]["total_compliance_arcsec_per_Nm"] - 1.0
    )

    def render(d):
        rows = [
            ("loaded TE p-p", d["te_pp_arcsec"], "arcsec"),
            ("loaded TE mean", d["te_mean_arcsec"], "arcsec"),
            ("no-load TE p-p", d["no_load_te_pp_arcsec"], "arcsec"),
            *[(k, d.get(k), DEFINITIONS[k][0]) for k in TE_ROWS],
            (
                f"lost_motion_small_torque (±{d['no_load_torque_Nm']:.3g} N m)",
                d["lost_motion_small_torque_arcmin"],
                "arcmin",
            ),
            ("max pin force", d.get("max_pin_force_N"), "N"),
            ("positions", d["positions"], "-"),
            ("solve time", d["solve_time_s"], "s"),
            ("output", d["output_dir"], ""),
        ]
        console.print(kv_table(f"quasi-static TE {reducer.name} at {d['torque_Nm']:.6g} N m", rows))
        console.print(
            budget_table(
                f"stiffness budget (quasi-static, strain energy) at {d['torque_Nm']:.6g} N m", d["stiffness_budget"]
            )
        )
        lines = [(f"{x['label']}", x["amplitude_arcsec"], f"order {x['order']:.4g}") for x in d["spectrum_lines"]]
        console.print(kv_table("largest TE lines [arcsec]", lines))
        if "uncertainty" in d:
            console.print(uncertainty_table(d["uncertainty"]))

    emit(data, json, render)


#: measured cost of the static solution per position [s] (loaded and no-load curves, outputs) and the
#: fixed cost of a run (model, catalog points, files, figures) on one core (benchmarks/bench_te.py,
#: benchmarks/bench_startup.py)
SECONDS_PER_POSITION = 2.5e-4
SECONDS_FIXED = 3.0


def announce_positions(reducer, output_revolutions, crank_revolutions, points_per_mesh: int) -> str:
    """One line on stderr before the static solution: how many positions, what is solved,
    how long it usually takes (:data:`SECONDS_PER_POSITION`)."""
    import sys

    from flexrv.model.quasi_static import positions_for

    n = len(positions_for(reducer, output_revolutions, crank_revolutions, points_per_mesh))
    line = (
        f"flexrv te {reducer.name}: static equilibrium at {n} positions (loaded and no-load curves), "
        f"catalog points, files and figures; usually ~{SECONDS_FIXED + SECONDS_PER_POSITION * n:.0f} s"
    )
    print(line, file=sys.stderr, flush=True)
    return line


def progress_bar(enabled: bool):
    """A rich progress bar on stderr of the curves' positions (``progress(stage, done, total)`` of
    :func:`flexrv.model.quasi_static.loaded_te`), one task per curve; None if not ``enabled``
    (``--json``). Rich draws it only on a terminal; ``.stop()`` ends it."""
    if not enabled:
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    tasks = {}

    def report(stage: str, done: int, total: int) -> None:
        if not tasks:
            bar.start()
        if stage not in tasks:
            tasks[stage] = bar.add_task(stage, total=total)
        bar.update(tasks[stage], completed=done)

    report.stop = bar.stop
    return report


def quasi_static_budget(summary: dict, outputs: dict, reducer):
    """The stiffness budget of the quasi-static solution (:func:`flexrv.analysis.budget.
    stiffness_budget` with the model's strain-energy shares, :meth:`flexrv.model.quasi_static.
    StaticModel.compliance_budget`, times its tangent compliance; the crank-support group split
    by the mean of the output ``crank_bending_fraction``)."""
    from flexrv.analysis.budget import ModelShares, stiffness_budget

    bend = outputs.get("crank_bending_fraction")
    model = ModelShares(
        shares={k: 0.01 * v for k, v in summary.get("compliance_budget_percent", {}).items()},
        tangent_compliance=RAD_PER_ARCMIN / summary["rigidity_tangent_Nm_per_arcmin"],
        bending_fraction=float(np.nanmean(bend.values)) if bend is not None else 0.0,
    )
    return stiffness_budget(reducer, summary["torque_Nm"], model=model, route="quasi_static")


def uncertainty_report(reducer, n: int, out: Path, quiet: bool = False) -> dict:
    """:func:`flexrv.studies.uncertainty.design_uncertainty` with ``n`` samples, written to
    ``out/uncertainty.json``; returns it without the per-sample table."""
    import json as _json

    from flexrv.cache import atomic_write_text, to_jsonable
    from flexrv.studies.uncertainty import design_uncertainty

    def progress(i, total):
        if not quiet:
            console.print(f"uncertainty sample {i}/{total}", end="\r")

    res = design_uncertainty(reducer, n, progress=progress)
    atomic_write_text(Path(out) / "uncertainty.json", _json.dumps(to_jsonable(res), indent=2))
    return {k: v for k, v in res.items() if k != "samples"}


def uncertainty_table(u: dict):
    """Table output | median | 5 % | 95 % | top contributors (SRC^2) of an uncertainty report."""
    from rich.table import Table

    table = Table(title=f"prediction intervals from the estimated inputs ({u['n']} samples)", title_justify="left")
    for col in ("output", "median", "5 %", "95 %", "top contributors (SRC^2)"):
        table.add_column(col)
    for name, r in u["outputs"].items():
        if not r.get("n"):
            continue
        c = r.get("contributors") or {}
        top = ", ".join(f"{k} {v:.2f}" for k, v in list(c.get("src2", {}).items())[:3])
        table.add_row(name, f"{r['median']:.4g}", f"{r['p05']:.4g}", f"{r['p95']:.4g}", top)
    if u.get("failed"):
        table.caption = f"{len(u['failed'])} samples failed (see uncertainty.json)"
    return table


def register(app: typer.Typer) -> None:
    """Add ``te`` to the app."""
    app.command("te")(te)
