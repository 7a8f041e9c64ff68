"""Generated sections of the documentation site, read from the code itself.

Each public function returns Markdown. The mkdocs hook (:mod:`docs.gen.hooks`) replaces a
marker ``<!-- gen:NAME -->`` in a page with ``NAME()``, so the design reference, the results
reference, the command help and the verification table cannot drift from the code. The
module sits outside the ``flexrv`` package (it may import any layer) and is also run by
the tests (``tests/test_docs.py``).
"""

from __future__ import annotations

import ast
import types
import typing
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


# ------------------------------------------------------------------ pydantic models -> rows
def _unit(name: str, description: str) -> str:
    """A field's unit: the ``[unit]`` at the end of its description, else the name's suffix."""
    from flexrv.cli._common import split_unit

    desc = description.rstrip()
    if desc.endswith("]") and "[" in desc:
        unit = desc[desc.rindex("[") + 1 : -1].strip()
        return "" if unit in ("-", "") else unit.replace("um", "µm")
    return split_unit(name)[1]


def _range(field) -> str:
    """The allowed range of a pydantic field, from its constraints and literal choices."""
    parts = []
    lo = hi = None
    for m in field.metadata:
        for attr, sym in (("ge", "≥"), ("gt", ">")):
            if getattr(m, attr, None) is not None:
                lo = f"{sym} {getattr(m, attr):g}"
        for attr, sym in (("le", "≤"), ("lt", "<")):
            if getattr(m, attr, None) is not None:
                hi = f"{sym} {getattr(m, attr):g}"
        if getattr(m, "min_length", None) is not None:
            parts.append(f"length ≥ {m.min_length}")
        if getattr(m, "max_length", None) is not None:
            parts.append(f"length ≤ {m.max_length}")
    if lo and hi:
        parts.insert(0, f"{lo} and {hi}")
    elif lo or hi:
        parts.insert(0, lo or hi)
    choices = _literal_choices(field.annotation)
    if choices:
        parts.append("one of " + ", ".join(f"`{c}`" for c in choices))
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    if extra.get("bound"):
        from flexrv.design.manufacturing import _BOUNDS

        lo_b, hi_b, unit = _BOUNDS[extra["bound"]]
        parts.append("any finite number" if extra["bound"] == "phase" else f"{lo_b:g} to {hi_b:g} {unit}")
        if extra.get("shape") in ("pin", "crank", "crank_disc"):
            index = {"pin": "[pin]", "crank": "[crank]", "crank_disc": "[crank][disc]"}[extra["shape"]]
            parts.append(f"one number or one value per {index}")
    return "; ".join(parts) or "—"


def _literal_choices(annotation) -> list:
    if typing.get_origin(annotation) is typing.Literal:
        return list(typing.get_args(annotation))
    for arg in typing.get_args(annotation):
        found = _literal_choices(arg)
        if found:
            return found
    return []


def _type_name(annotation) -> str:
    text = str(annotation).replace("typing.", "")
    if isinstance(annotation, type):
        text = annotation.__name__
    return text.replace("NoneType", "None").replace("Literal", "one of")


def _submodel(annotation):
    """(kind, model) of a nested pydantic model annotation: ``("table", M)`` for M or
    ``M | None``, ``("array", M)`` for ``list[M]``, ``("dict", M)`` for ``dict[str, M]``."""
    from pydantic import BaseModel

    def is_model(a):
        return isinstance(a, type) and issubclass(a, BaseModel)

    if is_model(annotation):
        return "table", annotation
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        models = [a for a in args if is_model(a)]
        if models:
            return "table", models[0]
    if origin is list and args and is_model(args[0]):
        return "array", args[0]
    if origin is dict and len(args) == 2 and is_model(args[1]):
        return "dict", args[1]
    return None, None


def model_fields(model, prefix: str = "") -> list[dict]:
    """Every leaf field of a pydantic model, recursively: path, type, unit, range, default,
    meaning. Nested tables are walked (``[[array]]`` and ``{name}`` keys shown in the path)."""
    from pydantic_core import PydanticUndefined

    rows = []
    for name, field in model.model_fields.items():
        path = f"{prefix}{name}"
        kind, sub = _submodel(field.annotation)
        if kind == "table":
            rows += model_fields(sub, path + ".")
            continue
        if kind == "array":
            rows += model_fields(sub, path + "[].")
            continue
        if kind == "dict":
            rows += model_fields(sub, path + ".{name}.")
            continue
        desc = field.description or ""
        if field.default is not PydanticUndefined:
            default = repr(field.default)
        elif field.default_factory is not None:
            default = repr(field.default_factory())
        else:
            default = "required"
        rows.append(
            {
                "path": path,
                "type": _type_name(field.annotation),
                "unit": _unit(name, desc),
                "range": _range(field),
                "default": default,
                "meaning": desc or name.replace("_", " "),
            }
        )
    return rows


def _table(rows: list[dict], columns: tuple[str, ...]) -> str:
    def cell(v) -> str:
        return str(v).replace("|", "\\|").replace("\n", " ")

    head = "| " + " | ".join(columns) + " |\n|" + "---|" * len(columns) + "\n"
    body = []
    for r in rows:
        vals = [f"`{r[c]}`" if c == "path" else cell(r[c]) for c in columns]
        body.append("| " + " | ".join(vals) + " |")
    return head + "\n".join(body) + "\n"


def design_fields() -> list[dict]:
    """All fields of the design model (:class:`flexrv.design.model.Reducer`)."""
    from flexrv.design.model import Reducer

    return model_fields(Reducer)


def design_reference() -> str:
    """The design TOML reference: one table per top-level section."""
    from flexrv.design.model import Reducer

    rows = design_fields()
    out = []
    sections: dict[str, list[dict]] = {}
    for r in rows:
        head = r["path"].split(".")[0].split("[")[0]
        sections.setdefault(head, []).append(r)
    for head, items in sections.items():
        field = Reducer.model_fields[head]
        out.append(f"### `{head}`\n")
        if field.description:
            out.append(field.description + "\n")
        out.append(_table(items, ("path", "unit", "range", "default", "meaning")))
    return "\n".join(out)


#: meanings of the tolerance-entry fields (written with the unit suffix of their error field)
_TOLERANCE_MEANINGS = {
    "distribution": "`normal` (mean, sigma), `band` (truncated normal inside mean ± band) or `uniform` (mean ± band)",
    "scope": "one draw per element, one per reducer (shared by its elements) or one for the whole batch",
    "sigma": "standard deviation of a `normal` entry, written `sigma_um` / `sigma_arcmin`",
    "band": "half width of the tolerance zone (`band`, `uniform`), written `band_um` / `band_arcmin`",
    "mean": "centre of the distribution, written `mean_um` / `mean_arcmin`",
    "sigma_fraction": "sigma of a `band` entry as a fraction of the band (1/3: band = 3 sigma, C_p = 1)",
    "source": "where the value comes from (standard, grade, size range)",
    "correlations[].fields": "error fields correlated element by element (same scope and element count)",
    "correlations[].coefficient": "correlation coefficient rho (Gaussian copula; marginals unchanged)",
}


def tolerances_reference() -> str:
    """The ``[tolerances."group.field"]`` entry fields and the error fields they may name."""
    from flexrv.design import tolerances

    rows = model_fields(tolerances.Tolerance)
    for r in rows:
        r["meaning"] = _TOLERANCE_MEANINGS.get(r["path"], r["meaning"])
    corr = model_fields(tolerances.Correlation, "correlations[].")
    for r in corr:
        r["meaning"] = _TOLERANCE_MEANINGS.get(r["path"], r["meaning"])
    names = ", ".join(f"`{n}`" for n in tolerances._allowed_names())
    intro = (tolerances.__doc__ or "").strip()
    return (
        intro
        + "\n\nFields of one entry (values in the unit of the error field they describe, written with its suffix, "
        "e.g. `band_um`, `sigma_arcmin`):\n\n"
        + _table(rows, ("path", "range", "default", "meaning"))
        + "\nCorrelation groups:\n\n"
        + _table(corr, ("path", "range", "default", "meaning"))
        + f"\nError fields an entry may name: {names}.\n"
    )


# ------------------------------------------------------------------ results files
def _sample_run():
    """A 0.5 ms rigid run of rv40e (cached FE bodies and kernels: seconds) whose dataset
    carries every declared output of the rigid model."""
    from flexrv import Simulation

    return Simulation("rv40e", model="rigid").run(t_end=0.0005)


#: meanings of the keys of a simulation's summary.json (units come from its own ``units`` table)
_SUMMARY_MEANINGS = {
    "preset": "design name",
    "model": "model: rigid, balls or flexible",
    "status": "ok, or how the run ended (failed, interrupted)",
    "steady_window_s": "[start, end] of the steady window: whole crank revolutions after the ramps and a settle time",
    "steady_state": "false when not even one crank revolution fits after the ramps (figures describe the start-up)",
    "steady_revolutions": "whole crank revolutions (relative to the carrier) in the steady window",
    "steady_note": "why the window is not steady, in words",
    "ratio_theoretical": "total ratio i from the tooth counts",
    "ratio_simulated": "mean input speed / mean output speed over the steady window",
    "ratio_simulated_over_theoretical": "their quotient (1 for a kinematically exact model)",
    "te_min_arcsec": "smallest TE in the steady window",
    "te_max_arcsec": "largest TE in the steady window",
    "te_pp_arcsec": "TE peak to peak (max - min) in the steady window",
    "te_mean_arcsec": "mean TE in the steady window (mostly elastic wind-up)",
    "te_rms_fluctuation_arcsec": "RMS of TE - mean in the steady window",
    "max_pin_force_N": "largest pin-disc contact force in the steady window",
    "pins_in_contact_mean": "mean number of pins in contact (per disc)",
    "pins_in_contact_max": "largest number of pins in contact (per disc)",
    "mean_input_power_W": "mean input power",
    "mean_output_power_W": "mean output power",
    "mean_kinetic_energy_rate_W": "mean rate of change of kinetic energy (0 in a steady state)",
    "mean_dissipation_W": "mean input minus output power minus kinetic energy rate",
    "efficiency": "mean output power / mean input power",
    "mean_friction_power_W": "mean power dissipated by friction (all groups)",
    "mean_pin_friction_power_W": "mean friction power at the pins",
    "mean_needle_friction_power_W": "mean friction power in the needle bearings",
    "power_balance_note": "the power balance in words",
    "notes": "remarks on the run, in words",
    "kinematics": "rows quantity, unit, theory, simulated, error_percent: member speeds against the kinematics",
    "failure": "the failure message of a run that did not finish (else null)",
    "units": "unit of each numeric key",
}


def results_reference() -> str:
    """Variables of ``results.nc`` (name, dimensions, unit, long name) and the keys of
    ``summary.json``, read from a short run and from the declared outputs."""
    from flexrv.cli._common import split_unit
    from flexrv.model.outputs import declared_outputs

    res = _sample_run()
    rows = []
    for name, var in res.ds.data_vars.items():
        rows.append(
            {
                "path": name,
                "dims": ", ".join(var.dims),
                "unit": var.attrs.get("units", ""),
                "meaning": var.attrs.get("long_name", ""),
            }
        )
    declared = declared_outputs()
    missing = sorted(set(declared) - set(res.ds.data_vars))
    summary = res.summary()
    srows = []
    units = summary.get("units", {})
    for key in summary:
        unit = units.get(key, split_unit(key)[1])
        srows.append(
            {"path": key, "unit": "" if unit in ("-", "1") else unit, "meaning": _SUMMARY_MEANINGS.get(key, "")}
        )
    text = (
        "### `results.nc` (NetCDF, xarray)\n\nCoordinate `time` [s]; every variable carries `units` and "
        "`long_name` attributes. Variables of the rigid model:\n\n" + _table(rows, ("path", "dims", "unit", "meaning"))
    )
    if missing:
        text += "\nDeclared but not written by the rigid model: " + ", ".join(f"`{m}`" for m in missing) + ".\n"
    text += "\n### `summary.json`\n\n" + _table(srows, ("path", "unit", "meaning"))
    return text


# ------------------------------------------------------------------ commands
def commands_reference() -> str:
    """The ``--help`` of every ``flexrv`` command, as the CLI prints it."""
    import click
    import typer

    from flexrv.cli import app

    group = typer.main.get_command(app)
    out = []
    for name in group.list_commands(click.Context(group)):
        cmd = group.commands[name]
        with click.Context(cmd, info_name=f"flexrv {name}", terminal_width=100, max_content_width=100) as ctx:
            text = cmd.get_help(ctx)
        out.append(f"### `flexrv {name}`\n\n```text\n{text}\n```\n")
    return "\n".join(out)


# ------------------------------------------------------------------ verification
def verification_table() -> str:
    """The pinned reference values of ``tests/reference_values.py`` with their tolerances,
    the case each comes from and its source."""
    import sys

    sys.path.insert(0, str(ROOT))
    from tests import reference_values

    cases = ast.parse((ROOT / "tests" / "regression_cases.py").read_text(encoding="utf-8"))
    docs = {n.name: ast.get_docstring(n) or "" for n in cases.body if isinstance(n, ast.FunctionDef)}
    out = []
    for name, ref in reference_values.REFERENCE.items():
        slow = " (slow: `-m slow`)" if name in reference_values.SLOW else ""
        out.append(f"### `{name}`{slow}\n\n{' '.join(docs.get(name, '').split())}\n")
        rows = [{"path": k, "value": f"{v:.9g}", "rtol": f"{ref['rtol'][k]:g}"} for k, v in ref["values"].items()]
        out.append(_table(rows, ("path", "value", "rtol")))
        out.append(f"\nSource: {ref['source']}\n")
    return "\n".join(out)


# ------------------------------------------------------------------ benchmarks
def benchmarks_list() -> str:
    """Each script of ``benchmarks/`` with the first paragraph of its docstring."""
    rows = []
    for path in sorted((ROOT / "benchmarks").glob("bench_*.py")):
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        first = " ".join(doc.split("\n\n")[0].split())
        rows.append({"path": f"benchmarks/{path.name}", "meaning": first})
    return _table(rows, ("path", "meaning"))


def changelog() -> str:
    """CHANGELOG.md of the repository (its title replaced by the page's)."""
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    return "# Changelog\n" + text.split("\n", 1)[1] if text.startswith("# ") else text


GENERATORS = {
    "changelog": changelog,
    "design_reference": design_reference,
    "tolerances_reference": tolerances_reference,
    "results_reference": results_reference,
    "commands_reference": commands_reference,
    "verification_table": verification_table,
    "benchmarks_list": benchmarks_list,
}
