"""flexrv optimize (:mod:`flexrv.studies.optimize`): parsing of the options, the batch
metrics, non-domination, an analytic two-objective problem with a known front through the
same machinery, resumability, and the rv40e search re-evaluated by the full solver."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexrv.studies._opt_expr import Variable
from flexrv.studies.optimize import (
    OptimizeConfig,
    Problem,
    attach_goals,
    non_dominated,
    run_optimize,
)

#: CRN perturbation of the analytic problem: draw d adds EPS * z_d to both objectives
EPS = 0.01


def analytic_task(design: dict, draws: list, options: dict) -> dict:
    """ZDT1 with two variables (Zitzler, Deb & Thiele 2000): f1 = x1, g = 1 + 9 x2,
    f2 = g (1 - sqrt(f1 / g)); Pareto front x2 = 0, f2 = 1 - sqrt(f1), f1 in [0, 1].
    Each draw adds EPS z_d (a common random number) to both objectives."""
    x1, x2 = float(design["x1"]), float(design["x2"])
    g = 1.0 + 9.0 * x2
    f1, f2 = x1, g * (1.0 - math.sqrt(x1 / g))
    z = [d["z"] for d in draws]
    options.get("calls", [0])[0] += 1
    return {
        "nominal": {"f1": f1, "f2": f2},
        "draws": {"f1": [f1 + EPS * v for v in z], "f2": [f2 + EPS * v for v in z]},
    }


analytic_task.quantities = {"f1": "", "f2": ""}


def _analytic_problem(draws: int = 4, constraints=()) -> Problem:
    z = np.random.default_rng(3).standard_normal(draws)
    p = Problem(
        base={"x1": 0.5, "x2": 0.5},
        variables=[Variable("x1", 0.0, 1.0), Variable("x2", 0.0, 1.0)],
        objectives=[],
        constraints=[],
        quantities=dict(analytic_task.quantities),
        rules={},
        draws=[{"z": float(v)} for v in z],
        task="tests.test_optimize:analytic_task",
        options={},
    )
    attach_goals(p, ["f1_mean:min", "f2_mean:min"], list(constraints))
    return p


def _cfg(tmp_path, budget=300, **kw) -> OptimizeConfig:
    return OptimizeConfig(
        design="analytic",
        vary=["x1=0:1", "x2=0:1"],
        objectives=["f1_mean:min", "f2_mean:min"],
        budget=budget,
        population=20,
        out=str(tmp_path / "run"),
        reevaluate=False,
        **kw,
    )


def test_analytic_front_recovered(tmp_path):
    """NSGA-II through run_optimize (store, metrics, Pareto extraction) on ZDT1 recovers the
    known front f2 = 1 - sqrt(f1) shifted by the draws' common offset EPS mean(z): every
    reported point within 0.02 of it, spread over f1 in [<0.05, >0.95] (Zitzler, Deb &
    Thiele 2000, the front of ZDT1)."""
    p = _analytic_problem()
    c = EPS * float(np.mean([d["z"] for d in p.draws]))
    r = run_optimize(_cfg(tmp_path, budget=600), progress=False, mode="inline", problem=p)
    pts = r["pareto"]
    assert len(pts) >= 10
    f1 = np.array([q["f1_mean"] for q in pts]) - c
    f2 = np.array([q["f2_mean"] for q in pts]) - c
    assert np.max(np.abs(f2 - (1.0 - np.sqrt(np.clip(f1, 0, 1))))) < 0.02
    assert f1.min() < 0.05 and f1.max() > 0.95
    assert all(q["x2"] < 0.01 for q in pts)


def test_pareto_is_non_dominated(tmp_path):
    """No reported point dominates another (objectives in minimisation form), and every
    feasible evaluated candidate is dominated by or equal to a reported one."""
    p = _analytic_problem()
    r = run_optimize(_cfg(tmp_path, budget=100), progress=False, mode="inline", problem=p)
    f = np.array([[q["f1_mean"], q["f2_mean"]] for q in r["pareto"]])
    for i in range(len(f)):
        others = np.delete(f, i, axis=0)
        assert not np.any(np.all(others <= f[i], axis=1) & np.any(others < f[i], axis=1))
    rows = np.genfromtxt(tmp_path / "run" / "evaluations.csv", delimiter=",", names=True, dtype=None, encoding=None)
    for row in rows:
        v = np.array([row["f1_mean"], row["f2_mean"]])
        assert np.any(np.all(f <= v + 1e-12, axis=1))


def test_non_dominated_mask():
    """Hand-made set: (1,3), (2,2), (3,1) non-dominated; (2,3) and (3,3) dominated; a duplicate kept."""
    f = np.array([[1, 3], [2, 2], [3, 1], [2, 3], [3, 3], [2, 2]], float)
    assert non_dominated(f).tolist() == [True, True, True, False, False, True]


def test_constraint_respected_and_resume(tmp_path):
    """A constraint f1_mean >= 0.5 cuts the front to f1 >= 0.5; a second run with the same
    arguments reads every stored evaluation and computes none (resumable), with the same
    front."""
    p = _analytic_problem(constraints=["f1_mean >= 0.5"])
    r1 = run_optimize(_cfg(tmp_path, budget=60), progress=False, mode="inline", problem=p)
    assert r1["computed_now"] > 0
    assert all(q["f1_mean"] >= 0.5 for q in r1["pareto"])
    p2 = _analytic_problem(constraints=["f1_mean >= 0.5"])
    r2 = run_optimize(_cfg(tmp_path, budget=60), progress=False, mode="inline", problem=p2)
    assert r2["computed_now"] == 0 and r2["reused"] > 0
    assert [q["x1"] for q in r2["pareto"]] == [q["x1"] for q in r1["pareto"]]


def test_resume_after_interruption(tmp_path):
    """A run interrupted after some evaluations (the evaluation task raising KeyboardInterrupt
    on its 25th candidate) continues from its stored evaluations: the rerun computes only
    the rest and ends with the same front as an uninterrupted run."""
    import tests.test_optimize as me

    p = _analytic_problem()
    ref = run_optimize(_cfg(tmp_path / "ref", budget=60), progress=False, mode="inline", problem=p)
    count = {"n": 0}
    orig = me.analytic_task

    def flaky(design, draws, options):
        count["n"] += 1
        if count["n"] == 25:
            raise KeyboardInterrupt
        return orig(design, draws, options)

    flaky.quantities = orig.quantities
    me.analytic_task = flaky
    try:
        with pytest.raises(KeyboardInterrupt):
            run_optimize(_cfg(tmp_path, budget=60), progress=False, mode="inline", problem=_analytic_problem())
    finally:
        me.analytic_task = orig
    stored = len(list((tmp_path / "run" / "evaluations").glob("*.json")))
    assert stored == 24
    r = run_optimize(_cfg(tmp_path, budget=60), progress=False, mode="inline", problem=_analytic_problem())
    assert r["reused"] >= 24 and r["computed_now"] == ref["computed_now"] - 24
    assert [q["x1"] for q in r["pareto"]] == [q["x1"] for q in ref["pareto"]]
