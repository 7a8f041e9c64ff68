"""The torque-path compliances of :mod:`flexrv.analysis.path_compliances` against independent
calculations of their closed forms, and the models' response to them (gear stage, support
points) against the closed forms."""

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
    kinematics: the crank's speed relative to the carrier over the carrier speed is z_rp
    (flexrv.geometry.kinematics.member_speeds, rel 1e-12), and the crank's turn relative to its
    planet per output turn, input held, i_c = z_rp + z_s / z_p, equals the virtual-work ratio
    i r_bs / r_bp (i the total ratio, flexrv.geometry.kinematics.total_ratio; rel 1e-12)."""
    from flexrv.geometry.kinematics import member_speeds, total_ratio
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
    i_c = (
        float(total_ratio(fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)) * fs.sun_teeth / fs.planet_teeth
    )
    assert pc.crank_ratio(r) == pytest.approx(i_c, rel=1e-12)
    assert pc.crank_torsion(r) == pytest.approx(total / (fs.n_planets * i_c**2), rel=1e-6)


def test_planet_spline_closed_form():
    """k = f z c' b r_m^2 per crank, referred to the output by 1 / (N i_c^2), recomputed from
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
    i_c = r.second_stage.pin_count + r.first_stage.sun_teeth / r.first_stage.planet_teeth
    assert pc.planet_spline(r) == pytest.approx(1.0 / (k * r.first_stage.n_planets * i_c**2), rel=1e-12)


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


def test_output_compliances_of_the_presets_and_without_estimates():
    """rv40e and rv221 carry all four elements; each lies in (0, 0.05) arcsec/(N m) (the
    range of hand estimates from the presets' dimensions: 0.004-0.04); without [path_estimates] only the
    crank torsion (geometry alone) remains, and with ``crankshaft.torsion_model = "rigid"`` not it."""
    from flexrv.units import ARCSEC_PER_RAD

    for name in ("rv40e", "rv221"):
        m = pc.output_compliances(load(name))
        assert set(m) == {"crank_torsion", "planet_spline", "support_bearing_rings", "carrier_joints"}
        assert all(0.0 < v * ARCSEC_PER_RAD < 0.05 for v in m.values())
    r = load("rv40e")
    bare = r.model_copy(update={"path_estimates": None})
    assert set(pc.output_compliances(bare)) == {"crank_torsion"}
    assert pc.output_compliances(override(bare, {"crankshaft.torsion_model": "rigid"})) == {}


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


def test_series_mesh_law_reduces_to_the_mesh_law():
    """The gear stage's stiffness law: with s = 0 the involute mesh's law itself (bit-identical)
    and with s > 0 its series combination 1 / (1/k + s) (rel 1e-14), over two mesh periods."""
    from flexrv.analysis.mesh_stiffness import mesh_stiffness_ramped
    from flexrv.model.gear_stage import series_mesh_stiffness

    ks, eps, ramp, s = 4.0e8, 1.6, 0.05, 2.5e-9
    for xi in np.linspace(0.0, 2.0, 41):
        k = mesh_stiffness_ramped(xi, ks, eps, ramp)
        assert series_mesh_stiffness(xi, ks, eps, ramp, 0.0) == k
        assert series_mesh_stiffness(xi, ks, eps, ramp, s) == pytest.approx(1.0 / (1.0 / k + s), rel=1e-14)


def test_gear_stage_carries_the_planet_torsion():
    """rv40e's gear element: the law's series compliance is s = (c_crank + c_spline) r_bp^2 with
    the closed forms per crank (rel 1e-12); the flexible-crank model keeps only the spline (its
    coupling is the crank's torsion)."""
    from flexrv.model.bodies import with_bodies
    from flexrv.model.drive import drive_parameters
    from flexrv.model.gear_stage import GearMeshes

    r = with_bodies(load("rv40e"), [])
    g = GearMeshes.from_design(r, drive_parameters(r), lambda t: 0.0, lambda t: 0.0)
    p = g.params
    c_t = pc.crank_torsion_compliance(r) + pc.planet_spline_compliance(r)
    assert g.law.s_t == pytest.approx(c_t * p.base_radius_planet**2, rel=1e-12)
    g.set_planet_torsion(p.planet_spline_compliance)
    assert g.law.s_t == pytest.approx(pc.planet_spline_compliance(r) * p.base_radius_planet**2, rel=1e-12)
    with pytest.raises(ValueError, match="planet torsion"):
        g.set_planet_torsion(-1.0)


def test_carrier_joints_rank_one_gives_c_T_for_any_torque_carrying_forces():
    """The joints' part c_T g g^T of the support-point compliance: under the pure torque's forces
    f = g T / |g|^2, and under random forces of the same torque, the support points turn
    rigidly by c_T T (displacement c_T T g; rel 1e-12); the rings' diagonal part gives
    c_r / (2 N a_w^2) at the output for equal tangential forces on the crank circle (rel 1e-12)."""
    r = load("rv40e")
    n, a_w = r.first_stage.n_planets, r.first_stage.center_distance
    ang = 2 * np.pi * np.arange(n) / n
    bores = a_w * np.column_stack([np.cos(ang), np.sin(ang)])
    mc = pc.model_compliances(r, bores)
    g = pc.torque_map(bores)
    c_t, torque = pc.carrier_joints(r), 412.0
    cj = mc.support_parts["carrier_joints"]
    for f in (g * torque / (g @ g), np.random.default_rng(3).normal(size=2 * n) * 1e3):
        t = g @ f
        np.testing.assert_allclose(cj @ f, c_t * t * g, rtol=1e-12)
        assert (g @ (cj @ f)) / (g @ g) == pytest.approx(c_t * t, rel=1e-12)
    f = g * torque / (g @ g)
    rot = (g @ (mc.support_parts["support_bearing_rings"] @ f)) / (g @ g)
    assert rot / torque == pytest.approx(pc.support_bearing_rings(r), rel=1e-12)
    assert mc.support_compliance(np.zeros((0, 0))) == pytest.approx(cj + mc.support_parts["support_bearing_rings"])


def test_quasi_static_model_responds_with_the_closed_forms():
    """rv40e with rigid FE bodies at the rated torque, input locked: the quasi-static tangent
    compliance with the four elements less the one without them (``crankshaft.torsion_model =
    "rigid"``, no [path_estimates]) equals the sum of the closed forms within 1 % (measured
    -0.03 %); the strain-energy shares of the support-bearing rings and the carrier joints equal
    their closed forms within 1 % (measured 0.01 %, 1e-5 %), and the gear stage's share exceeds
    crank torsion + planet spline by the mesh's own part only (< 0.001 arcsec/(N m), measured
    0.0005). The stiff remainder (needles, pins, supports) is unchanged within 0.5 %."""
    from flexrv.model.bodies import with_bodies
    from flexrv.model.quasi_static import StaticModel, ramp_to
    from flexrv.units import ARCSEC_PER_RAD

    def solve(r):
        sm = StaticModel(r)
        sm.torque = 0.0
        q = ramp_to(sm, 0.0, sm.kinematic_pose(0.0), r.operating.rated_torque_Nm, steps=8)
        c = 1.0 / sm.tangent_rigidity(0.0, q)
        return c, {k: v * c for k, v in sm.compliance_budget(0.0, q).items()}

    r = with_bodies(load("rv40e"), [])
    bare = override(r, {"crankshaft.torsion_model": "rigid"}).model_copy(update={"path_estimates": None})
    c1, b1 = solve(r)
    c0, b0 = solve(bare)
    closed = pc.output_compliances(r)
    assert c1 - c0 == pytest.approx(sum(closed.values()), rel=0.01)
    for k in ("support_bearing_rings", "carrier_joints"):
        assert b1[k] == pytest.approx(closed[k], rel=0.01), k
    mesh = b1["gear_stage"] - closed["crank_torsion"] - closed["planet_spline"]
    assert 0.0 < mesh * ARCSEC_PER_RAD < 1e-3
    for k in ("needle_bearings", "pins", "crank_supports"):
        assert b1[k] == pytest.approx(b0[k], rel=0.005), k


def test_gear_stage_jacobian_with_the_planet_torsion():
    """The gear element's dF/dq with the planet torsion in series (rv40e, s = c_t r_bp^2 > 0):
    central differences (h = 1e-10 m on the crank circle) of its own forces within 1e-6 of the
    largest entry at the quasi-static equilibrium at the rated torque, at rest and with random
    speeds (the damper's dependence on q); the stiffness slope of the series law enters through
    its central difference."""
    from flexrv.model.assembled import group_index
    from flexrv.model.bodies import with_bodies
    from flexrv.model.quasi_static import StaticModel, ramp_to

    r = with_bodies(load("rv40e"), [])
    sm = StaticModel(r)
    th = 0.37
    sm.torque = 0.0
    q = ramp_to(sm, th, sm.kinematic_pose(th), r.operating.rated_torque_Nm, steps=8)
    m = sm.model
    g = next(x for x in m.groups if x.name == "gear_stage")
    assert g.law.s_t > 0.0
    ix = np.arange(m.n)[group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])]
    rng = np.random.default_rng(5)
    for v_scale in (0.0, 1e-3):
        v = rng.normal(scale=v_scale, size=m.n) / sm.arm
        g.new_step()
        jq, _ = g.jacobian(th, q[ix], v[ix])
        nq = np.zeros_like(jq)
        for i in range(len(ix)):
            e = np.zeros(len(ix))
            e[i] = 1e-10 / sm.arm[ix[i]]
            g.new_step()
            fp, _ = g.evaluate(th, q[ix] + e, v[ix])
            g.new_step()
            fm, _ = g.evaluate(th, q[ix] - e, v[ix])
            nq[:, i] = (fp - fm) / (2 * e[i])
        scale = np.abs(nq).max()
        assert scale > 1e6
        assert np.abs(jq - nq).max() <= 1e-6 * scale
