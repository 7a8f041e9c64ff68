"""First-run and warm-run cost of the two main jobs, as whole processes:
``flexrv simulate rv221 --model rigid`` and ``flexrv te rv40e``.

    python benchmarks/bench_first_run.py [--only simulate|te] [--t-end S]

Cold means an empty cache: ``FLEXRV_CACHE_DIR`` points at a new temporary folder, so the
FE bodies (meshes, condensed compliances), the EHL maps and numba's compiled kernels
(``<cache>/numba/<version>``, :func:`flexrv.cache.numba_cache_dir`) are all built again.
Warm is the same command run again on that filled cache. For each run the benchmark
prints the wall time, the CPU time of the process and the time to its first printed
line (stdout and stderr merged, unbuffered, as a terminal shows them).

Goals (a fresh clone on 2 cores): cold ``simulate rv221 --model rigid`` <= 60 s,
cold ``te rv40e`` <= 45 s, each printing within 2 s of its start.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

#: the measured commands: name -> arguments of ``python -m flexrv``
COMMANDS = {
    "simulate": ["simulate", "rv221", "--model", "rigid"],
    "te": ["te", "rv40e"],
}


def run(args: list[str], env: dict) -> dict:
    """Run ``python -m flexrv ARGS`` and time it: wall, CPU of the child, first output line."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        bufsize=1,
    )
    first, first_line, lines = None, "", []
    for line in proc.stdout:
        if first is None and line.strip():
            first, first_line = time.perf_counter() - t0, line.strip()
        lines.append(line)
    code = proc.wait()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if code != 0:
        sys.stdout.write("".join(lines[-30:]))
        raise SystemExit(f"flexrv {' '.join(args)} exited {code}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": wall, "cpu": cpu, "first": first, "first_line": first_line[:100]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(COMMANDS), action="append", help="measure only this command")
    ap.add_argument("--t-end", type=float, default=None, help="--t-end of the simulate run [s] (default: its own)")
    a = ap.parse_args()
    names = a.only or list(COMMANDS)
    with tempfile.TemporaryDirectory(prefix="flexrv-first-run-") as tmp:
        env = dict(os.environ, FLEXRV_CACHE_DIR=os.path.join(tmp, "cache"), PYTHONUNBUFFERED="1")
        env.pop("NUMBA_CACHE_DIR", None)
        env.pop("FLEXRV_CACHE", None)
        env.setdefault("OMP_NUM_THREADS", "1")
        env.setdefault("OPENBLAS_NUM_THREADS", "1")
        env.setdefault("MPLBACKEND", "Agg")
        for name in names:  # one cache per command: each cold run starts empty
            env["FLEXRV_CACHE_DIR"] = os.path.join(tmp, f"cache-{name}")
            args = list(COMMANDS[name])
            if name == "simulate" and a.t_end is not None:
                args += ["--t-end", f"{a.t_end:g}"]
            for label in ("cold", "warm"):
                out = os.path.join(tmp, f"{name}-{label}")
                r = run([*args, "--out", out], env)
                print(
                    f"{label} flexrv {' '.join(args)}: wall {r['wall']:.1f} s, CPU {r['cpu']:.1f} s, "
                    f"first line after {r['first']:.2f} s ({r['first_line']!r})",
                    flush=True,
                )


if __name__ == "__main__":
    main()
