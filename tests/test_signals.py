"""A signal while the main thread is inside one long call into compiled code (here a BLAS
product that releases the GIL, as gmsh, SuperLU and LLVM do) ends a flexrv process within
about :data:`flexrv.cli._signals.GRACE_S`, with 128 + signum; without the watchdog the same
process runs on until the call returns (the control, so the test can fail)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests._procs import sigint_default

ROOT = Path(__file__).resolve().parents[1]

#: the child: size a single-threaded product to take ~LONG_S (at the fastest of three timed
#: 800 x 800 products), say "go", then run it
CHILD = """
import sys, time
import numpy as np
if sys.argv[1] == "watch":
    from flexrv.cli._signals import start_watchdog
    assert start_watchdog()
a = np.random.default_rng(0).standard_normal((800, 800))
t = 1e9
for _ in range(3):  # (the fastest of three: a rate measured under a passing load would size it short)
    t0 = time.perf_counter(); a @ a; t = min(t, time.perf_counter() - t0)
n = int(800 * (float(sys.argv[2]) / max(t, 1e-3)) ** (1 / 3))
b = np.random.default_rng(1).standard_normal((n, n))
print("go", flush=True)
b @ b
print("done", flush=True)
"""
LONG_S = 4.0


def _run(mode: str, sig: int) -> tuple[int, float]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    env["PYTHONPATH"] = f"{ROOT}{os.pathsep}{env.get('PYTHONPATH', '')}"
    if sig == signal.SIGTERM:  # as the CLI does: a Python-level handler (the interpreter's own for SIGINT)
        child = "import signal\nsignal.signal(signal.SIGTERM, lambda *a: (_ for _ in ()).throw(KeyboardInterrupt))\n"
    else:
        child = ""
    proc = subprocess.Popen(
        [sys.executable, "-c", child + CHILD, mode, str(LONG_S)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=sigint_default,
    )
    try:
        assert proc.stdout.readline().strip() == "go"
        time.sleep(0.3)
        t0 = time.monotonic()
        proc.send_signal(sig)
        proc.communicate(timeout=120)
        return proc.returncode, time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_inside_a_long_compiled_call_ends_the_process(sig):
    """With the watchdog: exit 128 + signum within GRACE_S + 1.5 s of the signal; the control
    without it ends only when the ~4 s product returns (later than the watchdog's run by > 1 s)."""
    from flexrv.cli._signals import GRACE_S

    code, elapsed = _run("watch", sig)
    assert code == 128 + sig, code
    assert elapsed < GRACE_S + 1.5, elapsed
    _, control = _run("plain", sig)
    assert control > elapsed + 1.0, (control, elapsed)
