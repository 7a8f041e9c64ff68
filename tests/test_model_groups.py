"""Force-element groups of the rigid model: geometry at the nominal pose and
analytic Jacobians against central differences (no time integration)."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load
from flexrv.model.factory import build_model


def _variant(name, needle="empirical", ideal=False):
    from flexrv.model.bodies import with_bodies

    # rigid carrier and discs, no support-point compliance (the elastic bodies, the rings and joints of
    # flexrv.analysis.path_compliances: tests/test_bodies.py, tests/test_path_compliances.py)
    r = with_bodies(load(name), [])
    upd = {"needle_bearing": r.needle_bearing.model_copy(update={"model": needle}), "path_estimates": None}
    if ideal:
        upd["second_stage"] = r.second_stage.model_copy(update={"modification_equidistant_mm": 0.0})
        upd["needle_bearing"] = upd["needle_bearing"].model_copy(update={"radial_clearance_um": 0.0})
        upd["first_stage"] = r.first_stage.model_copy(update={"backlash_um": 0.0})
    return r.model_copy(update=upd)


@pytest.fixture(scope="module", params=["rv40e", "rv221"])
def ideal_model(request):
    return build_model(_variant(request.param, ideal=True))


def test_nominal_pose_is_conjugate(ideal_model):
    """Ideal profile at the conjugate pose (flexrv.geometry.cycloid.nominal_disc_pose):
    every pin touches its disc (|gap| < 1 nm, Litvin & Fuentes 2004 ch. 19), no
    needle or mesh deflection, so all forces vanish."""
    m = ideal_model
    q, v = m.q0, np.zeros(m.n)
    pins = next(g for g in m.groups if g.name == "pins")
    pins.reset()
    pins.evaluate(0.0, m.group_state(pins, q), m.group_state(pins, v))
    assert np.max(np.abs(pins.gap)) < 1e-9
    for g in m.groups:
        f, _ = g.evaluate(0.0, m.group_state(g, q), m.group_state(g, v))
        assert np.max(np.abs(f)) < 1e-3, g.name


@pytest.mark.parametrize("needle", ["empirical", "rollers"])
def test_analytic_jacobians(needle):
    """Group Jacobians (stiffness and damping parts) vs central differences of the
    generalized force at a loaded state; tolerance 1 % of the largest entry (the
    geometric terms dropped by design are below that at operating loads). Steps: 1e-10
    in q, 1e-7 in v: the pins' force carries the round-off of the rim/housing Newton
    (up to ~3e-7 N, tests/test_friction.py, tests/test_housing.py), which a 1e-10 step in v
    would turn into ~3e3 N s/m of difference noise against damping entries of ~300 N s/m;
    at the random speeds of ~1e-3 m/s (100 v_reg) the friction law is smooth over 1e-7."""
    m = build_model(_variant("rv40e", needle=needle))
    rng = np.random.default_rng(1)
    q = m.q0.copy()
    for k in range(m.params.n_discs):
        s = m.slice(f"disc{k}")
        q[s.start + 2] += 1.5e-4  # turn the discs into the pins
    for j in range(m.params.n_cranks):
        q[m.slice(f"crank{j}").start + 2] += 5e-5  # load the drive flanks
    q += rng.normal(scale=1e-7, size=q.shape)
    v = rng.normal(scale=1e-3, size=q.shape)
    checked = 0
    for g in m.groups:
        if not g.analytic_jacobian:
            continue
        lq, lv = m.group_state(g, q), m.group_state(g, v)
        dq, dv = g.jacobian(0.0, lq, lv)
        n = len(lq)
        nq, nv = np.zeros((n, n)), np.zeros((n, n))
        h, hv = 1e-10, 1e-7
        for i in range(n):
            e = np.zeros(n)
            e[i] = h
            ev = np.zeros(n)
            ev[i] = hv
            if hasattr(g, "new_step"):
                g.new_step()
            nq[:, i] = (g.evaluate(0.0, lq + e, lv)[0] - g.evaluate(0.0, lq - e, lv)[0]) / (2 * h)
            nv[:, i] = (g.evaluate(0.0, lq, lv + ev)[0] - g.evaluate(0.0, lq, lv - ev)[0]) / (2 * hv)
        if np.abs(nq).max() > 0:
            assert np.abs(dq - nq).max() <= 0.01 * np.abs(nq).max(), g.name
            checked += 1
        if np.abs(nv).max() > 0:
            assert np.abs(dv - nv).max() <= 0.01 * np.abs(nv).max(), g.name
    assert checked >= 4


def test_roller_and_empirical_needle_agree_in_magnitude():
    """The roller-resolved needle bearing (Palmgren per roller, Harris & Kotzalas
    2007) and the :cite:`seed004` empirical law give the same order of radial stiffness:
    force at a 5 um journal offset within a factor 3 of each other (zero clearance)."""
    forces = []
    for needle in ("empirical", "rollers"):
        r = _variant("rv40e", needle=needle, ideal=True)
        m = build_model(r)
        g = next(g for g in m.groups if g.name == "needle_bearings")
        q = m.q0.copy()
        q[m.slice("crank0").start] += 5e-6
        _, out = g.evaluate(np.zeros(1), m.group_state(g, q)[None], np.zeros((1, g_size(m, g))), want_outputs=True)
        forces.append(out["needle_force"].values[0, 0].max())
    ratio = forces[0] / forces[1]
    assert 1 / 3 < ratio < 3, forces


def g_size(m, g):
    return sum(m.members[name].n for name in g.members)


def test_parameters_physical():
    """Masses/inertias positive; ratio equals :cite:`seed002,seed000` values (81, 221)."""
    for name, ratio in (("rv40e", 81.0), ("rv221", 221.0)):
        p = build_model(load(name)).params
        assert p.ratio == pytest.approx(ratio)
        assert min(p.crank_mass, p.crank_inertia, p.disc_mass, p.disc_inertia) > 0


def test_roller_load_distribution_stribeck():
    """Roller-resolved needle bearing with zero clearance under a pure radial
    journal offset: Q_max = F_r / sum(cos^(1+10/9) psi_i) -> about 4.08 F_r / Z
    (Stribeck's line-contact constant, Harris & Kotzalas 2007, ch. 7); checked
    against the exact discrete sum to 1e-9 and against 4.08 F_r / Z to 10 %."""
    r = _variant("rv40e", needle="rollers", ideal=True)
    m = build_model(r)
    g = next(g for g in m.groups if g.name == "needle_bearings")
    q = m.q0.copy()
    q[m.slice("crank0").start] += 3e-6  # journal of crank 0 pushed along +x in both discs
    n = g_size(m, g)
    _, out = g.evaluate(np.zeros(1), m.group_state(g, q)[None], np.zeros((1, n)), want_outputs=True)
    rollers = out["roller_force"].values[0, 0, 0]
    f_r = out["needle_force"].values[0, 0, 0]
    z = r.needle_bearing.roller_count
    # exact discrete relation for the actual roller angles (cage angle 0 at the start)
    psi = 2 * np.pi * np.arange(z) / z
    c = np.clip(np.cos(psi), 0, None)
    assert rollers.max() == pytest.approx(f_r / np.sum(c ** (1 + 10 / 9)), rel=1e-9)
    assert rollers.max() == pytest.approx(4.08 * f_r / z, rel=0.10)


def test_fused_force_element_matches_the_groups():
    """The rigid model's compiled groups share ONE Exudyn element
    (flexrv.model.kernels.FusedForces: members' mass objects + 1 object), and its
    residual at loaded states after a short run equals the sum of the groups' own
    evaluate() (same kernels on the group's local vectors) to round-off (1e-9 of
    the largest force; a mis-scattered coordinate block would differ at order 1)."""
    from flexrv.model.assembled import group_index
    from flexrv.simulation import Simulation

    r = load("rv40e")
    op = r.operating.model_copy(update={"speed_ramp_time_s": 0.002, "load_ramp_start_s": 0.0, "load_ramp_end_s": 0.002})
    sim = Simulation(r.model_copy(update={"operating": op}))
    model = sim.build()
    assert model.mbs.systemData.NumberOfObjects() == len(model.members) + 1
    res = sim.run(t_end=0.003, dt=1e-4)
    assert np.max(np.abs(res["pin_force"].values)) > 10.0  # the pins are loaded
    rng = np.random.default_rng(3)
    for i in range(5):
        q = model.q0.copy()
        q[model.slice("disc0").start + 2] += 1e-4 * (i + 1)
        q += rng.normal(scale=1e-7, size=q.shape)
        v = rng.normal(scale=1e-3, size=q.shape)
        f = model.fused.residual(0.001 * i, q, v).copy()
        total = np.zeros(model.n)
        for g in model.groups:
            ix = group_index([model.members[n].offset for n in g.members], [model.members[n].n for n in g.members])
            total[ix] += g.evaluate(0.001 * i, q[ix], v[ix])[0]
        np.testing.assert_allclose(f, total, rtol=0, atol=1e-9 * np.abs(total).max())


# ----------------------------------------------------------------------------- crank supports (issue 14)
def _support_params(reducer):
    """The crank supports' own parameters (CrankSupports.parameters) of a design."""
    from flexrv.model.cranks_discs import CrankSupports
    from flexrv.model.drive import drive_parameters

    return CrankSupports.parameters(reducer, drive_parameters(reducer))


def _support_state(p, g, seed=0, scatter=3e-6):
    from flexrv.model.factory import _members

    p = p.drive
    mem = _members(p)
    rng = np.random.default_rng(seed)
    q = np.concatenate([mem[n].q0 for n in g.members])
    q = q + rng.normal(scale=scatter, size=q.shape)
    q[2] += 1e-4  # carrier turned: the bores push the cranks
    for j in range(p.n_cranks):
        q[8 + 3 * j] += 0.3 * j  # cranks at different cage angles
    return q, 1e-3 * rng.normal(size=q.shape)


@pytest.mark.parametrize("clearance_um", [0.0, 2.0])
def test_crank_support_jacobian_exact(clearance_um):
    """Tapered-roller supports in series with the crank's bending (rv40e preset):
    the analytic Jacobian (series tangent K_s, cage-angle terms, bore rotation in
    the carrier moment) equals central differences (h = 1e-9) of the group's force
    within 1e-6 of the largest entry (measured 4e-9 without clearance), with and
    without an as-built radial clearance; damping Jacobian exact (c I on the
    relative velocity, bore rotation in the damper dropped: below 1e-6 here)."""
    import dataclasses

    from flexrv.model.cranks_discs import CrankSupports

    p = _support_params(_variant("rv40e"))
    p = dataclasses.replace(p, support_clearances=np.full(p.drive.n_cranks, clearance_um * 1e-6))
    g = CrankSupports(p)
    q, v = _support_state(p, g)
    v[2] = 0.0  # no carrier spin: the dropped damper term vanishes
    f, _ = g.evaluate(0.0, q, v)
    assert np.abs(f).max() > 500.0  # loaded
    jq, jv = g.jacobian(0.0, q, v)
    h = 1e-9
    nq, nv = np.zeros_like(jq), np.zeros_like(jv)
    for i in range(len(q)):
        e = np.zeros_like(q)
        e[i] = h
        nq[:, i] = (g.evaluate(0.0, q + e, v)[0] - g.evaluate(0.0, q - e, v)[0]) / (2 * h)
        nv[:, i] = (g.evaluate(0.0, q, v + e)[0] - g.evaluate(0.0, q, v - e)[0]) / (2 * h)
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    assert np.abs(jv - nv).max() <= 1e-6 * np.abs(nv).max()


def test_crank_support_forces_balance_and_bending_share():
    """Action = reaction: the support forces on the cranks are minus the force on
    the carrier, and their moment about the carrier centre is the carrier's
    generalized moment; the reported bending share equals |K_s t|^2 / (k_b t.K_s t)
    of the law (flexrv.contact.tapered_roller) and lies in (0, 1)."""
    from flexrv.model.cranks_discs import CrankSupports

    p = _support_params(_variant("rv40e"))
    g = CrankSupports(p)
    q, _ = _support_state(p, g, seed=3)
    f, out = g.evaluate(0.0, q, np.zeros_like(q), want_outputs=True)
    fx, fy = f[6::3], f[7::3]
    assert f[0] == pytest.approx(-fx.sum(), abs=1e-9) and f[1] == pytest.approx(-fy.sum(), abs=1e-9)
    c, s = np.cos(q[2]), np.sin(q[2])
    r = p.crank_bores @ np.array([[c, s], [-s, c]])
    assert f[2] == pytest.approx(-np.sum(r[:, 0] * fy - r[:, 1] * fx), rel=1e-12)
    share = out["crank_bending_fraction"].values
    assert np.all((share > 0.2) & (share < 0.8))


def test_linear_support_option_is_the_legacy_spring():
    """support_bearing_model = "linear" (explicit option): the group applies
    F = -2 k_sb d (two bearings) with a rigid crank, exactly."""
    from flexrv.model.cranks_discs import CrankSupports
    from tests.data.make_force_reference import legacy_supports

    p = _support_params(legacy_supports(_variant("rv40e"), "rv40e"))
    assert p.support_linear and p.support_stiffness == 4e8
    g = CrankSupports(p)
    q, _ = _support_state(p, g, seed=5)
    q[2] = 0.0
    f, out = g.evaluate(0.0, q, np.zeros_like(q), want_outputs=True)
    d = q[6:].reshape(-1, 3)[:, :2] - q[:2] - p.crank_bores
    np.testing.assert_allclose(f[6:].reshape(-1, 3)[:, :2], -4e8 * d, rtol=1e-12)
    assert "crank_bending_fraction" not in out


@pytest.mark.parametrize(
    "field,value,words",
    [
        ("support_bearing_roller_count", 30, ["support_bearing_roller_count", "must be <= 15", "overlap"]),
        (
            "support_bearing_pitch_diameter_mm",
            16.0,
            ["support_bearing_pitch_diameter_mm", "does not fit on the journal"],
        ),
        ("support_bearing_roller_length_mm", 12.0, ["support_bearing_roller_length_mm", "support_journal_length_mm"]),
        ("support_bearing_contact_angle_deg", 50.0, ["support_bearing_contact_angle_deg", "35"]),
        ("support_bearing_model", "linear", ["support_bearing_radial_stiffness_N_per_m", "required"]),
    ],
)
def test_support_bearing_bad_input(field, value, words):
    """A support bearing that cannot fit (rollers vs pitch circle, cone vs journal,
    rollers longer than the journal), out-of-range geometry or a missing field of
    the chosen law: ConfigError naming the field."""
    from flexrv.design import override
    from flexrv.errors import ConfigError

    with pytest.raises(ConfigError) as info:
        override("rv40e", {f"crankshaft.{field}": value})
    for w in words:
        assert w in str(info.value)
