"""Main-bearing subsystem in Exudyn (rigid balls, rigid or modal rings): statics vs
closed forms; analytic Jacobian vs finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from flexrv.contact.hertz import series_stiffness
from flexrv.design import load
from flexrv.geometry.bearing import BallBearingGeometry
from flexrv.model.flexible_bearing import add_main_bearing, evaluate_row, rows_from_design


def _static_rig(reducer, load_vec, moment=(0.0, 0.0, 0.0), rows=None, coordinates=False):
    """Static equilibrium of the standalone bearing (frame on the balls, rotation
    about z held) under a force and moment on the frame. Returns rows, row
    evaluations, frame coordinates and, with ``coordinates``, each row element's q."""
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateConstraint,
        LoadForceVector,
        LoadTorqueVector,
        MarkerNodeCoordinate,
        MarkerNodeRigid,
        NodePointGround,
        NodeRigidBodyRxyz,
        ObjectRigidBody,
    )
    from exudyn.utilities import RigidBodyInertia

    rows = rows or rows_from_design(reducer, ehl="dry")
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    frame = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[0.0] * 6))
    inertia = RigidBodyInertia(mass=10.0, inertiaTensor=np.diag([0.05, 0.05, 0.1]))
    mbs.AddObject(ObjectRigidBody(mass=10.0, inertia=inertia.GetInertia6D(), nodeNumber=frame))
    handle = add_main_bearing(mbs, rows, frame)
    ground = mbs.AddNode(NodePointGround())
    mbs.AddObject(
        CoordinateConstraint(
            markerNumbers=[
                mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0)),
                mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=frame, coordinate=5)),
            ]
        )
    )
    marker = mbs.AddMarker(MarkerNodeRigid(nodeNumber=frame))
    mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=list(load_vec)))
    mbs.AddLoad(LoadTorqueVector(markerNumber=marker, loadVector=list(moment)))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.staticSolver.verboseMode = 0
    settings.staticSolver.numberOfLoadSteps = 10
    settings.staticSolver.newton.absoluteTolerance = 1e-6
    exu.SolveStatic(mbs, settings)
    evals, qs = [], []
    for k in range(len(rows)):
        q, q_t = handle.element_coordinates(mbs, k)
        evals.append(evaluate_row(rows[k], q, q_t, jacobian=False))
        qs.append(q)
    frame_q = np.asarray(mbs.GetNodeOutput(frame, exu.OutputVariableType.Coordinates))
    if coordinates:
        return rows, evals, frame_q, qs
    return rows, evals, frame_q


@pytest.mark.parametrize("name,fa", [("rv221", 15000.0), ("rv40e", 2000.0)])
def test_axial_load_closed_form(name, fa):
    """Pure axial load on a back-to-back pair: the loaded row's balls share it
    equally, Fa = Z Q sin(a') with Q = K_s (A' - A)^1.5 and A' from the axial
    shift (preload + frame displacement) (Harris & Kotzalas 2007, sec. 7.2).
    The frame displacement and ball load agree with the scalar root of that
    equation within 0.1 % (weak pocket springs and the unloaded row's residual
    preload are the difference)."""
    reducer = load(name)
    rows, evals, frame_q = _static_rig(reducer, (0.0, 0.0, fa))
    geom = BallBearingGeometry.from_design(reducer.main_bearing)
    loaded = evals[0] if evals[0].inner.load.mean() > evals[1].inner.load.mean() else evals[1]
    q = loaded.inner.load
    assert np.ptp(q) < 1e-6 * q.mean()
    a, a0 = geom.curvature_center_distance, geom.contact_angle
    ks = series_stiffness(rows[0].row.k_inner, rows[0].row.k_outer)
    z = geom.ball_count

    def axial(e):
        ap = math.hypot(a * math.cos(a0), a * math.sin(a0) + e)
        return z * ks * max(ap - a, 0.0) ** 1.5 * (a * math.sin(a0) + e) / ap - fa

    e = brentq(axial, 0.0, 1e-3)
    ap = math.hypot(a * math.cos(a0), a * math.sin(a0) + e)
    q_expected = ks * (ap - a) ** 1.5
    assert q.mean() == pytest.approx(q_expected, rel=1e-3)
    assert abs(frame_q[2]) == pytest.approx(e - geom.axial_preload, rel=1e-2)
    assert np.sum(-loaded.inner.force_ball[:, 2]) == pytest.approx(
        math.copysign(fa, np.sum(-loaded.inner.force_ball[:, 2])), rel=1e-6
    )


def test_radial_load_balance_and_zone():
    """Radial load: forces balance the load, the loaded zone faces the load and
    the most loaded ball sits at the load direction."""
    reducer = load("rv221")
    fr = 20000.0
    rows, evals, frame_q = _static_rig(reducer, (fr, 0.0, 0.0))
    # force of the balls on the inner ring (= frame) balances the external load
    on_frame = sum(-(ev.inner.force_ball).sum(axis=0) for ev in evals)
    np.testing.assert_allclose(on_frame, [-fr, 0.0, 0.0], atol=1e-6 * fr)
    for ev in evals:
        j = np.argmax(ev.inner.load)
        assert abs(np.angle(np.exp(1j * ev.azimuth[j]))) < 2 * np.pi / 26 + 1e-9
    assert frame_q[0] > 0


def _random_state(model, seed):
    """A random element state near the reference: µm displacements, 1e-5 rad tilts."""
    rng = np.random.default_rng(seed)
    n = model.n_coordinates
    q = rng.normal(scale=1e-6, size=n)
    q[3:6] = rng.normal(scale=1e-5, size=3)
    return q, rng.normal(scale=1e-3, size=n)


def _fd_jacobian(model, q, qt, h=1e-10):
    """Central-difference d force / d q of a row element."""
    n = q.size
    jac = np.zeros((n, n))
    for k in range(n):
        dq = np.zeros(n)
        dq[k] = h
        jac[:, k] = (evaluate_row(model, q + dq, qt, False).force - evaluate_row(model, q - dq, qt, False).force) / (
            2 * h
        )
    return jac


def test_jacobian_vs_finite_difference():
    """Analytic Jacobian within 2 % of central differences (geometric-stiffness
    terms of the frame rotation are neglected by design)."""
    rows = rows_from_design(load("rv221"), ehl="dry")
    m = rows[0]
    q, qt = _random_state(m, seed=0)
    ev = evaluate_row(m, q, qt)
    jac = _fd_jacobian(m, q, qt)
    assert np.abs(jac - ev.jac_q).max() < 0.02 * np.abs(jac).max()


@pytest.mark.parametrize(
    "name,force,moment",
    [
        ("rv221", (20000.0, 0.0, 15000.0), (0.0, 0.0)),
        ("rv221", (5000.0, 0.0, 2000.0), (0.0, 1500.0)),
        ("rv40e", (3000.0, 0.0, 2000.0), (0.0, 0.0)),
    ],
)
def test_rigid_ring_limit_matches_analytic_distribution(name, force, moment):
    """Stiff-ring limit: the ball-resolved Exudyn bearing (free balls, cage, rigid
    rings) and the foundation's 5-DOF quasi-static distribution
    (:func:`flexrv.analysis.bearing_load.ball_load_distribution`, balls eliminated
    through the groove-centre distance) are independent implementations of the
    same physics. Ball loads agree within 1 % of the maximum load, ring
    displacements within 1 %."""
    from flexrv.analysis.bearing_load import ball_load_distribution
    from flexrv.contact.hertz import effective_modulus

    reducer = load(name)
    geom = BallBearingGeometry.from_design(reducer.main_bearing)
    ring, ball = reducer.material("bearing_rings"), reducer.material("rolling_elements")
    e_eff = float(effective_modulus(ring.youngs_modulus, ring.poisson_ratio, ball.youngs_modulus, ball.poisson_ratio))
    analytic = ball_load_distribution(geom, e_eff, force=force, moment=moment)
    rows, evals, frame_q = _static_rig(reducer, force, (moment[0], moment[1], 0.0))
    exudyn_loads = np.array([ev.inner.load for ev in evals])
    scale = analytic.loads.max()
    assert np.abs(exudyn_loads - analytic.loads).max() < 0.01 * scale
    np.testing.assert_allclose(
        frame_q[:3], analytic.displacement[:3], atol=0.01 * np.abs(analytic.displacement[:3]).max()
    )


class _FourierRing:
    """Synthetic RingModes: radial/axial Fourier deflection shapes (k = 0..2) as a
    cylindrical raceway table (the kernel's ring input), enough to exercise the
    modal coupling paths of the contact element."""

    mirror = False
    condensed = False

    def __init__(self, scale=1.0, n_grid=64):
        self.m = 5
        self.mass = np.eye(self.m)
        self.stiffness = np.diag(np.full(self.m, 4e7))
        self.damping = np.zeros((self.m, self.m))
        a = 2 * np.pi * np.arange(n_grid) / n_grid
        one, zero = np.ones(n_grid), np.zeros(n_grid)
        table = np.zeros((n_grid, 3, self.m))
        table[:, 0, :] = np.stack([one, np.cos(2 * a), np.sin(2 * a), zero, zero], -1)
        table[:, 2, :] = np.stack([zero, zero, zero, one, np.cos(a)], -1)
        self.table = scale * table


def test_jacobian_with_modal_rings_vs_finite_difference():
    """Modal (flexible) inner and outer rings: analytic Jacobian within 2 % of
    central differences, including the modal rows and columns."""
    reducer = load("rv221")
    rows = rows_from_design(
        reducer, inner=[_FourierRing(), _FourierRing()], outer=[_FourierRing(), _FourierRing()], ehl="dry"
    )
    m = rows[0]
    q, qt = _random_state(m, seed=2)
    ev = evaluate_row(m, q, qt)
    jac = _fd_jacobian(m, q, qt)
    assert np.abs(jac - ev.jac_q).max() < 0.02 * np.abs(jac).max()
    _, si, so, _ = m.slices()
    assert np.abs(jac[si, si]).max() > 0 and np.abs(jac[so, so]).max() > 0


@pytest.mark.slow
def test_reducer_with_ball_bearing_matches_rigid_model():
    """Consistency (issue 6): the reducer model with the ball-resolved main bearing
    (rigid rings) keeps the kinematic ratio in the mean and reproduces the rigid
    model's loaded TE level within 2 arcsec at the end of the load ramp: the main
    bearing's radial/tilt compliance acts on the cycloid stage only through the
    carrier's small displacement."""
    from flexrv.simulation import Simulation

    t_end = 0.3
    rigid = Simulation("rv40e", model="rigid").run(t_end=t_end)
    balls = Simulation("rv40e", model="balls").run(t_end=t_end)
    te_r = rigid["TE [arcsec]"].sel(time=slice(0.25, None)).values.mean()
    te_b = balls["TE [arcsec]"].sel(time=slice(0.25, None)).values.mean()
    assert abs(te_b - te_r) < 2.0
    assert balls.summary()["ratio_simulated_over_theoretical"] == pytest.approx(1.0, abs=2e-3)
    assert np.all(balls["ball_load_inner"].values >= 0)


def test_reducer_with_ball_bearing_runs_and_balances():
    """Short run of the reducer with the ball-resolved bearing (rv40e, 10 ms):
    the bearing's ball loads are non-negative and the preloaded rows carry the
    carrier (radial reaction finite, axial reaction ~0 without external load)."""
    from flexrv.simulation import Simulation

    res = Simulation("rv40e", model="balls").run(t_end=0.01)
    loads = res["ball_load_inner"].values
    assert loads.shape[1:] == (2, 38) and np.all(loads >= 0) and loads.max() > 0
    assert np.all(np.isfinite(res["TE [arcsec]"].values))
    assert abs(res["main_bearing_axial_force"].values[-1]) < 50.0


@pytest.fixture(scope="module")
def map_rows():
    """rv221 rows whose ball laws are EHLPointLaw in mode "map", each with a small solver
    map of its own contact (3 x 3 nodes, 33^2 solver grid, loads 20-500 N, speeds
    0.02-0.2 m/s: coarse for speed; the identity tests below do not depend on the
    map's accuracy)."""
    from dataclasses import replace

    from flexrv.ehl.maps import build_film_map

    rows = rows_from_design(load("rv221"), ehl="hamrock_dowson")
    maps = {}
    with pytest.warns(RuntimeWarning, match="EHL map"):
        for side in ("law_inner", "law_outer"):
            law = getattr(rows[0], side)
            maps[side] = replace(
                law,
                mode="map",
                film_map=build_film_map(
                    law.rx, law.ry, law.e_eff, law.lubricant, (20.0, 500.0), (0.02, 0.2), n_load=3, n_speed=3, grid=33
                ),
            )
    return [replace(row, law_inner=maps["law_inner"], law_outer=maps["law_outer"]) for row in rows]


@pytest.mark.parametrize("omega", [1.0, 5.0])
def test_kernel_map_law_equals_ehl_law(map_rows, omega):
    """EHL mode "map" in the compiled row kernel: every ball's inner and outer normal
    load and central film equal EHLPointLaw(mode="map") evaluated directly
    (flexrv.ehl.law, numpy Newton solve) at the approach, approach rate and
    entrainment speed computed here from the row's geometry (rigid rings, frame
    rotation about z only), to 1e-9 relative. Carrier speed 1 rad/s puts the
    entrainment speed (0.077 m/s) inside the map, 5 rad/s (0.385 m/s) beyond it
    (clamped table); the loads span the preloaded and the unloaded balls."""
    from dataclasses import replace

    from flexrv.model.bearing_kernel import N_RECORD, RECORD_FIELDS, row_kernel
    from flexrv.model.flexible_bearing import kernel_inputs

    m = map_rows[0]
    rng = np.random.default_rng(7)
    n = m.n_coordinates
    q = rng.normal(scale=3e-6, size=n)
    q[3:5] = 0.0
    q[5] = 0.1
    qt = rng.normal(scale=1e-3, size=n)
    qt[3:5] = 0.0
    qt[5] = omega
    rec = np.zeros((m.ball_count, N_RECORD))
    row_kernel(q, qt, kernel_inputs(m), False, rec)
    col = {name: i for i, name in enumerate(RECORD_FIELDS)}
    row = m.row
    b0 = n - 3 * m.ball_count
    ball = m.ball_reference + q[b0:].reshape(-1, 3)
    vel = qt[b0:].reshape(-1, 3)
    c, s = math.cos(q[5]), math.sin(q[5])
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    local = (ball - q[:3]) @ rot
    psi_i = np.arctan2(local[:, 1], local[:, 0])
    centre_i = (
        np.c_[
            row.inner_center_radius * np.cos(psi_i),
            row.inner_center_radius * np.sin(psi_i),
            np.full(psi_i.size, row.inner_center_z + m.z),
        ]
        @ rot.T
    )
    e_i = ball - q[:3] - centre_i
    w_i = vel - qt[:3] - np.cross([0.0, 0.0, omega], centre_i)
    psi_o = np.arctan2(ball[:, 1], ball[:, 0])
    e_o = (
        ball
        - np.c_[
            row.outer_center_radius * np.cos(psi_o),
            row.outer_center_radius * np.sin(psi_o),
            np.full(psi_o.size, row.outer_center_z + m.z),
        ]
    )
    speed = m.speed_factor * omega
    for label, e, w, offset, law in (
        ("inner", e_i, w_i, row.inner_offset, m.law_inner),
        ("outer", e_o, vel, row.outer_offset, m.law_outer),
    ):
        length = np.linalg.norm(e, axis=1)
        rate = np.sum(e * w, axis=1) / length
        ref = law(length - offset, rate, speed)
        loaded = ref.force > 0
        assert loaded.sum() >= 5 and (~loaded).sum() >= 1
        assert ref.force.max() > 20.0  # inside the map's load range
        np.testing.assert_allclose(rec[:, col[f"load_{label}"]], ref.force, rtol=1e-9, atol=1e-9 * ref.force.max())
        film = rec[:, col[f"film_{label}"]]
        np.testing.assert_allclose(film, ref.film, rtol=1e-9, atol=1e-9 * ref.film.max())
        # the map's correction is active: the film differs from Hamrock-Dowson's
        hd = replace(law, mode="hamrock_dowson", film_map=None)(length - offset, rate, speed).film
        assert np.abs(film[loaded] / hd[loaded] - 1).min() > 1e-3


def test_jacobian_with_map_law_vs_finite_difference(map_rows):
    """EHL mode "map": the row kernel's analytic Jacobian (dQ/d delta through the
    map's d ln h / d ln Q) within 2 % of central differences (as for the dry law, the
    frame rotation's geometric-stiffness terms are neglected by design), and the
    ball-ball block, which holds the contact law's derivative, within 1e-5 of the
    largest entry at the carrier speed 1 rad/s (entrainment speed inside the map)."""
    m = map_rows[0]
    q, qt = _random_state(m, seed=3)
    qt[5] = 1.0
    ev = evaluate_row(m, q, qt)
    jac = _fd_jacobian(m, q, qt)
    scale = np.abs(jac).max()
    assert np.abs(jac - ev.jac_q).max() < 0.02 * scale
    _, _, _, sb = m.slices()
    assert np.abs(jac[sb, sb] - ev.jac_q[sb, sb]).max() < 1e-5 * scale
    assert ev.inner.load.max() > 20.0


def test_kernel_refuses_a_law_it_does_not_cover():
    """A law outside the kernel (an EHL law with one radius per contact) is refused
    with a ConfigError naming the supported contact.ehl modes."""
    from dataclasses import replace

    from flexrv.errors import ConfigError
    from flexrv.model.flexible_bearing import kernel_inputs

    row = rows_from_design(load("rv221"), ehl="hamrock_dowson")[0]
    law = row.law_inner
    bad = replace(row, law_inner=replace(law, rx=np.full(row.ball_count, law.rx), ry=np.full(row.ball_count, law.ry)))
    with pytest.raises(ConfigError, match="'dry', 'hamrock_dowson' or 'map'"):
        kernel_inputs(bad)


def test_row_element_glue_equals_kernel():
    """The compiled element glue (issue 15, :class:`RowElement`: gather from the nodes'
    order, reference subtracted from absolute ball positions, kernel, scatter, and
    Exudyn's -(f_q dF/dq + f_v dF/dq_t)) returns what :func:`evaluate_row` gives for
    the same element state, permuted to the nodes' order of the reducer model (frame
    coordinates reordered as the carrier's), within 1e-13 of the largest entry: the
    calls share the row's film warm starts (:func:`flexrv.model.bearing_kernel._normal_load`),
    so each starts the film iteration from the previous call's films and their loads
    agree to round-off, not bit for bit (a glue error would be O(1)); its output
    arrays are reused by the next call, as Exudyn copies them."""
    from flexrv.model.flexible_bearing import _PERM, RowElement

    model = rows_from_design(load("rv40e"), ehl="hamrock_dowson")[1]
    q, qt = _random_state(model, seed=3)
    qt[5] = 1.3  # carrier spin: the films see an entrainment speed
    idx = np.concatenate([_PERM, np.arange(6, model.n_coordinates)])
    inv = np.argsort(idx)
    qn = q.copy()
    qn[6:] += model.ball_reference.ravel()  # absolute ball positions
    qn, vn = qn[inv], qt[inv]  # the nodes' order: element coordinate e is node coordinate idx[e]
    element = RowElement(model, idx, absolute=True)
    ev = evaluate_row(model, q, qt, jacobian=True)
    f_q, f_v = 0.37, 1.9e3
    ref_j = (-(f_q * ev.jac_q + f_v * ev.jac_v))[np.ix_(inv, inv)]
    for _ in range(2):  # second call: entry point, reused arrays
        force = element.force(list(qn), list(vn))
        np.testing.assert_allclose(force, ev.force[inv], rtol=0, atol=1e-13 * np.abs(ev.force).max())
        jac = element.jacobian(list(qn), list(vn), f_q, f_v)
        np.testing.assert_allclose(jac, ref_j, rtol=0, atol=1e-13 * np.abs(ref_j).max())
    assert element.stats == [2, 2]
    assert np.abs(ev.force).max() > 1.0


def test_film_speed_jacobian_vs_finite_difference():
    """d force / d q_t includes the films' entrainment-speed term (issue 15): the
    Hamrock-Dowson film grows as u^0.67 with u = speed_factor |omega_z|, so every
    loaded contact's load depends on the carrier's spin rate. The column of
    omega_z (element coordinate 5) matches central differences of the force
    within 1e-5 of its largest entry (it was missing before: 98 % error), and
    the film term is most of that column (the cage's share is checked apart)."""
    model = rows_from_design(load("rv40e"), ehl="hamrock_dowson")[0]
    q, qt = _random_state(model, seed=4)
    q[6:] = 0.0
    q[6 + 2 :: 3] = -2e-7  # axial preload side: every ball loaded
    qt[:] = 0.0
    qt[5] = 1.1
    ev = evaluate_row(model, q, qt, jacobian=True)
    h = 1e-6
    up, dn = qt.copy(), qt.copy()
    up[5] += h
    dn[5] -= h
    fd = (evaluate_row(model, q, up, False).force - evaluate_row(model, q, dn, False).force) / (2 * h)
    assert np.abs(ev.jac_v[:, 5] - fd).max() < 1e-5 * np.abs(fd).max()
    # the cage's tangential damper alone (a dry law has no film): a much smaller column
    dry = rows_from_design(load("rv40e"), ehl="dry")[0]
    cage = evaluate_row(dry, q, qt, jacobian=True).jac_v[:, 5]
    assert np.abs(fd - cage).max() > 0.5 * np.abs(fd).max()


def test_two_rows_one_element():
    """Both rows in one element (the glue's multi-row form, :class:`RowElement`): the
    force and Exudyn Jacobian are the sums of the rows' own
    (:func:`evaluate_row`) scattered to the shared carrier and each row's balls,
    equal to round-off (1e-14 of the largest entry; the carrier entries are sums
    of two terms), and the row-row blocks are exact zeros."""
    from flexrv.model.flexible_bearing import _PERM, RowElement

    rows = rows_from_design(load("rv221"), ehl="hamrock_dowson")
    nb = [r.n_coordinates - 6 for r in rows]
    n = 6 + sum(nb)
    idxs = [np.concatenate([_PERM, np.arange(6, 6 + nb[0])]), np.concatenate([_PERM, np.arange(6 + nb[0], n)])]
    rng = np.random.default_rng(7)
    carrier_q, carrier_v = rng.normal(scale=1e-6, size=6), rng.normal(scale=1e-3, size=6)
    carrier_q[3:6] = rng.normal(scale=1e-5, size=3)
    carrier_v[2] = 0.9
    qn, vn = np.zeros(n), np.zeros(n)
    qn[:6], vn[:6] = carrier_q, carrier_v
    ref_f, ref_j = np.zeros(n), np.zeros((n, n))
    f_q, f_v = 0.5, 2e3
    for r, idx in zip(rows, idxs):
        q, qt = _random_state(r, seed=11)
        q[:6], qt[:6] = carrier_q[_PERM], carrier_v[_PERM]
        qn[idx[6:]] = q[6:] + r.ball_reference.ravel()
        vn[idx[6:]] = qt[6:]
        ev = evaluate_row(r, q, qt, jacobian=True)
        ref_f[idx] += ev.force
        ref_j[np.ix_(idx, idx)] += -(f_q * ev.jac_q + f_v * ev.jac_v)
    element = RowElement(rows, idxs, absolute=True)
    force = element.force(list(qn), list(vn))
    jac = element.jacobian(list(qn), list(vn), f_q, f_v)
    np.testing.assert_allclose(force, ref_f, rtol=0, atol=1e-14 * np.abs(ref_f).max())
    np.testing.assert_allclose(jac, ref_j, rtol=0, atol=1e-14 * np.abs(ref_j).max())
    assert not jac[6 : 6 + nb[0], 6 + nb[0] :].any() and not jac[6 + nb[0] :, 6 : 6 + nb[0]].any()


@pytest.mark.parametrize("preset", ["rv221", "rv40e"])
def test_ball_equilibrium_matches_the_static_ball_solver(preset):
    """Quasi-static balls (issue 15: the ball coordinates solved inside the row
    element, bearing_kernel.ball_equilibrium, a Newton per ball on row_eval's own
    3x3 ball blocks) at the reference frame and at rest give the ball positions of
    flexrv.contact.ball_raceway.solve_ball_positions (an independent vectorised
    Newton on the contact laws, through initial_ball_displacements) within 1e-15 m
    once the pocket spring, the one force that solver leaves out, is removed
    (measured 9e-17 / 3e-17 m on displacements of 2.8 / 1.1 um); with the preset's
    pocket spring (1e3 N/m) they move by less than 1 % (measured 6.5e-9 / 5.4e-9 m).
    Ball forces end below the tolerance (1e-10 of the row's largest load here) in
    <= 6 steps, also on a displaced, tilted, spinning frame; a warm restart after a
    0.1 nm frame move takes one or two Newton steps (the second when the balls'
    velocities, b_t = -K_bb^-1 K_bx x_t, moved their damping forces by more than
    the tolerance)."""
    from dataclasses import replace

    from flexrv.model.bearing_kernel import N_RECORD, ball_equilibrium
    from flexrv.model.flexible_bearing import initial_ball_displacements, kernel_inputs

    row = rows_from_design(load(preset), ehl="hamrock_dowson")[0]
    n, nz = row.n_coordinates, row.ball_count
    f, kbb, rec = np.empty(n), np.empty((3 * nz, 4)), np.empty((nz, N_RECORD))
    ref = initial_ball_displacements(row).ravel()
    bare = replace(row, pocket_stiffness=0.0)
    q, qt = np.zeros(n), np.zeros(n)
    assert 0 <= ball_equilibrium(q, qt, kernel_inputs(bare), 1e-10, 30, f, kbb, rec) <= 6
    assert np.abs(q[6:] - ref).max() < 1e-15
    q = np.zeros(n)
    assert 0 <= ball_equilibrium(q, qt, kernel_inputs(row), 1e-10, 30, f, kbb, rec) <= 6
    assert np.abs(f[6:]).max() <= 1e-10 * rec[:, :2].max()
    assert 1e-10 < np.abs(q[6:] - ref).max() < 0.01 * np.abs(ref).max()
    q[0], q[2], q[4], qt[5] = 2e-6, 1e-6, 1e-5, 1.3  # frame displaced, tilted, spinning
    assert 0 <= ball_equilibrium(q, qt, kernel_inputs(row), 1e-10, 30, f, kbb, rec) <= 6
    ev = evaluate_row(row, q, qt, False)
    assert np.abs(ev.force[6:]).max() <= 1e-10 * ev.inner.load.max() and ev.inner.load.max() > 40.0
    np.testing.assert_array_equal(rec[:, 0], ev.inner.load)  # the records of the last evaluation
    q[0] += 1e-10
    assert 1 <= ball_equilibrium(q, qt, kernel_inputs(row), 1e-10, 30, f, kbb, rec) <= 2


def _quasi_static_row(preset, tol=None):
    """Row 0 of a preset with quasi-static balls (EHL contacts), its local solve's
    relative tolerance set to ``tol`` (None: the kernel's BALL_FORCE_TOL)."""
    from flexrv.model.flexible_bearing import set_ball_force_tolerance

    row = rows_from_design(load(preset), ehl="hamrock_dowson", ball_inertia=False)[0]
    if tol is not None:
        set_ball_force_tolerance(row, tol)
    return row


_FRAME = (np.array([2e-6, 0.0, 1e-6, 0.0, 1e-5, 0.3]), np.array([1e-4, 0.0, 0.0, 0.0, 0.0, 1.3]))


@pytest.mark.parametrize("preset", ["rv221", "rv40e"])
def test_quasi_static_row_is_the_dynamic_row_at_ball_equilibrium(preset):
    """A row with quasi-static balls (RowModel.ball_inertia = False: the element has
    the frame's 6 coordinates only) returns the force on the frame of the same row
    with ball coordinates (one row_eval, no solve) evaluated at the balls it solved
    -- the same kernel at the same state, to round-off (1e-13 of the largest entry:
    the two rows' film iterations start from different films) -- and
    there every ball's force vanishes to its tolerance (1e-6 of the largest load,
    bearing_kernel.BALL_FORCE_TOL). The per-ball records (loads, normals, ball
    centres) are those of that state too. Checked along a path that turns the frame
    by 0.3 rad in one call (the prediction turns the balls with their cage) and
    then moves it by 10 nm steps (the prediction b + S dx)."""
    from flexrv.model.bearing_kernel import BALL_FORCE_TOL, _split_balls
    from flexrv.model.flexible_bearing import kernel_inputs

    qs_row = _quasi_static_row(preset)
    dyn = rows_from_design(load(preset), ehl="hamrock_dowson")[0]
    nz = dyn.ball_count
    assert qs_row.n_coordinates == 6 and dyn.n_coordinates == 6 + 3 * nz
    x, xt = _FRAME[0].copy(), _FRAME[1].copy()
    ws = kernel_inputs(qs_row).balls
    for step in range(4):
        ev = evaluate_row(qs_row, x, xt, jacobian=True)
        b, bt = (a.copy() for a in _split_balls(ws, 3 * nz, 6)[:2])
        ref = evaluate_row(dyn, np.concatenate([x, b]), np.concatenate([xt, bt]), jacobian=False)
        np.testing.assert_allclose(ev.force, ref.force[:6], rtol=0, atol=1e-13 * np.abs(ref.force).max())
        assert np.abs(ref.force[6:]).max() <= BALL_FORCE_TOL * ref.inner.load.max()
        np.testing.assert_allclose(ev.inner.load, ref.inner.load, rtol=1e-13)
        np.testing.assert_array_equal(ev.ball_pos, ref.ball_pos)
        assert ev.inner.load.max() > 40.0 and np.abs(ev.force[:3]).max() > 100.0
        x[0] += 1e-8
        x[5] += 1e-6
    assert kernel_inputs(qs_row).state[4] == 0  # no failed solve


@pytest.mark.parametrize("preset", ["rv221", "rv40e"])
def test_quasi_static_row_jacobian_vs_finite_difference(preset):
    """With quasi-static balls the row's force on the frame F(x, x_t) (the balls solved
    at every evaluation) has the Jacobians of row_eval's CONDENSED_BALLS mode (the
    Schur complement of each ball's 3x3 block, bearing_kernel._condense_ball, with
    b_t = S x_t), returned by the row kernel. Central differences (1e-9 m /
    1e-8 rad, 1e-5 m/s; the local solve's tolerance tightened to 1e-11 of the loads,
    ~1e-9 N over these steps, ~1 N/m against ~1e8) on a displaced, tilted, spinning,
    moving frame: within 1e-4 (stiffness) and 5e-4 (damping) of the largest entry
    (measured 1.7e-5 / 1.7e-5 and 7.0e-6 / 7.6e-5 on rv221 / rv40e: the left-out
    d S / d x x_t and round-off)."""
    from flexrv.model.flexible_bearing import row_force, row_jacobian

    row = _quasi_static_row(preset, tol=1e-11)
    x0, xt0 = _FRAME[0].copy(), _FRAME[1].copy()
    kx, cx = row_jacobian(row, x0, xt0)
    k_fd, c_fd = np.zeros((6, 6)), np.zeros((6, 6))
    for c in range(6):
        d = np.zeros(6)
        d[c] = 1e-9 if c < 3 else 1e-8
        k_fd[:, c] = (row_force(row, x0 + d, xt0) - row_force(row, x0 - d, xt0)) / (2 * d[c])
        d[c] = 1e-5
        c_fd[:, c] = (row_force(row, x0, xt0 + d) - row_force(row, x0, xt0 - d)) / (2 * d[c])
    assert np.abs(kx - k_fd).max() <= 1e-4 * np.abs(k_fd).max() and np.abs(k_fd).max() > 1e8
    assert np.abs(cx - c_fd).max() <= 5e-4 * np.abs(c_fd).max() and np.abs(c_fd).max() > 10.0


def test_quasi_static_ball_failure_is_reported():
    """A local ball solve that cannot converge (tolerance 1e-20 of the loads, below
    round-off) is counted and flagged in the row's state, and the ball group's
    check() turns it into a failure message (a run then stops with it); the stored
    solution is not overwritten by the failed one."""
    from flexrv.model.flexible_bearing import BallBearingGroup, kernel_inputs, row_force

    row = _quasi_static_row("rv221", tol=1e-20)
    group = BallBearingGroup([row])
    assert group.members == ("carrier",)
    ws = kernel_inputs(row).balls.copy()
    row_force(row, *_FRAME)
    state = kernel_inputs(row).state
    assert state[4] == 1 and state[5] == 1
    np.testing.assert_array_equal(kernel_inputs(row).balls, ws)
    assert "quasi-static balls" in group.check()


def test_ball_inertia_option_routes():
    """The ``ball_inertia`` model option: the ball model's default is quasi-static balls
    (no ball members, info ``ball_inertia`` False), True gives each row's ball member
    (3 Z coordinates); the rigid main bearing refuses it, from the API and from
    ``flexrv simulate --quasi-static-balls`` (a clear ConfigError, exit 2); quasi-static
    balls between condensed rings are refused (a condensed ring couples every ball of
    the row)."""
    from types import SimpleNamespace

    from typer.testing import CliRunner

    from flexrv.cli import app
    from flexrv.errors import ConfigError
    from flexrv.model.factory import build_model

    r = load("rv40e")
    m = build_model(r, "balls", exudyn=False)
    assert m.info["ball_inertia"] is False and not any("balls" in name for name in m.members)
    m = build_model(r, "balls", exudyn=False, ball_inertia=True)
    nz = r.main_bearing.ball_count
    assert m.info["ball_inertia"] is True and m.members["main_bearing_balls1"].n == 3 * nz
    with pytest.raises(ConfigError, match="not allowed with the rigid main bearing"):
        build_model(r, "rigid", exudyn=False, ball_inertia=False)
    res = CliRunner().invoke(app, ["simulate", "rv40e", "--quasi-static-balls"])
    assert isinstance(res.exception, ConfigError) and "ball_inertia = False" in str(res.exception), res.output
    row = rows_from_design(r, ehl="dry")[0]
    with pytest.raises(ConfigError, match="need rigid or uncondensed modal rings"):
        rows_from_design(r, ehl="dry", outer=[SimpleNamespace(condensed=True)] * 2, ball_inertia=False)
    assert row.ball_inertia


@pytest.mark.parametrize("ball_inertia", [False, True])
def test_rows_element_equals_the_row_glue(ball_inertia):
    """The bearing rows as the compiled force element of the fused kernel
    (:class:`BallBearingGroup`, kernel :func:`flexrv.model.bearing_kernel.rows_kernel`) give
    the force and the Jacobians d F / d q, d F / d q_t of the Exudyn glue (:class:`RowElement`,
    the same rows, f_q = -1, f_v = 0 and f_q = 0, f_v = -1) on the group's coordinates
    [carrier, balls], at a loaded state with the carrier spinning (films: Hamrock-Dowson),
    within 1e-12 of the largest entry (the two share the rows' film and ball warm starts,
    so their iterations start from each other's results: round-off, not bit for bit), for
    quasi-static balls (rows on the carrier only; their condensed Jacobians) and balls with
    inertia (3 Z coordinates per row, absolute positions); the group declares the balls of
    each row as a dense block of the model's Newton matrix (its own members, contiguous)."""
    from flexrv.model.core.registry import dense_blocks
    from flexrv.model.factory import build_model
    from flexrv.model.flexible_bearing import _PERM, RowElement

    m = build_model(load("rv40e"), "balls", exudyn=False, ball_inertia=ball_inertia)
    group = next(g for g in m.groups if g.kind == "bearing_rows")
    n = sum(m.members[name].n for name in group.members)
    q = np.concatenate([m.members[name].q0 for name in group.members])
    v = np.zeros(n)
    q[:6] = [3e-6, -2e-6, 0.01, 4e-6, 2e-5, -1e-5]
    v[:6] = [1e-4, 2e-4, 1.3, -1e-4, 1e-3, 2e-3]
    rng = np.random.default_rng(5)
    v[6:] = rng.normal(scale=1e-3, size=n - 6)
    idxs = [np.concatenate([_PERM, 6 + k * r.n_ball_coordinates + np.arange(r.n_ball_coordinates)])
            for k, r in enumerate(group.rows)]  # fmt: skip
    glue = RowElement(group.rows, idxs, absolute=True)
    for _ in range(2):  # the second call from the first's warm starts, as in a run
        f, _ = group.evaluate(0.0, q, v)
        jq, jv = group.jacobian(0.0, q, v)
        ref_f = glue.force(list(q), list(v)).copy()
        ref_q = glue.jacobian(list(q), list(v), -1.0, 0.0).copy()
        ref_v = glue.jacobian(list(q), list(v), 0.0, -1.0).copy()
        for got, ref in ((f, ref_f), (jq, ref_q), (jv, ref_v)):
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    assert np.abs(ref_f[:6]).max() > 100.0 and np.abs(ref_q).max() > 1e7
    assert m.info["ball_inertia"] is ball_inertia
    blocks = dense_blocks(m)
    if ball_inertia:
        nb = 3 * group.rows[0].ball_count
        assert blocks == [(m.members[f"main_bearing_balls{k}"].offset, nb) for k in range(2)]
    else:
        assert blocks == [] and group.members == ("carrier",)


def test_quasi_static_jacobian_from_the_solve_equals_a_separate_evaluation():
    """The quasi-static balls' condensed Jacobians returned with a ball solve (computed from
    the solve's last evaluation, bearing_kernel._ball_solve) equal those of a separate
    CONDENSED_BALLS evaluation at the solved balls (a second Jacobian call at the same frame
    state, which reuses the stored solution): the same formula at the same state, within
    1e-12 of the largest entry (the two evaluations' film iterations start from films one
    call apart: round-off; measured 4.0e-15 and 2.8e-15 on rv40e)."""
    from flexrv.model.bearing_kernel import _split_balls
    from flexrv.model.flexible_bearing import kernel_inputs, row_jacobian

    row = _quasi_static_row("rv40e")
    x, xt = _FRAME[0].copy(), _FRAME[1].copy()
    kx, cx = row_jacobian(row, x, xt)  # a new state: the solve, its Jacobians from its last evaluation
    flag = _split_balls(kernel_inputs(row).balls, 3 * row.ball_count, 6)[5]
    assert flag[0] == 1.0 and kernel_inputs(row).state[4] == 0
    kx2, cx2 = row_jacobian(row, x, xt)  # the same state: one CONDENSED_BALLS evaluation at the stored balls
    assert np.abs(kx).max() > 1e8 and np.abs(cx).max() > 10.0
    np.testing.assert_allclose(kx, kx2, rtol=0, atol=1e-12 * np.abs(kx2).max())
    np.testing.assert_allclose(cx, cx2, rtol=0, atol=1e-12 * np.abs(cx2).max())


@pytest.mark.parametrize("preset", ["rv221", "rv40e"])
def test_quasi_static_jacobian_is_the_schur_complement_of_the_ball_row(preset):
    """The condensed Jacobians of quasi-static balls between rigid rings (each ball's share
    in closed form, bearing_kernel._condense_rigid_ball) are the Schur complement of the
    same row with ball coordinates (one row_eval with both Jacobians at the solved balls and
    their velocities), formed here with numpy: S = -J_bb^-1 J_bx, K = J_xx + J_xb S,
    C = V_xx + V_xb S - J_xb J_bb^-1 (V_bx + V_bb S). Within 5e-12 of the largest entry
    (measured 1.2e-12 / 2.4e-13 on rv221, 2.3e-13 / 4.4e-14 on rv40e: the two rows' film
    iterations start from different films, and the complement halves the entries of J_xx)."""
    from flexrv.model.bearing_kernel import _split_balls
    from flexrv.model.flexible_bearing import kernel_inputs, row_jacobian

    qs_row = _quasi_static_row(preset)
    dyn = rows_from_design(load(preset), ehl="hamrock_dowson")[0]
    nz = dyn.ball_count
    x, xt = _FRAME[0].copy(), _FRAME[1].copy()
    kx, cx = row_jacobian(qs_row, x, xt)
    b, bt = (a.copy() for a in _split_balls(kernel_inputs(qs_row).balls, 3 * nz, 6)[:2])
    ev = evaluate_row(dyn, np.concatenate([x, b]), np.concatenate([xt, bt]), jacobian=True)
    jq, jv = ev.jac_q, ev.jac_v
    xs, bs = slice(0, 6), slice(6, 6 + 3 * nz)
    s = -np.linalg.solve(jq[bs, bs], jq[bs, xs])
    k_ref = jq[xs, xs] + jq[xs, bs] @ s
    c_ref = jv[xs, xs] + jv[xs, bs] @ s - jq[xs, bs] @ np.linalg.solve(jq[bs, bs], jv[bs, xs] + jv[bs, bs] @ s)
    assert np.abs(k_ref).max() > 1e8 and np.abs(c_ref).max() > 10.0
    np.testing.assert_allclose(kx, k_ref, rtol=0, atol=5e-12 * np.abs(k_ref).max())
    np.testing.assert_allclose(cx, c_ref, rtol=0, atol=5e-12 * np.abs(c_ref).max())
