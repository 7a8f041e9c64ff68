"""``flexrv compare``: rigid vs flexible model on identical inputs."""

from __future__ import annotations

from pathlib import Path

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table
from flexrv.cli.design import PRESET_HELP


def compare(preset: str = typer.Argument(..., help=PRESET_HELP),
            t_end: float = typer.Option(None, "--t-end", help="End time [s] (default: ramps + 0.2 s)."),
            parts: str = typer.Option("main_bearing", "--parts",
                                      help="Flexible parts, comma-separated: main_bearing, crankshaft."),
            dt: float = typer.Option(1e-4, "--dt", help="Time step [s]."),
            out: Path = typer.Option(None, "--out", help="Output directory (default results/<preset>_compare_<time>/)."),
            overwrite: bool = typer.Option(False, "--overwrite", help="Allow an existing non-empty --out directory."),
            json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Run the rigid and the flexible model on identical inputs: TE overlay, TE spectra with the
    characteristic frequencies, ball loads, ring deflection, summary.md and compare.json."""
    from flexrv.model.factory import parse_parts
    from flexrv.post.compare import run_compare

    part_list = parse_parts(parts)
    if out is not None:
        from flexrv.cli._common import check_output_dir

        check_output_dir(out, "--out", overwrite=overwrite)
    cmp = run_compare(preset, t_end=t_end, parts=part_list, out_dir=out, dt=dt, progress=not json)
    nr, nf = cmp.numbers["rigid"], cmp.numbers["flexible"]
    data = {"output_dir": str(cmp.out_dir), "parts": list(part_list), "rigid": nr, "flexible": nf,
            "difference": cmp.numbers["difference"], "timing_s": cmp.numbers["timing"]}

    def render(d):
        rows = []
        for key in ("te_min_arcsec", "te_max_arcsec", "te_pp_arcsec", "te_mean_arcsec", "dominant_period_s"):
            rows.append((key, f"{nr.get(key, float('nan')):.4g} | {nf.get(key, float('nan')):.4g}", "rigid | flexible"))
        for key in ("max_ball_load_N", "max_ring_deformation_m", "min_film_thickness_m"):
            if key in nf and nf[key] is not None:
                rows.append((key, f"{nf[key]:.4g}", "flexible"))
        rows.append(("output_dir", d["output_dir"], ""))
        console.print(kv_table(f"compare {preset} ({', '.join(part_list)})", rows))

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    app.command("compare")(compare)
