"""Compiled force kernels (issue 15): the groups' compiled kernels and the fused
element reproduce the numpy groups they replaced, their Jacobians match finite
differences, the as-built fields act as their formulas say, a skipped pin is a
failure, and a short rigid run gives the same TE."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexrv.model.factory import build_model

REF = Path(__file__).parent / "data" / "force_reference.npz"
CASES = [("rv40e", "empirical"), ("rv40e", "rollers"), ("rv221", "empirical"), ("rv221", "rollers")]


def _variant(name, needle):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_force_reference", REF.with_name("make_force_reference.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.variant(name, needle)


def _close(a, b, rel=1e-9, what=""):
    """|a - b| <= rel * max|b| (+ a 1e-300 floor for all-zero references)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, (what, a.shape, b.shape)
    scale = max(np.max(np.abs(b), initial=0.0), 1e-300)
    err = np.max(np.abs(a - b), initial=0.0)
    assert err <= rel * scale, f"{what}: max error {err:.3g} vs scale {scale:.3g}"


#: groups whose dF/dq gained the terms the reference (made before) dropped: compared with
#: central differences (test_completed_jacobians_vs_central_differences), not with the reference
COMPLETED_JACOBIANS = ("pins", "gear_stage", "needle_bearings")


@pytest.fixture(scope="module")
def ref():
    return np.load(REF)


@pytest.mark.parametrize("name,needle", CASES)
def test_groups_match_reference(ref, name, needle):
    """Each group's compiled kernel (evaluate, jacobian, outputs on the 20 states as
    a history) equals the numpy groups of before issue 15 (tests/data/
    make_force_reference.py) within 1e-9 of each array's largest entry. The angular
    outputs of rollers compare modulo 2 pi."""
    key = f"{name}-{needle}"
    m = build_model(_variant(name, needle), exudyn=False)
    t, q, v = ref[f"{key}/t"], ref[f"{key}/q"], ref[f"{key}/v"]
    for g in m.groups:
        qg, vg = m.group_state(g, q), m.group_state(g, v)
        for i in range(len(t)):
            g.reset()
            f, _ = g.evaluate(float(t[i]), qg[i], vg[i])
            _close(f, ref[f"{key}/{g.name}/force"][i], what=f"{key} {g.name} force {i}")
            g.reset()
            jq, jv = g.jacobian(float(t[i]), qg[i], vg[i])
            if g.name not in COMPLETED_JACOBIANS:
                _close(jq, ref[f"{key}/{g.name}/jac_q"][i], what=f"{key} {g.name} jac_q {i}")
            _close(jv, ref[f"{key}/{g.name}/jac_v"][i], what=f"{key} {g.name} jac_v {i}")
        g.reset()
        _, out = g.evaluate(t, qg, vg, want_outputs=True)
        names = {k.split("/out/")[1] for k in ref.files if k.startswith(f"{key}/{g.name}/out/")}
        assert set(out) == names, g.name
        for k, o in out.items():
            r = ref[f"{key}/{g.name}/out/{k}"]
            if k == "roller_angle":
                d = np.angle(np.exp(1j * (o.values - r)))
                _close(d + np.pi, np.full_like(r, np.pi), what=k)
            else:
                _close(o.values, r, what=f"{key} {g.name} {k}")


@pytest.mark.parametrize("name,needle", CASES)
def test_fused_generalized_forces_match_reference(ref, name, needle):
    """AssembledModel.generalized_forces (ONE call of the fused compiled kernel)
    equals the sum of the reference groups' forces and Jacobians (1e-9 rel.)."""
    from flexrv.model.assembled import group_index

    key = f"{name}-{needle}"
    m = build_model(_variant(name, needle), exudyn=False)
    t, q, v = ref[f"{key}/t"], ref[f"{key}/q"], ref[f"{key}/v"]
    for i in range(len(t)):
        for g in m.groups:
            g.reset()
        f, dq, dv = m.generalized_forces(float(t[i]), q[i], v[i])
        fr, dqr, dvr = np.zeros(m.n), np.zeros((m.n, m.n)), np.zeros((m.n, m.n))
        for g in m.groups:
            ix = np.arange(m.n)[
                group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])
            ]
            fr[ix] += ref[f"{key}/{g.name}/force"][i]
            if g.name in COMPLETED_JACOBIANS:  # the group's own (checked against differences below)
                g.reset()
                dqr[np.ix_(ix, ix)] += g.jacobian(float(t[i]), q[i][ix], v[i][ix])[0]
            else:
                dqr[np.ix_(ix, ix)] += ref[f"{key}/{g.name}/jac_q"][i]
            dvr[np.ix_(ix, ix)] += ref[f"{key}/{g.name}/jac_v"][i]
        _close(f, fr, what="force")
        _close(dq, dqr, what="jac_q")
        _close(dv, dvr, what="jac_v")


# ----------------------------------------------------------------------------- Jacobians
def _loaded(m, disc_turn=1.5e-4, crank_turn=5e-5, seed=1):
    rng = np.random.default_rng(seed)
    q = m.q0.copy()
    for k in range(m.params.n_discs):
        q[m.slice(f"disc{k}").start + 2] += disc_turn  # discs into the pins
    for j in range(m.params.n_cranks):
        q[m.slice(f"crank{j}").start + 2] += crank_turn  # drive flanks loaded
    q += rng.normal(scale=1e-7, size=q.shape)
    return q, rng.normal(scale=1e-3, size=q.shape)


def _fd(fun, x, h):
    n = len(x)
    out = np.zeros((len(fun(x)), n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        out[:, i] = (fun(x + e) - fun(x - e)) / (2 * h)
    return out


@pytest.mark.parametrize("name,needle", CASES)
def test_fused_jacobian_vs_central_differences(name, needle):
    """dF/dq and dF/dv of the fused kernel vs central differences (h = 1e-10) of
    its own force at a loaded state (with speeds): within 1e-6 of the largest entry
    (measured 1.5e-8 on rv40e, 8.6e-8 on rv221, both needle models; before the
    needle Jacobian's completion 3e-5 / 1e-4 with the empirical needle model, so
    the old tolerance here was 1e-3). The pin, gear-mesh and needle-bearing
    Jacobians are complete (see test_completed_jacobians_vs_central_differences);
    still dropped by design (modified Newton converges on the exact residual): the
    rotation of the support bores in the damper (~c omega, below this state's
    resolution)."""
    m = build_model(_variant(name, needle), exudyn=False)
    q, v = _loaded(m)
    t = 0.002
    _, dq, dv = m.generalized_forces(t, q, v)
    nq = _fd(lambda x: m.generalized_forces(t, x, v, jacobian=False)[0], q, 1e-10)
    nv = _fd(lambda x: m.generalized_forces(t, q, x, jacobian=False)[0], v, 1e-6)
    assert np.abs(nq).max() > 1e6 and np.abs(nv).max() > 10.0  # contacts loaded
    assert np.abs(dq - nq).max() <= 1e-6 * np.abs(nq).max()
    assert np.abs(dv - nv).max() <= 1e-6 * np.abs(nv).max()


def _static_states(reducer, torques=(1.0, 0.01)):
    """Static equilibria (quasi-static solver) at fractions of the rated torque, at
    the first position: realistic contact sets, loaded and barely loaded."""
    from flexrv.errors import ConvergenceError
    from flexrv.model.quasi_static import StaticModel, ramp_to

    sm = StaticModel(reducer)
    th = 0.37
    q = sm.kinematic_pose(th)
    sm.torque = 0.0
    try:
        q, _ = sm.solve(th, q)
    except ConvergenceError:
        pass
    out = []
    for frac in torques:
        q = ramp_to(sm, th, q, frac * sm.t_ref, steps=8)
        out.append((th, q.copy()))
    return sm.model, out


@pytest.mark.parametrize("errors", [None, "iso_grade5_rv40e"])
def test_completed_jacobians_vs_central_differences(errors):
    """dF/dq of the pin contacts, the gear meshes (now with the gap curvature, the
    harmonics' foot-point term, the mesh deflection's curvature and the stiffness'
    phase slope) and the needle bearings (the eccentric and hole arms' rotation in
    the moments and in the damper's rate, the empirical damper's rate turning with
    the direction d/|d|, the rollers' cage angle, the friction moment through the
    whole dF/dq) equals central differences (h = 1e-10 m on the crank circle) of
    their own forces within 1e-6 of the largest entry, at static equilibria of
    rv40e (rated and 1 % torque; ideal and with the grade-5 error set: pin, disc
    harmonic and runout errors), at rest and with random speeds (the damping
    terms' dependence on q), for the needle bearings also at running speeds
    (~20 rad/s). Measured: 1-8e-8 (the differences' round-off); the needle
    Jacobian before its completion: 1.4e-4 at the small speeds, 3.6e-2 at the
    running ones."""
    from flexrv.design import load_error_set, with_errors
    from flexrv.model.assembled import group_index
    from flexrv.model.quasi_static import StaticModel

    red = _variant("rv40e", "empirical")
    if errors:
        red = with_errors(red, load_error_set(errors))
    m, states = _static_states(red)
    rng = np.random.default_rng(3)
    arm = StaticModel(red).arm  # the solver's length scale per coordinate (crank-circle radius for angles)
    checked = 0
    for th, q in states:
        for v_scale in (0.0, 1e-3, 0.3):
            v = rng.normal(scale=v_scale, size=m.n) / arm
            for g in m.groups:
                if g.name not in COMPLETED_JACOBIANS or (v_scale > 1e-2 and g.name != "needle_bearings"):
                    continue
                ix = np.arange(m.n)[
                    group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])
                ]
                g.new_step()
                jq, _ = g.jacobian(th, q[ix], v[ix])
                nq = np.zeros_like(jq)
                for i in range(len(ix)):
                    h = 1e-10 / arm[ix[i]]
                    e = np.zeros(len(ix))
                    e[i] = h
                    g.new_step()
                    fp, _ = g.evaluate(th, q[ix] + e, v[ix])
                    g.new_step()
                    fm, _ = g.evaluate(th, q[ix] - e, v[ix])
                    nq[:, i] = (fp - fm) / (2 * h)
                scale = np.abs(nq).max()
                assert scale > 1e7, (g.name, scale)  # contacts / meshes loaded
                err = np.abs(jq - nq).max() / scale
                assert err <= 1e-6, (g.name, th, v_scale, err)
                checked += 1
    assert checked == 14


@pytest.mark.parametrize("needle", ["empirical", "rollers"])
def test_needle_jacobian_columns_vs_central_differences(needle):
    """The needle bearings' dF/dq column by column: each column of the analytic
    Jacobian equals central differences (h = 1e-10 m on the crank circle) of the
    kernel's own forces within 1e-5 of that column's largest entry (columns above
    1e-6 of the whole matrix), at rv40e's static equilibria (rated and 1 % torque)
    at rest, with small and with running speeds (~20 rad/s), both needle laws. The
    column scale resolves the rotation columns, where the terms dropped before
    issue 15's completion live (arm rotations F e, the damper's rate turning with
    the arms, the rollers' cage angle): before, 3e-4 (rollers, at rest) to 9e-2
    (empirical, running); now 1e-7 to 7.4e-7 (the differences' round-off)."""
    from flexrv.model.assembled import group_index
    from flexrv.model.quasi_static import StaticModel

    red = _variant("rv40e", needle)
    m, states = _static_states(red)
    rng = np.random.default_rng(3)
    arm = StaticModel(red).arm
    g = next(g for g in m.groups if g.name == "needle_bearings")
    ix = np.arange(m.n)[group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])]
    worst = 0.0
    for th, q in states:
        for v_scale in (0.0, 1e-3, 0.3):
            v = rng.normal(scale=v_scale, size=m.n) / arm
            g.new_step()
            jq, _ = g.jacobian(th, q[ix], v[ix])
            nq = np.zeros_like(jq)
            for i in range(len(ix)):
                e = np.zeros(len(ix))
                e[i] = 1e-10 / arm[ix[i]]
                g.new_step()
                fp, _ = g.evaluate(th, q[ix] + e, v[ix])
                g.new_step()
                fm, _ = g.evaluate(th, q[ix] - e, v[ix])
                nq[:, i] = (fp - fm) / (2 * e[i])
            scale = np.abs(nq).max()
            assert scale > 1e7, scale  # needles loaded
            for i in range(len(ix)):
                col = np.abs(nq[:, i]).max()
                if col > 1e-6 * scale:
                    worst = max(worst, np.abs(jq[:, i] - nq[:, i]).max() / col)
    assert worst <= 1e-5, worst


# ----------------------------------------------------------------------------- as-built fields
def _params(name="rv40e", needle="empirical"):
    from flexrv.model.drive import drive_parameters

    return drive_parameters(_variant(name, needle))


def _element_params(group, name="rv40e", needle="empirical"):
    """The typed parameters of the element ``group`` (its own builder) for a variant."""
    from flexrv.model.drive import drive_parameters

    r = _variant(name, needle)
    return group.parameters(r, drive_parameters(r))


def _members(p):
    from flexrv.model.factory import _members as members

    return members(p)


def _state(mem, names):
    return np.concatenate([mem[n].q0 for n in names])


def test_support_clearance_dead_band():
    """Crank supports with radial clearance c: F = k max(|d| - c, 0) along d
    (zero inside the clearance, damping too); c = 0 is the linear spring k d."""
    import dataclasses

    from flexrv.model.cranks_discs import CrankSupports

    p = _params()
    ps = _element_params(CrankSupports)
    c = 10e-6
    g0 = CrankSupports(ps)
    g = CrankSupports(dataclasses.replace(ps, support_clearances=np.full(p.n_cranks, c)))
    mem = _members(p)
    q = _state(mem, g.members)
    v = np.zeros_like(q)
    v[6] = 0.05  # crank 0 moving: damping acts only in contact
    u = np.array([0.6, 0.8])
    for dist, expect in ((5e-6, 0.0), (15e-6, ps.support_stiffness * 5e-6)):
        qq = q.copy()
        qq[6:8] += dist * u
        _, out = g.evaluate(0.0, qq, np.zeros_like(q), want_outputs=True)
        assert out["crank_support_force"].values[0] == pytest.approx(expect, rel=1e-12, abs=1e-9)
        _, out0 = g0.evaluate(0.0, qq, np.zeros_like(q), want_outputs=True)
        assert out0["crank_support_force"].values[0] == pytest.approx(ps.support_stiffness * dist, rel=1e-12)
        f, _ = g.evaluate(0.0, qq, v)
        if expect == 0.0:
            assert np.all(f == 0.0)
        else:  # spring along d plus the damper
            assert f[6] == pytest.approx(-expect * u[0] - ps.support_damping * 0.05, rel=1e-12)


def test_crank_bore_position_error():
    """A crank bore moved by b in the carrier pulls the nominal crank by k b
    (linear support, c = 0)."""
    import dataclasses

    from flexrv.model.cranks_discs import CrankSupports

    p = _params()
    ps = _element_params(CrankSupports)
    bores = ps.crank_bores.copy()
    bores[1] += [3e-6, -4e-6]
    g = CrankSupports(dataclasses.replace(ps, crank_bores=bores))
    q = _state(_members(p), g.members)
    f, _ = g.evaluate(0.0, q, np.zeros_like(q))
    np.testing.assert_allclose(f[9:11], ps.support_stiffness * np.array([3e-6, -4e-6]), rtol=1e-9)
    assert np.all(f[6:8] == 0.0) and np.all(f[12:14] == 0.0)


def test_needle_eccentricity_phase_and_clearance():
    """Empirical needle law F = K (|d| - c)^(10/9) (c = needle_clearances[j, k]): at
    the nominal pose an eccentric phase error err gives |d| = 2 e sin(err/2); an
    eccentricity error de gives |d| = de; a clearance above |d| gives no force."""
    import dataclasses

    from flexrv.model.cranks_discs import NeedleBearings, empirical_needle_constant

    r = _variant("rv40e", "empirical")
    p = _params()
    pn = _element_params(NeedleBearings)
    k_emp = empirical_needle_constant(r)
    assert pn.model == "empirical" and pn.k == k_emp
    zero = np.zeros((p.n_cranks, p.n_discs))
    err, de = 2e-3, 4e-6
    errs, ecc = zero.copy(), np.full_like(zero, p.eccentricity)
    errs[0, 1] = err
    ecc[2, 0] += de
    g = NeedleBearings(dataclasses.replace(pn, clearances=zero, eccentric_phase_errors=errs, eccentricities=ecc))
    q = _state(_members(p), g.members)
    _, out = g.evaluate(0.0, q, np.zeros_like(q), want_outputs=True)
    force = out["needle_force"].values
    expect = np.zeros_like(zero)
    expect[0, 1] = k_emp * (2 * p.eccentricity * np.sin(err / 2)) ** (10 / 9)
    expect[2, 0] = k_emp * de ** (10 / 9)
    np.testing.assert_allclose(force, expect, rtol=1e-6, atol=1e-6 * expect.max())
    clear = zero.copy()
    clear[2, 0] = 1.01 * de
    g2 = NeedleBearings(dataclasses.replace(pn, clearances=clear, eccentricities=ecc))
    _, out2 = g2.evaluate(0.0, q, np.zeros_like(q), want_outputs=True)
    assert out2["needle_force"].values[2, 0] == 0.0


def test_pin_radius_position_profile_harmonics():
    """Pin gaps with as-built geometry at the ideal conjugate pose (every gap 0):
    pin i enlarged by dr -> its gap -dr; pin moved outward radially by s -> gap
    s n.e_r with the kernel's normal n, to O(s^2/rho)); disc 1's equidistant +dr
    -> its gaps +dr; a profile harmonic (order, A, phase) on disc 0 -> gap -A
    cos(order phi* + phase). Tolerance 1e-9 m: the moved pin's second-order term
    s^2 / rho (2.5e-10 m measured, rho > 3 mm)."""
    import dataclasses

    from flexrv.model.pins import PinContacts

    r = _variant("rv40e", "empirical")
    ss = r.second_stage.model_copy(
        update={"modification_equidistant_mm": 0.0, "modification_shift_mm": 0.0, "modification_rotation_deg": 0.0}
    )
    from flexrv.model.drive import drive_parameters

    r = r.model_copy(update={"second_stage": ss})
    d = drive_parameters(r)
    p = PinContacts.parameters(r, d)
    g0 = PinContacts(p)
    q = _state(_members(d), g0.members)
    v = np.zeros_like(q)
    g0.evaluate(0.0, q, v)
    gap0, phi0 = g0.gap.copy(), g0.phi.copy()
    n0 = np.stack([g0.nx, g0.ny], -1).copy()
    assert np.abs(gap0).max() < 1e-9
    radii = p.pin_radii.copy()
    radii[3] += 5e-6
    pins = p.pins.copy()
    s = 2e-6
    pins[7] *= 1 + s / np.linalg.norm(pins[7])
    profile = p.disc_profile.copy()
    profile[1, 1] += 4e-6
    harm = np.zeros((d.n_discs, 1, 3))
    harm[0, 0] = [9.0, 3e-6, 0.3]
    g = PinContacts(dataclasses.replace(p, pin_radii=radii, pins=pins, disc_profile=profile, profile_harmonics=harm))
    g.evaluate(0.0, q, v)
    expect = gap0.copy()
    expect[:, 3] -= 5e-6
    e_r = pins[7] / np.linalg.norm(pins[7])
    expect[:, 7] += s * (n0[:, 7] @ e_r)
    expect[1] += 4e-6
    expect[0] -= 3e-6 * np.cos(9.0 * g.phi[0] + 0.3)  # at the foot point (moved for the moved pin)
    assert np.abs(g.phi - phi0).max() < 1e-3
    np.testing.assert_allclose(g.gap, expect, rtol=0, atol=1e-9)


def test_gear_runout_and_phase_errors():
    """Mesh deflection with as-built first stage: delta_j changes by A_s sin(theta_s
    - beta_j + ph_s) + A_j sin(phi_j - beta_j + ph_j) + r_bp err_j at the same state."""
    import dataclasses

    from flexrv.model.gear_stage import GearMeshes
    from flexrv.model.loads import ramp_drive

    p = _params()
    pg = _element_params(GearMeshes)
    th, om = ramp_drive(p.input_speed, p.speed_ramp_time)
    runout = np.array([[5e-6, 0.4], [0.0, 0.0], [7e-6, -1.0]])
    err = np.array([0.0, 1e-4, 0.0])
    g0 = GearMeshes(pg, th, om)
    g = GearMeshes(
        dataclasses.replace(pg, sun_runout=np.array([4e-6, 1.1]), planet_runout=runout, planet_phase_errors=err),
        th,
        om,
    )
    q = _state(_members(p), g0.members)
    q[8::3] += 3e-5
    t = 0.003
    _, o0 = g0.evaluate(t, q, np.zeros_like(q), want_outputs=True)
    _, o1 = g.evaluate(t, q, np.zeros_like(q), want_outputs=True)
    beta = np.arctan2(q[7::3], q[6::3])
    ts = float(th(t))
    expect = (
        4e-6 * np.sin(ts - beta + 1.1)
        + runout[:, 0] * np.sin(q[8::3] - beta + runout[:, 1])
        + pg.base_radius_planet * err
    )
    np.testing.assert_allclose(o1["mesh_deflection"].values - o0["mesh_deflection"].values, expect, rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------- skipped pin
def test_skipped_pin_is_a_failure():
    """Every crank one full turn ahead of its disc (the disc skipped a pin: pins and
    needle bearings are periodic in the crank angle, so nothing else notices) is
    reported by NeedleBearings.check() after a fused evaluation; a loaded normal
    state is not. Simulation turns any check() message into status 'failed'."""
    m = build_model(_variant("rv40e", "empirical"), exudyn=False)
    needles = next(g for g in m.groups if g.name == "needle_bearings")
    q, v = _loaded(m)
    m.generalized_forces(0.0, q, v)
    assert needles.check() is None
    for j in range(m.params.n_cranks):
        q[m.slice(f"crank{j}").start + 2] += 2 * np.pi
    m.generalized_forces(0.0, q, v)
    msg = needles.check()
    assert msg is not None and "skipped a pin" in msg
    dep = needles.departure
    np.testing.assert_allclose(np.abs(dep), 2 * np.pi / m.params.z_c, rtol=1e-3)


def test_blas_threads_setting(monkeypatch):
    """One BLAS thread by default; FLEXRV_BLAS_THREADS overrides (0: library default)."""
    from flexrv.model.kernels import blas_threads, single_thread_blas

    monkeypatch.delenv("FLEXRV_BLAS_THREADS", raising=False)
    assert blas_threads() == 1
    monkeypatch.setenv("FLEXRV_BLAS_THREADS", "3")
    assert blas_threads() == 3
    monkeypatch.setenv("FLEXRV_BLAS_THREADS", "0")
    assert blas_threads() is None
    monkeypatch.delenv("FLEXRV_BLAS_THREADS")
    from threadpoolctl import threadpool_info

    before = {p["filepath"]: p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}
    for _ in range(2):  # the second time with the cached controller: the same limit, restored on exit
        with single_thread_blas():
            assert all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
        assert {p["filepath"]: p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"} == before


# ----------------------------------------------------------------------------- short run
def test_short_rigid_run_same_te():
    """Short rigid rv40e run (5 ms ramps, t_end 0.05 s, dt 1e-4) with the fused
    element: TE mean and p-p over t > 0.02 s equal the numpy groups' run of before
    issue 15 (tests/data/te_reference.json) within 1e-3 arcsec (measured: 1.4e-5
    and 7e-6 arcsec; the pin gaps are now exact at every Newton iteration instead
    of linearised within a step, and the summation order differs)."""
    import importlib.util
    import json

    spec = importlib.util.spec_from_file_location("make_force_reference", REF.with_name("make_force_reference.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ref = json.loads(REF.with_name("te_reference.json").read_text())
    new = mod.te_statistics(ref["preset"], ref["t_end"], ref["dt"])
    assert new["samples"] == ref["samples"]
    assert new["te_mean_arcsec"] == pytest.approx(ref["te_mean_arcsec"], abs=1e-3)
    assert new["te_pp_arcsec"] == pytest.approx(ref["te_pp_arcsec"], abs=1e-3)


@pytest.mark.parametrize("ball_inertia", [True, False])
def test_fused_element_coexists_with_ball_bearing(ball_inertia):
    """Ball-resolved main bearing (the bearing rows, a compiled element of the fused
    kernel): the fused element covers every coordinate (with ball inertia the balls too;
    no rigid main bearing) and generalized_forces, the fused kernel's, equals the sum of
    every group's evaluate/jacobian (1e-9 rel.)."""
    from flexrv.model.assembled import group_index

    m = build_model(_variant("rv40e", "empirical"), "balls", exudyn=False, ball_inertia=ball_inertia)
    q, v = _loaded(m)
    f, dq, dv = m.generalized_forces(0.002, q, v)
    assert m.fused.is_full and m.fused.n == m.n and not m.fused.others
    kinds = [g.kind for g in m.fused.groups]
    assert "bearing_rows" in kinds and "main_bearing" not in kinds
    fr, dqr, dvr = np.zeros(m.n), np.zeros((m.n, m.n)), np.zeros((m.n, m.n))
    for g in m.groups:
        ix = np.arange(m.n)[group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])]
        g.new_step()
        fr[ix] += g.evaluate(0.002, q[ix], v[ix])[0]
        jq, jv = g.jacobian(0.002, q[ix], v[ix])
        dqr[np.ix_(ix, ix)] += jq
        dvr[np.ix_(ix, ix)] += jv
    _close(f, fr, what="force")
    _close(dq, dqr, what="jac_q")
    _close(dv, dvr, what="jac_v")


def test_curve_reach_and_certified_warm_start():
    """The pin-centre curve's reach (pins._curve_reach) on rv40e: outside, the
    lobe tip's radius of curvature (closed form at phi = 0, |C'|^3 / |C' x C''|),
    times the 0.9 safety factor, within 1 %; inside, several mm. A pin whose warm
    start sits on a wrong flank (phi moved by 0.06 rad, where the local search
    finds a ~mm gap) gets the cold-start gap: the same gaps as a fresh group to
    1e-12 m and forces to 1e-9 (without the reach check the gaps are wrong)."""
    from flexrv.geometry.cycloid import center_curve
    from flexrv.model.pins import PinContacts, _curve_reach

    p = _element_params(PinContacts)
    d = p.drive
    radius = p.pin_circle_radius + p.disc_profile[0][0]
    out, inside = _curve_reach(int(d.z_rp), float(radius), float(d.eccentricity))
    _, d1, d2 = center_curve(np.array([0.0]), d.z_rp, radius, d.eccentricity)
    rho = np.hypot(*d1[0]) ** 3 / abs(d1[0, 0] * d2[0, 1] - d1[0, 1] * d2[0, 0])
    assert out == pytest.approx(0.9 * rho, rel=0.01)
    assert inside > 1e-3
    m = build_model(_variant("rv40e", "empirical"), exudyn=False)
    q, v = _loaded(m)
    g = next(x for x in m.groups if x.name == "pins")
    qg, vg = m.group_state(g, q), m.group_state(g, v)
    g.reset()
    f_ref, _ = g.evaluate(0.0, qg, vg)
    gap_ref = g.gap.copy()
    phi_ref = g.phi.copy()
    for reach, ok in ((1.0, False), (None, True)):  # reach 1 m: every warm start trusted (before the check)
        saved = g.reach.copy()
        if reach:
            g.reach[:] = reach
        g.phi[:] = phi_ref + 0.06  # every warm start on the neighbouring flank's side
        g.last[:] = np.nan  # nothing skipped
        f, _ = g.evaluate(0.0, qg, vg)
        g.reach[:] = saved
        assert (np.abs(g.gap - gap_ref).max() <= 1e-12) == ok
    assert np.abs(f - f_ref).max() <= 1e-9 * np.abs(f_ref).max()


def test_small_dense_algebra_matches_numpy():
    """The local Newtons' allocation-free algebra (flexrv.model.numerics.linalg.inv_small,
    matmul_small; issue 15) against numpy: the inverse of well- and ill-conditioned
    (cond ~1e8, pivoting needed: zero leading entry) matrices within 1e-12 relative
    times the condition number, the product to 1e-14 relative."""
    from flexrv.model.numerics.linalg import inv_small, matmul_small

    rng = np.random.default_rng(3)
    for m, cond in ((3, 1e2), (6, 1e2), (6, 1e8), (12, 1e4)):
        u, _ = np.linalg.qr(rng.normal(size=(m, m)))
        w, _ = np.linalg.qr(rng.normal(size=(m, m)))
        a = u @ np.diag(np.logspace(0, -np.log10(cond), m)) @ w
        a[[0, 1]] = a[[1, 0]]
        a[0, 0] = 0.0  # pivoting needed
        ref = np.linalg.inv(a)
        out = np.empty((m, m))
        inv_small(a.copy(), out)
        assert np.abs(out - ref).max() <= 1e-12 * cond * np.abs(ref).max(), (m, cond)
        b = rng.normal(size=(m, m + 1))
        prod = np.empty((m, m + 1))
        matmul_small(a, b, prod)
        assert np.abs(prod - a @ b).max() <= 1e-14 * np.abs(a).max() * np.abs(b).max() * m
