"""First-run notice for the numba kernels.

The hot kernels (closest point of the pin gap, the impact law, the ball-bearing row)
are compiled by numba on their first call and cached on disk (``cache=True``; the
folder is numba's default ``__pycache__`` next to the sources, or ``NUMBA_CACHE_DIR``).
The first run of a fresh install therefore spends most of its time compiling, with
no progress: :func:`announce_compile` prints one line before that happens.

Measured (rv221, ``flexrv simulate rv221 --model rigid``, fresh ``NUMBA_CACHE_DIR``,
2 shared cores, numba 0.68): 110 s first run, of which 86 s numba compilation —
67 s for the pin-gap closest-point kernel (``geometry.cycloid._closest_point_newton``
with the curve kernels it calls) and 20 s for the impact law
(``contact.laws._impact_kernel``); 16 s for the same run with the cache filled.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

#: (module, attribute) of every cached numba dispatcher that a run may compile
KERNELS = (("flexrv.geometry.cycloid", "_NEWTON"), ("flexrv.geometry.cycloid", "_CURVE"),
           ("flexrv.geometry.cycloid", "_DOT2"), ("flexrv.contact.laws", "_impact_jit"),
           ("flexrv.contact.laws", "_STEP"), ("flexrv.model.bearing_kernel", "row_kernel"),
           ("flexrv.model.bearing_kernel", "row_force_kernel"))
#: measured first-compile time [s] of the kernels above (see module docstring), for the message
COMPILE_ESTIMATE_S = 90


def uncached_kernels(modules: dict | None = None) -> list[str]:
    """Names of the kernels of the already imported modules whose on-disk cache index
    does not exist yet (they will compile on first call). Modules not imported are
    not used by the run and are skipped; without numba the list is empty."""
    modules = sys.modules if modules is None else modules
    out = []
    for mod_name, attr in KERNELS:
        mod = modules.get(mod_name)
        disp = getattr(mod, attr, None) if mod is not None else None
        cache = getattr(disp, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        if index is not None and not Path(index).exists():
            out.append(f"{mod_name.rsplit('.', 1)[-1]}.{attr}")
    return out


def cache_dir() -> str:
    """Where numba writes its cache (``NUMBA_CACHE_DIR`` or ``__pycache__`` beside the sources)."""
    return os.environ.get("NUMBA_CACHE_DIR") or str(Path(__file__).resolve().parents[1] / "**" / "__pycache__")


def announce_compile(stream=None, modules: dict | None = None) -> bool:
    """Print ``flexrv: compiling numba kernels (once, ~90 s) ...`` on stderr if any kernel
    the run uses is not cached yet; returns whether it printed."""
    missing = uncached_kernels(modules)
    if not missing:
        return False
    stream = sys.stderr if stream is None else stream
    print(f"flexrv: compiling numba kernels (once, ~{COMPILE_ESTIMATE_S} s; cached afterwards in {cache_dir()}): "
          f"{', '.join(missing)}", file=stream, flush=True)
    return True
