"""Compiled (numba) generalized force and Jacobian of one bearing row — the hot
path of the ball-resolved and flexible main bearing.

:func:`flexrv.model.flexible_bearing.evaluate_row` is the reference
implementation (numpy, with every contact state for post-processing). During a
run Exudyn asks for the residual ~6 times per step and for the Jacobian every
~5-50 steps; both are evaluated here in one compiled loop over the balls with the
same formulas (the numpy version spends ~1.4 ms per row force in ~200 small array
operations, this kernel ~0.05 ms; the Jacobian of a flexible row 5.2 -> 0.9 ms,
its T^T K T sums done as one stacked product). tests/test_model_flexible_rings.py
checks force and Jacobians against :func:`evaluate_row` to 1e-9 of the largest
entry for rigid and modal rings, dry Hertz and the Hamrock–Dowson EHL law.

Supported: rings given by a raceway table (:class:`flexrv.model.flexible_bearing.
ModalRing`) or rigid, normal laws :class:`flexrv.contact.ball_raceway.HertzLaw`
or :class:`flexrv.ehl.law.EHLPointLaw` in mode ``dry`` /
``hamrock_dowson`` with scalar radii. Anything else (the solver-map law, other
ring models) falls back to :func:`evaluate_row` (:func:`kernel_inputs` returns
None).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: law parameters: k [N/m^1.5], film at Q = 1 N and u = 1 m/s [m], load and speed
#: exponents of the film, load floor [N], c_max [N s/m], damping depth [m], Newton steps
LAW_FIELDS = ("k", "h_unit", "load_exponent", "speed_exponent", "load_floor", "c_max", "depth", "iterations")


def law_parameters(law) -> np.ndarray | None:
    """Kernel parameters of a normal law (see :data:`LAW_FIELDS`), or None if the
    kernel does not cover it."""
    from flexrv.contact.ball_raceway import HertzLaw
    from flexrv.ehl.law import EHLPointLaw
    from flexrv.ehl.film import HAMROCK_DOWSON_LOAD_EXPONENT

    if isinstance(law, HertzLaw) and np.ndim(law.k) == 0:
        return np.array([law.k, 0.0, 0.0, 0.0, 1.0, law.c_max, law.depth, 0.0])
    if isinstance(law, EHLPointLaw) and law.mode in ("dry", "hamrock_dowson") and np.ndim(law.stiffness) == 0:
        h_unit = float(law._h_unit) if law.mode == "hamrock_dowson" else 0.0
        return np.array([float(law.stiffness), h_unit, HAMROCK_DOWSON_LOAD_EXPONENT, 0.67, law.load_floor,
                         law.c_max, law.damping_depth, float(law.iterations)])
    return None


def ring_table(ring) -> tuple[np.ndarray, float] | None:
    """(cylindrical raceway table (n_grid, 3, m), z sign) of a ring, a (1, 3, 0)
    table for a rigid ring, or None if the ring model has no table."""
    from flexrv.model.flexible_bearing import ModalRing

    if ring is None:
        return np.zeros((1, 3, 0)), 1.0
    if isinstance(ring, ModalRing) and getattr(ring.body, "table", None) is not None:
        return np.ascontiguousarray(ring.body.table, dtype=float), -1.0 if ring.mirror else 1.0
    return None


def kernel_inputs(model) -> tuple | None:
    """Everything :func:`row_force_kernel` needs of a :class:`RowModel`, or None."""
    laws = [law_parameters(model.law_inner), law_parameters(model.law_outer)]
    rings = [ring_table(model.inner), ring_table(model.outer)]
    if any(x is None for x in laws + rings):
        return None
    row = model.row
    geometry = np.array([model.z, row.inner_center_radius, row.inner_center_z, row.outer_center_radius,
                         row.outer_center_z, row.inner_offset, row.outer_offset, row.ball_radius_pitch,
                         model.speed_factor, model.cage_ratio, model.cage_stiffness, model.cage_damping,
                         model.pocket_stiffness])
    return (np.ascontiguousarray(model.ball_reference, dtype=float), geometry, rings[0][0], rings[0][1],
            rings[1][0], rings[1][1], laws[0], laws[1])


@njit(cache=True)
def _normal_load(delta, rate, speed, law):
    """(Q, dQ/d delta, dQ/d rate) of the EHL-corrected / dry law
    (flexrv.ehl.law._solve and flexrv.contact.laws.impact_force, n = 3/2)."""
    k, h_unit, lexp, sexp, floor, c_max, depth, iters = (law[0], law[1], law[2], law[3], law[4], law[5],
                                                         law[6], int(law[7]))
    hu = h_unit * speed**sexp if h_unit > 0.0 and speed > 0.0 else 0.0
    dphi = 1.0
    if hu == 0.0:
        s = max(delta, 0.0)
    else:
        s = max(delta + hu * floor**lexp, 0.0)
        for it in range(iters + 1):
            q = k * s**1.5
            h = hu * max(q, floor) ** lexp
            dphi = 1.0
            if q > floor:
                dphi = 1.0 - 1.5 * lexp * h / max(s, 1e-300)
            dphi = max(dphi, 1e-3)
            if it == iters:
                break
            s = max(s - (s - delta - h) / dphi, 0.0)
    if s <= 0.0:
        return 0.0, 0.0, 0.0
    force = k * s**1.5
    dforce = 1.5 * k * math.sqrt(s) / dphi
    c = 0.0
    if c_max > 0.0:
        x = min(max(s / depth, 0.0), 1.0)
        c = c_max * x * x * (3.0 - 2.0 * x)
        force += c * rate
        dforce += c_max * 6.0 * x * (1.0 - x) / depth / dphi * rate
    if force <= 0.0:
        return 0.0, 0.0, 0.0
    return force, dforce, c


@njit(cache=True)
def _contact(ex, ey, ez, wx, wy, wz, offset, speed, law):
    """Ball-groove contact from the ball-minus-centre vector e and relative velocity w
    (flexrv.contact.ball_raceway.raceway_contacts): (|e|, unit normal, Q, dQ/ddelta, dQ/drate)."""
    length = math.sqrt(ex * ex + ey * ey + ez * ez)
    nx, ny, nz = ex / length, ey / length, ez / length
    q, dq, c = _normal_load(length - offset, nx * wx + ny * wy + nz * wz, speed, law)
    return length, nx, ny, nz, q, dq, c


@njit(cache=True)
def _basis(table, zsign, psi, out):
    """Cartesian raceway displacement per modal coordinate at azimuth psi -> out (3, m)
    (Catmull–Rom periodic cubic of the cylindrical table, flexrv.fem.reduction.periodic_cubic)."""
    ng = table.shape[0]
    m = table.shape[2]
    u = (psi % (2.0 * math.pi)) * (ng / (2.0 * math.pi))
    i = int(math.floor(u))
    t = u - i
    t2 = t * t
    t3 = t2 * t
    w0 = 0.5 * (-t3 + 2.0 * t2 - t)
    w1 = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0)
    w2 = 0.5 * (-3.0 * t3 + 4.0 * t2 + t)
    w3 = 0.5 * (t3 - t2)
    i0, i1, i2, i3 = (i - 1) % ng, i % ng, (i + 1) % ng, (i + 2) % ng
    c, s = math.cos(psi), math.sin(psi)
    for j in range(m):
        ar = w0 * table[i0, 0, j] + w1 * table[i1, 0, j] + w2 * table[i2, 0, j] + w3 * table[i3, 0, j]
        at = w0 * table[i0, 1, j] + w1 * table[i1, 1, j] + w2 * table[i2, 1, j] + w3 * table[i3, 1, j]
        az = w0 * table[i0, 2, j] + w1 * table[i1, 2, j] + w2 * table[i2, 2, j] + w3 * table[i3, 2, j]
        out[0, j] = c * ar - s * at
        out[1, j] = s * ar + c * at
        out[2, j] = zsign * az


@njit(cache=True)
def _contact_blocks(q_load, dq, c, length, nx, ny, nz, etx, ety, stiff, damp):
    """d force_ball / d ball position and velocity (3x3) of one contact
    (flexrv.contact.ball_raceway.raceway_contacts, plus the follower term Q/L
    e_t e_t^T of evaluate_row: the groove centre follows the ball's azimuth)."""
    n = (nx, ny, nz)
    et = (etx, ety, 0.0)
    ql = q_load / length
    for a in range(3):
        for b in range(3):
            nn = n[a] * n[b]
            eye = 1.0 if a == b else 0.0
            stiff[a, b] = -(dq * nn + ql * (eye - nn)) + ql * et[a] * et[b]
            damp[a, b] = -c * nn


@njit(cache=True)
def row_kernel(q, qt, ball_ref, geometry, tab_i, zs_i, tab_o, zs_o, law_i, law_o, jacobian):
    """Generalized force (n,) of a row element and, with ``jacobian``, its
    derivatives d f / d q and d f / d q_t (n, n); coordinates ordered
    [frame(6), inner modes, outer modes, balls(3Z)] (see evaluate_row, whose
    Jacobian blocks K_j, -K_j T_j, -T_j^T K_j, sum T_j^T K_j T_j this assembles)."""
    z_row, ci_r, ci_z, co_r, co_z, off_i, off_o, rb = (geometry[0], geometry[1], geometry[2], geometry[3],
                                                       geometry[4], geometry[5], geometry[6], geometry[7])
    speed_factor, cage_ratio, cage_k, cage_c, pocket_k = (geometry[8], geometry[9], geometry[10], geometry[11],
                                                         geometry[12])
    m_i = tab_i.shape[2]
    m_o = tab_o.shape[2]
    nz = ball_ref.shape[0]
    n = 6 + m_i + m_o + 3 * nz
    b0 = 6 + m_i + m_o
    nx_i = 6 + m_i
    f = np.zeros(n)
    nj = n if jacobian else 0
    jq = np.zeros((nj, nj))
    jv = np.zeros((nj, nj))
    ax, ay, az = q[3], q[4], q[5]
    sa, ca, sb, cb, sc, cc = math.sin(ax), math.cos(ax), math.sin(ay), math.cos(ay), math.sin(az), math.cos(az)
    # A = Rx(ax) Ry(ay) Rz(az); omega = G phi_t (Exudyn RotXYZ2RotationMatrix / RotXYZ2G)
    a = np.empty((3, 3))
    a[0, 0], a[0, 1], a[0, 2] = cb * cc, -cb * sc, sb
    a[1, 0], a[1, 1], a[1, 2] = ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb
    a[2, 0], a[2, 1], a[2, 2] = sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb
    g = np.array([[1.0, 0.0, sb], [0.0, ca, -sa * cb], [0.0, sa, ca * cb]])
    om = g @ qt[3:6]
    speed = speed_factor * abs(qt[5])
    bas_i = np.empty((3, m_i))
    bas_o = np.empty((3, m_o))
    t_i = np.zeros((3, nx_i))
    k_i = np.empty((3, 3))
    d_i = np.empty((3, 3))
    k_o = np.empty((3, 3))
    d_o = np.empty((3, 3))
    two_pi = 2.0 * math.pi
    nzj = nz if jacobian else 0
    ti_all = np.zeros((3 * nzj, nx_i))
    kti_q = np.zeros((3 * nzj, nx_i))
    kti_v = np.zeros((3 * nzj, nx_i))
    to_all = np.zeros((3 * nzj, m_o))
    kto_q = np.zeros((3 * nzj, m_o))
    kto_v = np.zeros((3 * nzj, m_o))
    for j in range(nz):
        bj = b0 + 3 * j
        bx = ball_ref[j, 0] + q[bj]
        by = ball_ref[j, 1] + q[bj + 1]
        bz = ball_ref[j, 2] + q[bj + 2]
        vx, vy, vz = qt[bj], qt[bj + 1], qt[bj + 2]
        # ---- inner ring (frame)
        dx, dy, dz = bx - q[0], by - q[1], bz - q[2]
        lx = dx * a[0, 0] + dy * a[1, 0] + dz * a[2, 0]
        ly = dx * a[0, 1] + dy * a[1, 1] + dz * a[2, 1]
        psi_i = math.atan2(ly, lx)
        p = np.array([ci_r * math.cos(psi_i), ci_r * math.sin(psi_i), ci_z + z_row])
        pv = np.zeros(3)
        if m_i > 0:
            _basis(tab_i, zs_i, psi_i, bas_i)
            p += bas_i @ q[6:6 + m_i]
            pv = bas_i @ qt[6:6 + m_i]
        ap = a @ p
        cx, cy, cz = q[0] + ap[0], q[1] + ap[1], q[2] + ap[2]
        apv = a @ pv
        cvx = qt[0] + om[1] * ap[2] - om[2] * ap[1] + apv[0]
        cvy = qt[1] + om[2] * ap[0] - om[0] * ap[2] + apv[1]
        cvz = qt[2] + om[0] * ap[1] - om[1] * ap[0] + apv[2]
        len_i, nix, niy, niz, qi, dqi, cdi = _contact(bx - cx, by - cy, bz - cz, vx - cvx, vy - cvy, vz - cvz,
                                                      off_i, speed, law_i)
        fix, fiy, fiz = -qi * nix, -qi * niy, -qi * niz
        # reaction on the frame: -f at c_i; moment -(Ap x f) mapped by G^T; modes -basis^T A^T f
        f[0] -= fix
        f[1] -= fiy
        f[2] -= fiz
        mx = ap[1] * fiz - ap[2] * fiy
        my = ap[2] * fix - ap[0] * fiz
        mz = ap[0] * fiy - ap[1] * fix
        for r in range(3):
            f[3 + r] -= g[0, r] * mx + g[1, r] * my + g[2, r] * mz
        if m_i > 0:
            flx = a[0, 0] * fix + a[1, 0] * fiy + a[2, 0] * fiz
            fly = a[0, 1] * fix + a[1, 1] * fiy + a[2, 1] * fiz
            flz = a[0, 2] * fix + a[1, 2] * fiy + a[2, 2] * fiz
            for k in range(m_i):
                f[6 + k] -= bas_i[0, k] * flx + bas_i[1, k] * fly + bas_i[2, k] * flz
        # ---- outer ring (housing)
        psi = math.atan2(by, bx)
        cos_p, sin_p = math.cos(psi), math.sin(psi)
        ox, oy, oz = co_r * cos_p, co_r * sin_p, co_z + z_row
        ovx = ovy = ovz = 0.0
        if m_o > 0:
            _basis(tab_o, zs_o, psi, bas_o)
            for k in range(m_o):
                qk, vk = q[6 + m_i + k], qt[6 + m_i + k]
                ox += bas_o[0, k] * qk
                oy += bas_o[1, k] * qk
                oz += bas_o[2, k] * qk
                ovx += bas_o[0, k] * vk
                ovy += bas_o[1, k] * vk
                ovz += bas_o[2, k] * vk
        len_o, nox, noy, noz, qo, dqo, cdo = _contact(bx - ox, by - oy, bz - oz, vx - ovx, vy - ovy, vz - ovz,
                                                      off_o, speed, law_o)
        fox, foy, foz = -qo * nox, -qo * noy, -qo * noz
        if m_o > 0:
            for k in range(m_o):
                f[6 + m_i + k] -= bas_o[0, k] * fox + bas_o[1, k] * foy + bas_o[2, k] * foz
        # ---- cage (tangential spring-damper to the kinematic pocket) + pocket spring
        pocket = two_pi * j / nz + cage_ratio * az
        dev = psi - pocket
        dev = math.atan2(math.sin(dev), math.cos(dev))
        radius = math.hypot(bx, by)
        etx, ety = -sin_p, cos_p
        s_t = vx * etx + vy * ety - radius * cage_ratio * qt[5]
        fc = -(cage_k * radius * dev + cage_c * s_t)
        pr = radius - rb
        f[bj] = fix + fox + fc * etx - pocket_k * pr * cos_p
        f[bj + 1] = fiy + foy + fc * ety - pocket_k * pr * sin_p
        f[bj + 2] = fiz + foz - pocket_k * (bz - z_row)
        if not jacobian:
            continue
        # ---- Jacobian blocks
        _contact_blocks(qi, dqi, cdi, len_i, nix, niy, niz, etx, ety, k_i, d_i)
        _contact_blocks(qo, dqo, cdo, len_o, nox, noy, noz, etx, ety, k_o, d_o)
        et = (etx, ety, 0.0)
        for c1 in range(3):
            for c2 in range(3):
                ee = et[c1] * et[c2]
                eye = 1.0 if c1 == c2 else 0.0
                jq[bj + c1, bj + c2] += k_i[c1, c2] + k_o[c1, c2] - cage_k * ee - pocket_k * (eye - ee)
                jv[bj + c1, bj + c2] += d_i[c1, c2] + d_o[c1, c2] - cage_c * ee
            jq[bj + c1, 5] += cage_k * radius * cage_ratio * et[c1]
            jv[bj + c1, 5] += cage_c * radius * cage_ratio * et[c1]
        # T_i = [I | -[Ap]x G | A basis_i]; stacked over the balls for one product each at the end
        rows3 = slice(3 * j, 3 * j + 3)
        for r in range(3):
            for c1 in range(3):
                t_i[r, c1] = 1.0 if r == c1 else 0.0
        skew = np.array([[0.0, -ap[2], ap[1]], [ap[2], 0.0, -ap[0]], [-ap[1], ap[0], 0.0]])
        t_i[:, 3:6] = -(skew @ g)
        if m_i > 0:
            t_i[:, 6:] = a @ bas_i
        ti_all[rows3] = t_i
        kti_q[rows3] = k_i @ t_i
        kti_v[rows3] = d_i @ t_i
        if m_o > 0:
            to_all[rows3] = bas_o
            kto_q[rows3] = k_o @ bas_o
            kto_v[rows3] = d_o @ bas_o
    if jacobian:
        # d f_ball/d x = -K T; d g/d b = -T^T K (K symmetric); d g/d x = sum T^T K T
        ball = slice(b0, b0 + 3 * nz)
        o = slice(6 + m_i, 6 + m_i + m_o)
        for jac, kt, kto in ((jq, kti_q, kto_q), (jv, kti_v, kto_v)):
            jac[ball, 0:nx_i] -= kt
            jac[0:nx_i, ball] -= kt.T
            jac[0:nx_i, 0:nx_i] += ti_all.T @ kt
            if m_o > 0:
                jac[ball, o] -= kto
                jac[o, ball] -= kto.T
                jac[o, o] += to_all.T @ kto
    return f, jq, jv


@njit(cache=True)
def row_force_kernel(q, qt, ball_ref, geometry, tab_i, zs_i, tab_o, zs_o, law_i, law_o):
    """Generalized force (n,) of a row element (see :func:`row_kernel`)."""
    f, _, _ = row_kernel(q, qt, ball_ref, geometry, tab_i, zs_i, tab_o, zs_o, law_i, law_o, False)
    return f
