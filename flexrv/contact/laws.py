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
"""

from __future__ import annotations

import numpy as np


def adams_step(x, x0, h0, x1, h1):
    """Cubic Adams STEP: h0 for x <= x0, h1 for x >= x1, C1 cubic in between.

    step = h0 + (h1 - h0) s^2 (3 - 2 s), s = (x - x0)/(x1 - x0) (MSC Adams
    function reference)."""
    x = np.asarray(x, dtype=float)
    s = np.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s)


def adams_step_derivative(x, x0, h0, x1, h1):
    """d step / dx of :func:`adams_step`."""
    x = np.asarray(x, dtype=float)
    s = (x - x0) / (x1 - x0)
    inside = (s > 0.0) & (s < 1.0)
    return np.where(inside, (h1 - h0) * 6.0 * s * (1.0 - s) / (x1 - x0), 0.0)


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
    delta = np.maximum(-gap, 0.0)
    spring = k * delta**exponent
    dspring = np.where(delta > 0, k * exponent * delta ** (exponent - 1.0), 0.0)
    c = c_max * adams_step(delta, 0.0, 0.0, depth, 1.0)
    dc = c_max * adams_step_derivative(delta, 0.0, 0.0, depth, 1.0)
    damping = -c * gap_rate
    force = spring + damping
    active = (delta > 0) & (force > 0)
    force = np.where(active, force, 0.0)
    # d/dgap = -d/ddelta
    dforce_dgap = np.where(active, -(dspring - dc * gap_rate), 0.0)
    dforce_dgap_rate = np.where(active, -c, 0.0)
    return force, dforce_dgap, dforce_dgap_rate
