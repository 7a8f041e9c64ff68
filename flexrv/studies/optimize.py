"""Design of the cycloid profile modification (``flexrv optimize``): a Pareto front of batch
figures (lost motion, rigidity, pin contact pressure, TE, assembly preload) over a box of
design fields, robust over the production tolerances, evaluated on dask.

Pipeline
--------
1. **Problem.** The design (preset or TOML) and its tolerance set
   (:mod:`flexrv.design.tolerances`); ``--vary FIELD=LO:HI`` names numeric fields of the
   design table (the disc's ``second_stage.modification_equidistant_mm``,
   ``modification_shift_mm``, ``modification_rotation_deg``, or any other number);
   ``--objective NAME[:min|max]`` and ``--constraint "EXPR"`` name batch metrics
   (:mod:`flexrv.studies._opt_expr`: ``<quantity>_<stat>_<unit>``, yields ``<rule>_yield``).
2. **Common random numbers.** One set of N tolerance draws (the sampling of
   ``flexrv tolerance``: :class:`flexrv.studies.tolerance.TolerancePlan`, scrambled Sobol',
   the seed) is used for every candidate, so two candidates differ only by their design
   fields, never by their draws: the comparison of candidates carries no sampling noise
   (their absolute figures carry the sampling error of N builds).
3. **Evaluation** of a candidate: its nominal build and its N builds
   (:func:`flexrv.studies._modification_eval.modification_task`) as one dask task, stored
   atomically per candidate (:mod:`flexrv.studies._opt_runner`): a killed run resumes without
   recomputing a stored candidate.
4. **Search**: NSGA-II (Deb et al. 2002 :cite:`deb2002nsga2`) from pymoo
   (:cite:`blank2020pymoo`). Why NSGA-II through pymoo: its ask/tell interface hands over a
   whole generation at once, which maps directly onto one batch of dask tasks; constraints
   are handled by the algorithm itself (constraint-domination: a feasible point beats an
   infeasible one, two infeasible ones compare by their violation), so no penalty weights
   are tuned; and the algorithm's random state is a local generator seeded by ``--seed``,
   so a run is reproducible, which is what makes the resume by re-asking work. The first
   generation is the design itself (where it lies in the box) plus a Latin hypercube.
5. **Cheap and full evaluation.** The search evaluates every build at
   :data:`CHEAP_RESOLUTION` (half a crank revolution, 3 catalog positions); the recommended
   designs and the design itself are re-evaluated with the same draws at
   :data:`FULL_RESOLUTION` (one crank revolution, 6 catalog positions: the evaluation of
   ``flexrv tolerance``), and both figures are reported. :data:`CHEAP_ERROR` is the largest
   difference of one build's quantity between the two, measured
   (benchmarks/bench_optimize.py); since a percentile, mean, min or max is monotone in
   every sample and shifts with them, it bounds the difference of every batch statistic
   of builds within the measured range (not of a yield on a spec of a quantity that
   differs: a build may cross the limit).
6. **Outputs**: ``pareto.csv`` / ``pareto.nc`` (non-dominated feasible candidates),
   ``evaluations.csv`` (every candidate), ``pareto.png`` (the front with the design itself
   marked), ``designs/<label>.toml`` (each recommended design with its provenance),
   ``summary.json`` and ``summary.md``.

Recommended designs: on the front, the best point of each objective and the balanced one
(the nearest to the ideal point in objectives scaled to [0, 1] over the front).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flexrv.errors import InputError
from flexrv.studies._opt_expr import (
    STATS,
    BuildRule,
    Constraint,
    Objective,
    Variable,
    metric_name,
    metric_names,
    parse_constraint,
    parse_objective,
    parse_spec,
    parse_vary,
)

#: the evaluation of the search: half a crank revolution at 2 points per pin-mesh period
#: (39 positions on rv40e), 3 catalog positions (lost motion, backlash, rigidity)
CHEAP_RESOLUTION = {
    "crank_revolutions": 0.5,
    "points_per_mesh": 2,
    "catalog_positions": 3,
    "force_tol": 1e-6,
    "max_iter": 200,
}
#: the full evaluation: one crank revolution (78 positions on rv40e), 6 catalog positions,
#: as ``flexrv tolerance`` (:data:`flexrv.studies.tolerance.DEFAULT_RESOLUTION`)
FULL_RESOLUTION = {**CHEAP_RESOLUTION, "crank_revolutions": 1.0, "catalog_positions": 6}

#: bound of |cheap - full| of one build's quantity (unit of the quantity). Measured by
#: benchmarks/bench_optimize.py --compare on rv40e over 54 builds (6 modifications of the
#: equidistant / shift box x (8 grade-5 draws + the nominal build)): largest differences
#: lost motion 0.251 arcmin (mean 0.066), backlash 0.391 (0.100), rigidity 1.72 N m/arcmin
#: (0.52), TE p-p 13.9 arcsec (4.1), pin force 323 N (61), pin contact pressure 172 MPa (34),
#: assembly penetration 0 (the same geometric function); stated here rounded up. It bounds
#: every batch statistic (module docstring, point 5) of builds like the measured ones.
CHEAP_ERROR = {
    "lost_motion": 0.3,
    "backlash": 0.45,
    "rigidity": 2.0,
    "te_pp": 16.0,
    "pin_force": 400.0,
    "pin_contact_pressure": 200.0,
    "assembly_penetration": 1e-9,
}

#: fields whose change alters the number of toleranced elements (the draws' shapes)
_SHAPE_FIELDS = ("second_stage.pin_count", "second_stage.n_discs", "second_stage.disc_teeth", "first_stage.n_planets")

#: the task of a reducer design
MODIFICATION_TASK = "flexrv.studies._modification_eval:modification_task"

#: built-in yields of the modification task: name -> per-build rule
MODIFICATION_YIELDS = {"no_preload": [BuildRule("assembly_penetration", "<=", 0.0, "assembly_penetration_um<=0")]}


# ----------------------------------------------------------------------------- the problem
@dataclass
class Problem:
    """A search problem on design tables (generic: the analytic test injects its own task)."""

    base: dict
    variables: list[Variable]
    objectives: list[Objective]
    constraints: list[Constraint]
    quantities: dict[str, str]
    rules: dict[str, list[BuildRule]]  #: yield name -> per-build rules (all must hold)
    draws: list
    task: str
    options: dict
    validate: Any = None  #: callable(design dict) raising FlexrvError for an invalid design

    @property
    def names(self) -> list[str]:
        return metric_names(self.quantities, list(self.rules))

    def design_for(self, x) -> dict:
        from flexrv.design import apply_overrides

        return apply_overrides(self.base, self.fields(x))

    def fields(self, x) -> dict:
        return {v.path: v.value(xi) for v, xi in zip(self.variables, x)}

    def base_x(self) -> np.ndarray:
        from flexrv.sweep import pick

        return np.array([float(pick(self.base, v.path)) for v in self.variables])


def batch_metrics(result: dict, quantities: dict[str, str], rules: dict[str, list[BuildRule]]) -> dict[str, float]:
    """Metrics of one candidate from its task result (``nominal`` and per-draw values)."""
    from flexrv.studies.tolerance import percentiles

    draws = {q: np.asarray(result["draws"][q], dtype=float) for q in quantities}
    n = len(next(iter(draws.values()))) if draws else 0
    out: dict[str, float] = {}
    for q, unit in quantities.items():
        p = percentiles(draws[q])
        for stat, key in STATS.items():
            if stat == "nominal":
                v = result["nominal"].get(q)
            else:
                v = p.get(key) if p.get("n") else None
            out[metric_name(q, stat, unit)] = float("nan") if v is None else float(v)
    failed = np.zeros(n, bool)
    for q in quantities:
        failed |= ~np.isfinite(draws[q])
    for name, rule_list in rules.items():
        ok = ~failed
        for rule in rule_list:
            ok &= rule.ok(draws[rule.quantity])
        out[f"{name}_yield"] = float(np.mean(ok)) if n else float("nan")
    out["failed_fraction"] = float(np.mean(failed)) if n else 0.0
    return out


def non_dominated(f: np.ndarray) -> np.ndarray:
    """Mask of the rows of f (n, m) (minimisation) no other row dominates: j dominates i if
    f_j <= f_i in every column and < in one."""
    f = np.asarray(f, dtype=float)
    keep = np.ones(len(f), bool)
    for i in range(len(f)):
        le = np.all(f <= f[i], axis=1)
        lt = np.any(f < f[i], axis=1)
        if np.any(le & lt):
            keep[i] = False
    return keep


@dataclass
class Candidate:
    """One evaluated candidate."""

    x: np.ndarray
    fields: dict
    metrics: dict
    status: str
    error: str = ""
    feasible: bool = False
    violations: dict = field(default_factory=dict)
    source: str = "search"

    def objective_vector(self, objectives: list[Objective]) -> np.ndarray:
        return np.array([o.value_to_min(self.metrics.get(o.name, math.nan)) for o in objectives])


def _candidate(problem: Problem, x, record: dict, preset_metrics: dict | None) -> Candidate:
    fields = problem.fields(x)
    if record.get("status") != "ok":
        return Candidate(np.asarray(x, float), fields, {}, record.get("status", "failed"), record.get("error", ""))
    metrics = batch_metrics(record["result"], problem.quantities, problem.rules)
    values = {**metrics, **{f"preset_{k}": v for k, v in (preset_metrics or metrics).items()}}
    viol = {str(c): c.violation(values) for c in problem.constraints}
    finite = all(math.isfinite(metrics.get(o.name, math.nan)) for o in problem.objectives)
    feasible = finite and all(v <= 0.0 for v in viol.values())
    return Candidate(np.asarray(x, float), fields, metrics, "ok", "", feasible, viol)


def _fg(problem: Problem, cands: list[Candidate]) -> tuple[np.ndarray, np.ndarray]:
    """pymoo's F (objectives, minimised) and G (<= 0 feasible): the constraints' violations
    and a last column 1 for a candidate that failed or has a non-finite objective."""
    big = 1e12
    f = np.full((len(cands), len(problem.objectives)), big)
    g = np.zeros((len(cands), len(problem.constraints) + 1))
    for i, c in enumerate(cands):
        vec = c.objective_vector(problem.objectives) if c.status == "ok" else np.full(len(problem.objectives), np.nan)
        if np.all(np.isfinite(vec)):
            f[i] = vec
        else:
            g[i, -1] = 1.0
        for j, con in enumerate(problem.constraints):
            v = c.violations.get(str(con), math.inf)
            g[i, j] = v if math.isfinite(v) else big
    return f, g


def search(
    problem: Problem,
    store,
    budget: int,
    population: int,
    seed: int,
    preset_metrics: dict | None = None,
    progress=None,
) -> list[Candidate]:
    """NSGA-II over the box (module docstring, point 4); returns every evaluated candidate
    in the order evaluated (duplicates once)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem as PymooProblem
    from pymoo.problems.static import StaticProblem
    from scipy.stats import qmc

    lo = np.array([v.lo for v in problem.variables])
    hi = np.array([v.hi for v in problem.variables])
    pp = PymooProblem(
        n_var=len(lo), n_obj=len(problem.objectives), n_ieq_constr=len(problem.constraints) + 1, xl=lo, xu=hi
    )
    pop = max(2, min(population, budget))
    init = qmc.scale(qmc.LatinHypercube(d=len(lo), rng=np.random.default_rng([seed, 7])).random(pop), lo, hi)
    x0 = problem.base_x()
    if np.all((x0 >= lo) & (x0 <= hi)):
        init[0] = x0  # the design itself starts in the first generation
    algo = NSGA2(pop_size=pop, sampling=init, eliminate_duplicates=True)
    algo.setup(pp, termination=("n_eval", budget), seed=seed, verbose=False)
    seen: dict[tuple, Candidate] = {}
    generation = 0
    while algo.has_next():
        off = algo.ask()
        xs = off.get("X")
        designs = [problem.design_for(x) for x in xs]
        records = _evaluate(problem, store, designs, [problem.fields(x) for x in xs])
        cands = [_candidate(problem, x, r, preset_metrics) for x, r in zip(xs, records)]
        f, g = _fg(problem, cands)
        algo.evaluator.eval(StaticProblem(pp, F=f, G=g), off)
        algo.tell(infills=off)
        for c in cands:
            seen.setdefault(tuple(np.round(c.x, 15)), c)
        generation += 1
        if progress:
            progress(generation, algo.evaluator.n_eval, budget)
    return list(seen.values())


def _evaluate(problem: Problem, store, designs: list[dict], labels: list[dict]) -> list[dict]:
    """Records of designs; an invalid design (``problem.validate``) is recorded as failed
    without a task."""
    from flexrv.errors import FlexrvError

    out: list[dict | None] = [None] * len(designs)
    todo = []
    for i, d in enumerate(designs):
        if problem.validate is not None:
            try:
                problem.validate(d)
            except FlexrvError as exc:
                out[i] = {"status": "invalid", "error": str(exc)}
                continue
        todo.append(i)
    recs = store.evaluate([designs[i] for i in todo], problem.options, [labels[i] for i in todo])
    for i, r in zip(todo, recs):
        out[i] = r
    return out


def pareto(problem: Problem, cands: list[Candidate]) -> list[Candidate]:
    """The feasible non-dominated candidates, sorted by the first objective."""
    feas = [c for c in cands if c.feasible]
    if not feas:
        return []
    f = np.array([c.objective_vector(problem.objectives) for c in feas])
    front = [c for c, k in zip(feas, non_dominated(f)) if k]
    return sorted(front, key=lambda c: c.objective_vector(problem.objectives)[0])


def recommend(problem: Problem, front: list[Candidate]) -> dict[str, Candidate]:
    """One design per trade-off: ``best_<objective>`` for each objective, and ``balanced``
    (nearest to the ideal point, objectives scaled to [0, 1] over the front)."""
    if not front:
        return {}
    f = np.array([c.objective_vector(problem.objectives) for c in front])
    out: dict[str, Candidate] = {}
    for j, o in enumerate(problem.objectives):
        out[f"best_{o.name}"] = front[int(np.argmin(f[:, j]))]
    span = np.ptp(f, axis=0)
    span[span == 0] = 1.0
    d = np.linalg.norm((f - f.min(axis=0)) / span, axis=1)
    out["balanced"] = front[int(np.argmin(d))]
    return out


def infeasibility_message(problem: Problem, cands: list[Candidate]) -> str:
    """Which constraint no evaluated design meets (or the fewest meet), with its best value."""
    ok = [c for c in cands if c.status == "ok"]
    if not ok:
        errs = sorted({c.error for c in cands if c.error})[:3]
        return "no candidate could be evaluated" + (f" ({'; '.join(errs)})" if errs else "")
    rows = []
    for con in problem.constraints:
        v = [c.violations.get(str(con), math.inf) for c in ok]
        rows.append((sum(x <= 0 for x in v), min(v), con))
    rows.sort(key=lambda r: (r[0], -r[1]))
    met, best, con = rows[0]
    if met == 0:
        return (
            f"--constraint {con.text!r}: no design in the box meets it ({len(ok)} candidates evaluated; "
            f"the closest misses by {100 * best:.3g} % of the limit)"
        )
    return (
        f"no design in the box meets all constraints together ({len(ok)} candidates evaluated; "
        f"fewest met: {con.text!r})"
    )


# ----------------------------------------------------------------------------- the study
@dataclass
class OptimizeConfig:
    """Arguments of :func:`run_optimize` (the options of ``flexrv optimize``)."""

    design: str
    vary: list[str]
    objectives: list[str]
    constraints: list[str] = field(default_factory=list)
    specs: list[str] = field(default_factory=list)
    tolerances: str | None = None
    samples_per_design: int = 32
    budget: int = 200
    population: int = 20
    seed: int = 0
    scheduler: str | None = None
    workers: int | None = None
    out: str | None = None
    resolution: dict = field(default_factory=lambda: dict(CHEAP_RESOLUTION))
    full_resolution: dict = field(default_factory=lambda: dict(FULL_RESOLUTION))
    #: re-evaluate the recommended designs and the design itself at ``full_resolution``
    reevaluate: bool = True
    #: the lost-motion target of the report [arcmin] (the catalog's 1 arcmin)
    lost_motion_target_arcmin: float = 1.0


def _int_option(name: str, value, lo: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise InputError(f"{name} {value!r}: must be an integer >= {lo}")


def _check_config(cfg: OptimizeConfig) -> None:
    _int_option("--budget", cfg.budget, 1)
    _int_option("--samples-per-design", cfg.samples_per_design, 1)
    _int_option("--population", cfg.population, 2)
    _int_option("--seed", cfg.seed, 0)
    if cfg.workers is not None:
        _int_option("--workers", cfg.workers, 1)
    if cfg.scheduler and cfg.workers:
        raise InputError("--scheduler and --workers exclude each other: give one")
    if not cfg.vary:
        raise InputError("give at least one --vary FIELD=LO:HI")
    if not cfg.objectives:
        raise InputError("give at least one --objective NAME[:min|max]")
    for res in (cfg.resolution, cfg.full_resolution):
        unknown = set(res) - set(CHEAP_RESOLUTION)
        if unknown:
            raise InputError(f"unknown resolution option(s) {sorted(unknown)}; allowed {sorted(CHEAP_RESOLUTION)}")
    if cfg.scheduler:
        from flexrv.studies.tolerance import check_scheduler

        check_scheduler(cfg.scheduler)


def _validator(source: str):
    def validate(design: dict) -> None:
        from flexrv.design import from_dict

        from_dict(design, source=source)

    return validate


def build_problem(cfg: OptimizeConfig) -> tuple[Problem, Any, list[str]]:
    """The problem of a reducer design: (Problem, reducer, spec labels); every user error an
    InputError/ConfigError naming the option before any evaluation."""
    from flexrv.design import apply_overrides, from_dict
    from flexrv.studies._modification_eval import QUANTITIES
    from flexrv.studies.tolerance import TolerancePlan, load_design_and_tolerances

    _check_config(cfg)
    reducer, tol, _ = load_design_and_tolerances(cfg.design, cfg.tolerances)
    base = reducer.model_dump(mode="python")
    variables = [parse_vary(v, base) for v in cfg.vary]
    paths = [v.path for v in variables]
    if len(set(paths)) != len(paths):
        raise InputError(f"--vary: a field is given twice ({', '.join(paths)})")
    for v in variables:
        if v.path in _SHAPE_FIELDS:
            raise InputError(
                f"--vary {v.path}: changes the number of toleranced elements, so the tolerance draws "
                f"cannot be shared; allowed: numeric fields other than {', '.join(_SHAPE_FIELDS)}"
            )
        for bound in (v.lo, v.hi):
            from_dict(apply_overrides(base, {v.path: v.value(bound)}), source=f"--vary {v.path}={v.lo:g}:{v.hi:g}")
    rules = dict(MODIFICATION_YIELDS)
    specs = [parse_spec(s, QUANTITIES) for s in cfg.specs]
    if specs:
        rules["spec"] = specs
    plan = TolerancePlan.build(reducer, tol, cfg.seed)
    x = plan.values(plan.unit_samples(cfg.samples_per_design, "sobol")) if plan.dim else None
    draws = [plan.errors_for(x[i] if x is not None else np.zeros(0)) for i in range(cfg.samples_per_design)]
    problem = Problem(
        base=base,
        variables=variables,
        objectives=[],
        constraints=[],
        quantities=dict(QUANTITIES),
        rules=rules,
        draws=draws,
        task=MODIFICATION_TASK,
        options={"resolution": dict(cfg.resolution)},
        validate=_validator("optimize candidate"),
    )
    attach_goals(problem, cfg.objectives, cfg.constraints)
    return problem, reducer, [s.label for s in specs]


def attach_goals(problem: Problem, objectives: list[str], constraints: list[str]) -> None:
    """Parse the objectives and constraints against the problem's metric names (and their
    ``preset_`` forms: the design itself, same draws)."""
    names = problem.names
    cnames = names + [f"preset_{n}" for n in names]
    problem.objectives = [parse_objective(o, names) for o in objectives]
    if len({o.name for o in problem.objectives}) != len(problem.objectives):
        raise InputError(f"--objective: a metric is given twice ({', '.join(objectives)})")
    problem.constraints = [parse_constraint(c, cnames) for c in constraints]


def run_optimize(cfg: OptimizeConfig, progress: bool = True, mode: str = "dask", problem=None) -> dict[str, Any]:
    """Run (or resume) ``flexrv optimize``; returns the summary dict (also ``summary.json``).
    ``problem`` (with ``reducer`` None) injects a generic problem (the analytic test)."""
    from flexrv.cache import atomic_write_text
    from flexrv.studies._opt_runner import Runner, Store

    if problem is None:
        problem, reducer, spec_labels = build_problem(cfg)
    else:
        _check_config(cfg)
        reducer, spec_labels = None, list(cfg.specs)
    name = reducer.name if reducer is not None else Path(str(cfg.design)).stem
    out = Path(cfg.out) if cfg.out else Path("results") / f"{Path(cfg.design).stem}_optimize_s{cfg.seed}"
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "config.json", json.dumps(_config_dict(cfg), indent=1))
    from flexrv.sweep import process_cpu_s

    runner = Runner(cfg.scheduler, cfg.workers, mode=mode)
    store = Store(out, problem.task, problem.draws, runner)
    t0, cpu0 = time.perf_counter(), process_cpu_s()
    try:
        preset = _evaluate_preset(problem, store)
        cands = search(problem, store, cfg.budget, cfg.population, cfg.seed, preset.metrics, _printer(progress))
        front = pareto(problem, cands)
        rec = recommend(problem, front)
        full = {}
        if cfg.reevaluate and front:
            full = _reevaluate(problem, store, cfg, [preset] + list(rec.values()), preset.metrics)
    finally:
        runner.close()
    result = {
        "design": name,
        "output_dir": str(out),
        "samples_per_design": cfg.samples_per_design,
        "seed": cfg.seed,
        "budget": cfg.budget,
        "population": max(2, min(cfg.population, cfg.budget)),
        "variables": [{"field": v.path, "lo": v.lo, "hi": v.hi} for v in problem.variables],
        "objectives": [str(o) for o in problem.objectives],
        "constraints": [str(c) for c in problem.constraints],
        "specs": spec_labels,
        "resolution": problem.options.get("resolution"),
        "full_resolution": cfg.full_resolution,
        "cheap_error": CHEAP_ERROR,
        "evaluations": len(cands),
        "feasible": sum(c.feasible for c in cands),
        "computed_now": store.computed,
        "reused": store.reused,
        "wall_time_s": time.perf_counter() - t0,
        "cpu": {"client_cpu_s": process_cpu_s() - cpu0, "workers_cpu_s": store.workers_cpu_s},
        "preset": _point(problem, preset, full.get(_key(preset))),
        "pareto": [_point(problem, c) for c in front],
        "recommended": {k: _point(problem, c, full.get(_key(c))) for k, c in rec.items()},
    }
    result["lost_motion_target"] = _lost_motion_report(problem, cands, front, cfg.lost_motion_target_arcmin)
    result["yield_gain"] = _yield_gain(result)
    from flexrv.studies._opt_output import write_outputs

    write_outputs(out, problem, cfg, cands, front, rec, result, reducer)
    atomic_write_text(out / "summary.json", json.dumps(_jsonable(result), indent=1))
    if not front:
        raise InputError(infeasibility_message(problem, cands) + f" (outputs in {out})")
    return result


def _jsonable(obj):
    from flexrv.cache import to_jsonable

    return to_jsonable(obj)


def _config_dict(cfg: OptimizeConfig) -> dict:
    return {k: getattr(cfg, k) for k in cfg.__dataclass_fields__}


def _printer(enabled: bool):
    if not enabled:
        return None

    def show(gen: int, n_eval: int, budget: int) -> None:
        import sys

        print(f"optimize: generation {gen}, {n_eval}/{budget} candidates", file=sys.stderr, flush=True)

    return show


def _key(c: Candidate) -> tuple:
    return tuple(np.round(c.x, 15))


def _evaluate_preset(problem: Problem, store) -> Candidate:
    """The design itself (its own field values, inside the box or not), same draws."""
    x = problem.base_x()
    (record,) = _evaluate(problem, store, [problem.base], [problem.fields(x)])
    c = _candidate(problem, x, record, None)
    c.source = "preset"
    return c


def _reevaluate(problem: Problem, store, cfg: OptimizeConfig, cands: list[Candidate], preset_metrics) -> dict:
    """Full-resolution metrics of candidates (same draws), by their key."""
    full = Problem(**{**problem.__dict__, "options": {"resolution": dict(cfg.full_resolution)}})
    uniq = {}
    for c in cands:
        uniq.setdefault(_key(c), c)
    xs = [c.x for c in uniq.values()]
    records = _evaluate(full, store, [full.design_for(x) for x in xs], [full.fields(x) for x in xs])
    out = {}
    for k, x, r in zip(uniq, xs, records):
        out[k] = _candidate(full, x, r, None)
    return out


def _point(problem: Problem, c: Candidate, full: Candidate | None = None) -> dict[str, Any]:
    """A point of the JSON: its varied fields, every metric, feasibility; ``full`` metrics if re-evaluated."""
    d: dict[str, Any] = dict(c.fields)
    d.update(c.metrics)
    d["feasible"] = c.feasible
    d["status"] = c.status
    if c.violations:
        d["constraint_violation"] = dict(c.violations)
    if full is not None:
        d["full"] = {k: v for k, v in full.metrics.items()}
        d["full_minus_cheap"] = {
            k: full.metrics[k] - c.metrics[k]
            for k in full.metrics
            if k in c.metrics and math.isfinite(full.metrics[k]) and math.isfinite(c.metrics[k])
        }
    return d


def _lost_motion_report(problem: Problem, cands, front, target: float) -> dict[str, Any] | None:
    """Does any modification reach P95 lost motion <= target; if only infeasible ones do,
    which constraint prevents it."""
    name = metric_name("lost_motion", "p95", problem.quantities.get("lost_motion", ""))
    if "lost_motion" not in problem.quantities:
        return None
    ok = [c for c in cands if c.status == "ok" and math.isfinite(c.metrics.get(name, math.nan))]
    if not ok:
        return None
    best_any = min(ok, key=lambda c: c.metrics[name])
    feas = [c for c in ok if c.feasible]
    best_feas = min(feas, key=lambda c: c.metrics[name]) if feas else None
    reached = [c for c in ok if c.metrics[name] <= target]
    out = {
        "metric": name,
        "target": target,
        "best_feasible": best_feas.metrics[name] if best_feas else None,
        "best_feasible_fields": best_feas.fields if best_feas else None,
        "best_any": best_any.metrics[name],
        "best_any_fields": best_any.fields,
    }
    if best_feas is not None and best_feas.metrics[name] <= target:
        out["verdict"] = f"reached: {name} = {best_feas.metrics[name]:.3f} <= {target:g} with every constraint met"
    elif reached:
        blocking: dict[str, int] = {}
        for c in reached:
            for con, v in c.violations.items():
                if v > 0:
                    blocking[con] = blocking.get(con, 0) + 1
        worst = max(blocking, key=blocking.get) if blocking else "-"
        out["blocking_constraint"] = worst
        out["verdict"] = (
            f"not reached with the constraints: {len(reached)} evaluated designs have {name} <= {target:g}, "
            f"but each violates a constraint (most often {worst!r})"
        )
    else:
        out["verdict"] = (
            f"not reached in the box: the smallest {name} of {len(ok)} evaluated designs is "
            f"{best_any.metrics[name]:.3f} > {target:g} (at {best_any.fields})"
        )
    return out


def _yield_gain(result: dict) -> dict[str, Any]:
    """Yields of each recommended design against the design itself (full figures where re-evaluated)."""

    def figs(p):
        return p.get("full", p)

    pre = figs(result["preset"])
    out = {}
    for k, p in result["recommended"].items():
        f = figs(p)
        out[k] = {
            y: {"preset": pre.get(y), "design": f.get(y), "gain": (f.get(y) or 0.0) - (pre.get(y) or 0.0)}
            for y in f
            if y.endswith("_yield")
        }
    return out
