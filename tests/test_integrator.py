"""The compiled generalized-alpha integrator (flexrv.model.numerics.gen_alpha,
flexrv.model.integrator) alone on linear oscillators against closed forms, and on every
preset's rigid model against Exudyn's integrator (the reference) by the criteria of
tests/test_time_step.py."""

from __future__ import annotations

import types

import numpy as np
import pytest

from flexrv.design import list_presets, load
from flexrv.errors import InputError
from flexrv.model.numerics import gen_alpha, linalg
from flexrv.simulation import choose_integrator

# -------------------------------------------------------------- the algorithm alone


def integrate_linear(mass, stiffness, damping, q0, v0, h, n_steps, rho=0.5, tol=(1e-12, 1e-14), blocks=None):
    """Integrate M a + D v + K q = 0 with the state machine, the linear force handed
    back as f = -K q - D v with its Jacobians (-K, -D); returns (q, v) per step.
    ``blocks``: the Newton systems by block elimination (gen_alpha.new_state)."""
    st = gen_alpha.new_state(mass, spectral_radius=rho, tolerance=tol, blocks=blocks)
    a0 = np.linalg.solve(mass, -stiffness @ q0 - damping @ v0)
    gen_alpha.set_state(st, q0, v0, a0)
    jq, jv = -np.asarray(stiffness, float), -np.asarray(damping, float)
    qs, vs = [np.array(q0, float)], [np.array(v0, float)]
    for _ in range(n_steps):
        gen_alpha.begin_step(st, h)
        status = gen_alpha.EVALUATE
        while status == gen_alpha.EVALUATE:
            status = gen_alpha.after_eval(st, jq @ st.q + jv @ st.v, jq, jv, st.blocks)
        assert status == gen_alpha.CONVERGED
        assert gen_alpha.finish_step(st)
        qs.append(st.q.copy())
        vs.append(st.v.copy())
    return np.array(qs), np.array(vs)


M2 = np.diag([1.0, 2.0])
K2 = np.array([[3.0, -1.0], [-1.0, 1.0]])


def exact_2dof(t, q0):
    """Closed form of M q'' + K q = 0 from rest at q0: the modes of K phi = w^2 M phi."""
    from scipy.linalg import eigh

    w2, phi = eigh(K2, M2)  # phi^T M phi = I
    eta0 = phi.T @ M2 @ q0
    return (phi @ (eta0[:, None] * np.cos(np.sqrt(w2)[:, None] * t[None, :]))).T


def test_second_order_convergence_on_a_linear_2dof_oscillator():
    """Undamped 2-DOF oscillator (M = diag(1, 2), K = [[3, -1], [-1, 1]]) from rest at
    q0 = (1, 0) over 2 s against its modal closed form: halving the step divides the
    error by 4 (second order, :cite:`chung1993`, for any rho_inf). Measured orders
    2.00-2.01 for rho_inf = 0.5 and 0.8; required 2 +- 0.1."""
    q0 = np.array([1.0, 0.0])
    for rho in (0.5, 0.8):
        errors = []
        for h in (1e-2, 5e-3, 2.5e-3):
            n = int(round(2.0 / h))
            qs, _ = integrate_linear(M2, K2, np.zeros((2, 2)), q0, np.zeros(2), h, n, rho=rho)
            errors.append(np.abs(qs - exact_2dof(h * np.arange(n + 1), q0)).max())
        orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert np.all(np.abs(orders - 2.0) < 0.1), (rho, orders)


def amplification(omega_h: float, rho: float) -> np.ndarray:
    """The one-step map of (q, h v, h^2 a, h^2 a_alg) for q'' + omega^2 q = 0 (h = 1),
    built column by column from the integrator (the scheme is linear)."""
    cols = []
    for e in np.eye(4):
        st = gen_alpha.new_state(np.eye(1), stiffness=[[omega_h**2]], spectral_radius=rho, tolerance=(1e-14, 0.0))
        gen_alpha.set_state(st, e[:1], e[1:2], e[2:3], e[3:4])
        gen_alpha.begin_step(st, 1.0)
        status = gen_alpha.EVALUATE
        z = np.zeros((1, 1))
        while status == gen_alpha.EVALUATE:
            status = gen_alpha.after_eval(st, np.zeros(1), z, z, None)
        assert status == gen_alpha.CONVERGED
        gen_alpha.finish_step(st)
        cols.append([st.q[0], st.v[0], st.a[0], st.aa[0]])
    return np.array(cols).T


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8, 1.0])
def test_spectral_radius_of_the_amplification(rho):
    """Closed form of the generalized-alpha (:cite:`chung1993`): the spectral radius of
    the one-step amplification tends to rho_inf for omega h -> infinity (the parameter's
    definition) and to 1 for omega h -> 0 (no dissipation of the resolved modes);
    rho_inf = 1 dissipates nothing at any omega h. At omega h = 1e6 the radius is within
    1e-4 of rho_inf (measured 8e-5 for rho_inf = 0.5 and 0.8, 1e-4 for 0: its double root
    at 0 splits as the square root of the perturbation); at omega h = 1e-3 within 1e-12
    of 1; required 2e-4 and 1e-9."""
    r_inf = max(abs(np.linalg.eigvals(amplification(1e6, rho))))
    r_0 = max(abs(np.linalg.eigvals(amplification(1e-3, rho))))
    assert r_inf == pytest.approx(rho, abs=2e-4)
    assert r_0 == pytest.approx(1.0, abs=1e-9)
    if rho == 1.0:
        assert max(abs(np.linalg.eigvals(amplification(3.0, rho)))) == pytest.approx(1.0, abs=1e-9)


def test_coefficients_match_exudyns_documented_values():
    """rho_inf = 0.5: alpha_m = 0, alpha_f = 1/3, gamma = 5/6, beta = 4/9 (the values
    flexrv.simulation's docstring derives its restart error from)."""
    am, af, g, b = gen_alpha.coefficients(0.5)
    assert (am, af, g, b) == pytest.approx((0.0, 1 / 3, 5 / 6, 4 / 9), abs=1e-15)


def test_linear_solve():
    """lu_factor / lu_solve against numpy on a random, pivoting-needing matrix; a singular
    matrix is reported."""
    rng = np.random.default_rng(3)
    a = rng.normal(size=(9, 9))
    a[0, 0] = 0.0
    lu, piv, x = np.zeros((9, 9)), np.zeros(9, np.int64), np.zeros(9)
    b = rng.normal(size=9)
    assert linalg.lu_factor(a, lu, piv)
    linalg.lu_solve(lu, piv, b, x)
    assert np.allclose(x, np.linalg.solve(a, b), rtol=1e-12, atol=1e-12)
    assert not linalg.lu_factor(np.zeros((3, 3)), np.zeros((3, 3)), np.zeros(3, np.int64))


def _block_system(rng, n, blocks_in, pivoting=True):
    """A random n x n matrix with uncoupled dense diagonal blocks (zero block-block entries),
    with a zero on each block's diagonal (partial pivoting needed) if ``pivoting``."""
    s = rng.normal(size=(n, n)) + 4.0 * np.eye(n)
    for i, (a0, am) in enumerate(blocks_in):
        if pivoting:
            s[a0, a0] = 0.0
        for j, (b0, bm) in enumerate(blocks_in):
            if i != j:
                s[a0 : a0 + am, b0 : b0 + bm] = 0.0
    return s


def test_block_elimination_solve():
    """block_lu (the balls' blocks eliminated first, then the Schur complement) against
    numpy's dense solve on random matrices of the flexible-rings structure (x coordinates
    before, between and after the blocks), with zero pivots inside the blocks: equal to
    1e-12 relative; a matrix changed only in its A block (the x-x entries) solved from the
    kept block factors and the Schur complement A' - sum B_k Y_k (the partial Jacobians of
    the integrator), the same; the structure check and a singular block are reported."""
    from flexrv.model.numerics import block_lu

    rng = np.random.default_rng(5)
    for n, blocks_in in ((40, [(3, 12), (20, 15)]), (249, [(21, 114), (135, 114)]), (10, [(0, 10)])):
        blocks, xs = block_lu.block_structure(n, blocks_in)
        assert sorted([*xs, *[i for b0, m in blocks for i in range(b0, b0 + m)]]) == list(range(n))
        s = _block_system(rng, n, blocks_in)
        assert block_lu.has_block_structure(s, blocks)
        nx, nb = len(xs), int(blocks[:, 1].sum())
        w, piv, ys = s.copy(), np.zeros(n, np.int64), np.zeros((nb, nx))
        dk = np.zeros(block_lu.work_sizes(blocks, xs)[1])
        schur, xpiv, by = np.zeros((nx, nx)), np.zeros(nx, np.int64), np.zeros((nx, nx))
        assert block_lu.block_factor(w, blocks, xs, piv, ys, dk, schur, xpiv, by)
        for _ in range(2):  # one factorisation, several right-hand sides
            r = rng.normal(size=n)
            x = np.zeros(n)
            block_lu.block_solve(w, blocks, xs, piv, ys, dk, schur, xpiv, r, x, np.zeros(nx), np.zeros(nx))
            ref = np.linalg.solve(s, r)
            assert np.max(np.abs(x - ref)) <= 1e-12 * np.max(np.abs(ref))
        if len(xs):  # A changed: the Schur complement only, from the kept factors
            a_new = s[np.ix_(xs, xs)] + rng.normal(size=(nx, nx))
            s2 = s.copy()
            s2[np.ix_(xs, xs)] = a_new
            schur[:] = a_new - by
            assert linalg.lu_factor(schur, schur, xpiv)
            r = rng.normal(size=n)
            x = np.zeros(n)
            block_lu.block_solve(w, blocks, xs, piv, ys, dk, schur, xpiv, r, x, np.zeros(nx), np.zeros(nx))
            ref = np.linalg.solve(s2, r)
            assert np.max(np.abs(x - ref)) <= 1e-12 * np.max(np.abs(ref))
    blocks2, _ = block_lu.block_structure(10, [(0, 4), (5, 5)])
    assert not block_lu.has_block_structure(_block_system(rng, 10, [(0, 3), (5, 5)]), blocks2)
    with pytest.raises(ValueError, match="overlaps"):
        block_lu.block_structure(10, [(0, 4), (3, 2)])
    sing = np.eye(6)
    sing[2:4, 2:4] = 0.0
    blocks, xs = block_lu.block_structure(6, [(2, 2)])
    assert not block_lu.block_factor(
        sing,
        blocks,
        xs,
        np.zeros(6, np.int64),
        np.zeros((2, 4)),
        np.zeros(4),
        np.zeros((4, 4)),
        np.zeros(4, np.int64),
        np.zeros((4, 4)),
    )


def test_block_elimination_inside_the_integrator():
    """A 12-coordinate linear system whose stiffness and damping couple two dense blocks
    (coordinates 3-6 and 7-11) only through the first three coordinates, integrated 60
    steps with the Newton systems solved by block elimination and by one dense LU: the
    same states to 1e-12 relative (the algorithm is the same, only the linear solver's
    round-off differs); a mass matrix that couples the blocks is refused."""
    rng = np.random.default_rng(8)
    n, blocks = 12, [(3, 4), (7, 5)]
    a = rng.normal(size=(n, n))
    k = a @ a.T + n * np.eye(n)
    k[3:7, 7:12] = 0.0
    k[7:12, 3:7] = 0.0
    mass = np.diag(rng.uniform(0.5, 2.0, n))
    q0, v0 = rng.normal(size=n), np.zeros(n)
    dense = integrate_linear(mass, k, 0.01 * k, q0, v0, 0.05, 60)
    block = integrate_linear(mass, k, 0.01 * k, q0, v0, 0.05, 60, blocks=blocks)
    for d, b in zip(dense, block):
        assert np.max(np.abs(b - d)) <= 1e-12 * np.max(np.abs(d))
    coupled = mass.copy()
    coupled[3, 8] = coupled[8, 3] = 0.1
    with pytest.raises(ValueError, match="couples two of the dense blocks"):
        gen_alpha.new_state(coupled, k, blocks=blocks)


def _duffing(st, h, n_steps, k, c):
    """Integrate M a + k q + c q^3 = 0 (the force and its Jacobian handed back to the state
    machine); returns the states per step."""
    qs = []
    for _ in range(n_steps):
        gen_alpha.begin_step(st, h)
        status = gen_alpha.EVALUATE
        while status == gen_alpha.EVALUATE:
            f = -k * st.q - c * st.q**3
            jq = np.diag(-k - 3.0 * c * st.q**2)
            status = gen_alpha.after_eval(st, f, jq, np.zeros_like(jq), st.blocks)
        assert status == gen_alpha.CONVERGED
        assert gen_alpha.finish_step(st)
        qs.append(st.q.copy())
    return np.array(qs)


def test_jacobian_kept_across_steps():
    """jacobian_each_step=False (Exudyn's modifiedNewtonJacUpdatePerStep = False): on a
    linear 2-DOF oscillator (exact Jacobian) the first step's factorisation serves all 100
    steps with bit-identical states; on a stiffening (Duffing) oscillator, 3 coordinates
    from q0 = 0.5..1.5 with k = 1, c = 4, 200 steps of 0.01, the states agree with a fresh
    Jacobian per step within 1e-9 (Newton tolerance 1e-10 relative; measured 7.9e-11) with
    fewer Jacobians (measured 1 against 200) and more Newton iterations (657 against 400)."""
    q0, h = np.array([1.0, 0.0]), 0.02
    each = integrate_linear(M2, K2, np.zeros((2, 2)), q0, np.zeros(2), h, 100)
    st = gen_alpha.new_state(M2, spectral_radius=0.5, tolerance=(1e-12, 1e-14), jacobian_each_step=False)
    gen_alpha.set_state(st, q0, np.zeros(2), np.linalg.solve(M2, -K2 @ q0))
    jq = -K2
    for i in range(100):
        gen_alpha.begin_step(st, h)
        status = gen_alpha.EVALUATE
        while status == gen_alpha.EVALUATE:
            status = gen_alpha.after_eval(st, jq @ st.q, jq, np.zeros((2, 2)), None)
        assert status == gen_alpha.CONVERGED and gen_alpha.finish_step(st)
        np.testing.assert_array_equal(st.q, each[0][i + 1])
    assert st.ip[gen_alpha.I_JACOBIANS] == 1
    mass, k, c, q0 = np.eye(3), 1.0, 4.0, np.array([0.5, 1.0, 1.5])
    runs = {}
    for flag in (True, False):
        st = gen_alpha.new_state(mass, tolerance=(1e-10, 1e-14), jacobian_each_step=flag)
        gen_alpha.set_state(st, q0, np.zeros(3), -k * q0 - c * q0**3)
        runs[flag] = (_duffing(st, 0.01, 200, k, c), st.ip[gen_alpha.I_JACOBIANS], st.ip[gen_alpha.I_NEWTON])
    assert np.max(np.abs(runs[False][0] - runs[True][0])) < 1e-9
    assert runs[True][1] == 200 and runs[False][1] <= 5
    assert runs[False][2] > runs[True][2]


def _partial_system(st, h, n_steps, kc, e, k, c, xs):
    """Integrate M a + Kc q + e q^3 + k q_x + c q_x^3 = 0 (q_x: the coordinates ``xs`` outside
    the dense blocks) as the generated fused kernel drives the state: Kc q + e q^3 is the
    "costly" element, its Jacobian into the state's kept arrays only when every element's is
    asked for (JAC_FULL) when the state has them, else into jq; the cubic spring on q_x the
    cheap element on (xs, xs). Returns the states per step and the calls with the costly
    element's Jacobian."""
    n = st.q.shape[0]
    qs, costly_calls = [], 0
    kept = st.jqk.shape[0] > 0
    for _ in range(n_steps):
        gen_alpha.begin_step(st, h)
        status = gen_alpha.EVALUATE
        while status == gen_alpha.EVALUATE:
            mode = st.ip[gen_alpha.I_JAC]
            x = st.q[xs]
            f = -kc @ st.q - e * st.q**3
            f[xs] -= k * x + c * x**3
            jc = -kc - np.diag(3.0 * e * st.q**2)
            jq, jv = np.full((n, n), np.nan), np.zeros((n, n))  # (outside the state's xs: never read)
            jq[np.ix_(st.xs, st.xs)] = 0.0  # (gen_alpha.zero_outer)
            jq[np.ix_(xs, xs)] += np.diag(-k - 3.0 * c * x**2)
            if not kept:
                jq = np.nan_to_num(jq) + jc
            elif mode == gen_alpha.JAC_FULL:
                st.jqk[:] = jc
                st.jvk[:] = 0.0
                costly_calls += 1
            status = gen_alpha.after_eval(st, f, jq, jv, st.blocks)
        assert status == gen_alpha.CONVERGED and gen_alpha.finish_step(st)
        qs.append(st.q.copy())
    return np.array(qs), costly_calls


def test_partial_jacobians():
    """partial_jacobian (the compiled integrator's default where an element's Jacobian is costly:
    the ball and flexible-ring models): 8 coordinates, two dense blocks (2-4, 5-7) coupled through
    the two others by the costly element (a linear stiffness and a weak cubic one on every
    coordinate), a stiff cubic spring on the two others (the cheap element), 200 steps of 0.01 from
    q_x = (1.0, 1.5). Against every element's Jacobian every step: with a kept matrix, with a new
    matrix every step, and without blocks (one dense LU), the same states within 1e-9 (Newton
    tolerance 1e-10 relative; measured 2.4e-10 each); the costly Jacobian computed only for the full
    Jacobians (1 of them) while the other steps refresh the cheap one (199 partial); fewer Newton
    iterations than the kept matrix without partial Jacobians (measured 600 / 435 / 867: partial,
    full each step, kept). The entries of jq outside the state's ``xs`` are never read (NaN
    there), and the kept arrays exist only with partial Jacobians."""
    rng = np.random.default_rng(3)
    n, blocks, xs = 8, [(2, 3), (5, 3)], np.array([0, 1])
    a = rng.normal(size=(n, n))
    kc = a @ a.T + n * np.eye(n)
    kc[2:5, 5:8] = 0.0
    kc[5:8, 2:5] = 0.0
    mass = np.diag(rng.uniform(0.5, 2.0, n))
    q0 = np.zeros(n)
    q0[xs] = (1.0, 1.5)
    e, k, c = 0.5, 1.0, 40.0
    runs = {}
    cases = (
        ("full", True, False, blocks),
        ("kept", False, False, blocks),
        ("partial", False, True, blocks),
        ("partial each step", True, True, blocks),
        ("partial, no blocks", True, True, None),
    )
    for label, each, partial, bl in cases:
        st = gen_alpha.new_state(
            mass, tolerance=(1e-10, 1e-14), blocks=bl, jacobian_each_step=each, partial_jacobian=partial
        )
        f0 = -kc @ q0 - e * q0**3
        f0[xs] -= k * q0[xs] + c * q0[xs] ** 3
        gen_alpha.set_state(st, q0, np.zeros(n), np.linalg.solve(mass, f0))
        qs, costly = _partial_system(st, 0.01, 200, kc, e, k, c, xs)
        ip = st.ip
        runs[label] = (qs, costly, ip[gen_alpha.I_JACOBIANS], ip[gen_alpha.I_PARTIALS], ip[gen_alpha.I_NEWTON])
    full, kept = runs["full"], runs["kept"]
    assert kept[3] == 0 and full[2] == 200
    for label in ("partial", "partial each step", "partial, no blocks"):
        r = runs[label]
        assert np.max(np.abs(r[0] - full[0])) < 1e-9 * np.max(np.abs(full[0]))
        assert r[1] == r[2] <= 10 and r[2] + r[3] >= 200
        assert full[4] <= r[4] < 0.75 * kept[4]
    assert gen_alpha.new_state(mass, blocks=blocks, partial_jacobian=True).jqk.shape == (n, n)
    assert gen_alpha.new_state(mass, blocks=blocks).jqk.shape == (0, 0)


def test_partial_jacobians_only_for_cheap_elements_outside_the_blocks():
    """The condition of partial Jacobians (:func:`flexrv.model.integrator.partial_jacobian_allowed`):
    a costly element present and every other element's coordinates outside the dense blocks."""
    from types import SimpleNamespace

    from flexrv.model.integrator import partial_jacobian_allowed

    cheap, costly = SimpleNamespace(costly_jacobian=False), SimpleNamespace(costly_jacobian=True)
    fused = SimpleNamespace(n=8, index=np.arange(8), slots=[(cheap, np.array([0, 1])), (costly, np.arange(8))])
    assert partial_jacobian_allowed(fused, [(2, 3), (5, 3)])
    assert partial_jacobian_allowed(fused, [])
    fused.slots[0] = (cheap, np.array([0, 1, 4]))
    assert not partial_jacobian_allowed(fused, [(2, 3), (5, 3)])
    fused.slots = [(cheap, np.array([0, 1]))]
    assert not partial_jacobian_allowed(fused, [(2, 3), (5, 3)])


def test_partial_jacobians_by_model():
    """Which models run with partial Jacobians by default: the flexible rings (bearing rows with
    condensed rings) do, measured on a 6-step run (the first step's full Jacobian, then one partial
    per step); the rigid model (no costly element) and the quasi-static balls between rigid rings
    (their Jacobian comes with the ball solve) do not; ``partialJacobian`` False turns them off."""
    from flexrv.model.integrator import partial_jacobians
    from flexrv.simulation import Simulation

    sim = Simulation("rv40e", model="flexible")
    sim.run(t_end=6e-4)
    t = sim.timing
    assert partial_jacobians(sim.build()) and t["partial_jacobians"] >= t["steps"] - 1 >= 5
    sim.run(t_end=6e-4, newton_options={"partialJacobian": False})
    assert sim.timing["partial_jacobians"] == 0 and sim.timing["jacobians"] >= 1
    for model in ("rigid", "balls"):
        assert not partial_jacobians(Simulation("rv40e", model=model).build())


def test_extrapolated_predictor_same_states_closer_start():
    """extrapolate=True (the predictor moved by the previous step's Newton correction,
    along the iterates' own directions (dq, gamma' dq, beta' dq)) converges to the states
    of Exudyn's predictor: on the linear 2-DOF oscillator (tolerance 1e-12 relative) within
    1e-12 of the largest coordinate. On the Duffing oscillator (3 coordinates from
    0.5..1.5, k = 1, c = 4, 200 steps of 0.01) at a loose tolerance (1e-3 relative: one
    Newton iteration per step either way) the states are nearer the tightly converged
    ones (1e-14): measured 1.0e-8 against 5.0e-7 for Exudyn's predictor (required: within
    1e-7, and 10x nearer), the quadratic convergence from a start ~25x nearer. The
    correction is not carried over a restart (set_state)."""
    q0, h = np.array([1.0, 0.0]), 0.02
    each = integrate_linear(M2, K2, np.zeros((2, 2)), q0, np.zeros(2), h, 100)
    st = gen_alpha.new_state(M2, spectral_radius=0.5, tolerance=(1e-12, 1e-14), extrapolate=True)
    gen_alpha.set_state(st, q0, np.zeros(2), np.linalg.solve(M2, -K2 @ q0))
    for i in range(100):
        gen_alpha.begin_step(st, h)
        status = gen_alpha.EVALUATE
        while status == gen_alpha.EVALUATE:
            status = gen_alpha.after_eval(st, -K2 @ st.q, -K2, np.zeros((2, 2)), None)
        assert status == gen_alpha.CONVERGED and gen_alpha.finish_step(st)
        assert np.max(np.abs(st.q - each[0][i + 1])) <= 1e-12
    mass, k, c, q0 = np.eye(3), 1.0, 4.0, np.array([0.5, 1.0, 1.5])
    runs = {}
    for flag, tol in ((None, (1e-14, 1e-15)), (False, (1e-3, 1e-6)), (True, (1e-3, 1e-6))):
        st = gen_alpha.new_state(mass, tolerance=tol, extrapolate=bool(flag))
        gen_alpha.set_state(st, q0, np.zeros(3), -k * q0 - c * q0**3)
        runs[flag] = _duffing(st, 0.01, 200, k, c)
    err = {flag: np.max(np.abs(runs[flag] - runs[None])) for flag in (False, True)}
    assert err[True] < 1e-7 and err[True] < 0.1 * err[False]
    gen_alpha.set_state(st, q0, np.zeros(3), -k * q0 - c * q0**3)  # a restart forgets the correction
    gen_alpha.begin_step(st, 0.01)
    assert np.array_equal(st.q, st.qp)


# -------------------------------------------------------------- choice of the integrator


def test_choice_of_the_integrator():
    """Default: compiled where every force is a compiled kernel, else Exudyn; "compiled"
    for a model with a Python group is one InputError naming the group; unknown names rejected."""
    python_group = types.SimpleNamespace(name="ball_bearing")
    balls = types.SimpleNamespace(name="balls", fused=types.SimpleNamespace(others=[python_group]), n=3, groups=[])
    assert choose_integrator(balls, None) == "exudyn"
    assert choose_integrator(balls, "exudyn") == "exudyn"
    with pytest.raises(InputError, match="ball_bearing"):
        choose_integrator(balls, "compiled")
    with pytest.raises(InputError, match="choose from compiled, exudyn"):
        choose_integrator(balls, "rk4")


def test_compiled_only_option_refused_on_exudyn():
    """``extrapolatedPredictor`` and ``partialJacobian`` are the compiled integrator's own
    options: on Exudyn's integrator one InputError naming them; a wrong type is refused by
    name as any Newton option."""
    from flexrv.simulation import Simulation

    sim = Simulation("rv40e")
    for option in ("extrapolatedPredictor", "partialJacobian"):
        with pytest.raises(InputError, match=f"'{option}': an option of the compiled integrator only"):
            sim.run(t_end=1e-3, integrator="exudyn", newton_options={option: False})
        with pytest.raises(InputError, match=option):
            sim.run(t_end=1e-3, newton_options={option: 1.5})


def test_cli_refuses_compiled_for_python_groups(tmp_path, capfd):
    """flexrv simulate --model flexible --parts crankshaft --integrator compiled (the flexible
    crankshaft is a Python group): one clear message, exit 2."""
    from flexrv.cli import main

    with pytest.raises(SystemExit) as info:
        main(["simulate", "rv40e", "--model", "flexible", "--parts", "crankshaft", "--integrator", "compiled",
              "--t-end", "0.001", "--out", str(tmp_path / "o")])  # fmt: skip
    err = capfd.readouterr().err
    assert info.value.code == 2
    assert "integrator = 'compiled' is not allowed" in err and "--integrator exudyn" in err


# -------------------------------------------------------------- cross-check against Exudyn


def te_of(reducer, integrator, t_end, model="rigid", window=None, newton_tolerance=None):
    """(mean, p-p, frequencies, amplitudes, results) of the TE of ``model`` over the steady
    window (``window`` [s]: the last ``window`` of the run instead) on tests/test_time_step.py's grid;
    ``newton_tolerance`` (relative, absolute) instead of the run's default."""
    from flexrv.post.spectra import amplitude_spectrum
    from flexrv.simulation import Simulation
    from tests.test_time_step import GRID

    kw = {} if newton_tolerance is None else {"newton_tolerance": newton_tolerance}
    res = Simulation(reducer, model=model).run(t_end=t_end, integrator=integrator, **kw)
    assert res.attrs["status"] == "completed" and res.attrs["integrator"] == integrator
    t0, t1 = res.steady_window() if window is None else (t_end - window, t_end)
    tg = np.arange(int(round(t0 / GRID)), int(round(t1 / GRID)) + 1) * GRID
    te = np.interp(tg, res.time, res["te"].values)
    f, a = amplitude_spectrum(te, tg)
    return float(te.mean()), float(np.ptp(te)), f, a, res


def cross_check(reducer, t_end, unique=True, model="rigid", window=None):
    """Compiled vs Exudyn: TE mean within 0.05 arcsec, p-p within 0.05 arcsec and the
    lines up to the cycloid mesh within 2 % (tests/test_time_step.py's criterion); for
    a response that is not unique (rv221 at its light preset load, see that module):
    mean within 0.1 arcsec and the dominant line within 2 %."""
    from tests.test_time_step import lines

    m0, pp0, f0, a0, _ = te_of(reducer, "exudyn", t_end, model, window)
    m1, pp1, f1, a1, res = te_of(reducer, "compiled", t_end, model, window)
    assert np.array_equal(f0, f1)
    if unique:
        pk = lines(reducer, f0, a0)
        assert abs(m1 - m0) < 0.05
        assert abs(pp1 - pp0) < 0.05
        assert np.max(np.abs(a1[pk] - a0[pk]) / a0[pk]) < 0.02
    else:
        assert abs(m1 - m0) < 0.1
        i = int(np.argmax(a0 * (f0 > 0)))
        assert abs(a1[i] - a0[i]) < 0.02 * a0[i]
    return res


@pytest.mark.parametrize("name", list_presets())
def test_cross_check_against_exudyn_every_preset(name):
    """Every preset, rigid model, shortened ramps (rated speed at 0.01 s, load 0.01-0.03
    s), t_end 0.3 s, both integrators (the compiled one with its extrapolated predictor).
    Measured: rv40e mean 3.6e-5 arcsec apart, p-p 2.1e-4 arcsec, lines (60, 120, 180, 340,
    390 Hz) within 3.1e-4; rv221 at its rated 3000 N m mean 7.9e-6 arcsec, p-p 2.2e-4
    arcsec, the 13.6 Hz line 4.5e-7; rv221 at its preset 20 N m mean 0.044 arcsec, the
    13.6 Hz line 0.84 % (p-p 4.99 / 5.38 arcsec: its two steady responses, picked by
    Newton-tolerance-level differences, docs/integrator.md). ~10 s each."""
    from tests.test_time_step import fast

    r = fast(name)
    light = r.operating.load_torque_Nm < 0.1 * r.operating.rated_torque_Nm
    cross_check(r, 0.3, unique=not light)
    if light:  # loaded, the response is unique: the full criterion
        op = r.operating.model_copy(update={"load_torque_Nm": r.operating.rated_torque_Nm})
        cross_check(r.model_copy(update={"operating": op}), 0.3)


@pytest.mark.parametrize("name", list_presets())
def test_cross_check_ball_model_against_exudyn(name):
    """The ball-resolved main bearing (quasi-static balls between rigid rings; the rows a
    compiled element of the fused kernel on both integrators), every preset, shortened
    ramps, 0.12 s, the last 0.05 s: the criterion of :func:`cross_check`; a preset whose load
    is light (rv221: two steady responses, see :func:`test_cross_check_against_exudyn_every_preset`;
    its dominant line differed by 11 % in this short window) at its rated torque. Measured
    rv40e: mean -202.4718 / -202.4721 arcsec, p-p 0.6836 / 0.6835 arcsec. ~2 s each (warm)."""
    from tests.test_time_step import fast

    r = fast(name)
    if r.operating.load_torque_Nm < 0.1 * r.operating.rated_torque_Nm:
        op = r.operating.model_copy(update={"load_torque_Nm": r.operating.rated_torque_Nm})
        r = r.model_copy(update={"operating": op})
    cross_check(r, 0.12, model="balls", window=0.05)


def test_cross_check_flexible_rings_against_exudyn():
    """The flexible main-bearing rings (condensed rings, balls with inertia: the block
    elimination of the balls' dense blocks, the iteration matrix kept across steps as Exudyn's
    integrator does above 100 coordinates; on the compiled integrator with its partial
    Jacobians and Exudyn's predictor), rv40e, shortened ramps, 0.12 s, the last 0.05 s: the
    criterion of :func:`cross_check`. Measured: mean -202.472819 / -202.472825 arcsec, p-p
    0.6745 / 0.6824 arcsec, the lines (60, 120, 179, 339 Hz) within 0.44 %. ~7 s (warm)."""
    from tests.test_time_step import fast

    cross_check(fast("rv40e"), 0.12, model="flexible", window=0.05)


@pytest.mark.slow
def test_cross_check_flexible_rings_rv221_rated():
    """The flexible rings of rv221 (slow: its rings' meshing and CMS on a cold cache), at its
    rated 3000 N m (at the preset's 20 N m its response is not unique, see
    :func:`test_cross_check_against_exudyn_every_preset`), shortened ramps, 0.12 s, the last
    0.05 s: the criterion of :func:`cross_check`. Measured: mean -159.95775 / -159.95779 arcsec,
    p-p 7.7546 / 7.7679 arcsec, the lines (20, 299 Hz) within 0.02 %. ~60 s (warm)."""
    from tests.test_time_step import fast

    r = fast("rv221")
    op = r.operating.model_copy(update={"load_torque_Nm": r.operating.rated_torque_Nm})
    cross_check(r.model_copy(update={"operating": op}), 0.12, model="flexible", window=0.05)


@pytest.mark.slow
@pytest.mark.parametrize("name", list_presets())
def test_cross_check_full_default_run(name):
    """The full default run (default ramps and t_end) of every preset, both integrators,
    the criterion of :func:`cross_check`. A preset at a light load (rv221 at 20 of 3000
    N m: two steady responses, tests/test_time_step.py) is held to what Exudyn's own
    integrator shows there: the compiled TE mean within 0.05 arcsec of the span of
    Exudyn's means at its default Newton tolerance, 10x tighter and 3x looser (which land
    on different responses: measured -30.2020 / -30.3477 / -30.1707 arcsec, 0.146 apart
    between default and tight; compiled -30.3483), the dominant line within 2 % of
    Exudyn's at the default. ~30 s each."""
    r = load(name)
    if r.operating.load_torque_Nm >= 0.1 * r.operating.rated_torque_Nm:
        cross_check(r, None)
        return
    from flexrv.simulation import DEFAULT_NEWTON_TOLERANCE

    rel, ab = DEFAULT_NEWTON_TOLERANCE
    means = [te_of(r, "exudyn", None, newton_tolerance=(rel * k, ab * k))[0] for k in (0.1, 3.0)]
    m0, _, f0, a0, _ = te_of(r, "exudyn", None)
    m1, _, f1, a1, _ = te_of(r, "compiled", None)
    assert np.array_equal(f0, f1)
    assert min(means + [m0]) - 0.05 < m1 < max(means + [m0]) + 0.05
    i = int(np.argmax(a0 * (f0 > 0)))
    assert abs(a1[i] - a0[i]) < 0.02 * a0[i]


def test_same_steps_as_exudyn_through_step_reductions():
    """From rest with 20 ms ramps and a tight Newton tolerance (1e-5 / 1e-3 N, the
    regression cases' setting), rv40e's start-up has Newton failures and step reductions
    (eight in the first 4 ms): with Exudyn's predictor (``extrapolatedPredictor`` False)
    both integrators take the same steps at the same times with the same Newton
    iterations and Jacobians, and their TE agrees to round-off growth (measured over
    0.06 s: 2055 iterations and 917 Jacobians each, TE within 1e-9 arcsec; required here
    over 0.02 s: equal counts and times, TE within 1e-6 arcsec)."""
    from flexrv.design import override
    from flexrv.simulation import Simulation
    from tests.regression_cases import FAST, NEWTON_TOLERANCE

    out = {}
    for integrator in ("exudyn", "compiled"):
        sim = Simulation(override("rv40e", FAST))
        own = {"extrapolatedPredictor": False} if integrator == "compiled" else None
        res = sim.run(t_end=0.02, dt=1e-4, newton_tolerance=NEWTON_TOLERANCE, integrator=integrator, newton_options=own)
        out[integrator] = (res, sim.timing)
    (ra, ta), (rb, tb) = out["exudyn"], out["compiled"]
    assert ta["newton_iterations"] == tb["newton_iterations"] and ta["jacobians"] == tb["jacobians"]
    assert len(ra.time) == len(rb.time) and np.allclose(ra.time, rb.time, rtol=0, atol=1e-12)
    assert np.any(np.abs(np.diff(ra.time) - 1e-4) > 1e-6)  # the reductions moved the output times off the grid
    assert np.abs(ra["te"].values - rb["te"].values).max() < 1e-6
