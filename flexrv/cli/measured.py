"""CLI: ``flexrv measured FILE...`` — what measured-data files hold and their figures."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table

FILES_HELP = "Measured-data CSV files (format flexrv-measured-1; see docs/measured-data.md)."
DESIGN_HELP = "Design (preset or TOML) whose orders label the TE spectrum lines (default: order 1 only)."


def read_all(files: list[Path]) -> list:
    """Every file read and checked before anything else happens (the first bad one raises
    :class:`flexrv.measured.MeasuredFileError`: file, line, column; exit 2)."""
    from flexrv.errors import InputError
    from flexrv.measured import read_measured

    if not files:
        raise InputError("give at least one measured-data file")
    return [read_measured(f) for f in files]


def file_summary(m, figures: dict) -> dict:
    """JSON-ready description of one file and its figures (arrays left out)."""
    return {
        "path": m.path,
        "kind": m.kind,
        "origin": m.meta.get("origin"),
        "simulated": m.simulated,
        "rows": m.rows,
        "columns": m.units,
        "metadata": {k: v for k, v in m.meta.items() if k not in ("format", "kind")},
        "figures": {k: v for k, v in figures.items() if not k.startswith("spectrum_") or k == "spectrum_lines"},
    }


def measured(
    files: List[Path] = typer.Argument(..., help=FILES_HELP),
    design: Optional[str] = typer.Option(None, "--design", help=DESIGN_HELP),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Read measured-data files (stiffness loops, TE records, lost-motion points) and print what
    each holds and its figures (rigidity by each definition, lost motion, backlash, hysteresis;
    TE p-p, mean, forward-backward difference, spectrum lines). A bad file: one message naming
    file, line and column, exit 2."""
    from flexrv.measured.figures import forward_backward, measurement_figures, reducer_orders

    ms = read_all(files)
    orders = None
    if design is not None:
        from flexrv.design import load

        orders = reducer_orders(load(design))
    data = {"files": [file_summary(m, measurement_figures(m, orders)) for m in ms]}
    pairs = forward_backward(ms)
    if pairs:
        data["forward_backward"] = pairs

    def render(d):
        from flexrv.cli._common import split_unit

        for f in d["files"]:
            note = " (SIMULATED by flexrv, not a measurement)" if f["simulated"] else ""
            cols = ", ".join(f"{k} [{u}]" for k, u in f["columns"].items())
            rows = [("kind", f["kind"], ""), ("rows", f["rows"], ""), ("columns", cols, "")]
            rows += [(k, v, "") for k, v in f["metadata"].items()]
            for k, v in f["figures"].items():
                if k == "spectrum_lines":
                    continue
                label, unit = split_unit(k)
                rows.append((label.replace("_", " "), v, unit))
            console.print(kv_table(f"{f['path']}{note}", rows))
            lines = f["figures"].get("spectrum_lines")
            if lines:
                console.print(
                    kv_table(
                        "largest TE lines [arcsec]",
                        [(x["label"], x["amplitude_arcsec"], f"order {x['order']:.4g}") for x in lines],
                    )
                )
        for p in d.get("forward_backward", []):
            console.print(
                kv_table(
                    f"forward - backward at {p['torque_Nm']:.6g} N m",
                    [
                        ("mean", p["te_forward_backward_mean_arcsec"], "arcsec"),
                        ("max |.|", p["te_forward_backward_max_arcsec"], "arcsec"),
                    ],
                )
            )

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    """Add ``measured`` to the app."""
    app.command("measured")(measured)
