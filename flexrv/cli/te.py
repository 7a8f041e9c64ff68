"""CLI: ``flexrv te DESIGN`` — quasi-static loaded transmission error."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import typer

from flexrv.cli._common import JSON_HELP, OVERWRITE_HELP, check_output_dir, console, emit, kv_table
from flexrv.cli.design import analytic_budget, budget_table

PRESET_HELP = "Preset name (see `flexrv presets`) or path to a design TOML file."


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
) -> None:
    """Static equilibrium of discs, cranks and carrier at a sequence of input positions under the
    output torque: loaded and no-load TE, lost motion, backlash, torsional rigidity, contact forces,
    TE spectrum; NetCDF, summary.md and PNGs."""
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.model.quasi_static import loaded_te
    from flexrv.post.te import save_te, te_dataset, te_summary
    from flexrv.viz.te_plots import te_plots

    if output_revolutions is not None and crank_revolutions is not None:
        raise InputError("--output-revolutions and --crank-revolutions exclude each other: give one")
    reducer = load(preset)
    out = check_output_dir(
        out or Path("results") / f"{Path(preset).stem}_te_{time.strftime('%Y%m%d-%H%M%S')}",
        "--out",
        overwrite=overwrite,
    )
    result = loaded_te(
        reducer,
        torque=torque_nm,
        output_revolutions=output_revolutions,
        crank_revolutions=crank_revolutions,
        points_per_mesh=points_per_mesh,
    )
    ds = te_dataset(result, reducer)
    summary = te_summary(ds)
    save_te(ds, summary, reducer, out)
    te_plots(ds, summary, out)
    data = {"output_dir": str(out), **summary}
    if csv is not None:  # the loaded TE in the measured-data format (flexrv.measured.writer)
        from flexrv.measured.writer import export_te

        data["csv"] = str(export_te(csv, result, reducer.name, f"flexrv te {preset} --torque-nm {result.torque:.17g}"))
    data["stiffness_budget"] = quasi_static_budget(summary, result.outputs, reducer)
    analytic = analytic_budget(reducer, summary["torque_Nm"])
    data["stiffness_budget"]["analytic_rigidity_Nm_per_arcmin"] = analytic["rigidity_Nm_per_arcmin"]
    data["stiffness_budget"]["analytic_difference_percent"] = 100.0 * (
        analytic["total_compliance_arcsec_per_Nm"] / data["stiffness_budget"]["total_compliance_arcsec_per_Nm"] - 1.0
    )

    def render(d):
        rows = [
            ("loaded TE p-p", d["te_pp_arcsec"], "arcsec"),
            ("loaded TE mean", d["te_mean_arcsec"], "arcsec"),
            ("no-load TE p-p", d["no_load_te_pp_arcsec"], "arcsec"),
            ("lost motion (±3 % rated)", d["lost_motion_arcmin"], "arcmin"),
            (f"backlash (±{d['no_load_torque_Nm']:.3g} N m)", d["backlash_arcmin"], "arcmin"),
            ("rigidity, tangent", d["torsional_rigidity_Nm_per_arcmin"], "N m/arcmin"),
            ("rigidity, 50-100 % rated", d["catalog_rigidity_Nm_per_arcmin"], "N m/arcmin"),
            ("rigidity, 3-50 % rated (low torque)", d.get("low_torque_rigidity_Nm_per_arcmin"), "N m/arcmin"),
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

    emit(data, json, render)


def quasi_static_budget(summary: dict, outputs: dict, reducer=None) -> dict:
    """Stiffness budget of the quasi-static solution in the elements of ``flexrv
    design`` (:func:`flexrv.cli.design.budget_dict`): each force group's share of the
    tangent compliance 1 / k_t (strain-energy fractions,
    :meth:`flexrv.model.quasi_static.StaticModel.compliance_budget`) times 1 / k_t;
    the crank-support group (bearings and crank bending in series, one element) is
    split by its bending share of the tangential compliance (output
    ``crank_bending_fraction``, mean over positions and cranks); with the ``reducer``,
    the pin path split and the unmodelled housing added
    (:func:`flexrv.analysis.torsional.budget_from_group_shares`)."""
    from flexrv.analysis.torsional import budget_from_group_shares
    from flexrv.cli.design import budget_dict
    from flexrv.units import RAD_PER_ARCMIN

    total = RAD_PER_ARCMIN / summary["torsional_rigidity_Nm_per_arcmin"]
    shares = {k: 0.01 * v for k, v in summary.get("compliance_budget_percent", {}).items()}
    bend = outputs.get("crank_bending_fraction")
    frac = float(np.nanmean(bend.values)) if bend is not None else 0.0
    comp, notes = budget_from_group_shares(shares, total, frac, reducer, summary["torque_Nm"])
    out = budget_dict(comp, summary["torque_Nm"])
    if notes:
        out["notes"] = list(notes)
    return out


def register(app: typer.Typer) -> None:
    """Add ``te`` to the app."""
    app.command("te")(te)
