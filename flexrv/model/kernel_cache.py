"""First-run notice for the numba kernels.

The hot kernels (the fused kernel of the compiled force elements, the ball-bearing rows)
are compiled by numba on their first call and cached on disk (``cache=True``) in
``NUMBA_CACHE_DIR``, which flexrv sets to ``<user cache>/flexrv/numba/<version>``
(:func:`flexrv.cache.numba_cache_dir`; a damaged entry is discarded and compiled
again, :func:`flexrv.cache.guard_numba_cache`). The first run of a fresh install
therefore spends most of its time compiling: :func:`announce_compile` prints one short
line before that happens (and the command line one line at its start,
:func:`flexrv.cli.first_run_notice`). Ctrl-C or SIGTERM during the compilation end the
run at once (:func:`stop_now`). The time estimates quoted come from
``benchmarks/bench_first_run.py`` (docs/benchmarks.md).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

#: modules whose cached numba dispatchers a run may compile (every dispatcher found in them counts)
KERNEL_MODULES = (
    "flexrv.geometry.cycloid",
    "flexrv.contact.laws",
    "flexrv.analysis.mesh_stiffness",
    "flexrv.model.pins",
    "flexrv.model.gear_stage",
    "flexrv.model.cranks_discs",
    "flexrv.model.loads",
    "flexrv.model.main_bearing_rigid",
    "flexrv.model.kernels",
    "flexrv.model.bearing_kernel",
)
#: prefix of the fused kernels generated from the element registry (:mod:`flexrv.model.core.registry`);
#: their dispatchers are listed as ``fused.<name>``
GENERATED_PREFIX = "flexrv.model.core._generated."
#: the compiled functions a run calls directly, per kind of force element (they compile their callees
#: into themselves): the fused element of the kernel groups and the ball-bearing rows. A helper a run
#: never calls (e.g. row_kernel, which the tests and the quasi-static path use) stays uncached and must
#: not trigger the notice on every run
RUN_ENTRY_POINTS = {
    "fused": ("fused.fused_kernel", "fused.fused_history", "kernels.copy_records_if_same"),
    "rows": ("bearing_kernel.row_element", "bearing_kernel.row_history"),
}
#: first-compile time [s] of the rigid model's kernels on 2 cores (benchmarks/bench_first_run.py), for the notice
COMPILE_ESTIMATE_S = 60
#: a whole first run [s] on 2 cores (kernels and FE bodies of a preset), for the command line's notice
FIRST_RUN_ESTIMATE_S = 120


def uncached_kernels(modules: dict | None = None) -> list[str]:
    """Names of the kernels of the already imported modules (:data:`KERNEL_MODULES` and the
    generated fused kernels) whose on-disk cache index does not exist yet (they will compile
    on first call). Modules not imported are not used by the run and are skipped; without
    numba the list is empty."""
    modules = sys.modules if modules is None else modules
    names = [(m, m.rsplit(".", 1)[-1]) for m in KERNEL_MODULES]
    names += [(m, "fused") for m in sorted(modules) if m.startswith(GENERATED_PREFIX)]
    out = []
    for mod_name, label in names:
        mod = modules.get(mod_name)
        if mod is None:
            continue
        for attr, disp in sorted(vars(mod).items()):
            cache = getattr(disp, "_cache", None)
            index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
            if index is not None and not Path(index).exists():
                out.append(f"{label}.{attr}")
    return out


def cache_dir() -> str:
    """Where numba writes its cache (``NUMBA_CACHE_DIR``, set by flexrv at import)."""
    from flexrv.cache import numba_cache_dir

    return str(numba_cache_dir())


def stop_now(signum: int) -> None:
    """End the process at once with exit code 128 + ``signum`` (130 Ctrl-C, 143 SIGTERM),
    after flushing stdout and stderr: for a signal that arrives before a run has
    integrated its first step (numba compiling its kernels for a minute holds the run
    in that step), when there are no partial results to keep."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(128 + int(signum))


def announce_compile(stream=None, modules: dict | None = None, kinds=None) -> bool:
    """Print one short line, ``flexrv: compiling numba kernels (once, ~60 s or more; ...)``, on
    stderr if a kernel the run calls (:data:`RUN_ENTRY_POINTS` of ``kinds``, default all)
    is not cached yet; returns whether it printed."""
    missing = uncached_kernels(modules)
    kinds = RUN_ENTRY_POINTS if kinds is None else kinds
    entries = {name for kind in kinds for name in RUN_ENTRY_POINTS[kind]}
    if not entries.intersection(missing):
        # only helpers the run does not call are uncached: nothing compiles now
        return False
    stream = sys.stderr if stream is None else stream
    print(
        f"flexrv: compiling numba kernels (once, ~{COMPILE_ESTIMATE_S} s or more; cached in {cache_dir()})",
        file=stream,
        flush=True,
    )
    return True
