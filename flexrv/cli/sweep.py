"""CLI: ``flexrv sweep SPEC.toml`` — resumable parameter sweeps on dask.distributed."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table

FORCE_HELP = "Allow more local workers than the machine has CPU cores."


def sweep(
    spec: Path = typer.Argument(..., help="Sweep specification TOML (see flexrv.sweep)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Results directory (default results/<name>)."),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", help="Address of an existing dask scheduler (default: a LocalCluster)."
    ),
    workers: Optional[int] = typer.Option(
        None, "--workers", min=1, help="LocalCluster worker processes, 1 to the CPU count (default: CPU count)."
    ),
    retry_failed: bool = typer.Option(False, "--retry-failed", help="Recompute cases recorded as failed."),
    batch: Optional[int] = typer.Option(
        None, "--batch", min=1, help="Cases per dask task (default: 4 tasks per worker, at most 32 cases each)."
    ),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Run a grid/list of design variations of a task; killed sweeps resume where they stopped.
    Exit code 1 if any case failed (recorded in table.csv with its error)."""
    from flexrv.cli._common import check_output_dir
    from flexrv.sweep import check_workers, load_spec, run_sweep

    check_workers(workers, force)
    sweep_spec = load_spec(spec)
    target = out if out is not None else Path("results") / sweep_spec.name
    check_output_dir(target, "--out", allow_existing=True)  # an existing sweep directory is resumed
    summary = run_sweep(
        sweep_spec,
        out_dir=target,
        scheduler=scheduler,
        n_workers=workers,
        retry_failed=retry_failed,
        progress=not json,
        force=force,
        batch=batch,
    )
    data = {
        "out_dir": str(summary.out_dir),
        "cases": summary.total,
        "computed": summary.computed,
        "skipped_existing": summary.skipped,
        "failed": summary.failed,
        "table_csv": str(summary.table_csv),
        "table_nc": str(summary.table_nc),
        "plots": [str(p) for p in summary.plots],
        "cpu": summary.cpu.as_dict(),
    }

    def render(d):
        console.print(kv_table("sweep", [(k, v, "") for k, v in d.items() if k not in ("plots", "cpu")]))

    emit(data, json, render)
    if summary.failed:
        from flexrv.cli import print_error

        print_error(f"{summary.failed} of {summary.total} cases failed (see the error column of {summary.table_csv})")
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("sweep")(sweep)
