"""Numba compile time per kernel of a first run, in one process (no background compilation).

    python benchmarks/bench_compile.py [--checkout DIR] [--top N] -- simulate rv221 --model rigid
    python benchmarks/bench_compile.py -- te rv40e
    python benchmarks/bench_compile.py -- job simulate rv221 rigid     # the background job alone
    python benchmarks/bench_compile.py -- job te rv40e

Runs ``python -m flexrv ARGS`` with an empty numba cache (``FLEXRV_CACHE_DIR`` points at a new
temporary folder holding hard links of the FE bodies and EHL maps of the user cache, so only
the compilation is cold) and ``FLEXRV_BACKGROUND_COMPILE=0`` (everything compiles in the
command's own process, where it can be timed). A listener of numba's ``numba:compile`` events
times (CPU) every compiled function: its inclusive time, its exclusive time (without the functions
compiled while typing it, its callees) and the part of that spent in LLVM (optimisation and
machine-code generation: ``numba:llvm_lock``). Prints the process's CPU time, the total
compile time and the functions sorted by exclusive time. ``job COMMAND ...`` runs only the
background job of that command (:mod:`flexrv.cli._precompile`, rigid bodies): its kernels
without the FE bodies, the quickest measure of a change of the kernels' compile time.
``--background`` keeps the background compilation on: the listener then times what the
command compiles in its own process.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the child: a listener on numba's compile events around the command (JSON of the events to a file)
CHILD = r"""
import json, os, resource, runpy, sys, time
from numba.core import event as ev

events, stack, llvm = [], [], [0, 0.0]

class Listener(ev.Listener):
    def on_start(self, e):
        if e.kind == "numba:compile":
            d = e.data["dispatcher"]
            name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
            stack.append([name, time.process_time(), 0.0, 0.0])
        elif e.kind == "numba:llvm_lock":
            if llvm[0] == 0:
                llvm[1] = time.process_time()
            llvm[0] += 1

    def on_end(self, e):
        if e.kind == "numba:compile":
            name, t0, children, in_llvm = stack.pop()
            incl = time.process_time() - t0
            if stack:
                stack[-1][2] += incl
            events.append((name, incl, incl - children, in_llvm, stack[-1][0] if stack else ""))
        elif e.kind == "numba:llvm_lock":
            llvm[0] -= 1
            if llvm[0] == 0 and stack:
                stack[-1][3] += time.process_time() - llvm[1]

for kind in ("numba:compile", "numba:llvm_lock"):
    ev.register(kind, Listener())

def dump():
    r = resource.getrusage(resource.RUSAGE_SELF)
    with open(os.environ["BENCH_COMPILE_OUT"], "w") as fh:
        json.dump({"events": events, "cpu": r.ru_utime + r.ru_stime}, fh)

import atexit
atexit.register(dump)
try:
    if sys.argv[1] == "job":  # the background job of a command alone (rigid bodies: no FE body is built)
        from flexrv.cli import _precompile
        from flexrv.design import load

        if sys.argv[2] == "simulate":
            from flexrv.simulation import DEFAULT_DT

            _precompile.simulate_job(load(sys.argv[3]), sys.argv[4], {}, DEFAULT_DT, None)
        else:
            _precompile.te_job(load(sys.argv[3]))
    else:
        sys.argv = ["flexrv", *sys.argv[1:]]
        runpy.run_module("flexrv", run_name="__main__")
finally:
    dump()
"""


def linked_cache(tmp: Path) -> Path:
    """A cache folder with hard links (or copies) of the user cache's files except numba's."""
    from flexrv.cache import cache_dir

    src = Path(os.environ.get("FLEXRV_CACHE_DIR") or cache_dir())
    dst = tmp / "cache"
    for path in src.rglob("*"):
        rel = path.relative_to(src)
        if rel.parts[0] in ("numba", "fused") or not path.is_file():
            continue
        (dst / rel).parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(path, dst / rel)
        except OSError:
            (dst / rel).write_bytes(path.read_bytes())
    return dst


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkout", type=Path, default=ROOT, help="the flexrv checkout to run (default: this one)")
    ap.add_argument("--top", type=int, default=25, help="functions listed")
    ap.add_argument("--json", type=Path, default=None, help="also write the events as JSON here")
    ap.add_argument("--background", action="store_true", help="keep the background compilation on")
    ap.add_argument("args", nargs="+", help="arguments of python -m flexrv")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="flexrv-compile-") as tmp:
        tmp = Path(tmp)
        cache = linked_cache(tmp)
        out = tmp / "events.json"
        env = dict(os.environ, FLEXRV_CACHE_DIR=str(cache), FLEXRV_BACKGROUND_COMPILE="0", BENCH_COMPILE_OUT=str(out))
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(a.checkout.resolve()), os.environ.get("PYTHONPATH")) if p)
        # numba reads its cache folder when imported, which the listener does before flexrv sets it
        env["NUMBA_CACHE_DIR"] = str(cache / "numba")
        if a.background:
            env.pop("FLEXRV_BACKGROUND_COMPILE")
        args = list(a.args)
        if args[0] in ("simulate", "te") and "--out" not in args:
            args += ["--out", str(tmp / "out")]
        t0 = time.perf_counter()
        proc = subprocess.run(  # (in the checkout: ``python -c`` puts the working folder first on sys.path)
            [sys.executable, "-c", CHILD, *args], env=env, capture_output=True, text=True, cwd=a.checkout.resolve()
        )
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            print(proc.stdout[-3000:], proc.stderr[-3000:])
            raise SystemExit(f"flexrv {' '.join(args)} exited {proc.returncode}")
        data = json.loads(out.read_text())
    events = data["events"]
    top = [e for e in events if e[1] == max(x[1] for x in events)] if events else []
    total = sum(e[2] for e in events)
    llvm = sum(e[3] for e in events)
    print(
        f"flexrv {' '.join(a.args)} [{a.checkout}]: wall {wall:.1f} s, CPU {data['cpu']:.1f} s, "
        f"compile {total:.1f} s (LLVM {llvm:.1f} s) in {len(events)} compilations"
    )
    by_name: dict = {}
    for name, incl, excl, lv, _ in events:
        n, i, e, v = by_name.get(name, (0, 0.0, 0.0, 0.0))
        by_name[name] = (n + 1, i + incl, e + excl, v + lv)
    print(f"{'function':70s} {'n':>3s} {'incl s':>8s} {'excl s':>8s} {'LLVM s':>8s}")
    for name, (n, incl, excl, lv) in sorted(by_name.items(), key=lambda kv: -kv[1][2])[: a.top]:
        print(f"{name[-70:]:70s} {n:3d} {incl:8.2f} {excl:8.2f} {lv:8.2f}")
    if a.json is not None:
        a.json.write_text(json.dumps({"wall": wall, **data}))
    del top


if __name__ == "__main__":
    main()
