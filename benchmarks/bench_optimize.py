"""Benchmark of ``flexrv optimize`` (:mod:`flexrv.studies.optimize`) on rv40e.

Two parts, paired in one run:

* ``--compare``: the cheap evaluation of the search against the full one on the same builds:
  ``--designs`` designs (the preset and a Latin hypercube of the equidistant / shift box)
  times ``--draws`` tolerance draws, every build at both resolutions. Prints the largest and
  mean |cheap - full| of every quantity (the bound :data:`flexrv.studies.optimize.CHEAP_ERROR`
  states) and the CPU time per build of each (their ratio).
* the search: ``--budget`` candidates x ``--samples`` draws on ``--workers`` dask workers
  (goal: 200 x 32 on 2 cores in <= 15 min), wall time and candidates per minute.

* ``--paired``: the same search twice in one run, first as the former evaluation (every
  build computes the constants of the design without errors itself, one task per
  candidate always), then as today's (the builds of a candidate share those constants;
  a batch with few candidates split into chunks of draws): wall and CPU of each, their
  ratio, and whether the two Pareto sets are identical (they must be: the same numbers).
* ``--builds``: CPU per cheap build in this process, the builds of a candidate sharing the
  error-free constants or not (paired, alternating; the same figures bit for bit).

Figures: docs/benchmarks.md.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --compare --designs 6 --draws 8
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --budget 200 --samples 32 --workers 2
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --paired --budget 20 --samples 32
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_optimize.py --builds --samples 8
"""

from __future__ import annotations

import argparse
import contextlib
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from _shared import children_cpu_s, use_this_checkout

use_this_checkout()

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


@contextlib.contextmanager
def _unshared():
    import flexrv.design.manufacturing as mf

    @contextlib.contextmanager
    def off(memo=None):
        yield

    orig = mf.shared_nominal_constants
    mf.shared_nominal_constants = off
    try:
        yield
    finally:
        mf.shared_nominal_constants = orig


def unshared_task(design: dict, draws: list, options: dict) -> dict:
    """The modification task with every build computing the error-free constants itself."""
    from flexrv.studies._modification_eval import modification_task

    with _unshared():
        return modification_task(design, draws, options)


def builds(samples: int, seed: int) -> dict:
    """CPU per cheap build of one candidate, shared constants or not (paired, alternating)."""
    from flexrv.studies._modification_eval import _NOMINAL_MEMO, modification_task
    from flexrv.studies.optimize import CHEAP_RESOLUTION, OptimizeConfig, build_problem

    cfg = OptimizeConfig("rv40e", vary=VARY, objectives=["lost_motion_p95_arcmin"], tolerances="rv40e")
    cfg.samples_per_design, cfg.seed = samples, seed
    problem, _, _ = build_problem(cfg)
    opts = {"resolution": CHEAP_RESOLUTION}
    modification_task(problem.base, problem.draws[:1], opts)  # warm
    t = {"shared": 0.0, "unshared": 0.0}
    res = {}
    for _ in range(2):
        for label in ("unshared", "shared"):
            _NOMINAL_MEMO.clear()
            c = time.process_time()
            with _unshared() if label == "unshared" else contextlib.nullcontext():
                r = modification_task(problem.base, problem.draws, opts)
            t[label] += time.process_time() - c
            res.setdefault(label, r)
            assert r == res[label]
    n = 2 * (samples + 1)
    return {
        "builds": n,
        "unshared_cpu_s_per_build": t["unshared"] / n,
        "shared_cpu_s_per_build": t["shared"] / n,
        "ratio": t["unshared"] / t["shared"],
        "identical": res["shared"] == res["unshared"],
    }


def paired(budget: int, samples: int, workers: int, seed: int) -> dict:
    """The same search as before (unshared constants, one task per candidate) and now."""
    import flexrv.studies._opt_runner as runner
    from flexrv.studies.optimize import build_problem, run_optimize
    from flexrv.sweep import process_cpu_s

    out = {}
    chunk = runner.chunk_draws
    for label in ("before", "now"):
        with tempfile.TemporaryDirectory() as tmp:
            cfg = _config(budget, samples, workers, seed, tmp)
            problem = None
            if label == "before":
                problem, _, _ = build_problem(cfg)
                problem.task = "benchmarks.bench_optimize:unshared_task"
                runner.chunk_draws = lambda n, c, s: [(0, n)]
            c0, k0, t0 = process_cpu_s(), children_cpu_s(), time.perf_counter()
            try:
                r = run_optimize(cfg, progress=False, problem=problem)
            finally:
                runner.chunk_draws = chunk
            wall = time.perf_counter() - t0
            workers_cpu = sum(
                json.loads(p.read_text()).get("cpu_time_s", 0.0) for p in (Path(tmp) / "evaluations").glob("*.json")
            )
            out[label] = {
                "wall_time_s": wall,
                "client_cpu_s": process_cpu_s() - c0,
                "children_cpu_s": children_cpu_s() - k0,
                "workers_task_cpu_s": workers_cpu,
                "computed": r["computed_now"],
                "pareto": [{k: v for k, v in p.items() if k not in ("full", "full_minus_cheap")} for p in r["pareto"]],
            }
        print(label, json.dumps({k: v for k, v in out[label].items() if k != "pareto"}), flush=True)
    same = out["before"]["pareto"] == out["now"]["pareto"]
    return {
        "budget": budget,
        "samples_per_design": samples,
        "workers": workers,
        "before": {k: v for k, v in out["before"].items() if k != "pareto"},
        "now": {k: v for k, v in out["now"].items() if k != "pareto"},
        "wall_ratio": out["before"]["wall_time_s"] / out["now"]["wall_time_s"],
        "identical_pareto": same,
        "pareto_points": len(out["now"]["pareto"]),
    }


def _config(budget: int, samples: int, workers: int, seed: int, out: str):
    from flexrv.studies.optimize import OptimizeConfig

    return OptimizeConfig(
        "rv40e",
        vary=VARY,
        objectives=["lost_motion_p95_arcmin:min", "rigidity_median_Nm_per_arcmin:max"],
        constraints=["pin_contact_pressure_p95_MPa <= preset_pin_contact_pressure_p95_MPa"],
        tolerances="rv40e",
        samples_per_design=samples,
        budget=budget,
        workers=workers,
        seed=seed,
        out=out,
    )


def search(budget: int, samples: int, workers: int, seed: int, out: str | None) -> dict:
    from flexrv.studies.optimize import run_optimize

    tmp = Path(out) if out else Path(tempfile.mkdtemp(prefix="bench_optimize_"))
    cfg = _config(budget, samples, workers, seed, str(tmp))
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
    ap.add_argument("--paired", action="store_true", help="the search before/now, paired in one run")
    ap.add_argument("--builds", action="store_true", help="CPU per cheap build, shared constants or not")
    a = ap.parse_args()
    if a.paired:
        print(json.dumps(paired(a.budget, a.samples, a.workers, a.seed), indent=1))
    elif a.builds:
        print(json.dumps(builds(a.samples, a.seed), indent=1))
    elif a.compare:
        print(json.dumps(compare(a.designs, a.draws, a.seed), indent=1))
    else:
        print(json.dumps(search(a.budget, a.samples, a.workers, a.seed, a.out), indent=1))


if __name__ == "__main__":
    main()
