"""Benchmark: tolerance-study throughput on rv40e with 1 and 2 LocalCluster workers
at the study's default resolution (:data:`flexrv.studies.tolerance.DEFAULT_RESOLUTION`:
one crank revolution, 2 points per pin mesh), with the rv40e tolerance preset.

    python benchmarks/bench_tolerance.py [--samples 16 128] [--workers 1 2]

Every worker count runs two studies of different sizes N1 < N2 (fresh output
folders, nothing resumed) and separates the whole study's wall time T(N) = T0 +
N / rate into

* the fixed start-up T0 (LocalCluster and worker processes, imports, numba's
  cache load on each worker, sampling, NetCDF and plots) and
* the steady rate (samples per second) = (N2 - N1) / (T(N2) - T(N1)),

and projects 1,000 samples as T0 + 1000 / rate (target: <= 10 min on 2 cores). Wall
time on a shared machine is noisy; the CPU time of
the study (this process and its worker processes, which are reaped when the
cluster closes: getrusage SELF + CHILDREN) is printed beside it, with its own
per-sample value (CPU s per sample, the same on 1 or 2 workers if the scaling is
clean).

``--client N``: the client's CPU against the workers', paired in one run: the same study
of N samples on 2 workers one sample per dask task with dask's default settings (the
former execution), then in batches (:func:`flexrv.sweep.batch_size`, the builds of a
batch sharing the error-free constants) with :data:`flexrv.sweep.DASK_CONFIG`. Prints the
client's CPU (getrusage of this process) during the execution and over the whole study,
the workers' CPU (their own timers, per batch) and the ratios (goal: client <= 5 % of
the workers').
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _shared import cpu_with_children_s, use_this_checkout

use_this_checkout()


def study(n: int, workers: int, res: dict) -> tuple[float, float, int]:
    """(wall s, CPU s, failed) of one fresh study of ``n`` samples."""
    from flexrv.studies.tolerance import StudyConfig, run_study

    with tempfile.TemporaryDirectory() as tmp:
        cfg = StudyConfig(
            design="rv40e",
            tolerances="rv40e",
            samples=n,
            seed=1,
            sampler="sobol",
            workers=workers,
            what_if_samples=0,
            out=tmp,
            resolution=res,
        )
        c0, t0 = cpu_with_children_s(), time.perf_counter()
        r = run_study(cfg, progress=False)
        return time.perf_counter() - t0, cpu_with_children_s() - c0, r["failed"]


def client_share(n: int, workers: int, res: dict) -> None:
    """The --client comparison (module docstring)."""
    import flexrv.sweep as sw
    from flexrv.studies.tolerance import StudyConfig, run_study

    tuned = dict(sw.DASK_CONFIG)
    with tempfile.TemporaryDirectory() as tmp:  # imports and first calls before either leg
        run_study(StudyConfig("rv40e", 2, tolerances="rv40e", workers=1, what_if_samples=0, out=tmp), progress=False)
    for label, batch, config in (("one sample per task, dask defaults", 1, {}), ("batched", None, tuned)):
        sw.DASK_CONFIG = config
        with tempfile.TemporaryDirectory() as tmp:
            cfg = StudyConfig(
                design="rv40e",
                tolerances="rv40e",
                samples=n,
                seed=1,
                workers=workers,
                what_if_samples=0,
                out=tmp,
                resolution=res,
                batch=batch,
            )
            t0 = time.perf_counter()
            c = run_study(cfg, progress=False)["cpu"]
            wall = time.perf_counter() - t0
        print(
            f"{label}: {n} samples, {c['batches']} tasks, wall {wall:.1f} s; client {c['client_cpu_s']:.2f} CPU s "
            f"during the execution, {c['client_study_cpu_s']:.2f} over the study; workers {c['workers_cpu_s']:.2f} "
            f"CPU s ({c['workers_cpu_s'] / n:.3f} per sample); client / workers: execution "
            f"{c['client_over_workers']:.4f}, study {c['client_study_cpu_s'] / c['workers_cpu_s']:.4f}",
            flush=True,
        )
    sw.DASK_CONFIG = tuned


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, nargs=2, default=[16, 128], metavar=("N1", "N2"))
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--crank-revolutions", type=float, default=1.0)
    ap.add_argument("--points-per-mesh", type=int, default=2)
    ap.add_argument("--client", type=int, default=0, metavar="N", help="client vs workers CPU, N samples")
    args = ap.parse_args()
    import flexrv
    from flexrv.studies.tolerance import DEFAULT_RESOLUTION

    print(f"flexrv from {Path(flexrv.__file__).parent}", flush=True)
    res = dict(DEFAULT_RESOLUTION, crank_revolutions=args.crank_revolutions, points_per_mesh=args.points_per_mesh)
    if args.client:
        client_share(args.client, max(args.workers), res)
        return
    n1, n2 = sorted(args.samples)
    if n1 >= n2 or n1 < 1:
        ap.error("--samples N1 N2 with 1 <= N1 < N2")
    rates = {}
    for w in args.workers:
        (t1, c1, f1), (t2, c2, f2) = study(n1, w, res), study(n2, w, res)
        rate = (n2 - n1) / (t2 - t1)
        fixed = t1 - n1 / rate
        cpu_per = (c2 - c1) / (n2 - n1)
        rates[w] = rate
        print(
            f"workers {w}: {n1} samples {t1:.1f} s wall ({c1:.1f} s CPU), {n2} samples {t2:.1f} s wall "
            f"({c2:.1f} s CPU), failed {f1} / {f2}",
            flush=True,
        )
        print(
            f"  fixed start-up {fixed:.1f} s, steady {rate:.2f} samples/s ({cpu_per:.3f} CPU s per sample); "
            f"projected 1,000 samples: {(fixed + 1000 / rate) / 60:.1f} min",
            flush=True,
        )
    if 1 in rates and 2 in rates:
        print(f"steady-rate scaling 1 -> 2 workers: x{rates[2] / rates[1]:.2f}")


if __name__ == "__main__":
    main()
