"""Main-bearing ball load distribution (rigid rings) vs Stribeck/Harris closed forms."""

import math

import numpy as np
import pytest

from flexrv.analysis.bearing_load import ball_load_distribution, stribeck_max_load
from flexrv.contact.hertz import effective_modulus
from flexrv.design import load
from flexrv.errors import InputError
from flexrv.geometry.bearing import BallBearingGeometry


@pytest.fixture(scope="module")
def geom():
    return BallBearingGeometry.from_design(load("rv221").main_bearing)


E_EFF = float(effective_modulus(208e9, 0.3, 208e9, 0.3))


def _resultants(g, res):
    """Independent re-computation of the force/moment of the balls on the inner ring."""
    z_rows, sides = g.row_positions(), g.row_sides()
    d = g.ball_diameter
    r_i = 0.5 * g.pitch_diameter + (g.inner_conformity - 0.5) * d * math.cos(g.contact_angle)
    total_f, total_m = np.zeros(3), np.zeros(3)
    for r in range(len(z_rows)):
        zi = z_rows[r] + (g.inner_conformity - 0.5) * d * sides[r] * math.sin(g.contact_angle)
        for j, psi in enumerate(res.azimuth):
            a = res.contact_angle[r, j]
            n = np.array([math.cos(a) * math.cos(psi), math.cos(a) * math.sin(psi), sides[r] * math.sin(a)])
            f = -res.loads[r, j] * n
            p = np.array([r_i * math.cos(psi), r_i * math.sin(psi), zi])
            total_f += f
            total_m += np.cross(p, f)
    return total_f, total_m


def test_pure_axial_equal_sharing(geom):
    """Pure axial load: all balls of the loaded row carry the same load, and
    Z Q sin(a) = F_a (Harris & Kotzalas 2007, ch. 7), relative 1e-9."""
    fa = 20e3
    res = ball_load_distribution(geom, E_EFF, force=(0.0, 0.0, fa))
    loaded = res.loads[res.loads.max(axis=1).argmax()]
    assert np.ptp(loaded) < 1e-9 * loaded.max()
    f, _ = _resultants(geom, res)
    assert np.isclose(-f[2], fa, rtol=1e-9)


def test_stribeck_single_row_zero_clearance(geom):
    """Single row, zero clearance, pure radial load with the axial and tilt
    displacements held at zero: Q_max = 4.37 F_r / (Z cos a) (Stribeck; Harris &
    Kotzalas 2007 eq. 7.44) within 5 %, and Q(psi)/Q_max = cos(psi)^1.5 within 2 %
    (a small deviation comes from the load-dependent contact angle)."""
    fr = 20e3
    res = ball_load_distribution(
        geom, E_EFF, force=(fr, 0.0, 0.0), rows=[0], preload=0.0, free=(True, True, False, False, False)
    )
    q_ref = stribeck_max_load(fr, geom.ball_count, geom.contact_angle)
    assert abs(res.max_load / q_ref - 1) < 0.05
    psi = res.azimuth
    front = np.cos(psi) > 0.05
    assert np.allclose(res.loads[0, front] / res.max_load, np.cos(psi[front]) ** 1.5, atol=0.02)
    assert np.all(res.loads[0, np.cos(psi) < -1e-9] == 0)  # half the row unloaded


def test_moment_load_balances(geom):
    """Combined radial + axial + tilting moment: the recomputed ball resultants
    balance the applied loads (relative 1e-8)."""
    force, moment = np.array([8e3, -3e3, 12e3]), np.array([2e3, -4e3])
    res = ball_load_distribution(geom, E_EFF, force=force, moment=moment)
    f, m = _resultants(geom, res)
    assert np.allclose(-f, force, rtol=0, atol=1e-8 * 12e3)
    assert np.allclose(-m[:2], moment, rtol=0, atol=1e-8 * 4e3)
    assert np.abs(res.displacement[3:]).max() > 0  # the moment tilts the inner ring


def test_preload_only_symmetric(geom):
    """Preload alone: both rows equally loaded, no net force."""
    res = ball_load_distribution(geom, E_EFF)
    assert np.allclose(res.loads, res.loads[0, 0], rtol=1e-12) and res.max_load > 0
    assert np.allclose(res.displacement, 0.0, atol=1e-15)


def test_bad_input(geom):
    with pytest.raises(InputError):
        ball_load_distribution(geom, E_EFF, force=(np.nan, 0, 0))
