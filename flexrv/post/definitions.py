"""The named figures of a torque-twist test and of a TE record: one implementation for
predictions (``flexrv te``, ``flexrv stiffness-test``, ``flexrv design``) and for
measurements (bench files).

Every figure's name says which definition it is; :data:`DEFINITIONS` gives its unit, how it
is read and its source. Conventions (the catalogue's, :cite:`nabtesco_rv`, and the test
bench's, :cite:`seed004`):

* ``rigidity_slope_50_100_Nm_per_arcmin``: the catalogue's torsional rigidity, the slope of
  the loading branches between 50 % and 100 % of the rated torque (least-squares line of each
  branch, mean of the +T_r and -T_r branches) :cite:`nabtesco_rv`;
* ``rigidity_tangent_Nm_per_arcmin``: the tangent dT/dtheta at the rated torque (on a loop:
  the least-squares slope of the loading branches over the top :data:`TANGENT_WINDOW` of the
  rated torque; the quasi-static route reads it from its condensed Jacobian);
* ``rigidity_low_torque_Nm_per_arcmin``: the slope between 3 % and 50 % of the rated torque,
  from the edge of the lost-motion band to the start of the catalogue range (flexrv's range,
  the lower of the piecewise-linear stiffness regions strain-wave catalogues give as K1/K2);
* ``rigidity_loop_secant_Nm_per_arcmin``: :cite:`seed004`'s "average slope of the loading and
  unloading curves" of the +-T_r loop read as the secant through the loop's tips,
  2 T_r / (theta(+T_r) - theta(-T_r)): lost motion and hysteresis included;
* ``lost_motion_arcmin``: the rotation between +3 % and -3 % of the rated torque on the loop's
  mid curve (the mean of the ascending and descending branches) :cite:`nabtesco_rv`;
* ``lost_motion_1pct_arcmin``: the same read at +-1 % of the rated torque (includes the
  elastic wind-up between the two torques);
* ``backlash_arcmin``: the geometric play at zero torque: the play p(T) = m(T) - m(-T) of the
  mid curve m read at two small torques T1 < T2 (0.1 % and 0.2 % rated) and extrapolated
  linearly to T = 0, p(0) = (T2 p(T1) - T1 p(T2)) / (T2 - T1) (:func:`extrapolated_play`): a
  linear wind-up p = b + 2 T / k is taken out exactly. The wind-up is steepest at the smallest
  torques (one contact after another closes), so the two torques must be small: on rv40e with
  a 10 um equidistant modification the play reads 78.42 arcsec at 0.01 %, 78.90 at 0.1 %,
  80.69 at 0.5 %, 82.32 at 1 %; extrapolated from 0.5 % and 1 % it gave 79.05 (+0.8 %), from
  1 % and 3 % 79.27. A loop with friction crosses the play only where the torque exceeds the
  friction band: its mid curve at small torques lags, and the figure reads the play less the
  friction's wind-up (a Coulomb band f in series with a spring k: b - 2 f / k; rv40e's
  dynamic loop with friction reads 0.32 arcmin where the frictionless quasi-static route
  reads 1.25);
* ``hysteresis_arcmin``: the loop's width at T = 0 (descending minus ascending branch);
* ``hysteresis_loss_J``: the energy dissipated per cycle, the loop's area (twice the lower
  half, :func:`loop_energy`).

Sign convention: the output rotation increases with the output torque. Widths are the
descending minus the ascending branch, positive for a loop that dissipates energy (the
descending branch lies at the larger angles). TE records: :func:`te_figures`.
"""

from __future__ import annotations

import numpy as np

from flexrv.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD

#: (low, high) fractions of the rated torque of the catalogue rigidity
CATALOG_RANGE = (0.5, 1.0)
#: (low, high) fractions of the rated torque of the low-torque rigidity
LOW_TORQUE_RANGE = (0.03, 0.5)
#: fraction of the rated torque at which the lost motion is read (+-3 %)
LOST_MOTION_FRACTION = 0.03
#: the two small torques (fractions of rated) of the backlash extrapolation
PLAY_FRACTIONS = (0.001, 0.002)
#: the small torque of ``lost_motion_1pct_arcmin``
ONE_PERCENT = 0.01
#: top fraction of the loading branches over which a loop's tangent at rated is fitted
TANGENT_WINDOW = 0.05

#: name -> (unit, how it is read, source)
DEFINITIONS: dict[str, tuple[str, str, str]] = {
    "rigidity_tangent_Nm_per_arcmin": (
        "N m/arcmin",
        "tangent dT/dtheta at the rated torque (loop: slope of the loading branches over the top 5 % of T_r)",
        "flexrv",
    ),
    "rigidity_slope_50_100_Nm_per_arcmin": (
        "N m/arcmin",
        "catalogue rigidity: slope of the loading branches over 50-100 % T_r, mean of +T_r and -T_r",
        "nabtesco_rv",
    ),
    "rigidity_low_torque_Nm_per_arcmin": (
        "N m/arcmin",
        "slope of the loading branches over 3-50 % T_r, mean of +T_r and -T_r",
        "flexrv",
    ),
    "rigidity_loop_secant_Nm_per_arcmin": (
        "N m/arcmin",
        "secant through the tips of the +-T_r loop, 2 T_r / (theta(+T_r) - theta(-T_r)), lost motion included",
        "seed004",
    ),
    "lost_motion_arcmin": ("arcmin", "rotation between +3 % and -3 % T_r on the loop's mid curve", "nabtesco_rv"),
    "lost_motion_1pct_arcmin": ("arcmin", "rotation between +1 % and -1 % T_r on the loop's mid curve", "flexrv"),
    "backlash_arcmin": (
        "arcmin",
        "geometric play at zero torque: the +-0.1 % and +-0.2 % plays extrapolated linearly to T = 0",
        "flexrv",
    ),
    "hysteresis_arcmin": ("arcmin", "width of the loop at T = 0 (descending minus ascending branch)", "nabtesco_rv"),
    "hysteresis_loss_J": ("J", "energy dissipated per load cycle, the loop's area", "flexrv"),
}


def describe(name: str) -> dict:
    """``{"units", "description", "source"}`` of a named figure (KeyError for an unknown name)."""
    units, how, source = DEFINITIONS[name]
    return {"units": units, "description": how, "source": source}


def secant(t_a: float, theta_a: float, t_b: float, theta_b: float) -> float:
    """Slope (T_b - T_a) / (theta_b - theta_a) of the chord between two points of a curve."""
    return (t_b - t_a) / (theta_b - theta_a)


def loop_secant(rated_torque: float, span: float) -> float:
    """:cite:`seed004`'s loop rigidity: 2 T_r / (theta(+T_r) - theta(-T_r)), ``span`` the
    rotation between the loop's tips (any angle unit; the result per that unit)."""
    return 2.0 * rated_torque / span


def extrapolated_play(t1: float, play1: float, t2: float, play2: float) -> float:
    """Geometric play at zero torque from the plays ``play1``, ``play2`` read between +-t1 and
    +-t2 (0 < t1 < t2): the line through (t1, play1), (t2, play2) at T = 0,
    (t2 play1 - t1 play2) / (t2 - t1). Exact for a play b plus a linear wind-up 2 T / k."""
    return (t2 * play1 - t1 * play2) / (t2 - t1)


def split_branches(torque, angle):
    """The ascending (dT > 0) and descending (dT < 0) branches of a record in time order,
    each a list of monotone runs ``(T, theta)`` in time order; a turning point belongs to the
    runs on both sides, a hold (dT = 0) to the run before it."""
    t = np.asarray(torque, dtype=float)
    a = np.asarray(angle, dtype=float)
    s = np.sign(np.diff(t))
    for i in range(1, len(s)):  # holds continue the previous direction
        if s[i] == 0:
            s[i] = s[i - 1]
    asc, desc = [], []
    start = 0
    for i in range(1, len(s) + 1):
        if i == len(s) or s[i] != s[start]:
            if s[start] != 0:
                (asc if s[start] > 0 else desc).append((t[start : i + 1], a[start : i + 1]))
            start = i
    return asc, desc


def angle_at(branch, value: float) -> float:
    """The branch's angle at torque ``value``: linear interpolation on its latest run that
    covers ``value`` (a test that starts from rest has the virgin curve as an earlier run);
    NaN where no run does."""
    for t, a in reversed(branch):
        if len(t) >= 2 and t.min() <= value <= t.max():
            order = np.argsort(t, kind="stable")
            return float(np.interp(value, t[order], a[order]))
    return float("nan")


def fit_slope(branch, lo: float, hi: float) -> float:
    """Least-squares slope dT/dtheta of the samples with lo <= |T| <= hi on the branch's
    latest run that has at least 3 of them (NaN if none has)."""
    for t, a in reversed(branch):
        sel = (np.abs(t) >= lo) & (np.abs(t) <= hi)
        if sel.sum() >= 3 and np.ptp(a[sel]) > 0.0:
            return float(np.polyfit(a[sel], t[sel], 1)[0])
    return float("nan")


def loop_energy(descending, ascending, rated: float, samples: int = 2001) -> float:
    """Energy dissipated per load cycle = the loop's area oint T dtheta (angles [rad],
    torques [N m]): E = 2 int_{-T_r}^{0} (theta_desc(T) - theta_asc(T)) dT, the lower half of
    the loop doubled by its point symmetry (T, theta) -> (-T, -theta) (a reducer without a
    load-direction bias). The lower half is used because a test starting from rest has the
    virgin curve, not the ascending branch, above T = 0. Trapezoid rule on ``samples``
    torques. Check: a Coulomb element (spring k, friction F_c) gives the parallelogram's
    4 F_c (T_r - F_c)/k (tests/test_friction.py)."""
    t = np.linspace(-rated, 0.0, samples)
    a_d = np.array([angle_at(descending, x) for x in t])
    a_b = np.array([angle_at(ascending, x) for x in t])
    return float(2.0 * np.trapezoid(a_d - a_b, t))


def _loading(asc, desc):
    """The loading branches: the ascending runs at T >= 0, the descending ones at T <= 0."""
    pos = [(t[t >= 0.0], a[t >= 0.0]) for t, a in asc]
    neg = [(t[t <= 0.0], a[t <= 0.0]) for t, a in desc]
    return pos, neg


def mid_curve(asc, desc, value: float) -> float:
    """The loop's mid curve at torque ``value``: the mean of the ascending and descending
    branches' angles there (the hysteresis taken out)."""
    return 0.5 * (angle_at(asc, value) + angle_at(desc, value))


def loop_figures(torque_Nm, angle_rad, rated_torque_Nm: float) -> dict:
    """The named figures (:data:`DEFINITIONS`) of a torque-twist loop in time order (output
    torque [N m], output rotation [rad], rotation increasing with torque), with the points
    they are read at (``*_Nm`` / ``*_angle_arcmin`` and the branch slopes ``*_positive`` /
    ``*_negative``). A figure whose torques the loop does not reach is NaN."""
    tr = float(rated_torque_Nm)
    asc, desc = split_branches(torque_Nm, np.asarray(angle_rad, dtype=float) * ARCMIN_PER_RAD)
    pos, neg = _loading(asc, desc)
    out = {}
    for name, (lo, hi) in (
        ("rigidity_slope_50_100", CATALOG_RANGE),
        ("rigidity_low_torque", LOW_TORQUE_RANGE),
        ("rigidity_tangent", (1.0 - TANGENT_WINDOW, 1.0)),
    ):
        kp, kn = fit_slope(pos, lo * tr, hi * tr), fit_slope(neg, lo * tr, hi * tr)
        out[f"{name}_Nm_per_arcmin"] = 0.5 * (kp + kn)
        out[f"{name}_positive_Nm_per_arcmin"] = kp
        out[f"{name}_negative_Nm_per_arcmin"] = kn
    tip_p, tip_n = angle_at(pos, tr), angle_at(neg, -tr)
    out["rigidity_loop_secant_Nm_per_arcmin"] = loop_secant(tr, tip_p - tip_n)
    out["angle_at_rated_arcmin"] = tip_p
    plays = {}
    for f in sorted({LOST_MOTION_FRACTION, ONE_PERCENT, *PLAY_FRACTIONS}):
        lo_, hi_ = mid_curve(asc, desc, -f * tr), mid_curve(asc, desc, f * tr)
        plays[f] = (lo_, hi_)
    lm_n, lm_p = plays[LOST_MOTION_FRACTION]
    out["lost_motion_arcmin"] = lm_p - lm_n
    out["lost_motion_negative_angle_arcmin"], out["lost_motion_positive_angle_arcmin"] = lm_n, lm_p
    f1, f2 = PLAY_FRACTIONS
    p1, p2 = plays[f1][1] - plays[f1][0], plays[f2][1] - plays[f2][0]
    out["lost_motion_1pct_arcmin"] = plays[ONE_PERCENT][1] - plays[ONE_PERCENT][0]
    out["backlash_arcmin"] = extrapolated_play(f1 * tr, p1, f2 * tr, p2)
    a_d0, a_a0 = angle_at(desc, 0.0), angle_at(asc, 0.0)
    out["hysteresis_arcmin"] = a_d0 - a_a0
    out["hysteresis_descending_angle_arcmin"], out["hysteresis_ascending_angle_arcmin"] = a_d0, a_a0
    in_rad = [[(t, a / ARCMIN_PER_RAD) for t, a in branch] for branch in (desc, asc)]
    out["hysteresis_loss_J"] = loop_energy(in_rad[0], in_rad[1], tr)
    out["rated_torque_Nm"] = tr
    out["lost_motion_torque_Nm"] = LOST_MOTION_FRACTION * tr
    out["fit_range_low_Nm"] = CATALOG_RANGE[0] * tr
    out["low_range_low_Nm"] = LOW_TORQUE_RANGE[0] * tr
    return out


def te_figures(angle_rad, te_rad, backward_angle_rad=None, backward_te_rad=None) -> dict:
    """Named figures of a TE record (TE = theta_out - theta_in / i [rad] over the input or
    output angle [rad]): ``te_pp_arcsec`` (peak to peak), ``te_mean_arcsec``; with a record
    in the opposite direction of rotation, ``te_forward_backward_mean_arcsec`` (mean of the
    forward minus the backward TE over the common angles, the lost motion under motion) and
    ``te_forward_backward_max_arcsec`` (its largest absolute value). NaN samples (unconverged
    positions) are left out."""
    x = np.asarray(angle_rad, dtype=float)
    y = np.asarray(te_rad, dtype=float) * ARCSEC_PER_RAD
    ok = np.isfinite(y)
    out = {
        "te_pp_arcsec": float(np.ptp(y[ok])) if ok.any() else float("nan"),
        "te_mean_arcsec": float(np.mean(y[ok])) if ok.any() else float("nan"),
    }
    if backward_te_rad is not None:
        xb = np.asarray(backward_angle_rad, dtype=float)
        yb = np.asarray(backward_te_rad, dtype=float) * ARCSEC_PER_RAD
        okb = np.isfinite(yb)
        order = np.argsort(xb[okb])
        xs, ys = xb[okb][order], yb[okb][order]
        common = ok & (x >= xs[0]) & (x <= xs[-1])
        d = y[common] - np.interp(x[common], xs, ys)
        out["te_forward_backward_mean_arcsec"] = float(np.mean(d)) if d.size else float("nan")
        out["te_forward_backward_max_arcsec"] = float(np.max(np.abs(d))) if d.size else float("nan")
    return out
