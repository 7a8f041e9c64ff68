"""LU of a Newton matrix whose dense diagonal blocks couple only through a few shared
coordinates, by block elimination (numba, no allocation).

The matrix of the flexible-rings model has this structure: the balls of each bearing
row (3 Z coordinates, coupled all-to-all through the condensed rings) form a dense
diagonal block D_k, the blocks of two rows are zero (the rows interact only through
the carrier), and every block couples to the remaining coordinates x (the carrier and
the other members, a few tens) by B_k = S[x, k] and C_k = S[k, x]:

    S = [[A,   B_1, B_2, ...],
         [C_1, D_1,  0,  ...],
         [C_2,  0,  D_2, ...]]

Eliminating the blocks first, D_k = L_k U_k (partial pivoting inside the block),
Y_k = D_k^-1 C_k, and the Schur complement A - sum_k B_k Y_k (n_x x n_x) factored
last, costs sum_k (m_k^3 / 3 + m_k^2 n_x) multiply-adds instead of n^3 / 3 for the
whole matrix (rv40e's flexible rings: two 114-coordinate blocks and 21 others,
1.6 M instead of 5.1 M). A solve is then the blocks' triangular solves, the
Schur system and the back-substitution z_k = D_k^-1 r_k - Y_k z_x.

Pivoting is restricted to each block and to the Schur complement: exact in exact
arithmetic, numerically as good as the whole matrix's partial pivoting when the
blocks are well conditioned on their own (a mass-dominated iteration matrix
beta' M + ...: diagonally dominant in the balls' coordinates).
:func:`block_structure` checks that a matrix has the structure.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexrv.model.numerics.linalg import lu_factor, lu_solve


def block_structure(n: int, blocks) -> tuple[np.ndarray, np.ndarray]:
    """(blocks as int64 (K, 2) of (start, size), the other coordinates xs (int64)) of an
    n x n matrix with the dense diagonal blocks ``blocks`` [(start, size), ...]
    (contiguous, disjoint, inside 0..n-1)."""
    b = np.asarray(blocks, dtype=np.int64).reshape(-1, 2)
    inside = np.zeros(n, bool)
    for start, size in b:
        if size <= 0 or start < 0 or start + size > n or inside[start : start + size].any():
            raise ValueError(f"block ({start}, {size}) is empty, outside 0..{n - 1} or overlaps another")
        inside[start : start + size] = True
    return np.ascontiguousarray(b), np.flatnonzero(~inside).astype(np.int64)


def has_block_structure(s: np.ndarray, blocks: np.ndarray) -> bool:
    """True if the blocks of ``s`` are uncoupled (the off-diagonal block-block entries are zero)."""
    for i, (a0, am) in enumerate(blocks):
        for j, (b0, bm) in enumerate(blocks):
            if i != j and np.any(s[a0 : a0 + am, b0 : b0 + bm]):
                return False
    return True


def work_sizes(blocks: np.ndarray, xs: np.ndarray) -> tuple[int, int]:
    """(rows of ``ys``, length of ``dk``) of :func:`block_factor`: the blocks' total size and
    the sum of their squares."""
    return int(blocks[:, 1].sum()), int((blocks[:, 1] ** 2).sum())


@njit(cache=True)
def block_factor(s, blocks, xs, piv, ys, dk, schur, xpiv, by):
    """Factor ``s`` (n x n, read only) by block elimination (module docstring): ``dk`` (the
    sum of the blocks' squared sizes) the blocks' LU factors, each contiguous (the inner
    loops vectorise; a strided view of ``s`` ran 1.7x slower), ``piv`` (n,) their pivots
    (local to each block), ``ys`` (sum of the block sizes, n_x) the Y_k stacked, ``by``
    (n_x, n_x) the sum of the B_k Y_k (kept: a matrix that differs only in A has the Schur
    complement A - by), ``schur`` (n_x, n_x) and ``xpiv`` (n_x,) the factored Schur
    complement. False if a block or the Schur complement is singular."""
    nx = xs.shape[0]
    for a in range(nx):
        for c in range(nx):
            by[a, c] = 0.0
    o = 0
    o2 = 0
    for kb in range(blocks.shape[0]):
        b0, m = blocks[kb, 0], blocks[kb, 1]
        d = dk[o2 : o2 + m * m].reshape((m, m))
        for i in range(m):
            for j in range(m):
                d[i, j] = s[b0 + i, b0 + j]
        p = piv[b0 : b0 + m]
        if not lu_factor(d, d, p):
            return False
        y = ys[o : o + m]
        for i in range(m):  # C_k, then Y_k = U^-1 L^-1 P C_k in place
            for c in range(nx):
                y[i, c] = s[b0 + i, xs[c]]
        for k in range(m):
            pk = p[k]
            if pk != k:
                for c in range(nx):
                    y[k, c], y[pk, c] = y[pk, c], y[k, c]
        for i in range(m):
            for j in range(i):
                lij = d[i, j]
                if lij != 0.0:
                    for c in range(nx):
                        y[i, c] -= lij * y[j, c]
        for i in range(m - 1, -1, -1):
            for j in range(i + 1, m):
                uij = d[i, j]
                if uij != 0.0:
                    for c in range(nx):
                        y[i, c] -= uij * y[j, c]
            inv = 1.0 / d[i, i]
            for c in range(nx):
                y[i, c] *= inv
        for a in range(nx):  # the sum of B_k Y_k
            ra = xs[a]
            for i in range(m):
                bai = s[ra, b0 + i]
                if bai != 0.0:
                    for c in range(nx):
                        by[a, c] += bai * y[i, c]
        o += m
        o2 += m * m
    for a in range(nx):  # the Schur complement A - sum B_k Y_k
        for c in range(nx):
            schur[a, c] = s[xs[a], xs[c]] - by[a, c]
    return lu_factor(schur, schur, xpiv)


@njit(cache=True)
def block_solve(s, blocks, xs, piv, ys, dk, schur, xpiv, r, x, tx, zx):
    """x = S^-1 r from :func:`block_factor`'s factors (``s``: the factored matrix, for
    its couplings B_k); ``tx``, ``zx`` (n_x,): work; ``x`` may be ``r``."""
    nx = xs.shape[0]
    for a in range(nx):
        tx[a] = r[xs[a]]
    o2 = 0
    for kb in range(blocks.shape[0]):  # t_k = D_k^-1 r_k, r_x - B_k t_k
        b0, m = blocks[kb, 0], blocks[kb, 1]
        xk = x[b0 : b0 + m]
        lu_solve(dk[o2 : o2 + m * m].reshape((m, m)), piv[b0 : b0 + m], r[b0 : b0 + m], xk)
        o2 += m * m
        for a in range(nx):
            ra = xs[a]
            acc = 0.0
            for i in range(m):
                acc += s[ra, b0 + i] * xk[i]
            tx[a] -= acc
    lu_solve(schur, xpiv, tx, zx)
    for a in range(nx):
        x[xs[a]] = zx[a]
    o = 0
    for kb in range(blocks.shape[0]):  # z_k = t_k - Y_k z_x
        b0, m = blocks[kb, 0], blocks[kb, 1]
        for i in range(m):
            acc = 0.0
            for c in range(nx):
                acc += ys[o + i, c] * zx[c]
            x[b0 + i] -= acc
        o += m
