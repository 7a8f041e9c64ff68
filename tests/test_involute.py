"""Involute first stage: contact ratio and ISO 6336-1 mesh stiffness vs hand calculations."""

import math

import numpy as np
import pytest

from flexrv.analysis.mesh_stiffness import (
    basic_rack_factor,
    involute_stage,
    mesh_damping,
    mesh_stiffness_per_width,
    min_flexibility,
    single_tooth_stiffness,
    time_varying_mesh_stiffness,
)
from flexrv.design import load
from flexrv.errors import InputError
from flexrv.geometry.involute import (
    contact_ratio,
    line_of_action,
    tip_radius,
    tooth_pair_count,
    working_center_distance,
)

A20 = math.radians(20.0)


def test_single_tooth_stiffness_hand_calc_shifted():
    """:cite:`seed001` pair z1 = 12, z2 = 44, x1 = 0.5, x2 = -0.5 (ISO 6336-1 method B), by hand:
    q' = 0.04723 + 0.15551/12 + 0.25791/44 - 0.00635*0.5 - 0.11654*0.5/12
         - 0.00193*(-0.5) - 0.24188*(-0.5)/44 + 0.00529*0.25 + 0.00182*0.25
       = 0.04723 + 0.0129592 + 0.0058616 - 0.003175 - 0.0048558 + 0.000965
         + 0.0027486 + 0.0013225 + 0.000455 = 0.0635111 mm um/N
    c'_th = 1/q' = 15.7453 N/(mm um); C_B = (1 + 0.5(1.2 - 1.25)) = 0.975;
    c' = 15.7453 * 0.8 * 1 * 0.975 = 12.2813 N/(mm um) = 1.22813e10 N/m^2 (rel. 1e-5)."""
    assert np.isclose(min_flexibility(12, 44, 0.5, -0.5), 0.0635111, rtol=1e-5)
    assert np.isclose(basic_rack_factor(A20), 0.975)
    assert np.isclose(single_tooth_stiffness(12, 44, 0.5, -0.5, A20), 12.2813e9, rtol=1e-5)


def test_single_tooth_stiffness_hand_calc_unshifted():
    """RV-40E pair z1 = 16, z2 = 32, x = 0: q' = 0.04723 + 0.15551/16 + 0.25791/32
    = 0.0650091 mm um/N; c' = 0.78/q' = 11.9983 N/(mm um) (rel. 1e-5)."""
    assert np.isclose(min_flexibility(16, 32, 0, 0), 0.0650091, rtol=1e-5)
    assert np.isclose(single_tooth_stiffness(16, 32, 0, 0, A20), 11.9983e9, rtol=1e-5)


def test_contact_ratio_hand_calc():
    """z 12/44, m 3, x +0.5/-0.5 (a_w = a = 84 mm): r_a1 = 22.5, r_b1 = 16.9145,
    r_a2 = 67.5, r_b2 = 62.0197 mm; g = sqrt(506.25 - 286.0992) + sqrt(4556.25 - 3846.4448)
    - 84 sin 20 = 14.83748 + 26.64217 - 28.72970 = 12.74995 mm;
    p_b = 3 pi cos 20 = 8.856394 mm; eps = 1.439633 (rel. 1e-5). Unshifted 16/32,
    m 1.5: eps = 1.58319."""
    m = 0.003
    assert np.isclose(working_center_distance(12, 44, m, A20, 0.5, -0.5), 0.084, rtol=1e-12)
    assert np.isclose(tip_radius(12, m, 0.5, -0.5, 44, A20), 0.0225)
    assert np.isclose(line_of_action(12, 44, m, A20, 0.5, -0.5), 12.74995e-3, rtol=1e-5)
    assert np.isclose(contact_ratio(12, 44, m, A20, 0.5, -0.5), 1.439633, rtol=1e-5)
    assert np.isclose(contact_ratio(16, 32, 0.0015, A20, 0, 0), 1.58319, rtol=1e-5)
    # positive sum shift: tip alteration k >= 0 shortens the tips
    assert tip_radius(16, 0.0015, 0.3, 0.2, 32, A20) <= tip_radius(16, 0.0015, 0.3)


def test_time_varying_stiffness_mean_and_zones():
    """Mean over a cycle = c_gamma b (ISO mean), zones of lengths eps - 1 and 2 - eps."""
    eps, ks = 1.4396, 2.0e8
    ph = (np.arange(200000) + 0.5) / 200000
    for ramp in (0.0, 0.1):
        k = time_varying_mesh_stiffness(ph, ks, eps, ramp)
        assert np.isclose(k.mean(), float(mesh_stiffness_per_width(ks, eps)), rtol=1e-6)
        assert np.isclose(k.max(), 1.75 * ks) and np.isclose(k.min(), ks)
    assert np.isclose(np.mean(tooth_pair_count(ph, eps) == 2), eps - 1, atol=1e-5)
    with pytest.raises(InputError):
        time_varying_mesh_stiffness(ph, ks, 2.1)
    with pytest.raises(InputError):
        time_varying_mesh_stiffness(ph, ks, eps, ramp=0.5)


def test_mesh_damping_reduces_to_two_masses():
    """For J_i = m_i r_i^2: c = 2 xi sqrt(k m1 m2/(m1 + m2)) (rel. 1e-12)."""
    k, m1, m2, r1, r2, xi = 2e8, 0.3, 1.5, 0.02, 0.06, 0.07
    c = mesh_damping(k, r1, r2, m1 * r1**2, m2 * r2**2, xi)
    assert np.isclose(c, 2 * xi * math.sqrt(k * m1 * m2 / (m1 + m2)), rtol=1e-12)


def test_involute_stage_of_presets():
    """k12 = c_gamma b and c_gamma = (0.75 eps + 0.25) c' for both presets."""
    for name in ("rv221", "rv40e"):
        r = load(name)
        st = involute_stage(r)
        assert np.isclose(st.k12, st.c_gamma * r.first_stage.face_width)
        assert np.isclose(st.c_gamma, (0.75 * st.eps_alpha + 0.25) * st.c_single)
        assert 1.2 < st.eps_alpha < 1.8 and st.c12 > 0
