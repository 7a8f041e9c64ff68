"""``flexrv compare``: rigid vs flexible model on identical inputs."""

from __future__ import annotations

from pathlib import Path

import typer

from flexrv.cli._common import JSON_HELP, PRESET_HELP, console, emit


def compare(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    t_end: float = typer.Option(
        None, "--t-end", help="End time in s (default: end of the speed and load ramps + 0.2 s)."
    ),
    parts: str = typer.Option(
        "main_bearing",
        "--parts",
        help="Elastic parts of the flexible run, comma-separated: main_bearing, "
        "crankshaft, carrier, cycloid_disc (the rigid reference has none).",
    ),
    dt: float = typer.Option(1e-4, "--dt", help="Time step in s."),
    out: Path = typer.Option(None, "--out", help="Output directory (default results/<preset>_compare_<time>/)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Allow an existing non-empty --out directory."),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Run the rigid and the flexible model on identical inputs: TE overlay, TE spectra with the
    characteristic frequencies, ball loads, ring deflection, summary.md and compare.json."""
    from flexrv.model.factory import parse_parts
    from flexrv.studies.compare import run_compare

    part_list = parse_parts(parts)
    if out is not None:
        from flexrv.cli._common import check_output_dir

        check_output_dir(out, "--out", overwrite=overwrite)
    cmp = run_compare(preset, t_end=t_end, parts=part_list, out_dir=out, dt=dt, progress=not json)
    nr, nf = cmp.numbers["rigid"], cmp.numbers["flexible"]
    data = {
        "output_dir": str(cmp.out_dir),
        "parts": list(part_list),
        "rigid": nr,
        "flexible": nf,
        "difference": cmp.numbers["difference"],
        "timing_s": cmp.numbers["timing"],
        "seed_reference": cmp.numbers.get("seed"),
    }

    def render(d):
        from rich.table import Table

        def g(x):
            return "–" if x is None else f"{x:.4g}"

        seed = d["seed_reference"]
        table = Table(title=f"compare {preset} ({', '.join(part_list)})", title_justify="left")
        for col in ("quantity", "rigid", "flexible", "unit") + (("seed000/seed001 rigid | flexible",) if seed else ()):
            table.add_column(col, justify="left" if col in ("quantity", "unit") else "right")
        rows = [
            ("TE min", "te_min_arcsec", "arcsec"),
            ("TE max", "te_max_arcsec", "arcsec"),
            ("TE peak-to-peak", "te_pp_arcsec", "arcsec"),
            ("TE mean", "te_mean_arcsec", "arcsec"),
            ("dominant TE period", "dominant_period_s", "s"),
        ]
        for label, key, unit in rows:
            extra = ()
            if seed:
                if key in ("te_min_arcsec", "te_max_arcsec"):
                    extra = (f"{seed['rigid'][key]} | {seed['flexible'][key]}",)
                elif key == "dominant_period_s":
                    extra = (f"{seed['rigid']['period_s']} | {seed['flexible']['period_s']}",)
                else:
                    extra = ("–",)
            table.add_row(label, g(nr.get(key)), g(nf.get(key)), unit, *extra)
        for label, key, scale, unit in (
            ("max ball load", "max_ball_load_N", 1.0, "N"),
            ("max outer-ring deflection", "max_ring_deformation_m", 1e6, "µm"),
            ("min EHL film", "min_film_thickness_m", 1e6, "µm"),
        ):
            if nf.get(key) is not None:
                table.add_row(label, "–", g(scale * nf[key]), unit, *(("–",) if seed else ()))
        console.print(table)
        if not seed:
            console.print(f"no seed reference: seed000/seed001 simulate the rv221, not {preset}")
        if not nr.get("steady_state", True):
            console.print(f"[bold red]NOT STEADY[/]: {nr.get('steady_note')}")
        console.print(f"wrote {d['output_dir']}")

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    app.command("compare")(compare)
