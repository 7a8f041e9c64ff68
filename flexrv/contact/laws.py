"""Normal-contact force laws on numpy arrays (vectorised over contacts).

The seeds (000/001/002/003) use the Adams IMPACT function

    F = k (q0 - q)^e - c_max * dq/dt * step(q, q0 - d, 1, q0, 0)   for q <= q0,
    F = 0                                                          for q >  q0,

i.e. a power-law spring on the penetration plus a damper whose coefficient
ramps smoothly from 0 at first touch to c_max at penetration d. Here it is
written on the signed gap g (> 0 open, < 0 penetration, delta = -g):

    F = k delta^e + c(delta) * (-dg/dt),   c(delta) = c_max * step(delta, 0, 0, d, 1),

and clipped at F >= 0 (a contact cannot pull). All functions return the force and
its partial derivatives so that Exudyn user functions can supply analytic
Jacobians.

Speed: the Exudyn force functions call :func:`impact_force` several times per
Newton iteration on a few dozen contacts, where numpy's per-operation overhead
dominates. If numba is installed, the same kernel (:func:`_impact_kernel`) is
compiled with ``numba.njit`` and used for float arrays; without numba it runs
as plain numpy. Both give the same numbers (one formula, two executors).
"""

from __future__ import annotations

import numpy as np

try:  # optional accelerator
    from numba import njit as _njit
except ImportError:  # pragma: no cover - numba absent: plain numpy
    _njit = None


def _step_and_slope(x, x0, h0, x1, h1):
    """Cubic Adams STEP and its derivative from one normalised coordinate (the
    single implementation behind :func:`adams_step`, :func:`adams_step_derivative`
    and :func:`impact_force`): s = clip((x - x0)/(x1 - x0), 0, 1),
    step = h0 + (h1 - h0) s^2 (3 - 2 s), d step/dx = (h1 - h0) 6 s (1 - s)/(x1 - x0)
    (zero outside the ramp, where s is clipped to 0 or 1). MSC Adams function
    reference (STEP)."""
    s = np.minimum(np.maximum((x - x0) / (x1 - x0), 0.0), 1.0)
    return h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s), (h1 - h0) * 6.0 * s * (1.0 - s) / (x1 - x0)


#: the STEP used inside the impact kernel (numba-compiled when available)
_STEP = _njit(cache=True)(_step_and_slope) if _njit is not None else _step_and_slope


def adams_step(x, x0, h0, x1, h1):
    """Cubic Adams STEP: h0 for x <= x0, h1 for x >= x1, C1 cubic in between.

    step = h0 + (h1 - h0) s^2 (3 - 2 s), s = (x - x0)/(x1 - x0) (MSC Adams
    function reference)."""
    return _step_and_slope(np.asarray(x, dtype=float), x0, h0, x1, h1)[0]


def adams_step_derivative(x, x0, h0, x1, h1):
    """d step / dx of :func:`adams_step`."""
    return _step_and_slope(np.asarray(x, dtype=float), x0, h0, x1, h1)[1]


def _impact_kernel(gap, gap_rate, k, exponent, c_max, depth):
    """Body of :func:`impact_force` on float arrays (numba-compilable)."""
    delta = np.maximum(-gap, 0.0)
    spring = k * delta**exponent
    dspring = k * exponent * delta ** (exponent - 1.0)  # used only where delta > 0
    step, dstep = _STEP(delta, 0.0, 0.0, depth, 1.0)
    c = c_max * step
    force = spring - c * gap_rate
    inactive = ~((delta > 0) & (force > 0))  # open or pulling: no force
    dforce_dgap = np.where(inactive, 0.0, (c_max * dstep) * gap_rate - dspring)  # d/dgap = -d/ddelta
    dforce_dgap_rate = np.where(inactive, 0.0, -c)
    return np.where(inactive, 0.0, force), dforce_dgap, dforce_dgap_rate


_impact_jit = _njit(cache=True)(_impact_kernel) if _njit is not None else None


def impact_force(gap, gap_rate, k, exponent, c_max, depth):
    """Impact law on the signed gap (seeds 000/001 IMPACT function).

    Parameters
    ----------
    gap : array_like
        Signed gap g [m]; penetration delta = -g where g < 0.
    gap_rate : array_like
        dg/dt [m/s] (negative while closing).
    k : array_like
        Stiffness constant [N/m^e].
    exponent : float
        Force exponent e (1.5 Hertz point, 10/9 line contact, 1 linear).
    c_max : array_like
        Maximum damping coefficient [N s/m].
    depth : float
        Penetration d [m] at which damping reaches c_max.

    Returns
    -------
    force, dforce_dgap, dforce_dgap_rate : ndarray
        Compressive normal force [N] (>= 0) and its partial derivatives.
    """
    gap = np.asarray(gap, dtype=float)
    gap_rate = np.asarray(gap_rate, dtype=float)
    if (_impact_jit is not None and gap.ndim >= 1 and gap.shape == gap_rate.shape and np.ndim(k) == 0
            and np.ndim(c_max) == 0):
        return _impact_jit(gap, gap_rate, float(k), float(exponent), float(c_max), float(depth))
    return _impact_kernel(gap, gap_rate, k, exponent, c_max, depth)
