"""flexrv optimize (:mod:`flexrv.studies.optimize`): parsing of the options, the batch
metrics, non-domination, an analytic two-objective problem with a known front through the
same machinery, resumability, and the rv40e search re-evaluated by the full solver."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from flexrv.errors import InputError
from flexrv.studies._opt_expr import Variable, parse_constraint, parse_objective, parse_vary
from flexrv.studies.optimize import (
    OptimizeConfig,
    Problem,
    attach_goals,
    batch_metrics,
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


# ----------------------------------------------------------------------------- parsing
def test_parse_objective_constraint_vary():
    """Objective senses, a constraint's violation (relative, <= 0 where it holds), and the
    rejection of executable text: a call, an attribute, a lambda are not parsed."""
    names = ["lost_motion_p95_arcmin", "no_preload_yield", "rigidity_median_Nm_per_arcmin"]
    assert parse_objective("rigidity_median_Nm_per_arcmin:max", names).sense == "max"
    assert parse_objective("lost_motion_p95_arcmin", names).sense == "min"
    c = parse_constraint("no_preload_yield >= 0.99", names)
    assert c.holds({"no_preload_yield": 0.995}) and not c.holds({"no_preload_yield": 0.98})
    assert c.violation({"no_preload_yield": 0.98}) == pytest.approx(0.01 / 0.99)
    c2 = parse_constraint("2 * lost_motion_p95_arcmin - 0.5 < 1.5", names)
    assert c2.holds({"lost_motion_p95_arcmin": 0.9}) and not c2.holds({"lost_motion_p95_arcmin": 1.0})
    for bad in ("__import__('os').system('true') <= 1", "lost_motion_p95_arcmin.real <= 1", "(lambda: 1)() <= 1"):
        with pytest.raises(InputError, match="not allowed|unknown"):
            parse_constraint(bad, names)
    base = {"second_stage": {"modification_shift_mm": 0.0, "disc_body_model": "rigid"}}
    v = parse_vary("second_stage.modification_shift_mm=-0.01:0.02", base)
    assert (v.lo, v.hi, v.integer) == (-0.01, 0.02, False)


@pytest.mark.parametrize(
    "args, word",
    [
        (["--vary", "second_stage.modification_colour_mm=0:1"], "unknown design field"),
        (["--vary", "second_stage.modification_shift_mm=0.01:-0.01"], "must be below"),
        (["--vary", "second_stage.disc_body_model=0:1"], "not a number"),
        (["--vary", "second_stage.modification_shift_mm=0:0.5"], "modification_shift_mm"),
        (["--objective", "lost_motion_p96_arcmin"], "unknown metric"),
        (["--objective", "lost_motion_p95_arcmin:maximise"], "bad syntax"),
        (["--constraint", "pin_contact_pressure_p95_MPa <="], "not an expression"),
        (["--constraint", "pin_contact_pressure_p95_MPa"], "one comparison"),
        (["--constraint", "open('x') <= 1"], "not allowed"),
        (["--budget", "0"], "--budget"),
        (["--samples-per-design", "0"], "--samples-per-design"),
        (["--spec", "lost_motion<=1"], "unknown quantity"),
    ],
)
def test_cli_bad_input_exit_2(tmp_path, capsys, args, word):
    """Each bad option: one message on stderr naming the culprit, exit code 2, before any
    evaluation (no output folder is written)."""
    from flexrv.cli import main

    base = {
        "--vary": "second_stage.modification_shift_mm=-0.01:0.01",
        "--objective": "lost_motion_p95_arcmin:min",
        "--budget": "2",
        "--samples-per-design": "1",
    }
    argv = ["optimize", "rv40e", "--tolerances", "rv40e", *args]
    for k, v in base.items():
        if k not in args:
            argv += [k, v]
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert exc.value.code == 2, err
    assert word in " ".join(err.split()), err
    assert "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_constraint_no_design_meets(tmp_path):
    """A constraint no design in the box can meet (f1 + f2 <= 0.2 on ZDT1, whose front has
    f1 + f2 >= 0.75) ends with one InputError naming it (exit 2 from the CLI), after the
    outputs are written."""
    p = _analytic_problem(constraints=["f1_mean + f2_mean <= 0.2"])
    with pytest.raises(InputError, match=r"f1_mean \+ f2_mean <= 0.2.*no design in the box meets it"):
        run_optimize(_cfg(tmp_path, budget=40), progress=False, mode="inline", problem=p)
    assert (tmp_path / "run" / "evaluations.csv").exists()


def test_batch_metrics_names_and_values():
    """Metric names <quantity>_<stat>_<unit> and their values on a hand-made batch: P95 by
    linear interpolation (numpy), the yield of a per-build rule, a failed draw (NaN)
    excluded from the statistics and counted as not passing."""
    from flexrv.studies._opt_expr import BuildRule

    res = {"nominal": {"lost_motion": 0.5}, "draws": {"lost_motion": [0.2, 0.4, 0.6, 0.8, float("nan")]}}
    m = batch_metrics(res, {"lost_motion": "arcmin"}, {"fit": [BuildRule("lost_motion", "<=", 0.5, "x")]})
    assert m["lost_motion_p95_arcmin"] == pytest.approx(np.percentile([0.2, 0.4, 0.6, 0.8], 95))
    assert m["lost_motion_median_arcmin"] == pytest.approx(0.5)
    assert m["lost_motion_nominal_arcmin"] == 0.5
    assert m["fit_yield"] == pytest.approx(2 / 5) and m["failed_fraction"] == pytest.approx(1 / 5)


# ----------------------------------------------------------------------------- rv40e
def test_pin_contact_pressure_closed_form():
    """The nominal pose maps the loaded pins onto the profile: at every position of rv40e
    (no errors) each pin's nominal gap equals the equidistant modification (5 um, to
    1e-9 m), and a pin force F gives Hertz's p = sqrt(F E' / (2 pi L R)) (Johnson 1985,
    eq. 4.45) with the reported r_eff, to 1e-12 relative."""
    from flexrv.analysis.pin_load import disc_effective_modulus
    from flexrv.design import load
    from flexrv.studies._modification_eval import contact_parameters, pin_contact_pressure

    red = load("rv40e")
    angles = np.linspace(0.0, 2.0, 5)
    r_eff, gap = contact_parameters(red, angles)
    assert np.allclose(gap, red.second_stage.modification_equidistant_mm * 1e-3, atol=1e-9)
    f = np.full(r_eff.shape, 500.0)
    p = pin_contact_pressure(red, angles, f)
    e = disc_effective_modulus(red)
    ref = np.sqrt(500.0 * e / (2.0 * np.pi * red.second_stage.disc_width * r_eff))
    ok = r_eff > 0
    assert np.allclose(p[ok], ref[ok], rtol=1e-12)


def test_rv40e_points_reevaluate_within_stated_error(tmp_path):
    """The documented rv40e command (the pressure limit: the preset's own P95, same draws) on a tiny budget
    (2 designs, 1 draw, in-process): every reported
    Pareto point, re-evaluated by the full solver with the same draw, matches its reported
    figures within CHEAP_ERROR (per build, which bounds every batch statistic) and has the
    same no-preload yield (the same geometric function in both)."""
    from flexrv.studies._modification_eval import modification_task
    from flexrv.studies._opt_expr import STATS, metric_name
    from flexrv.studies.optimize import CHEAP_ERROR, FULL_RESOLUTION, build_problem

    cfg = OptimizeConfig(
        design="rv40e",
        tolerances="rv40e",
        vary=["second_stage.modification_equidistant_mm=0:0.015", "second_stage.modification_shift_mm=-0.015:0.015"],
        objectives=["lost_motion_p95_arcmin:min", "rigidity_median_Nm_per_arcmin:max"],
        constraints=["pin_contact_pressure_p95_MPa <= preset_pin_contact_pressure_p95_MPa"],
        samples_per_design=1,
        budget=2,
        population=2,
        out=str(tmp_path / "rv"),
        reevaluate=False,
    )
    r = run_optimize(cfg, progress=False, mode="inline")
    assert r["pareto"]
    problem, _, _ = build_problem(cfg)
    fields = [v.path for v in problem.variables]
    for point in r["pareto"]:
        design = problem.design_for([point[f] for f in fields])
        full = batch_metrics(
            modification_task(design, problem.draws, {"resolution": FULL_RESOLUTION}), problem.quantities, problem.rules
        )
        for q, unit in problem.quantities.items():
            for stat in STATS:
                if stat == "std":
                    continue
                name = metric_name(q, stat, unit)
                assert abs(full[name] - point[name]) <= CHEAP_ERROR[q], (name, full[name], point[name])
        assert full["no_preload_yield"] == point["no_preload_yield"]
    summary = json.loads((tmp_path / "rv" / "summary.json").read_text())
    assert summary["pareto"] == r["pareto"]
    for name in ("pareto.csv", "pareto.nc", "pareto.png", "summary.md", "evaluations.csv"):
        assert (tmp_path / "rv" / name).exists()


def test_modification_design_smoke(tmp_path):
    """Workflow ``modification_design`` in smoke size (in-process: 2 designs x 1 draw): the
    summary carries the preset's point, the recommended designs or the constraint that no
    design meets, and numbers that match the search's own summary.json."""
    from flexrv.workflows.modification_design import run

    r = run(out_dir=tmp_path, smoke=True, budget=2, samples=1, mode="inline")
    text = (tmp_path / "summary.md").read_text()
    assert "SMOKE RUN" in text and "P95 lost motion of the preset's batch" in text
    search = json.loads((tmp_path / "search" / "summary.json").read_text())
    assert r.numbers["preset"] == search["preset"]
    assert r.numbers["infeasible"] or r.numbers["recommended"]
    assert (tmp_path / "search" / "evaluations.csv").exists()


@pytest.mark.slow
def test_documented_command_cli(tmp_path):
    """(slow: a LocalCluster and 6 designs x 3 builds, 2-4 min.) The documented rv40e command from the
    CLI with --json: a non-empty Pareto set, each point with both varied fields and every
    objective and constraint metric by name, no point dominating another."""
    import subprocess
    import sys

    args = [
        sys.executable, "-m", "flexrv", "optimize", "rv40e", "--tolerances", "rv40e",
        "--vary", "second_stage.modification_equidistant_mm=0:0.015",
        "--vary", "second_stage.modification_shift_mm=-0.015:0.015",
        "--objective", "lost_motion_p95_arcmin:min", "--objective", "rigidity_median_Nm_per_arcmin:max",
        "--constraint", "pin_contact_pressure_p95_MPa <= 1900",
        "--samples-per-design", "2", "--budget", "6", "--population", "3", "--workers", "2",
        "--out", str(tmp_path / "o"), "--json",
    ]  # fmt: skip
    res = subprocess.run(args, capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-2000:]
    d = json.loads(res.stdout)
    pts = d["pareto"]
    assert pts
    for p in pts:
        for k in (
            "second_stage.modification_equidistant_mm",
            "second_stage.modification_shift_mm",
            "lost_motion_p95_arcmin",
            "rigidity_median_Nm_per_arcmin",
            "pin_contact_pressure_p95_MPa",
        ):
            assert isinstance(p[k], float)
        assert p["pin_contact_pressure_p95_MPa"] <= 1900
    f = np.array([[p["lost_motion_p95_arcmin"], -p["rigidity_median_Nm_per_arcmin"]] for p in pts])
    assert non_dominated(f).all()
