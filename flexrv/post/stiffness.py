"""Evaluation of the virtual torsional-stiffness test (:cite:`seed004` test bench):
input locked, output torque 0 -> +T_r -> -T_r -> 0 quasi-statically.

Definitions (Nabtesco RV catalogue conventions, :cite:`seed004` "average slope of the
loading and unloading curves"):

* torsional rigidity [N m/arcmin]: mean of the slopes dT/dtheta of the +T_r
  loading branch and of the -T_r branch, each a least-squares line over
  |T| in [T_r/2, T_r];
* lost motion [arcmin]: rotation between T = +3 % and T = -3 % of T_r on the
  mean (loading/unloading averaged) curve;
* hysteresis [arcmin]: width of the loop at T = 0 (descending minus returning
  branch), the "hysteresis loss" angle of the catalogues;
* low-torque rigidity [N m/arcmin]: the same mean of the two branches' least-squares
  slopes over |T| in [3 %, 50 %] of T_r, from the edge of the lost-motion band to the
  start of the catalogue range: the lower of the piecewise-linear torsional stiffness
  regions that Harmonic Drive catalogues give as K1/K2 (the RV catalogue gives the
  50-100 % slope only; the low range here is flexrv's definition, stated with its
  bounds in the figures);
* hysteresis loss [J]: the energy dissipated per load cycle, the loop's area
  oint T dtheta (:func:`loop_energy`).
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
    #: where the figures are read on the loop (for the plot and the saved file)
    fit_range_low_Nm: float = float("nan")  #: rigidity fit over |T| in [low, rated]
    lost_motion_torque_Nm: float = float("nan")  #: the +-3 % band of the lost motion
    lost_motion_negative_arcmin: float = float("nan")  #: mean-curve angle at -3 % T_r
    lost_motion_positive_arcmin: float = float("nan")  #: mean-curve angle at +3 % T_r
    hysteresis_returning_arcmin: float = float("nan")  #: returning branch at T = 0
    hysteresis_descending_arcmin: float = float("nan")  #: descending branch at T = 0
    hysteresis_loss_J: float = float("nan")  #: energy dissipated per load cycle, the loop area (loop_energy)
    friction_energy_J: float = 0.0  #: friction dissipation over the test program (0: no friction)
    rigidity_low_Nm_per_arcmin: float = float("nan")  #: mean branch slope over |T| in [3 %, 50 %] T_r
    low_range_low_Nm: float = float("nan")  #: low-torque fit over |T| in [low_range_low, fit_range_low]


def _fit_slope(torque, angle, lo, hi):
    sel = (np.abs(torque) >= lo) & (np.abs(torque) <= hi)
    if sel.sum() < 3:
        return float("nan")
    return float(np.polyfit(angle[sel], torque[sel], 1)[0])


def _angle_at(torque_branch, angle_branch, value):
    order = np.argsort(torque_branch)
    return float(np.interp(value, torque_branch[order], angle_branch[order]))


def loop_energy(torque_down, angle_down, torque_back, angle_back, rated: float, samples: int = 2001) -> float:
    """Energy dissipated per load cycle [J] = the area of the torque-twist loop,
    oint T dtheta, from the descending branch (+T_r -> -T_r) and the returning branch
    (-T_r -> 0) of the test program (angles [rad], torques [N m]):

        E = 2 int_{-T_r}^{0} (theta_down(T) - theta_back(T)) dT,

    the lower half of the loop, where both branches are measured, doubled by the
    loop's point symmetry (T, theta) -> (-T, -theta) (a reducer without load-direction
    bias; the upper half would need a second loading from the loop's centre). Trapezoid
    rule on ``samples`` torques, each branch interpolated at them (angle as a function of
    torque: monotone ramps). Check (tests/test_friction.py): a Coulomb element (spring
    k, friction force F_c) gives the parallelogram's 4 F_c (T_r - F_c)/k."""
    t = np.linspace(-rated, 0.0, samples)
    a_d = np.array([_angle_at(torque_down, angle_down, x) for x in t])
    a_b = np.array([_angle_at(torque_back, angle_back, x) for x in t])
    return float(2.0 * np.trapezoid(a_d - a_b, t))


def evaluate_stiffness_test(time, torque, angle, times, friction_power=None) -> StiffnessTest:
    """Evaluate a loop. ``times`` = (t_start, t_pos, t_neg, t_end): the program
    ramps 0 -> +T_r on [t_start, t_pos], +T_r -> -T_r on [t_pos, t_neg] and
    -T_r -> 0 on [t_neg, t_end]; ``angle`` is the output rotation [rad].
    ``friction_power`` [W] over ``time`` (the run's output ``friction_power``, if it has
    friction): its integral over [t_start, t_end] is the friction energy of the program
    [J], the friction part of the dissipation measured directly (trapezoid rule; 0
    without friction)."""
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
    a_down0, a_back0 = _angle_at(torque[down], a[down], 0.0), _angle_at(torque[back], a[back], 0.0)
    loss = loop_energy(torque[down], angle[down], torque[back], angle[back], rated)
    e_fric = 0.0
    if friction_power is not None:
        prog = (time >= t0) & (time <= te)
        e_fric = float(np.trapezoid(np.asarray(friction_power, dtype=float)[prog], time[prog]))
    k_low = 0.5 * (_fit_slope(torque[up], a[up], d3, 0.5 * rated) + _fit_slope(torque[neg], a[neg], d3, 0.5 * rated))
    return StiffnessTest(
        rated_torque=rated,
        rigidity_Nm_per_arcmin=0.5 * (k_pos + k_neg),
        rigidity_positive_Nm_per_arcmin=k_pos,
        rigidity_negative_Nm_per_arcmin=k_neg,
        lost_motion_arcmin=mid_p - mid_n,
        hysteresis_arcmin=a_down0 - a_back0,
        angle_at_rated_arcmin=_angle_at(torque[up], a[up], rated),
        fit_range_low_Nm=0.5 * rated,
        lost_motion_torque_Nm=d3,
        lost_motion_negative_arcmin=mid_n,
        lost_motion_positive_arcmin=mid_p,
        hysteresis_returning_arcmin=a_back0,
        hysteresis_descending_arcmin=a_down0,
        hysteresis_loss_J=loss,
        friction_energy_J=e_fric,
        rigidity_low_Nm_per_arcmin=k_low,
        low_range_low_Nm=d3,
    )


#: (variable, StiffnessTest field, units, long name) of the saved figures
_FIGURES = (
    ("rated_torque", "rated_torque", "N m", "rated (peak) torque of the loop"),
    (
        "torsional_rigidity",
        "rigidity_Nm_per_arcmin",
        "N m/arcmin",
        "torsional rigidity, mean of the +T_r and -T_r branch slopes over T_r/2 <= abs(T) <= T_r",
    ),
    (
        "torsional_rigidity_positive",
        "rigidity_positive_Nm_per_arcmin",
        "N m/arcmin",
        "slope of the +T_r loading branch over T in [T_r/2, T_r]",
    ),
    (
        "torsional_rigidity_negative",
        "rigidity_negative_Nm_per_arcmin",
        "N m/arcmin",
        "slope of the -T_r branch over -T in [T_r/2, T_r]",
    ),
    (
        "lost_motion",
        "lost_motion_arcmin",
        "arcmin",
        "lost motion: rotation between +3 % and -3 % of T_r on the mean curve",
    ),
    ("hysteresis", "hysteresis_arcmin", "arcmin", "hysteresis: loop width at T = 0"),
    (
        "hysteresis_loss",
        "hysteresis_loss_J",
        "J",
        "hysteresis loss: energy dissipated per load cycle, the loop area (twice the measured lower half)",
    ),
    (
        "friction_energy",
        "friction_energy_J",
        "J",
        "energy dissipated by friction over the test program "
        "(0 -> +T_r -> -T_r -> 0), integral of friction_power; 0 without friction",
    ),
    (
        "torsional_rigidity_low",
        "rigidity_low_Nm_per_arcmin",
        "N m/arcmin",
        "low-torque rigidity, mean of the +T_r and -T_r branch slopes over 3 % T_r <= abs(T) <= T_r/2",
    ),
    ("angle_at_rated", "angle_at_rated_arcmin", "arcmin", "output rotation at +T_r (loading)"),
    ("fit_range_low", "fit_range_low_Nm", "N m", "lower end of the rigidity fit range, abs(T)"),
    ("lost_motion_torque", "lost_motion_torque_Nm", "N m", "torque band of the lost motion, 3 % T_r"),
    ("lost_motion_negative_angle", "lost_motion_negative_arcmin", "arcmin", "mean-curve angle at -3 % T_r"),
    ("lost_motion_positive_angle", "lost_motion_positive_arcmin", "arcmin", "mean-curve angle at +3 % T_r"),
    ("hysteresis_returning_angle", "hysteresis_returning_arcmin", "arcmin", "returning branch at T = 0"),
    ("hysteresis_descending_angle", "hysteresis_descending_arcmin", "arcmin", "descending branch at T = 0"),
)


def stiffness_dataset(figures: StiffnessTest, time, torque, angle_arcmin, base=None):
    """The test's numbers as an :class:`xarray.Dataset`: every figure a scalar variable
    with ``units`` and ``long_name`` (rigidity, lost motion, hysteresis, ...), and the loop
    ``loop_torque`` [N m] / ``loop_angle`` [arcmin] over ``time`` [s]; merged into ``base``
    (the run's dataset) if given."""
    import xarray as xr

    data = {
        name: xr.Variable((), float(getattr(figures, field)), {"units": units, "long_name": long})
        for name, field, units, long in _FIGURES
    }
    data["loop_torque"] = xr.Variable(
        ("time",), np.asarray(torque, dtype=float), {"units": "N m", "long_name": "output torque of the test loop"}
    )
    data["loop_angle"] = xr.Variable(
        ("time",),
        np.asarray(angle_arcmin, dtype=float),
        {"units": "arcmin", "long_name": "output rotation of the test loop"},
    )
    ds = xr.Dataset(data, coords={"time": ("time", np.asarray(time, dtype=float), {"units": "s"})})
    if base is not None:
        ds = base.assign(**{k: ds[k] for k in ds.data_vars})
        ds.attrs = {k: v for k, v in base.attrs.items() if k != "stiffness_test"}
    ds.attrs["kind"] = "stiffness_test"
    return ds


def stiffness_json(figures: StiffnessTest) -> dict:
    """JSON-ready figures: ``{name: {"value", "units", "description"}}``."""
    return {
        name: {"value": float(getattr(figures, field)), "units": units, "description": long}
        for name, field, units, long in _FIGURES
    }


def stiffness_summary_markdown(
    figures: StiffnessTest,
    preset: str,
    model: str,
    quarter_time: float,
    dt: float,
    plot: str | None = "hysteresis.png",
    budget: dict | None = None,
) -> str:
    """summary.md of a stiffness test (not the time-simulation template): the program,
    the figures with units and how each is read, the loop plot, References."""
    f = figures
    lines = [
        f"# Stiffness test {preset} ({model} model)",
        "",
        f"Input locked; output torque 0 -> +{f.rated_torque:.4g} -> -{f.rated_torque:.4g} -> 0 N m, each "
        f"quarter over {quarter_time:.4g} s (quasi-static), dt = {dt:.3g} s. Definitions as in the RV "
        "catalogue and seed004 (average slope of the loading and unloading curves).",
        "",
        "| quantity | value | unit | how it is read |",
        "|---|---|---|---|",
    ]
    for name, field, units, long in _FIGURES[:9]:
        lines.append(f"| {name.replace('_', ' ')} | {getattr(f, field):.4g} | {units} | {long} |")
    lines += [
        "",
        f"Rigidity fit range: abs(T) = {f.fit_range_low_Nm:.4g} .. {f.rated_torque:.4g} N m; lost motion read "
        f"at T = +-{f.lost_motion_torque_Nm:.3g} N m ({f.lost_motion_negative_arcmin:.4g} .. "
        f"{f.lost_motion_positive_arcmin:.4g} arcmin); hysteresis at T = 0 ({f.hysteresis_returning_arcmin:.4g}"
        f" .. {f.hysteresis_descending_arcmin:.4g} arcmin).",
        "",
    ]
    if plot:
        lines += [f"![torque vs output rotation loop]({plot})", ""]
    if budget and not budget.get("compliances"):
        lines += [f"Note: {n}" for n in budget.get("notes", [])] + [""]
    elif budget:
        from flexrv.units import ARCSEC_PER_RAD, RAD_PER_ARCMIN

        comp = budget["compliances"]
        total = sum(comp.values())
        lines += [
            f"## Stiffness budget at {budget['torque']:.4g} N m",
            "",
            "Strain-energy budget of the quasi-static model at the test's pose (flexrv.simulation."
            "stiffness_test_budget), the same elements as `flexrv te` and `flexrv design`.",
            "",
            "| element | compliance [arcsec/(N m)] | share [%] |",
            "|---|---|---|",
        ]
        for name, c in sorted(comp.items(), key=lambda kv: -kv[1]):
            lines.append(f"| {name.replace('_', ' ')} | {c * ARCSEC_PER_RAD:.4g} | {100 * c / total:.3g} |")
        lines += [
            f"| total | {total * ARCSEC_PER_RAD:.4g} | 100 |",
            "",
            f"Budget rigidity {RAD_PER_ARCMIN / total:.4g} N m/arcmin; measured in the loop (50-100 % T_r) "
            f"{budget['measured_rigidity'] * RAD_PER_ARCMIN:.4g} N m/arcmin, "
            f"{budget['measured_with_unmodelled_rigidity'] * RAD_PER_ARCMIN:.4g} N m/arcmin with the elements "
            f"the model does not contain ({', '.join(budget['unmodelled']) or 'none'}) in series.",
        ]
        lines += [f"Note: {n}" for n in budget.get("notes", [])] + [""]
    lines += [
        "Files: results.nc (the run plus the figures as variables with units, and the loop), "
        "stiffness.json, config.toml.",
        "",
        "## References",
        "",
        "seed004 (RV-40E torsional stiffness): key `seed004` of `docs/references.md` in the flexrv repository.",
        "",
    ]
    return "\n".join(lines)
