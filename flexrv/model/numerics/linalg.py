"""Small dense linear algebra for the compiled force elements (numba, no allocation).

The local systems of the condensed bodies are m x m with m = 3 n_discs (rims),
2 n_cranks (carrier support points), the ball count (condensed rings) or 3 (one
ball): LAPACK's call overhead and work arrays cost more than the arithmetic, so
these loops are used instead. Each is verified against numpy in
``tests/test_kernel.py`` (inverse, product), ``tests/test_elements.py``
(Cholesky, adjugate, condensed step) and ``tests/test_integrator.py`` (LU).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def inv_small(a, out):
    """out = a^-1 for a small dense square matrix (Gauss-Jordan with partial pivoting;
    ``a`` is overwritten)."""
    m = a.shape[0]
    for r in range(m):
        for c in range(m):
            out[r, c] = 1.0 if r == c else 0.0
    for k in range(m):
        p = k
        big = abs(a[k, k])
        for r in range(k + 1, m):
            if abs(a[r, k]) > big:
                big, p = abs(a[r, k]), r
        if p != k:
            for c in range(m):
                a[k, c], a[p, c] = a[p, c], a[k, c]
                out[k, c], out[p, c] = out[p, c], out[k, c]
        d = 1.0 / a[k, k]
        for c in range(m):
            a[k, c] *= d
            out[k, c] *= d
        for r in range(m):
            w = a[r, k]
            if r != k and w != 0.0:
                for c in range(m):
                    a[r, c] -= w * a[k, c]
                    out[r, c] -= w * out[k, c]


@njit(cache=True)
def matmul_small(a, b, out):
    """out = a @ b (small dense, no allocation; ``out`` must not alias a or b)."""
    for r in range(a.shape[0]):
        for c in range(b.shape[1]):
            acc = 0.0
            for k in range(a.shape[1]):
                acc += a[r, k] * b[k, c]
            out[r, c] = acc


@njit(cache=True)
def condensed_step(c, j, sign, res, tmp, inv, step):
    """step = (I + sign C J)^-1 res: the Newton correction of a condensation's local
    solve (the rim offsets, sign -1: R = delta - C Q(q + delta); the carrier's support
    points, sign +1: R = u + C f_s(d0 - u)); inv = the inverse (kept for the condensed
    tangent), tmp: scratch. All (m, m) / (m,), no allocation."""
    m = res.shape[0]
    matmul_small(c, j, tmp)
    for r in range(m):
        for k in range(m):
            tmp[r, k] = (1.0 if r == k else 0.0) + sign * tmp[r, k]
    inv_small(tmp, inv)
    for r in range(m):
        acc = 0.0
        for k in range(m):
            acc += inv[r, k] * res[k]
        step[r] = acc


@njit(cache=True)
def cholesky(m):
    """In-place lower Cholesky factor of a small SPD matrix m (pivots floored at 1e-300)."""
    n = m.shape[0]
    for j in range(n):
        d = m[j, j]
        for k in range(j):
            d -= m[j, k] * m[j, k]
        d = math.sqrt(max(d, 1e-300))
        m[j, j] = d
        for i in range(j + 1, n):
            v = m[i, j]
            for k in range(j):
                v -= m[i, k] * m[j, k]
            m[i, j] = v / d


@njit(cache=True)
def cholesky_solve(m, b):
    """b <- m^-1 b with m's lower Cholesky factor (from :func:`cholesky`)."""
    n = m.shape[0]
    for i in range(n):
        v = b[i]
        for k in range(i):
            v -= m[i, k] * b[k]
        b[i] = v / m[i, i]
    for i in range(n - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, n):
            v -= m[k, i] * b[k]
        b[i] = v / m[i, i]


@njit(cache=True)
def adjugate3(k, adj):
    """The adjugate of the 3x3 block k[:3, :3] into ``adj`` (k^-1 = adj / det); returns
    det (cofactor expansion along the first row)."""
    adj[0, 0] = k[1, 1] * k[2, 2] - k[1, 2] * k[2, 1]
    adj[0, 1] = k[0, 2] * k[2, 1] - k[0, 1] * k[2, 2]
    adj[0, 2] = k[0, 1] * k[1, 2] - k[0, 2] * k[1, 1]
    adj[1, 0] = k[1, 2] * k[2, 0] - k[1, 0] * k[2, 2]
    adj[1, 1] = k[0, 0] * k[2, 2] - k[0, 2] * k[2, 0]
    adj[1, 2] = k[0, 2] * k[1, 0] - k[0, 0] * k[1, 2]
    adj[2, 0] = k[1, 0] * k[2, 1] - k[1, 1] * k[2, 0]
    adj[2, 1] = k[0, 1] * k[2, 0] - k[0, 0] * k[2, 1]
    adj[2, 2] = k[0, 0] * k[1, 1] - k[0, 1] * k[1, 0]
    return k[0, 0] * adj[0, 0] + k[0, 1] * adj[1, 0] + k[0, 2] * adj[2, 0]


@njit(cache=True)
def lu_factor(a, lu, piv):
    """LU factorisation with partial pivoting of a (n x n) into lu, piv (``lu`` may be ``a``:
    in place); False if singular."""
    n = a.shape[0]
    for i in range(n):  # (loops: a slice copy compiles its error message's formatting)
        for j in range(n):
            lu[i, j] = a[i, j]
    for k in range(n):
        p, big = k, abs(lu[k, k])
        for i in range(k + 1, n):
            if abs(lu[i, k]) > big:
                p, big = i, abs(lu[i, k])
        piv[k] = p
        if big == 0.0 or not math.isfinite(big):
            return False
        if p != k:
            for j in range(n):
                lu[k, j], lu[p, j] = lu[p, j], lu[k, j]
        inv = 1.0 / lu[k, k]
        for i in range(k + 1, n):
            lu[i, k] *= inv
            lik = lu[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    lu[i, j] -= lik * lu[k, j]
    return True


@njit(cache=True)
def lu_solve(lu, piv, b, x):
    """x = A^-1 b from :func:`lu_factor`'s lu, piv."""
    n = lu.shape[0]
    for i in range(n):
        x[i] = b[i]
    for k in range(n):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]
    for i in range(n):
        s = x[i]
        for j in range(i):
            s -= lu[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= lu[i, j] * x[j]
        x[i] = s / lu[i, i]
