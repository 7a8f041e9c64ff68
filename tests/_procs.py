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
    """The files of ``folder`` matching ``pattern`` whose write has finished: not an atomic write's
    temporary file (:func:`flexrv.cache.temp_file_writer`), which pathlib's glob also matches
    (``.<name>.<pid>.<random>.tmp.json``): a test that kills a run once a file is stored must not
    count a file still being written."""
    from flexrv.cache import temp_file_writer

    return sorted(p for p in folder.glob(pattern) if temp_file_writer(p.name) is None)
