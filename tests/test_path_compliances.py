"""The torque-path compliances no model contains yet (:mod:`flexrv.analysis.path_compliances`)
against independent calculations of their closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexrv.analysis import path_compliances as pc
from flexrv.design import load, override


def test_crank_torsion_energy_length_and_ratio():
    """c_crank against a numerical integral of (M(x)/M_c)^2 / (G J(x)) over the stepped shaft
    (gear seat: torque fed in linearly; support journal: whole; eccentrics: half taken out on
    each, linearly), 20000 midpoints per segment (rel 1e-6); the output ratio against the
    kinematics (crank speed relative to the carrier over the carrier speed = z_rp,
    flexrv.geometry.kinematics.member_speeds, rel 1e-12)."""
    from flexrv.geometry.kinematics import member_speeds
    from flexrv.units import M_PER_MM

    r = load("rv40e")
    cs = r.crankshaft
    g = pc.shear_modulus(r.material("crankshaft"))
    segs = [
        (cs.gear_seat_length_mm, cs.gear_seat_diameter_mm, lambda u: u),
        (cs.support_journal_length_mm, cs.support_journal_diameter_mm, lambda u: np.ones_like(u)),
        (cs.eccentric_journal_length_mm, cs.eccentric_journal_diameter_mm, lambda u: 1.0 - 0.5 * u),
        (cs.eccentric_journal_length_mm, cs.eccentric_journal_diameter_mm, lambda u: 0.5 - 0.5 * u),
    ]
    total = 0.0
    n = 20000
    for length, d, m in segs:
        u = (np.arange(n) + 0.5) / n
        j = math.pi * (d * M_PER_MM) ** 4 / 32.0
        total += np.sum(m(u) ** 2) / n * length * M_PER_MM / (g * j)
    assert pc.crank_torsion_compliance(r) == pytest.approx(total, rel=1e-6)
    fs, ss = r.first_stage, r.second_stage
    sp = member_speeds(1.0, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    lam = abs(sp.crank_relative / sp.carrier)
    assert lam == pytest.approx(ss.pin_count, rel=1e-12)
    assert pc.crank_torsion(r) == pytest.approx(total / (fs.n_planets * lam**2), rel=1e-6)


def test_planet_spline_closed_form():
    """k = f z c' b r_m^2 per crank, referred to the output by 1 / (N z_rp^2), recomputed from
    the preset's numbers (rel 1e-12)."""
    r = load("rv40e")
    pe, cs = r.path_estimates, r.crankshaft
    k = (
        pe.planet_spline_engaged_fraction
        * pe.planet_spline_teeth
        * pe.spline_tooth_stiffness_N_per_mm_um
        * 1e9
        * cs.gear_seat_length_mm
        * 1e-3
        * (0.5e-3 * cs.gear_seat_diameter_mm) ** 2
    )
    assert pc.planet_spline(r) == pytest.approx(1.0 / (k * r.first_stage.n_planets * r.second_stage.pin_count**2))


def test_ring_on_foundation_against_a_finite_difference_beam():
    """Deflection under a point load of a beam on a Winkler foundation, EI w'''' + k w = P delta,
    solved by central finite differences over +-12/beta (4001 nodes) against Hetenyi's
    P beta / (2 k) (rel 2e-3)."""
    r_in, r_out, b, e, phi = 14e-3, 16e-3, 7e-3, 2.1e11, 1.0
    c = pc.ring_on_foundation(r_in, r_out, b, e, phi)
    k = phi * e * b / (0.5 * (r_in + r_out))
    ei = e * b * (r_out - r_in) ** 3 / 12.0
    beta = (k / (4 * ei)) ** 0.25
    n = 4001
    x = np.linspace(-12 / beta, 12 / beta, n)
    h = x[1] - x[0]
    a = np.zeros((n, n))
    stencil = np.array([1.0, -4.0, 6.0, -4.0, 1.0]) * ei / h**4
    for i in range(n):
        for off, v in zip(range(-2, 3), stencil):
            j = i + off
            if 0 <= j < n:
                a[i, j] += v
        a[i, i] += k
    f = np.zeros(n)
    f[n // 2] = 1.0 / h  # unit point load
    w = np.linalg.solve(a, f)
    assert c == pytest.approx(w[n // 2], rel=2e-3)


def test_joint_shear_compliance_against_a_beam_element():
    """Euler-Bernoulli beam element clamped at one end, its other end sheared by V between
    supports that do not turn, through a rotational spring 1/c_phi: [12 EI/L^3, -6 EI/L^2;
    -6 EI/L^2, 4 EI/L + 1/c_phi] [w, theta] = [V, 0]; the joint's added compliance equals
    w/V - L^3/(12 EI) (rel 1e-12) for c_phi over three decades."""
    length, ei = 0.026, 500.0
    for c_phi in (1e-6, 3e-5, 1e-3):
        kk = np.array([[12 * ei / length**3, -6 * ei / length**2], [-6 * ei / length**2, 4 * ei / length + 1 / c_phi]])
        w = np.linalg.solve(kk, [1.0, 0.0])[0]
        assert pc.joint_shear_compliance(length, ei, c_phi) == pytest.approx(w - length**3 / (12 * ei), rel=1e-12)


def test_missing_compliances_of_the_presets_and_without_estimates():
    """rv40e and rv221 carry all four elements; each lies in (0, 0.05) arcsec/(N m) (the
    range of hand estimates from the presets' dimensions: 0.004-0.04); without [path_estimates] only the
    crank torsion (geometry alone) remains."""
    from flexrv.units import ARCSEC_PER_RAD

    for name in ("rv40e", "rv221"):
        m = pc.missing_compliances(load(name))
        assert set(m) == {"crank_torsion", "planet_spline", "support_bearing_rings", "carrier_joints"}
        assert all(0.0 < v * ARCSEC_PER_RAD < 0.05 for v in m.values())
    r = load("rv40e")
    bare = r.model_copy(update={"path_estimates": None})
    assert set(pc.missing_compliances(bare)) == {"crank_torsion"}


def test_every_estimate_of_path_estimates_has_provenance_and_a_range():
    """Each [path_estimates] field of the presets has a provenance note and a plausible range
    with a reason that contains the preset's value."""
    for name in ("rv40e", "rv221"):
        r = load(name)
        for field in type(r.path_estimates).model_fields:
            path = f"path_estimates.{field}"
            assert path in r.provenance, (name, path)
            rng = r.ranges[path]
            assert rng.low <= getattr(r.path_estimates, field) <= rng.high and rng.reason


def test_ranges_are_validated():
    """A range must name a numeric field and have low < high (one message naming it)."""
    from flexrv.errors import ConfigError

    with pytest.raises(ConfigError, match="ranges"):
        override("rv40e", {"ranges": {"first_stage.module_mm": {"low": 2.0, "high": 1.0, "reason": "bad"}}})
    with pytest.raises(ConfigError, match="numeric field"):
        override("rv40e", {"ranges": {"first_stage.nonsense": {"low": 1.0, "high": 2.0, "reason": "bad"}}})
