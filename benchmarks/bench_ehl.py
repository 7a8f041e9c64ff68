"""Benchmark of the EHL solver and the EHL-corrected contact law.

Prints wall and CPU time per solve at 65^2, 129^2, 257^2 grids (default scheme, plus the
first-order fast path at 129^2) for two cases
(circular M = 260, L = 11.4; rv221 main-bearing ball M ~ 720, L = 6.6, k ~ 9) and
the contact-law evaluation time for 52 contacts (2 rows x 26 balls) in the three modes.

Run:  OPENBLAS_NUM_THREADS=1 python benchmarks/bench_ehl.py   (one core, as the goal states)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from flexrv.ehl.law import EHLPointLaw  # noqa: E402
from flexrv.ehl.maps import film_map  # noqa: E402
from flexrv.ehl.solver import LubricantProperties, solve_point_contact  # noqa: E402

CASES = {
    "circular M=260": (100.0, 1.0, 0.01, 0.01, 2.2e11, LubricantProperties(0.05, 2e-8, 0.67, 1.96e8, 870.0)),
    "rv221 ball M=720": (
        97.7,
        0.0548,
        0.01389,
        0.39,
        2.2857e11,
        LubricantProperties(0.13, 2e-8, 0.68, 1.96e8, 870.0, 0.6e-9, 1.7e-9),
    ),
}


def bench_solver(repeats: int = 2) -> None:
    """Fixed grids 65^2 (first order), 129^2 and 257^2 (second-order wedge + Richardson h_c, no
    refinement), the fast first-order path (``wedge_order=1, extrapolate=False``) at 129^2, and the
    default adaptive solve (scheme ``+A``: 129^2 refined until h_c changes < 2 %; the grid
    column shows where it stopped)."""
    print(
        f"{'case':18s} {'grid':>6s} {'scheme':>8s} {'wall [s]':>9s} {'cpu [s]':>8s} {'Newton':>7s} "
        f"{'h_c [nm]':>9s} {'h_c grid':>9s} {'h_min [nm]':>10s}"
    )
    runs = [
        (65, {}),
        (129, dict(grid_tol=None)),
        (129, dict(wedge_order=1, extrapolate=False)),
        (257, dict(grid_tol=None)),
        (129, {}),
    ]
    for name, (q, u, rx, ry, e, lub) in CASES.items():
        for n, kw in runs:
            best_wall = best_cpu = np.inf
            for _ in range(repeats if n < 257 else 1):
                t0, c0 = time.perf_counter(), time.process_time()
                res = solve_point_contact(q, u, rx, ry, e, lub, grid=n, **kw)
                best_wall = min(best_wall, time.perf_counter() - t0)
                best_cpu = min(best_cpu, time.process_time() - c0)
            scheme = f"o{res.wedge_order}" + ("+R" if res.extrapolated else "") + ("+A" if not kw and n >= 129 else "")
            print(
                f"{name:18s} {res.grid:4d}^2 {scheme:>8s} {best_wall:9.3f} {best_cpu:8.3f} "
                f"{res.iterations:3d}/{res.total_iterations:<3d} {res.h_central * 1e9:9.2f} "
                f"{res.h_central_grid * 1e9:9.2f} {res.h_min * 1e9:10.2f}"
            )


def bench_law(n_calls: int = 2000) -> None:
    q, u, rx, ry, e, lub = CASES["rv221 ball M=720"]
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["FLEXRV_CACHE"] = tmp
        t0 = time.perf_counter()
        fmap = film_map(rx, ry, e, lub, (20.0, 100.0), (0.03, 0.1), n_load=3, n_speed=3, grid=33)
        t_map = time.perf_counter() - t0
        t0 = time.perf_counter()
        film_map(rx, ry, e, lub, (20.0, 100.0), (0.03, 0.1), n_load=3, n_speed=3, grid=33)
        t_load = time.perf_counter() - t0
    print(f"\nfilm map 3x3 on 33^2: build {t_map:.2f} s, reload from cache {t_load * 1e3:.1f} ms")
    delta = np.linspace(-1e-7, 1e-5, 52)
    rate = np.full(52, 1e-4)
    speed = np.full(52, u)
    print(f"{'law mode':16s} {'us/call (52 contacts)':>22s}")
    for mode in ("dry", "hamrock_dowson", "map"):
        law = EHLPointLaw(rx, ry, e, lub, mode=mode, film_map=fmap, c_max=500.0)
        law(delta, rate, speed)
        t0 = time.perf_counter()
        for _ in range(n_calls):
            law(delta, rate, speed)
        print(f"{mode:16s} {(time.perf_counter() - t0) / n_calls * 1e6:22.1f}")


if __name__ == "__main__":
    bench_solver()
    bench_law()
