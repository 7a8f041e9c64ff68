"""The ``flexrv`` command line.

Each command group lives in its own module under :mod:`flexrv.cli` and exposes
``register(app)``; commands are thin wrappers around library functions. Every
command accepts ``--json`` (machine-readable output on stdout) and prints a rich
table by default. Any :class:`flexrv.errors.FlexrvError` becomes one clear message
on stderr and exit code 2 — never a traceback.
"""

from __future__ import annotations

import importlib
import sys

import typer

from flexrv.errors import FlexrvError

app = typer.Typer(
    name="flexrv",
    help="Transmission error, stiffness and contact loads of RV reducers (gmsh -> FE -> CMS -> Exudyn).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

#: Command modules; each defines ``register(app)``. A module that is not present
#: (capability not installed yet) is skipped.
_COMMAND_MODULES = ("design", "ehl", "mesh", "simulate", "te", "compare", "view", "sweep", "tolerance", "workflows")

for _name in _COMMAND_MODULES:
    try:
        _mod = importlib.import_module(f"flexrv.cli.{_name}")
    except ModuleNotFoundError as exc:  # only skip the command module itself
        if exc.name != f"flexrv.cli.{_name}":
            raise
        continue
    _mod.register(app)


def main() -> None:
    """Console-script entry point: run the app, map user errors to exit code 2."""
    try:
        app(standalone_mode=False)
    except FlexrvError as exc:
        from rich.console import Console

        Console(stderr=True).print(f"[bold red]error:[/] {exc}", highlight=False, markup=True)
        sys.exit(2)
    except typer.Exit as exc:
        sys.exit(exc.exit_code)
    except typer.Abort:
        sys.exit(130)
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as exc:  # click usage errors
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show()
            sys.exit(2)
        raise
