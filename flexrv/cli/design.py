"""CLI: ``flexrv presets``, ``flexrv show PRESET`` and ``flexrv design PRESET``."""

from __future__ import annotations

from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from flexrv.cli._common import JSON_HELP, console, emit, fmt, render_nested
from flexrv.design import list_presets, load, to_toml

PRESET_HELP = "Preset name (see `flexrv presets`) or path to a design TOML file."


def presets(json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """List the built-in reducer presets."""
    rows = []
    for name in list_presets():
        r = load(name)
        rows.append({"name": name, "description": r.description,
                     "ratio": 1 + r.first_stage.planet_teeth * r.second_stage.pin_count
                     / (r.first_stage.sun_teeth * (r.second_stage.pin_count - r.second_stage.disc_teeth)),
                     "estimated_fields": len(r.provenance)})

    def render(data: list[dict[str, Any]]) -> None:
        table = Table(title="flexrv presets", title_justify="left")
        for col in ("name", "ratio", "estimated/annotated fields", "description"):
            table.add_column(col)
        for row in data:
            table.add_row(row["name"], fmt(row["ratio"]), str(row["estimated_fields"]), row["description"])
        console.print(table)

    emit(rows, json, render)


def show(preset: str = typer.Argument(..., help=PRESET_HELP),
         toml: bool = typer.Option(False, "--toml", help="Print as TOML that loads back unchanged (a template for your own design)."),
         json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Print a design (all fields, with provenance notes of estimated values)."""
    reducer = load(preset)
    if toml:
        print(to_toml(reducer), end="")
        return

    def render(r) -> None:
        data = r.model_dump()
        console.print(f"[bold]{r.name}[/] — {r.description}")
        for section, values in data.items():
            if not isinstance(values, dict) or section in ("provenance", "errors"):
                continue
            table = Table(title=section, title_justify="left")
            table.add_column("field")
            table.add_column("value", justify="right")
            table.add_column("provenance")
            for key, value in values.items():
                if isinstance(value, dict):
                    value = ", ".join(f"{k}={fmt(v)}" for k, v in value.items())
                table.add_row(key, fmt(value), r.provenance.get(f"{section}.{key}", ""))
            console.print(table)
        errors = r.errors.nonzero_items()
        if not errors:
            console.print("errors: none (ideal geometry)")
            return
        table = Table(title="errors (manufacturing and assembly, non-zero only)", title_justify="left")
        table.add_column("field", no_wrap=True, min_width=max(len(key) for key, _ in errors))
        table.add_column("value", justify="right", overflow="fold")
        for key, value in errors:
            table.add_row(escape(key), escape(", ".join(fmt(v) for v in value) if isinstance(value, list) else fmt(value)))
        console.print(table)

    emit(reducer, json, render)


def design(preset: str = typer.Argument(..., help=PRESET_HELP),
           json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Analytic design report at the preset's operating point (kinematics, ISO 6336
    mesh stiffness, cycloid stage and pin loads, torsional stiffness, main-bearing
    loads, Hertz, film thickness, life)."""
    from flexrv.analysis.report import design_report

    reducer = load(preset)
    report = design_report(reducer)
    emit(report, json, lambda rep: render_nested(f"Design report: {reducer.name}", rep))


def register(app: typer.Typer) -> None:
    """Add the design commands to the app."""
    app.command("presets")(presets)
    app.command("show")(show)
    app.command("design")(design)
