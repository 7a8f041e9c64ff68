"""CLI: ``flexrv validate DESIGN --measured FILE...`` — measurements beside predictions."""

from __future__ import annotations

import time
from pathlib import Path
from typing import List, Optional

import typer

from flexrv.cli._common import JSON_HELP, OVERWRITE_HELP, PRESET_HELP, check_output_dir, console, emit

MEASURED_HELP = "Measured-data CSV file (repeatable; format flexrv-measured-1, see docs/measured-data.md)."
LOOP_MODEL_HELP = (
    "Prediction of a stiffness loop: stiffness-test (the dynamic virtual test, the bench's program, with "
    "friction hysteresis; about a minute) or quasi-static (the quasi-static loop, no hysteresis; 0.3 s)."
)


def validate(
    design: str = typer.Argument(..., help=PRESET_HELP),
    measured: List[Path] = typer.Option(..., "--measured", help=MEASURED_HELP),
    loop_model: str = typer.Option("stiffness-test", "--loop-model", help=LOOP_MODEL_HELP),
    model: str = typer.Option("rigid", "--model", help="Model of the dynamic stiffness test (rigid, balls, flexible)."),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Output directory (default results/<design>_validate_<time>/)."
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Run the predictions that match the measured files (stiffness test for a loop, `te` at the
    measured torque for a TE record) and write a side-by-side table of every figure (measured,
    predicted, difference) and overlay plots (loop on loop, TE on TE, spectrum on spectrum)."""
    from flexrv.cache import atomic_write_text, to_jsonable
    from flexrv.cli.measured import read_all
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.studies.validate import LOOP_MODELS, max_abs_difference
    from flexrv.studies.validate import validate as run_validation

    if loop_model not in LOOP_MODELS:
        raise InputError(f"--loop-model {loop_model!r}: allowed {', '.join(LOOP_MODELS)}")
    ms = read_all(measured)  # every file checked before any work
    reducer = load(design)
    out = check_output_dir(
        out or Path("results") / f"{Path(design).stem}_validate_{time.strftime('%Y%m%d-%H%M%S')}",
        "--out",
        overwrite=overwrite,
    )
    rows = run_validation(reducer, ms, loop_model=loop_model, model=model)
    plots = _plots(rows, out, reducer.name)
    data = {
        "design": reducer.name,
        "output_dir": str(out),
        "files": [
            {k: r[k] for k in ("path", "kind", "simulated", "prediction", "comparison", "spectrum_lines")} for r in rows
        ],
        "max_abs_difference": max_abs_difference(rows),
        "plots": [str(p) for p in plots],
    }
    import json as _json

    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "validation.json", _json.dumps(to_jsonable(data), indent=1))
    atomic_write_text(out / "summary.md", _markdown(data))

    def render(d):
        from rich.table import Table

        from flexrv.cli._common import fmt, split_unit

        for f in d["files"]:
            note = " (SIMULATED file)" if f["simulated"] else ""
            table = Table(title=f"{f['path']}{note} vs {f['prediction']}", title_justify="left")
            for col, just in (
                ("figure", "left"),
                ("measured", "right"),
                ("predicted", "right"),
                ("difference", "right"),
                ("unit", "left"),
            ):
                table.add_column(col, justify=just)
            for key, v in f["comparison"].items():
                if "_measured" not in key:
                    continue
                base, unit = key.split("_measured", 1)
                label, u = split_unit(base + unit)
                table.add_row(
                    base.replace("_", " "),
                    fmt(v),
                    fmt(f["comparison"][key.replace("_measured", "_predicted")]),
                    fmt(f["comparison"][key.replace("_measured", "_difference")]),
                    u,
                )
            console.print(table)
        console.print(f"wrote {d['output_dir']}")

    emit(data, json, render)


def _plots(rows, out: Path, name: str) -> list[Path]:
    from flexrv.viz.measured_plots import plot_loop_overlay, plot_spectrum_overlay, plot_te_overlay

    paths = []
    for i, r in enumerate(rows):
        stem = f"{i:02d}_{Path(r['path']).stem}"
        title = f"{Path(r['path']).name} vs {name}: {r['prediction']}"
        if r["kind"] == "te_record":
            paths.append(plot_te_overlay(*r["arrays"].values(), out / f"{stem}_te.png", title))
            paths.append(
                plot_spectrum_overlay(
                    *r["spectra"].values(), out / f"{stem}_spectrum.png", title, r["spectrum_lines"]["measured"]
                )
            )
        else:
            paths.append(plot_loop_overlay(*r["arrays"].values(), out / f"{stem}_loop.png", title))
    return paths


def _markdown(d: dict) -> str:
    from flexrv.cli._common import fmt

    lines = [f"# Validation of {d['design']} against measured files", ""]
    for f in d["files"]:
        lines += [
            f"## {f['path']}" + (" (simulated by flexrv, not a measurement)" if f["simulated"] else ""),
            "",
            f"Prediction: {f['prediction']}. Difference = predicted - measured.",
            "",
            "| figure | measured | predicted | difference |",
            "|---|---|---|---|",
        ]
        for key, v in f["comparison"].items():
            if "_measured" in key:
                lines.append(
                    f"| {key.replace('_measured', '')} | {fmt(v)} | "
                    f"{fmt(f['comparison'][key.replace('_measured', '_predicted')])} | "
                    f"{fmt(f['comparison'][key.replace('_measured', '_difference')])} |"
                )
        lines.append("")
    lines += [f"![{Path(p).name}]({Path(p).name})" for p in d["plots"]] + [""]
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    """Add ``validate`` to the app."""
    app.command("validate")(validate)
