"""The per-iteration arithmetic of the quasi-static equilibrium solver
(:meth:`flexrv.model.quasi_static.StaticModel.solve`) and the per-position image of the
periodic route (:func:`flexrv.model.quasi_static.equilibrium_path`), compiled: at the model's 15-30
coordinates numpy's call overhead (LAPACK's solve with its checks, the norms, the
temporaries) costs more than the arithmetic, about 40 us per iteration against the fused
force kernel's 25-55 us, so these loops are used instead. Verified against numpy in
``tests/test_quasi_static.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from flexrv.model.numerics.linalg import lu_factor, lu_solve


@njit(cache=True)
def scaled_norms(f, arm):
    """(max_i |f_i / arm_i|, |f / arm|_2): the solver's residual measure and merit."""
    big, ss = 0.0, 0.0
    for i in range(f.shape[0]):
        x = f[i] / arm[i]
        ss += x * x
        if abs(x) > big or x != x:  # a NaN propagates, as numpy's max does
            big = abs(x)
    return big, math.sqrt(ss)


@njit(cache=True)
def largest_stiffness_per_mass(jac, mass):
    """max_i |J_ii| / m_i (NaN if any is NaN, as numpy's max)."""
    big = 0.0
    for i in range(mass.shape[0]):
        x = abs(jac[i, i]) / mass[i]
        if x > big or x != x:
            big = x
    return big


@njit(cache=True)
def shifted_newton_step(jac, f, shift, mass, arm, max_step, halve, a, piv, dq):
    """dq = (shift diag(mass) - jac)^-1 f, scaled down so that max_i |dq_i| arm_i <= max_step,
    then halved if ``halve``; ``a`` (n, n) and ``piv`` (n,) are work arrays. Returns (ok,
    max_i |dq_i| arm_i, max_i |dq_i|) of the final step; ok is False (dq undefined) if the
    matrix is singular or the step is not finite."""
    n = f.shape[0]
    for i in range(n):
        for j in range(n):
            a[i, j] = -jac[i, j]
        a[i, i] += shift * mass[i]
    if not lu_factor(a, a, piv):
        return False, 0.0, 0.0
    lu_solve(a, piv, f, dq)
    size = 0.0
    for i in range(n):
        if not math.isfinite(dq[i]):
            return False, 0.0, 0.0
        size = max(size, abs(dq[i]) * arm[i])
    scale = max_step / size if size > max_step else 1.0
    if halve:
        scale *= 0.5
    size, raw = 0.0, 0.0
    for i in range(n):
        dq[i] *= scale
        size = max(size, abs(dq[i]) * arm[i])
        raw = max(raw, abs(dq[i]))
    return True, size, raw


def work_arrays(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The (a, piv) work arrays of :func:`shifted_newton_step` for n coordinates."""
    return np.empty((n, n)), np.empty(n, dtype=np.int64)


@njit(cache=True)
def turned_deviation(q_earlier, kin_earlier, kin_now, ia, ib, c, s):
    """kin_now + d with d = q_earlier - kin_earlier, its in-plane pairs (d[ia], d[ib]) turned by
    the angle of cosine ``c`` and sine ``s``: the image of an equilibrium one crank revolution
    later (:func:`flexrv.model.quasi_static._periodic_image`). A new array."""
    out = q_earlier - kin_earlier
    for j in range(ia.shape[0]):
        x, y = out[ia[j]], out[ib[j]]
        out[ia[j]] = c * x - s * y
        out[ib[j]] = s * x + c * y
    for i in range(out.shape[0]):
        out[i] += kin_now[i]
    return out
