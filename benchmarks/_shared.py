"""What the benchmark scripts share: this checkout's flexrv in this process and in the dask
workers it spawns (one BLAS thread, headless plots), CPU clocks, and the presets with short
speed and load ramps. Imports no flexrv at module level, so a script can call
:func:`use_this_checkout` before its own flexrv imports."""

from __future__ import annotations

import os
import resource
import sys
from pathlib import Path

#: the checkout the benchmarks belong to
ROOT = str(Path(__file__).resolve().parent.parent)


def use_this_checkout() -> None:
    """Import this checkout's flexrv here and in spawned workers (PYTHONPATH), with one BLAS
    thread and the Agg backend unless the caller set them."""
    here = str(Path(__file__).resolve().parent)  # the scripts' own helpers, for workers that unpickle them
    if ROOT not in sys.path:
        sys.path.insert(0, ROOT)
    paths = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p and p not in (ROOT, here)]
    os.environ["PYTHONPATH"] = os.pathsep.join([ROOT, here, *paths])
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("MPLBACKEND", "Agg")


def children_cpu_s() -> float:
    """CPU time [s] of this process's finished child processes (user + system)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_with_children_s() -> float:
    """CPU time [s] of this process and its finished children."""
    from flexrv.sweep import process_cpu_s

    return process_cpu_s() + children_cpu_s()


def quick_ramps(name: str):
    """The preset ``name`` with rated speed and load reached at 5 ms (a benchmark's window
    then starts in the operating point)."""
    from flexrv.design import load

    r = load(name)
    op = r.operating.model_copy(update={"speed_ramp_time_s": 0.005, "load_ramp_start_s": 0.0, "load_ramp_end_s": 0.005})
    return r.model_copy(update={"operating": op})
