"""CLI: ``flexrv presets``, ``flexrv show PRESET`` and ``flexrv design PRESET``."""

from __future__ import annotations

from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from flexrv.cli._common import JSON_HELP, PRESET_HELP, console, emit, fmt, render_nested
from flexrv.design import list_presets, load, to_toml


def presets(json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """List the built-in reducer presets."""
    rows = []
    for name in list_presets():
        r = load(name)
        rows.append(
            {
                "name": name,
                "description": r.description,
                "ratio": 1
                + r.first_stage.planet_teeth
                * r.second_stage.pin_count
                / (r.first_stage.sun_teeth * (r.second_stage.pin_count - r.second_stage.disc_teeth)),
                "estimated_fields": len(r.provenance),
            }
        )

    def render(data: list[dict[str, Any]]) -> None:
        table = Table(title="flexrv presets", title_justify="left")
        for col in ("name", "ratio", "estimated/annotated fields", "description"):
            table.add_column(col)
        for row in data:
            table.add_row(row["name"], fmt(row["ratio"]), str(row["estimated_fields"]), row["description"])
        console.print(table)

    emit(rows, json, render)


def show(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    toml: bool = typer.Option(
        False, "--toml", help="Print as TOML that loads back unchanged (a template for your own design)."
    ),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Print a design (all fields, with provenance notes of estimated values)."""
    reducer = load(preset)
    if not reducer.provenance:  # optional for an own design, but then nothing says where estimates come from
        from rich.console import Console

        Console(stderr=True, markup=False, highlight=False).print(
            f"warning: {reducer.name} has no [provenance] table: no field says where its value comes from "
            "(add 'field.path = \"note\"' lines for every estimated value)"
        )
    if toml:
        print(to_toml(reducer, comments=True), end="")
        return

    def render(r) -> None:
        data = r.model_dump()
        console.print(f"{r.name} — {r.description}", style="bold")
        for section, values in data.items():
            if not isinstance(values, dict) or section in ("provenance", "errors"):
                continue
            table = Table(title=section, title_justify="left")
            table.add_column("field", overflow="fold")  # wrapped, never cut: a name to copy
            table.add_column("value", justify="right", overflow="fold")
            table.add_column("provenance", overflow="fold")
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
            table.add_row(
                escape(key), escape(", ".join(fmt(v) for v in value) if isinstance(value, list) else fmt(value))
            )
        console.print(table)

    emit(reducer, json, render)


def design(
    preset: str = typer.Argument(..., help=PRESET_HELP), json: bool = typer.Option(False, "--json", help=JSON_HELP)
) -> None:
    """Analytic design report at the preset's operating point (kinematics, ISO 6336
    mesh stiffness, cycloid stage and pin loads, torsional stiffness, main-bearing
    loads, Hertz, film thickness, life) and the stiffness budget of the torque path
    (each element's torsional compliance, share and the total)."""
    from flexrv.analysis.report import design_report
    from flexrv.errors import ConvergenceError

    reducer = load(preset)
    check_design_report_range(reducer)
    try:
        report = design_report(reducer)
    except ConvergenceError as exc:
        mb = reducer.main_bearing
        if mb.axial_preload_um < 0:
            raise ConvergenceError(
                f"main_bearing.axial_preload_um = {mb.axial_preload_um:g} um (axial clearance) is not supported by "
                f"flexrv design: the quasi-static ball loads are indeterminate in the clearance at this load "
                f"({exc}); use a preload >= 0 for the design report (simulate models the clearance)"
            ) from None
        raise
    warnings = load_sanity_warnings(report)
    if warnings:
        report["warnings"] = warnings
    report["stiffness_budget"] = analytic_budget(reducer)
    report = {
        "rigidity_tangent_Nm_per_arcmin": report["stiffness_budget"]["rigidity_Nm_per_arcmin"],
        "rigidity_definition": "tangent at the rated torque of the analytic stiffness budget (every element of the "
        "torque path in series, flexrv.analysis.budget); the second-stage series models below are not it",
        **report,
    }

    def render(rep):
        console.print(
            f"torsional rigidity (tangent at {rep['stiffness_budget']['torque_Nm']:.6g} N m, stiffness budget): "
            f"{rep['rigidity_tangent_Nm_per_arcmin']:.4g} N m/arcmin",
            style="bold",
        )
        render_nested(
            f"Design report: {reducer.name}",
            {
                k: v
                for k, v in rep.items()
                if k not in ("warnings", "stiffness_budget", "rigidity_tangent_Nm_per_arcmin", "rigidity_definition")
            },
        )
        console.print(
            budget_table(
                f"stiffness budget (analytic series model) at {rep['stiffness_budget']['torque_Nm']:.6g} N m",
                rep["stiffness_budget"],
            )
        )
        for message in rep.get("warnings", []):
            console.print(f"warning: {message}", style="yellow")

    emit(report, json, render)


def analytic_budget(reducer, torque: float | None = None) -> dict:
    """The analytic stiffness budget (:func:`flexrv.analysis.budget.stiffness_budget` with the
    design's elastic bodies) in engineering units (:meth:`flexrv.analysis.budget.Budget.to_dict`)."""
    from flexrv.analysis.budget import stiffness_budget

    return stiffness_budget(reducer, torque, bodies=elastic_body_compliances(reducer)).to_dict()


def elastic_body_compliances(reducer) -> dict:
    """Torsional compliances [rad/(N m)] at the output of the design's elastic bodies
    per its switches (``carrier.body_model``, ``second_stage.disc_body_model``
    = "condensed_fe"): the FE condensations of :func:`flexrv.fem.disc.body_compliances`
    (cached); a rigid body is left out."""
    from flexrv.fem.disc import body_compliances

    carrier = reducer.carrier is not None and reducer.carrier.body_model == "condensed_fe"
    disc = reducer.second_stage.disc_body_model == "condensed_fe"
    if not (carrier or disc):
        return {}
    fe = body_compliances(reducer)
    out = {}
    if carrier:
        out["carrier"] = fe["carrier"]["compliance_rad_per_Nm"]
    if disc:
        out["cycloid_disc"] = fe["cycloid_disc"]["compliance_rad_per_Nm"]
    return out


def budget_table(title: str, budget: dict) -> Table:
    """Table element | compliance | share of a budget dict (:meth:`flexrv.analysis.budget.
    Budget.to_dict`, every element in the route's model), with the total and the rigidities."""
    table = Table(title=title, title_justify="left")
    for col, just in (("element", "left"), ("compliance [arcsec/(N m)]", "right"), ("share [%]", "right")):
        table.add_column(col, justify=just)
    for name, e in sorted(budget["elements"].items(), key=lambda kv: -kv[1]["share_percent"]):
        table.add_row(name.replace("_", " "), fmt(e["compliance_arcsec_per_Nm"]), fmt(e["share_percent"]))
    table.add_row("total", fmt(budget["total_compliance_arcsec_per_Nm"]), "100")
    table.add_row("rigidity [N m/arcmin]", fmt(budget["rigidity_Nm_per_arcmin"]), "")
    for key, value in budget.items():
        if key.endswith("_Nm_per_arcmin") and key not in ("rigidity_Nm_per_arcmin",):
            table.add_row(key[: -len("_Nm_per_arcmin")].replace("_", " ") + " [N m/arcmin]", fmt(value), "")
    if budget.get("notes"):
        table.caption = "; ".join(budget["notes"])
    return table


#: ISO 76:2006 static load rating: the contact pressure at the static rating is
#: 4200 MPa for ball bearings and 4000 MPa for roller bearings (line contacts, also
#: used here for the pin-disc contact). Above it the contact deforms permanently and
#: the elastic (Hertz) results of the report no longer hold.
ISO76_BALL_PA = 4.2e9
ISO76_LINE_PA = 4.0e9


def load_sanity_warnings(report: dict, prefix: str = "") -> list[str]:
    """Warnings for every contact pressure of the design report above the ISO 76
    static limit (ball contacts: keys ``*_p_max_Pa``; line contacts: ``max_hertz_pressure_Pa``)."""
    out = []
    for key, value in report.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            out += load_sanity_warnings(value, f"{path}.")
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            limit = (
                ISO76_BALL_PA
                if key.endswith("_p_max_Pa")
                else ISO76_LINE_PA
                if key.endswith("max_hertz_pressure_Pa")
                else None
            )
            if limit is not None and value > limit:
                out.append(
                    f"{path} = {value / 1e9:.3g} GPa exceeds the ISO 76 static limit {limit / 1e9:g} GPa: "
                    "the contact yields, the elastic (Hertz) results do not hold; check the loads "
                    "(operating.*) and the contact geometry"
                )
    return out


def check_design_report_range(reducer) -> None:
    """Refuse, naming the field, a design whose main-bearing contact angle lies
    outside the ISO 281 table that the life rating of the design report uses."""
    from flexrv.analysis.life import _ISO281_XY
    from flexrv.errors import InputError

    lo, hi = float(_ISO281_XY[0, 0]), float(_ISO281_XY[-1, 0])
    angle = reducer.main_bearing.contact_angle_deg
    if not lo <= angle <= hi:
        raise InputError(
            f"main_bearing.contact_angle_deg = {angle:g} is not allowed for flexrv design: must lie in "
            f"{lo:g} <= value <= {hi:g} deg (the ISO 281 X/Y table of the bearing life rating)"
        )


def register(app: typer.Typer) -> None:
    """Add the design commands to the app."""
    app.command("presets")(presets)
    app.command("show")(show)
    app.command("design")(design)
