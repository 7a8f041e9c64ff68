"""Hertz point and line contact against closed forms (Johnson 1985; Harris & Kotzalas 2007;
Hamrock 1994)."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.contact.hertz import (
    effective_modulus,
    line_contact,
    line_contact_stiffness,
    point_contact,
    point_contact_stiffness,
    series_stiffness,
)
from flexrv.errors import InputError

E_STEEL, NU = 207e9, 0.3


def test_effective_modulus_equal_steel():
    """E' = E/(1-nu^2) for two equal materials (Hamrock's definition)."""
    assert np.isclose(effective_modulus(E_STEEL, NU, E_STEEL, NU), E_STEEL / (1 - NU**2), rtol=1e-14)


def test_two_equal_spheres_closed_form():
    """Two steel spheres of radius r under W (Johnson 1985, eqs. 4.22–4.25):
    a = (3 W R/(4 E*))^(1/3) with 1/R = 2/r, E* = E'/2; delta = a^2/R; p0 = 3W/(2 pi a^2).
    Tolerance 1e-9 relative (exact elliptic integrals)."""
    r, load = 0.0125, np.array([10.0, 1e3, 5e4])
    e_eff = effective_modulus(E_STEEL, NU, E_STEEL, NU)
    res = point_contact(load, r / 2, r / 2, e_eff)
    r_j, e_star = r / 2, e_eff / 2
    a = (3 * load * r_j / (4 * e_star)) ** (1 / 3)
    np.testing.assert_allclose(res.a, a, rtol=1e-9)
    np.testing.assert_allclose(res.b, a, rtol=1e-9)
    np.testing.assert_allclose(res.approach, a**2 / r_j, rtol=1e-9)
    np.testing.assert_allclose(res.p_max, 3 * load / (2 * np.pi * a**2), rtol=1e-9)
    k = point_contact_stiffness(r / 2, r / 2, e_eff)
    np.testing.assert_allclose(k * res.approach**1.5, load, rtol=1e-9)


@pytest.mark.parametrize("ratio", [1.5, 4.0, 10.0, 30.0])
def test_ellipticity_vs_hamrock_brewe(ratio):
    """Exact k, F, E agree with the Hamrock–Brewe fits (stated accuracy ~3 %)."""
    e_eff = effective_modulus(E_STEEL, NU, E_STEEL, NU)
    res = point_contact(1000.0, 0.005, 0.005 * ratio, e_eff)
    assert np.isclose(res.ellipticity, 1.0339 * ratio**0.636, rtol=0.03)
    assert np.isclose(res.first_kind, 1.5277 + 0.6023 * np.log(ratio), rtol=0.03)
    assert np.isclose(res.second_kind, 1.0003 + 0.5968 / ratio, rtol=0.03)


def test_ball_bearing_textbook_case():
    """Harris & Kotzalas example: 22.23 mm ball, d_m 125 mm, f_i=0.52, deep groove,
    inner contact; p_max ~ 2.0-2.1 GPa at Q = 4000 N (hand calculation with the
    curvature sums: sum rho = 0.1139 /mm, F(rho) = 0.9192 -> k ~ 8.5).
    Checked: p_max * 2 pi a b / 3 == Q (consistency) and ellipticity in 7..10."""
    d, dm, f = 22.23e-3, 125e-3, 0.52
    rx = 1 / (2 / d + 2 / (dm - d))
    ry = 1 / (2 / d - 1 / (f * d))
    e_eff = effective_modulus(E_STEEL, NU, E_STEEL, NU)
    res = point_contact(4000.0, rx, ry, e_eff)
    assert 7.0 < res.ellipticity < 10.0
    assert 1.9e9 < res.p_max < 2.3e9
    assert np.isclose(res.p_max * 2 * np.pi * res.a * res.b / 3, 4000.0, rtol=1e-12)


def test_swapped_axes():
    """rx > ry gives the same ellipse with a and b exchanged."""
    e_eff = 2.2e11
    r1 = point_contact(500.0, 0.004, 0.02, e_eff)
    r2 = point_contact(500.0, 0.02, 0.004, e_eff)
    assert np.isclose(r1.a, r2.b) and np.isclose(r1.b, r2.a) and np.isclose(r1.p_max, r2.p_max)


def test_line_contact_half_width_and_palmgren():
    """b = sqrt(8 W R/(pi L E')) (Johnson eq. 4.43 in Hamrock's E'); Palmgren:
    delta[mm] = 3.84e-5 Q^0.9 / L^0.8 for steel (Harris & Kotzalas eq. 6.74)."""
    e_eff = effective_modulus(E_STEEL, NU, E_STEEL, NU)
    q, length, r = 3513.0, 10e-3, 2e-3
    res = line_contact(q, length, r, e_eff)
    assert np.isclose(res.half_width, np.sqrt(8 * q * r / (np.pi * length * e_eff)), rtol=1e-12)
    assert np.isclose(res.p_max, 2 * q / (np.pi * res.half_width * length), rtol=1e-12)
    assert np.isclose(res.approach * 1e3, 3.84e-5 * q**0.9 / 10.0**0.8, rtol=1e-9)
    k = line_contact_stiffness(length, e_eff)
    assert np.isclose(k * res.approach ** (10 / 9), q, rtol=1e-9)


def test_series_stiffness():
    """Equal springs in series: delta doubles, so K_series = K / 2^1.5."""
    assert np.isclose(series_stiffness(1e10, 1e10), 1e10 / 2**1.5)


@pytest.mark.parametrize("bad", [-1.0, float("nan")])
def test_bad_input(bad):
    with pytest.raises(InputError, match="load"):
        point_contact(bad, 0.01, 0.02, 2e11)
    with pytest.raises(InputError, match="rx"):
        point_contact(1.0, bad, 0.02, 2e11)
