"""Benchmark: the whole ``flexrv compare PRESET --t-end T`` (rigid + flexible model,
plots, summary), optionally from a cold cache (meshing and CMS of the rings included).

    python benchmarks/bench_compare.py [--preset rv221] [--t-end 1.0] [--cold] [--parts main_bearing]

Goal of the flexible-bearing issue: ``flexrv compare rv221 --t-end 1`` from a cold
cache in <= 3 min on 2 cores. Prints the wall time of each phase.
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
    t0 = time.perf_counter()
    cmp = run_compare(args.preset, t_end=args.t_end, parts=args.parts.split(","), out_dir=out)
    total = time.perf_counter() - t0
    t = cmp.numbers["timing"]
    print(f"compare {args.preset} --t-end {args.t_end} --parts {args.parts} ({'cold' if args.cold else 'warm'} cache)")
    print(f"  rigid model (build + run + save): {t['rigid_s']:8.1f} s")
    print(f"  flexible model (build incl. meshing/CMS + run + save): {t['flexible_s']:8.1f} s")
    print(f"  plots + summary: {total - t['rigid_s'] - t['flexible_s']:8.1f} s")
    print(f"  total: {total:8.1f} s   (goal: 180 s for rv221, t_end 1 s, cold)")


if __name__ == "__main__":
    main()
