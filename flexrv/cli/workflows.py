"""CLI: ``flexrv workflow NAME [--smoke] [--out DIR]`` and ``flexrv report``."""

from __future__ import annotations

import enum
import importlib
import sys
from pathlib import Path
from typing import Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table
from flexrv.errors import ConfigError


class Workflow(str, enum.Enum):
    kinematic_validation = "kinematic_validation"
    torsional_stiffness = "torsional_stiffness"
    mode_gallery = "mode_gallery"
    rigid_vs_flexible = "rigid_vs_flexible"
    ring_deformation = "ring_deformation"
    lubrication = "lubrication"
    crankshaft_flexibility = "crankshaft_flexibility"
    crank_bearing_forces = "crank_bearing_forces"


def _import(module: str):
    """Import ``workflows.<module>``; the workflows package lives in the repository
    root (parent of the flexrv package), added to sys.path if needed."""
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name not in ("workflows", module):
            raise
    root = str(Path(__file__).resolve().parents[2])
    if root not in sys.path:
        sys.path.insert(0, root)
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        raise ConfigError(f"workflows package not found next to flexrv (looked in {root}): {exc}") from exc


def workflow(name: Workflow = typer.Argument(..., help="Workflow to run.", case_sensitive=True),
             smoke: bool = typer.Option(False, "--smoke", help="Short runs / coarse meshes (quick check)."),
             out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default: results/NAME)."),
             json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Run a seed-study workflow: seed-vs-flexrv table, NetCDF, PNGs and summary.md."""
    if out is not None:  # a workflow regenerates its folder: existing content is expected
        from flexrv.cli._common import check_output_dir

        check_output_dir(out, "--out", allow_existing=True)
    mod = _import(f"workflows.{name.value}")
    res = mod.run(out_dir=out, smoke=smoke)
    data = {"workflow": name.value, "out_dir": str(res.out_dir), "numbers": res.numbers,
            "comparisons": [{"quantity": c.quantity, "unit": c.unit, "seed": c.seed, "flexrv": c.flexrv,
                             "note": c.note} for c in res.comparisons]}

    def render(d):
        console.print(kv_table(f"workflow {name.value}",
                               [(c["quantity"], f"seed {c['seed']} | flexrv {c['flexrv']}", c["unit"])
                                for c in d["comparisons"]]))
        console.print(f"wrote {d['out_dir']}")

    emit(data, json, render)


def report(results: Optional[Path] = typer.Option(None, "--results", help="Results folder (default: results/)."),
           json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Collect every results/<workflow>/summary.md into results/README.md."""
    common = _import("workflows._common")
    root = Path(results) if results else common.RESULTS_ROOT
    path = common.collect_report(root)
    data = {"path": str(path), "sections": sorted(p.parent.name for p in root.glob("*/summary.md"))}

    def render(d):
        console.print(kv_table("report", [("README", d["path"], ""), ("sections", ", ".join(d["sections"]), "")]))

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    """Add ``workflow`` and ``report`` to the app."""
    app.command("workflow")(workflow)
    app.command("report")(report)
