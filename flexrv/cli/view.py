"""``flexrv view RESULT_DIR``: the deformed main-bearing rings of a flexible run."""

from __future__ import annotations

from pathlib import Path

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table


def view(
    result_dir: Path = typer.Argument(..., help="Result folder of `flexrv simulate ... --model flexible`."),
    time: float = typer.Option(None, "--time", help="Instant to show [s] (default: the last record)."),
    scale: float = typer.Option(None, "--scale", help="Displacement scale (default: largest = 3 % of the OD)."),
    field: str = typer.Option("displacement", "--field", help="Colour: displacement or von_mises."),
    png: Path = typer.Option(None, "--png", help="Write an off-screen PNG (default <result>/rings.png)."),
    vtu: Path = typer.Option(None, "--vtu", help="Also write a PVD time series (VTU per frame) to this folder."),
    every: int = typer.Option(
        10,
        "--every",
        help="With --vtu: every k-th record (the stride; the size of the series is printed after its first frame).",
    ),
    show: bool = typer.Option(False, "--show", help="Open an interactive window (needs a display)."),
    rebuild: bool = typer.Option(
        False,
        "--rebuild",
        help="Mesh and reduce the rings again from the saved "
        "design if the run's cached bodies are gone (view never re-meshes otherwise).",
    ),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Deformed rings (scaled) coloured by displacement or von Mises stress: PNG off-screen,
    interactive with --show, PVD/VTU time series for ParaView with --vtu."""
    from flexrv.cli._common import check_output_dir, check_output_file
    from flexrv.errors import InputError
    from flexrv.post.results import load_results
    from flexrv.viz.rings import render_rings_png, show_rings, write_pvd

    if not (result_dir / "results.nc").exists():
        raise InputError(f"{result_dir} is not a result folder (no results.nc)")
    if png is not None:
        check_output_file(png, "--png", (".png",))
    if vtu is not None:
        check_output_dir(vtu, "--vtu", allow_existing=True)
    if every < 1:
        raise InputError(f"--every {every}: must be >= 1")
    res = load_results(result_dir)
    t = res.time
    if time is not None and not (len(t) and t[0] - 1e-12 <= time <= t[-1] + 1e-12):
        raise InputError(
            f"--time {time:g} s is not allowed: the run covers {t[0]:g} .. {t[-1]:g} s"
            if len(t)
            else f"--time {time:g} s: the run has no records"
        )
    data = {"result_dir": str(result_dir)}
    if show:
        data["interactive"] = show_rings(res, time, scale, field, rebuild=rebuild)
        if not data["interactive"]:
            console.print("no display: writing the PNG instead", style="yellow")
    if not data.get("interactive"):
        data["png"] = str(render_rings_png(res, png or result_dir / "rings.png", time, scale, field, rebuild=rebuild))
    if vtu is not None:

        def notice(frames, size):
            from rich.console import Console

            Console(stderr=True, markup=False, highlight=False).print(
                f"writing {frames} frames of the rings to {vtu}: at most {size / 1e6:.3g} MB "
                f"(--every {every}; a larger --every writes fewer)"
            )
            data["vtu_frames"], data["vtu_bytes_estimate"] = frames, size

        data["pvd"] = str(write_pvd(res, vtu, every=every, field=field, notice=notice, rebuild=rebuild))

    def render(d):
        console.print(kv_table("view", [(k, v, "") for k, v in d.items()]))

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    app.command("view")(view)
