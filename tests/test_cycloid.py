"""Cycloid-disc geometry: exact pin gap, curvature, moment arms, pin stiffness.

References: Litvin & Fuentes, Gear Geometry and Applied Theory (2004) ch. 19
(conjugate action of the pin-centre epitrochoid); :cite:`seed000` (moment arm l_i,
k_ni, k34); :cite:`seed004` (profile curvature radius, K_cj).
"""

import numpy as np
import pytest

from flexrv.errors import InputError
from flexrv.geometry.cycloid import (
    center_curve_curvature,
    k34,
    moment_arm,
    nominal_disc_pose,
    pin_gap,
    pin_positions,
    pin_stiffness_seed000,
    pin_stiffness_seed004,
    profile_curvature_radius,
    profile_points,
    seed004_curvature_radius,
    to_disc_frame,
)

Z, R, RP, A = 40, 0.064, 0.003, 0.0013  # RV-40E second stage (:cite:`seed002` Table 1)


def _pins(chi, z=Z, radius=R, ecc=A):
    centre, rot = nominal_disc_pose(z, ecc, chi)
    return to_disc_frame(pin_positions(z, radius), centre, rot)


def _brute_distance(points, mods, n=400_001):
    """Distance from points to the modified profile by dense sampling of
    profile_points (independent of pin_gap's offset/Newton method) followed by a
    vectorised golden-section refinement around the best sample."""
    phi = np.linspace(0.0, 2 * np.pi, n)
    prof = profile_points(phi, Z, R, RP, A, **mods)
    best = np.empty(len(points))
    for i, p in enumerate(points):
        best[i] = phi[np.argmin(np.sum((prof - p) ** 2, axis=1))]
    lo, hi = best - 2 * np.pi / n * 2, best + 2 * np.pi / n * 2
    g = (np.sqrt(5) - 1) / 2

    def dist(t):
        return np.linalg.norm(profile_points(t, Z, R, RP, A, **mods) - points, axis=1)

    for _ in range(80):
        c, d = hi - g * (hi - lo), lo + g * (hi - lo)
        left = dist(c) < dist(d)
        hi = np.where(left, d, hi)
        lo = np.where(left, lo, c)
    return dist(0.5 * (lo + hi))


def test_gap_matches_brute_force_sampling():
    """Signed gap vs brute-force distance to the sampled modified profile:
    |gap + r_rp| = distance to profile, tolerance 1e-9 m."""
    rng = np.random.default_rng(7)
    ang = rng.uniform(0, 2 * np.pi, 60)
    rad = rng.uniform(R - 0.8 * A, R + 1.5 * A, 60)
    pts = rad[:, None] * np.stack([np.sin(ang), np.cos(ang)], axis=1)
    mods = dict(d_radius=2e-5, d_pin_radius=8e-6, d_rotation=2e-4)
    gap, normal, phi = pin_gap(pts, Z, R, RP, A, **mods)
    ref = _brute_distance(pts, mods)
    assert np.max(np.abs((gap + RP) - ref)) < 1e-9
    assert np.allclose(np.linalg.norm(normal, axis=1), 1.0)
    # warm start from phi reproduces the result
    gap2, _, phi2 = pin_gap(pts, Z, R, RP, A, phi0=phi, **mods)
    assert np.max(np.abs(gap2 - gap)) < 1e-13


@pytest.mark.parametrize("chi", [0.0, 0.37, 2.9])
def test_conjugate_action_gap_zero(chi):
    """Ideal pins at the nominal (conjugate) pose touch the unmodified profile:
    gap = 0 for all 40 pins (to round-off, 1e-12 m)."""
    gap, _, _ = pin_gap(_pins(chi), Z, R, RP, A)
    assert np.max(np.abs(gap)) < 1e-12


def test_equidistant_modification_clearance_pattern():
    """+dr_rp: normal gap = dr_rp at every pin; after turning the disc by
    beta = dr_rp / r'_c the remaining clearance is dr_rp (1 - |l_i| / r'_c)
    (classic initial-clearance pattern, e.g. Li Lixing, Cycloid drive design).
    Checked on the working flank (second-order remainder < 2e-7 m, scaling as beta^2)."""
    dr = 10e-6
    chi = 0.4
    pins = _pins(chi)
    gap, normal, _ = pin_gap(pins, Z, R, RP, A, d_pin_radius=dr)
    assert np.allclose(gap, dr, atol=1e-12, rtol=0)
    rc = A * (Z - 1)
    beta = dr / rc
    # turning the disc by +beta (ccw) moves the pins by -beta in the disc frame
    c, s = np.cos(-beta), np.sin(-beta)
    turned = pins @ np.array([[c, s], [-s, c]])
    gap_t, _, _ = pin_gap(turned, Z, R, RP, A, d_pin_radius=dr)
    arms = pins[:, 0] * normal[:, 1] - pins[:, 1] * normal[:, 0]
    expected = dr - beta * arms
    # the pattern is first order in beta: the second-order term (R beta)^2 / (2 rho) is
    # <~1.3e-7 m on the working flank and ~1e-6 m near the tooth root, where the
    # pin-centre curve's curvature radius is only ~70 um (but those gaps are wide open).
    work = arms > 0.5 * rc
    assert work.sum() >= 10
    assert np.max(np.abs(gap_t - expected)[work]) < 2e-7
    # halving beta divides the deviation by ~4 (second-order remainder)
    c2, s2 = np.cos(-beta / 2), np.sin(-beta / 2)
    gap_h, _, _ = pin_gap(pins @ np.array([[c2, s2], [-s2, c2]]), Z, R, RP, A, d_pin_radius=dr)
    ratio = np.abs(gap_t - expected)[work] / np.abs(gap_h - (dr - beta / 2 * arms))[work]
    assert np.all((ratio > 3.5) & (ratio < 4.5))
    assert gap_t.min() > -1e-9  # only the pin with l = r'_c closes
    closing = np.argmin(gap_t)
    assert abs(arms[closing] - rc) / rc < 0.02


def test_signed_arm_equals_seed000_formula():
    """(P x n)_z of the exact normal = -l_i of :cite:`seed000` with phi_i = psi_i - chi
    (pin angle from the eccentric direction), to 1e-12 m."""
    chi = 1.1
    pins = _pins(chi)
    _, n, _ = pin_gap(pins, Z, R, RP, A)
    arms = pins[:, 0] * n[:, 1] - pins[:, 1] * n[:, 0]
    psi = 2 * np.pi * np.arange(Z) / Z
    assert np.max(np.abs(arms + moment_arm(psi - chi, Z, R, A))) < 1e-12
    assert np.isclose(np.max(moment_arm(np.linspace(0, np.pi, 100001), Z, R, A)), A * (Z - 1), rtol=1e-8)


def test_curvature_radius_matches_seed004():
    """Actual profile curvature radius = -rho_i(:cite:`seed004`) at theta = z_c phi
    (unmodified profile), relative 1e-9; and the curvature from a finite-difference
    circle fit of profile_points agrees (1e-4 relative) on the convex flank."""
    phi = np.linspace(0.003, 2 * np.pi / (Z - 1) - 0.003, 57)
    rho = profile_curvature_radius(phi, Z, R, RP, A)
    seed = seed004_curvature_radius((Z - 1) * phi, Z, R, RP, A)
    assert np.allclose(rho, -seed, rtol=1e-9)
    # independent: curvature of the sampled profile (3-point circle)
    h = 1e-5
    p0, p1, p2 = (profile_points(phi + d, Z, R, RP, A) for d in (-h, 0.0, h))
    a_, b_, c_ = (np.linalg.norm(p1 - p0, axis=1), np.linalg.norm(p2 - p1, axis=1), np.linalg.norm(p2 - p0, axis=1))
    cross = np.abs((p1 - p0)[:, 0] * (p2 - p0)[:, 1] - (p1 - p0)[:, 1] * (p2 - p0)[:, 0])
    circ = a_ * b_ * c_ / (2 * cross)
    convex = rho > 0
    assert np.allclose(circ[convex], rho[convex], rtol=1e-4)


def test_pin_stiffness_models():
    """:cite:`seed000` k_ni = pi b E'/4 (curvature-free); :cite:`seed004` K_cj equals it on the
    convex flank and is smaller (but >= 0) on the concave part."""
    e_eff = 219e9 / (1 - 0.3**2)
    b = 0.012
    k0 = pin_stiffness_seed000(b, e_eff)
    assert np.isclose(k0, np.pi * b * 219e9 / (4 * (1 - 0.3**2)))
    th = np.linspace(0.05, np.pi, 200)
    rho = seed004_curvature_radius(th, Z, R, RP, A)
    k4 = pin_stiffness_seed004(rho, RP, b, e_eff)
    assert np.allclose(k4[rho < 0], k0)
    assert np.all(k4[rho > 0] < k0)
    arms = moment_arm(th, Z, R, A)
    assert np.isclose(k34(k0, arms), np.sum(k0 * arms**2))
    assert k34(k0, arms, engaged=arms > 0.04) < k34(k0, arms)


def test_vectorised_over_crank_angles():
    """Several poses at once (crank angles (m,) -> pins (m, z, 2)) give the same gaps
    as one pose at a time."""
    chis = np.array([0.1, 0.7, 2.0])
    centre, rot = nominal_disc_pose(Z, A, chis)
    pins = to_disc_frame(pin_positions(Z, R)[None], centre[:, None, :], rot[:, None])
    gap, normal, phi = pin_gap(pins, Z, R, RP, A, d_radius=1e-5)
    assert gap.shape == (3, Z) and normal.shape == (3, Z, 2)
    for k, chi in enumerate(chis):
        g1, _, _ = pin_gap(_pins(chi), Z, R, RP, A, d_radius=1e-5)
        assert np.allclose(gap[k], g1, rtol=0, atol=1e-15)


def test_pin_gap_bad_input():
    with pytest.raises(InputError):
        pin_gap(np.array([[np.nan, 0.06]]), Z, R, RP, A)
    with pytest.raises(InputError):
        pin_gap(np.zeros((3, 3)), Z, R, RP, A)


def test_curvature_sign_convention():
    """Tooth tip (|C| max, phi = lobe/2) is convex, root (phi = 0) concave."""
    lobe = 2 * np.pi / (Z - 1)
    assert center_curve_curvature(lobe / 2, Z, R, A) > 0
    assert center_curve_curvature(0.0, Z, R, A) < 0
