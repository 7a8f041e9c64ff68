"""Faults a run must survive with a clear outcome: signals while numba compiles, a
cluster endpoint that is not a dask scheduler, full or read-only disks, spec limits.

Each test names the mechanism it checks; the CLI cases run ``python -m flexrv`` in a
subprocess, as a user would.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _env(**extra) -> dict:
    return {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MPLBACKEND": "Agg",
        **extra,
    }


# ----------------------------------------------------------------- signals while compiling
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_during_first_compile_exits_within_5s(tmp_path, sig, code):
    """With an empty numba cache the first step of a run compiles the kernels (tens of
    seconds to minutes); a signal then ends the run within 5 s with 128 + signum and
    leaves no run folder (nothing was integrated). The compile notice is one short line."""
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", "simulate", "rv221", "--model", "rigid", "--t-end", "0.01", "--out", str(out)],
        cwd=tmp_path,
        env=_env(NUMBA_CACHE_DIR=str(tmp_path / "numba")),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        notice = proc.stderr.readline()  # printed just before the kernels compile
        assert "compiling numba kernels" in notice, notice
        assert len(notice) < 200 and "laws." not in notice  # one short line, no list of functions
        time.sleep(2.0)  # well inside the compilation (>= 10 s of it on this model)
        assert proc.poll() is None, "the run ended before the signal: nothing compiled?"
        t0 = time.monotonic()
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=30)
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == code, stderr[-2000:]
    assert elapsed < 5.0, elapsed
    assert "Traceback" not in stderr
    assert not out.exists()
