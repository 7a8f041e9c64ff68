"""Calibration: the design's uncertain inputs identified from bench measurements, with 95 %
intervals, their correlation and what one set of measurements cannot separate
(``flexrv calibrate``).

Forward model
-------------
The quasi-static equilibrium (:class:`flexrv.model.quasi_static.StaticModel`, the dynamic
model's force groups at zero speed) with the input locked at theta_in = 0, as in the
stiffness test: the output angle at the torques +-f T_r for f in :data:`LOOP_FRACTIONS`,
assembled into the loop 0 -> +T_r -> -T_r -> 0 (:func:`quasi_static_loop`). One evaluation
costs about 0.3 s on rv40e (model build from the cached FE bodies 0.2 s, 22 equilibria of a
few ms); a field that changes an FE body's geometry (e.g. the needle clearance, which sizes
the disc's crank holes) rebuilds that body (20 s) and is not freed by default.

Observations
------------
A stiffness loop gives the mid-curve spans s(f) = m(+f T_r) - m(-f T_r) for f in
:data:`SPAN_FRACTIONS`, m the mean of the ascending and descending branches
(:func:`flexrv.post.definitions.split_branches` / ``angle_at``): the span removes the
encoder's zero and the hysteresis (which the quasi-static model does not have), and holds
the lost motion (small f) and the wind-up (large f). A lost-motion points file gives its
lost motion and backlash (:func:`flexrv.post.definitions.loop_figures`). Every observation
is computed by the same function from the measured file and from the predicted loop.

Fit
---
Bounded nonlinear least squares (``scipy.optimize.least_squares``, trust-region reflective)
in unit coordinates u = (x - lo) / (hi - lo) of the free fields, residuals weighted by the
stated uncertainty (``angle_uncertainty_arcmin``: s(f) is a difference of two means of two
branches, sigma_s = sigma_angle) or, without one, by the residual scatter
s^2 = RSS / (n - p). The Jacobian is a forward difference (step :data:`FD_STEP` of each
range) whose p + 1 evaluations run in parallel on dask (the cluster options of
``flexrv tolerance``), or in the calling process with ``workers = 0``.

Uncertainty (Bates & Watts 1988 :cite:`bates1988nonlinear`): covariance s^2 (J^T J)^-1 of
the weighted Jacobian J at the optimum, 95 % intervals x +- q sigma_x (q = 1.96 for a stated
sigma, Student's t_{0.975, n-p} for a sigma from the scatter), the
correlation matrix; each interval's linearity is checked at its ends and the interval is
widened along the linearised profile path where the objective is visibly flatter than linear
(:func:`_profile_check`). Identifiability from the singular values sv_i of the scaled sensitivity
J (unit coordinates, weighted residuals): along the right singular vector v_i the data
determine the fields to a 95 % half-width t s / sv_i (in plausible ranges); a combination
with a half-width above :data:`UNRESOLVED_HALF_WIDTH` (the data do not narrow it to half its
range) or sv_i below :data:`IDENTIFIABLE_RATIO` sv_1 (structurally flat) is reported with its
weights; a field with a weight above 0.3 in such a combination is not identifiable and gets
no interval (its bounds are reported instead, never a tight interval). Two compliances in
series seen through one loop are the textbook case: only their sum is determined.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flexrv.errors import ConvergenceError, InputError
from flexrv.units import ARCMIN_PER_RAD

#: torque fractions of the rated torque at which the quasi-static loop is solved
LOOP_FRACTIONS = (0.001, 0.002, 0.01, 0.03, 0.1, 0.25, 0.5, 0.75, 0.95, 0.975, 1.0)
#: fractions at which a loop's mid-curve spans are observed
SPAN_FRACTIONS = (0.03, 0.1, 0.25, 0.5, 0.75, 1.0)
#: forward-difference step of the Jacobian in unit coordinates (1 % of each range)
FD_STEP = 0.01
#: singular-value ratio below which a combination of free fields is structurally not identifiable
IDENTIFIABLE_RATIO = 1e-6
#: 95 % half-width along a singular direction, in plausible ranges, above which the data do not
#: resolve that combination (practically not identifiable)
UNRESOLVED_HALF_WIDTH = 0.5
#: weight of a field in a non-identifiable combination above which the field is not identifiable
COMBINATION_WEIGHT = 0.3
#: range of the actual / linear objective rise at the Jacobian interval's ends taken as linear
LINEAR_RISE = (0.7, 1.4)
#: default plausible range of an estimated field, as factors of its estimate
DEFAULT_RANGE = (0.5, 1.5)


# ----------------------------------------------------------------------------- forward model
def quasi_static_loop(reducer, rated: float, fractions=LOOP_FRACTIONS, theta_in: float = 0.0):
    """The quasi-static loop (input locked at ``theta_in``): torques 0 -> +T_r -> -T_r -> 0
    through +-f ``rated`` for f in ``fractions`` and the output angle [rad], positive with
    positive torque (the loop's convention). Returns (torque [N m], angle [rad]) in the
    program's order. The model has no friction: both branches coincide."""
    from flexrv.model.quasi_static import StaticModel, ramp_to

    f = np.sort(np.asarray(fractions, dtype=float))
    sm = StaticModel(reducer)
    q_kin = sm.kinematic_pose(theta_in)
    angles = {}
    for sign in (1.0, -1.0):
        sm.torque = 0.0
        q = ramp_to(sm, theta_in, q_kin, sign * rated, steps=8)
        for x in f[::-1]:
            q = ramp_to(sm, theta_in, q, sign * x * rated, steps=1 if x > 0.2 else 2)
            angles[sign * x] = -float(q[sm.i_theta])
    pos = np.array([angles[x] for x in f])
    neg = np.array([angles[-x] for x in f])
    t = np.r_[f, f[::-1], -f, -f[::-1], f[:1]] * rated
    a = np.r_[pos, pos[::-1], neg, neg[::-1], pos[:1]]
    return t, a


def mid_spans(torque, angle_rad, rated: float, fractions=SPAN_FRACTIONS) -> np.ndarray:
    """Mid-curve spans m(+f T_r) - m(-f T_r) [arcmin] of a loop in time order, m the mean of
    its ascending and descending branches (:func:`flexrv.post.definitions.mid_curve`)."""
    from flexrv.post.definitions import mid_curve, split_branches

    asc, desc = split_branches(torque, np.asarray(angle_rad, dtype=float) * ARCMIN_PER_RAD)
    return np.array([mid_curve(asc, desc, f * rated) - mid_curve(asc, desc, -f * rated) for f in fractions])


@dataclass(frozen=True)
class Target:
    """One measured file as the fit sees it: what is observed and at which rated torque."""

    path: str
    kind: str  #: stiffness_loop | lost_motion
    rated: float  #: [N m]
    names: tuple[str, ...]  #: observation names
    values: np.ndarray  #: measured values [arcmin]
    sigma: float | None  #: stated 1-sigma of each observation [arcmin] (None: from the scatter)


LOST_MOTION_OBS = ("lost_motion_arcmin", "backlash_arcmin")


def observe(kind: str, torque, angle_rad, rated: float) -> np.ndarray:
    """The observations of a loop or of lost-motion points (the same function for a measured
    and a predicted record): spans at :data:`SPAN_FRACTIONS`, or lost motion and backlash."""
    if kind == "stiffness_loop":
        return mid_spans(torque, angle_rad, rated)
    from flexrv.measured.figures import loop_figures_of

    figs = loop_figures_of(torque, angle_rad, rated)
    return np.array([figs[k] for k in LOST_MOTION_OBS])


def targets_of(measurements) -> list[Target]:
    """The fit's targets from measured files (loops and lost-motion points; TE records are
    predicted, not fitted)."""
    from flexrv.measured.figures import rated_torque

    out = []
    for m in measurements:
        if m.kind not in ("stiffness_loop", "lost_motion"):
            continue
        rated = rated_torque(m)
        values = observe(m.kind, m.columns["torque"], m.columns["angle"], rated)
        if not np.all(np.isfinite(values)):
            raise InputError(f"{m.path}: the loop does not reach every torque of the fit ({SPAN_FRACTIONS} x T_r)")
        names = (
            tuple(f"span_{int(round(100 * f))}pct_arcmin" for f in SPAN_FRACTIONS)
            if m.kind == "stiffness_loop"
            else LOST_MOTION_OBS
        )
        sigma = m.meta.get("angle_uncertainty_arcmin")
        out.append(Target(m.path, m.kind, rated, names, values, None if sigma is None else float(sigma)))
    if not out:
        raise InputError("calibration needs at least one stiffness_loop or lost_motion file")
    return out


def predict(design: dict, overrides: dict, targets: list[tuple[str, float]]) -> list[list[float]]:
    """The forward model (one evaluation, runs on a dask worker): the design dict with the
    dotted ``overrides`` applied, its quasi-static loop at each target's rated torque and the
    target's observations. ``targets``: (kind, rated). NaN observations when the equilibrium
    does not converge (the fit treats them as a failed evaluation)."""
    from flexrv.design import apply_overrides, from_dict

    reducer = from_dict(apply_overrides(design, overrides), source="calibration")
    out = []
    for kind, rated in targets:
        try:
            t, a = quasi_static_loop(reducer, rated)
            out.append([float(v) for v in observe(kind, t, a, rated)])
        except ConvergenceError:
            out.append([float("nan")] * (len(SPAN_FRACTIONS) if kind == "stiffness_loop" else len(LOST_MOTION_OBS)))
    return out


# ----------------------------------------------------------------------------- evaluators
class Evaluator:
    """Runs forward-model evaluations in this process (``workers = 0``) or on dask (a
    LocalCluster of single-threaded worker processes, or the scheduler at ``scheduler``:
    the options of ``flexrv tolerance``)."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None):
        self.client = self.cluster = None
        self.calls = 0
        if scheduler:
            from flexrv.studies.tolerance import check_scheduler
            from flexrv.sweep import connect_scheduler

            check_scheduler(scheduler)
            self.client = connect_scheduler(scheduler)
        elif workers is None or workers > 0:
            from dask.distributed import Client, LocalCluster

            n = workers or min(2, os.cpu_count() or 1)
            self.cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
            )
            self.client = Client(self.cluster)

    def map(self, design: dict, overrides: list[dict], targets) -> list[list[list[float]]]:
        self.calls += len(overrides)
        if self.client is None:
            return [predict(design, o, targets) for o in overrides]
        futures = [self.client.submit(predict, design, o, targets, pure=False) for o in overrides]
        return self.client.gather(futures)

    def close(self) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


# ----------------------------------------------------------------------------- free fields
def field_value(reducer, dotted: str):
    node: Any = reducer
    for key in dotted.split("."):
        node = node[key] if isinstance(node, dict) else getattr(node, key, None)
        if node is None:
            raise InputError(f"--free {dotted}: no field {key!r} in the design")
    return node


def parse_free(texts: list[str], reducer) -> dict[str, tuple[float, float]]:
    """``FIELD=LO:HI`` -> {field: (lo, hi)}; the field must be a numeric design field and its
    value (the start) inside the range."""
    out = {}
    for text in texts:
        if "=" not in text or ":" not in text.split("=", 1)[1]:
            raise InputError(
                f"--free {text!r}: expected FIELD=LO:HI, e.g. crankshaft.support_bearing_axial_preload_um=0:6"
            )
        name, rng = text.split("=", 1)
        name = name.strip()
        try:
            lo, hi = (float(x) for x in rng.split(":", 1))
        except ValueError:
            raise InputError(f"--free {text!r}: LO and HI must be numbers") from None
        value = field_value(reducer, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"--free {name}: not a numeric design field (value {value!r})")
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise InputError(f"--free {text!r}: need finite LO < HI")
        if not lo <= float(value) <= hi:
            raise InputError(f"--free {name}={lo:g}:{hi:g}: the design's value {value!r} lies outside the range")
        out[name] = (lo, hi)
    return out


def estimated_fields(reducer) -> dict[str, tuple[float, float]]:
    """Candidate free fields: every float field whose provenance starts with "estimate" or that
    the design's ``[ranges]`` table gives a plausible range, > 0 (a range may start at 0),
    inside its range, and changing no FE body's geometry (a new body per evaluation would cost
    ~20 s); the range is the design's ``[ranges]`` entry, else :data:`DEFAULT_RANGE` x the
    estimate."""
    from flexrv.design import override
    from flexrv.fem.disc import body_design
    from flexrv.meshing.parts import spec_for

    def specs(r):
        out = [spec_for(body_design(r), "cycloid_disc")]
        if r.carrier is not None:
            out.append(spec_for(r, "carrier"))
        return out

    base = specs(reducer)
    ranges = getattr(reducer, "ranges", None) or {}
    names = [k for k, note in reducer.provenance.items() if note.lower().startswith("estimate")]
    names += [k for k in ranges if k not in names]
    out = {}
    for name in names:
        try:
            value = field_value(reducer, name)
        except InputError:
            continue
        if isinstance(value, bool) or not isinstance(value, float) or not (value > 0 or name in ranges):
            continue
        if name in ranges:
            lo, hi = float(ranges[name].low), float(ranges[name].high)
        else:
            lo, hi = DEFAULT_RANGE[0] * value, DEFAULT_RANGE[1] * value
        if not lo <= value <= hi or not lo < hi:
            continue
        try:
            if specs(override(reducer, {name: hi})) != base:
                continue
        except Exception:  # the design rejects the changed value: not a candidate
            continue
        out[name] = (lo, hi)
    return out


def screen(
    evaluator: Evaluator, design: dict, candidates: dict, targets: list[Target], max_free: int
) -> tuple[dict, list[dict]]:
    """Sensitivity screen of the candidate fields: each moved by 10 % of its range; the
    scaled sensitivity column (per unit range, per observation's scale) decides. Fields are
    taken by decreasing sensitivity while each adds a direction the chosen ones do not span
    (the part of its column orthogonal to theirs > 10 % of the column) and its effect exceeds
    1 % of the largest; at most ``max_free`` (fewer than the observations)."""
    names = list(candidates)
    spec = [(t.kind, t.rated) for t in targets]
    moved = []
    for n in names:
        lo, hi = candidates[n]
        v = float(_value_in(design, n))
        moved.append({n: v + 0.1 * (hi - lo) if v + 0.1 * (hi - lo) <= hi else v - 0.1 * (hi - lo)})
    rows = evaluator.map(design, [{}] + moved, spec)
    y0 = np.concatenate([np.asarray(r, dtype=float) for r in rows[0]])
    scale = np.maximum(np.abs(y0), 1e-3)
    cols = []
    for r in rows[1:]:
        y = np.concatenate([np.asarray(x, dtype=float) for x in r])
        cols.append((y - y0) / scale / 0.1)
    norms = np.array([np.linalg.norm(c) if np.all(np.isfinite(c)) else 0.0 for c in cols])
    order = np.argsort(-norms)
    chosen: list[int] = []
    report = []
    for i in order:
        reason = "chosen"
        if norms[i] < 0.01 * norms.max() or norms[i] == 0:
            reason = "insensitive (< 1 % of the most sensitive)"
        elif len(chosen) >= max_free:
            reason = f"limit of {max_free} free fields (observations - 1)"
        else:
            basis = np.array([cols[j] for j in chosen]).T if chosen else np.zeros((len(cols[i]), 0))
            resid = cols[i] - basis @ np.linalg.lstsq(basis, cols[i], rcond=None)[0] if chosen else cols[i]
            if np.linalg.norm(resid) < 0.1 * norms[i]:
                reason = "not separable from the chosen fields (collinear sensitivity)"
            else:
                chosen.append(int(i))
        report.append({"field": names[i], "sensitivity": float(norms[i]), "decision": reason})
    return {names[i]: candidates[names[i]] for i in chosen}, report


def _value_in(design: dict, dotted: str):
    node = design
    for key in dotted.split("."):
        node = node[key]
    return node


# ----------------------------------------------------------------------------- the fit
@dataclass
class Calibration:
    """Result of :func:`calibrate` (values in the fields' own units)."""

    free: dict[str, tuple[float, float]]
    start: dict[str, float]
    identified: dict[str, dict]  #: field -> value, ci95_low, ci95_high, identifiable, estimate, bounds
    correlation: list[list[float]]
    singular_values: list[float]  #: of the scaled sensitivity, largest first
    non_identifiable: list[dict]  #: combinations: {"singular_value_ratio", "weights": {field: w}}
    residuals: list[dict]  #: per observation: file, name, measured, fitted, residual, sigma
    residual_rms: float  #: RMS of the weighted residuals (1 for a fit at the stated uncertainty)
    residual_rms_arcmin: float
    sigma_source: str  #: "stated" or "residual scatter"
    evaluations: int
    wall_time_s: float
    status: str
    screening: list[dict] = field(default_factory=list)

    def overrides(self) -> dict[str, float]:
        return {k: v["value"] for k, v in self.identified.items()}


def _flat(rows) -> np.ndarray:
    return np.concatenate([np.asarray(r, dtype=float) for r in rows])


def calibrate(
    reducer,
    measurements,
    free: dict[str, tuple[float, float]] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    max_free: int = 3,
    max_nfev: int = 30,
) -> Calibration:
    """Fit the ``free`` fields (default: the screened estimates, :func:`screen`) of a design to
    the measured loops and lost-motion points (module docstring). Returns the
    :class:`Calibration` (the design itself is not changed; :func:`calibrated_design`)."""
    from scipy.optimize import least_squares
    from scipy.stats import norm
    from scipy.stats import t as student_t

    t_start = time.perf_counter()
    targets = targets_of(measurements)
    design = reducer.model_dump(mode="python")
    y_meas = np.concatenate([t.values for t in targets])
    n = len(y_meas)
    spec = [(t.kind, t.rated) for t in targets]
    stated = [t.sigma for t in targets]
    sigma = np.concatenate([np.full(len(t.values), t.sigma if t.sigma else 1.0) for t in targets])
    ev = Evaluator(workers, scheduler)
    screening: list[dict] = []
    try:
        if free is None:
            free, screening = screen(ev, design, estimated_fields(reducer), targets, min(max_free, n - 1))
        if not free:
            raise InputError("no free field: give --free FIELD=LO:HI (no estimated field is sensitive)")
        if len(free) >= n:
            raise InputError(f"{len(free)} free fields but only {n} observations: free fewer fields")
        names = list(free)
        lo = np.array([free[k][0] for k in names])
        hi = np.array([free[k][1] for k in names])
        x0 = np.array([float(field_value(reducer, k)) for k in names])
        u0 = (x0 - lo) / (hi - lo)
        cache: dict[bytes, np.ndarray] = {}

        def over(u):
            return {k: float(v) for k, v in zip(names, lo + np.clip(u, 0, 1) * (hi - lo))}

        def run(us):
            todo = [u for u in us if np.asarray(u).tobytes() not in cache]
            for u, rows in zip(todo, ev.map(design, [over(u) for u in todo], spec)):
                cache[np.asarray(u).tobytes()] = _flat(rows)
            return [cache[np.asarray(u).tobytes()] for u in us]

        def resid(u):
            y = run([np.asarray(u, dtype=float)])[0]
            r = (y - y_meas) / sigma
            return np.where(np.isfinite(r), r, 1e3)

        def jac(u):
            u = np.asarray(u, dtype=float)
            steps = [np.where(u[j] + FD_STEP <= 1.0, FD_STEP, -FD_STEP) for j in range(len(u))]
            pts = [u] + [u + steps[j] * np.eye(len(u))[j] for j in range(len(u))]
            ys = run(pts)
            return np.column_stack([(ys[j + 1] - ys[0]) / steps[j] / sigma for j in range(len(u))])

        sol = least_squares(resid, u0, jac=jac, bounds=(0.0, 1.0), x_scale=1.0, max_nfev=max_nfev, xtol=1e-6)
        u = sol.x
        r = resid(u)
        jw = jac(u)
        p = len(names)
        dof = n - p
        rss = float(r @ r)
        if all(s is not None for s in stated):
            s2, source = 1.0, "stated"
        else:
            s2, source = rss / dof, "residual scatter"
        # known sigma: the normal quantile; sigma from the scatter: Student's t with n - p dof
        t95 = float(norm.ppf(0.975)) if source == "stated" else float(student_t.ppf(0.975, dof))
        out = _uncertainty(names, lo, hi, x0, u, jw, s2, t95)
        _profile_check(out["identified"], names, lo, hi, u, jw, s2, t95, rss, lambda us: [resid(x) for x in us])
    finally:
        ev.close()
    fitted = y_meas + r * sigma
    rows, k = [], 0
    for t in targets:
        for name, v in zip(t.names, t.values):
            rows.append(
                {
                    "file": t.path,
                    "quantity": name,
                    "measured": float(v),
                    "fitted": float(fitted[k]),
                    "residual": float(fitted[k] - v),
                    "sigma": float(sigma[k] * math.sqrt(s2)),
                }
            )
            k += 1
    return Calibration(
        free=dict(free),
        start=dict(zip(names, x0.tolist())),
        identified=out["identified"],
        correlation=out["correlation"],
        singular_values=out["singular_values"],
        non_identifiable=out["non_identifiable"],
        residuals=rows,
        residual_rms=float(math.sqrt(rss / n) / math.sqrt(s2)),
        residual_rms_arcmin=float(np.sqrt(np.mean((fitted - y_meas) ** 2))),
        sigma_source=source,
        evaluations=ev.calls,
        wall_time_s=time.perf_counter() - t_start,
        status=str(sol.message),
        screening=screening,
    )


def _uncertainty(names, lo, hi, x0, u, jw, s2: float, t95: float) -> dict:
    """Intervals, correlation and identifiability from the weighted Jacobian ``jw`` in unit
    coordinates (module docstring)."""
    _, sv, vt = np.linalg.svd(jw, full_matrices=False)
    ratio = sv / sv[0] if sv[0] > 0 else np.zeros_like(sv)
    with np.errstate(divide="ignore"):
        half = np.where(sv > 0, t95 * math.sqrt(s2) / sv, np.inf)  # 95 % half-width along v_i, unit coordinates
    weak = [i for i in range(len(sv)) if ratio[i] < IDENTIFIABLE_RATIO or half[i] > UNRESOLVED_HALF_WIDTH]
    bad = set()
    combos = []
    for i in weak:
        w = vt[i] / np.max(np.abs(vt[i]))
        combos.append(
            {
                "singular_value_ratio": float(ratio[i]),
                "half_width_in_ranges": float(half[i]),
                "weights": dict(zip(names, w.tolist())),
            }
        )
        bad |= {names[j] for j in range(len(names)) if abs(vt[i][j]) > COMBINATION_WEIGHT}
    cov_u = s2 * np.linalg.pinv(jw.T @ jw)
    scale = hi - lo
    cov = cov_u * np.outer(scale, scale)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    corr[np.diag_indices_from(corr)] = np.where(sd > 0, 1.0, np.nan)  # exactly 1 by definition (not sd^2 / sd^2)
    x = lo + u * scale
    ident = {}
    for j, k in enumerate(names):
        ok = k not in bad and sd[j] > 0
        half = t95 * sd[j]
        ident[k] = {
            "value": float(x[j]),
            "ci95_low": float(x[j] - half) if ok else float(lo[j]),
            "ci95_high": float(x[j] + half) if ok else float(hi[j]),
            "identifiable": bool(ok),
            "estimate": float(x0[j]),
            "bounds": [float(lo[j]), float(hi[j])],
            "at_bound": bool(u[j] < 1e-6 or u[j] > 1 - 1e-6),
        }
    return {
        "identified": ident,
        "correlation": np.where(np.isfinite(corr), corr, np.nan).tolist(),
        "singular_values": sv.tolist(),
        "non_identifiable": combos,
    }


def _profile_check(ident: dict, names, lo, hi, u, jw, s2: float, t95: float, rss: float, residuals) -> None:
    """Nonlinearity check of each identifiable field's interval, widened where the objective is
    flatter than linear. In linear theory the profile of field j (the others at their
    conditional optimum) runs along d_j = C e_j / sqrt(C_jj) (C the covariance in unit
    coordinates) and the objective rises by exactly t^2 at u +- t d_j. The rise is evaluated
    there (2 evaluations per field): ``nonlinearity`` = actual / expected rise per end. Along
    this fixed path the others are not re-optimised, so the rise is an upper bound of the
    profile's: where it is below t^2 (ratio < ``LINEAR_RISE[0]``) the profile interval extends
    at least to where the path's rise reaches t^2, and the interval is widened to that point
    (bisection, ``interval_method = "profile path"``); a steeper rise cannot narrow it (that
    would need the full profile) and the Jacobian's end stays."""
    cov = s2 * np.linalg.pinv(jw.T @ jw)
    scale = hi - lo
    for j, k in enumerate(names):
        v = ident[k]
        v["interval_method"] = "jacobian"
        if not v["identifiable"] or cov[j, j] <= 0:
            continue
        d = cov[:, j] / math.sqrt(cov[j, j])

        def rise(a):
            x = np.clip(u + a * d, 0.0, 1.0)
            r = residuals([x])[0]
            return (float(r @ r) - rss) / s2

        ratios = [rise(t95) / t95**2, rise(-t95) / t95**2]
        v["nonlinearity"] = ratios
        for sign, ratio in zip((1.0, -1.0), ratios):
            if ratio >= LINEAR_RISE[0]:
                continue
            a_in, a_out = t95, 2 * t95
            while rise(sign * a_out) < t95**2 and a_out < 16 * t95:
                a_in, a_out = a_out, 2 * a_out
            for _ in range(10):
                mid = 0.5 * (a_in + a_out)
                a_in, a_out = (mid, a_out) if rise(sign * mid) < t95**2 else (a_in, mid)
            end = float(lo[j] + np.clip(u[j] + sign * a_out * d[j], 0.0, 1.0) * scale[j])
            key = "ci95_high" if sign > 0 else "ci95_low"
            v[key] = max(v[key], end) if sign > 0 else min(v[key], end)
            v["interval_method"] = "profile path"


def calibrated_design(reducer, cal: Calibration, files: list[str]):
    """The design with the identified values of the identifiable fields, each field's
    provenance naming the measurement files and the fit (the input design is not changed;
    the presets are never tuned)."""
    from flexrv.design import apply_overrides, from_dict

    over = {k: v["value"] for k, v in cal.identified.items() if v["identifiable"]}
    data = apply_overrides(reducer.model_dump(mode="python"), over)
    prov = dict(data.get("provenance", {}))
    names = ", ".join(Path(f).name for f in files)
    for k, v in cal.identified.items():
        if not v["identifiable"]:
            continue
        prov[k] = (
            f"calibrated by flexrv calibrate on {names}: {v['value']:.6g} (95 % interval {v['ci95_low']:.6g} .. "
            f"{v['ci95_high']:.6g}; bounded least squares on the quasi-static loop, sigma from {cal.sigma_source}); "
            f"was {v['estimate']:.6g}: {reducer.provenance.get(k, 'no provenance')}"
        )
    data["provenance"] = prov
    return from_dict(data, source=f"{reducer.name} calibrated")


def write_calibration(out: Path, reducer, cal: Calibration, files: list[str], extra: dict | None = None) -> dict:
    """``calibrated.toml`` (:func:`calibrated_design`) and ``calibration.json`` into ``out``;
    returns the JSON dict."""
    from flexrv.cache import atomic_write_text, to_jsonable
    from flexrv.design import to_toml

    out.mkdir(parents=True, exist_ok=True)
    design = calibrated_design(reducer, cal, files)
    atomic_write_text(out / "calibrated.toml", to_toml(design))
    data = calibration_dict(cal, files) | (extra or {})
    data["calibrated_design"] = str(out / "calibrated.toml")
    atomic_write_text(out / "calibration.json", json.dumps(to_jsonable(data), indent=1))
    return data


def calibration_dict(cal: Calibration, files: list[str]) -> dict:
    """The JSON of ``flexrv calibrate --json``."""
    return {
        "measured_files": list(files),
        "identified": cal.identified,
        "correlation": {"fields": list(cal.identified), "matrix": cal.correlation},
        "singular_values": cal.singular_values,
        "non_identifiable": cal.non_identifiable,
        "residual_rms": cal.residual_rms,
        "residual_rms_arcmin": cal.residual_rms_arcmin,
        "sigma_source": cal.sigma_source,
        "residuals": cal.residuals,
        "screening": cal.screening,
        "evaluations": cal.evaluations,
        "wall_time_s": cal.wall_time_s,
        "status": cal.status,
    }


def synthetic_loop(reducer, rated: float, sigma_arcmin: float, seed: int, points: int = 40):
    """A synthetic bench loop for round trips: the quasi-static loop of ``reducer`` at
    ``points`` torques per quarter (:func:`quasi_static_loop`, fractions 1 % .. 100 %) with
    independent normal angle noise of ``sigma_arcmin`` (generator seed ``seed``).
    Returns (torque [N m], angle [rad])."""
    from flexrv.units import RAD_PER_ARCMIN

    fractions = np.unique(np.r_[np.linspace(0.01, 1.0, points), LOOP_FRACTIONS])
    t, a = quasi_static_loop(reducer, rated, fractions)
    rng = np.random.default_rng(seed)
    return t, a + rng.normal(0.0, sigma_arcmin * RAD_PER_ARCMIN, size=a.shape)
