"""The no-load curve of `flexrv te` started from its image one crank revolution earlier
(flexrv.model.quasi_static.equilibrium_path(periodic=True)): the same equilibria as the
position-by-position route, at one residual call per position after the first revolution."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load, override
from flexrv.model.quasi_static import StaticModel, _periodic_image, equilibrium_path, positions_for, ramp_to
from flexrv.units import ARCSEC_PER_RAD


def _no_load_paths(reducer, crank_revolutions: float):
    """The no-load curve (1 % rated torque) by both routes from the same start; returns
    (angles, model, (q, iterations, residual calls) of the old route, of the periodic one)."""
    angles = positions_for(reducer, crank_revolutions=crank_revolutions, points_per_mesh=8)
    sm = StaticModel(reducer)
    rated = reducer.operating.rated_torque_Nm
    sm.torque = 0.0
    q = ramp_to(sm, angles[0], sm.kinematic_pose(angles[0]), rated, steps=8)
    q = ramp_to(sm, angles[0], q, 0.01 * rated)
    out = []
    for periodic in (False, True):
        c0 = sm.calls
        qs, its = equilibrium_path(sm, angles, q, periodic=periodic)
        out.append((qs, its, sm.calls - c0))
    return angles, sm, out[0], out[1]


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
    one of 468, at the edge of the tolerance), so it costs at most 0.6 x the old route's calls over
    2.5 revolutions (measured 0.56)."""
    angles, sm, (q0, it0, c0), (q1, it1, c1) = _no_load_paths(load("rv40e"), 2.5)
    assert np.all(it0 >= 0) and np.all(it1 >= 0)
    te0 = (q0[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    te1 = (q1[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
    assert np.max(np.abs(te1 - te0)) < 8e-4
    assert np.ptp(te1) == pytest.approx(np.ptp(te0), rel=1e-6)
    assert np.count_nonzero(it1[312:]) <= 0.01 * len(it1[312:])
    assert c1 < 0.6 * c0


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
