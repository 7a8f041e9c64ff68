"""Main-bearing geometry (Harris & Kotzalas 2007, ch. 2)."""

import math

import numpy as np
import pytest

from flexrv.design import load
from flexrv.geometry.bearing import BallBearingGeometry


@pytest.fixture(params=["rv221", "rv40e"])
def geom(request):
    return BallBearingGeometry.from_design(load(request.param).main_bearing)


def test_contact_points_on_groove(geom):
    """The nominal contact point lies on the groove torus and on the ball surface,
    along the contact angle."""
    for ring in ("inner", "outer"):
        s = geom.ring_section(ring)
        dist_groove = math.hypot(s.contact_r - s.groove_center_r, s.contact_z - s.groove_center_z)
        assert math.isclose(dist_groove, s.groove_radius, rel_tol=1e-12)
        dist_ball = math.hypot(s.contact_r - geom.pitch_diameter / 2, s.contact_z)
        assert math.isclose(dist_ball, geom.ball_diameter / 2, rel_tol=1e-12)
        angle = math.atan2(abs(s.contact_z), abs(s.contact_r - geom.pitch_diameter / 2))
        assert math.isclose(angle, geom.contact_angle, rel_tol=1e-12)
        assert s.r_inner < s.contact_r < s.r_outer and abs(s.contact_z) < s.width / 2


def test_groove_centres_distance_is_A(geom):
    si, so = geom.ring_section("inner"), geom.ring_section("outer")
    a = math.hypot(si.groove_center_r - so.groove_center_r, si.groove_center_z - so.groove_center_z)
    assert math.isclose(a, geom.curvature_center_distance, rel_tol=1e-12)
    # free contact angle from clearance: cos a0 = 1 - Pd/(2A)
    assert math.isclose(math.acos(1 - geom.diametral_clearance / (2 * a)), geom.contact_angle, rel_tol=1e-12)


def test_contact_radii_and_kinematics(geom):
    """Curvature sums (Harris eq. 2.27ff) and pure-rolling cage speed: for a fixed
    outer ring w_c = w_i (1 - gamma)/2."""
    rx_i, ry_i, rx_o, ry_o = geom.contact_radii()
    d = geom.ball_diameter
    assert rx_i < d / 2 < rx_o and ry_i > ry_o > 0  # f_i < f_o: inner groove conforms closer
    g = geom.gamma
    assert math.isclose(geom.cage_speed(10.0, 0.0), 10.0 * (1 - g) / 2)
    assert math.isclose(geom.entrainment_speed(10.0, 0.0), geom.pitch_diameter / 4 * (1 - g * g) * 10.0)
    # back-to-back: outer contacts face the other row
    assert np.all(geom.row_sides() == np.array([1.0, -1.0]))
