"""Benchmark of ``flexrv optimize`` (:mod:`flexrv.studies.optimize`) on rv40e.

Two parts, paired in one run:

* ``--compare``: the cheap evaluation of the search against the full one on the same builds:
  ``--designs`` designs (the preset and a Latin hypercube of the equidistant / shift box)
  times ``--draws`` tolerance draws, every build at both resolutions. Prints the largest and
  mean |cheap - full| of every quantity (the bound :data:`flexrv.studies.optimize.CHEAP_ERROR`
  states) and the CPU time per build of each (their ratio).
* the search: ``--budget`` candidates x ``--samples`` draws on ``--workers`` dask workers
  (goal: 200 x 32 on 2 cores in <= 15 min), wall time and candidates per minute.

Figures: docs/benchmarks.md.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --compare --designs 6 --draws 8
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --budget 200 --samples 32 --workers 2
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

VARY = ["second_stage.modification_equidistant_mm=0:0.015", "second_stage.modification_shift_mm=-0.015:0.015"]


def compare(designs: int, draws: int, seed: int) -> dict:
    """|cheap - full| per build over designs x draws, and the time per build of each."""
    from scipy.stats import qmc

    from flexrv.design import apply_overrides, from_dict
    from flexrv.studies._modification_eval import QUANTITIES, build_quantities
    from flexrv.studies.optimize import CHEAP_RESOLUTION, FULL_RESOLUTION, OptimizeConfig, build_problem

    cfg = OptimizeConfig("rv40e", vary=VARY, objectives=["lost_motion_p95_arcmin"], tolerances="rv40e")
    cfg.samples_per_design, cfg.seed = draws, seed
    problem, _, _ = build_problem(cfg)
    lo = np.array([v.lo for v in problem.variables])
    hi = np.array([v.hi for v in problem.variables])
    xs = [problem.base_x()] + list(qmc.scale(qmc.LatinHypercube(d=2, rng=seed).random(designs - 1), lo, hi))
    err = {q: [] for q in QUANTITIES}
    t_cheap = t_full = 0.0
    n = 0
    for x in xs:
        base = problem.design_for(x)
        for errors in [base["errors"]] + problem.draws:
            red = from_dict(apply_overrides(base, {"errors": errors}))
            t = time.process_time()
            c = build_quantities(red, CHEAP_RESOLUTION)
            t_cheap += time.process_time() - t
            t = time.process_time()
            f = build_quantities(red, FULL_RESOLUTION)
            t_full += time.process_time() - t
            n += 1
            for q in QUANTITIES:
                err[q].append(abs(c[q] - f[q]))
        print(f"design {np.round(x, 5)}: {n} builds", flush=True)
    out = {
        "builds": n,
        "cheap_cpu_s_per_build": t_cheap / n,
        "full_cpu_s_per_build": t_full / n,
        "full_over_cheap": t_full / t_cheap,
        "max_abs_error": {q: float(np.nanmax(v)) for q, v in err.items()},
        "mean_abs_error": {q: float(np.nanmean(v)) for q, v in err.items()},
    }
    return out


def search(budget: int, samples: int, workers: int, seed: int, out: str | None) -> dict:
    from flexrv.studies.optimize import OptimizeConfig, run_optimize

    tmp = Path(out) if out else Path(tempfile.mkdtemp(prefix="bench_optimize_"))
    cfg = OptimizeConfig(
        "rv40e",
        vary=VARY,
        objectives=["lost_motion_p95_arcmin:min", "rigidity_median_Nm_per_arcmin:max"],
        constraints=["pin_contact_pressure_p95_MPa <= preset_pin_contact_pressure_p95_MPa"],
        tolerances="rv40e",
        samples_per_design=samples,
        budget=budget,
        workers=workers,
        seed=seed,
        out=str(tmp),
    )
    t = time.perf_counter()
    r = run_optimize(cfg, progress=True)
    wall = time.perf_counter() - t
    if not out:
        shutil.rmtree(tmp, ignore_errors=True)
    return {
        "budget": budget,
        "samples_per_design": samples,
        "workers": workers,
        "wall_time_s": wall,
        "computed_now": r["computed_now"],
        "candidates_per_min": 60.0 * r["computed_now"] / wall,
        "builds_per_s": r["computed_now"] * (samples + 1) / wall,
        "projected_200x32_min": 200 * 33 / (r["computed_now"] * (samples + 1) / wall) / 60.0,
        "pareto_points": len(r["pareto"]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--compare", action="store_true", help="cheap vs full evaluation only")
    ap.add_argument("--designs", type=int, default=6)
    ap.add_argument("--draws", type=int, default=8)
    ap.add_argument("--budget", type=int, default=200)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="keep the search's output directory here")
    a = ap.parse_args()
    if a.compare:
        print(json.dumps(compare(a.designs, a.draws, a.seed), indent=1))
    else:
        print(json.dumps(search(a.budget, a.samples, a.workers, a.seed, a.out), indent=1))


if __name__ == "__main__":
    main()
