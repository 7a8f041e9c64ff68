"""Helpers for tests that start flexrv in a child process and signal it."""

from __future__ import annotations

import signal
from pathlib import Path


def sigint_default() -> None:
    """``preexec_fn`` of a child that a test sends SIGINT: the child starts with SIGINT at its
    default disposition, so Python installs its KeyboardInterrupt handler there. A process
    started in the background by a non-interactive shell (``cmd &``, ``nohup``) has SIGINT
    ignored, every child inherits that, and Python then leaves it ignored: the signal would do
    nothing whatever flexrv does, and the test would test how pytest was started."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def stored_files(folder: Path, pattern: str = "*.json") -> list[Path]:
    """The files of ``folder`` matching ``pattern`` whose write has finished. An atomic write's
    temporary file (``.<name>.<pid>.<random>.tmp<suffix>``, :func:`flexrv.cache.atomic_write_text`)
    is hidden and not one of them, though pathlib's glob matches hidden names: a test that kills a
    run once a file is stored must not count a file still being written."""
    return sorted(p for p in folder.glob(pattern) if not p.name.startswith("."))
