"""Crankshafts in the carrier and the needle bearings between the cranks'
eccentrics and the cycloid discs.

Crank supports (group ``crank_supports``, members carrier + cranks): each crank
centre is tied to its bore in the carrier, h_j = c_c + Rot(theta_c) b_j (b_j the
as-built bore centre ``crank_bores``, nominally a_w (cos beta_j0, sin beta_j0)),
through its two support bearings in series with the crank's bending
(:mod:`flexrv.contact.tapered_roller`: a roller-resolved preloaded tapered-roller
pair with the as-built radial clearance c_j ``support_clearances``, or the linear
law as the explicit option, and the Timoshenko bending stiffness of the shaft
between its supports and eccentrics): with d = p_j - h_j the force on the crank is
f(d, gamma) of :func:`flexrv.contact.tapered_roller.crank_support_force`, gamma =
(1 - g) phi_j / 2 + (1 + g) theta_c / 2 the cage angle, plus the damper -c dd/dt
(c = 2 c_sb) while the support is loaded; the crank turns freely (rollers carry
no torque). Jacobian (exact for the spring): B^T (-K_s B + h dgamma/dq) with the
series tangent K_s and h = df/dgamma of the law, plus the bore's rotation in the
carrier's moment, (r . f) on (theta, theta); the terms of the bore's rotation with
theta in the damper are dropped, and for the linear law also in the spring (its
Jacobian is kept as in tests/data/force_reference.npz).

Carrier (design ``carrier.body_model = "condensed_fe"``): the carrier's
end plates and pillars are elastic. Its FE condensation
(:func:`flexrv.fem.carrier.crank_support_compliance`) gives the (2N x 2N)
compliance C of the cranks' support points (each crank's force split over its two
bores, input/output plate) relative to the output flange, in the carrier frame;
the flange is the carrier member's rigid body (main bearing, load). The support
points move by u = -C_h f_s(d0 - u) (C_h = R C R^T turned with the carrier, f_s
the support springs' forces on the cranks at d = d0 - u, d0 = p_j - h_j the
rigid-bore displacement): the carrier is in series with the supports and couples
the cranks. :func:`crank_support_kernel` condenses it (local Newton on u,
warm-started), its tangent being (I + K C_h)^-1 K plus the terms of C_h's turn
with the carrier; the carrier's moment takes the deflected arm r + u (the
element is conservative: its energy is W(d) + u.C^-1 u / 2). The damper acts on the
rigid relative velocity (the carrier's elastic rate is left out, as the bodies are
massless in this condensation). With C = 0 the element is the rigid-carrier one.
Verified in tests/test_bodies.py (explicit unknowns u solved by a root finder to
1e-9, central differences to 1e-6, QS torsional compliance + g^T C g to 1 %).

Needle bearings (group ``needle_bearings``, members cranks + discs): the journal
centre of crank j under disc k is E = p_j + e_jk (sin chi, cos chi), chi = chi0_k +
err_jk - phi_j (clockwise eccentric angle, :mod:`flexrv.geometry.cycloid`
convention; e_jk, err_jk the as-built ``eccentricities`` and
``eccentric_phase_errors``); the hole centre is H = c_k + Rot(psi_k) h_kj. With
d = E - H and the as-built radial clearance c_r = c_jk (``needle_clearances``):

* ``empirical`` (:cite:`seed004`): a radial power law on the eccentricity of the journal
  in its hole, delta = |d| - c_r, F = K delta^(10/9) along d/|d|. The constant
  follows from :cite:`seed004`'s empirical radial stiffness
  K_Hc = dF/d(delta) = C F^0.1 (see :func:`flexrv.analysis.torsional`); its
  integral is exactly a 10/9 power law, F = (0.9 C delta)^(10/9).
* ``rollers`` (:cite:`seed003`): each of the Z rollers is a Hertz line contact pair
  (journal–roller and roller–hole in series, Palmgren Q = K delta^(10/9),
  :func:`flexrv.contact.hertz.line_contact_stiffness`) with the radial clearance:
  delta_i = d . e_i - c_r, e_i the roller direction at gamma_c + 2 pi i / Z. The
  cage angle follows epicyclic rolling, gamma_c = ((1 - g) phi_j + (1 + g) psi_k)/2,
  g = D/d_m (Harris & Kotzalas 2007, ch. 8). Rollers are massless (their
  inertia is negligible against the disc's).

Friction: a constant-coefficient rolling-bearing friction moment
between eccentric and disc hole (SKF/JTEKT model M = mu P d/2, P the radial
load, d the bore = eccentric journal diameter; mu = design
``contact.needle_friction_coefficient``), regularised like the pin friction:
M = -mu F (d/2) s(omega_rel d/2) on the crank and +M on the disc, omega_rel =
dphi_j/dt - dpsi_k/dt, F = |F| the bearing force, s
:func:`flexrv.contact.laws._friction_one`; its power M omega_rel <= 0. Jacobian (exact):
dF = e^T dF-vector, e = F-vector/F, with the complete force tangents below, plus the regularisation term
-mu F (d/2)^2 s' on (phi_j, psi_k) of dM/dv.

Both use the impact-law damping ramp of :func:`flexrv.contact.laws.impact_force`.
Generalized forces are Q = -B^T F (B = dd/dq over crank x, y, phi and disc x, y,
psi; F the bearing force on the disc). The analytic Jacobian is the exact
derivative of Q as computed (with the arm rotations dropped, Newton
converged only linearly at running speeds): dQ/dq = -B^T G - (dB^T/dq) F with
G = dF/dq = K B + D W + c g, K the contact tangent (empirical law: spring,
rotation F/|d| of the direction d/|d| and the damper's rate turning with it,
c_d u (P dd/dt)^T/|d|, P = I - u u^T), D = dF/d(dd/dt) the damping tangent, W =
d(dd/dt)/dq the arms' rotation in the relative velocity (phi column
-(E - p) dphi/dt, psi column (H - c) dpsi/dt), c g the rollers' turn with the cage
angle (rollers law); (dB^T/dq) F puts (E - p) . F on (phi, phi) and -(H - c) . F
on (psi, psi). dQ/dv = -B^T D B. Verified against central differences of the
kernel's own forces to 1e-6 of the largest entry (tests/test_kernel.py::
test_completed_jacobians_vs_central_differences).

Skipped pin: disc k's rotation must stay at its conjugate value psi_k =
chi_jk / z_c (mean over the cranks, :func:`flexrv.geometry.cycloid.nominal_disc_pose`)
up to elastic deflections; a disc that skipped a pin is off by a whole tooth
pitch 2 pi / z_c. :meth:`NeedleBearings.check` reports a failure when the
departure exceeds half a pin pitch, pi / z_rp.

Compiled kernels (numba, :func:`crank_support_kernel`, :func:`needle_kernel`) are
the only executors: the groups' evaluate/jacobian and the model's fused element
call them.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.contact.hertz import LINE_EXPONENT
from flexrv.contact.laws import _friction_one, _impact_one
from flexrv.contact.tapered_roller import SupportConstants, crank_support_force_at, roller_directions_into
from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, law_type, pack_type
from flexrv.model.drive import DriveParameters
from flexrv.model.numerics.linalg import matmul_small
from flexrv.model.numerics.newton import NEWTON_STATE, VALID, apply_predictor, newton_start, newton_update
from flexrv.units import DEG_PER_RAD, M_PER_MM, M_PER_UM

_F, _I = np.float64, np.int64
#: the crank supports' damper and law switch: damping c [N s/m] while loaded, the linear support law, the
#: crank's bending stiffness k_bend [N/m] (0: rigid crank) and the cage's pitch ratio g = D cos(alpha) / d_m
#: (the roller law's entries that the kernel itself reads)
SupportLaw = law_type("SupportLaw", damping=float, linear=bool, k_bend=float, g=float)
#: :func:`crank_support_kernel`'s pack: indices (carrier x, y, theta, then each crank's x, y, phi), law,
#: the tapered-roller pair's constants (passed on to :func:`flexrv.contact.tapered_roller.crank_support_force`),
#: as-built bores (N, 2) in the carrier frame and clearances, the roller angles' cosines and sines (2, Z),
#: outputs (force on each
#: crank, the bearings' state = Newton start (:data:`BEARING_STATE` columns), bending share), the
#: elastic carrier's support-point compliance (2N, 2N) (empty: rigid), its deflections (N, 4), the
#: roller directions at each cage angle (N, 2, Z) and the work array (:func:`support_work_size`)
SupportPack = pack_type(
    "SupportPack",
    ("idx", (_I, (6,))),
    ("law", SupportLaw),
    ("roller_law", SupportConstants),
    ("bores", (_F, 2)),
    ("clear", (_F, 1)),
    ("angle_cs", (_F, 2)),
    ("fx", (_F, 1)),
    ("fy", (_F, 1)),
    ("bstate", (_F, 2)),
    ("bend", (_F, 1)),
    ("carrier_c", (_F, 2)),
    ("ustate", (_F, 2)),
    ("dirs", (_F, 3)),
    ("work", (_F, 1)),
)
#: the needle bearings' scalar law: contact K, exponent, c_max, depth, roller-resolved model (else the
#: empirical radial law), pitch ratio g = D/d_m, disc teeth z_c, friction coefficient, friction radius
#: d/2 [m], regularisation speed, and the per-step check's limits (:func:`needle_check`): half a pin pitch
#: pi / z_rp [rad] of a disc's departure from its conjugate rotation, the needle penetration [m]
NeedleLaw = law_type(
    "NeedleLaw",
    k=float,
    exponent=float,
    c_max=float,
    depth=float,
    rollers=bool,
    pitch_ratio=float,
    z_c=float,
    mu=float,
    friction_radius=float,
    v_reg=float,
    skip_limit=float,
    penetration_limit=float,
)
#: :func:`needle_kernel`'s pack: indices (each crank's x, y, phi, then each disc's x, y, psi), law,
#: disc eccentric phases chi0, as-built eccentricities, phase errors, hole centres x, y (cranks,
#: discs), clearances, roller angles, outputs per bearing (force x, y, rollers' forces and angles,
#: friction power), the smallest gap of the last call and each disc's departure from its conjugate rotation
NeedlePack = pack_type(
    "NeedlePack",
    ("idx", (_I, 1)),
    ("law", NeedleLaw),
    ("chi0", (_F, 1)),
    ("ecc", (_F, 2)),
    ("err", (_F, 2)),
    ("hx", (_F, 2)),
    ("hy", (_F, 2)),
    ("clear", (_F, 2)),
    ("roller_angles", (_F, 1)),
    ("fx", (_F, 2)),
    ("fy", (_F, 2)),
    ("roll", (_F, 3)),
    ("angle", (_F, 3)),
    ("pw", (_F, 2)),
    ("min_gap", (_F, (1,))),
    ("departure", (_F, 1)),
)


@njit(cache=True)
def _add_btkb(jq, ii, b, kxx, kxy, kyy, w):
    """jq[ii, ii] -= w B^T K B for a 2 x m map B (rows b[0], b[1]) and the symmetric
    2 x 2 matrix K = [[kxx, kxy], [kxy, kyy]]."""
    m = ii.shape[0]
    for r in range(m):
        kb0 = kxx * b[0, r] + kxy * b[1, r]
        kb1 = kxy * b[0, r] + kyy * b[1, r]
        for s in range(m):
            jq[ii[s], ii[r]] -= w * (b[0, s] * kb0 + b[1, s] * kb1)


#: the columns of a crank's bearing state (SupportPack field ``bstate``, per crank): the bearing
#: displacement b (x, y) of its last solution, the crank-centre displacement d (x, y) it solved and
#: the series tangent K_s (xx, xy, yy) there; a zero row (a reset) starts from b without the
#: first-order change
B_X, B_Y, B_DX, B_DY, B_KXX, B_KXY, B_KYY = 0, 1, 2, 3, 4, 5, 6
BEARING_STATE = 7


@njit(cache=True, inline="always")
def _bearing_start(bstate, j, dx, dy, kb):
    """The Newton start of crank j's bearing displacement at d: the last solution b_prev plus
    its first-order change, b_prev + (I - K_s / k_bend)(d - d_prev) (db/dd = (K_b + k I)^-1 k
    = I - K_s / k, :mod:`flexrv.contact.tapered_roller`), K_s the series tangent of the last
    solution; the change is second order in d - d_prev. A reset state (K_s zero) or a rigid
    crank: b_prev."""
    b0x, b0y = bstate[j, B_X], bstate[j, B_Y]
    kxx, kxy, kyy = bstate[j, B_KXX], bstate[j, B_KXY], bstate[j, B_KYY]
    if kb > 0.0 and (kxx != 0.0 or kyy != 0.0):
        ex, ey = dx - bstate[j, B_DX], dy - bstate[j, B_DY]
        b0x += ex - (kxx * ex + kxy * ey) / kb
        b0y += ey - (kxy * ex + kyy * ey) / kb
    return b0x, b0y


@njit(cache=True)
def _support_forces(d0x, d0y, u, dirs, clear, sc, linear, kb, bstate, fs, kk, hh, qs):
    """Spring force of every crank support at d = d0 - u (housing frame): fs (2N,)
    on the cranks, the block-diagonal tangent kk = -dfs/dd (2N, 2N), hh (2N, N)
    = dfs/dgamma, the roller loads qs (N,); updates the bearings' state (their Newton
    starts, :func:`_bearing_start`; kb the crank's bending stiffness). ``dirs`` (N, 2, Z): each
    support's roller directions at its cage angle (:func:`_support_approach`)."""
    for j in range(d0x.shape[0]):
        dx, dy = d0x[j] - u[2 * j], d0y[j] - u[2 * j + 1]
        b0x, b0y = _bearing_start(bstate, j, dx, dy, kb)
        fx, fy, kxx, kxy, kyy, hx, hy, bx, by, qj = crank_support_force_at(
            dx, dy, dirs[j, 0], dirs[j, 1], clear[j], sc, linear, b0x, b0y
        )
        bstate[j, B_X], bstate[j, B_Y], bstate[j, B_DX], bstate[j, B_DY] = bx, by, dx, dy
        bstate[j, B_KXX], bstate[j, B_KXY], bstate[j, B_KYY] = kxx, kxy, kyy
        fs[2 * j], fs[2 * j + 1] = fx, fy
        kk[2 * j, 2 * j], kk[2 * j, 2 * j + 1], kk[2 * j + 1, 2 * j], kk[2 * j + 1, 2 * j + 1] = kxx, kxy, kxy, kyy
        hh[2 * j, j], hh[2 * j + 1, j] = hx, hy
        qs[j] = qj


def support_work_size(n: int) -> int:
    """Length of :func:`crank_support_kernel`'s work array for n cranks."""
    n2, m = 2 * n, 3 + 3 * n
    return 4 + NEWTON_STATE + m + n2 * m + n2 + 9 * n + 9 * n2 + 4 * n2 * n2 + n2 * n + 3 * n2 * m + n * m


#: the carrier Newton's caps and round-off rule (numerics.newton.newton_update: max_evals, max_steps,
#: roundoff_abs, roundoff_rel): 60 Newton steps (the evaluation cap 40 per step never binds: halving
#: ends after 21); round-off: a worse residual at max|R| <= 1e-12 m
CARRIER_NEWTON = (2400, 60, 1e-12, 0.0)


@njit(cache=True)
def _carrier_residual(u, ch, fs, res):
    """res = u + C_h fs (the elastic carrier's local residual); returns max|res|."""
    r0 = 0.0
    for r in range(u.shape[0]):
        acc = u[r]
        for k in range(u.shape[0]):
            acc += ch[r, k] * fs[k]
        res[r] = acc
        r0 = max(r0, abs(acc))
    return r0


@njit(cache=True)
def _carrier_evaluate(d0x, d0y, dirs, clear, sc, linear, kb, bstate, fs, kk, hh, qs, ch, u, res):
    """The elastic carrier's support forces at d = d0 - u and residual R = u + C_h f_s into
    ``res`` (tangent K into kk) for :func:`~flexrv.model.numerics.newton.newton_update`;
    returns (max|R|, max|u|)."""
    _support_forces(d0x, d0y, u, dirs, clear, sc, linear, kb, bstate, fs, kk, hh, qs)
    r0 = _carrier_residual(u, ch, fs, res)
    umax = 0.0
    for r in range(u.shape[0]):
        umax = max(umax, abs(u[r]))
    return r0, umax


#: views of :func:`crank_support_kernel`'s work array (:func:`_support_views`): the predictor's
#: validity flag and the Newton state, the last call's q and S = du/dq and u, per crank the bore's
#: arm, rigid approach d0 and its rate, cage angle, roller load and damper, the carrier Newton's
#: vectors (2N) and matrices (2N x 2N), dfs/dgamma, d(d0)/dq, dfs/dq and d(gamma)/dq
SupportWork = namedtuple(
    "SupportWork",
    "st nw qp su ulast rx ry d0x d0y dvx dvy gam qs damp fs u res step zf wc av u0 ones kk ch mm tmp hh d0 df t2 gg",
)


@njit(cache=True, inline="always")
def _support_views(wk, n):
    """The named views of the work array (:func:`support_work_size`) for n cranks."""
    n2, m = 2 * n, 3 + 3 * n
    st = wk[0:4]
    nw = wk[4 : 4 + NEWTON_STATE]
    o = 4 + NEWTON_STATE
    qp = wk[o : o + m]
    o += m
    su = wk[o : o + n2 * m].reshape((n2, m))
    o += n2 * m
    ulast = wk[o : o + n2]
    o += n2
    rx, ry, d0x, d0y = wk[o : o + n], wk[o + n : o + 2 * n], wk[o + 2 * n : o + 3 * n], wk[o + 3 * n : o + 4 * n]
    dvx, dvy, gam = wk[o + 4 * n : o + 5 * n], wk[o + 5 * n : o + 6 * n], wk[o + 6 * n : o + 7 * n]
    qs, damp = wk[o + 7 * n : o + 8 * n], wk[o + 8 * n : o + 9 * n]
    o += 9 * n
    fs, u, res, step = wk[o : o + n2], wk[o + n2 : o + 2 * n2], wk[o + 2 * n2 : o + 3 * n2], wk[o + 3 * n2 : o + 4 * n2]
    zf, wc, av, u0 = (
        wk[o + 4 * n2 : o + 5 * n2],
        wk[o + 5 * n2 : o + 6 * n2],
        wk[o + 6 * n2 : o + 7 * n2],
        wk[o + 7 * n2 : o + 8 * n2],
    )
    ones = wk[o + 8 * n2 : o + 9 * n2]  # the Newton's norms: unweighted
    o += 9 * n2
    nn = n2 * n2
    kk = wk[o : o + nn].reshape((n2, n2))
    ch = wk[o + nn : o + 2 * nn].reshape((n2, n2))
    mm = wk[o + 2 * nn : o + 3 * nn].reshape((n2, n2))
    tmp = wk[o + 3 * nn : o + 4 * nn].reshape((n2, n2))
    o += 4 * nn
    hh = wk[o : o + n2 * n].reshape((n2, n))
    o += n2 * n
    d0 = wk[o : o + n2 * m].reshape((n2, m))
    df = wk[o + n2 * m : o + 2 * n2 * m].reshape((n2, m))
    t2 = wk[o + 2 * n2 * m : o + 3 * n2 * m].reshape((n2, m))
    o += 3 * n2 * m
    gg = wk[o : o + n * m].reshape((n, m))
    return SupportWork(
        st, nw, qp, su, ulast, rx, ry, d0x, d0y, dvx, dvy, gam, qs, damp, fs, u, res, step, zf, wc, av, u0, ones,
        kk, ch, mm, tmp, hh, d0, df, t2, gg,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _support_approach(q, v, idx, bores, g, c, s, angle_cs, dirs, w):
    """Per crank: the bore's arm (rx, ry) in the housing frame, the rigid approach d0 of
    the crank centre to its bore and its rate, the cage angle gamma and the roller
    directions there into ``dirs`` (N, 2, Z; once per call: the carrier's Newton keeps
    gamma); fs, u, K and H zeroed."""
    rx, ry, d0x, d0y, dvx, dvy, gam, fs = w.rx, w.ry, w.d0x, w.d0y, w.dvx, w.dvy, w.gam, w.fs
    u, kk, hh = w.u, w.kk, w.hh
    th, om = q[idx[2]], v[idx[2]]
    n = bores.shape[0]
    for j in range(n):
        lx, ly = bores[j, 0], bores[j, 1]
        rx[j], ry[j] = c * lx - s * ly, s * lx + c * ly
        jx, jy, jp = idx[6 + 3 * j], idx[7 + 3 * j], idx[8 + 3 * j]
        d0x[j] = q[jx] - q[idx[0]] - rx[j]
        d0y[j] = q[jy] - q[idx[1]] - ry[j]
        dvx[j] = v[jx] - v[idx[0]] + om * ry[j]
        dvy[j] = v[jy] - v[idx[1]] - om * rx[j]
        gam[j] = 0.5 * (1.0 - g) * q[jp] + 0.5 * (1.0 + g) * th
        roller_directions_into(gam[j], angle_cs[0], angle_cs[1], dirs[j, 0], dirs[j, 1])
    for r in range(2 * n):
        fs[r], u[r] = 0.0, 0.0
        for k in range(2 * n):
            kk[r, k] = 0.0
        for k in range(n):
            hh[r, k] = 0.0


@njit(cache=True, inline="always")
def _carrier_solve(q, idx, cc, c, s, clear, sc, dirs, linear, kb, bstate, ustate, w):
    """The elastic carrier's support-point deflection u = -C_h f_s(d0 - u) by the carrier
    Newton (numerics.newton), started from the first-order predictor of the previous
    call; the last correction applied linearised; u stored in ``ustate``."""
    ch, u, ulast, step, st, fs, kk, res = w.ch, w.u, w.ulast, w.step, w.st, w.fs, w.kk, w.res
    ones, su, qp, nw, d0x, d0y, hh = w.ones, w.su, w.qp, w.nw, w.d0x, w.d0y, w.hh
    qs, u0, tmp, mm = w.qs, w.u0, w.tmp, w.mm
    n = ustate.shape[0]
    n2, m = 2 * n, 3 + 3 * n
    for a in range(n):  # C_h = R C R^T, blockwise
        for b in range(n):
            c00, c01 = cc[2 * a, 2 * b], cc[2 * a, 2 * b + 1]
            c10, c11 = cc[2 * a + 1, 2 * b], cc[2 * a + 1, 2 * b + 1]
            t00, t01 = c * c00 - s * c10, c * c01 - s * c11  # R C
            t10, t11 = s * c00 + c * c10, s * c01 + c * c11
            ch[2 * a, 2 * b], ch[2 * a, 2 * b + 1] = t00 * c - t01 * s, t00 * s + t01 * c  # (R C) R^T
            ch[2 * a + 1, 2 * b], ch[2 * a + 1, 2 * b + 1] = t10 * c - t11 * s, t10 * s + t11 * c
    valid = st[VALID] > 0.0
    for r in range(n2):
        ones[r] = 1.0
    for j in range(n):
        u[2 * j], u[2 * j + 1] = ustate[j, 0], ustate[j, 1]
        if u[2 * j] != ulast[2 * j] or u[2 * j + 1] != ulast[2 * j + 1]:
            valid = False  # set from outside (reset, history pass): start from it
    if valid:  # first-order predictor from the previous call's u (numerics.newton: trusted within a tenth)
        for r in range(n2):
            acc = 0.0
            for col in range(m):
                qc = q[idx[col]] if col < 3 else q[idx[col + 3]]
                acc += su[r, col] * (qc - qp[col])
            step[r] = acc
        apply_predictor(u, step, ones)
    newton_start(nw)
    while True:  # the carrier Newton (numerics.newton): R = u + C_h f_s(d0 - u), dR/du = I + C_h K
        r1, scale = _carrier_evaluate(d0x, d0y, dirs, clear, sc, linear, kb, bstate, fs, kk, hh, qs, ch, u, res)
        if newton_update(nw, r1, scale, u, u0, step, res, ch, kk, 1.0, tmp, mm, *CARRIER_NEWTON):
            break
    # the last Newton correction -step, linearised (O(|R|^2) exact): the result is smooth in q down to
    # round-off, below the Newton tolerance (finite differences of 5e-11 m see the condensation)
    for r in range(n2):
        acc = 0.0
        for k in range(n2):
            acc -= kk[r, k] * step[k]
        u[r] -= step[r]
        res[r] = acc  # K du
    for r in range(n2):
        fs[r] += res[r]  # fs + K du with du = -step (kk = -dfs/dd = dfs/du)
    for j in range(n):
        ustate[j, 0], ustate[j, 1] = u[2 * j], u[2 * j + 1]
        ulast[2 * j], ulast[2 * j + 1] = u[2 * j], u[2 * j + 1]
        ustate[j, 2], ustate[j, 3] = c * u[2 * j] + s * u[2 * j + 1], -s * u[2 * j] + c * u[2 * j + 1]


@njit(cache=True, inline="always")
def _support_loads(f, idx, cd, kb, out_fx, out_fy, out_bend, w):
    """The support forces (spring and damper) on cranks and carrier into ``f`` and the
    outputs: the force on each crank and the bending share of each support's tangential
    compliance, |K_s t|^2 / (k_bend t.K_s t) (module docstring of
    flexrv.contact.tapered_roller: the shaft deflection is K_s dd / k_bend)."""
    rx, ry, kk, fs, u, damp, qs, dvx = w.rx, w.ry, w.kk, w.fs, w.u, w.damp, w.qs, w.dvx
    dvy = w.dvy
    for j in range(rx.shape[0]):
        jx, jy = idx[6 + 3 * j], idx[7 + 3 * j]
        kxx, kxy, kyy = kk[2 * j, 2 * j], kk[2 * j, 2 * j + 1], kk[2 * j + 1, 2 * j + 1]
        damp[j] = cd if (qs[j] > 0.0 or kxx + kyy > 0.0) else 0.0
        fx = fs[2 * j] - damp[j] * dvx[j]  # on the crank
        fy = fs[2 * j + 1] - damp[j] * dvy[j]
        ax, ay = rx[j] + u[2 * j], ry[j] + u[2 * j + 1]  # the bore's arm (elastic carrier: deflected)
        f[idx[0]] -= fx
        f[idx[1]] -= fy
        f[idx[2]] -= ax * fy - ay * fx
        f[jx] += fx
        f[jy] += fy
        out_fx[j], out_fy[j] = fx, fy
        rr = np.sqrt(rx[j] * rx[j] + ry[j] * ry[j]) + 1e-300
        tx, ty = -ry[j] / rr, rx[j] / rr
        ktx, kty = kxx * tx + kxy * ty, kxy * tx + kyy * ty
        ktt = tx * ktx + ty * kty
        out_bend[j] = (ktx * ktx + kty * kty) / (kb * ktt) if (kb > 0.0 and ktt > 0.0) else 0.0


@njit(cache=True, inline="always")
def _support_tangent(q, idx, g, elastic, w):
    """dfs/dq over the local coordinates into ``w.df`` (elastic carrier: condensed,
    M (-K dd0 + H dgamma) - M K a dtheta) and, elastic, the predictor's S = du/dq and q
    for the next calls (the calls without the Jacobian keep S and move only q,
    :func:`_predictor_origin`); returns the moment's arm term d(arm)/dtheta x fs."""
    rx, ry, fs, u, d0, df, t2, gg = w.rx, w.ry, w.fs, w.u, w.d0, w.df, w.t2, w.gg
    kk, ch, mm, zf, wc, av, hh = w.kk, w.ch, w.mm, w.zf, w.wc, w.av, w.hh
    su, qp, st = w.su, w.qp, w.st
    n = rx.shape[0]
    n2, m = 2 * n, 3 + 3 * n
    # d(d0)/dq and d(gamma)/dq over the local coordinates
    for r in range(n2):
        for col in range(m):
            d0[r, col] = 0.0
    for j in range(n):
        for col in range(m):
            gg[j, col] = 0.0
        d0[2 * j, 0], d0[2 * j, 2], d0[2 * j, 3 + 3 * j] = -1.0, ry[j], 1.0
        d0[2 * j + 1, 1], d0[2 * j + 1, 2], d0[2 * j + 1, 4 + 3 * j] = -1.0, -rx[j], 1.0
        gg[j, 2], gg[j, 5 + 3 * j] = 0.5 * (1.0 + g), 0.5 * (1.0 - g)
    matmul_small(kk, d0, df)
    matmul_small(hh, gg, t2)
    for r in range(n2):
        for col in range(m):
            df[r, col] = t2[r, col] - df[r, col]  # dfs/dq (rigid carrier)
    for j in range(n):
        zf[2 * j], zf[2 * j + 1] = -fs[2 * j + 1], fs[2 * j]  # Z fs
    arm_term = 0.0  # d(arm)/dtheta x fs: the bore's rotation in the carrier's moment
    for j in range(n):
        arm_term += rx[j] * fs[2 * j] + ry[j] * fs[2 * j + 1]
    for r in range(n2):
        wc[r] = 0.0  # extra row weight of the elastic carrier: C_h Z fs
    if not elastic:
        return arm_term
    for r in range(n2):
        acc = 0.0
        for k in range(n2):
            acc += ch[r, k] * zf[k]
        wc[r] = acc
    for j in range(n):  # -Z u - C_h Z fs
        av[2 * j], av[2 * j + 1] = u[2 * j + 1] - wc[2 * j], -u[2 * j] - wc[2 * j + 1]
    # M = (I + K C_h)^-1 = ((I + C_h K)^-1)^T (K and C_h symmetric): the transpose of the carrier Newton's
    # last inverse, which it computed at the same K
    for r in range(n2):
        for k in range(r + 1, n2):
            mm[r, k], mm[k, r] = mm[k, r], mm[r, k]
    matmul_small(mm, df, t2)
    for r in range(n2):
        acc = 0.0  # M K a
        for k in range(n2):
            acc2 = 0.0
            for l in range(n2):
                acc2 += kk[k, l] * av[l]
            acc += mm[r, k] * acc2
        for col in range(m):
            df[r, col] = t2[r, col]
        df[r, 2] -= acc
    for r in range(n2):
        arm_term -= zf[r] * av[r]
    # the predictor's sensitivity S = du/dq = -C_h df - a e_theta^T (u = -C_h f_s, C_h turning with theta)
    matmul_small(ch, df, su)
    for r in range(n2):
        for col in range(m):
            su[r, col] = -su[r, col]
        su[r, 2] -= av[r]
    _predictor_origin(q, idx, qp)
    st[VALID] = 1.0
    return arm_term


@njit(cache=True, inline="always")
def _predictor_origin(q, idx, qp):
    """qp = the local coordinates of q (the point the carrier predictor's S (q - qp) starts from)."""
    for col in range(qp.shape[0]):
        qp[col] = q[idx[col]] if col < 3 else q[idx[col + 3]]


@njit(cache=True, inline="always")
def _support_jacobian(jq, jv, idx, with_arm, arm_term, w):
    """The Jacobian rows: crank j (x, y) += df; carrier (x, y) -= sum df; carrier theta
    -= (Z (r + u) + C_h Z fs) . df (+ the arm term, ``with_arm``); the dampers' d f / d v."""
    rx, ry, u, df, wc, damp = w.rx, w.ry, w.u, w.df, w.wc, w.damp
    n = rx.shape[0]
    m = 3 + 3 * n
    for j in range(n):
        for col in range(m):
            gc = idx[col] if col < 3 else idx[col + 3]
            jq[idx[6 + 3 * j], gc] += df[2 * j, col]
            jq[idx[7 + 3 * j], gc] += df[2 * j + 1, col]
            jq[idx[0], gc] -= df[2 * j, col]
            jq[idx[1], gc] -= df[2 * j + 1, col]
            wx = -(ry[j] + u[2 * j + 1]) + wc[2 * j]
            wy = rx[j] + u[2 * j] + wc[2 * j + 1]
            jq[idx[2], gc] -= wx * df[2 * j, col] + wy * df[2 * j + 1, col]
    if with_arm:
        jq[idx[2], idx[2]] += arm_term
    for j in range(n):  # the damper on the rigid relative velocity: B = d(d0)/d(crank x, y; carrier x, y, theta)
        if damp[j] == 0.0:
            continue
        i0, i1, i2, i3, i4 = idx[6 + 3 * j], idx[7 + 3 * j], idx[0], idx[1], idx[2]
        ii = (i0, i1, i2, i3, i4)
        b0 = (1.0, 0.0, -1.0, 0.0, ry[j])
        b1 = (0.0, 1.0, 0.0, -1.0, -rx[j])
        # rows: the generalized force of F_d = -c B v on crank, carrier and, with the arm r + u, the
        # carrier's moment (its row weight (u_y, -u_x) beyond B's rigid arm)
        for col in range(5):
            for a_ in range(4):
                jv[ii[a_], ii[col]] -= damp[j] * (b0[a_] * b0[col] + b1[a_] * b1[col])
            jv[ii[4], ii[col]] -= damp[j] * ((ry[j] + u[2 * j + 1]) * b0[col] - (rx[j] + u[2 * j]) * b1[col])


@njit(cache=True)
def crank_support_kernel(q, v, f, jq, jv, jac, pack):
    """Crank supports (module docstring): Q into f[idx], Jacobians into jq, jv; the
    force on each crank into out_fx, out_fy, the bearings' state into bstate (the
    next call's Newton start, :func:`_bearing_start`), the bending share of each support's
    tangential compliance into out_bend and, with an elastic carrier (``cc``, the
    (2N, 2N) support-point compliance in the carrier frame; (0, 0): rigid), the
    support points' deflection into ``ustate`` (N, 4): housing-frame x, y (the next
    call's Newton start) and carrier-frame x, y. ``wk``
    (:func:`support_work_size`): the carrier Newton's predictor state and scratch
    arrays (no allocation per call, no LAPACK/BLAS calls: the matrices are 2N x 2N).

    Elastic carrier (module docstring, "Carrier"): the support points move by
    u = -C_h f_s(d0 - u), C_h = R(theta) C R(theta)^T, solved by a local Newton
    (R(u) = u + C_h f_s, dR/du = I + C_h K, step halving on |R|, to 1e-10 of u, at most 1e-13 m), its
    last correction c applied linearised (f_s + K du, exact to O(|R|^2)); the condensed tangent is df_s =
    M (-K dd0 + H dgamma) - M K a dtheta with M = (I + K C_h)^-1 and a = (Z C_h - C_h Z) f_s the turn of
    C_h with the carrier (Z the 90-degree rotation); the carrier's moment takes the
    arm r + u. Cost: the Newton starts from the first-order predictor u_prev + S (q - q_prev), u_prev
    and q_prev of the previous call and S = du/dq = -C_h df_s - a e_theta^T of the last call with the
    Jacobian (used where the predicted change is below a tenth of max|u|; the calls without the Jacobian
    compute no tangent), and stops on the residual rule above; M is the transpose of the carrier Newton's
    last (I + C_h K)^-1 (K and C_h symmetric); the roller directions are one rotation of the stored
    cosines and sines of the roller angles per cage angle; the small systems are solved without LAPACK
    (:func:`flexrv.model.numerics.linalg.inv_small`) and nothing is allocated per call. Measured on rv40e
    (a run's 2,400 solver calls replayed, CPU per call, loaded machine): 5.9 us compiled (rv221 5.0 us).

    Phases (each its own compiled function): the rigid approach of every support
    (:func:`_support_approach`), the elastic carrier's solve (:func:`_carrier_solve`) or
    the supports' forces at the rigid approach, the loads and outputs
    (:func:`_support_loads`), the tangent (:func:`_support_tangent`) and the Jacobian rows
    (:func:`_support_jacobian`)."""
    idx, sc, bores, clear = pack.idx, pack.roller_law, pack.bores, pack.clear
    linear, g, kb = pack.law.linear, pack.law.g, pack.law.k_bend
    th = q[idx[2]]
    c, s = np.cos(th), np.sin(th)
    n = bores.shape[0]
    elastic = n > 0 and pack.carrier_c.shape[0] == 2 * n
    w = _support_views(pack.work, n)
    _support_approach(q, v, idx, bores, g, c, s, pack.angle_cs, pack.dirs, w)
    if elastic:
        _carrier_solve(q, idx, pack.carrier_c, c, s, clear, sc, pack.dirs, linear, kb, pack.bstate, pack.ustate, w)
    else:
        _support_forces(w.d0x, w.d0y, w.u, pack.dirs, clear, sc, linear, kb, pack.bstate, w.fs, w.kk, w.hh, w.qs)
    _support_loads(f, idx, pack.law.damping, pack.law.k_bend, pack.fx, pack.fy, pack.bend, w)
    if not jac:
        if elastic:  # the predictor's S of the last call with the Jacobian, from this call's q on
            _predictor_origin(q, idx, w.qp)
        return
    arm_term = _support_tangent(q, idx, g, elastic, w)
    # (the linear legacy law keeps its Jacobian of tests/data/force_reference.npz: no arm term)
    _support_jacobian(jq, jv, idx, elastic or not linear, arm_term, w)


# ---------------------------------------------------------------- the elements' parameters from the design
@dataclass(frozen=True)
class CrankSupportParameters:
    """The crank supports' parameters (SI). Built by :func:`crank_support_parameters`."""

    drive: DriveParameters
    crank_bores: np.ndarray  #: (N, 2) as-built crank-bore centres in the carrier frame [m]
    support_clearances: np.ndarray  #: (N,) as-built radial clearance of each crank's support bearings [m]
    support_law: SupportConstants  #: constants of flexrv.contact.tapered_roller.crank_support_force
    support_roller_angles: np.ndarray  #: (Z,) roller spacing of a support bearing [rad] (empty: linear law)
    support_linear: bool  #: the linear support law (crankshaft.support_bearing_model = "linear")
    #: linear support law only: radial stiffness of one crank (two bearings) [N/m]; NaN otherwise
    support_stiffness: float
    support_damping: float  #: damper of one crank (two bearings) [N s/m]
    #: (2N, 2N) compliance [m/N] of the cranks' support points in the carrier frame (FE carrier,
    #: :func:`flexrv.fem.carrier.crank_support_compliance`, plus ``carrier_parts``); (0, 0): rigid
    #: carrier (``carrier.body_model``) without parts
    carrier_compliance: np.ndarray
    #: element -> its (2N, 2N) part of ``carrier_compliance`` [m/N]: support-bearing rings, carrier joints
    #: (:func:`flexrv.analysis.path_compliances.model_compliances`)
    carrier_parts: dict


def crank_support_parameters(reducer, drive: DriveParameters) -> CrankSupportParameters:
    """The crank supports' parameters: the support law's constants
    (:func:`flexrv.analysis.torsional.support_constants`), the as-built bores and clearances
    (:func:`flexrv.geometry.as_built.as_built`), and the carrier's compliance at the as-built
    support points: the FE carrier if condensed (:func:`flexrv.model.bodies.body_compliance_matrix`,
    the only FE build of this element) with the support-bearing rings and the pillar joints
    (:func:`flexrv.analysis.path_compliances.model_compliances`)."""
    from flexrv.analysis.path_compliances import model_compliances
    from flexrv.analysis.torsional import support_constants
    from flexrv.model.bodies import body_compliance_matrix

    cs = reducer.crankshaft
    ab = drive.as_built
    law, angles, linear = support_constants(reducer)
    path = model_compliances(reducer, ab.crank_bores)
    return CrankSupportParameters(
        drive=drive,
        crank_bores=ab.crank_bores,
        support_clearances=ab.support_clearances,
        support_law=law,
        support_roller_angles=angles,
        support_linear=linear,
        support_stiffness=2.0 * cs.support_bearing_radial_stiffness_N_per_m if linear else float("nan"),
        support_damping=2.0 * cs.support_bearing_damping_Ns_per_m,
        carrier_compliance=path.support_compliance(body_compliance_matrix(reducer, "carrier")),
        carrier_parts=path.support_parts,
    )


@dataclass(frozen=True)
class NeedleParameters:
    """The needle bearings' parameters (SI). Built by :func:`needle_parameters`."""

    drive: DriveParameters
    model: str  #: needle_bearing.model: "rollers" or "empirical"
    #: empirical model: the constant K [N/m^(10/9)] of F = K delta^(10/9) (:func:`empirical_needle_constant`);
    #: rollers model: the roller constant (inner + outer line contacts in series) [N/m^(10/9)]
    k: float
    roller_count: int
    pitch_ratio: float  #: gamma = D / d_m of the needle bearing
    eccentricities: np.ndarray  #: (N, n_discs) as-built eccentric radius of crank j under disc k [m]
    eccentric_phase_errors: np.ndarray  #: (N, n_discs) added to chi0_k: chi = chi0_k + err_jk - phi_j [rad]
    holes: np.ndarray  #: (n_discs, N, 2) as-built crank-hole centres in each disc's frame [m]
    clearances: np.ndarray  #: (N, n_discs) as-built radial clearance of each needle bearing [m]
    c_max: float  #: impact law's full damping [N s/m]
    penetration_limit: float  #: [m] a run stops as failed beyond it
    friction: float  #: constant friction coefficient of the needle bearings [-] (0: friction off)
    friction_radius: float  #: d/2 of the friction moment, the eccentric journal radius [m]


def empirical_needle_constant(reducer) -> float:
    """Constant K [N/m^(10/9)] of the needle-bearing law F = K delta^(10/9) that
    integrates :cite:`seed004`'s empirical stiffness dF/d(delta) = C F^0.1
    (:func:`flexrv.analysis.torsional.needle_radial_stiffness`, C = its value at
    F = 1 N): F^0.9 = 0.9 C delta, so K = (0.9 C)^(10/9)."""
    from flexrv.analysis.torsional import needle_radial_stiffness

    nb = reducer.needle_bearing
    c = float(needle_radial_stiffness(1.0, nb.roller_count, nb.roller_length_mm * M_PER_MM))
    return (0.9 * c) ** (10.0 / 9.0)


def needle_parameters(reducer, drive: DriveParameters) -> NeedleParameters:
    """The needle bearings' parameters: the law of the design's ``needle_bearing.model``
    (rollers: two Hertz line contacts in series per roller,
    :func:`flexrv.contact.hertz.line_contact_stiffness`; empirical:
    :func:`empirical_needle_constant`), the as-built eccentrics, holes and clearances
    (:func:`flexrv.geometry.as_built.as_built`), damping, limit and friction (design ``[contact]``)."""
    from flexrv.contact.hertz import effective_modulus, line_contact_stiffness, series_stiffness

    cs, nb, ct = reducer.crankshaft, reducer.needle_bearing, reducer.contact
    if nb.model == "empirical":
        k = empirical_needle_constant(reducer)
    else:
        mc, mr = reducer.material("crankshaft"), reducer.material("rolling_elements")
        e_nb = effective_modulus(mc.youngs_modulus, mc.poisson_ratio, mr.youngs_modulus, mr.poisson_ratio)
        k_roll = float(line_contact_stiffness(nb.roller_length_mm * M_PER_MM, e_nb))
        k = float(series_stiffness(k_roll, k_roll, LINE_EXPONENT))
    d_roll = nb.roller_diameter_mm * M_PER_MM
    ab = drive.as_built
    return NeedleParameters(
        drive=drive,
        model=nb.model,
        k=k,
        roller_count=nb.roller_count,
        pitch_ratio=d_roll / (cs.eccentric_journal_diameter_mm * M_PER_MM + d_roll),
        eccentricities=ab.eccentricities,
        eccentric_phase_errors=ab.eccentric_phase_errors,
        holes=ab.holes,
        clearances=ab.needle_clearances,
        c_max=ct.pin_max_damping_Ns_per_m,
        penetration_limit=ct.needle_penetration_limit_um * M_PER_UM,
        friction=ct.needle_friction_coefficient if ct.friction else 0.0,
        friction_radius=0.5 * M_PER_MM * cs.eccentric_journal_diameter_mm,
    )


class CrankSupports(KernelGroup):
    """Crank centres in their carrier bores (members: carrier, crank0..N-1); the law
    of :func:`flexrv.contact.tapered_roller.crank_support_force` with the constants of
    :func:`flexrv.analysis.torsional.support_constants`."""

    name = "crank_supports"
    kind = "supports"
    summary_rows = (
        SummaryRow("max_crank_support_force_N", "N", "largest crank-support force", "crank_support_force", "max"),
    )
    kernel = staticmethod(crank_support_kernel)

    parameters = staticmethod(crank_support_parameters)

    def __init__(self, params: CrankSupportParameters):
        p = self.params = params
        self.n = p.drive.n_cranks
        self.members = ("carrier",) + tuple(f"crank{j}" for j in range(self.n))
        self.bores = np.ascontiguousarray(p.crank_bores, dtype=float)
        self.clear = np.ascontiguousarray(p.support_clearances, dtype=float)
        self.sc = p.support_law
        self.angles = np.ascontiguousarray(p.support_roller_angles, dtype=float)
        #: cos and sin of the roller angles (2, Z): the kernel's roller directions by one rotation per cage angle
        self.angle_cs = np.ascontiguousarray([np.cos(self.angles), np.sin(self.angles)], dtype=float).reshape(2, -1)
        self.linear = bool(p.support_linear)
        self.c = p.support_damping
        self.law = SupportLaw.of(damping=self.c, linear=self.linear, k_bend=self.sc.k_bend, g=self.sc.g)
        self.fx, self.fy = np.zeros(self.n), np.zeros(self.n)
        #: per crank the bearings' last solution, its d and K_s (BEARING_STATE columns: the Newton start)
        self.bstate = np.zeros((self.n, BEARING_STATE))
        self.bend = np.zeros(self.n)
        #: (2N, 2N) support-point compliance of the elastic carrier, carrier frame [m/N]; (0, 0): rigid
        self.carrier_c = np.ascontiguousarray(p.carrier_compliance, dtype=float)
        if self.carrier_c.size and self.carrier_c.shape != (2 * self.n, 2 * self.n):
            raise ValueError(f"carrier_compliance has shape {self.carrier_c.shape}, expected {(2 * self.n,) * 2}")
        if self.carrier_c.size:  # (the kernel's condensed tangent uses C = C^T: M = ((I + C_h K)^-1)^T)
            asym = np.abs(self.carrier_c - self.carrier_c.T).max()
            if asym > 1e-9 * np.abs(self.carrier_c).max():
                raise ValueError(f"carrier_compliance is not symmetric: max|C - C^T| = {asym:.3g} m/N")
        self.ustate = np.zeros((self.n, 4))
        #: per crank the roller directions (x, y) at its cage angle (crank_support_kernel's scratch)
        self.dirs = np.zeros((self.n, 2, len(self.angles)))
        #: crank_support_kernel's work array (the carrier Newton's predictor state, scratch)
        self.work = np.zeros(support_work_size(self.n))

    @property
    def elastic_carrier(self) -> bool:
        return self.carrier_c.size > 0

    def pack(self, idx, history=False):
        return SupportPack(
            idx=idx,
            law=self.law,
            roller_law=self.sc,
            bores=self.bores,
            clear=self.clear,
            angle_cs=self.angle_cs,
            fx=self.fx,
            fy=self.fy,
            bstate=self.bstate,
            bend=self.bend,
            carrier_c=self.carrier_c,
            ustate=self.ustate,
            dirs=self.dirs,
            work=np.zeros_like(self.work) if history else self.work,
        )

    @staticmethod
    def empty_pack():
        return empty_pack(SupportPack)

    def reset(self) -> None:
        """Forget the bearing displacements of earlier evaluations (the inner Newton's
        start; the solution does not depend on it beyond its 1e-13 tolerance)."""
        self.bstate[:] = 0.0
        self.ustate[:] = 0.0
        self.work[:] = 0.0
        super().reset()

    def record_sources(self):
        return {"fx": self.fx, "fy": self.fy, "bend": self.bend, "u": self.ustate}

    def outputs(self, t, rec):
        out = {
            "crank_support_force": Output(
                np.hypot(rec["fx"], rec["fy"]),
                ("time", "crank"),
                "N",
                "radial force of the carrier on each crank (both support bearings)",
            )
        }
        if self.law.k_bend > 0.0:  # elastic crank
            out["crank_bending_fraction"] = Output(
                rec["bend"],
                ("time", "crank"),
                "1",
                "share of crank bending in the crank support's tangential compliance",
            )
        if self.elastic_carrier:
            u = rec["u"][..., 2:]  # (T, N, 2) carrier frame (ustate columns 2, 3)
            out["carrier_bore_deflection"] = Output(
                np.hypot(u[..., 0], u[..., 1]),
                ("time", "crank"),
                "m",
                "deflection of each crank's support point (split-weighted bores) "
                "in the elastic carrier relative to the output flange",
            )
            t = np.asarray(self.bores, dtype=float)
            t = np.stack([-t[:, 1], t[:, 0]], axis=1) / np.linalg.norm(t, axis=1)[:, None]
            out["carrier_bore_deflection_tangential"] = Output(
                (u * t).sum(axis=-1),
                ("time", "crank"),
                "m",
                "tangential (torque-direction) component of carrier_bore_deflection",
            )
        return out


@njit(cache=True, inline="always")
def _needle_contact(dx, dy, dvx, dvy, clear, law, roller_angles, phc, psd, arms, out_roll, out_angle):
    """One needle bearing at the relative displacement (dx, dy) and velocity (dvx, dvy) of
    the eccentric to the disc hole: the force on the disc (fx, fy), the moments on crank
    and disc (mc, md; arms = (E', H') the arms' rates), the smallest gap and the tangent
    (kxx, kxy, kyx, kyy, dxx, dxy, dyy, cgx, cgy): dF/dq = K B + D W + cg gq_row (module
    docstring), K (2 x 2, not symmetric for the empirical law's damper) the contact
    tangent, D = dF/d(dv) the damping tangent, cg the rollers' turn with the cage angle.
    Rollers model: the rollers' forces and angles into ``out_roll``, ``out_angle`` (this
    bearing's rows)."""
    epx, epy, hpx, hpy = arms
    k_c, expo, c_max, depth = law.k, law.exponent, law.c_max, law.depth
    fx = fy = mc = md = 0.0
    min_gap = np.inf
    kxx = kxy = kyx = kyy = dxx = dxy = dyy = cgx = cgy = 0.0
    if not law.rollers:
        r = np.sqrt(dx * dx + dy * dy + 1e-30)
        ux, uy = dx / r, dy / r
        delta = r - clear
        fr, dfg, dfr = _impact_one(-delta, -(ux * dvx + uy * dvy), k_c, expo, c_max, depth)
        min_gap = min(min_gap, -delta)
        fx, fy = fr * ux, fr * uy
        mc, md = fr * (ux * epx + uy * epy), fr * (ux * hpx + uy * hpy)
        kq, kv = -dfg, -dfr
        if fr > 0.0 or kq > 0.0:
            w = fr / r
            # P dv / r (P = I - u u^T): the damper's rate turns with the direction u = d/|d|
            pvx = (dvx - ux * (ux * dvx + uy * dvy)) / r
            pvy = (dvy - uy * (ux * dvx + uy * dvy)) / r
            kxx = kq * ux * ux + w * (1.0 - ux * ux) + kv * ux * pvx
            kxy = (kq - w) * ux * uy + kv * ux * pvy
            kyx = (kq - w) * ux * uy + kv * uy * pvx
            kyy = kq * uy * uy + w * (1.0 - uy * uy) + kv * uy * pvy
            dxx, dxy, dyy = kv * ux * ux, kv * ux * uy, kv * uy * uy
        return fx, fy, mc, md, min_gap, (kxx, kxy, kyx, kyy, dxx, dxy, dyy, cgx, cgy)
    g_ratio = law.pitch_ratio
    gam0 = 0.5 * ((1.0 - g_ratio) * phc + (1.0 + g_ratio) * psd)
    for i in range(roller_angles.shape[0]):
        gam = gam0 + roller_angles[i]
        ux, uy = np.cos(gam), np.sin(gam)
        delta = dx * ux + dy * uy - clear
        fr, dfg, dfr = _impact_one(-delta, -(dvx * ux + dvy * uy), k_c, expo, c_max, depth)
        min_gap = min(min_gap, -delta)
        fx += fr * ux
        fy += fr * uy
        mc += fr * (ux * epx + uy * epy)
        md += fr * (ux * hpx + uy * hpy)
        out_roll[i], out_angle[i] = fr, np.arctan2(uy, ux)
        kq, kv = -dfg, -dfr
        kxx += kq * ux * ux
        kxy += kq * ux * uy
        kyy += kq * uy * uy
        dxx += kv * ux * ux
        dxy += kv * ux * uy
        dyy += kv * uy * uy
        # the roller direction turns with the cage: d(delta)/dgam = d . t, t = du/dgam
        cf = kq * (-dx * uy + dy * ux) + kv * (-dvx * uy + dvy * ux)
        cgx += cf * ux - fr * uy
        cgy += cf * uy + fr * ux
    kyx = kxy
    return fx, fy, mc, md, min_gap, (kxx, kxy, kyx, kyy, dxx, dxy, dyy, cgx, cgy)


@njit(cache=True, inline="always")
def _needle_jacobian(jq, jv, ii, v, law, arms, ecc_arm, rh, force, tangent, friction, b, gmat):
    """One needle bearing's Jacobian rows (``ii``: crank x, y, phi; disc x, y, psi): B =
    d(d)/dq, G = dF/dq = K B + D W + cg g, dQ/dq = -B^T G - (dB^T/dq) F, the damper's
    B^T D B and the friction moment's; ``arms`` = (E', H'), ``ecc_arm`` = E, ``rh`` = H,
    ``force`` = (fx, fy), ``friction`` = (F_n, M_f, s, s'), b, gmat: work (2, 6)."""
    epx, epy, hpx, hpy = arms
    ax, ay = ecc_arm
    rhx, rhy = rh
    fx, fy = force
    kxx, kxy, kyx, kyy, dxx, dxy, dyy, cgx, cgy = tangent
    fn, mf, sf, dsf = friction
    g_ratio, mu_b, r_b = law.pitch_ratio, law.mu, law.friction_radius
    ipc, ipd = ii[2], ii[5]
    b[0, 0], b[0, 1], b[0, 2], b[0, 3], b[0, 4], b[0, 5] = 1.0, 0.0, epx, -1.0, 0.0, -hpx
    b[1, 0], b[1, 1], b[1, 2], b[1, 3], b[1, 4], b[1, 5] = 0.0, 1.0, epy, 0.0, -1.0, -hpy
    # G = dF/dq (2 x 6): K B + D W + cg g; W = d(dv)/dq has the columns phi: -(E - p) dphi/dt
    # and psi: (H - c) dpsi/dt; g = d(cage angle)/dq ((1 -+ g)/2 on phi, psi; rollers only)
    for col in range(6):
        gmat[0, col] = kxx * b[0, col] + kxy * b[1, col]
        gmat[1, col] = kyx * b[0, col] + kyy * b[1, col]
    wx, wy = -ax * v[ipc], -ay * v[ipc]
    gmat[0, 2] += dxx * wx + dxy * wy
    gmat[1, 2] += dxy * wx + dyy * wy
    wx, wy = rhx * v[ipd], rhy * v[ipd]
    gmat[0, 5] += dxx * wx + dxy * wy
    gmat[1, 5] += dxy * wx + dyy * wy
    if law.rollers:
        gmat[0, 2] += cgx * 0.5 * (1.0 - g_ratio)
        gmat[1, 2] += cgy * 0.5 * (1.0 - g_ratio)
        gmat[0, 5] += cgx * 0.5 * (1.0 + g_ratio)
        gmat[1, 5] += cgy * 0.5 * (1.0 + g_ratio)
    # Q = -B^T F: dQ/dq = -B^T G - (dB^T/dq) F (the arms' rotation: phi, phi: (E - p) . F;
    # psi, psi: -(H - c) . F)
    for a_ in range(6):
        for col in range(6):
            jq[ii[a_], ii[col]] -= b[0, a_] * gmat[0, col] + b[1, a_] * gmat[1, col]
    jq[ipc, ipc] += ax * fx + ay * fy
    jq[ipd, ipd] -= rhx * fx + rhy * fy
    _add_btkb(jv, ii, b, dxx, dxy, dyy, 1.0)
    if mf != 0.0 or sf != 0.0:
        # dM = -mu_b r_b (s dF_n + F_n s' r_b d(omega_rel)), dF_n = e^T (G dq + D B dv), e = F/F_n
        ex, ey = fx / fn, fy / fn
        a_s = -mu_b * r_b * sf
        dex, dey = dxx * ex + dxy * ey, dxy * ex + dyy * ey
        for col in range(6):
            gq = a_s * (ex * gmat[0, col] + ey * gmat[1, col])
            gv = a_s * (dex * b[0, col] + dey * b[1, col])
            jq[ipc, ii[col]] += gq
            jq[ipd, ii[col]] -= gq
            jv[ipc, ii[col]] += gv
            jv[ipd, ii[col]] -= gv
        a_d = -mu_b * fn * r_b * r_b * dsf
        jv[ipc, ipc] += a_d
        jv[ipc, ipd] -= a_d
        jv[ipd, ipc] -= a_d
        jv[ipd, ipd] += a_d


@njit(cache=True)
def needle_kernel(q, v, f, jq, jv, jac, pack):
    """Needle bearings (module docstring): Q into f[idx], Jacobians into jq, jv;
    per-bearing force on the disc into out_fx, out_fy, roller forces and angles
    (rollers model) into out_roll, out_angle; the smallest gap [m] into min_gap, disc
    k's departure from its conjugate rotation [rad] into departure[k]. Phases: each bearing's
    contact (:func:`_needle_contact`), its loads and friction moment here, its
    Jacobian rows (:func:`_needle_jacobian`)."""
    idx, chi0, ecc, err, hx, hy = pack.idx, pack.chi0, pack.ecc, pack.err, pack.hx, pack.hy
    clear, roller_angles = pack.clear, pack.roller_angles
    out_fx, out_fy, out_roll, out_angle, out_pw = pack.fx, pack.fy, pack.roll, pack.angle, pack.pw
    departure = pack.departure
    law = pack.law
    z_c = law.z_c
    mu_b, r_b, v_reg = law.mu, law.friction_radius, law.v_reg  # friction moment (module docstring)
    fric = mu_b > 0.0 and v_reg > 0.0
    nc, nd = ecc.shape[0], ecc.shape[1]
    min_gap = np.inf
    b = np.zeros((2, 6))
    gmat = np.zeros((2, 6))
    ii = np.zeros(6, np.int64)
    for kd in range(nd):
        acc = 0.0
        for j in range(nc):
            acc += (chi0[kd] + err[j, kd] - q[idx[3 * j + 2]]) / z_c
        departure[kd] = q[idx[3 * nc + 3 * kd + 2]] - acc / nc
    for j in range(nc):
        ixc, iyc, ipc = idx[3 * j], idx[3 * j + 1], idx[3 * j + 2]
        phc = q[ipc]
        for kd in range(nd):
            ixd, iyd, ipd = idx[3 * nc + 3 * kd], idx[3 * nc + 3 * kd + 1], idx[3 * nc + 3 * kd + 2]
            psd = q[ipd]
            e = ecc[j, kd]
            chi = chi0[kd] + err[j, kd] - phc
            sch, cch = np.sin(chi), np.cos(chi)
            epx, epy = -e * cch, e * sch  # dE/dphi
            c, s = np.cos(psd), np.sin(psd)
            rhx, rhy = c * hx[j, kd] - s * hy[j, kd], s * hx[j, kd] + c * hy[j, kd]
            hpx, hpy = -rhy, rhx  # dH/dpsi
            dx = q[ixc] + e * sch - q[ixd] - rhx
            dy = q[iyc] + e * cch - q[iyd] - rhy
            dvx = v[ixc] + epx * v[ipc] - v[ixd] - hpx * v[ipd]
            dvy = v[iyc] + epy * v[ipc] - v[iyd] - hpy * v[ipd]
            arms = (epx, epy, hpx, hpy)
            fx, fy, mc, md, gap, tangent = _needle_contact(
                dx, dy, dvx, dvy, clear[j, kd], law, roller_angles, phc, psd, arms, out_roll[j, kd], out_angle[j, kd]
            )
            min_gap = min(min_gap, gap)
            f[ixc] -= fx
            f[iyc] -= fy
            f[ipc] -= mc
            f[ixd] += fx
            f[iyd] += fy
            f[ipd] += md
            out_fx[j, kd], out_fy[j, kd] = fx, fy
            # friction moment -mu_b F (d/2) s(omega_rel d/2) on the crank, opposite on the disc
            fn = np.sqrt(fx * fx + fy * fy)
            mf = sf = dsf = 0.0
            if fric and fn > 0.0:
                rel = v[ipc] - v[ipd]
                sf, dsf = _friction_one(rel * r_b, v_reg)
                mf = -mu_b * fn * r_b * sf
                f[ipc] += mf
                f[ipd] -= mf
                out_pw[j, kd] = mf * rel
            elif out_pw.shape[0] > 0:
                out_pw[j, kd] = 0.0
            if jac:  # B = d(d)/d(crank x, y, phi; disc x, y, psi)
                ii[0], ii[1], ii[2], ii[3], ii[4], ii[5] = ixc, iyc, ipc, ixd, iyd, ipd
                _needle_jacobian(
                    jq,
                    jv,
                    ii,
                    v,
                    law,
                    arms,
                    (e * sch, e * cch),
                    (rhx, rhy),
                    (fx, fy),
                    tangent,
                    (fn, mf, sf, dsf),
                    b,
                    gmat,
                )
    pack.min_gap[0] = min_gap


@njit(cache=True)
def needle_check(departure, min_gap, skip_limit, penetration_limit) -> int:
    """The needle bearings' per-step check (:meth:`NeedleBearings.check`, and
    :func:`needle_step_check` in the compiled integrator's steps) on the last call's results: 1 if a
    disc departs from its conjugate rotation by more than ``skip_limit`` (a skipped pin: the cause,
    so it comes first; NaN: not evaluated yet, never a skip), 2 if the smallest gap ``min_gap[0]``
    is a penetration beyond ``penetration_limit`` [m] (the symptom), else 0."""
    for k in range(departure.shape[0]):
        if abs(departure[k]) > skip_limit:
            return 1
    if min_gap[0] < -penetration_limit:
        return 2
    return 0


@njit(cache=True)
def needle_step_check(pack) -> int:
    """The needle bearings' per-step check on their pack (:data:`NeedlePack`) after an accepted step
    of the compiled integrator (:mod:`flexrv.model.core.registry`): :func:`needle_check`."""
    law = pack.law
    return needle_check(pack.departure, pack.min_gap, law.skip_limit, law.penetration_limit)


class NeedleBearings(KernelGroup):
    """All crank–disc needle bearings in one element (members: cranks, discs)."""

    name = "needle_bearings"
    kind = "needles"
    summary_rows = (SummaryRow("max_needle_force_N", "N", "largest needle-bearing force", "needle_force", "max"),)
    kernel = staticmethod(needle_kernel)
    step_check = staticmethod(needle_step_check)
    friction_outputs = ("needle_friction_power",)

    parameters = staticmethod(needle_parameters)

    def __init__(self, params: NeedleParameters):
        p = self.params = params
        d = p.drive
        self.nc, self.nd = d.n_cranks, d.n_discs
        self.members = tuple(f"crank{j}" for j in range(self.nc)) + tuple(f"disc{k}" for k in range(self.nd))
        self.model = p.model
        if p.model not in ("rollers", "empirical"):
            raise ValueError(f"needle model = {p.model!r}: choose 'rollers' or 'empirical'")
        self.chi0 = np.ascontiguousarray(d.chi0, dtype=float)
        self.ecc = np.ascontiguousarray(p.eccentricities, dtype=float)  # (nc, nd)
        self.err = np.ascontiguousarray(p.eccentric_phase_errors, dtype=float)
        self.hx = np.ascontiguousarray(p.holes[..., 0].T)  # (nc, nd) hole centres in the disc frames
        self.hy = np.ascontiguousarray(p.holes[..., 1].T)
        self.clear = np.ascontiguousarray(p.clearances, dtype=float)
        self.z_c = d.z_c
        self.k = float(p.k)
        if p.model == "empirical":
            self.roller_angles = np.zeros(0)
        else:
            z = p.roller_count
            self.roller_angles = 2.0 * np.pi * np.arange(z) / z
        self.law = NeedleLaw.of(
            k=self.k,
            exponent=LINE_EXPONENT,
            c_max=p.c_max,
            depth=d.contact_depth,
            rollers=p.model == "rollers",
            pitch_ratio=p.pitch_ratio,
            z_c=d.z_c,
            mu=p.friction,
            friction_radius=p.friction_radius,
            v_reg=d.friction_velocity,
            skip_limit=math.pi / d.z_rp,
            penetration_limit=max(20.0 * d.contact_depth, p.penetration_limit),
        )
        self.mu = p.friction if d.friction_velocity > 0.0 else 0.0
        z = len(self.roller_angles)
        self.fx, self.fy = np.zeros((self.nc, self.nd)), np.zeros((self.nc, self.nd))
        self.roll, self.angle = np.zeros((self.nc, self.nd, z)), np.zeros((self.nc, self.nd, z))
        self.pw = np.zeros((self.nc, self.nd))  # friction power on crank + disc (<= 0)
        self.gap_min = np.full(1, np.inf)  # smallest gap of the last call [m]
        self.departure = np.full(self.nd, np.nan)  # each disc's departure from its conjugate rotation [rad]
        self.reset()

    def pack(self, idx, history=False):
        return NeedlePack(
            idx=idx,
            law=self.law,
            chi0=self.chi0,
            ecc=self.ecc,
            err=self.err,
            hx=self.hx,
            hy=self.hy,
            clear=self.clear,
            roller_angles=self.roller_angles,
            fx=self.fx,
            fy=self.fy,
            roll=self.roll,
            angle=self.angle,
            pw=self.pw,
            min_gap=self.gap_min,
            departure=self.departure,
        )

    @staticmethod
    def empty_pack():
        return empty_pack(NeedlePack)

    @property
    def min_gap(self) -> float:
        """Smallest gap [m] of the last evaluation (negative: penetration)."""
        return float(self.gap_min[0])

    def record_sources(self):
        rec = {"fx": self.fx, "fy": self.fy, "pw": self.pw}
        if self.model == "rollers":
            rec.update(roll=self.roll, angle=self.angle)
        return rec

    def outputs(self, t, rec):
        fx, fy = rec["fx"], rec["fy"]
        dims = ("time", "crank", "disc")
        out = {
            "needle_force": Output(np.hypot(fx, fy), dims, "N", "needle-bearing force (journal on disc hole)"),
            "needle_force_x": Output(fx, dims, "N", "needle-bearing force on the disc, x"),
            "needle_force_y": Output(fy, dims, "N", "needle-bearing force on the disc, y"),
        }
        if self.mu > 0.0:
            out["needle_friction_power"] = Output(
                -rec["pw"], dims, "W", "power dissipated by the needle-bearing friction moment (>= 0)"
            )
        if self.model == "rollers":
            out["roller_force"] = Output(rec["roll"], dims + ("roller",), "N", "needle roller contact force")
            out["roller_angle"] = Output(
                rec["angle"],
                dims + ("roller",),
                "rad",
                "direction of each roller's contact force on the disc (housing frame)",
            )
        return out

    def reset(self) -> None:
        self.departure[:] = np.nan
        self.gap_min[0] = np.inf

    def check(self) -> str | None:
        law = self.law
        code = needle_check(self.departure, self.gap_min, law.skip_limit, law.penetration_limit)
        if code == 1:
            dep = self.departure
            k = int(np.nanargmax(np.abs(dep)))
            return (
                f"disc {k} skipped a pin: its rotation departs from the conjugate value by "
                f"{dep[k] * DEG_PER_RAD:.3g} deg (more than half a pin pitch, {law.skip_limit * DEG_PER_RAD:.3g} deg)"
            )
        if code == 2:
            return (
                f"needle-bearing penetration {-self.min_gap * 1e6:.3g} um exceeds the physical limit "
                f"{law.penetration_limit * 1e6:.3g} um"
            )
        return None
