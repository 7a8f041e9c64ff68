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
    """+dr_rp: first contact after beta0 = dr / max(l_i) ~ dr / r'_c (1 %) to first
    order; the exact beta0 (found on the exact gaps) differs from the first-order
    value dr / max(l_i) by the second-order term, relative O(beta0) ~ 1e-4 (2e-4)."""
    dr = 5e-6
    res = pin_load_distribution(1.0, Z, R, RP, A, B, E_EFF, d_pin_radius=dr, crank_angle=0.1)
    assert np.isclose(res.backlash_rotation, dr / (A * (Z - 1)), rtol=1e-2)
    assert np.isclose(res.backlash_rotation, dr / res.arms.max(), rtol=2e-4)
    assert np.min(res.clearance[res.arms > 0]) == pytest.approx(0.0, abs=1e-15)


def _polyline_gap(points, d_pin_radius, d_rotation):
    """Independent signed gap [m] of nominal pins to the modified profile: the
    distance of each pin centre (disc frame) to the pin-centre curve sampled at
    2e6 points (point-to-segment distance, chord error h^2 kappa / 8 < 1e-11 m),
    signed negative inside the curve, plus dr_rp (pin_gap's closed form gap = s + dr)."""
    from flexrv.geometry.cycloid import center_curve

    c, s = np.cos(-d_rotation), np.sin(-d_rotation)
    pts = np.stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1]], -1)
    curve = center_curve(np.linspace(0.0, 2 * np.pi, 2_000_001), Z, R, A)[0]
    out = []
    for p in pts:
        j = int(np.argmin(np.sum((curve - p) ** 2, axis=1)))
        best = np.inf
        for s0, s1 in ((curve[j - 1], curve[j]), (curve[j], curve[j + 1])):
            v = s1 - s0
            t = np.clip(np.dot(p - s0, v) / np.dot(v, v), 0.0, 1.0)
            best = min(best, float(np.linalg.norm(p - s0 - t * v)))
        out.append(-best if np.linalg.norm(p) < np.linalg.norm(curve[j]) else best)
    return np.array(out) + d_pin_radius


@pytest.mark.parametrize("d_rot", [0.0, -0.1 * np.pi / 180])
def test_clearance_exact_at_no_load_pose(d_rot):
    """Issue 17 (3): the initial clearances are the exact gaps at the no-load pose
    (disc turned by beta0 to its first contact), checked against an independent
    dense-polyline distance to the pin-centre curve at that pose to 1e-10 m. The
    former first-order value gap(0) - l_i(0) beta0 is off by up to 0.27 um at the
    tip pins for the plain +5 um equidistant modification (measured: 0.09 um at
    chi = 0, 0.22 um at chi = 0.05) and by several um under a rotation modification."""
    from flexrv.geometry.cycloid import nominal_disc_pose, pin_positions, to_disc_frame

    chi, dr = 0.05, 5e-6
    res = pin_load_distribution(206.0, Z, R, RP, A, B, E_EFF, d_pin_radius=dr, d_rotation=d_rot, crank_angle=chi)
    center, rot = nominal_disc_pose(Z, A, chi)
    beta0 = dr / res.arms.max() - d_rot  # first-order estimate: only to pick the pose below
    exact_beta0 = res.backlash_rotation
    assert exact_beta0 == pytest.approx(beta0, rel=1e-3)
    pts = to_disc_frame(pin_positions(Z, R), center, rot + exact_beta0)
    ref = _polyline_gap(pts, dr, d_rot)
    assert np.max(np.abs(res.clearance - ref)) < 1e-10


def test_rotation_modification_is_a_rigid_turn():
    """A pure rotation modification d turns the whole profile rigidly, so the exact
    method gives the same pin forces as without it (to 1e-6 relative: the Newton
    tolerance of the gaps, 1e-14 m scale, against approaches of ~1e-6 m) and a
    no-load rotation smaller by exactly d. The former linear clearances broke this
    invariance: -5 % to -6 % on the max pin force of rv40e at d = -0.1 deg (739.9
    and 743.0 N instead of 701.7 and 696.3 N at chi = 0 and 0.05), +17 % to +20 %
    for rv221 at d = +-0.1 deg."""
    chi, dr, t = 0.05, 5e-6, 206.0
    ref = pin_load_distribution(t, Z, R, RP, A, B, E_EFF, d_pin_radius=dr, crank_angle=chi)
    for d in (-0.1 * np.pi / 180, 0.02 * np.pi / 180, 0.1 * np.pi / 180):
        res = pin_load_distribution(t, Z, R, RP, A, B, E_EFF, d_pin_radius=dr, d_rotation=d, crank_angle=chi)
        np.testing.assert_allclose(res.forces, ref.forces, rtol=1e-6, atol=1e-6 * ref.max_force)
        assert res.rotation == pytest.approx(ref.rotation - d, abs=1e-12)
        assert res.n_contact == ref.n_contact


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
