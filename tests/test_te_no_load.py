"""The no-load curve of `flexrv te` started from its image one crank revolution earlier
(flexrv.model.quasi_static.equilibrium_path(periodic=True)): the same equilibria as the
position-by-position route, at one residual call per position after the first revolution."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load, override
from flexrv.model.quasi_static import StaticModel, _periodic_image, equilibrium_path, positions_for, ramp_to
from flexrv.units import ARCSEC_PER_RAD


def _no_load_paths(reducer, crank_revolutions: float, check_every: tuple = ()):
    """The no-load curve (1 % rated torque) by both routes from the same start; returns
    (angles, model, (q, iterations, residual calls) of the old route, of the periodic one[, of the
    periodic one sampled every c-th imaged start for each c of ``check_every``])."""
    angles = positions_for(reducer, crank_revolutions=crank_revolutions, points_per_mesh=8)
    sm = StaticModel(reducer)
    rated = reducer.operating.rated_torque_Nm
    sm.torque = 0.0
    q = ramp_to(sm, angles[0], sm.kinematic_pose(angles[0]), rated, steps=8)
    q = ramp_to(sm, angles[0], q, 0.01 * rated)
    out = []
    for periodic, every in [(False, 1), (True, 1)] + [(True, c) for c in check_every]:
        c0 = sm.calls
        qs, its = equilibrium_path(sm, angles, q, periodic=periodic, check_every=every)
        out.append((qs, its, sm.calls - c0))
    return (angles, sm, *out)


def test_periodic_image_is_one_crank_revolution_and_one_pin_pitch():
    """rv40e at 8 points per mesh period: the image maps 8 x 39 = 312 positions (one crank
    revolution relative to the carrier, z_c = 39 mesh periods) and turns the in-plane vectors by
    the carrier's rotation over it, one pin pitch 2 pi / 40 (exact kinematics, 1e-12)."""
    red = load("rv40e")
    sm = StaticModel(red)
    angles = positions_for(red, crank_revolutions=2.0, points_per_mesh=8)
    image = _periodic_image(sm, angles)
    assert image.period == 8 * red.second_stage.disc_teeth == 312
    kin = sm.kinematic_pose(angles)
    dth = kin[312, sm.i_theta] - kin[0, sm.i_theta]
    assert dth == pytest.approx(2 * np.pi / red.second_stage.pin_count, rel=1e-12)
    # the kinematic pose is its own image (zero deviation), and a radial crank offset turns with the carrier
    q = kin[0].copy()
    assert np.allclose(image(q, kin[0], kin[312]), kin[312], atol=1e-15)
    o = sm.model.members["crank0"].offset
    q[o] += 1e-6
    moved = image(q, kin[0], kin[312]) - kin[312]
    assert moved[o] == pytest.approx(1e-6 * np.cos(dth), rel=1e-12)
    assert moved[o + 1] == pytest.approx(1e-6 * np.sin(dth), rel=1e-12)
    assert _periodic_image(sm, positions_for(red, crank_revolutions=0.5, points_per_mesh=8)) is None


def test_periodic_no_load_curve_equals_the_old_route():
    """rv40e, 2.5 crank revolutions (780 positions) at 1 % rated torque: both routes converge
    every position to the same tolerance, and their TE agree within the solver's resolution, 8e-4
    arcsec (it locates an equilibrium to about that, quasi_static.StaticModel.solve; measured 1.1e-4)
    and their p-p within 1e-6 relative; after the first revolution the periodic route needs zero
    Newton iterations (one residual call per position) at all but 1 % of the positions (measured:
    one of 468, at the edge of the tolerance), so it costs at most 0.7 x the old route's calls over
    2.5 revolutions (measured 0.65; the old route's extrapolated warm start needs 2.36 calls per
    position)."""
    angles, sm, (q0, it0, c0), (q1, it1, c1) = _no_load_paths(load("rv40e"), 2.5)
    assert np.all(it0 >= 0) and np.all(it1 >= 0)
    te0 = (q0[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    te1 = (q1[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    assert np.max(np.abs(te1 - te0)) < 8e-4
    assert np.ptp(te1) == pytest.approx(np.ptp(te0), rel=1e-6)
    assert np.count_nonzero(it1[312:]) <= 0.01 * len(it1[312:])
    assert c1 < 0.7 * c0


def test_periodic_start_ends_where_errors_break_the_symmetry():
    """One pin moved tangentially by 2 um breaks the symmetry: the image one revolution later sits
    on the neighbouring pin, is no equilibrium, and the route falls back to the old warm start;
    the curve (with its 4-6 arcsec bump) equals the old route's within 1e-4 arcsec."""
    base = override("rv40e", {"needle_bearing.radial_clearance_um": 0.0})
    t = [0.0] * base.second_stage.pin_count
    t[5] = 2.0
    angles, sm, (q0, it0, _), (q1, it1, _) = _no_load_paths(
        override(base, {"errors.pins.pin_tangential_position_um": t}), 1.5
    )
    te0 = (q0[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    te1 = (q1[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    assert np.ptp(te0) > 3.0
    assert np.max(np.abs(te1 - te0)) < 8e-4
    assert np.any(it1[312:] > 0)


def test_sampled_periodic_no_load_curve_equals_the_checked_route():
    """rv40e without errors, 4 crank revolutions (1248 positions) at 1 % rated torque, every 8th
    imaged start evaluated from the third revolution on (what `flexrv te` does for a design without
    manufacturing errors): the TE equals the periodic route's that checks every position within
    1e-8 arcsec (they differ only where that route took a Newton step at a miss, whose image then
    propagates: measured 3.7e-10 arcsec over a whole output revolution) and the position-by-position
    route's within the solver's resolution 8e-4 arcsec (measured 4.7e-5), at under 0.75 x the checked
    route's residual calls over 4 revolutions (measured 0.67: the first two revolutions are checked
    in full; over the whole output revolution of rv40e 0.20 against 1.03 calls per position, rv221
    0.17 against 1.02, TE within 9e-5 arcsec of the old route)."""
    angles, sm, (q0, it0, c0), (q1, it1, c1), (q8, it8, c8) = _no_load_paths(load("rv40e"), 4.0, check_every=(8,))
    assert np.all(it8 >= 0)
    te = [(q[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD for q in (q0, q1, q8)]
    assert np.max(np.abs(te[2] - te[1])) < 1e-8
    assert np.max(np.abs(te[2] - te[0])) < 8e-4
    assert c8 < 0.75 * c1


def test_sampled_periodic_route_solves_the_unchecked_positions_where_errors_break_the_symmetry():
    """One pin moved tangentially by 2 um (as in the test above), 3.5 crank revolutions, every 8th
    imaged start checked: the first check in the third revolution that misses ends the sampling and
    the positions taken unchecked before it are solved, so the curve (with its 4-6 arcsec bump)
    equals the position-by-position route's within the solver's resolution 8e-4 arcsec."""
    base = override("rv40e", {"needle_bearing.radial_clearance_um": 0.0})
    t = [0.0] * base.second_stage.pin_count
    t[5] = 2.0
    angles, sm, (q0, _, _), _, (q8, it8, _) = _no_load_paths(
        override(base, {"errors.pins.pin_tangential_position_um": t}), 3.5, check_every=(8,)
    )
    te0 = (q0[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    te8 = (q8[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    assert np.ptp(te0) > 3.0
    assert np.max(np.abs(te8 - te0)) < 8e-4


def test_check_every_needs_no_record():
    """Sampling skips residual calls, so it is refused with a per-position record."""
    red = load("rv40e")
    sm = StaticModel(red)
    angles = positions_for(red, crank_revolutions=0.1, points_per_mesh=8)
    with pytest.raises(ValueError, match="check_every"):
        equilibrium_path(sm, angles, sm.kinematic_pose(angles[0]), check_every=8, record=lambda *a: None)
