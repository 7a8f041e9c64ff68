"""First-run cost: `flexrv simulate rv40e --t-end 0.01` with an empty numba cache
(every kernel compiled once) against a warm cache, as whole processes.

    python benchmarks/bench_first_run.py

Prints both wall times and their difference (the one-off compile time the CLI
announces with its "compiling numba kernels" line).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time


def run(env: dict, out: str) -> float:
    t0 = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "flexrv", "simulate", "rv40e", "--t-end", "0.01", "--out", out, "--overwrite", "--json"],
        env=env,
        check=True,
        capture_output=True,
    )
    return time.perf_counter() - t0


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(
            os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba"), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1"
        )
        cold = run(env, os.path.join(tmp, "a"))
        warm = run(env, os.path.join(tmp, "b"))
    print(
        f"simulate rv40e --t-end 0.01: cold numba cache {cold:.1f} s, warm {warm:.1f} s, "
        f"one-off compile {cold - warm:.1f} s"
    )


if __name__ == "__main__":
    main()
