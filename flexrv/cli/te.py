"""CLI: ``flexrv te DESIGN`` — quasi-static loaded transmission error."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table

PRESET_HELP = "Preset name (see `flexrv presets`) or path to a design TOML file."


def te(preset: str = typer.Argument(..., help=PRESET_HELP),
       torque_nm: float = typer.Option(None, "--torque-nm", help="Output torque in N m (default: the rated torque)."),
       output_revolutions: float = typer.Option(None, "--output-revolutions",
                                                help="Range in output revolutions (default 1)."),
       crank_revolutions: float = typer.Option(None, "--crank-revolutions",
                                               help="Range in crank revolutions relative to the carrier."),
       points_per_mesh: int = typer.Option(8, "--points-per-mesh",
                                           help="Positions per cycloid-mesh (pin-mesh) period, 2-1000."),
       out: Path = typer.Option(None, "--out", help="Output directory (default results/<design>_te_<time>/)."),
       json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
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
    out = out or Path("results") / f"{Path(preset).stem}_te_{time.strftime('%Y%m%d-%H%M%S')}"
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is an existing file: give a directory")
    result = loaded_te(reducer, torque=torque_nm, output_revolutions=output_revolutions,
                       crank_revolutions=crank_revolutions, points_per_mesh=points_per_mesh)
    ds = te_dataset(result, reducer)
    summary = te_summary(ds)
    save_te(ds, summary, reducer, out)
    te_plots(ds, summary, out)
    data = {"output_dir": str(out), **summary}

    def render(d):
        rows = [("loaded TE p-p", d["te_pp_arcsec"], "arcsec"), ("loaded TE mean", d["te_mean_arcsec"], "arcsec"),
                ("no-load TE p-p", d["no_load_te_pp_arcsec"], "arcsec"),
                ("lost motion (±3 % rated)", d["lost_motion_arcmin"], "arcmin"),
                (f"backlash (±{d['no_load_torque_Nm']:.3g} N m)", d["backlash_arcmin"], "arcmin"),
                ("rigidity, tangent", d["torsional_rigidity_Nm_per_arcmin"], "N m/arcmin"),
                ("rigidity, 50-100 % rated", d["catalog_rigidity_Nm_per_arcmin"], "N m/arcmin"),
                ("max pin force", d.get("max_pin_force_N"), "N"), ("positions", d["positions"], "-"),
                ("solve time", d["solve_time_s"], "s"), ("output", d["output_dir"], "")]
        console.print(kv_table(f"quasi-static TE {reducer.name} at {d['torque_Nm']:.6g} N m", rows))
        budget = sorted(d.get("compliance_budget_percent", {}).items(), key=lambda kv: -kv[1])
        console.print(kv_table("compliance budget", [(k.replace("_", " "), v, "%") for k, v in budget]))
        lines = [(f"{x['label']}", x["amplitude_arcsec"], f"order {x['order']:.4g}") for x in d["spectrum_lines"]]
        console.print(kv_table("largest TE lines [arcsec]", lines))

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    """Add ``te`` to the app."""
    app.command("te")(te)
