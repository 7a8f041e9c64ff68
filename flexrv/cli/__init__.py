"""The ``flexrv`` command line.

Each command group lives in its own module under :mod:`flexrv.cli` and exposes
``register(app)``; commands are thin wrappers around library functions. Every
command accepts ``--json`` (machine-readable output on stdout) and prints a rich
table by default. Any :class:`flexrv.errors.FlexrvError` and every usage error
(unknown option or command, a value of the wrong type, a missing argument)
becomes one clear message on stderr and exit code 2 — never a traceback. A bare
``flexrv`` (or a command that needs arguments, given none) prints the help on
stderr and exits 2, like any other usage error. Ctrl-C exits 130 and SIGTERM 143 in every phase.
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

import typer

from flexrv.errors import FlexrvError

app = typer.Typer(
    name="flexrv",
    help="Transmission error, stiffness and contact loads of RV reducers (gmsh -> FE -> CMS -> Exudyn).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # plain help texts: rich markup would eat the units in square brackets ("End time [s]")
    rich_markup_mode=None,
)


@app.callback()
def _options(
    cache_dir: Path = typer.Option(
        None,
        "--cache-dir",
        help="Folder of the cached meshes, reduced bodies and EHL maps "
        "(default: $FLEXRV_CACHE_DIR, else the user cache directory, "
        "~/.cache/flexrv on Linux).",
    ),
) -> None:
    """Transmission error, stiffness and contact loads of RV reducers (gmsh -> FE -> CMS -> Exudyn)."""
    if cache_dir is not None:
        from flexrv.cache import CACHE_ENV

        if cache_dir.exists() and not cache_dir.is_dir():
            from flexrv.errors import InputError

            raise InputError(f"--cache-dir {cache_dir}: exists and is not a directory")
        os.environ[CACHE_ENV] = str(cache_dir)


#: Command modules; each defines ``register(app)``. A module that is not present
#: (capability not installed yet) is skipped.
_COMMAND_MODULES = (
    "design", "ehl", "mesh", "simulate", "te", "compare", "view", "sweep", "tolerance", "workflows", "optimize",
    "measured", "validate", "calibrate",
)  # fmt: skip

for _name in _COMMAND_MODULES:
    try:
        _mod = importlib.import_module(f"flexrv.cli.{_name}")
    except ModuleNotFoundError as exc:  # only skip the command module itself
        if exc.name != f"flexrv.cli.{_name}":
            raise
        continue
    _mod.register(app)

#: exit code of a usage or input error
USAGE_EXIT = 2

#: the garbage collector's generation thresholds in a command's process. A command creates
#: millions of long-lived objects (modules, numba's compiled kernels, xarray, matplotlib) and
#: few reference cycles; with Python's default (700, 10, 10) the collector scans the growing
#: heap again and again (~0.45 s CPU of a warm ``simulate`` or ``te``, a seventh of it), with
#: these thresholds ~0.1 s. Cycles are still collected, in larger batches.
GC_THRESHOLDS = (50_000, 20, 10)


def collect_garbage_less() -> None:
    """Set :data:`GC_THRESHOLDS` (once the command line runs, not on import)."""
    import gc

    gc.set_threshold(*GC_THRESHOLDS)


def _click_modules() -> list:
    """The click exception modules in use: typer >= 0.2x vendors its own click
    (``typer._click``), older typer uses the ``click`` package; both are checked."""
    mods = []
    for name in ("typer._click.exceptions", "click.exceptions"):
        try:
            mods.append(importlib.import_module(name))
        except ImportError:
            continue
    return mods


def _types(attr: str) -> tuple[type, ...]:
    return tuple(getattr(m, attr) for m in _click_modules() if hasattr(m, attr))


def print_error(message: str) -> None:
    """One error message on stderr, printed literally (no rich markup parsing)."""
    from rich.console import Console
    from rich.text import Text

    Console(stderr=True, highlight=False, soft_wrap=True).print(Text("error: ", style="bold red") + Text(str(message)))


def _argv_value(opts, argv: list[str]) -> str | None:
    """The raw command-line text given for an option (``--dt abc`` or ``--dt=abc``)."""
    for i, arg in enumerate(argv):
        for opt in opts:
            if arg == opt and i + 1 < len(argv):
                return argv[i + 1]
            if arg.startswith(opt + "="):
                return arg[len(opt) + 1 :]
    return None


def _param_name(param) -> str:
    name = getattr(param, "human_readable_name", None) or getattr(param, "name", None) or "?"
    return str(name).upper()


def usage_message(exc, argv: list[str]) -> str:
    """One line for a click usage error: the command, the option or argument,
    the value given and what is allowed."""
    ctx = getattr(exc, "ctx", None)
    command = ctx.command_path if ctx is not None else "flexrv"
    command = "flexrv" + command[command.find(" ") :] if " " in command else "flexrv"
    kind = type(exc).__name__
    param = getattr(exc, "param", None)
    msg = exc.format_message() if hasattr(exc, "format_message") else str(exc)
    msg = " ".join(str(msg).split())
    if kind == "NoSuchOption":
        opt = getattr(exc, "option_name", "?")
        allowed = []
        if ctx is not None:
            for p in ctx.command.params:
                allowed += [o for o in getattr(p, "opts", []) if o.startswith("-")]
        return f"{command}: unknown option {opt}; allowed options: {', '.join(allowed + ['--help'])}"
    if kind == "BadParameter" and param is not None:
        opts = [o for o in getattr(param, "opts", []) if o.startswith("-")]
        name = opts[0] if opts else _param_name(param)
        value = _argv_value(opts, argv) if opts else None
        reason = str(getattr(exc, "message", msg)).removeprefix("Value error, ")
        reason = " ".join(reason.split())
        expected = getattr(getattr(param, "type", None), "name", None)
        shown = f" {value!r}" if value is not None else ""
        tail = f" (expected: {expected})" if expected and expected not in reason.lower() else ""
        return f"{command}: invalid value{shown} for {name}: {reason}{tail}"
    if kind == "MissingParameter" and param is not None:
        opts = [o for o in getattr(param, "opts", []) if o.startswith("-")]
        name = opts[0] if opts else _param_name(param)
        what = "option" if opts else "argument"
        usage = " ".join(ctx.get_usage().split()) if ctx is not None else ""
        return f"{command}: missing required {what} {name}" + (f" ({usage})" if usage else "")
    if kind == "UsageError" and ctx is not None and "command" in msg.lower() and hasattr(ctx.command, "commands"):
        return f"{msg} Available commands: {', '.join(sorted(ctx.command.commands))}"
    return f"{command}: {msg}"


def empty_value_message(argv: list[str]) -> str | None:
    """The message for an empty option value (``--out ""``, ``--out=``) or an empty
    argument (``design ""``), or None: no option or argument of flexrv may be empty (an
    empty path would mean the current directory, an empty name nothing)."""
    command = next((a for a in argv if not a.startswith("-")), "")
    where = f"flexrv {command}" if command else "flexrv"
    for i, arg in enumerate(argv):
        if arg.startswith("--") and arg.endswith("=") and len(arg) > 3:
            return f"{where}: empty value for {arg[:-1]}; give a value"
        if arg.strip() == "":
            prev = argv[i - 1] if i > 0 else ""
            if prev.startswith("-") and "=" not in prev:
                return f"{where}: empty value {arg!r} for {prev}; give a value"
            return f"{where}: empty argument {arg!r} (argument {i + 1}); give a value"
    return None


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the process is (like Ctrl-C's KeyboardInterrupt), so every
    phase of a command stops the same way: cleanup handlers run, exit code 143."""

    signum = 15


#: SIGTERM received by this process (typer returns a KeyboardInterrupt as exit code 130, whatever raised it)
_TERMINATED: list[int] = []


def _raise_terminated(signum, frame) -> None:
    _TERMINATED.append(signum)
    raise Terminated()


#: commands that may build FE bodies or compile numba kernels (the first-run notice)
_BUILDING_COMMANDS = frozenset(
    {"simulate", "stiffness-test", "te", "design", "compare", "tolerance", "sweep", "optimize", "calibrate"}
    | {"validate", "workflow", "mesh", "modes", "report", "ehl"}
)


def first_run_notice(args: list[str], stream=None) -> str | None:
    """The one line a command prints at its start when numba's kernel cache is still empty
    (a first run on this machine or of this flexrv version): what the minutes go to and that
    it happens once. None (nothing printed) for a warm cache, ``--help`` and commands that
    build nothing."""
    from flexrv.cache import numba_cache_dir

    command = next((a for a in args if a in _BUILDING_COMMANDS), None)
    if command is None or "--help" in args:
        return None
    folder = numba_cache_dir()
    try:
        warm = folder.is_dir() and any(folder.rglob("*.nbi"))
    except OSError:
        warm = False
    if warm:
        return None
    from flexrv.model.kernel_cache import FIRST_RUN_ESTIMATE_S

    line = (
        f"flexrv {command}: first run: compiling numba kernels and building the design's FE bodies "
        f"(once, about {FIRST_RUN_ESTIMATE_S} s on 2 cores; later runs take seconds)"
    )
    print(line, file=sys.stderr if stream is None else stream, flush=True)
    return line


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point: run the app, map user errors to exit code 2,
    Ctrl-C to 130 and SIGTERM to 143 in every phase (a run that is integrating installs
    its own handlers and keeps its partial results); the exit code of a command
    (``typer.Exit``) is passed on."""
    import signal

    collect_garbage_less()
    args = list(sys.argv[1:] if argv is None else argv)
    empty = empty_value_message(args)
    if empty:
        print_error(empty)
        sys.exit(USAGE_EXIT)
    try:
        signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread (an embedding application): its own handling applies
        pass
    from flexrv.model.kernel_cache import stop_on_signal_while_compiling

    stop_on_signal_while_compiling()  # (a signal inside numba's compilation would otherwise be lost)
    if argv is None:  # this process's own command line: a signal inside a long compiled call ends it
        from flexrv.cli._signals import start_watchdog

        start_watchdog()
    first_run_notice(args)
    no_args = _types("NoArgsIsHelpError")
    click_exc = _types("ClickException")
    click_exit = _types("Exit")
    click_abort = _types("Abort")
    try:
        try:
            rv = app(args=args, prog_name="flexrv", standalone_mode=False)
        finally:  # a command that failed or was stopped before writing leaves no empty run folder
            from flexrv.cli._common import remove_unused_outputs

            remove_unused_outputs()
    except FlexrvError as exc:
        print_error(str(exc))
        sys.exit(USAGE_EXIT)
    except OSError as exc:  # a file the user named cannot be read or written (disk full, read-only)
        where = getattr(exc, "filename", None)
        print_error(f"{exc.strerror or exc}: {where}" if where else f"{exc.strerror or exc}")
        sys.exit(USAGE_EXIT)
    except (typer.Exit, *click_exit) as exc:
        sys.exit(_signal_code(exc.exit_code))
    except (typer.Abort, *click_abort, KeyboardInterrupt) as exc:
        sys.exit(128 + getattr(exc, "signum", 15 if _TERMINATED else 2))
    except no_args as exc:  # bare `flexrv` / a command given no arguments: help, usage exit code
        print(exc.format_message(), file=sys.stderr)
        sys.exit(USAGE_EXIT)
    except click_exc as exc:
        if type(exc).__name__ in (
            "BadParameter",
            "MissingParameter",
            "NoSuchOption",
            "UsageError",
            "BadOptionUsage",
            "BadArgumentUsage",
        ):
            try:
                text = usage_message(exc, args)
            except Exception:  # never a traceback for a usage error
                text = " ".join(str(exc.format_message()).split())
            print_error(text)
            sys.exit(USAGE_EXIT)
        print_error(" ".join(str(exc.format_message()).split()))
        sys.exit(exc.exit_code if exc.exit_code else USAGE_EXIT)
    if isinstance(rv, int) and not isinstance(rv, bool):
        sys.exit(_signal_code(rv))


def _signal_code(code: int) -> int:
    """Exit code 143 for a run that SIGTERM stopped (typer reports any KeyboardInterrupt, and so
    SIGTERM's :class:`Terminated`, as 130), else ``code``."""
    return 128 + _TERMINATED[-1] if code == 130 and _TERMINATED else code
