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

One formula: the law at one contact is :func:`_impact_scalar` (numba-compiled);
the force groups' compiled kernels call it per contact and :func:`impact_force`
loops it over (broadcast) arrays.
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


def _impact_scalar(gap, gap_rate, k, exponent, c_max, depth):
    """The impact law at one contact (the single implementation: compiled
    kernels of the force groups call it directly, :func:`impact_force` loops it
    over arrays). Returns (force, dforce_dgap, dforce_dgap_rate); all zero where
    the contact is open or the damped force would pull."""
    delta = max(-gap, 0.0)
    if not delta > 0.0:
        return 0.0, 0.0, 0.0
    step, dstep = _STEP(delta, 0.0, 0.0, depth, 1.0)
    c = c_max * step
    force = k * delta**exponent - c * gap_rate
    if not force > 0.0:  # pulling: no force
        return 0.0, 0.0, 0.0
    dspring = k * exponent * delta ** (exponent - 1.0)
    return force, (c_max * dstep) * gap_rate - dspring, -c  # d/dgap = -d/ddelta


_impact_one = _njit(cache=True)(_impact_scalar) if _njit is not None else _impact_scalar


def _impact_kernel(gap, gap_rate, k, exponent, c_max, depth, force, dgap, drate):
    """:func:`_impact_scalar` over flat float arrays of equal length (gap, rate,
    k, c_max), results into ``force``, ``dgap``, ``drate``."""
    for i in range(gap.shape[0]):
        force[i], dgap[i], drate[i] = _impact_one(gap[i], gap_rate[i], k[i], exponent, c_max[i], depth)


_impact_jit = _njit(cache=True)(_impact_kernel) if _njit is not None else _impact_kernel


def impact_force(gap, gap_rate, k, exponent, c_max, depth):
    """Impact law on the signed gap (:cite:`seed000,seed001` IMPACT function).

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
    gap, gap_rate, k, c_max = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (gap, gap_rate, k, c_max)))
    shape = gap.shape
    flat = [np.ascontiguousarray(a).ravel() for a in (gap, gap_rate, k, c_max)]
    out = np.empty((3, flat[0].size))
    _impact_jit(flat[0], flat[1], flat[2], float(exponent), flat[3], float(depth), out[0], out[1], out[2])
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


def _friction_scalar(v_slide, v_reg):
    """Regularised Coulomb friction factor at one contact (the single implementation:
    the pin and needle kernels call it per contact, :func:`friction_factor` over arrays):

        s(v) = v / sqrt(v^2 + v_reg^2),   ds/dv = v_reg^2 / (v^2 + v_reg^2)^(3/2),

    so the friction force is -mu F_n s(v_t) (along the sliding direction), smooth and
    odd in v, |s| < 1, s -> sign(v) for |v| >> v_reg (s = 0.995 at v = 10 v_reg).
    Below v_reg it acts as a viscous damper of coefficient mu F_n / v_reg (the
    regularisation of e.g. Pennestri et al. 2016, "Review and comparison of dry
    friction force models", Nonlinear Dyn. 83; algebraic form chosen over tanh for
    its cheap, exact derivative). Returns (s, ds/dv); v_reg <= 0 gives (0, 0)
    (friction off)."""
    if not v_reg > 0.0:
        return 0.0, 0.0
    r2 = v_slide * v_slide + v_reg * v_reg
    root = np.sqrt(r2)
    return v_slide / root, v_reg * v_reg / (r2 * root)


_friction_one = _njit(cache=True)(_friction_scalar) if _njit is not None else _friction_scalar


def friction_factor(v_slide, v_reg):
    """:func:`_friction_scalar` over an array of sliding speeds [m/s]: (s, ds/dv)."""
    v = np.asarray(v_slide, dtype=float)
    out = np.array([_friction_one(float(x), float(v_reg)) for x in v.ravel()]).reshape(v.shape + (2,))
    return out[..., 0], out[..., 1]


def effective_pin_friction(mu_disc: float, mu_seat: float) -> float:
    """Effective Coulomb coefficient of a pin free to turn in its housing groove:
    mu_eff = min(mu_disc, mu_seat).

    Assumptions: the pin is massless (no rotary inertia: its spin follows the
    friction balance at once), the groove radius equals the pin radius (both
    friction forces act at the same lever arm r_pin), and the seat load equals the
    disc load F_n (the pin is a two-force member across its diameter; the groove's
    distributed reaction is lumped into one line contact opposite the flank
    contact). The moment balance of the pin about its axis then gives equal
    tangential forces f at the flank and in the seat, each bounded by its Coulomb
    limit mu_i F_n. A pin stuck in its seat slides on the disc (f = mu_disc F_n), a
    pin rolling on the disc slides in its seat (f = mu_seat F_n); the pin turns so
    that sliding happens where it is cheaper, f = min(mu_disc, mu_seat) F_n, and
    because the groove and pin radii are equal the sliding speed in the seat equals
    the flank sliding speed v_t: the dissipated power is min(mu) F_n |v_t| either
    way. So the pin kernel treats the pin as fixed with mu_eff (no pin spin DOF).
    Not modelled: the pin's spin inertia (I omega_dot ~ 1e-7 N m at rv40e's pin
    accelerations, against mu F r ~ 0.05 * 500 N * 3 mm = 0.08 N m) and
    pin bending (the seat load then differs from F_n)."""
    return float(min(mu_disc, mu_seat))
