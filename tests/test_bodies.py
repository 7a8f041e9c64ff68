"""Elastic carrier and cycloid-disc bodies in the models (issue 14): the FE
condensations (flexrv.fem.carrier, flexrv.fem.disc) condensed into the crank-support
kernel and around the pins' kernel. Numbers against independent solves: the
condensed forces against the uncondensed problem (the body's interface
displacements as explicit unknowns, solved by scipy's root finder), the condensed
tangents against central differences, the stiff-body limit against the rigid
models, and the quasi-static torsional compliance against the FE's g^T C g.

The FE matrices come from the cache (~/.cache/flexrv; cold: about a minute per
preset body)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import root

from flexrv.design import load
from flexrv.model.bodies import with_bodies
from flexrv.model.drive import drive_parameters


def _element_params(group, reducer):
    """The element's own typed parameters from the design (its ``parameters`` builder)."""
    return group.parameters(reducer, drive_parameters(reducer))


@pytest.fixture(scope="module")
def params():
    """The pins' parameters of rv40e with a rigid housing: the disc body on its own (the
    housing: tests/test_housing.py)."""
    from flexrv.model.pins import PinContacts

    return dataclasses.replace(_element_params(PinContacts, load("rv40e")), housing_compliance=0.0)


@pytest.fixture(scope="module")
def supports():
    """The crank supports' parameters of rv40e (the condensed FE carrier)."""
    from flexrv.model.cranks_discs import CrankSupports

    return _element_params(CrankSupports, load("rv40e"))


def _rigid_carrier(p):
    return dataclasses.replace(p, carrier_compliance=np.zeros((0, 0)))


def _rigid_discs(p):
    return dataclasses.replace(p, disc_compliance=np.zeros((0, 3, 3)))


def _support_state(p, theta=0.3, seed=1, scale=20e-6):
    """A loaded crank-support state: carrier turned by theta, each crank off its bore."""
    rng = np.random.default_rng(seed)
    n = p.drive.n_cranks
    q = np.zeros(6 + 3 * n)
    q[0:2] = rng.normal(0.0, 2e-6, 2)
    q[2] = theta
    c, s = np.cos(theta), np.sin(theta)
    for j in range(n):
        b = p.crank_bores[j]
        q[6 + 3 * j : 8 + 3 * j] = q[0:2] + [c * b[0] - s * b[1], s * b[0] + c * b[1]] + rng.normal(0.0, scale, 2)
        q[8 + 3 * j] = rng.normal()
    return q


def _central(g, q, v, h):
    out = np.zeros((len(q), len(q)))
    for i in range(len(q)):
        e = np.zeros_like(q)
        e[i] = h
        out[:, i] = (g.evaluate(0.0, q + e, v)[0] - g.evaluate(0.0, q - e, v)[0]) / (2 * h)
    return out


# ------------------------------------------------------------------ FE matrices as the models use them
def test_carrier_support_compliance_reproduces_fe_torsion():
    """C_eff = S^T C S (fem.carrier.crank_support_compliance): with the tangential
    crank loads T / (N a_w) per unit torque, g_c^T C_eff g_c equals the FE torsional
    compliance g^T C g of the carrier (identity: S g_c = g; to 1e-12), and C_eff is
    symmetric positive definite."""
    from flexrv.fem.carrier import carrier_compliance, crank_support_compliance

    r = load("rv40e")
    c = carrier_compliance(r)
    ce = crank_support_compliance(r)
    n, a_w = c.n_cranks, c.crank_circle_radius
    psi = 2 * np.pi * np.arange(n) / n
    g = (np.stack([-np.sin(psi), np.cos(psi)], axis=1) / (n * a_w)).ravel()
    assert g @ ce @ g == pytest.approx(c.torsional, rel=1e-12)
    assert np.allclose(ce, ce.T, rtol=0, atol=1e-15 * np.abs(ce).max())
    assert np.linalg.eigvalsh(ce).min() > 0.0


def test_rim_compliance_reproduces_fe_torsion(params):
    """The disc's rim compliance (fem.disc.rim_compliance) stores the FE strain energy
    of the rated pin-load pattern in the rim's rotation: C_d[psi, psi] equals the
    mean torsional compliance of disc_torsion_sweep (the budget's value) to 1e-12,
    so a disc torque T twists the rim by c_d T; the discs in parallel give the
    budget's cycloid_disc compliance c_d / n_discs. disc_torsion_sweep (patch
    compliances of the unmodified body, keyed on geometry, loaded by the design's
    pin loads) reproduces disc_compliance_sweep (FE of the modified disc under the
    same loads) at every crank angle within 0.5 % (measured 0.2 %; rv221 0.08 %)."""
    from flexrv.fem.disc import body_compliances, disc_compliance_sweep, disc_torsion_sweep

    r = load("rv40e")
    d = disc_torsion_sweep(r)
    np.testing.assert_allclose(d.torsional, disc_compliance_sweep(r).torsional, rtol=5e-3)
    cd = params.disc_compliance
    assert cd.shape == (2, 3, 3)
    assert cd[0, 2, 2] == pytest.approx(d.mean, rel=1e-12)
    assert cd[1, 2, 2] / params.drive.n_discs == pytest.approx(
        body_compliances(r)["cycloid_disc"]["compliance_rad_per_Nm"], rel=1e-12
    )


# ------------------------------------------------------------------ carrier in the crank supports
def test_condensed_carrier_equals_explicit_bore_unknowns(supports):
    """The condensed kernel's forces equal the uncondensed problem: the support
    points' displacements u (2N, housing frame) as explicit unknowns of
    u + R C R^T f_s(d0 - u) = 0 (f_s from flexrv.contact.tapered_roller.crank_support_force
    per crank), solved by scipy's hybrid root finder to 1e-15 m; forces on the
    cranks, the carrier and the carrier's moment (arm r + u) agree to 1e-9
    relative. The carrier visibly matters here (forces change by > 10 %)."""
    from flexrv.contact.tapered_roller import crank_support_force
    from flexrv.model.cranks_discs import CrankSupports

    p = supports
    g = CrankSupports(p)
    q = _support_state(p)
    v = np.zeros_like(q)
    f, _ = g.evaluate(0.0, q, v)
    n, th = p.drive.n_cranks, q[2]
    c, s = np.cos(th), np.sin(th)
    rot = np.array([[c, -s], [s, c]])
    R = np.kron(np.eye(n), rot)
    ch = R @ p.carrier_compliance @ R.T
    r = p.crank_bores @ rot.T
    d0 = q[6:].reshape(n, 3)[:, :2] - q[:2] - r
    gam = 0.5 * (1 - p.support_law.g) * q[8::3] + 0.5 * (1 + p.support_law.g) * th

    def spring(u):
        out = np.zeros(2 * n)
        for j in range(n):
            fx, fy, *_ = crank_support_force(
                d0[j, 0] - u[2 * j],
                d0[j, 1] - u[2 * j + 1],
                gam[j],
                p.support_clearances[j],
                p.support_law,
                p.support_roller_angles,
                p.support_linear,
                0.0,
                0.0,
            )
            out[2 * j], out[2 * j + 1] = fx, fy
        return out

    sol = root(lambda u: 1e6 * (u + ch @ spring(u)), np.zeros(2 * n), method="hybr", tol=1e-15)
    u = sol.x
    assert np.abs(u + ch @ spring(u)).max() < 1e-14
    fs = spring(u)
    np.testing.assert_allclose(f[6:].reshape(n, 3)[:, :2].ravel(), fs, rtol=1e-9, atol=1e-9 * np.abs(fs).max())
    assert f[0] == pytest.approx(-fs[0::2].sum(), rel=1e-9)
    arm = r + u.reshape(n, 2)
    moment = -np.sum(arm[:, 0] * fs[1::2] - arm[:, 1] * fs[0::2])
    assert f[2] == pytest.approx(moment, rel=1e-9)
    np.testing.assert_allclose(g.ustate[:, :2].ravel(), u, atol=1e-13)
    f_rigid, _ = CrankSupports(_rigid_carrier(p)).evaluate(0.0, q, v)
    assert np.abs(f_rigid - f).max() > 0.1 * np.abs(f).max()


def _warm_against_cold(warm, cold, states, v, before=None, after=None):
    """Largest relative force and Jacobian differences of ``warm`` (called along the
    sequence, keeping its predictor) against ``cold`` (reset before every call); every
    third state compares Jacobians, the others forces. Returns (err_f, err_j, last cold
    force). ``before``/``after``: called around each pair of calls."""
    err_f = err_j = 0.0
    fc = None
    for k, q in enumerate(states):
        if before is not None:
            before()
        cold.reset()  # (also sets a pin group's counter to 0)
        if k % 3 == 2:
            jw, jc = warm.jacobian(0.0, q, v)[0], cold.jacobian(0.0, q, v)[0]
            err_j = max(err_j, np.abs(jw - jc).max() / np.abs(jc).max())
        else:
            fw, fc = warm.evaluate(0.0, q, v)[0], cold.evaluate(0.0, q, v)[0]
            err_f = max(err_f, np.abs(fw - fc).max() / np.abs(fc).max())
        if after is not None:
            after()
    return err_f, err_j, fc


@pytest.mark.parametrize("theta", [0.3, 2.1])
def test_condensed_carrier_jacobian_central_differences(supports, theta):
    """Condensed tangent (I + K C_h)^-1 K with the turn of C_h with the carrier and
    the deflected arm: equals central differences (h = 1e-9) of the group's force
    within 1e-6 of the largest entry (measured ~1e-7); the damper Jacobian likewise."""
    from flexrv.model.cranks_discs import CrankSupports

    g = CrankSupports(supports)
    q = _support_state(supports, theta=theta, seed=2)
    v = np.zeros_like(q)
    f, _ = g.evaluate(0.0, q, v)
    assert np.abs(f).max() > 500.0
    jq, jv = g.jacobian(0.0, q, v)
    nq = _central(g, q, v, 1e-9)
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    nv = np.zeros_like(jv)
    for i in range(len(q)):
        e = np.zeros_like(q)
        e[i] = 1e-6
        nv[:, i] = (g.evaluate(0.0, q, v + e)[0] - g.evaluate(0.0, q, v - e)[0]) / 2e-6
    assert np.abs(jv - nv).max() <= 1e-6 * np.abs(nv).max()


def test_stiff_carrier_reproduces_rigid_supports(supports):
    """C -> 0 (1e-9 of the FE carrier): forces equal the rigid-carrier kernel's to
    1e-6 relative (the remaining carrier share is ~1e-9 of the supports'), the
    Jacobian to 1e-6 of its largest entry."""
    from flexrv.model.cranks_discs import CrankSupports

    p = supports
    stiff = CrankSupports(dataclasses.replace(p, carrier_compliance=1e-9 * p.carrier_compliance))
    rigid = CrankSupports(_rigid_carrier(p))
    q = _support_state(p, seed=4)
    v = np.zeros_like(q)
    f1, f0 = stiff.evaluate(0.0, q, v)[0], rigid.evaluate(0.0, q, v)[0]
    np.testing.assert_allclose(f1, f0, rtol=1e-6, atol=1e-6 * np.abs(f0).max())
    j1, j0 = stiff.jacobian(0.0, q, v)[0], rigid.jacobian(0.0, q, v)[0]
    assert np.abs(j1 - j0).max() <= 1e-6 * np.abs(j0).max()


# ------------------------------------------------------------------ disc body around the pins
def _disc_state(p, turn=3e-4):
    from flexrv.model.factory import _members

    mem = _members(p.drive)
    q = np.concatenate([mem[f"disc{k}"].q0 for k in range(p.drive.n_discs)])
    q[2::3] -= turn  # the discs turned against their pins: loaded
    return q


def test_condensed_disc_equals_explicit_rim_unknowns(params):
    """The wrapper's forces equal the uncondensed problem: the rim offsets delta
    (x, y, psi per disc) as explicit unknowns of delta = C_d Q_pins(q + delta), Q
    from the RIGID pins group at the rim pose, solved by scipy's root finder; forces
    agree to 1e-9 relative; the rim turns by c_d times the pins' disc torque."""
    from flexrv.model.pins import PinContacts

    p = params
    g, g0 = PinContacts(p), PinContacts(_rigid_discs(p))
    q = _disc_state(p)
    v = np.zeros_like(q)
    f, _ = g.evaluate(0.0, q, v)
    cd = p.disc_compliance

    def resid(x):
        d = x.reshape(-1, 3) * np.array([1.0, 1.0, 1.0 / p.pin_circle_radius])
        Q = g0.evaluate(0.0, q + d.ravel(), v)[0].reshape(-1, 3)
        return (
            (d - np.einsum("kab,kb->ka", cd, Q)).ravel()
            * np.array([1.0, 1.0, p.pin_circle_radius] * p.drive.n_discs)
            * 1e6
        )

    sol = root(resid, np.zeros_like(q), method="hybr", tol=1e-15)
    delta = sol.x.reshape(-1, 3) * np.array([1.0, 1.0, 1.0 / p.pin_circle_radius])
    fe = g0.evaluate(0.0, q + delta.ravel(), v)[0]
    np.testing.assert_allclose(f, fe, rtol=1e-9, atol=1e-9 * np.abs(fe).max())
    np.testing.assert_allclose(g.dstate, delta, rtol=0, atol=1e-12)
    assert g.dstate[0, 2] == pytest.approx(cd[0, 2, 2] * f[2], rel=1e-9)
    f0, _ = g0.evaluate(0.0, q, v)
    assert np.abs(f0 - f).max() > 0.1 * np.abs(f).max()  # the disc body matters here


def test_condensed_disc_jacobian_central_differences(params):
    """Condensed tangents (I - J C_d)^-1 J and (I - J C_d)^-1 J_v of the wrapper equal
    central differences of the group's force within 1e-6 of the largest entry (h =
    1e-9 m for q; h = 1e-4 m/s for v at 1 mm/s, where the contact damping acts: the
    force is linear in v there, and a smaller step meets the round-off of the rim's
    Newton, ~1e-8 N). Without friction (pin_friction = 0): the step 1e-4 m/s is ten
    times the friction's regularisation speed, so the regularised Coulomb force is not
    linear over it; the condensation with friction is checked at smaller steps in
    tests/test_friction.py::test_pin_friction_jacobian_with_disc_rim_condensation."""
    from flexrv.model.pins import PinContacts

    g = PinContacts(dataclasses.replace(params, pin_friction=0.0))
    assert g.mu == 0.0
    q = _disc_state(params)
    v = np.zeros_like(q)
    jq, _ = g.jacobian(0.0, q, v)
    nq = _central(g, q, v, 1e-9)
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    v = np.full_like(q, 1e-3)
    v[2::3] = 1e-3 / params.pin_circle_radius
    _, jv = g.jacobian(0.0, q, v)
    nv = np.zeros_like(jv)
    for i in range(len(q)):
        e = np.zeros_like(q)
        e[i] = 1e-4 * (1.0 if i % 3 < 2 else 1.0 / params.pin_circle_radius)
        nv[:, i] = (g.evaluate(0.0, q, v + e)[0] - g.evaluate(0.0, q, v - e)[0]) / (2 * e[i])
    assert np.abs(nv).max() > 1.0
    assert np.abs(jv - nv).max() <= 1e-6 * np.abs(nv).max()


def test_stiff_disc_reproduces_rigid_pins(params):
    """C_d -> 0 (1e-9 of the FE disc): forces and Jacobians equal the rigid discs'
    (plain pin kernel) to 1e-6."""
    from flexrv.model.pins import PinContacts

    p = params
    stiff = PinContacts(dataclasses.replace(p, disc_compliance=1e-9 * p.disc_compliance))
    rigid = PinContacts(_rigid_discs(p))
    q = _disc_state(p)
    v = np.zeros_like(q)
    f1, f0 = stiff.evaluate(0.0, q, v)[0], rigid.evaluate(0.0, q, v)[0]
    np.testing.assert_allclose(f1, f0, rtol=1e-6, atol=1e-6 * np.abs(f0).max())
    j1, j0 = stiff.jacobian(0.0, q, v)[0], rigid.jacobian(0.0, q, v)[0]
    assert np.abs(j1 - j0).max() <= 1e-6 * np.abs(j0).max()


# ------------------------------------------------------------------ switches and the parameter route
def test_with_bodies_sets_the_design_switches():
    """--parts names the elastic bodies: with_bodies turns the design's switches,
    and each element's parameters carry the FE matrix only of its named body (the crank
    supports the carrier's, the pins the discs'); a rigid carrier's support points keep
    the rings' and joints' parts (flexrv.analysis.path_compliances), and without
    [path_estimates] they are rigid."""
    from flexrv.fem.carrier import crank_support_compliance
    from flexrv.model.cranks_discs import CrankSupports
    from flexrv.model.pins import PinContacts

    r = load("rv40e")
    p = _element_params(CrankSupports, with_bodies(r, ["carrier"]))
    parts = sum(p.carrier_parts.values())
    assert set(p.carrier_parts) == {"support_bearing_rings", "carrier_joints"}
    np.testing.assert_allclose(p.carrier_compliance - parts, crank_support_compliance(r), rtol=1e-12, atol=0)
    assert _element_params(PinContacts, with_bodies(r, ["carrier"])).disc_compliance.shape == (0, 3, 3)
    p = _element_params(CrankSupports, with_bodies(r, ["cycloid_disc"]))
    assert np.array_equal(p.carrier_compliance, parts)
    assert _element_params(PinContacts, with_bodies(r, ["cycloid_disc"])).disc_compliance.shape == (2, 3, 3)
    p = _element_params(CrankSupports, with_bodies(r, []))
    assert np.array_equal(p.carrier_compliance, parts)
    assert _element_params(PinContacts, with_bodies(r, [])).disc_compliance.size == 0
    p = _element_params(CrankSupports, with_bodies(r, []).model_copy(update={"path_estimates": None}))
    assert p.carrier_compliance.size == 0 and p.carrier_parts == {}


# ------------------------------------------------------------------ quasi-static torsional compliance
def _qs_loaded(red):
    """Quasi-static equilibrium at the rated torque (crank angle 0): (tangent torsional
    compliance, compliance budget, the pins group evaluated at that state)."""
    from flexrv.model.quasi_static import StaticModel, ramp_to

    sm = StaticModel(red)
    sm.torque = 0.0
    q = ramp_to(sm, 0.0, sm.kinematic_pose(0.0), red.operating.rated_torque_Nm)
    c = 1.0 / sm.tangent_rigidity(0.0, q)
    budget = sm.compliance_budget(0.0, q)
    pins = next(g for g in sm.model.groups if g.name == "pins")
    pins.evaluate(0.0, sm.model.group_state(pins, q), np.zeros(3 * pins.nd))
    return c, budget, pins


def _qs_compliance(red):
    c, budget, pins = _qs_loaded(red)
    disc_torque = -(pins.force * pins.rxn).sum(axis=-1)  # the pins' torque on each disc about its centre
    return c, budget, disc_torque


def test_quasi_static_carrier_and_disc_add_their_fe_compliance():
    """Quasi-static tangent torsional compliance at the rated torque (crank angle 0,
    ~10 s): with the carrier alone minus with no elastic body = g^T C g of the FE
    carrier within 1 % (series element; measured 0.1 %, the load sharing between
    the cranks shifting a little). With the discs alone minus none = c_d sum_k
    (M_k / T)^2 within 1 % (measured < 0.1 %): the rim's twist is c_d M_k, M_k the
    pins' torque on disc k about its centre, which the model finds at 0.964 T /
    n_discs on the rv40e (the first stage carries the rest of the output torque to
    the carrier), so the disc's share is 7 % below the analytic budget's c_d /
    n_discs, which takes M_k = T / n_discs. The budget's carrier / cycloid_disc
    shares times the compliance reproduce the same differences within 1 %."""
    from flexrv.fem.disc import body_compliances

    r = load("rv40e")
    torque = r.operating.rated_torque_Nm
    fe = body_compliances(r)
    c_none, _, _ = _qs_compliance(with_bodies(r, []))
    c_car, b_car, _ = _qs_compliance(with_bodies(r, ["carrier"]))
    c_disc, b_disc, m_disc = _qs_compliance(with_bodies(r, ["cycloid_disc"]))
    g_c = fe["carrier"]["compliance_rad_per_Nm"]
    g_d = fe["cycloid_disc"]["compliance_one_disc_rad_per_Nm"] * float(np.sum((m_disc / torque) ** 2))
    assert np.all(np.abs(m_disc / (torque / 2) - 0.964) < 0.01)
    assert c_car - c_none == pytest.approx(g_c, rel=0.01)
    assert c_disc - c_none == pytest.approx(g_d, rel=0.01)
    assert b_car["carrier"] * c_car == pytest.approx(g_c, rel=0.01)
    assert b_disc["cycloid_disc"] * c_disc == pytest.approx(g_d, rel=0.01)
    assert sum(b_car.values()) == pytest.approx(1.0, abs=1e-9)


# ------------------------------------------------------------------ bad input
def test_self_intersecting_disc_and_bad_switch_name_the_field():
    """A disc whose crank holes would cut the teeth or be cut by the centre hole,
    planets that would overlap on the crank circle, and an unknown body model: ConfigError naming the field
    (the carrier's
    own cases: tests/test_fem_carrier.py::test_carrier_design_errors_name_the_field)."""
    from flexrv.design import override
    from flexrv.errors import ConfigError

    cases = [
        ({"second_stage.center_hole_radius_mm": 30.0}, "second_stage.center_hole_radius_mm"),
        ({"first_stage.module_mm": 2.2}, "first_stage.module_mm"),
        ({"first_stage.n_planets": 6}, "first_stage.n_planets"),
        ({"second_stage.disc_body_model": "flexible"}, "disc_body_model"),
        ({"carrier.body_model": "modal"}, "body_model"),
    ]
    for ov, field in cases:
        with pytest.raises(ConfigError, match=field):
            override("rv40e", ov)


def test_parts_semantics_and_cli_errors():
    """--parts names the elastic parts of the run: carrier / cycloid_disc with any
    model (option ``bodies``), main_bearing / crankshaft only with --model flexible;
    a wrong combination or name is a ConfigError naming it (exit 2 through
    flexrv.cli.main), before any run."""
    from typer.testing import CliRunner

    from flexrv.cli import app
    from flexrv.errors import ConfigError
    from flexrv.model.factory import parts_options

    assert parts_options("rigid", None) == {}
    assert parts_options("rigid", "carrier,cycloid_disc") == {"bodies": ("carrier", "cycloid_disc")}
    assert parts_options("balls", "carrier") == {"bodies": ("carrier",)}
    assert parts_options("flexible", "main_bearing,cycloid_disc") == {"parts": ("main_bearing", "cycloid_disc")}
    assert parts_options("rigid", "none") == {"bodies": ()} and parts_options("flexible", "none") == {"parts": ()}
    with pytest.raises(ConfigError, match="main_bearing needs --model flexible"):
        parts_options("rigid", "main_bearing")
    for args, words in (
        (["simulate", "rv40e", "--parts", "crankshaft"], "needs --model flexible"),
        (["stiffness-test", "rv40e", "--parts", "housing"], "parts = housing is not allowed"),
    ):
        res = CliRunner().invoke(app, args)
        assert isinstance(res.exception, ConfigError) and words in str(res.exception), res.output


def test_model_info_names_the_elastic_bodies():
    """The assembled model records its elastic bodies (info ``elastic_bodies``) from
    the design's switches or the ``bodies`` option; the declared outputs carry the
    carrier's support-point deflection [m] and the discs' rim twist [rad]."""
    from flexrv.model.factory import build_model

    r = load("rv40e")
    assert build_model(r, exudyn=False).info["elastic_bodies"] == ["carrier", "cycloid_disc"]
    assert build_model(r, exudyn=False, bodies=("carrier",)).info["elastic_bodies"] == ["carrier"]
    assert build_model(r, "balls", exudyn=False, bodies=()).info["elastic_bodies"] == []
    m = build_model(r, exudyn=False)
    sup = next(g for g in m.groups if g.name == "crank_supports")
    pins = next(g for g in m.groups if g.name == "pins")
    q = m.q0.copy()
    for k in range(m.params.n_discs):
        q[m.slice(f"disc{k}").start + 2] -= 3e-4
    _, out = pins.evaluate(0.0, m.group_state(pins, q), np.zeros(3 * pins.nd), want_outputs=True)
    assert out["disc_rim_rotation"].units == "rad" and np.all(out["disc_rim_rotation"].values != 0.0)
    _, out = sup.evaluate(0.0, _support_state(sup.params), np.zeros(6 + 3 * m.params.n_cranks), want_outputs=True)
    assert out["carrier_bore_deflection"].units == "m" and np.all(out["carrier_bore_deflection"].values > 1e-7)


# ------------------------------------------------------------------ predictor path (issue 15)
def _moving_sequence(q0, big, small, n=30):
    """States as a time integration visits them: a step ``big`` every other call and,
    between, a Newton-like correction ``small`` of the step's state."""
    return [q0 + (k // 2) * big + (k % 2) * small for k in range(n)]


def test_predictor_path_equals_cold_starts_on_a_moving_sequence():
    """Issue 15: the rim condensation (pins, elastic discs + elastic housing + friction,
    rv40e) and the carrier condensation (crank supports) start each call from a
    first-order predictor of the previous call (flexrv.model.pins._pin_condensed_kernel,
    flexrv.model.cranks_discs.crank_support_kernel). Along a moving sequence of states
    (load growing ~10 % over 15 steps, Newton-like corrections between) their forces
    equal those of cold starts (state reset before every call) within 1e-9 of the
    largest entry and their Jacobians within 1e-6 (the explicit-unknowns and
    central-difference bounds of the tests above; measured 2026-11-24: pins 9e-13 /
    2e-11, supports 5e-14 / 6e-15), and the predictor makes the pins cheaper: at most
    2 pin-kernel evaluations per call on average against at least 3 from cold starts
    (measured 1.6 and 5.0)."""
    from flexrv.model.cranks_discs import CrankSupports
    from flexrv.model.pins import PinContacts

    p = _element_params(PinContacts, load("rv40e"))
    assert p.housing_compliance > 0.0 and p.disc_compliance.size and p.pin_friction > 0.0
    warm, cold = PinContacts(p), PinContacts(p)
    q0 = _disc_state(p)
    v = np.zeros_like(q0)
    v[0::3], v[1::3], v[2::3] = 2e-4, -1e-4, 1e-2  # sliding: the friction forces act
    big = np.zeros_like(q0)
    big[0::3], big[1::3], big[2::3] = 3e-8, -2e-8, -2e-6
    counts = {"warm": 0, "cold": 0}

    def count():  # pin-kernel evaluations of this call (the cold group's counter restarts at its reset)
        counts["warm"] += warm.ctr[0] - counts.setdefault("c0", 0)
        counts["cold"] += cold.ctr[0]

    def mark():
        counts["c0"] = warm.ctr[0]

    err_f, err_j, fc = _warm_against_cold(warm, cold, _moving_sequence(q0, big, 1e-3 * big), v, mark, count)
    n_warm, n_cold = counts["warm"], counts["cold"]
    assert np.abs(fc).max() > 1e3 and np.abs(warm.hstate[1]) > 0.0 and np.abs(warm.dstate[:, 2]).max() > 1e-6
    assert err_f <= 1e-9 and err_j <= 1e-6, (err_f, err_j)
    assert n_warm / 30 <= 2.0 and n_cold / 30 >= 3.0, (n_warm / 30, n_cold / 30)

    p = _element_params(CrankSupports, load("rv40e"))
    warm, cold = CrankSupports(p), CrankSupports(p)
    assert warm.elastic_carrier
    q0 = _support_state(p)
    v = np.zeros_like(q0)
    big = np.zeros_like(q0)
    big[2] = 1e-6  # the carrier turns against the cranks, which roll on (cage angles move)
    big[8::3] = 1e-3
    big[6::3] = 1e-8
    err_f, err_j, fc = _warm_against_cold(warm, cold, _moving_sequence(q0, big, 1e-3 * big), v)
    assert np.abs(fc).max() > 1e3 and np.abs(warm.ustate).max() > 1e-7
    assert err_f <= 1e-9 and err_j <= 1e-6, (err_f, err_j)
