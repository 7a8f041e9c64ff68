"""Prediction intervals from the estimated inputs of a design (``flexrv te --uncertainty N``,
``flexrv stiffness-test --uncertainty N``).

Each entry of the design's ``[ranges]`` table (an estimated field with its plausible range and
reason) is one input, uniform over its range. The unit hypercube is sampled by the tolerance
study's sampler (:meth:`flexrv.studies.tolerance.TolerancePlan.unit_samples`, scrambled
Sobol' from the seed) and every sample evaluated; each output is reported as its median and
90 % interval (5th and 95th percentiles) with the inputs it comes from (standardised
regression coefficients, :func:`flexrv.studies.tolerance.src_indices`: SRC^2 per input, and
the R^2 that says how much of the variance a linear model explains).

The evaluation (:func:`te_sample`) is the quasi-static route at a coarse resolution (one crank
revolution's tenth, 4 points per pin mesh, 2 catalog positions) with the design's elastic FE
bodies rigid and their nominal compliances added in series (the FE condensation of every
sample would cost a mesh each; their compliances depend on the sampled fields only through the
crank holes' micrometre changes): a series compliance c changes a rigidity k to 1 / (1/k + c),
the loop span by 2 T_r c and the lost motion by 2 (0.03 T_r) c. The compliances of
:mod:`flexrv.analysis.path_compliances` are in the sampled model (gear stage, support points).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from flexrv.units import RAD_PER_ARCMIN

#: the outputs of :func:`te_sample`
OUTPUTS = (
    "rigidity_tangent_Nm_per_arcmin",
    "rigidity_slope_50_100_Nm_per_arcmin",
    "rigidity_loop_secant_Nm_per_arcmin",
    "lost_motion_arcmin",
    "backlash_arcmin",
    "te_pp_arcsec",
)


def _plan(names: list[str], seed: int):
    """A :class:`flexrv.studies.tolerance.TolerancePlan` with one unit variable per input."""
    from flexrv.studies.tolerance import Column, TolerancePlan

    return TolerancePlan(
        reducer=None,
        tol=None,
        seed=int(seed),
        columns=[Column(n, n) for n in names],
        slices={n: slice(i, i + 1) for i, n in enumerate(names)},
    )


def interval(y: np.ndarray) -> dict:
    """Median and 90 % interval (5th, 95th percentile) of the finite values."""
    y = np.asarray(y, dtype=float)
    y = y[np.isfinite(y)]
    if y.size == 0:
        return {"n": 0}
    p5, p50, p95 = np.percentile(y, [5.0, 50.0, 95.0])
    return {"n": int(y.size), "median": float(p50), "p05": float(p5), "p95": float(p95)}


def propagate(
    evaluate: Callable[[dict], dict], ranges: dict, n: int, seed: int = 0, progress: Callable | None = None
) -> dict:
    """Sample ``ranges`` {input: (low, high)} uniformly (n scrambled Sobol' points), call
    ``evaluate({input: value})`` -> {output: value} on each, and return per output its
    :func:`interval` and ``contributors``: the inputs ranked by SRC^2 with R^2 (None with too
    few samples), plus ``samples`` (inputs and outputs per sample, NaN where it failed)."""
    from flexrv.errors import InputError
    from flexrv.studies.tolerance import src_indices

    if n < 4:
        raise InputError(f"--uncertainty {n}: allowed >= 4 samples")
    names = list(ranges)
    plan = _plan(names, seed)
    u = plan.unit_samples(n, "sobol")
    lo = np.array([ranges[k][0] for k in names], dtype=float)
    hi = np.array([ranges[k][1] for k in names], dtype=float)
    x = lo + u * (hi - lo)
    rows = []
    for i in range(n):
        try:
            rows.append(evaluate(dict(zip(names, x[i]))))
        except Exception as exc:  # a sample outside what the model converges on is reported, not fatal
            rows.append({"error": f"{type(exc).__name__}: {exc}"})
        if progress is not None:
            progress(i + 1, n)
    outputs = sorted({k for r in rows for k, v in r.items() if k != "error"})
    result = {"n": n, "inputs": {k: list(ranges[k]) for k in names}, "outputs": {}}
    for out in outputs:
        y = np.array([r.get(out, np.nan) for r in rows], dtype=float)
        src = src_indices(u, y, plan)
        entry = interval(y)
        entry["contributors"] = _contributors(u, y, names, src.get("variables"))
        result["outputs"][out] = entry
    result["failed"] = [r["error"] for r in rows if "error" in r]
    result["samples"] = {"inputs": x.tolist(), "outputs": [[r.get(o, np.nan) for o in outputs] for r in rows]}
    return result


def _contributors(u: np.ndarray, y: np.ndarray, names: list[str], fit: dict | None) -> dict | None:
    """The inputs an output's spread comes from: SRC^2 of the joint linear fit with its R^2, or,
    with fewer samples than inputs + 3 (no joint fit), each input's own SRC^2 (its squared
    correlation with the output; ``basis`` "marginal"), kept above the ``noise_floor`` 1/(N - 1)
    that an input without effect scores on average."""
    if fit is not None:
        return {"r2": fit["r2"], "src2": {k: v for k, v in fit["indices"].items() if v > 1e-4}}
    ok = np.isfinite(y)
    if ok.sum() < 3 or np.std(y[ok]) == 0.0:
        return None
    floor = 1.0 / (ok.sum() - 1)
    r2 = {k: float(np.corrcoef(u[ok, i], y[ok])[0, 1] ** 2) for i, k in enumerate(names) if np.std(u[ok, i]) > 0}
    top = sorted(((k, v) for k, v in r2.items() if v > floor), key=lambda kv: -kv[1])
    return {"r2": None, "basis": "marginal", "noise_floor": float(floor), "src2": dict(top)}


def _with_values(reducer, values: dict):
    """The design with the sampled values (integers rounded for integer fields)."""
    from flexrv.design import override
    from flexrv.design.model import field_value

    upd = {}
    for path, v in values.items():
        current = field_value(reducer, path)
        upd[path] = int(round(v)) if isinstance(current, int) and not isinstance(current, bool) else float(v)
    return override(reducer, upd)


def nominal_body_compliance(reducer) -> float:
    """The design's elastic FE bodies' torsional compliance at the output [rad/(N m)]
    (:func:`flexrv.fem.disc.body_compliances`, cached), 0 for rigid bodies."""
    carrier = reducer.carrier is not None and reducer.carrier.body_model == "condensed_fe"
    disc = reducer.second_stage.disc_body_model == "condensed_fe"
    if not (carrier or disc):
        return 0.0
    from flexrv.fem.disc import body_compliances

    fe = body_compliances(reducer)
    return (fe["carrier"]["compliance_rad_per_Nm"] if carrier else 0.0) + (
        fe["cycloid_disc"]["compliance_rad_per_Nm"] if disc else 0.0
    )


def te_sample(reducer, bodies: float) -> dict:
    """The named figures of one sampled design by the coarse quasi-static route, the FE bodies'
    nominal compliance ``bodies`` [rad/(N m)] in series (module docstring)."""
    from flexrv.model.quasi_static import loaded_te
    from flexrv.post.definitions import LOST_MOTION_FRACTION, PLAY_FRACTIONS
    from flexrv.post.te import te_dataset, te_summary

    upd = {"second_stage.disc_body_model": "rigid"}
    if reducer.carrier is not None:
        upd["carrier.body_model"] = "rigid"
    from flexrv.design import override

    rigid = override(reducer, upd)
    res = loaded_te(rigid, crank_revolutions=0.1, points_per_mesh=4, catalog_positions=2, play_fractions=PLAY_FRACTIONS)
    s = te_summary(te_dataset(res, rigid))
    c = bodies / RAD_PER_ARCMIN  # arcmin per N m
    rated = reducer.operating.rated_torque_Nm
    out = {k: s[k] for k in ("te_pp_arcsec", "backlash_arcmin")}
    for k in ("rigidity_tangent_Nm_per_arcmin", "rigidity_slope_50_100_Nm_per_arcmin"):
        out[k] = 1.0 / (1.0 / s[k] + c)
    out["rigidity_loop_secant_Nm_per_arcmin"] = (
        2.0 * rated / (2.0 * rated / s["rigidity_loop_secant_Nm_per_arcmin"] + 2.0 * rated * c)
    )
    out["lost_motion_arcmin"] = s["lost_motion_arcmin"] + 2.0 * LOST_MOTION_FRACTION * rated * c
    return out


def screen(evaluate: Callable[[dict], dict], ranges: dict, nominal: dict) -> list[str]:
    """The inputs an evaluation does not read: each input moved alone to the end of its range
    farther from its ``nominal`` value leaves every output bit-identical to the nominal
    evaluation (a deterministic route gives the same floats). An input whose move raises is kept."""
    base = evaluate({})
    inert = []
    for k, (lo, hi) in ranges.items():
        v = nominal.get(k)
        end = hi if v is None or abs(hi - v) >= abs(v - lo) else lo
        try:
            moved = evaluate({k: end})
        except Exception:  # the end alone is outside what the route converges on: the input matters
            continue
        if moved == base:
            inert.append(k)
    return inert


def design_uncertainty(reducer, n: int, seed: int = 0, progress: Callable | None = None) -> dict:
    """Prediction intervals of :data:`OUTPUTS` from the design's ``[ranges]`` (module docstring).
    Inputs the quasi-static route does not read (damping, inertia, thresholds of the dynamic
    models; :func:`screen`) are listed in ``no_effect`` and not sampled."""
    from flexrv.design.model import field_value
    from flexrv.errors import InputError

    if not reducer.ranges:
        raise InputError(f"{reducer.name} has no [ranges] table: no estimated input declares a plausible range")
    ranges = {k: (r.low, r.high) for k, r in reducer.ranges.items()}
    bodies = nominal_body_compliance(reducer)

    def evaluate(v):
        return te_sample(_with_values(reducer, v), bodies)

    inert = screen(evaluate, ranges, {k: field_value(reducer, k) for k in ranges})
    sampled = {k: r for k, r in ranges.items() if k not in inert}
    out = propagate(evaluate, sampled, n, seed, progress)
    out["sampled"] = list(sampled)
    out["inputs"] = {k: list(r) for k, r in ranges.items()}
    out["no_effect"] = inert
    out["reasons"] = {k: r.reason for k, r in reducer.ranges.items()}
    out["method"] = (
        "quasi-static route at a coarse resolution with every path compliance in the model, the FE bodies' "
        "nominal compliance added in series; inputs the route does not read screened out (no_effect); the others "
        "uniform over their [ranges], scrambled Sobol' samples; median and 5-95 % interval; contributors: "
        "SRC^2 of a linear fit (R^2 given), or each input's own SRC^2 with fewer samples than inputs + 3"
    )
    return out
