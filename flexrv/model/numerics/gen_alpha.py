"""Generalized-alpha time integration of M a + K q + D v = f(t, q, v), compiled.

The scheme is the Arnold–Brüls form :cite:`arnold2007` of the Chung–Hulbert
generalized-alpha method :cite:`chung1993`, as Exudyn's implicit second-order solver
runs it (its documented settings and its published solver source were read; nothing
is copied): from the spectral radius rho_inf

    alpha_m = (2 rho - 1) / (rho + 1),  alpha_f = rho / (rho + 1),
    gamma = 1/2 + alpha_f - alpha_m,    beta = (gamma + 1/2)^2 / 4

(rho = 0.5: alpha_m = 0, alpha_f = 1/3, gamma = 5/6, beta = 4/9). A step h from
(q_n, v_n, a_n, a_alg_n) (a_alg: the algorithmic accelerations) predicts

    q = q_n + h v_n + h^2 (1/2 - beta) a_alg_n + h^2 beta a*,
    v = v_n + h (1 - gamma) a_alg_n + h gamma a*,   a* = (alpha_f a_n - alpha_m a_alg_n) / (1 - alpha_m),
    a = 0,

(with ``extrapolate``, moved by the previous step's whole Newton correction e = q_n -
q_pred,n when that step had the same size: q += e, v += gamma' e, a += beta' e, the
direction of every Newton update below, so the iterates solve the same equations from
a nearer start), and corrects with Newton on the residual r = M a + K q + D v - f(t_n+1, q, v): with
beta' = (1 - alpha_m) / (h^2 beta (1 - alpha_f)) and gamma' = gamma / (h beta), the
iteration matrix S = beta' M + K + gamma' D - df/dq - gamma' df/dv and the update
S dx = r, q -= dx, v -= gamma' dx, a -= beta' dx. After convergence
a_alg_n+1 = a* + (1 - alpha_f) / (1 - alpha_m) a_n+1.

Newton control (Exudyn's defaults of the modified Newton with a Jacobian at the start
of every step): converged when ||r||_2 / r_0 <= relative tolerance or ||r||_2 <=
absolute tolerance, r_0 the residual at the predictor (at least 2 x the absolute
tolerance; raised to the first iteration's residual if that is larger); the Jacobian
is reused while the residual contracts by at most ``contractivity`` per iteration
(checked from the third iteration), else a new one is computed at the current state;
a contraction worse than 2 (or a diverged state) restarts the step from the predictor
with one extra iteration, a second failure switches to full Newton; after
``max_modified`` iterations full Newton; at most ``max_iterations`` iterations. With
``jacobian_each_step`` False a step starts from the factorised iteration matrix of an
earlier step of the same size (within 1e-9 relative) and computes a new one only when
the contraction test above asks for it or after a restart.

Partial Jacobians (``partial_jacobian``): the elements whose Jacobian is costly (the bearing
rows with condensed rings: their dense tangents, about four force calls) put it into the
state's own arrays ``jqk``, ``jvk`` only when the state asks
for every element's (:data:`I_JAC` = :data:`JAC_FULL`), which keep it; a step's predictor asks
for the other elements' Jacobians only (:data:`JAC_PARTIAL`) once the kept arrays hold one, where
it would otherwise ask for every element's (a step without a kept matrix) or none (a step that
keeps the factorised matrix). The contraction test and a restart ask for every element's, as
before. With dense blocks the other elements touch only coordinates outside them (the caller
checks it, ``xs``; without blocks ``xs`` is every coordinate), so a step that keeps the matrix
keeps the blocks' factors D_k = L_k U_k, Y_k and the sum of B_k Y_k, and forms and factors only
the Schur complement (n_x x n_x) again. Measured (docs/integrator.md): the contacts outside the
rows (the needle bearings opening and closing, the pins) change their Jacobians from step to
step, the rows' hardly: the Newton iteration's contraction with the rows' Jacobian 11 steps old
and the others' current 0.003 on the flexible rings (every Jacobian one step old: 0.6). Their
Newton iterations per step 3.37 -> 1.69, full Jacobians 0.17 -> 0.10
(benchmarks/bench_integrator.py --model flexible).

Reverse communication: the functions here never call the force; the caller (the
generated ``fused_integrate`` of :mod:`flexrv.model.core.registry`, or the test's
driver) evaluates f (and, when :data:`I_JAC` asks, df/dq, df/dv) at the state the
state machine holds and hands it back to :func:`after_eval`. So the force kernel has
ONE call site, inside a small loop, whatever the Newton does.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from flexrv.model.core.params import pack_type
from flexrv.model.numerics.block_lu import (
    block_factor,
    block_solve,
    block_structure,
    has_block_structure,
    work_sizes,
)
from flexrv.model.numerics.linalg import lu_factor, lu_solve

# -- indices into the state's float parameters ``par``
P_ALPHA_M, P_ALPHA_F, P_GAMMA, P_BETA, P_RTOL, P_ATOL, P_CONTRACT, P_MAXNORM = range(8)
P_H, P_R0, P_RES, P_LAST, P_HJAC, P_HPREV = 8, 9, 10, 11, 12, 13
N_PAR = 14
# -- indices into the state's integer registers ``ip``
I_PHASE, I_IT, I_JACREQ, I_FULL, I_RESTARTED, I_EXTRA, I_JAC, I_MAXIT, I_MAXMOD = range(9)
I_NEWTON, I_JACOBIANS, I_CALLS, I_JACCALLS, I_ADAPT = 9, 10, 11, 12, 13
I_EACHSTEP, I_FACTORED, I_EXTRAPOLATE, I_PARTIAL, I_PARTIALS, I_KEPT = 14, 15, 16, 17, 18, 19
N_IP = 20
# -- values of ip[I_JAC]: no Jacobian, every element's, the elements' outside the kept ones (partial)
JAC_NONE, JAC_FULL, JAC_PARTIAL = 0, 1, 2
# -- phases: what the evaluation the state machine asked for is
PH_PREDICTOR, PH_ITERATE, PH_JACOBIAN = 0, 1, 2
# -- results of after_eval
EVALUATE, CONVERGED, FAILED = 1, 0, -1

#: the integrator state: parameters, registers, current and start-of-step vectors,
#: residual, Newton correction, the constant matrices and the factorised iteration matrix; with
#: dense diagonal blocks (``blocks`` (K, 2) of (start, size); empty: one dense LU), the block
#: elimination's other coordinates ``xs``, its Y_k, blocks' LU, Schur complement, pivots and work vectors,
#: the sum of the B_k Y_k (:mod:`flexrv.model.numerics.block_lu`), the nonzero pattern of M, K, D by rows (row
#: pointers ``rp``, column indices ``ci``: the residual's products skip the zeros) and the kept Jacobians of the
#: costly elements ``jqk``, ``jvk`` (n x n with partial Jacobians, else 0 x 0)
GaState = pack_type(
    "GaState",
    ("par", (np.float64, 1)),
    ("ip", (np.int64, 1)),
    ("q", (np.float64, 1)),
    ("v", (np.float64, 1)),
    ("a", (np.float64, 1)),
    ("aa", (np.float64, 1)),
    ("q0", (np.float64, 1)),
    ("v0", (np.float64, 1)),
    ("a0", (np.float64, 1)),
    ("aa0", (np.float64, 1)),
    ("r", (np.float64, 1)),
    ("dx", (np.float64, 1)),
    ("qp", (np.float64, 1)),
    ("e", (np.float64, 1)),
    ("mass", (np.float64, 2)),
    ("stiff", (np.float64, 2)),
    ("damp", (np.float64, 2)),
    ("lu", (np.float64, 2)),
    ("piv", (np.int64, 1)),
    ("blocks", (np.int64, 2)),
    ("xs", (np.int64, 1)),
    ("ys", (np.float64, 2)),
    ("dk", (np.float64, 1)),
    ("schur", (np.float64, 2)),
    ("xpiv", (np.int64, 1)),
    ("tx", (np.float64, 1)),
    ("zx", (np.float64, 1)),
    ("by", (np.float64, 2)),
    ("rp", (np.int64, 1)),
    ("ci", (np.int64, 1)),
    ("jqk", (np.float64, 2)),
    ("jvk", (np.float64, 2)),
)


def coefficients(spectral_radius: float) -> tuple[float, float, float, float]:
    """(alpha_m, alpha_f, gamma, beta) of the spectral radius rho_inf in [0, 1] (module docstring).

    >>> coefficients(0.5)
    (0.0, 0.3333333333333333, 0.8333333333333333, 0.4444444444444444)
    """
    rho = float(spectral_radius)
    am = (2.0 * rho - 1.0) / (rho + 1.0)
    af = rho / (rho + 1.0)
    gamma = 0.5 + af - am
    return am, af, gamma, 0.25 * (gamma + 0.5) ** 2


def new_state(
    mass,
    stiffness=None,
    damping=None,
    spectral_radius: float = 0.5,
    tolerance: tuple[float, float] = (1e-3, 1e-1),
    contractivity: float = 0.5,
    max_iterations: int = 25,
    max_modified: int = 8,
    adapt_initial_residual: bool = True,
    blocks=None,
    jacobian_each_step: bool = True,
    extrapolate: bool = False,
    partial_jacobian: bool = False,
) -> GaState:
    """A fresh integrator state for the constant matrices M, K, D (n x n; K, D default 0).
    ``extrapolate``: the predictor moved by the previous step's Newton correction (module
    docstring); False: Exudyn's predictor.
    ``blocks``: [(start, size), ...] dense diagonal blocks of the iteration matrix that couple
    only through the other coordinates (M, K, D and the force's Jacobians zero between two
    blocks): the Newton systems are then solved by block elimination
    (:mod:`flexrv.model.numerics.block_lu`); None: one dense LU. ``jacobian_each_step``
    False: a step starts with the factorised iteration matrix of an earlier step of the
    same size (a new one only when the contraction test asks for it, Exudyn's
    ``modifiedNewtonJacUpdatePerStep = False``). ``partial_jacobian``: the costly elements'
    Jacobians kept, the others' refreshed at every step's predictor (module docstring; the
    caller checks that these elements stay outside the blocks)."""
    m = np.ascontiguousarray(mass, dtype=float)
    n = m.shape[0]
    z = np.zeros((n, n))
    stiff = z.copy() if stiffness is None else np.ascontiguousarray(stiffness, dtype=float)
    damp = z.copy() if damping is None else np.ascontiguousarray(damping, dtype=float)
    if blocks:
        bl, xs = block_structure(n, blocks)
        if not all(has_block_structure(a, bl) for a in (m, stiff, damp)):
            raise ValueError("the mass, stiffness or damping matrix couples two of the dense blocks")
    else:  # (partial Jacobians: every coordinate is outside the blocks)
        bl, xs = np.zeros((0, 2), np.int64), np.arange(n if partial_jacobian else 0, dtype=np.int64)
    (nb, nd), nx = work_sizes(bl, xs), len(xs)
    par = np.zeros(N_PAR)
    par[P_ALPHA_M], par[P_ALPHA_F], par[P_GAMMA], par[P_BETA] = coefficients(spectral_radius)
    par[P_RTOL], par[P_ATOL] = tolerance
    par[P_CONTRACT], par[P_MAXNORM] = contractivity, 1e38
    ip = np.zeros(N_IP, np.int64)
    ip[I_MAXIT], ip[I_MAXMOD], ip[I_ADAPT] = max_iterations, max_modified, int(adapt_initial_residual)
    ip[I_EACHSTEP] = int(jacobian_each_step)
    ip[I_EXTRAPOLATE] = int(extrapolate)
    partial = bool(partial_jacobian)
    ip[I_PARTIAL] = int(partial)
    vec = [np.zeros(n) for _ in range(12)]
    nonzero = (m != 0) | (stiff != 0) | (damp != 0)
    rp = np.concatenate(([0], np.cumsum(nonzero.sum(axis=1)))).astype(np.int64)
    return GaState(
        par,
        ip,
        *vec,
        m,
        stiff,
        damp,
        z.copy(),
        np.zeros(n, np.int64),
        bl,
        xs,
        np.zeros((nb, nx)),
        np.zeros(nd),
        np.zeros((nx, nx)),
        np.zeros(nx, np.int64),
        np.zeros(nx),
        np.zeros(nx),
        np.zeros((nx, nx)),
        rp,
        np.nonzero(nonzero)[1].astype(np.int64),
        np.zeros((n, n) if partial else (0, 0)),
        np.zeros((n, n) if partial else (0, 0)),
    )


def set_state(st: GaState, q, v, a, a_alg=None) -> None:
    """Start from (q, v, a); the algorithmic accelerations a_alg default to a (a restart,
    which also forgets the factorised iteration matrix)."""
    st.ip[I_FACTORED] = 0
    st.par[P_HPREV] = 0.0
    st.q[:], st.v[:], st.a[:] = q, v, a
    st.aa[:] = a if a_alg is None else a_alg


@njit(cache=True, inline="always")
def _predict(st):
    """The predictor from the start-of-step state (module docstring); a := 0."""
    par = st.par
    h, am, af, gamma, beta = par[P_H], par[P_ALPHA_M], par[P_ALPHA_F], par[P_GAMMA], par[P_BETA]
    c_q, c_v = h * h * (0.5 - beta), h * (1.0 - gamma)
    for i in range(st.q.shape[0]):
        aa = (af * st.a0[i] - am * st.aa0[i]) / (1.0 - am)
        st.aa[i] = aa
        st.q[i] = st.q0[i] + h * st.v0[i] + c_q * st.aa0[i] + h * h * beta * aa
        st.v[i] = st.v0[i] + c_v * st.aa0[i] + h * gamma * aa
        st.a[i] = 0.0


@njit(cache=True, inline="always")
def _factored_at(st, h):
    """True if the factorised iteration matrix is of step size h (within 1e-9 relative)."""
    return st.ip[I_FACTORED] != 0 and abs(st.par[P_HJAC] - h) <= 1e-9 * h


@njit(cache=True, inline="always")
def begin_step(st, h):
    """Start a step of size h from the current state: store it as the start of the step,
    predict, and ask for an evaluation with the Jacobian (the Jacobian of every step), or
    without it when the iteration matrix of an earlier step of this size is kept
    (``jacobian_each_step`` False); with partial Jacobians whose kept arrays hold one, with
    the Jacobians of the elements other than the costly ones in both cases."""
    for i in range(st.q.shape[0]):  # (loops: a slice copy compiles its error message's formatting)
        st.q0[i] = st.q[i]
        st.v0[i] = st.v[i]
        st.a0[i] = st.a[i]
        st.aa0[i] = st.aa[i]
    st.par[P_H] = h
    ip = st.ip
    ip[I_IT] = 0
    ip[I_FULL] = 0
    ip[I_RESTARTED] = 0
    ip[I_EXTRA] = 0
    ip[I_JACREQ] = 0
    ip[I_PHASE] = PH_PREDICTOR
    kept = ip[I_EACHSTEP] == 0 and _factored_at(st, h)
    if ip[I_KEPT]:
        ip[I_JAC] = JAC_PARTIAL
    else:
        ip[I_JAC] = JAC_NONE if kept else JAC_FULL
    _predict(st)
    for i in range(st.q.shape[0]):
        st.qp[i] = st.q[i]
    if ip[I_EXTRAPOLATE] and abs(st.par[P_HPREV] - h) <= 1e-9 * h:
        _add_correction(st)


@njit(cache=True, inline="always")
def _add_correction(st):
    """The predictor moved by the previous step's Newton correction e (the same step):
    q += e, v += gamma' e, a += beta' e, along the Newton iterates' own directions, so the
    converged state solves the same equations."""
    par = st.par
    h = par[P_H]
    bp = (1.0 - par[P_ALPHA_M]) / (h * h * par[P_BETA] * (1.0 - par[P_ALPHA_F]))
    gp = par[P_GAMMA] / (h * par[P_BETA])
    for i in range(st.q.shape[0]):
        st.q[i] += st.e[i]
        st.v[i] += gp * st.e[i]
        st.a[i] += bp * st.e[i]


@njit(cache=True, inline="always")
def _residual(st, f):
    """r = M a + K q + D v - f over the nonzero entries of M, K, D; returns ||r||_2 (NaN if not finite)."""
    n = st.q.shape[0]
    s = 0.0
    for i in range(n):
        ri = -f[i]
        for k in range(st.rp[i], st.rp[i + 1]):
            j = st.ci[k]
            ri += st.mass[i, j] * st.a[j] + st.stiff[i, j] * st.q[j] + st.damp[i, j] * st.v[j]
        st.r[i] = ri
        s += ri * ri
    return math.sqrt(s)


@njit(cache=True, inline="always")
def zero_outer(st, jq, jv):
    """Zero ``jq``, ``jv`` on the coordinates outside the dense blocks (xs, xs): with partial
    Jacobians the only entries the cheap elements write and :func:`_factor` reads (n_x^2
    entries instead of n^2 per evaluation with the Jacobian)."""
    xs = st.xs
    for a in range(xs.shape[0]):
        for c in range(xs.shape[0]):
            jq[xs[a], xs[c]] = 0.0
            jv[xs[a], xs[c]] = 0.0


@njit(cache=True, inline="always")
def _assemble(st, jq, jv, bp, gp):
    """st.lu = beta' M + K + gamma' D - jq - gamma' jv (the entries where M, K, D are zero: the
    same sum, bit for bit, without the zeros)."""
    s = st.lu
    n = st.q.shape[0]
    for i in range(n):
        for j in range(n):
            s[i, j] = (0.0 - jq[i, j]) - gp * jv[i, j]
        for k in range(st.rp[i], st.rp[i + 1]):
            j = st.ci[k]
            s[i, j] = bp * st.mass[i, j] + st.stiff[i, j] + gp * st.damp[i, j] - jq[i, j] - gp * jv[i, j]


@njit(cache=True, inline="always")
def _factor(st, jq, jv, blocks):
    """Factorise S = beta' M + K + gamma' D - df/dq - gamma' df/dv; with partial Jacobians
    (``st.jqk`` not empty) df/dq is the costly elements' kept ``st.jqk`` plus the other
    elements' ``jq``, read on the coordinates outside the blocks only (:func:`zero_outer`), the
    same for df/dv; with ``ip[I_JAC]`` = :data:`JAC_PARTIAL` and the blocks' factors of this
    step size only the Schur complement, from the kept factors (module docstring). False if
    singular. ``blocks``: ``st.blocks``, or None for a state without blocks (:func:`after_eval`)."""
    par = st.par
    h = par[P_H]
    bp = (1.0 - par[P_ALPHA_M]) / (h * h * par[P_BETA] * (1.0 - par[P_ALPHA_F]))
    gp = par[P_GAMMA] / (h * par[P_BETA])
    jqk, jvk = st.jqk, st.jvk
    partial = st.ip[I_JAC] == JAC_PARTIAL
    if partial and blocks is not None and blocks.shape[0] > 0 and _factored_at(st, h):
        xs, m, k, d = st.xs, st.mass, st.stiff, st.damp
        for a in range(xs.shape[0]):
            i = xs[a]
            for c in range(xs.shape[0]):
                j = xs[c]
                dq = jq[i, j] + jqk[i, j]
                dv = jv[i, j] + jvk[i, j]
                st.schur[a, c] = bp * m[i, j] + k[i, j] + gp * d[i, j] - dq - gp * dv - st.by[a, c]
        st.ip[I_PARTIALS] += 1
        ok = lu_factor(st.schur, st.schur, st.xpiv)
        st.ip[I_FACTORED] = int(ok)
        return ok
    s = st.lu
    if jqk.shape[0] > 0:  # the costly elements' Jacobians in jqk, jvk, the others' in jq, jv on (xs, xs) only
        _assemble(st, jqk, jvk, bp, gp)
        xs = st.xs
        for a in range(xs.shape[0]):
            for c in range(xs.shape[0]):
                s[xs[a], xs[c]] -= jq[xs[a], xs[c]] + gp * jv[xs[a], xs[c]]
    else:
        _assemble(st, jq, jv, bp, gp)
    if partial:
        st.ip[I_PARTIALS] += 1
    else:
        st.ip[I_JACOBIANS] += 1
        st.ip[I_KEPT] = int(jqk.shape[0] > 0)
    st.par[P_HJAC] = h
    if blocks is not None and blocks.shape[0] > 0:
        ok = block_factor(s, blocks, st.xs, st.piv, st.ys, st.dk, st.schur, st.xpiv, st.by)
    else:
        ok = lu_factor(s, s, st.piv)  # in place
    st.ip[I_FACTORED] = int(ok)
    return ok


@njit(cache=True, inline="always")
def _correct(st, blocks):
    """One Newton correction with the factorised S; the next evaluation without Jacobian."""
    par = st.par
    h = par[P_H]
    bp = (1.0 - par[P_ALPHA_M]) / (h * h * par[P_BETA] * (1.0 - par[P_ALPHA_F]))
    gp = par[P_GAMMA] / (h * par[P_BETA])
    if blocks is not None and blocks.shape[0] > 0:
        block_solve(st.lu, blocks, st.xs, st.piv, st.ys, st.dk, st.schur, st.xpiv, st.r, st.dx, st.tx, st.zx)
    else:
        lu_solve(st.lu, st.piv, st.r, st.dx)
    for i in range(st.q.shape[0]):
        st.q[i] -= st.dx[i]
        st.v[i] -= gp * st.dx[i]
        st.a[i] -= bp * st.dx[i]
    st.ip[I_IT] += 1
    st.ip[I_NEWTON] += 1
    st.ip[I_PHASE] = PH_ITERATE
    st.ip[I_JAC] = JAC_NONE
    return EVALUATE


@njit(cache=True, inline="always")
def _restart(st):
    """Back to the predictor of this step, one extra iteration after convergence; the
    evaluation brings the Jacobian."""
    ip = st.ip
    st.par[P_RES] = st.par[P_R0]
    st.par[P_LAST] = st.par[P_R0]
    ip[I_RESTARTED] = 1
    ip[I_EXTRA] = 1
    for i in range(st.q.shape[0]):
        st.q[i] = st.q0[i]
        st.v[i] = st.v0[i]
        st.a[i] = st.a0[i]
        st.aa[i] = st.aa0[i]
    _predict(st)
    ip[I_PHASE] = PH_JACOBIAN
    ip[I_JAC] = JAC_FULL
    return EVALUATE


@njit(cache=True, inline="always")
def _diverged(st):
    big = st.par[P_MAXNORM]
    sq = 0.0
    sv = 0.0
    for i in range(st.q.shape[0]):
        sq += st.q[i] * st.q[i]
        sv += st.v[i] * st.v[i]
    return not (sq < big and sv < big)


@njit(cache=True, inline="always")
def _iterate(st, res, blocks):
    """Convergence test and Newton control after an evaluation at a corrected state."""
    par, ip = st.par, st.ip
    it = ip[I_IT]
    if ip[I_ADAPT] and res > par[P_R0] and it <= 1:
        par[P_R0] = res
        par[P_LAST] = res
    par[P_RES] = res
    converged = res / par[P_R0] <= par[P_RTOL] or res <= par[P_ATOL]
    if converged and ip[I_EXTRA]:
        ip[I_EXTRA] = 0
        converged = False
    elif converged:
        return CONVERGED
    else:
        ip[I_EXTRA] = 0
        diverged = _diverged(st) or not math.isfinite(res)
        if diverged and ip[I_FULL]:
            return FAILED
        if not ip[I_FULL] and it > ip[I_MAXMOD]:
            ip[I_JACREQ] = 1
            ip[I_FULL] = 1
        contraction = res / par[P_LAST]
        par[P_LAST] = res
        if not ip[I_FULL] and (diverged or (contraction > par[P_CONTRACT] and it > 2)):
            ip[I_JACREQ] = 1
            if ip[I_RESTARTED]:
                ip[I_FULL] = 1
            if diverged or contraction > 2.0 or ip[I_FULL]:
                ip[I_JACREQ] = 0
                if it >= ip[I_MAXIT]:
                    return FAILED
                return _restart(st)
    if it >= ip[I_MAXIT]:
        return FAILED
    if ip[I_JACREQ] or ip[I_FULL]:  # a new Jacobian at this state first
        ip[I_JACREQ] = 0
        ip[I_PHASE] = PH_JACOBIAN
        ip[I_JAC] = JAC_FULL
        return EVALUATE
    return _correct(st, blocks)


@njit(cache=True, inline="always")
def after_eval(st, f, jq, jv, blocks):
    """Take the evaluation f (and df/dq, df/dv if ``ip[I_JAC]``: every element's, or with
    :data:`JAC_PARTIAL` those of the elements other than the costly ones, whose kept
    Jacobians are in ``st.jqk``, ``st.jvk``) at the current state;
    return :data:`EVALUATE` (evaluate again at the new current state, with the Jacobian if
    ``ip[I_JAC]``), :data:`CONVERGED` or :data:`FAILED`. ``blocks``: ``st.blocks``, or None
    for a state without dense blocks: the block elimination is then pruned at compile time
    (not compiled in; the rigid models' integrator)."""
    ip = st.ip
    ip[I_CALLS] += 1
    ip[I_JACCALLS] += ip[I_JAC] == JAC_FULL
    res = _residual(st, f)
    phase = ip[I_PHASE]
    if phase == PH_PREDICTOR:
        r0 = res if math.isfinite(res) else np.inf
        if r0 <= st.par[P_ATOL]:
            r0 = 2.0 * st.par[P_ATOL]
        if r0 == 0.0:  # (an absolute tolerance of 0 and an exact predictor)
            r0 = 1e-300
        st.par[P_R0] = r0
        st.par[P_RES] = r0
        st.par[P_LAST] = r0
    elif phase == PH_ITERATE:
        return _iterate(st, res, blocks)
    if not math.isfinite(res):
        return FAILED
    if ip[I_JAC] and not _factor(st, jq, jv, blocks):  # (no Jacobian: the kept factorisation)
        return FAILED
    return _correct(st, blocks)


@njit(cache=True, inline="always")
def finish_step(st):
    """After convergence: a_alg_n+1 = a* + (1 - alpha_f) / (1 - alpha_m) a_n+1; True if
    the state is finite."""
    par = st.par
    c = (1.0 - par[P_ALPHA_F]) / (1.0 - par[P_ALPHA_M])
    ok = True
    par[P_HPREV] = par[P_H]
    for i in range(st.q.shape[0]):
        st.aa[i] += c * st.a[i]
        st.e[i] = st.q[i] - st.qp[i]
        if not (math.isfinite(st.q[i]) and math.isfinite(st.v[i])):
            ok = False
    return ok
