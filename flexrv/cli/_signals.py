"""Ctrl-C and SIGTERM while the main thread is inside a long call into compiled code.

Python runs a signal's handler in the main thread between two bytecodes, so a signal that
arrives while that thread is inside one long call into a compiled library (gmsh meshing a
body, SuperLU factorising its stiffness, a large BLAS product, LLVM generating a kernel) waits
until the call returns: seconds to tens of seconds on a first run. These libraries release the
GIL while they work, so a thread can still act: :func:`start_watchdog` registers a wakeup file
descriptor (the interpreter writes the signal's number into it the moment the signal arrives)
and a daemon thread that reads it. If after :data:`GRACE_S` the main thread's Python frame has
not moved, its handler has not run: the thread ends the process with 128 + signum
(:func:`flexrv.model.kernel_cache.stop_now`, which kills a background compilation first). When
the main thread did move, its handler ran and decided (a simulation that has integrated steps
stops after the current one and keeps its results), and the thread does nothing.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

#: how long the main thread may take to run a signal's handler before the process is ended [s]
GRACE_S = 1.0
#: how often the watchdog looks at the main thread while it waits [s]
POLL_S = 0.05
#: the signals acted on
SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _main_position() -> tuple[int, int] | None:
    """(id of the main thread's innermost frame, its last bytecode offset), None if not running."""
    frame = sys._current_frames().get(threading.main_thread().ident)
    return None if frame is None else (id(frame), frame.f_lasti)


def _stuck(before, grace: float) -> bool:
    """Whether the main thread stays at ``before`` for ``grace`` seconds (its handler not run)."""
    end = time.monotonic() + grace
    while time.monotonic() < end:
        time.sleep(POLL_S)
        if _main_position() != before:
            return False
    return True


def _watch(fd: int, grace: float) -> None:
    from flexrv.model.kernel_cache import stop_now

    while True:
        try:
            data = os.read(fd, 64)
        except OSError:
            return
        if not data:
            return
        received = [s for s in data if s in SIGNALS]
        if not received:
            continue
        if _stuck(_main_position(), grace):
            stop_now(received[-1])


def start_watchdog(grace: float = GRACE_S) -> bool:
    """Start the watchdog thread (module docstring); False where it cannot be (not the main
    thread, or a wakeup descriptor another component set already)."""
    if threading.current_thread() is not threading.main_thread():
        return False
    r, w = os.pipe()
    os.set_blocking(w, False)
    try:
        previous = signal.set_wakeup_fd(w, warn_on_full_buffer=False)
    except ValueError:
        os.close(r), os.close(w)
        return False
    if previous != -1:  # someone else listens: leave theirs in place
        signal.set_wakeup_fd(previous)
        os.close(r), os.close(w)
        return False
    threading.Thread(target=_watch, args=(r, grace), daemon=True, name="flexrv-signal-watchdog").start()
    return True
