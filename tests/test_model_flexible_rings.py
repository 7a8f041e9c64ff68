"""Flexible (reduced) bearing rings in the ball-resolved main bearing.

References: the full FE static solution of the clamped ring under the same ball
loads (patch-distributed as in the reduction, :mod:`flexrv.fem.reduction`), the
rigid-ring bearing (stiff-ring limit), Hamrock–Dowson film and Hertz pressure for
the per-ball outputs.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load
from flexrv.fem.body import _assemble, build_reduced_body, material_dict, raceway_spec_for
from flexrv.meshing import build_mesh, spec_for
from flexrv.model.flexible_bearing import (
    RING_EIGENMODES_QUASI_STATIC,
    RING_HARMONICS,
    ModalRing,
    evaluate_row,
    ring_modal_coordinates,
    rows_from_design,
    rxyz_matrices,
)
from tests.test_fem_reduction import fe_patch_deflection
from tests.test_model_flexible_bearing import _static_rig

SIZE, LOCAL = 0.015, 0.01  # coarse rv221 rings (as tests/test_fem_reduction.py)
#: :cite:`seed001`'s first external load case: 20 kN radial, 15 kN axial
SEED001_FORCE = (20000.0, 0.0, 15000.0)


@pytest.fixture(scope="module")
def rings(tmp_path_factory):
    """rv221 outer and inner rings, coarse mesh, reduced with the flexible model's
    default basis for quasi-static rings (RING_HARMONICS, no eigenmodes); full FE
    kept for reference."""
    import os

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    rv = load("rv221")
    out = {}
    for part in ("outer_ring", "inner_ring"):
        mres = build_mesh(rv, part, size=SIZE, local_size=LOCAL)
        mat = material_dict(rv, part)
        fe = _assemble(mres.data, mat)
        spec = raceway_spec_for(spec_for(rv, part), None, RING_HARMONICS)
        body = build_reduced_body(mres, mat, n_eig=RING_EIGENMODES_QUASI_STATIC, raceway=spec, fe=fe)
        out[part] = (mres, fe, body)
    del os.environ["FLEXRV_CACHE"]  # the private cache only while the fixture builds (the runs below
    return rv, out  # share the session's cache, e.g. the preset's FE carrier and disc bodies)


def _flexible_rows(rv, out, scale=1.0, rings=("inner", "outer"), condense=True, ehl="dry"):
    kw = {}
    for label in rings:
        body = out[f"{label}_ring"][2]
        zeta = rv.main_bearing.ring_damping_ratio
        kw[label] = [
            ModalRing(body, damping_ratio=zeta, stiffness_scale=scale, condense=condense),
            ModalRing(body, damping_ratio=zeta, stiffness_scale=scale, mirror=True, condense=condense),
        ]
    return rows_from_design(rv, ehl=ehl, **kw)


@pytest.mark.parametrize("condense", [True, False])
def test_ring_deflection_under_ball_loads_matches_full_fe(rings, condense):
    """:cite:`seed001`'s 20 kN radial + 15 kN axial case: the static bearing with both
    rings flexible (condensed into the row elements, or with their modal
    coordinates as system coordinates) gives ball loads and modal ring
    coordinates (a condensed ring's recovered from its contact loads); the reduced ring's
    raceway deflection at every loaded ball (along its contact normal) equals the
    full FE solution of the clamped ring under the same ball loads within 1 % of
    the largest deflection (measured 0.08 % with 12 eigenmodes in the basis; outer and inner ring, both rows;
    the second row is the
    mirror image z -> -z of the meshed ring, so its loads are mirrored for the
    FE reference)."""
    rv, out = rings
    rows, evals, frame_q, qs = _static_rig(
        rv, SEED001_FORCE, rows=_flexible_rows(rv, out, condense=condense), coordinates=True
    )
    checked = 0
    for k, (row, ev) in enumerate(zip(rows, evals)):
        for label, st in (("outer", ev.outer), ("inner", ev.inner)):
            mres, fe, body = out[f"{label}_ring"]
            loaded = st.load > 0.02 * st.load.max()
            load_on_ring = (-st.force_ball)[loaded]  # force of the ball on the ring (global frame)
            if label == "inner":  # inner ring: its frame is the (slightly displaced) carrier frame
                a_mat = rxyz_matrices(frame_q[3:6])[0]
                local = (ev.ball_pos[loaded] - frame_q[0:3]) @ a_mat
                load_on_ring = load_on_ring @ a_mat
                normal = st.normal[loaded] @ a_mat
            else:
                local = ev.ball_pos[loaded]
                normal = st.normal[loaded]
            psi = np.arctan2(local[:, 1], local[:, 0])
            mirror = np.array([1.0, 1.0, -1.0 if k == 1 else 1.0])
            ref = fe_patch_deflection(rv, mres, fe, psi, load_on_ring * mirror, part=f"{label}_ring") * mirror
            ring = getattr(row, label)
            q_modal = ring_modal_coordinates(row, label, qs[k], ev)
            red = np.einsum("nkm,m->nk", ring.groove_basis(psi), q_modal)
            ref_n = np.einsum("nk,nk->n", ref, normal)
            red_n = np.einsum("nk,nk->n", red, normal)
            assert ref_n.max() > 5e-7  # a real deflection of the order of um
            assert np.abs(red_n - ref_n).max() < 0.01 * np.abs(ref_n).max(), (k, label, red_n, ref_n)
            checked += 1
    assert checked == 4


def test_stiffened_rings_reproduce_the_rigid_ring_bearing(rings):
    """Stiff-ring limit inside the same element: rings with their stiffness scaled
    by 1e6 give the rigid-ring ball loads within 0.05 % of the maximum load; the
    real rings add compliance (carrier displacement grows) but change the loads
    only slightly (< 3 % of the maximum: ring deflection ~1 um against a Hertz
    approach of ~10 um)."""
    rv, out = rings
    _, rigid, frame_rigid = _static_rig(rv, SEED001_FORCE)
    _, stiff, _ = _static_rig(rv, SEED001_FORCE, rows=_flexible_rows(rv, out, scale=1e6))
    _, real, frame_real = _static_rig(rv, SEED001_FORCE, rows=_flexible_rows(rv, out))
    q_rigid = np.array([ev.inner.load for ev in rigid])
    q_stiff = np.array([ev.inner.load for ev in stiff])
    q_real = np.array([ev.inner.load for ev in real])
    scale = q_rigid.max()
    assert np.abs(q_stiff - q_rigid).max() < 5e-4 * scale
    assert 1e-4 * scale < np.abs(q_real - q_rigid).max() < 0.03 * scale
    assert np.hypot(*frame_real[:2]) > np.hypot(*frame_rigid[:2])
    assert abs(frame_real[2]) > abs(frame_rigid[2])


def test_flexible_reducer_run_outputs(rings):
    """Short run of the reducer with flexible rings (rv221, 5 ms, coarse rings):
    per-ball outputs are consistent with their closed forms — film thickness =
    Hamrock–Dowson h_c at the recorded load and the entrainment speed
    u = (d_m/4)(1 - gamma^2)|omega_carrier| (Hamrock 1994, ch. 24); Hertz
    p_max ~ Q^(1/3) (Harris & Kotzalas 2007, eq. 6.33: p_max/Q^(1/3) equal for
    all balls); the recorded ring deformation equals the raceway deflection of
    the recorded modal coordinates at the most-loaded ball; the massless ring
    modes carry no inertia."""
    from flexrv.contact.hertz import effective_modulus
    from flexrv.ehl.film import hamrock_dowson
    from flexrv.ehl.solver import LubricantProperties
    from flexrv.geometry.bearing import BallBearingGeometry
    from flexrv.simulation import Simulation

    rv, out = rings
    sim = Simulation(rv, model="flexible", model_options={"ring_options": {"size": SIZE}})
    model = sim.build()
    assert not any(m.kind == "modal" for m in model.members.values())
    res = sim.run(t_end=0.005)
    assert res.attrs["status"] == "completed"
    load_i = res["ball_load_inner"].values[-1]
    film = res["ball_film_thickness"].values[-1]
    p_max = res["ball_max_pressure"].values
    k, j = np.unravel_index(np.argmax(load_i), load_i.shape)
    geom = BallBearingGeometry.from_design(rv.main_bearing)
    rx, ry, _, _ = geom.contact_radii()
    ring, ball = rv.material("bearing_rings"), rv.material("rolling_elements")
    e_eff = float(effective_modulus(ring.youngs_modulus, ring.poisson_ratio, ball.youngs_modulus, ball.poisson_ratio))
    lub = LubricantProperties.from_design(rv.lubricant)
    speed = 0.25 * geom.pitch_diameter * (1 - geom.gamma**2) * abs(res["omega_out"].values[-1])
    assert speed > 0
    h_c, _ = hamrock_dowson(load_i[k, j], speed, rx, ry, e_eff, lub.viscosity, lub.pressure_viscosity)
    assert film[k, j] == pytest.approx(float(h_c), rel=1e-6)
    all_loads = res["ball_load_inner"].values
    loaded = all_loads > 1.0
    ratio = p_max[loaded] / np.cbrt(all_loads[loaded])
    assert np.ptp(ratio) < 1e-9 * ratio.mean()
    # the ring-deformation output is the deflection of the recorded modal
    # coordinates at the most-loaded ball, along its contact normal
    group = next(g for g in model.groups if g.name == "main_bearing")
    q_modal = res["ring_modal_outer"].values[-1, 0]
    balls = model.members["main_bearing_balls0"]
    q_end = np.asarray(model.mbs.systemData.GetODE2Coordinates())
    pos = q_end[balls.offset : balls.offset + balls.n].reshape(-1, 3)
    j_max = int(np.argmax(res["ball_load_outer"].values[-1, 0]))
    u = group.rows[0].outer.groove_basis(np.arctan2(pos[j_max : j_max + 1, 1], pos[j_max : j_max + 1, 0]))[0] @ q_modal
    assert np.linalg.norm(u) > 1e-9
    assert abs(res["ring_deformation_outer"].values[-1, 0]) <= np.linalg.norm(u) * (1 + 1e-9)
    assert res["ring_deformation_outer"].values[-1, 0] > 0.5 * np.linalg.norm(u)


@pytest.mark.slow
def test_stiffened_flexible_reducer_matches_rigid_ring_reducer():
    """Consistency (issue 6): the reducer with flexible rings stiffened 1e4x and
    EHL off reproduces the rigid-ring ball-bearing reducer (EHL off): loaded TE
    over the last 10 ms within 0.2 % (the Newton tolerance is 1e-3; measured
    0.07 arcsec of 86 at the end of the load ramp), ball loads within 1 % of the maximum; the kinematic ratio
    stays exact in the mean (0.2 %). Then the real rings: the TE level moves by
    less than 1 arcsec (ring deflection ~0.1 um at these loads)."""
    from flexrv.design import override
    from flexrv.simulation import Simulation

    rv = override("rv40e", {"contact.ehl": "dry"})
    t_end = 0.3  # past the load ramp (0.1-0.2 s): the steady window gives the mean ratio
    opts = {"ring_options": {"harmonics": 8, "n_eig": 4, "stiffness_scale": 1e4}}
    balls = Simulation(rv, model="balls").run(t_end=t_end)
    stiff = Simulation(rv, model="flexible", model_options=opts).run(t_end=t_end)
    window = slice(t_end - 0.01, None)  # loaded steady state
    te_b = balls["te"].sel(time=window).values
    te_s = stiff["te"].sel(time=window).values
    assert abs(te_s.mean() - te_b.mean()) < 2e-3 * abs(te_b.mean())
    lb, ls = balls["ball_load_inner"].values, stiff["ball_load_inner"].values
    assert np.abs(ls[-1] - lb[-1]).max() < 0.01 * lb[-1].max()
    assert stiff.summary()["ratio_simulated_over_theoretical"] == pytest.approx(1.0, abs=2e-3)
    real = Simulation(rv, model="flexible").run(t_end=t_end)
    assert abs(real["te"].sel(time=window).values.mean() - te_b.mean()) < 1.0


def test_condensed_rings_match_the_uncondensed_formulation(rings):
    """Static condensation (issue 15) against the uncondensed formulation (the
    rings' massless modal coordinates as system coordinates, same kernel): :cite:`seed001`'s 20 kN radial + 15
    kN axial case on the standalone bearing, both rings
    flexible, both rows. Ball loads and raceway deflections at the contacts agree
    within 1e-6 of their maxima (measured 2e-9 and 2e-8: the local solve's
    tolerance 1e-13 m on ~1 um deflections, and the static solver's), the
    frame displacement within 1e-6, the recovered modal amplitudes within 1e-6
    (measured 2e-9). Evaluated at the SAME state (the uncondensed solution's
    frame and balls), the condensed element reproduces the uncondensed ring's
    deflections B q and contact loads within 1e-6 (ring equilibrium K q = sum
    B^T g holds for the uncondensed solution)."""
    rv, out = rings
    rows_c, ev_c, frame_c, q_c = _static_rig(rv, SEED001_FORCE, rows=_flexible_rows(rv, out), coordinates=True)
    rows_f, ev_f, frame_f, q_f = _static_rig(
        rv, SEED001_FORCE, rows=_flexible_rows(rv, out, condense=False), coordinates=True
    )
    assert rows_c[0].n_coordinates == 6 + 3 * rows_c[0].ball_count  # no ring coordinates left
    assert rows_f[0].n_coordinates > rows_c[0].n_coordinates + 200
    np.testing.assert_allclose(frame_c[:3], frame_f[:3], rtol=0, atol=1e-6 * np.abs(frame_f[:3]).max())
    for k in range(2):
        _, _, _, sb = rows_f[k].slices()
        q_same = np.concatenate([q_f[k][:6], q_f[k][sb]])
        ev_same = evaluate_row(rows_c[k], q_same, np.zeros_like(q_same), jacobian=False)
        for label in ("inner", "outer"):
            a, b = getattr(ev_c[k], label), getattr(ev_f[k], label)
            assert b.load.max() > 1000.0 and np.abs(b.displacement).max() > 5e-7
            np.testing.assert_allclose(a.load, b.load, rtol=0, atol=1e-6 * b.load.max())
            np.testing.assert_allclose(a.displacement, b.displacement, rtol=0, atol=1e-6 * np.abs(b.displacement).max())
            qm_c = ring_modal_coordinates(rows_c[k], label, q_c[k], ev_c[k])
            qm_f = ring_modal_coordinates(rows_f[k], label, q_f[k], ev_f[k])
            np.testing.assert_allclose(qm_c, qm_f, rtol=0, atol=1e-6 * np.abs(qm_f).max())
            s = getattr(ev_same, label)
            np.testing.assert_allclose(s.displacement, b.displacement, rtol=0, atol=1e-6 * np.abs(b.displacement).max())
            np.testing.assert_allclose(s.load, b.load, rtol=0, atol=1e-6 * b.load.max())


def _fd(row, q, qt, which, h):
    """Central differences of the row force w.r.t. q (which = 0) or q_t (1)."""
    n = q.size
    jac = np.zeros((n, n))
    for k in range(n):
        d = np.zeros(n)
        d[k] = h
        args_p = (q + d, qt) if which == 0 else (q, qt + d)
        args_m = (q - d, qt) if which == 0 else (q, qt - d)
        jac[:, k] = (
            evaluate_row(row, *args_p, jacobian=False).force - evaluate_row(row, *args_m, jacobian=False).force
        ) / (2 * h)
    return jac


@pytest.mark.parametrize("ehl", ["dry", "hamrock_dowson"])
def test_condensed_row_jacobian_vs_finite_difference(rings, ehl):
    """The condensed tangent (I - K C)^-1 K of the contacts in series with the
    rings (both rings flexible, row 1 mirrored) against central differences of
    the exact condensed force at a loaded state with um displacements, mrad tilts
    and a turning frame: within 2 % of the largest entry (the geometric-stiffness
    terms of the frame rotation and of the compliance's azimuth dependence are
    dropped by design, as in the rigid-ring element); the ball-ball block, which
    the condensation makes dense, within 1 %, and its off-diagonal (ball-to-ball
    coupling through the ring) is non-zero. Velocity Jacobian likewise, except the
    frame-spin column (the EHL film's dependence on the entrainment speed is not
    in the analytic tangent, as in the rigid-ring element)."""
    rv, out = rings
    rows = _flexible_rows(rv, out, ehl=ehl)
    rng = np.random.default_rng(7)
    for row in rows:
        n = row.n_coordinates
        q = rng.normal(scale=1e-6, size=n)
        q[0:3] = [2e-5, -1e-5, 1e-5]
        q[3:6] = rng.normal(scale=1e-5, size=3)
        q[5] = 0.3
        qt = rng.normal(scale=1e-4, size=n)
        qt[5] = 1.2
        ev = evaluate_row(row, q, qt, jacobian=True)
        assert ev.inner.load.max() > 100.0
        jq = _fd(row, q, qt, 0, 1e-10)
        assert np.abs(ev.jac_q - jq).max() < 0.02 * np.abs(jq).max()
        _, _, _, sb = row.slices()
        blk, blk_fd = ev.jac_q[sb, sb], jq[sb, sb]
        assert np.abs(blk - blk_fd).max() < 0.01 * np.abs(blk_fd).max()
        assert np.abs(blk[0:3, 3:6]).max() > 1e-4 * np.abs(blk).max()
        jv = _fd(row, q, qt, 1, 1e-6)
        keep = np.arange(n) != 5  # the film's entrainment-speed dependence on the frame spin is not in the tangent
        assert np.abs(ev.jac_v - jv)[:, keep].max() < 0.02 * np.abs(jv[:, keep]).max()


def _loaded_history(rv, out, n_samples=12, ehl="hamrock_dowson"):
    """Rows with both rings condensed and a short history of element states around
    :cite:`seed001`'s loaded static state (sub-um ball and frame perturbations, a
    turning frame): (rows, [(q (T, n), q_t (T, n)) per row])."""
    rows, _, _, qs = _static_rig(rv, SEED001_FORCE, rows=_flexible_rows(rv, out, ehl=ehl), coordinates=True)
    rng = np.random.default_rng(11)
    hist = []
    for q0 in qs:
        q = q0 + rng.normal(scale=2e-8, size=(n_samples, q0.size))
        q[:, 5] = q0[5] + 0.01 * np.arange(n_samples)
        qt = rng.normal(scale=1e-4, size=q.shape)
        qt[:, 5] = 1.2
        hist.append((q, qt))
    return rows, hist


def test_output_pass_equals_per_sample_kernel_calls(rings):
    """The outputs pass (issue 15: one compiled loop per row over the samples,
    :func:`flexrv.model.bearing_kernel.row_history`) returns exactly (bit for bit)
    the forces and per-ball records of one :func:`row_kernel` call per sample in
    the same order (same warm starts of the condensed rings' local solves); and
    the condensed rings' modal amplitudes recovered from the records
    (:func:`ring_modal_amplitudes`) equal K^-1 sum_j B(psi_j)^T g_j computed here
    with the reduced body's own raceway basis (numpy,
    :meth:`flexrv.fem.body.ReducedBody.raceway_matrix`) within 1e-10 of their
    largest entry."""
    from flexrv.model.bearing_kernel import N_RECORD, RECORD_FIELDS, ring_modal_amplitudes, row_history, row_kernel
    from flexrv.model.flexible_bearing import kernel_inputs

    rv, out = rings
    rows, hist = _loaded_history(rv, out)
    col = {name: i for i, name in enumerate(RECORD_FIELDS)}
    for row, (q, qt) in zip(rows, hist):
        inputs = kernel_inputs(row)
        ws = [inputs.ws_i.copy(), inputs.ws_o.copy()]
        recs = np.zeros((q.shape[0], row.ball_count, N_RECORD))
        forces = row_history(q, qt, inputs, recs)
        inputs.ws_i[:], inputs.ws_o[:] = ws
        for i in range(q.shape[0]):
            rec = np.zeros((row.ball_count, N_RECORD))
            f, _, _ = row_kernel(q[i], qt[i], inputs, False, rec)
            np.testing.assert_array_equal(forces[i], f)
            np.testing.assert_array_equal(recs[i], rec)
        assert recs[:, :, col["load_outer"]].max() > 1000.0
        for label in ("inner", "outer"):
            ring = getattr(row, label)
            s = label[0]
            psi = recs[:, :, col[f"psi_{label}"]]
            g = np.ascontiguousarray(recs[:, :, [col[f"g{s}x"], col[f"g{s}y"], col[f"g{s}z"]]])
            got = ring_modal_amplitudes(
                np.ascontiguousarray(psi),
                g,
                ring.table,
                -1.0 if ring.mirror else 1.0,
                np.ascontiguousarray(ring.compliance_diag),
            )
            ref = np.stack(
                [
                    ring.compliance_diag * np.einsum("jcm,jc->m", ring.groove_basis(psi[i]), g[i])
                    for i in range(psi.shape[0])
                ]
            )
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10 * np.abs(ref).max())


def test_condensed_tangent_equals_direct_solve():
    """The condensed contact stiffness and damping of
    :func:`_condensed_contact_matrix` (issue 15: one 2Z x 2Z inverse through the
    push-through and Woodbury identities) equal the direct solutions
    (I - K C)^-1 K and -(I - K C)^-1 N diag(c) N^T (numpy.linalg.solve on 3Z x 3Z)
    within 1e-11 of their largest entries, for 9 balls with random rank-2 contact
    blocks K_j = -V_j V_j^T (one unloaded: zero block and damping) and a random
    symmetric positive semi-definite compliance C = W W^T of rank below 3Z."""
    from flexrv.model.bearing_kernel import _condensed_contact_matrix

    rng = np.random.default_rng(5)
    nz, m = 9, 20
    n = rng.normal(size=(nz, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    cd = rng.uniform(10.0, 100.0, nz)
    factors = 1e4 * rng.normal(size=(nz, 2, 3))
    factors[2] = 0.0
    cd[2] = 0.0
    w = 1e-5 * rng.normal(size=(3 * nz, m))
    kq, kv = _condensed_contact_matrix(factors, n, cd, w)
    cmat = w @ w.T
    k = np.zeros((3 * nz, 3 * nz))
    nn = np.zeros((3 * nz, nz))
    for j in range(nz):
        k[3 * j : 3 * j + 3, 3 * j : 3 * j + 3] = -factors[j].T @ factors[j]
        nn[3 * j : 3 * j + 3, j] = n[j]
    a = np.eye(3 * nz) - k @ cmat
    ref_q = np.linalg.solve(a, k)
    ref_v = -np.linalg.solve(a, nn) @ np.diag(cd) @ nn.T
    assert np.abs(k @ cmat).max() > 0.1  # the ring compliance matters
    np.testing.assert_allclose(kq, ref_q, rtol=0, atol=1e-11 * np.abs(ref_q).max())
    np.testing.assert_allclose(kv, ref_v, rtol=0, atol=1e-11 * np.abs(ref_v).max())


def test_contact_factors_are_the_contact_blocks():
    """:func:`_contact_factors` V with -V V^T against the stiffness block of
    :func:`_contact_blocks` (the one formula of the contact tangent): equal within
    1e-14 of dQ/d delta for a normal in the ball's meridian plane (normal to the
    azimuth direction e_t, the rigid-ring geometry), and within Q/L |n.e_t| (2 + 1e-9)
    when a ring's tangential deflection tilts it out of that plane (|n.e_t| = 1e-5:
    the difference is ~1e-5 of the geometric term, itself Q/L / (dQ/d delta) ~ 1e-2)."""
    from flexrv.model.bearing_kernel import _contact_blocks, _contact_factors

    psi = 0.7
    et = np.array([-np.sin(psi), np.cos(psi), 0.0])
    er = np.array([np.cos(psi), np.sin(psi), 0.0])
    q_load, dq, length = 120.0, 8e7, 3e-4
    for tilt in (0.0, 1e-5):
        n = np.cos(0.6) * er + np.sin(0.6) * np.array([0.0, 0.0, 1.0]) + tilt * et
        n /= np.linalg.norm(n)
        stiff, damp, v = np.empty((3, 3)), np.empty((3, 3)), np.empty((2, 3))
        _contact_blocks(q_load, dq, 5.0, length, *n, et[0], et[1], stiff, damp)
        _contact_factors(q_load, dq, length, *n, et[0], et[1], v)
        diff = np.abs(-v.T @ v - stiff).max()
        ql, c = q_load / length, abs(n @ et)
        if tilt == 0.0:
            assert diff <= 1e-14 * dq
        else:
            assert 0.5 * ql * c <= diff <= ql * c * (2.0 + 1e-9)


@pytest.mark.parametrize("speed", [0.0, 0.08, 0.4])
def test_kernel_normal_law_equals_ehl_law(speed):
    """The row kernel's normal law (issue 15: speed terms once per ring and call,
    :func:`_law_speed`; the film Newton stops at its bit-exact fixed point;
    s^1.5 as s sqrt(s)) equals EHLPointLaw(mode="hamrock_dowson") of
    flexrv.ehl.law (numpy, all ``iterations`` Newton steps) within 1e-12 relative
    in load and film, and its approach derivative dQ/d delta within 1e-5 of
    central differences of that law (step 1e-12 m: round-off limited), from out of contact through the load
    floor to 5 um approach, with approach rates of both signs (contact damping).
    At speed 0 the law is dry Hertz."""
    from flexrv.model.bearing_kernel import _law_speed, _normal_load, law_parameters

    rv = load("rv221")
    law = rows_from_design(rv, ehl="hamrock_dowson")[0].law_inner
    p = law_parameters(law)
    delta = np.concatenate([np.linspace(-2e-6, 1e-8, 7), np.geomspace(1e-9, 5e-6, 30)])
    rate = np.where(np.arange(delta.size) % 2 == 0, 1e-4, -2e-4)
    terms = _law_speed(speed, p)
    got = np.array([_normal_load(d, r, *terms, p) for d, r in zip(delta, rate)])
    ref = law(delta, rate, speed)
    assert (ref.force > 0).sum() > 25 and (ref.force == 0).sum() >= 5
    np.testing.assert_allclose(got[:, 0], ref.force, rtol=1e-12, atol=1e-12 * ref.force.max())
    if speed > 0:
        assert ref.film.max() > 1e-8
        loaded = ref.force > 0
        np.testing.assert_allclose(got[loaded, 3], ref.film[loaded], rtol=1e-12)
    h = 1e-12
    loaded = delta > 1e-7
    d_ref = (law(delta + h, rate, speed).force - law(delta - h, rate, speed).force) / (2 * h)
    np.testing.assert_allclose(got[loaded, 1], d_ref[loaded], rtol=1e-5)


@pytest.mark.parametrize("ehl", ["hamrock_dowson", "map"])
def test_film_warm_start_same_fixed_point(ehl):
    """The film iteration started from a previous film (issue 15: the row kernel keeps
    each contact's film of the last call, bearing_kernel._normal_load's h_start) stops
    at the same fixed point s = delta + h(k s^1.5) as the cold start from the load
    floor's film: loads, films, dQ/d delta and dQ/d rate within 1e-14 relative (the
    stop rule's bound: 0.75 (1e-8)^2 < 1e-16, plus round-off), from films of a
    neighbouring state (approach 1e-4 relative apart: a solver step), from the
    solution itself, and from films 10x too thick or thin (a far warm start still
    converges, only slower); rv221's inner contact at 0.08 m/s, 1 nm to 5 um
    approach."""
    from flexrv.model.bearing_kernel import _law_speed, _normal_load, law_parameters

    law = rows_from_design(load("rv221"), ehl=ehl)[0].law_inner
    p = law_parameters(law)
    terms = _law_speed(0.08, p)
    delta = np.geomspace(1e-9, 5e-6, 25)
    cold = np.array([_normal_load(d, 1e-4, *terms, p) for d in delta])
    assert np.all(cold[:, 0] > 0) and np.all(cold[:, 3] > 1e-8)
    for start in (
        np.array([_normal_load(d * (1 + 1e-4), 1e-4, *terms, p)[3] for d in delta]),
        cold[:, 3],
        10.0 * cold[:, 3],
        0.1 * cold[:, 3],
    ):
        warm = np.array([_normal_load(d, 1e-4, *terms, p, h) for d, h in zip(delta, start)])
        np.testing.assert_allclose(warm, cold, rtol=1e-14, atol=0)
