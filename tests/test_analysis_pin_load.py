"""Pin load distribution (initial-clearance method) against closed forms."""

import numpy as np
import pytest

from flexrv.analysis.pin_load import pin_load_distribution, reducer_pin_loads
from flexrv.design import load
from flexrv.errors import InputError

Z, R, RP, A, B = 40, 0.064, 0.003, 0.0013, 0.012
E_EFF = 219e9 / (1 - 0.3**2)


@pytest.mark.parametrize("law", ["palmgren", "linear"])
@pytest.mark.parametrize("torque", [206.0, -150.0])
def test_torque_balance(law, torque):
    """sum F_i l_i = T_disc to 1e-6 relative; forces >= 0 only where the approach > 0."""
    res = pin_load_distribution(torque, Z, R, RP, A, B, E_EFF, d_pin_radius=5e-6, crank_angle=0.3, law=law)
    assert abs(np.sum(res.forces * res.arms) - torque) < 1e-6 * abs(torque)
    assert np.all(res.forces >= 0)
    assert np.all((res.forces > 0) == (res.approach > 0))
    assert np.sign(res.rotation) == np.sign(torque)


def test_ideal_profile_linear_closed_form():
    """Zero modification, linear law: F_i = k l_i beta on all pins with l_i > 0
    (about half the pins, z_rp/2) and F_max = 4 T / (z_rp z_c a) (classic result,
    since sum l_i^2 = z_rp r'_c^2 / 4 from int_0^pi sin^2/(1+K^2-2K cos) = pi/2);
    relative 1e-3 (discrete sum vs integral)."""
    t = 206.0
    res = pin_load_distribution(t, Z, R, RP, A, B, E_EFF, crank_angle=0.05, law="linear")
    assert res.n_contact == Z // 2
    assert np.isclose(res.max_force, 4 * t / (Z * (Z - 1) * A), rtol=1e-3)
    k = np.pi * B * E_EFF / 4
    pos = res.arms > 0
    # rtol 1e-7: the conjugate gaps are round-off (~1e-17 m) against approaches of ~1e-8 m
    assert np.allclose(res.forces[pos], k * res.arms[pos] * t / (k * np.sum(res.arms[pos] ** 2)), rtol=1e-7)
    assert np.isclose(res.torsional_stiffness, k * np.sum(res.arms[pos] ** 2), rtol=1e-9)


def test_ideal_profile_palmgren_half_pins():
    """Zero modification with the Palmgren law: still every pin with l_i > 0 carries load."""
    res = pin_load_distribution(206.0, Z, R, RP, A, B, E_EFF, crank_angle=0.05)
    assert res.n_contact == Z // 2


def test_lost_motion_equidistant():
    """+dr_rp: first contact after beta0 = dr / max(l_i) ~ dr / r'_c (1 %)."""
    dr = 5e-6
    res = pin_load_distribution(1.0, Z, R, RP, A, B, E_EFF, d_pin_radius=dr, crank_angle=0.1)
    assert np.isclose(res.backlash_rotation, dr / (A * (Z - 1)), rtol=1e-2)
    assert np.isclose(res.backlash_rotation, dr / res.arms.max(), rtol=1e-6)


def test_monotone_in_torque():
    """More torque -> (weakly) more pins, higher max force and (Palmgren, e > 1)
    higher tangent stiffness."""
    torques = [5.0, 20.0, 60.0, 150.0, 300.0, 600.0]
    res = [pin_load_distribution(t, Z, R, RP, A, B, E_EFF, d_pin_radius=5e-6) for t in torques]
    n = [r.n_contact for r in res]
    assert n == sorted(n) and n[-1] > n[0]
    assert np.all(np.diff([r.max_force for r in res]) > 0)
    assert np.all(np.diff([r.torsional_stiffness for r in res]) > 0)


def test_more_modification_fewer_pins():
    """At fixed torque a larger equidistant modification engages fewer pins."""
    n = [pin_load_distribution(206.0, Z, R, RP, A, B, E_EFF, d_pin_radius=d).n_contact for d in (0, 2e-6, 5e-6, 2e-5)]
    assert n == sorted(n, reverse=True) and n[0] > n[-1]


def test_reducer_wrapper_and_errors():
    r = load("rv40e")
    res = reducer_pin_loads(r, 412.0)
    assert np.isclose(res.torque, 412.0 / r.second_stage.n_discs)
    assert 1 <= res.n_contact <= r.second_stage.pin_count // 2
    with pytest.raises(InputError):
        pin_load_distribution(float("nan"), Z, R, RP, A, B, E_EFF)
    with pytest.raises(InputError):
        pin_load_distribution(1.0, Z, R, RP, A, B, E_EFF, law="foo")
