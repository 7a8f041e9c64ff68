"""Eigenfrequencies (free-free, constrained) from one shared sparse factorisation.

The generalized eigenproblem K x = w^2 M x is solved with
``scipy.sparse.linalg.eigsh`` in shift-invert mode; the shifted matrix is
factorised once by :func:`flexrv.fem.factor.factorize` (nested-dissection order,
SuperLU in symmetric mode), far less fill than SciPy's default COLAMD, which
``eigsh(sigma=...)`` would use.

Free-free bodies: the six rigid-body modes are *deflated*. With the shift
sigma = -(2 pi 1 Hz)^2 next to the rigid-body cluster (lambda = 0), the shift-inverted
rigid-body eigenvalues 1/(0 - sigma) exceed the elastic ones 1/(lambda_el - sigma) by ~1e8-1e10,
so without deflation the elastic Ritz values carry the round-off of that cluster (ARPACK's
random start vector gives a 0.1-0.5 % scatter on the first modes from run to run). So the
rigid-body subspace R is found first by subspace iteration with the same factorisation (three steps: its eigenvalues of
(K - sigma M)^-1 M dominate the elastic ones by that factor of ~1e8, so the subspace is exact
to round-off after two) and a Rayleigh–Ritz step; the elastic modes are then computed with the
M-orthogonal projector P = I - R R^T M applied on both sides of the shift-invert operator,
P (K - sigma M)^-1 P^T, for which the rigid-body modes are eigenvalue 0 and never compete. The
start vectors are deterministic (seeded), so reruns are bit-identical, and different start
vectors agree to ARPACK's tolerance (tests/test_fem_frequencies.py).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from flexrv.errors import ConvergenceError, InputError
from flexrv.fem.factor import factorize

#: rigid-body modes of a free three-dimensional body (3 translations, 3 rotations)
RIGID_BODY_MODES = 6


def _start_vector(size: int, seed: int = 0) -> np.ndarray:
    """Deterministic ARPACK start vector (ARPACK's own is random, so reruns differed)."""
    return np.random.default_rng(seed).standard_normal(size)


def rigid_body_subspace(
    K, M, solve, n_rigid: int = RIGID_BODY_MODES, seed: int = 0, steps: int = 3
) -> tuple[np.ndarray, np.ndarray]:
    """Rigid-body modes of a free body: (eigenvalues [rad^2/s^2] ~0, M-orthonormal (N, n_rigid)).

    Subspace iteration X <- (K - sigma M)^-1 M X with ``solve`` = (K - sigma M)^-1 (sigma < 0
    close to 0; module docstring), two guard vectors, Euclidean re-orthonormalisation each step,
    then a Rayleigh–Ritz step on (X^T K X, X^T M X) whose lowest ``n_rigid`` pairs are returned.
    Multiple (equal) eigenvalues are no difficulty for a block iteration, unlike for Lanczos.
    """
    import scipy.linalg as la

    X = np.random.default_rng(seed).standard_normal((K.shape[0], n_rigid + 2))
    for _ in range(steps):
        X, _ = np.linalg.qr(solve(M @ X))
    lam, Y = la.eigh(X.T @ (K @ X), X.T @ (M @ X))
    R = X @ Y[:, :n_rigid]
    return lam[:n_rigid], R


def free_dofs(n_dof: int, fixed_nodes: np.ndarray | None) -> np.ndarray:
    """DOF indices (Exudyn node-wise order) not belonging to ``fixed_nodes``."""
    if fixed_nodes is None or len(fixed_nodes) == 0:
        return np.arange(n_dof)
    mask = np.ones(n_dof, dtype=bool)
    fixed = np.asarray(fixed_nodes, dtype=np.int64)
    mask[(3 * fixed[:, None] + np.arange(3)).ravel()] = False
    return np.flatnonzero(mask)


def eigenmodes(
    K: sp.spmatrix,
    M: sp.spmatrix,
    n: int,
    fixed_nodes: np.ndarray | None = None,
    shift_hz: float | None = None,
    tol: float = 1e-8,
    solve0: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n`` eigenpairs of K x = w^2 M x.

    Parameters
    ----------
    K, M : stiffness [N/m] and mass [kg] (3N x 3N, node-wise DOFs).
    n : number of modes (free-free: includes the 6 rigid-body modes).
    fixed_nodes : nodes clamped in x, y, z (None: free-free).
    shift_hz : shift sigma = -(2 pi shift_hz)^2 (free body, default 1 Hz; the six rigid-body
        modes are deflated, module docstring) or, when None and
        nodes are fixed, an automatic shift: the lowest eigenvalue lambda_1 is
        estimated with a loose k = 1 run on K^-1 M and sigma = 0.8 lambda_1 is used.
        A clamped thin ring has a dense cluster of modes just above lambda_1, for
        which sigma = 0 converges slowly (measured 30 s -> see benchmarks).
    tol : ARPACK relative accuracy of the Ritz values.
    solve0 : an existing solver of K_ff (sigma = 0, fixed DOFs removed) to reuse.

    Returns
    -------
    freq_hz : (n,) frequencies [Hz] (free-free: the first six are the rigid-body modes, ~0
        (Rayleigh quotients of round-off size); tiny negative round-off eigenvalues are clipped to 0).
    modes : (3N, n) M-orthonormal mode shapes (zeros at fixed DOFs).
    """
    ndof = K.shape[0]
    dofs = free_dofs(ndof, fixed_nodes)
    if not 1 <= n < dofs.size - 1:
        raise InputError(f"number of modes n = {n} must be in [1, {dofs.size - 2}]")
    Kf = K[dofs][:, dofs]
    Mf = M[dofs][:, dofs]
    constrained = fixed_nodes is not None and len(fixed_nodes) > 0
    v0 = _start_vector(dofs.size)
    try:
        if constrained and shift_hz is None:
            solve = solve0 or factorize(Kf)
            op0 = sla.LinearOperator(Kf.shape, matvec=solve, dtype=float)
            lam1 = sla.eigsh(
                Kf, k=1, M=Mf, sigma=0.0, which="LM", OPinv=op0, tol=1e-3, v0=v0, return_eigenvectors=False
            )[0]
            sigma = 0.8 * float(lam1)
        else:
            sigma = -((2.0 * np.pi * (1.0 if shift_hz is None else shift_hz)) ** 2)
        solve = factorize(Kf - sigma * Mf)
        if constrained:
            op = sla.LinearOperator(Kf.shape, matvec=solve, dtype=float)
            w2, vec = sla.eigsh(Kf, k=n, M=Mf, sigma=sigma, which="LM", OPinv=op, tol=tol, v0=v0)
        else:
            w2_r, R = rigid_body_subspace(Kf, Mf, solve)
            MR = Mf @ R

            def deflated(b):  # P (K - sigma M)^-1 P^T b,  P = I - R R^T M
                x = solve(b - MR @ (R.T @ b))
                return x - R @ (MR.T @ x)

            n_el = n - RIGID_BODY_MODES
            if n_el > 0:
                op = sla.LinearOperator(Kf.shape, matvec=deflated, dtype=float)
                w2_e, vec_e = sla.eigsh(
                    Kf, k=n_el, M=Mf, sigma=sigma, which="LM", OPinv=op, tol=tol, v0=v0 - R @ (MR.T @ v0)
                )
                w2 = np.concatenate([w2_r, w2_e])
                vec = np.hstack([R, vec_e])
            else:
                w2, vec = w2_r[:n], R[:, :n]
    except sla.ArpackNoConvergence as exc:  # pragma: no cover - rare
        raise ConvergenceError(f"eigsh did not converge for {n} modes: {exc}") from None
    order = np.argsort(w2)
    w2, vec = w2[order], vec[:, order]
    modes = np.zeros((ndof, n))
    modes[dofs] = vec
    return np.sqrt(np.clip(w2, 0.0, None)) / (2.0 * np.pi), modes
