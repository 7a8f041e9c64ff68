"""Sparse factorisation of the symmetric positive definite FE matrices, and the
condensation B^T A^-1 B from half the triangular solves.

Ordering: the fill of a sparse LU or Cholesky factor depends on the elimination
order. Nested dissection (George 1973, :cite:`george1973`) orders a separator of
the graph after the two parts it splits, recursively; on three-dimensional meshes
it keeps much less fill than minimum degree. The order comes from METIS's
multilevel nested dissection (Karypis & Kumar 1998, :cite:`karypis1998`; the
``pymetis`` wheel) on the graph of the matrix compressed to supervariables (runs
of consecutive columns with the same pattern: the three DOFs of a node), then
expanded back to the DOFs. SuperLU factorises the permuted matrix in its natural
order, symmetric mode, diagonal pivots. Against SuperLU's own MMD(A^T + A) order
on the carrier and disc bodies it keeps a half to two thirds of the fill and factorises two to
five times faster (docs/benchmarks.md, benchmarks/bench_bodies.py).

Condensation: with diagonal pivots, the LU factor of a symmetric matrix is
A = L U, U = D L^T (L unit lower triangular, D = diag(U) > 0 for a positive
definite A), so B^T A^-1 B = V^T V with V = D^-1/2 L^-1 B: one forward
substitution instead of a forward and a backward one. SuperLU's own solve treats
the right-hand sides one column at a time through its supernodes; here the
forward substitution runs supernode by supernode on all columns at once (a dense
triangular solve and a matrix product per supernode, level-3 BLAS), the
supernodes read from the factor's L (consecutive columns whose patterns nest),
each on the columns that are non-zero in its rows: a local load (a pin patch)
fills only the supernodes on its elimination-tree path (on the rv40e disc, 4 % of
L^-1 B is non-zero), so the substitution costs a fraction of a full solve.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from flexrv.errors import InputError


def _supervariables(A: sp.csc_matrix) -> np.ndarray:
    """Start index of each run of consecutive columns with the same sparsity pattern,
    plus n at the end. Runs are told apart by (count, sum, sum of squares) of their
    row indices: a false merge could only worsen the order, never the factor."""
    n = A.shape[0]
    cnt = np.diff(A.indptr)
    idx = A.indices.astype(np.int64)
    starts = A.indptr[:-1]
    nonempty = cnt > 0
    s1 = np.zeros(n, dtype=np.int64)
    s2 = np.zeros(n, dtype=np.int64)
    s1[nonempty] = np.add.reduceat(idx, starts[nonempty])
    s2[nonempty] = np.add.reduceat(idx * idx, starts[nonempty])
    same = (cnt[1:] == cnt[:-1]) & (s1[1:] == s1[:-1]) & (s2[1:] == s2[:-1]) & nonempty[1:]
    return np.concatenate([[0], np.flatnonzero(~same) + 1, [n]])


def nested_dissection_order(A: sp.spmatrix) -> np.ndarray:
    """Fill-reducing symmetric permutation ``perm`` of a structurally symmetric
    matrix (eliminate DOF ``perm[0]`` first): METIS nested dissection on the
    supervariable graph (module doc)."""
    import pymetis

    A = sp.csc_matrix(A)
    n = A.shape[0]
    bounds = _supervariables(A)
    size = np.diff(bounds)
    ns = size.size
    if ns < 3:
        return np.arange(n)
    agg = sp.csr_matrix((np.ones(n), (np.arange(n), np.repeat(np.arange(ns), size))), shape=(n, ns))
    pattern = sp.csc_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    G = sp.csr_matrix(agg.T @ pattern @ agg)
    G.setdiag(0)
    G.eliminate_zeros()
    if G.nnz == 0:
        return np.arange(n)
    G.sort_indices()
    order = np.asarray(pymetis.nested_dissection(adjacency=pymetis.CSRAdjacency(G.indptr, G.indices))[0])
    lengths = size[order]
    offsets = np.cumsum(lengths) - lengths
    return np.repeat(bounds[order] - offsets, lengths) + np.arange(n)


class SymmetricFactor:
    """Factor of a sparse symmetric positive definite matrix A (module doc).

    Calling it solves: ``factor(b)`` = A^-1 b for (n,) or (n, k) ``b``;
    :meth:`whitened` gives V with B^T A^-1 B = V^T V."""

    def __init__(self, A: sp.spmatrix):
        A = sp.csc_matrix(A)
        if A.shape[0] != A.shape[1]:
            raise InputError(f"matrix of shape {A.shape} is not square")
        self.n = A.shape[0]
        self.perm = nested_dissection_order(A)
        self.inverse = np.empty_like(self.perm)
        self.inverse[self.perm] = np.arange(self.n)
        Ap = sp.csc_matrix(A[self.perm][:, self.perm])
        self._lu = sla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})

    @property
    def nnz(self) -> int:
        """Stored entries of L + U (the fill)."""
        return int(self._lu.nnz)

    def __call__(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        return self._lu.solve(b[self.perm])[self.inverse]

    def whitened(self, B) -> np.ndarray:
        """V = D^-1/2 L^-1 P B (n, m) for the (n, m) dense or sparse ``B``, so that
        B^T A^-1 B = V^T V (rows in the factor's order; module doc). Pass all
        right-hand sides in one call: the supernodes are read from L each time."""
        lu = self._lu
        if not np.array_equal(lu.perm_r, lu.perm_c):
            raise InputError("the factor pivoted off the diagonal: the matrix is not symmetric positive definite")
        q = np.argsort(lu.perm_r)
        d = lu.U.diagonal()
        if not np.all(d > 0.0):
            raise InputError("non-positive pivot: the matrix is not symmetric positive definite")
        rows = self.perm[q]
        B = B.tocsr()[rows].toarray() if sp.issparse(B) else np.asarray(B, dtype=float)[rows]
        Y = np.ascontiguousarray(B.reshape(self.n, -1), dtype=float)
        probe = Y @ np.random.default_rng(0).standard_normal(Y.shape[1])
        _forward_supernodal(lu.L, Y)
        Y /= np.sqrt(d)[:, None]
        energy = probe @ lu.solve(probe[np.argsort(q)])[q]  # the same quadratic form by SuperLU's solve
        vr = Y @ np.random.default_rng(0).standard_normal(Y.shape[1])
        if not abs(vr @ vr - energy) <= 1e-9 * abs(energy):
            raise InputError(f"forward substitution check failed: {vr @ vr!r} against {energy!r}")
        return Y


def _supernodes(L: sp.csc_matrix) -> np.ndarray:
    """Column bounds of the supernodes of a unit lower triangular L (sorted CSC,
    diagonal first): column j + 1 joins column j's supernode when L[j + 1, j] is
    stored and column j + 1 has one entry fewer. That decides: in a Cholesky pattern
    (the symmetric-mode LU of a symmetric matrix), L[j + 1, j] != 0 makes column j's
    pattern below j + 1 a subset of column j + 1's, so equal counts mean equal
    patterns (the parent of j in the elimination tree is j + 1);
    :meth:`SymmetricFactor.whitened` also checks its result against a full solve."""
    n = L.shape[0]
    ip, ix = L.indptr, L.indices
    cnt = np.diff(ip)
    j = np.arange(n - 1)
    second = np.where(cnt[:-1] > 1, ix[np.minimum(ip[:-2] + 1, L.nnz - 1)], -1)
    same = (second == j + 1) & (cnt[:-1] == cnt[1:] + 1)
    return np.concatenate([[0], np.flatnonzero(~same) + 1, [n]])


def _forward_supernodal(L: sp.csc_matrix, Y: np.ndarray) -> None:
    """Y <- L^-1 Y in place (Y C-contiguous (n, m)), supernode by supernode, each on
    the columns of Y that are non-zero in its rows: local loads (a pin patch, a bore)
    reach only the supernodes on their elimination-tree paths, so most blocks of Y
    stay zero and are skipped (exactly: a zero block neither changes nor updates)."""
    from scipy.linalg.blas import dtrsm

    L = sp.csc_matrix(L)
    L.sort_indices()
    ip, ix, data = L.indptr, L.indices, L.data
    if not np.array_equal(ix[ip[:-1]], np.arange(L.shape[0])):
        raise InputError("the factor's L does not store its unit diagonal first in every column")
    bounds = _supernodes(L)
    m = Y.shape[1]
    for a, b in zip(bounds[:-1], bounds[1:]):
        Yb = Y[a:b]
        live = Yb.any(axis=0)
        k = np.count_nonzero(live)
        if k == 0:
            continue
        s = b - a
        rows = ix[ip[a] : ip[a + 1]]
        block = np.zeros((rows.size, s), order="F")
        for c in range(s):
            block[c:, c] = data[ip[a + c] : ip[a + c + 1]]
        cols = np.flatnonzero(live) if 2 * k < m else slice(None)
        Ys = Yb[:, cols]
        if s > 1:
            Ys = dtrsm(1.0, block[:s], Ys.T, side=1, lower=1, trans_a=1, diag=1).T
            Yb[:, cols] = Ys
        if rows.size > s:
            Y[np.ix_(rows[s:], cols) if 2 * k < m else rows[s:]] -= block[s:] @ Ys


def factorize(A: sp.spmatrix) -> SymmetricFactor:
    """Factor of a sparse symmetric positive definite matrix (module doc); the
    returned :class:`SymmetricFactor` is called as ``solve(b)`` with (n,) or (n, k)
    right-hand sides."""
    return SymmetricFactor(A)
