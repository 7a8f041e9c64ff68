"""The named figures of :mod:`flexrv.post.definitions` against closed forms of
piecewise-linear synthetic loops (known slopes, play and friction width)."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.post import definitions as d
from flexrv.units import ARCMIN_PER_RAD

T_R = 400.0


def _curve(t, b, k1, k2, t_knee):
    """Mid curve of a reducer with total play b [arcmin] and a stiffening wind-up: slope k1
    [N m/arcmin] below |T| = t_knee, k2 above; odd in T."""
    s, m = np.sign(t), np.abs(t)
    wind = np.where(m <= t_knee, m / k1, t_knee / k1 + (m - t_knee) / k2)
    return s * (0.5 * b + wind)


def _loop(b=2.0, k1=100.0, k2=200.0, t_knee=0.5 * T_R, h=0.0, n=4001):
    """The test program 0 -> +T_R -> -T_R -> 0 in time order: mid curve :func:`_curve`, the
    descending branch shifted by +h/2 and the ascending by -h/2 [arcmin] (a friction width h
    constant over the loop); the virgin branch 0 -> +T_R lies on the ascending branch. Angles
    returned in rad."""
    up = np.linspace(0.0, T_R, n)
    down = np.linspace(T_R, -T_R, 2 * n - 1)[1:]
    back = np.linspace(-T_R, 0.0, n)[1:]
    t = np.r_[up, down, back]
    shift = np.r_[-0.5 * h * np.ones(n), 0.5 * h * np.ones(2 * n - 2), -0.5 * h * np.ones(n - 1)]
    # the play is taken up at zero torque: the branches jump by b at T = 0 (sign of T)
    a = _curve(t, b, k1, k2, t_knee) + shift
    return t, a / ARCMIN_PER_RAD


def test_rigidities_on_a_piecewise_linear_loop():
    """Slopes k1 = 100 below T_R/2 and k2 = 200 above: the 50-100 % slope and the tangent are
    k2, the 3-50 % slope k1 (exact: the samples of each range lie on one line, rel 1e-9);
    the loop secant is 2 T_R / (theta(+T_R) - theta(-T_R)) with
    theta(T_R) = b/2 + T_R/(2 k1) + T_R/(2 k2) (closed form, rel 1e-9)."""
    b, k1, k2 = 2.0, 100.0, 200.0
    t, a = _loop(b, k1, k2)
    f = d.loop_figures(t, a, T_R)
    assert f["rigidity_slope_50_100_Nm_per_arcmin"] == pytest.approx(k2, rel=1e-9)
    assert f["rigidity_tangent_Nm_per_arcmin"] == pytest.approx(k2, rel=1e-9)
    assert f["rigidity_low_torque_Nm_per_arcmin"] == pytest.approx(k1, rel=1e-9)
    theta_r = 0.5 * b + 0.5 * T_R / k1 + 0.5 * T_R / k2
    assert f["rigidity_loop_secant_Nm_per_arcmin"] == pytest.approx(T_R / theta_r, rel=1e-9)
    assert f["angle_at_rated_arcmin"] == pytest.approx(theta_r, rel=1e-9)


def test_lost_motion_backlash_and_hysteresis_closed_forms():
    """Play b = 2 arcmin, linear wind-up k1 up to T_R/2, friction width h = 0.3 arcmin:
    lost motion at +-3 % = b + 2 (0.03 T_R)/k1, at +-1 % = b + 2 (0.01 T_R)/k1; the
    extrapolated backlash is b exactly (linear wind-up, rel 1e-9); hysteresis width = h;
    loss = the loop's area, width h over 2 T_R: E = 2 T_R h [N m arcmin] (rel 1e-3: the
    sample at T = 0 sits in the middle of the play's jump and narrows the loop over one
    torque step, 2.5e-4 here)."""
    b, k1, h = 2.0, 100.0, 0.3
    t, a = _loop(b, k1, 200.0, h=h)
    f = d.loop_figures(t, a, T_R)
    assert f["lost_motion_arcmin"] == pytest.approx(b + 2 * 0.03 * T_R / k1, rel=1e-9)
    assert f["lost_motion_1pct_arcmin"] == pytest.approx(b + 2 * 0.01 * T_R / k1, rel=1e-9)
    assert f["backlash_arcmin"] == pytest.approx(b, rel=1e-9)
    assert f["hysteresis_arcmin"] == pytest.approx(h, rel=1e-9)
    assert f["hysteresis_loss_J"] == pytest.approx(2 * T_R * h / ARCMIN_PER_RAD, rel=1e-3)
    # the mid curve removes the friction width: the rigidities are those of the mid curve
    assert f["rigidity_slope_50_100_Nm_per_arcmin"] == pytest.approx(200.0, rel=1e-9)


def test_branch_split_and_extrapolation_primitives():
    """split_branches: runs in time order, a turning point in the runs on both sides, a
    hold in the run before it; angle_at reads the latest run covering the torque;
    extrapolated_play recovers b of p = b + c T exactly."""
    t = np.array([0.0, 1.0, 2.0, 2.0, 1.0, 0.0, 1.0])
    a = np.arange(7.0)
    asc, desc = d.split_branches(t, a)
    assert [list(r[1]) for r in asc] == [[0, 1, 2, 3], [5, 6]]
    assert [list(r[1]) for r in desc] == [[3, 4, 5]]  # the hold ends at sample 3, the upper turning point
    assert d.angle_at(asc, 0.5) == pytest.approx(5.5)  # the later run, not the virgin one
    assert d.angle_at(asc, 1.5) == pytest.approx(1.5)  # only the first run reaches 1.5
    assert d.extrapolated_play(1.0, 3.0 + 0.5, 3.0, 3.0 + 1.5) == pytest.approx(3.0, rel=1e-14)
    assert d.loop_secant(412.0, 2.0) == pytest.approx(412.0)


def test_figures_outside_the_loop_are_nan():
    """A loop that does not reach the rated torque gives NaN where its torques are missing
    (the loop secant, the 50-100 % slope's upper samples fit, but not the tip)."""
    t, a = _loop()
    f = d.loop_figures(0.8 * t, a, T_R)
    assert np.isnan(f["rigidity_loop_secant_Nm_per_arcmin"])
    assert np.isnan(f["rigidity_tangent_Nm_per_arcmin"])
    assert np.isfinite(f["lost_motion_arcmin"])


def test_te_figures_forward_backward():
    """TE p-p and mean of a sine record (amplitude 2 arcsec, offset -5): p-p 4, mean -5
    (whole period, rel 1e-6); a backward record shifted by 0.7 arcsec gives a forward-backward
    difference of -0.7 (mean and |max| 0.7) on the common angles, also on another grid."""
    x = np.linspace(0.0, 2 * np.pi, 2001)
    arcsec = 1.0 / (ARCMIN_PER_RAD * 60.0)
    y = (-5.0 + 2.0 * np.sin(x)) * arcsec
    xb = np.linspace(0.0, 2 * np.pi, 777)
    yb = (-5.0 + 0.7 + 2.0 * np.sin(xb)) * arcsec
    f = d.te_figures(x, y, xb, yb)
    assert f["te_pp_arcsec"] == pytest.approx(4.0, rel=1e-6)
    assert f["te_mean_arcsec"] == pytest.approx(-5.0, rel=1e-3)
    assert f["te_forward_backward_mean_arcsec"] == pytest.approx(-0.7, abs=1e-4)
    assert f["te_forward_backward_max_arcsec"] == pytest.approx(0.7, abs=1e-4)


def test_every_definition_names_its_unit_and_a_known_source():
    """Each name ends with its unit and cites a bibliography key (or flexrv's own)."""
    from flexrv.references import REFERENCES

    for name, (units, how, source) in d.DEFINITIONS.items():
        suffix = {"N m/arcmin": "_Nm_per_arcmin", "arcmin": "_arcmin", "J": "_J"}[units]
        assert name.endswith(suffix) and how
        assert source == "flexrv" or source in REFERENCES
