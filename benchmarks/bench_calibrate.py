"""Benchmark: a 3-parameter calibration of rv40e on one stiffness loop (goal: <= 2 min on the
machine's 2 cores).

    python benchmarks/bench_calibrate.py [--workers 0 2]

The loop is synthetic: rv40e with three known "true" values (pin-disc clearance through the
equidistant modification, crank support preload, needle roller length), the quasi-static
loop at 40 torques per quarter (:func:`flexrv.studies.calibrate.synthetic_loop`) with
0.005 arcmin of normal angle noise, written and read through the measured-data format. The
calibration (:func:`flexrv.studies.calibrate.calibrate`) frees the three fields over their
plausible ranges, starting from the preset's estimates. For every worker count (0: every
evaluation in this process; N: a dask LocalCluster of N single-threaded workers, start-up
included) it prints the wall time, the CPU time (this process + reaped workers), the
evaluations, and each identified value with its 95 % interval beside the truth (one draw; the
coverage over 20 draws is counted by ``flexrv workflow calibration``).

Figures: docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _shared import cpu_with_children_s

from flexrv.workflows.calibration import EXAMPLE_TRUTH as TRUTH
from flexrv.workflows.calibration import FREE


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, nargs="+", default=[0, 2])
    args = ap.parse_args()
    from flexrv.design import load, override
    from flexrv.measured import read_measured
    from flexrv.measured.writer import write_loop
    from flexrv.studies.calibrate import calibrate, synthetic_loop

    rv = load("rv40e")
    t, a = synthetic_loop(override(rv, TRUTH), 412.0, 0.005, seed=1)
    path = write_loop(Path(tempfile.mkdtemp()) / "synthetic.csv", t, a, angle_uncertainty_arcmin=0.005)
    m = read_measured(path)
    for w in args.workers:
        t0, c0 = time.perf_counter(), cpu_with_children_s()
        cal = calibrate(rv, [m], free=FREE, workers=w)
        wall, cpu = time.perf_counter() - t0, cpu_with_children_s() - c0
        print(f"workers={w}: wall {wall:.1f} s, CPU {cpu:.1f} s, {cal.evaluations} evaluations, {cal.status}")
        for k, v in cal.identified.items():
            inside = v["ci95_low"] <= TRUTH[k] <= v["ci95_high"]
            print(
                f"  {k}: truth {TRUTH[k]:.5g}, fitted {v['value']:.5g} "
                f"[{v['ci95_low']:.5g}, {v['ci95_high']:.5g}] covers: {inside}, identifiable: {v['identifiable']}"
            )
        print(f"  residual RMS (weighted) {cal.residual_rms:.3f}, {cal.residual_rms_arcmin:.2e} arcmin")


if __name__ == "__main__":
    main()
