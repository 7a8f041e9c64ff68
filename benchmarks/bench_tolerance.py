"""Benchmark: tolerance-study throughput on rv40e (samples per second with 1 and 2
LocalCluster workers) at the study's default resolution
(:data:`flexrv.studies.tolerance.DEFAULT_RESOLUTION`: one crank revolution, 2
points per pin mesh), with the rv40e tolerance preset; prints the projected wall
time of 1,000 samples (issue 13's target: <= 10 min on this machine's 2 cores).

    python benchmarks/bench_tolerance.py [--samples 8] [--workers 1 2] [--crank-revolutions 1]

Each run uses a fresh output directory (nothing is resumed). The rate is the
whole study's wall time (cluster start-up and numba's first-call compile on each
worker included), i.e. what a user sees for a study of this size; with more
samples the fixed part weighs less.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--crank-revolutions", type=float, default=1.0)
    ap.add_argument("--points-per-mesh", type=int, default=2)
    args = ap.parse_args()
    from flexrv.studies.tolerance import DEFAULT_RESOLUTION, StudyConfig, run_study

    res = dict(DEFAULT_RESOLUTION, crank_revolutions=args.crank_revolutions, points_per_mesh=args.points_per_mesh)
    rates = {}
    for w in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            cfg = StudyConfig(design="rv40e", tolerances="rv40e", samples=args.samples, seed=1, sampler="sobol",
                              workers=w, what_if_samples=0, out=tmp, resolution=res)
            t0 = time.perf_counter()
            r = run_study(cfg, progress=False)
            wall = time.perf_counter() - t0
        rates[w] = args.samples / wall
        print(f"workers {w}: {args.samples} samples in {wall:.1f} s -> {rates[w]:.3f} samples/s "
              f"({r['failed']} failed); projected 1,000 samples: {1000 / rates[w] / 60:.1f} min", flush=True)
    if 1 in rates and 2 in rates:
        print(f"scaling 1 -> 2 workers: x{rates[2] / rates[1]:.2f}")


if __name__ == "__main__":
    main()
