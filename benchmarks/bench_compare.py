"""Benchmark: the whole ``flexrv compare PRESET --t-end T`` (rigid + flexible model,
plots, summary), optionally from a cold cache (meshing and CMS of the rings included).

    python benchmarks/bench_compare.py [--preset rv221] [--t-end 1.0] [--cold] [--parts main_bearing]

Goal: ``flexrv compare rv221 --t-end 1`` from a cold mesh/CMS cache in
<= 60 s (2 cores, one BLAS thread; the numba cache is warm: see
bench_first_run.py for the first compile). Prints the wall time of each phase,
the process CPU time (``time.process_time``; quote it on a shared machine) and
the TE statistics of both models (so speed never buys a different answer).

The numba cache is not included: a fresh clone's first flexible run compiles its kernels
(bench_first_run.py). Measured figures with date and machine: docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="rv221")
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--parts", default="main_bearing")
    parser.add_argument("--cold", action="store_true", help="empty mesh/CMS cache (meshing and reduction timed)")
    args = parser.parse_args()
    if args.cold:
        os.environ["FLEXRV_CACHE"] = tempfile.mkdtemp(prefix="flexrv-bench-")
    from flexrv.studies.compare import run_compare

    out = tempfile.mkdtemp(prefix="flexrv-compare-")
    c0 = time.process_time()
    t0 = time.perf_counter()
    cmp = run_compare(args.preset, t_end=args.t_end, parts=args.parts.split(","), out_dir=out)
    total = time.perf_counter() - t0
    cpu = time.process_time() - c0
    t = cmp.numbers["timing"]
    print(f"compare {args.preset} --t-end {args.t_end} --parts {args.parts} ({'cold' if args.cold else 'warm'} cache)")
    print(
        f"  rigid model (build + run + save):      {t['rigid_s']:8.1f} s wall {t['rigid_cpu_s']:8.1f} s CPU "
        f"(solve {t['rigid_solve_cpu_s']:.1f} s CPU)"
    )
    print(
        f"  flexible model (build + run + save):   {t['flexible_s']:8.1f} s wall {t['flexible_cpu_s']:8.1f} s CPU "
        f"(build incl. meshing/CMS {t['flexible_build_s']:.1f} s wall, solve {t['flexible_solve_cpu_s']:.1f} s CPU)"
    )
    if "main_bearing" in args.parts:
        from flexrv.design import load
        from flexrv.model.flexible_bearing import flexible_rings

        for label, rings in flexible_rings(load(args.preset)).items():  # cache hits: the run's bodies
            if label in ("inner", "outer"):
                info = rings[0].body.info
                print(
                    f"    {label} ring: {info['n_dof']} DOF, {rings[0].n_modes} modes; FE assembly "
                    f"{info['t_assemble_s']:.1f} s, reduction (sparse LU + attachment modes) {info['t_reduce_s']:.1f} s"
                    " wall (in the build)"
                )
    print(f"  plots + summary: {total - t['rigid_s'] - t['flexible_s']:8.1f} s wall")
    print(f"  total: {total:8.1f} s wall, {cpu:8.1f} s CPU   (goal: 60 s for rv221, t_end 1 s, cold)")
    for name in ("rigid", "flexible"):
        n = cmp.numbers[name]
        print(
            f"  {name:8s} TE mean {n['te_mean_arcsec']:10.4f} arcsec, p-p {n['te_pp_arcsec']:8.4f} arcsec, "
            f"rms fluctuation {n['te_rms_fluctuation_arcsec']:8.4f} arcsec"
        )


if __name__ == "__main__":
    main()
