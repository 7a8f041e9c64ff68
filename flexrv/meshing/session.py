"""A quiet, exception-safe gmsh session (the only place gmsh is initialised).

gmsh keeps global state; :func:`gmsh_session` initialises it with terminal output
off, yields the module and always finalises it, so an error inside a builder never
leaves a half-initialised gmsh behind (a second ``gmsh.initialize`` in the same
process would otherwise inherit the old model).
"""

from __future__ import annotations

import contextlib
from typing import Iterator


@contextlib.contextmanager
def gmsh_session(model_name: str = "flexrv", threads: int = 1) -> Iterator["object"]:
    """Initialise gmsh quietly, yield the ``gmsh`` module, finalise on exit.

    Parameters
    ----------
    model_name : name of the (single) gmsh model created in the session.
    threads : number of meshing threads (``General.NumThreads``).
    """
    import gmsh

    if gmsh.isInitialized():  # a crashed caller left a session open: start clean
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False, run=False, interruptible=False)
    _restore_signal_handlers()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 0)
        gmsh.option.setNumber("General.NumThreads", int(threads))
        gmsh.model.add(model_name)
        yield gmsh
    finally:
        gmsh.finalize()


def _restore_signal_handlers() -> None:
    """gmsh's initialisation installs its own C handler of SIGTERM, which kills the process
    (exit -15) instead of letting Python's handler stop the command with 143: give Python's
    handlers of SIGTERM and SIGINT back (main thread only; elsewhere signals are not ours)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return
    for sig in (signal.SIGTERM, signal.SIGINT):
        handler = signal.getsignal(sig)
        if handler is not None:
            signal.signal(sig, handler)
