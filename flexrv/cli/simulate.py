"""CLI: ``flexrv simulate PRESET`` and ``flexrv stiffness-test PRESET``."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from flexrv.cli._common import (
    JSON_HELP,
    OVERWRITE_HELP,
    PRESET_HELP,
    check_output_dir,
    console,
    emit,
    kv_table,
    skip_final_collection,
)


def _bar(enabled: bool):
    """A rich progress callback on stderr (keeps stdout clean for --json)."""
    if not enabled:
        return False
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress(
        TextColumn("[bold]simulating[/]"),
        BarColumn(),
        TextColumn("{task.completed:.4f}/{task.total:.4f} s"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    state = {"task": None}

    def report(t, t_end):
        if state["task"] is None:
            bar.start()
            state["task"] = bar.add_task("sim", total=t_end)
        bar.update(state["task"], completed=t)
        if t >= t_end * (1 - 1e-9):
            bar.stop()

    def stop():
        if state["task"] is not None:
            bar.stop()

    report.stop = stop
    return report


MODEL_HELP = (
    "Model name: rigid (5-DOF main-bearing element), balls (ball-resolved main bearing, rigid rings) "
    "or flexible (reduced flexible parts, see --parts)."
)
PARTS_HELP = (
    "Elastic parts of the run, comma-separated (the others rigid): carrier, cycloid_disc (FE bodies, "
    "any --model) and, with --model flexible, main_bearing (flexible rings of both rows), crankshaft. "
    "Default: the design's carrier.body_model / second_stage.disc_body_model (and main_bearing for "
    "--model flexible); none: every part rigid."
)


def model_options(model: str, parts: str | None) -> dict:
    """Builder options of a model from the CLI's --parts
    (:func:`flexrv.model.factory.parts_options`)."""
    from flexrv.model.factory import parts_options

    return parts_options(model, parts)


def _default_out(preset: str, model: str, kind: str) -> Path:
    stem = Path(preset).stem
    return Path("results") / f"{stem}_{model}_{kind}_{time.strftime('%Y%m%d-%H%M%S')}"


BALLS_HELP = (
    "Ball-resolved main bearing (--model balls / flexible): the balls as point masses, or "
    "quasi-static (massless, solved inside the bearing rows). Default: quasi-static balls between "
    "rigid rings (--model balls), point masses between condensed flexible rings (--model flexible, "
    "which needs them)."
)
DT_HELP = (
    "Time step [s] (default flexrv.simulation.DEFAULT_DT = 1e-4 s: TE mean and lines within 0.05 arcsec / "
    "2 % of a 2.5e-5 s reference on rv40e, rigid and ball models, tests/test_time_step.py)."
)
CHECKPOINT_HELP = "Wall time between two checkpoints of the results into --out [s] (0: none)."
INTEGRATOR_HELP = (
    "Time integrator: 'compiled' (the compiled generalized-alpha around the fused force kernel; the "
    "default for models whose forces are all compiled, e.g. --model rigid) or 'exudyn' (Exudyn's "
    "solver, the reference; the default for models with Python force groups: balls, flexible). "
    "Same algorithm and Newton control, docs/integrator.md."
)


def _exit_code(res) -> int:
    """128 + signal number for a run stopped by a signal (130 Ctrl-C, 143 SIGTERM), else 0."""
    import signal

    if res.attrs.get("status") != "interrupted":
        return 0
    name = res.attrs.get("signal", "SIGINT")
    return 128 + int(getattr(signal, name, signal.SIGINT))


def simulate(
    preset: str = typer.Argument(None, help=PRESET_HELP + " Not with --resume."),
    model: str = typer.Option("rigid", "--model", help=MODEL_HELP),
    t_end: float = typer.Option(None, "--t-end", help="End time [s] (default: ramps + 0.2 s)."),
    dt: float = typer.Option(None, "--dt", help=DT_HELP),
    parts: str = typer.Option(None, "--parts", help=PARTS_HELP),
    ball_inertia: bool = typer.Option(None, "--ball-inertia/--quasi-static-balls", help=BALLS_HELP),
    out: Path = typer.Option(None, "--out", help="Output directory (default results/<run>/)."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    resume: Path = typer.Option(
        None, "--resume", help="Continue a killed run from the last checkpoint in this output directory."
    ),
    checkpoint: float = typer.Option(10.0, "--checkpoint-s", help=CHECKPOINT_HELP),
    integrator: str = typer.Option(None, "--integrator", help=INTEGRATOR_HELP),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Run the multibody model; write NetCDF, config, summary.md and PNGs.
    Checkpoints into --out while running; Ctrl-C or SIGTERM keeps the partial results
    (exit 130 / 143); --resume DIR continues a killed run."""
    import math

    from flexrv.cli._precompile import start_simulate
    from flexrv.errors import InputError
    from flexrv.post.io import xarray_without_dask
    from flexrv.simulation import DEFAULT_DT, Simulation

    xarray_without_dask()
    skip_final_collection()
    dt = DEFAULT_DT if dt is None else dt
    if not (math.isfinite(checkpoint) and checkpoint >= 0):
        raise InputError(f"--checkpoint-s {checkpoint}: must be a finite number >= 0 s")
    bar = _bar(not json)
    if resume is not None:
        if preset is not None or out is not None:
            raise InputError(
                "--resume DIR continues the run in DIR with its own design and options: give no PRESET and no --out"
            )
        if not resume.is_dir():
            raise InputError(f"--resume {resume}: not a directory")
        check_output_dir(resume, "--resume", allow_existing=True)
        out = resume
        try:
            extra = {} if integrator is None else {"integrator": integrator}
            sim, res = Simulation.resume(resume, progress=bar, checkpoint_s=checkpoint or None, **extra)
        finally:
            if bar:
                bar.stop()
        preset, model = res.attrs.get("preset", str(resume)), sim.model_name
    else:
        if preset is None:
            raise InputError("flexrv simulate: missing argument PRESET (a preset name or design TOML), or --resume DIR")
        options = model_options(model, parts)
        if ball_inertia is not None:
            options["ball_inertia"] = ball_inertia
        out = check_output_dir(out or _default_out(preset, model, "sim"), "--out", overwrite=overwrite)
        sim = Simulation(preset, model=model, model_options=options)
        start_simulate(sim, dt, integrator)  # a first run: its kernels compile in a second process
        try:
            res = sim.run(
                t_end=t_end, dt=dt, progress=bar, save_to=out, checkpoint_s=checkpoint or None, integrator=integrator
            )
        finally:
            if bar:
                bar.stop()
    if res.attrs.get("status") != "interrupted":
        res.save(out)
        if res.attrs.get("status") == "completed":  # saved in full: the resume data is no longer needed
            (Path(out) / "checkpoint.npz").unlink(missing_ok=True)
    from flexrv.post.stats import SUMMARY_KEYS, summary_table

    s = res.summary()
    data = {
        "output_dir": str(out),
        "status": s["status"],
        "ratio_simulated_over_theoretical": s["ratio_simulated_over_theoretical"],
        "ratio_theoretical": s["ratio_theoretical"],
        "ratio_simulated": s["ratio_simulated"],
        "steady_window_s": s["steady_window_s"],
        "steady": s["steady_state"],  # what summary.md says in words: its window is (NOT) STEADY, and why
        "steady_reason": s["steady_note"],
        "notes": s["notes"],
        "wall_time_s": sim.timing.get("solve_s"),
        "integrator": res.attrs.get("integrator"),
    }
    # the run's figures: the rows of the one summary table (summary.md's), then its unlisted keys present
    data.update({key: value for key, value, _ in summary_table(s)})
    data.update({row.key: s[row.key] for row in SUMMARY_KEYS if not row.listed and row.key in s})

    def render(d):
        shown = {k: v for k, v in d.items() if k not in ("steady_reason", "notes")}
        rows = [
            (*_label_unit(k), v if not isinstance(v, list) else f"{v[0]:.4g} - {v[1]:.4g}") for k, v in shown.items()
        ]
        console.print(kv_table(f"simulate {preset} ({model})", [(k, v, u) for k, u, v in rows]))
        for note in d["notes"]:
            console.print(f"note: {note}", style=None if d["steady"] else "yellow")

    emit(data, json, render)
    code = _exit_code(res)
    if code:
        raise typer.Exit(code)


def stiffness_test_cmd(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    model: str = typer.Option("rigid", "--model", help=MODEL_HELP),
    quarter_time: float = typer.Option(
        None,
        "--quarter-time",
        help="Duration of each quarter of the torque loop [s] "
        "(default flexrv.simulation.DEFAULT_QUARTER_TIME = 0.08 s: "
        "the branches are quasi-static on both presets).",
    ),
    dt: float = typer.Option(None, "--dt", help=DT_HELP),
    parts: str = typer.Option(None, "--parts", help=PARTS_HELP),
    out: Path = typer.Option(None, "--out", help="Output directory (default results/<run>/)."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    csv: Path = typer.Option(None, "--csv", help="Also write the loop as a measured-data CSV (flexrv measured)."),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
    uncertainty: int = typer.Option(
        None,
        "--uncertainty",
        help="Also propagate the design's [ranges] (estimated inputs) with N samples by the quasi-static route: "
        "median, 90 % interval and top contributors of the rigidities, lost motion and backlash (uncertainty.json).",
    ),
) -> None:
    """Virtual stiffness test: input locked, output torque 0 -> +rated -> -rated -> 0;
    torsional rigidity, lost motion, hysteresis loop PNG."""
    from flexrv.simulation import DEFAULT_DT, DEFAULT_QUARTER_TIME, stiffness_test

    dt = DEFAULT_DT if dt is None else dt
    quarter_time = DEFAULT_QUARTER_TIME if quarter_time is None else quarter_time
    options = model_options(model, parts)
    out = check_output_dir(out or _default_out(preset, model, "stiffness"), "--out", overwrite=overwrite)
    bar = _bar(not json)
    try:
        fig, res = stiffness_test(
            preset, model=model, quarter_time=quarter_time, dt=dt, progress=bar, save_to=out, model_options=options
        )
    finally:
        if bar:
            bar.stop()
    data = {"output_dir": str(out), **fig.named(), "reading": fig.reading(), "stiffness_budget": _budget(res)}
    if csv is not None:  # the loop in the measured-data format (flexrv.measured.writer)
        from flexrv.measured.writer import export_stiffness_test

        data["csv"] = str(
            export_stiffness_test(csv, res, f"flexrv stiffness-test {preset} --model {model}", quarter_time)
        )
    if uncertainty is not None:
        from flexrv.cli.te import uncertainty_report
        from flexrv.design import load

        data["uncertainty"] = uncertainty_report(load(preset), uncertainty, out, quiet=json)

    def render(d):
        from flexrv.cli.design import budget_table

        skip = ("stiffness_budget", "uncertainty", "reading")
        rows = [(*_label_unit(k), v) for k, v in d.items() if k not in skip]
        console.print(kv_table(f"stiffness test {preset} ({model})", [(k, v, u) for k, u, v in rows]))
        if "uncertainty" in d:
            from flexrv.cli.te import uncertainty_table

            console.print(uncertainty_table(d["uncertainty"]))
        b = d["stiffness_budget"]
        if not b.get("elements"):
            for note in b.get("notes", []):
                console.print(f"note: {note}", style="yellow")
            return
        console.print(
            budget_table(
                f"stiffness budget (quasi-static model at the test's pose, strain energy) at {b['torque_Nm']:.6g} N m",
                b,
            )
        )

    emit(data, json, render)


def _budget(res) -> dict:
    """The stiffness test's budget stored in its results (:func:`flexrv.analysis.budget.
    budget_from_dataset`) in engineering units; only its notes if it could not be computed."""
    from flexrv.analysis.budget import budget_from_dataset

    if "budget_element" not in res.ds.dims:
        return {"elements": {}, "notes": [n for n in res.ds.attrs.get("budget_notes", "").split("\n") if n]}
    return budget_from_dataset(res.ds).to_dict()


def _label_unit(key: str) -> tuple[str, str]:
    """(label, unit) of a unit-suffixed result key for the table's unit column."""
    from flexrv.cli._common import split_unit

    label, unit = split_unit(key)
    return label.replace("_", " "), unit


def register(app: typer.Typer) -> None:
    """Add ``simulate`` and ``stiffness-test`` to the app."""
    app.command("simulate")(simulate)
    app.command("stiffness-test")(stiffness_test_cmd)
