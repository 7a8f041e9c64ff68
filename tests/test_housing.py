"""The pin housing inside the models (issue 14): an elastic rotation phi_h = c_h M_h of
the pin ring about the reducer axis, shared by all discs, condensed into the pins'
rim wrapper (flexrv.model.pins, "Housing"; c_h from
flexrv.analysis.torsional.housing_model_compliance). Numbers against independent
solves: the condensed forces against the uncondensed problem (the discs' rim
offsets and phi_h as explicit unknowns, scipy's root finder), the condensed tangents
against central differences, the tiny-c_h limit against the per-disc wrapper, the
quasi-static torsional compliance against c_h (M_h / T)^2, and the budgets."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import root

from flexrv.design import load
from flexrv.model.bodies import with_bodies
from tests.test_bodies import _central, _element_params, _qs_loaded  # one central-difference helper


def _pin_params(reducer):
    from flexrv.model.pins import PinContacts

    return _element_params(PinContacts, reducer)


@pytest.fixture(scope="module")
def params():
    """The pins' parameters of rv40e (elastic discs and housing)."""
    return _pin_params(load("rv40e"))


def _disc_state(p, turn=3e-4):
    """Discs at their kinematic pose, turned against their pins (loaded)."""
    from flexrv.model.factory import _members

    mem = _members(p.drive)
    q = np.concatenate([mem[f"disc{k}"].q0 for k in range(p.drive.n_discs)])
    q[2::3] -= turn
    return q


def _axis_arms(q):
    """a_k = (-y_k, x_k, 1) per disc (flexrv.model.pins, "Housing")."""
    x = q.reshape(-1, 3)
    return np.stack([-x[:, 1], x[:, 0], np.ones(len(x))], axis=1)


def test_housing_estimate_enters_the_parameters(params):
    """c_h of the models is housing_compliance(...).total at the rated torque (rv40e:
    ~8e-8 rad/(N m)); body_model = "rigid" gives 0."""
    from flexrv.analysis.torsional import housing_compliance

    r = load("rv40e")
    assert params.housing_compliance == pytest.approx(housing_compliance(r).total, rel=1e-12)
    assert 1e-8 < params.housing_compliance < 1e-6
    rigid = r.model_copy(update={"housing": r.housing.model_copy(update={"body_model": "rigid"})})
    assert _pin_params(rigid).housing_compliance == 0.0


def test_condensed_housing_equals_explicit_unknowns(params):
    """The wrapper's forces equal the uncondensed problem: the disc bodies' rim offsets
    d_k (x, y, psi) and the housing rotation phi_h as explicit unknowns of
    d_k = C_d,k Q_k and phi_h = c_h M_h, M_h = -sum_k a_k . Q_k, Q from the group with
    rigid discs and rigid housing at the rim pose q_k + d_k - phi_h a_k, solved by
    scipy's root finder; forces agree to 1e-9 relative, phi_h to 1e-9."""
    from flexrv.model.pins import PinContacts

    p = params
    g = PinContacts(p)
    g0 = PinContacts(dataclasses.replace(p, disc_compliance=np.zeros((0, 3, 3)), housing_compliance=0.0))
    q = _disc_state(p)
    v = np.zeros_like(q)
    f, _ = g.evaluate(0.0, q, v)
    cd, ch, a = p.disc_compliance, p.housing_compliance, _axis_arms(q)
    w = np.array([1.0, 1.0, p.pin_circle_radius])

    def pose(x):
        d = x[:-1].reshape(-1, 3) / w
        phi = x[-1] / p.pin_circle_radius
        return d, phi, q + (d - phi * a).ravel()

    def resid(x):
        d, phi, qr = pose(x)
        Q = g0.evaluate(0.0, qr, v)[0].reshape(-1, 3)
        rd = (d - np.einsum("kab,kb->ka", cd, Q)) * w
        rh = (phi + ch * np.sum(a * Q)) * p.pin_circle_radius
        return np.append(rd.ravel(), rh) * 1e6

    sol = root(resid, np.zeros(len(q) + 1), method="hybr", tol=1e-15)
    d, phi, qr = pose(sol.x)
    fe = g0.evaluate(0.0, qr, v)[0]
    np.testing.assert_allclose(f, fe, rtol=1e-9, atol=1e-9 * np.abs(fe).max())
    assert g.hstate[1] == pytest.approx(phi, rel=1e-9)
    np.testing.assert_allclose(g.dstate, d - phi * a, rtol=0, atol=1e-12)
    # the housing matters here: phi_h is a fifth of the imposed turn, the forces change by > 10 %
    assert abs(phi) > 0.1 * 3e-4
    g1 = PinContacts(dataclasses.replace(p, housing_compliance=0.0))
    f1, _ = g1.evaluate(0.0, q, v)
    assert np.abs(f1 - f).max() > 0.1 * np.abs(f).max()


def test_condensed_housing_jacobian_rigid_discs(params):
    """Rigid disc bodies, friction off, elastic housing: the condensed tangent
    (I - J C)^-1 J (I + D) (C = c_h A A^T, D the turn of the arms a_k with the hub
    centres) equals central differences (h = 1e-9 m) within 1e-6 of the largest
    entry (measured ~4e-9); without D the error would be ~phi_h ~ 1e-4."""
    from flexrv.model.pins import PinContacts

    p = dataclasses.replace(params, disc_compliance=np.zeros((0, 3, 3)), pin_friction=0.0)
    g = PinContacts(p)
    q = _disc_state(p)
    v = np.zeros_like(q)
    jq, _ = g.jacobian(0.0, q, v)
    nq = _central(g, q, v, 1e-9)
    assert np.abs(jq).max() > 1e8
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()


def test_condensed_housing_jacobian_combined(params):
    """Disc bodies, housing and friction together (the presets' model), discs turning
    at 1 mm/s on the pin circle: dQ/dq by central differences (h = 1e-9 m) within
    1e-6 of the largest entry; dQ/dv (h = 1e-6 m/s, rad/s times R_p) within 1e-5 of
    the largest entry. Bound: the pins' sliding speeds are ~1 mm/s, 100 v_reg, where
    the regularised friction sign is still curved, so the difference quotient
    carries its O(h^2) truncation plus the rim Newton's round-off over h (~1e-8 N /
    1e-6): measured 2.7e-6 with the housing, 1.4e-6 for the per-disc wrapper
    (c_h = 0) and 2.5e-6 with the housing and friction off; at h = 1e-5 the
    truncation dominates (4-6e-5 with and without the housing alike)."""
    from flexrv.model.pins import PinContacts

    p = params
    assert p.pin_friction > 0.0 and p.disc_compliance.shape[0] == p.drive.n_discs
    g = PinContacts(p)
    q = _disc_state(p)
    v = np.zeros_like(q)
    v[2::3] = 1e-3 / p.pin_circle_radius
    jq, jv = g.jacobian(0.0, q, v)
    nq = _central(g, q, v, 1e-9)
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    nv = np.zeros_like(jv)
    for i in range(len(q)):
        e = np.zeros_like(q)
        e[i] = 1e-6 * (1.0 if i % 3 < 2 else 1.0 / p.pin_circle_radius)
        nv[:, i] = (g.evaluate(0.0, q, v + e)[0] - g.evaluate(0.0, q, v - e)[0]) / (2 * e[i])
    assert np.abs(nv).max() > 1.0
    assert np.abs(jv - nv).max() <= 1e-5 * np.abs(nv).max()
    assert np.abs(g.ft).max() > 0.0  # friction acts


def test_tiny_housing_reproduces_per_disc_wrapper(params):
    """c_h -> 0 (1e-9 of the estimate) through the coupled code equals the per-disc
    wrapper of c_h = 0 (the integ code path, unchanged) to 1e-7 relative in forces
    and Jacobians (the remaining housing share is ~1e-9 of the pins')."""
    from flexrv.model.pins import PinContacts

    p = params
    tiny = PinContacts(dataclasses.replace(p, housing_compliance=1e-9 * p.housing_compliance))
    per_disc = PinContacts(dataclasses.replace(p, housing_compliance=0.0))
    assert tiny.elastic_housing and not per_disc.elastic_housing
    q = _disc_state(p)
    v = np.zeros_like(q)
    f1, f0 = tiny.evaluate(0.0, q, v)[0], per_disc.evaluate(0.0, q, v)[0]
    np.testing.assert_allclose(f1, f0, rtol=1e-7, atol=1e-7 * np.abs(f0).max())
    j1, j0 = tiny.jacobian(0.0, q, v)[0], per_disc.jacobian(0.0, q, v)[0]
    assert np.abs(j1 - j0).max() <= 1e-7 * np.abs(j0).max()
    np.testing.assert_allclose(tiny.dstate, per_disc.dstate, rtol=0, atol=1e-13)


def _qs(red):
    c, budget, pins = _qs_loaded(red)
    rec = pins.record()
    m_h = float(np.sum(pins._housing_torque({k: x[None] for k, x in rec.items()})))
    return c, budget, m_h, float(pins.hstate[1])


@pytest.mark.slow
def test_quasi_static_housing_adds_its_compliance():
    """Quasi-static tangent torsional compliance of rv40e at the rated torque (crank
    angle 0, rigid bodies otherwise, ~20 s): with the housing minus without =
    c_h (M_h / T)^2 within 1 %, M_h the pins' torque on the housing (the first stage
    carries the rest of T); phi_h = c_h M_h; the budget's housing share times the
    compliance reproduces the difference within 1 %, and the shares sum to 1."""
    r = with_bodies(load("rv40e"), [])
    torque = r.operating.rated_torque_Nm
    rigid = r.model_copy(update={"housing": r.housing.model_copy(update={"body_model": "rigid"})})
    c_h = _pin_params(r).housing_compliance
    c1, b1, m_h, phi = _qs(r)
    c0, b0, _, _ = _qs(rigid)
    assert "housing" not in b0 and "housing" in b1
    assert 0.9 < abs(m_h) / torque < 1.0
    assert phi == pytest.approx(c_h * m_h, rel=1e-6)
    assert c1 - c0 == pytest.approx(c_h * (m_h / torque) ** 2, rel=0.01)
    assert b1["housing"] * c1 == pytest.approx(c_h * (m_h / torque) ** 2, rel=0.01)
    assert sum(b1.values()) == pytest.approx(1.0, abs=1e-9)


def test_budgets_count_the_housing_once():
    """The analytic budget lists the housing as c_h (the models' constant) and the
    model budgets take it from the model's own share: budget_from_group_shares adds
    nothing unmodelled; body_model = "rigid" drops it from every budget (noted)."""
    from flexrv.analysis.torsional import (
        UNMODELLED_ELEMENTS,
        budget_from_group_shares,
        housing_model_compliance,
        stiffness_budget,
        unmodelled_elements,
    )

    r = load("rv40e")
    b = stiffness_budget(r)
    assert b.compliances["housing"] == pytest.approx(housing_model_compliance(r), rel=1e-12)
    assert b.total == pytest.approx(sum(b.compliances.values()), rel=1e-12)
    assert UNMODELLED_ELEMENTS == () and unmodelled_elements(r, 1e-6)[0] == {}
    comp, _ = budget_from_group_shares({"pins": 0.5, "housing": 0.2, "crank_supports": 0.3}, 1e-6, 0.0, r)
    assert comp["housing"] == pytest.approx(0.2e-6) and sum(comp.values()) == pytest.approx(1e-6)
    rigid = r.model_copy(update={"housing": r.housing.model_copy(update={"body_model": "rigid"})})
    b0 = stiffness_budget(rigid)
    assert "housing" not in b0.compliances
    assert b.total - b0.total == pytest.approx(housing_model_compliance(r), rel=1e-9)
    assert any("rigid" in n for n in b0.notes)


def test_bad_housing_switch_names_the_field():
    """An unknown housing.body_model: ConfigError naming the field."""
    from flexrv.design import override
    from flexrv.errors import ConfigError

    with pytest.raises(ConfigError, match="body_model"):
        override("rv40e", {"housing.body_model": "stiff"})
    assert override("rv40e", {"housing.body_model": "rigid"}).housing.body_model == "rigid"
