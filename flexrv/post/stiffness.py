"""Evaluation of the virtual torsional-stiffness test (seed 004 test bench):
input locked, output torque 0 -> +T_r -> -T_r -> 0 quasi-statically.

Definitions (Nabtesco RV catalogue conventions, seed 004 "average slope of the
loading and unloading curves"):

* torsional rigidity [N m/arcmin]: mean of the slopes dT/dtheta of the +T_r
  loading branch and of the -T_r branch, each a least-squares line over
  |T| in [T_r/2, T_r];
* lost motion [arcmin]: rotation between T = +3 % and T = -3 % of T_r on the
  mean (loading/unloading averaged) curve;
* hysteresis [arcmin]: width of the loop at T = 0 (descending minus returning
  branch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.units import ARCMIN_PER_RAD



@dataclass(frozen=True)
class StiffnessTest:
    """Figures of a stiffness test (angles in arcmin, torques in N m)."""

    rated_torque: float
    rigidity_Nm_per_arcmin: float
    rigidity_positive_Nm_per_arcmin: float
    rigidity_negative_Nm_per_arcmin: float
    lost_motion_arcmin: float
    hysteresis_arcmin: float
    angle_at_rated_arcmin: float


def _fit_slope(torque, angle, lo, hi):
    sel = (np.abs(torque) >= lo) & (np.abs(torque) <= hi)
    if sel.sum() < 3:
        return float("nan")
    return float(np.polyfit(angle[sel], torque[sel], 1)[0])


def _angle_at(torque_branch, angle_branch, value):
    order = np.argsort(torque_branch)
    return float(np.interp(value, torque_branch[order], angle_branch[order]))


def evaluate_stiffness_test(time, torque, angle, times) -> StiffnessTest:
    """Evaluate a loop. ``times`` = (t_start, t_pos, t_neg, t_end): the program
    ramps 0 -> +T_r on [t_start, t_pos], +T_r -> -T_r on [t_pos, t_neg] and
    -T_r -> 0 on [t_neg, t_end]; ``angle`` is the output rotation [rad]."""
    time, torque, angle = (np.asarray(a, dtype=float) for a in (time, torque, angle))
    a = angle * ARCMIN_PER_RAD
    t0, tp, tn, te = times
    rated = float(np.max(np.abs(torque)))
    up = (time >= t0) & (time <= tp)
    down = (time >= tp) & (time <= tn)
    back = (time >= tn) & (time <= te)
    k_pos = _fit_slope(torque[up], a[up], 0.5 * rated, rated)
    neg = down & (torque < 0)
    k_neg = _fit_slope(torque[neg], a[neg], 0.5 * rated, rated)
    # mean curve near zero: average of descending branch and ascending (up + back) branches
    asc_t = np.r_[torque[back], torque[up]]
    asc_a = np.r_[a[back], a[up]]
    d3 = 0.03 * rated
    mid_p = 0.5 * (_angle_at(torque[down], a[down], d3) + _angle_at(asc_t, asc_a, d3))
    mid_n = 0.5 * (_angle_at(torque[down], a[down], -d3) + _angle_at(asc_t, asc_a, -d3))
    hyst = _angle_at(torque[down], a[down], 0.0) - _angle_at(torque[back], a[back], 0.0)
    return StiffnessTest(rated_torque=rated, rigidity_Nm_per_arcmin=0.5 * (k_pos + k_neg),
                         rigidity_positive_Nm_per_arcmin=k_pos, rigidity_negative_Nm_per_arcmin=k_neg,
                         lost_motion_arcmin=mid_p - mid_n, hysteresis_arcmin=hyst,
                         angle_at_rated_arcmin=_angle_at(torque[up], a[up], rated))
