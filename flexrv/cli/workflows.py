"""CLI: ``flexrv workflow NAME [--smoke] [--out DIR]`` and ``flexrv report [--smoke]``.

The workflows are modules of :mod:`flexrv.workflows` (installed with the package);
outputs go to ``./results/<name>/`` of the current directory (``./results/<name>-smoke/``
with ``--smoke``) or to ``--out``, as for ``flexrv simulate``."""

from __future__ import annotations

import enum
import importlib
from pathlib import Path
from typing import Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit
from flexrv.workflows._common import _fmt


class Workflow(str, enum.Enum):
    kinematic_validation = "kinematic_validation"
    torsional_stiffness = "torsional_stiffness"
    mode_gallery = "mode_gallery"
    rigid_vs_flexible = "rigid_vs_flexible"
    ring_deformation = "ring_deformation"
    lubrication = "lubrication"
    crankshaft_flexibility = "crankshaft_flexibility"
    crank_bearing_forces = "crank_bearing_forces"
    te_errors = "te_errors"
    tolerance_study = "tolerance_study"
    modification_design = "modification_design"
    calibration = "calibration"


def workflow(
    name: Workflow = typer.Argument(..., help="Workflow to run.", case_sensitive=True),
    smoke: bool = typer.Option(
        False,
        "--smoke",
        help="Short runs / coarse meshes (a quick check, not results); written to results/NAME-smoke/.",
    ),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Output folder (default: ./results/NAME, or ./results/NAME-smoke with --smoke)."
    ),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Run a seed-study workflow: seed-vs-flexrv table, NetCDF, PNGs and summary.md."""
    if out is not None:  # a workflow regenerates its folder: existing content is expected
        from flexrv.cli._common import check_output_dir

        check_output_dir(out, "--out", allow_existing=True)
    from rich.table import Table

    mod = importlib.import_module(f"flexrv.workflows.{name.value}")
    res = mod.run(out_dir=out, smoke=smoke)
    data = {
        "workflow": name.value,
        "smoke": smoke,
        "out_dir": str(res.out_dir),
        "numbers": res.numbers,
        "comparisons": [
            {"quantity": c.quantity, "unit": c.unit, "seed": c.seed, "flexrv": c.flexrv, "note": c.note}
            for c in res.comparisons
        ],
    }

    def render(d):
        table = Table(
            title=f"workflow {name.value}" + (" (SMOKE RUN: not results)" if smoke else ""), title_justify="left"
        )
        for col, just in (("quantity", "left"), ("seed", "right"), ("flexrv", "right"), ("unit", "left")):
            table.add_column(col, justify=just, overflow="fold")
        for c in d["comparisons"]:
            table.add_row(c["quantity"], _fmt(c["seed"]), _fmt(c["flexrv"]), c["unit"])
        console.print(table)
        console.print(f"wrote {d['out_dir']}")

    emit(data, json, render)


def report(
    results: Optional[Path] = typer.Option(None, "--results", help="Results folder (default: ./results)."),
    smoke: bool = typer.Option(
        False, "--smoke", help="Collect the smoke runs (results/NAME-smoke) into REPORT-smoke.md."
    ),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Collect the workflow summaries into the generated results/REPORT.md (full runs only;
    --smoke: results/REPORT-smoke.md from the smoke runs)."""
    from flexrv.workflows._common import SMOKE_SUFFIX, collect_report, is_workflow_summary, results_root

    root = Path(results) if results else results_root()
    if results is not None and not root.is_dir():
        from flexrv.errors import InputError

        what = "is not a directory" if root.exists() else "does not exist"
        raise InputError(f"--results {root}: {what}; give the folder the workflows wrote into")
    path = collect_report(root, smoke=smoke)
    data = {
        "path": str(path),
        "smoke": smoke,
        "sections": sorted(
            p.parent.name
            for p in root.glob("*/summary.md")
            if p.parent.name.endswith(SMOKE_SUFFIX) == smoke and is_workflow_summary(p)
        ),
    }

    def render(d):
        console.print(f"wrote {d['path']} ({', '.join(d['sections']) or 'no workflow results yet'})")

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    """Add ``workflow`` and ``report`` to the app."""
    app.command("workflow")(workflow)
    app.command("report")(report)
