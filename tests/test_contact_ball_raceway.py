"""Ball–raceway contact kernel vs closed forms (Harris & Kotzalas 2007, sec. 7.2:
axially loaded angular contact ball bearing on rigid rings)."""

import math

import numpy as np
import pytest

from flexrv.contact.ball_raceway import RowContactGeometry, hertz_law, raceway_contacts, solve_ball_positions
from flexrv.contact.hertz import effective_modulus, series_stiffness
from flexrv.design import load
from flexrv.geometry.bearing import BallBearingGeometry


@pytest.fixture(params=["rv221", "rv40e"])
def setup(request):
    r = load(request.param)
    geom = BallBearingGeometry.from_design(r.main_bearing)
    m = r.material("bearing_rings")
    e_eff = effective_modulus(m.youngs_modulus, m.poisson_ratio, m.youngs_modulus, m.poisson_ratio)
    return geom, RowContactGeometry.from_bearing(geom, e_eff, side=1.0)


def test_unloaded_ball_touches_both_grooves(setup):
    """Nominal geometry: a ball at the pitch radius touches both grooves with zero approach."""
    geom, row = setup
    psi = np.linspace(0, 2 * np.pi, geom.ball_count, endpoint=False)
    ball = np.stack([row.ball_radius_pitch * np.cos(psi), row.ball_radius_pitch * np.sin(psi), 0 * psi], -1)
    law = hertz_law(row.k_inner)
    zero = np.zeros_like(ball)
    si = raceway_contacts(ball, zero, row.groove_centers(psi, "inner"), zero, row.inner_offset, law)
    so = raceway_contacts(ball, zero, row.groove_centers(psi, "outer"), zero, row.outer_offset, law)
    np.testing.assert_allclose(si.approach, 0, atol=1e-15)
    np.testing.assert_allclose(so.approach, 0, atol=1e-15)
    np.testing.assert_allclose(si.contact_angle, geom.contact_angle, rtol=1e-12)


@pytest.mark.parametrize("shift_um", [2.0, 10.0, 40.0])
def test_axial_shift_closed_form(setup, shift_um):
    """Rigid inner ring shifted axially by e (loading the row): every ball carries
    Q = K_s (A' - A)^1.5 with A' = sqrt((A cos a0)^2 + (A sin a0 + e)^2) and the
    loaded contact angle tan a = (A sin a0 + e)/(A cos a0) (Harris & Kotzalas
    eqs. 7.5-7.7). Tolerance 1e-6 relative."""
    geom, row = setup
    e = shift_um * 1e-6
    psi = np.linspace(0, 2 * np.pi, geom.ball_count, endpoint=False)
    ci = row.groove_centers(psi, "inner") + np.array([0, 0, row.side * e])
    co = row.groove_centers(psi, "outer")
    pos, si, so = solve_ball_positions(row, ci, co, hertz_law(row.k_inner), hertz_law(row.k_outer))
    a = geom.curvature_center_distance
    a0 = geom.contact_angle
    a_loaded = math.hypot(a * math.cos(a0), a * math.sin(a0) + e)
    q_expected = series_stiffness(row.k_inner, row.k_outer) * (a_loaded - a) ** 1.5
    np.testing.assert_allclose(si.load, q_expected, rtol=1e-6)
    np.testing.assert_allclose(so.load, q_expected, rtol=1e-6)
    alpha = math.atan2(a * math.sin(a0) + e, a * math.cos(a0))
    np.testing.assert_allclose(si.contact_angle, alpha, rtol=1e-6)
    # ball force balance
    np.testing.assert_allclose(si.force_ball + so.force_ball, 0, atol=1e-9 * q_expected)


def test_jacobian_matches_finite_difference(setup):
    geom, row = setup
    rng = np.random.default_rng(3)
    psi = rng.uniform(0, 2 * np.pi, 8)
    ci = row.groove_centers(psi, "inner")
    ball = row.groove_centers(psi, "inner") + 0  # start at the centres, move out along n
    co = row.groove_centers(psi, "outer")
    n = (ci - co) / np.linalg.norm(ci - co, axis=-1, keepdims=True)
    ball = ci - n * (row.inner_offset + 3e-6) + rng.normal(scale=1e-6, size=(8, 3))
    law = hertz_law(row.k_inner, c_max=50.0, depth=1e-6)
    vel = rng.normal(scale=1e-3, size=(8, 3))
    zero = np.zeros((8, 3))
    st = raceway_contacts(ball, vel, ci, zero, row.inner_offset, law)
    h = 1e-11
    for k in range(3):
        dpos = np.zeros(3)
        dpos[k] = h
        st2 = raceway_contacts(ball + dpos, vel, ci, zero, row.inner_offset, law)
        np.testing.assert_allclose(st.stiffness[:, :, k], (st2.force_ball - st.force_ball) / h, rtol=2e-4, atol=1e-3)
        dvel = np.zeros(3)
        dvel[k] = 1e-6
        st3 = raceway_contacts(ball, vel + dvel, ci, zero, row.inner_offset, law)
        np.testing.assert_allclose(st.damping[:, :, k], (st3.force_ball - st.force_ball) / 1e-6, rtol=1e-5, atol=1e-6)
