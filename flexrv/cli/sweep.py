"""CLI: ``flexrv sweep SPEC.toml`` — resumable parameter sweeps on dask.distributed."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from flexrv.cli._common import JSON_HELP, console, emit, kv_table


def sweep(spec: Path = typer.Argument(..., help="Sweep specification TOML (see flexrv.sweep)."),
          out: Optional[Path] = typer.Option(None, "--out", help="Results directory (default results/<name>)."),
          scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Address of an existing dask scheduler (default: a LocalCluster)."),
          workers: Optional[int] = typer.Option(None, "--workers", help="LocalCluster worker processes (default: CPU count)."),
          retry_failed: bool = typer.Option(False, "--retry-failed", help="Recompute cases recorded as failed."),
          json: bool = typer.Option(False, "--json", help=JSON_HELP)) -> None:
    """Run a grid/list of design variations of a task; killed sweeps resume where they stopped."""
    from flexrv.sweep import load_spec, run_sweep

    summary = run_sweep(load_spec(spec), out_dir=out, scheduler=scheduler, n_workers=workers,
                        retry_failed=retry_failed, progress=not json)
    data = {"out_dir": str(summary.out_dir), "cases": summary.total, "computed": summary.computed,
            "skipped_existing": summary.skipped, "failed": summary.failed,
            "table_csv": str(summary.table_csv), "table_nc": str(summary.table_nc),
            "plots": [str(p) for p in summary.plots]}

    def render(d):
        console.print(kv_table("sweep", [(k, v, "") for k, v in d.items() if k != "plots"]))

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    app.command("sweep")(sweep)
