"""Helpers for tests that start flexrv in a child process and signal it."""

from __future__ import annotations

import signal


def sigint_default() -> None:
    """``preexec_fn`` of a child that a test sends SIGINT: the child starts with SIGINT at its
    default disposition, so Python installs its KeyboardInterrupt handler there. A process
    started in the background by a non-interactive shell (``cmd &``, ``nohup``) has SIGINT
    ignored, every child inherits that, and Python then leaves it ignored: the signal would do
    nothing whatever flexrv does, and the test would test how pytest was started."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
