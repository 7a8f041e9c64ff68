"""Quasi-static ball load distribution of the main bearing (back-to-back pair of
angular contact ball bearings) on rigid rings: 5-DOF Jones–Harris type model.

Model (Jones 1960; Harris & Kotzalas, *Advanced Concepts of Bearing Technology*,
2007, ch. 1 "distribution of internal loading", low-speed form without centrifugal
and gyroscopic ball loads — at the carrier's 7-40 deg/s they are ~1e-3 N):

The inner ring (carrier) moves rigidly by u = (d_x, d_y, d_z, th_x, th_y) relative
to the outer ring (housing). For ball j of row r at azimuth psi_j, with the
locus of inner groove curvature centres R_i = d_m/2 + (f_i - 1/2) D cos a0 at
axial position z_ri = z_r + (f_i - 1/2) D s_r sin a0 (s_r = axial sign of the
row's outer contact, :mod:`flexrv.geometry.bearing`), the distance between the
inner and outer groove curvature centres becomes

    A_1 = A sin a0 + p_r + s_r [d_z + R_i (th_x sin psi - th_y cos psi)]   (axial),
    A_2 = A cos a0 + (d_x + th_y z_ri) cos psi + (d_y - th_x z_ri) sin psi  (radial),

A = (f_i + f_o - 1) D (:attr:`BallBearingGeometry.curvature_center_distance`),
p_r the axial preload (interference) of the row. The total elastic approach is
delta_j = sqrt(A_1^2 + A_2^2) - A, the loaded contact angle a_j = atan(A_1/A_2),
and Q_j = K_n delta_j^1.5 with K_n the series combination of the inner and outer
Hertz constants (:func:`flexrv.contact.hertz.point_contact_stiffness` on the
radii of :meth:`BallBearingGeometry.contact_radii` at the loaded angle,
:func:`flexrv.contact.hertz.series_stiffness`). Each ball pushes the inner ring
with -Q_j n_j, n_j = (cos a_j cos psi, cos a_j sin psi, s_r sin a_j), acting
through the inner groove curvature centre; the five equilibrium equations
(forces x, y, z and moments about x, y at the bearing centre) are solved by a
damped Newton method with an analytic Jacobian (K_n's weak dependence on a_j is
lagged), vectorised over all balls.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.contact.hertz import point_contact, point_contact_stiffness, series_stiffness
from flexrv.errors import ConvergenceError, InputError


@dataclass(frozen=True)
class BallLoadResult:
    """Solution of :func:`ball_load_distribution` (arrays (n_rows, Z)).

    displacement : (5,) d_x, d_y, d_z [m], th_x, th_y [rad] of the inner ring;
    loads : ball loads Q [N]; contact_angle : loaded contact angles [rad];
    approach : total elastic approach delta [m]; azimuth : (Z,) [rad];
    stiffness_constant : K_n [N/m^1.5] per ball; max_load [N]; max_index : (row, ball);
    row_forces : (n_rows, 3) force of each row on the inner ring [N];
    residual : max equilibrium residual [N or N m]; iterations : Newton iterations.
    """

    displacement: np.ndarray
    loads: np.ndarray
    contact_angle: np.ndarray
    approach: np.ndarray
    azimuth: np.ndarray
    stiffness_constant: np.ndarray
    max_load: float
    max_index: tuple[int, int]
    row_forces: np.ndarray
    residual: float
    iterations: int


def _row_setup(geom, rows):
    z_rows = geom.row_positions()
    sides = geom.row_sides()
    if rows is not None:
        z_rows, sides = z_rows[list(rows)], sides[list(rows)]
    return z_rows, sides


def ball_load_distribution(
    geom,
    e_eff: float,
    force=(0.0, 0.0, 0.0),
    moment=(0.0, 0.0),
    rows=None,
    preload: float | None = None,
    free=(True, True, True, True, True),
    u0=None,
    tol: float = 1e-9,
    max_iter: int = 200,
) -> BallLoadResult:
    """Quasi-static ball loads of the rigid-ring bearing under external loads on
    the inner ring (see module docstring).

    Parameters
    ----------
    geom : :class:`flexrv.geometry.bearing.BallBearingGeometry`.
    e_eff : effective modulus E' of ball and rings [Pa].
    force : (F_x, F_y, F_z) on the inner ring [N] (F_z axial, along +z).
    moment : (M_x, M_y) on the inner ring about the bearing centre [N m].
    rows : indices of the rows to include (default both: 0 at z = -s/2, 1 at +s/2).
    preload : axial interference per row [m] (default ``geom.axial_preload``).
    free : which of (d_x, d_y, d_z, th_x, th_y) are unknown; fixed ones stay at u0 (0).
    tol : relative tolerance on the force residual (times the load scale).

    Raises
    ------
    InputError for non-finite loads; ConvergenceError if Newton fails (e.g. a
    single row asked to carry a moment, or a load direction no ball can carry).
    """
    force = np.asarray(force, dtype=float)
    moment = np.asarray(moment, dtype=float)
    if force.shape != (3,) or moment.shape != (2,) or not (np.all(np.isfinite(force)) and np.all(np.isfinite(moment))):
        raise InputError(
            f"force must be 3 finite values [N] and moment 2 finite values [N m], got {force!r}, {moment!r}"
        )
    z_rows, sides = _row_setup(geom, rows)
    pre = geom.axial_preload if preload is None else float(preload)
    d, a0 = geom.ball_diameter, geom.contact_angle
    big_a = geom.curvature_center_distance
    r_i = 0.5 * geom.pitch_diameter + (geom.inner_conformity - 0.5) * d * np.cos(a0)
    zi = (z_rows + (geom.inner_conformity - 0.5) * d * sides * np.sin(a0))[:, None]
    s = sides[:, None]
    psi = 2.0 * np.pi * np.arange(geom.ball_count) / geom.ball_count
    cp, sp = np.cos(psi)[None, :], np.sin(psi)[None, :]
    free = np.asarray(free, dtype=bool)

    def k_of(alpha):
        rx_i, ry_i, rx_o, ry_o = geom.contact_radii(alpha)
        return series_stiffness(point_contact_stiffness(rx_i, ry_i, e_eff), point_contact_stiffness(rx_o, ry_o, e_eff))

    # derivatives of A1, A2 w.r.t. u (constant): shape (rows, Z, 5)
    zero = np.zeros_like(cp * s)
    dA1 = np.stack([zero, zero, s + zero, s * r_i * sp, -s * r_i * cp], axis=-1)
    dA2 = np.stack([cp + zero, sp + zero, zero, -zi * sp, zi * cp], axis=-1)
    px, py = r_i * cp + zero, r_i * sp + zero
    pz = zi + zero

    def state(u, kn):
        a1 = big_a * np.sin(a0) + pre + s * (u[2] + r_i * (u[3] * sp - u[4] * cp))
        a2 = big_a * np.cos(a0) + (u[0] + u[4] * zi) * cp + (u[1] - u[3] * zi) * sp
        ad = np.hypot(a1, a2)
        delta = ad - big_a
        dp = np.maximum(delta, 0.0)
        q = kn * dp**1.5
        dq = 1.5 * kn * np.sqrt(dp)
        g = q / ad
        vx, vy, vz = a2 * cp, a2 * sp, s * a1
        fx, fy, fz = -g * vx, -g * vy, -g * vz
        mx = py * fz - pz * fy
        my = pz * fx - px * fz
        res = np.array(
            [force[0] + fx.sum(), force[1] + fy.sum(), force[2] + fz.sum(), moment[0] + mx.sum(), moment[1] + my.sum()]
        )
        # Jacobian
        h = (dq - g) / ad**2
        dg1, dg2 = h * a1, h * a2
        dfx = -(dg1[..., None] * vx[..., None] * dA1 + (dg2 * vx + g * cp)[..., None] * dA2)
        dfy = -(dg1[..., None] * vy[..., None] * dA1 + (dg2 * vy + g * sp)[..., None] * dA2)
        dfz = -((dg1 * vz + g * s)[..., None] * dA1 + (dg2 * vz)[..., None] * dA2)
        dmx = py[..., None] * dfz - pz[..., None] * dfy
        dmy = pz[..., None] * dfx - px[..., None] * dfz
        jac = np.stack([dfx.sum((0, 1)), dfy.sum((0, 1)), dfz.sum((0, 1)), dmx.sum((0, 1)), dmy.sum((0, 1))])
        alpha = np.arctan2(a1, a2)
        return res, jac, q, alpha, delta, np.stack([fx.sum(1), fy.sum(1), fz.sum(1)], axis=-1)

    # scaling: moments by R_i, rotations by R_i
    scale_u = np.array([1.0, 1.0, 1.0, 1.0 / r_i, 1.0 / r_i])
    scale_r = np.array([1.0, 1.0, 1.0, 1.0 / r_i, 1.0 / r_i])
    kn = k_of(np.full(psi.shape, a0))[None, :] + zero
    load_scale = max(np.abs(force).max(), np.abs(moment).max() / r_i, 1.0)
    u = np.zeros(5) if u0 is None else np.array(u0, dtype=float)
    if u0 is None and pre <= 0:
        # start from a small interference so every free direction has stiffness
        k0 = float(kn.mean())
        n_b = geom.ball_count * len(z_rows)
        d0 = (load_scale / (0.25 * n_b * k0)) ** (2.0 / 3.0)
        f_dir = np.concatenate([force, moment / r_i])
        u = np.where(free, 2.0 * d0 * np.sign(f_dir) * scale_u * (np.abs(f_dir) > 0), 0.0)
        if not np.any(u):
            u[2] = d0
    u, kn, norm, it = _damped_newton(state, k_of, u, kn, free, (scale_u, scale_r), tol * load_scale, max_iter, big_a)
    if not norm < tol * load_scale:
        raise ConvergenceError(
            f"ball_load_distribution: equilibrium residual {norm:.3g} N after {it} Newton "
            f"iterations (load scale {load_scale:.3g} N); the load may not be supportable "
            "by the selected rows/free directions"
        )
    res, jac, q, alpha, delta, row_f = state(u, kn)
    idx = np.unravel_index(int(np.argmax(q)), q.shape)
    return BallLoadResult(
        displacement=u,
        loads=q,
        contact_angle=alpha,
        approach=delta,
        azimuth=psi,
        stiffness_constant=kn,
        max_load=float(q[idx]),
        max_index=(int(idx[0]), int(idx[1])),
        row_forces=row_f,
        residual=float(np.max(np.abs(res[free]))),
        iterations=it,
    )


def _damped_newton(state, k_of, u, kn, free, scales, tolerance: float, max_iter: int, big_a: float):
    """Newton on the free displacements of :func:`ball_load_distribution` with steps
    limited to 5 % of A and backtracking on the scaled residual, the contact stiffness
    lagged by one iteration; returns (u, kn, residual norm, iterations)."""
    scale_u, scale_r = scales
    res, jac, *_ = state(u, kn)
    norm = np.linalg.norm((res * scale_r)[free])
    it = 0
    for it in range(1, max_iter + 1):
        if norm < tolerance:
            break
        jf = (jac * scale_r[:, None])[np.ix_(free, free)]
        rf = (res * scale_r)[free]
        reg = 1e-12 * max(np.abs(np.diag(jf)).max(), 1.0)
        try:
            step_f = np.linalg.solve(jf - reg * np.eye(free.sum()), -rf)
        except np.linalg.LinAlgError:
            step_f = -rf / (np.abs(np.diag(jf)).max() + reg)
        step = np.zeros(5)
        step[free] = step_f
        # limit the step to a fraction of A (the contact scale) and backtrack on the residual
        lim = 0.05 * big_a
        size = np.max(np.abs(step / scale_u))
        if size > lim:
            step *= lim / size
        t = 1.0
        for _ in range(30):
            u_new = u + t * step
            res_new, jac_new, q_new, alpha_new, *_ = state(u_new, kn)
            norm_new = np.linalg.norm((res_new * scale_r)[free])
            if norm_new < norm or t < 1e-6:
                break
            t *= 0.5
        u, res, jac, norm = u_new, res_new, jac_new, norm_new
        kn = np.where(q_new > 0, k_of(alpha_new), kn)  # lag K_n(alpha)
        res, jac, *_ = state(u, kn)
        norm = np.linalg.norm((res * scale_r)[free])
    return u, kn, norm, it


def stribeck_max_load(radial_force, ball_count, contact_angle):
    """Stribeck's maximum ball load Q_max = 4.37 F_r / (Z cos a) [N] of a ball
    bearing row with zero clearance under pure radial load (Harris & Kotzalas
    2007, eq. 7.44; 4.37 = 1/J_r(0.5))."""
    return 4.37 * np.asarray(radial_force, dtype=float) / (ball_count * np.cos(contact_angle))


def max_ball_contact(geom, e_eff: float, result: BallLoadResult):
    """Hertz contact of the most loaded ball at its loaded angle, inner and outer
    raceway: returns (inner, outer) :class:`flexrv.contact.hertz.PointContact` and
    the radii (rx_i, ry_i, rx_o, ry_o) [m]."""
    r, j = result.max_index
    alpha = result.contact_angle[r, j]
    rx_i, ry_i, rx_o, ry_o = geom.contact_radii(alpha)
    q = result.max_load
    return (point_contact(q, rx_i, ry_i, e_eff), point_contact(q, rx_o, ry_o, e_eff), (rx_i, ry_i, rx_o, ry_o))
