"""First-run and warm-run cost of the two main jobs, as whole processes:
``flexrv simulate rv221 --model rigid`` and ``flexrv te rv40e``.

    python benchmarks/bench_first_run.py [--only simulate|te] [--t-end S] [--checkout DIR ...] [--lines]

Cold means an empty cache: ``FLEXRV_CACHE_DIR`` points at a new temporary folder, so the
FE bodies (meshes, condensed compliances), the EHL maps and numba's compiled kernels
(``<cache>/numba/<version>``, :func:`flexrv.cache.numba_cache_dir`) are all built again.
Warm is the same command run again on that filled cache. For each run the benchmark
prints the wall time, the CPU time of the process and of every process it started (the
background compilation, :mod:`flexrv.model.kernel_cache`), the time to its first printed
line (stdout and stderr merged, unbuffered, as a terminal shows them) and the load
average when it started (other work on the machine stretches the wall time). With
``--lines`` every line the command printed is listed with its time (where the time goes).

``--checkout DIR`` (repeatable) runs the commands of another checkout of flexrv (its
folder is put first on PYTHONPATH); with several, the runs alternate between them, so a
change in the machine's load affects both alike (paired comparison).

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
import threading
import time
from pathlib import Path

#: the measured commands: name -> arguments of ``python -m flexrv``
COMMANDS = {
    "simulate": ["simulate", "rv221", "--model", "rigid"],
    "te": ["te", "rv40e"],
}
ROOT = Path(__file__).resolve().parents[1]


def _cpu_of_descendants(root: int, seen: dict) -> None:
    """Record in ``seen`` (pid -> (role, CPU s)) the CPU time of ``root`` and of its children and
    grandchildren now (Linux /proc; elsewhere nothing)."""
    tick = os.sysconf("SC_CLK_TCK")
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                text = (entry / "stat").read_text()
                cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            fields = text.rsplit(")", 1)[-1].split()
            stats[int(entry.name)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / tick, cmd)
    depth, level = {root: 0}, [root]
    for k in (1, 2):  # the background process and its helper
        level = [pid for pid, (ppid, _, _) in stats.items() if ppid in level]
        depth.update((pid, k) for pid in level)
    for pid, k in depth.items():
        if pid in stats:
            seen[pid] = (("command", "background", "its helper")[k], stats[pid][1])


def run(args: list[str], env: dict, cwd: Path = ROOT) -> dict:
    """Run ``python -m flexrv ARGS`` in ``cwd`` (``-m`` puts the working folder first on sys.path:
    the checkout whose flexrv runs): wall, CPU of it and its descendants, first line, the lines
    with their times."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", *args],
        env=env,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        bufsize=1,
    )
    first, first_line, lines, seen = None, "", [], {}
    stop = threading.Event()

    def sample():  # the CPU of each process, sampled until it ends (the background processes end first)
        while not stop.wait(0.5):
            _cpu_of_descendants(proc.pid, seen)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    for line in proc.stdout:
        now = time.perf_counter() - t0
        if first is None and line.strip():
            first, first_line = now, line.strip()
        lines.append((now, line.rstrip()))
    code = proc.wait()
    wall = time.perf_counter() - t0
    stop.set()
    sampler.join()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)  # includes the descendants it reaped
    if code != 0:
        sys.stdout.write("\n".join(text for _, text in lines[-30:]) + "\n")
        raise SystemExit(f"flexrv {' '.join(args)} exited {code}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    per_process = ", ".join(f"{name} {c:.1f} s" for name, c in sorted(seen.values(), key=lambda x: x[0] != "command"))
    return {
        **{"wall": wall, "cpu": cpu, "first": first, "first_line": first_line[:100], "lines": lines},
        **{"load": load, "per_process": per_process},
    }


def environment(checkout: Path, cache: Path) -> dict:
    """The environment of a run of ``checkout`` with the cache folder ``cache``."""
    env = dict(os.environ, FLEXRV_CACHE_DIR=str(cache), PYTHONUNBUFFERED="1")
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(checkout), os.environ.get("PYTHONPATH")) if p)
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("FLEXRV_CACHE", None)
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    env.setdefault("MPLBACKEND", "Agg")
    return env


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(COMMANDS), action="append", help="measure only this command")
    ap.add_argument("--t-end", type=float, default=None, help="--t-end of the simulate run [s] (default: its own)")
    ap.add_argument("--checkout", type=Path, action="append", help="a flexrv checkout to run (default: this one)")
    ap.add_argument("--lines", action="store_true", help="list every printed line with its time")
    ap.add_argument("--cold-only", action="store_true", help="skip the warm runs")
    a = ap.parse_args()
    names = a.only or list(COMMANDS)
    checkouts = [c.resolve() for c in (a.checkout or [ROOT])]
    print(f"{time.strftime('%Y-%m-%d %H:%M')} UTC, {os.cpu_count()} CPUs, {os.uname().nodename}", flush=True)
    with tempfile.TemporaryDirectory(prefix="flexrv-first-run-") as tmp:
        for name in names:
            args = list(COMMANDS[name])
            if name == "simulate" and a.t_end is not None:
                args += ["--t-end", f"{a.t_end:g}"]
            for label in ("cold",) if a.cold_only else ("cold", "warm"):
                for k, checkout in enumerate(checkouts):  # one cache per command and checkout: cold starts empty
                    env = environment(checkout, Path(tmp) / f"cache-{name}-{k}")
                    out = os.path.join(tmp, f"{name}-{label}-{k}")
                    r = run([*args, "--out", out], env, checkout)
                    where = f" [{checkout}]" if len(checkouts) > 1 else ""
                    print(
                        f"{label} flexrv {' '.join(args)}{where}: wall {r['wall']:.1f} s, CPU {r['cpu']:.1f} s "
                        f"(with its child processes), first line after {r['first']:.2f} s ({r['first_line']!r}), "
                        f"load average {r['load']:.2f} at start",
                        flush=True,
                    )
                    print(f"    CPU by process (sampled every 0.5 s): {r['per_process']}", flush=True)
                    if a.lines:
                        for t, text in r["lines"]:
                            if text.startswith("flexrv"):
                                print(f"    {t:7.2f} s  {text[:150]}", flush=True)


if __name__ == "__main__":
    main()
