"""CLI: ``flexrv calibrate DESIGN --measured FILE... [--free FIELD=LO:HI ...]`` — the uncertain
inputs identified from bench measurements, with 95 % intervals."""

from __future__ import annotations

import time
from pathlib import Path
from typing import List, Optional

import typer

from flexrv.cli._common import JSON_HELP, OVERWRITE_HELP, check_output_dir, console, emit, kv_table

PRESET_HELP = "Preset name or design TOML to calibrate (it is not changed; the result is a new TOML in --out)."
FREE_HELP = (
    "A design field to fit and its plausible range, FIELD=LO:HI (repeatable), e.g. "
    "crankshaft.support_bearing_axial_preload_um=0:6. Default: the fields whose provenance says "
    "'estimate', screened by sensitivity so that only identifiable ones are freed."
)


def calibrate(
    design: str = typer.Argument(..., help=PRESET_HELP),
    measured: List[Path] = typer.Option(..., "--measured", help="Measured-data CSV file (repeatable)."),
    free: Optional[List[str]] = typer.Option(None, "--free", help=FREE_HELP),
    max_free: int = typer.Option(3, "--max-free", help="Most fields the screening frees (default 3)."),
    workers: Optional[int] = typer.Option(
        None, "--workers", help="LocalCluster worker processes (default min(2, CPUs); 0: evaluate in this process)."
    ),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Address of a running dask scheduler."),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Output directory (default results/<design>_calibrate_<time>/)."
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Fit uncertain design fields to measured loops / lost-motion points by bounded least squares on
    the quasi-static model (evaluations on dask); 95 % intervals, correlation, non-identifiable
    combinations, residuals, the calibrated model's prediction of what was not fitted, and the
    calibrated design TOML (provenance names the files and the fit)."""
    from flexrv.cli.measured import read_all
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.studies.calibrate import calibrate as run_calibration
    from flexrv.studies.calibrate import calibrated_design, parse_free, write_calibration

    if max_free < 1:
        raise InputError(f"--max-free {max_free}: must be >= 1")
    if workers is not None and workers < 0:
        raise InputError(f"--workers {workers}: must be >= 0")
    ms = read_all(measured)  # every file checked before any work
    reducer = load(design)
    free_ranges = parse_free(list(free), reducer) if free else None
    out = check_output_dir(
        out or Path("results") / f"{Path(design).stem}_calibrate_{time.strftime('%Y%m%d-%H%M%S')}",
        "--out",
        overwrite=overwrite,
    )
    cal = run_calibration(reducer, ms, free=free_ranges, workers=workers, scheduler=scheduler, max_free=max_free)
    files = [m.path for m in ms]
    not_fitted = predicted_not_fitted(calibrated_design(reducer, cal, files), ms)
    data = write_calibration(out, reducer, cal, files, {"design": reducer.name, "predicted_not_fitted": not_fitted})
    data["output_dir"] = str(out)
    _write_report(out, reducer, cal, ms, data)

    def render(d):
        from rich.table import Table

        from flexrv.cli._common import fmt

        table = Table(title=f"calibration of {d['design']} ({d['sigma_source']})", title_justify="left")
        for col in ("field", "estimate", "value", "95 % low", "95 % high", "identifiable"):
            table.add_column(col, justify="left" if col == "field" else "right", overflow="fold")
        for k, v in d["identified"].items():
            table.add_row(
                k, fmt(v["estimate"]), fmt(v["value"]), fmt(v["ci95_low"]), fmt(v["ci95_high"]), str(v["identifiable"])
            )
        console.print(table)
        for c in d["non_identifiable"]:
            w = ", ".join(f"{fmt(x)} x {k}" for k, x in c["weights"].items())
            console.print(f"not identifiable from these data: the combination {w}", style="yellow")
        console.print(
            kv_table(
                "fit",
                [
                    ("residual RMS (weighted)", d["residual_rms"], "-"),
                    ("residual RMS", d["residual_rms_arcmin"], "arcmin"),
                    ("evaluations", d["evaluations"], "-"),
                    ("wall time", d["wall_time_s"], "s"),
                ],
            )
        )
        console.print(f"wrote {d['calibrated_design']} and {d['output_dir']}/calibration.json")

    emit(data, json, render)


def predicted_not_fitted(calibrated, measurements) -> list[dict]:
    """The calibrated model's prediction of the measured quantities the fit did not use: every
    figure of every TE record (loaded TE at its torque), and of every loop the figures other
    than the fitted mid-curve spans (rigidity by each definition, lost motion, backlash,
    hysteresis: read from the same record, so not independent of the fit), each with its
    measured value and the difference (:func:`flexrv.studies.validate.validate`,
    quasi-static loops)."""
    from flexrv.studies.validate import validate

    rows = validate(calibrated, measurements, loop_model="quasi-static")
    return [
        {
            "path": r["path"],
            "kind": r["kind"],
            "independent_of_fit": r["kind"] == "te_record",
            "prediction": r["prediction"],
            "comparison": r["comparison"],
        }
        for r in rows
    ]


def _write_report(out: Path, reducer, cal, ms, data: dict) -> None:
    """summary.md and the loop overlay (measured, estimate, calibrated)."""
    from flexrv.cache import atomic_write_text
    from flexrv.cli._common import fmt

    lines = [
        f"# Calibration of {reducer.name}",
        "",
        f"Measured files: {', '.join(data['measured_files'])}. Sigma from {cal.sigma_source}; "
        f"{cal.evaluations} evaluations in {cal.wall_time_s:.1f} s; {cal.status}.",
        "",
        "| field | estimate | value | 95 % low | 95 % high | identifiable |",
        "|---|---|---|---|---|---|",
    ]
    for k, v in cal.identified.items():
        lines.append(
            f"| {k} | {fmt(v['estimate'])} | {fmt(v['value'])} | {fmt(v['ci95_low'])} | {fmt(v['ci95_high'])} "
            f"| {v['identifiable']} |"
        )
    lines += ["", "Not identifiable combinations (weights of the fields):", ""]
    lines += [f"- {c['weights']} (singular value ratio {c['singular_value_ratio']:.3g})" for c in cal.non_identifiable]
    lines += ["- none" if not cal.non_identifiable else "", "", "| file | quantity | measured | fitted | residual |"]
    lines += ["|---|---|---|---|---|"]
    lines += [
        f"| {Path(r['file']).name} | {r['quantity']} | {fmt(r['measured'])} | {fmt(r['fitted'])} "
        f"| {fmt(r['residual'])} |"
        for r in cal.residuals
    ]
    lines += ["", f"Calibrated design: `{Path(data['calibrated_design']).name}`.", ""]
    atomic_write_text(out / "summary.md", "\n".join(lines))


def register(app: typer.Typer) -> None:
    """Add ``calibrate`` to the app."""
    app.command("calibrate")(calibrate)
