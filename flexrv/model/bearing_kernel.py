"""Compiled (numba) generalized force and Jacobian of one bearing row — THE
implementation of the ball-resolved and flexible main bearing.

One row element sees the coordinates [frame(6), inner modes, outer modes,
balls(3Z)]: the inner ring rides on the frame (carrier), the outer ring sits in
the housing, the balls are point masses held by a kinematic cage. A ring is

* **rigid** (no table),
* **modal** — its modal coordinates are element coordinates (a dynamic ring with
  mass, or the uncondensed quasi-static ring kept for verification), or
* **condensed** — a quasi-static (massless) ring whose modal coordinates are
  eliminated by static condensation: with K q = sum_k B_k^T g_k (B_k the raceway
  basis at the contact azimuth psi_k, g_k the contact force on the ring) the
  raceway displacements at the contacts are u_j = sum_k C_jk g_k with the
  compliance C_jk = B_j K^-1 B_k^T = W_j W_k^T, W_j = B_j K^-1/2 interpolated
  from the ring's factor table T K^-1/2 (T the raceway table,
  :meth:`flexrv.fem.body.ReducedBody.raceway_compliance_factors`) with the same
  Catmull–Rom weights as the basis — so C equals B_j K^-1 B_k^T of the
  interpolated basis exactly (to round-off), and is never formed in the
  residual (u = W (W^T g): 2 Z x 3 x m products). The contact deflections solve the
  local nonlinear system u = C g(e0 - u) (e0: ball minus rigid-ring groove
  centre) by Newton iterations whose Jacobian keeps the normal contact
  stiffness (I + C N diag(dQ/d delta) N^T, solved by the Woodbury identity as a
  Z x Z SPD system); the neglected geometric term Q/L (I - n n^T) is ~1e-2 of it, so
  the iteration converges linearly to the exact solution (tolerance
  ``CONDENSE_TOL``). The element Jacobian uses the condensed tangent
  (I - K C)^-1 K of the contacts in series with the ring (dense over the
  balls of the row; :func:`_condensed_contact_matrix`, through a 2Z x 2Z inverse of the rank-2
  contact blocks). Measured: a cheaper tangent that
  condenses only the normal stiffness (Z x Z solve through N^T C N, 4x cheaper)
  moved rv40e's TE mean by 0.5 arcsec and its p-p by 2 arcsec over 0.05-0.1 s
  (the integrator's Newton tolerance lets the tangent shape the answer), so the
  full one is kept. The ring's own velocity at the contacts is left out of the
  contact damping (u_dot = 0; the uncondensed massless ring's modal velocities
  enter it): the one modelling difference to the uncondensed formulation, exact
  in statics (tests/test_model_flexible_rings.py); its effect on the TE is
  within the integrator's Newton-tolerance scatter (benchmarks/
  bench_flexible_model.py, condensed vs ``{"condense": false}``).

Per-ball results of a call go to ``rec`` (:data:`RECORD_FIELDS`) when it has Z
rows: post-processing runs the same kernel on every recorded sample; the
condensed rings' modal amplitudes follow from the recorded ring loads by
:func:`ring_modal_amplitudes` (q = K^-1 sum_j B_j^T g_j).

Supported laws: :class:`flexrv.contact.ball_raceway.HertzLaw` and
:class:`flexrv.ehl.law.EHLPointLaw` in mode ``dry`` / ``hamrock_dowson`` / ``map``
with scalar radii (:func:`law_parameters`); in mode ``map`` the solver map's
table travels in the law array and is interpolated by the map's own compiled
function (:func:`flexrv.ehl.maps.packed_log_correction`). The kernel takes plain arrays only
(the bearing's data classes live in :mod:`flexrv.model.flexible_bearing`, which
prepares them).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from flexrv.ehl.maps import packed_log_correction
from flexrv.model.core.params import law_type, pack_type
from flexrv.model.numerics.linalg import adjugate3, cholesky, cholesky_solve

#: a ball contact's normal law: k [N/m^1.5], film at Q = 1 N and u = 1 m/s [m] (0: dry), load and
#: speed exponents of the film, load floor [N], c_max [N s/m], damping depth [m], the film
#: iteration's Newton steps, the solver map's packed table (:meth:`flexrv.ehl.maps.FilmMap.packed`;
#: empty: Hamrock-Dowson or dry)
PointLaw = law_type(
    "PointLaw",
    k=float,
    h_unit=float,
    load_exponent=float,
    speed_exponent=float,
    load_floor=float,
    c_max=float,
    depth=float,
    iterations=int,
    film_map=np.ndarray,
)

#: columns of the per-ball record ``rec`` (Z, len(RECORD_FIELDS)): loads [N], unit
#: normals (global), ring azimuths [rad], contact force on each ring in the ring's
#: own Cartesian frame [N], raceway displacement of each ring at the contact
#: (global) [m], ball centre (global) [m], central EHL film of each contact [m] (0 dry or
#: out of contact)
RECORD_FIELDS = (
    "load_inner",
    "load_outer",
    "nix",
    "niy",
    "niz",
    "nox",
    "noy",
    "noz",
    "psi_inner",
    "psi_outer",
    "gix",
    "giy",
    "giz",
    "gox",
    "goy",
    "goz",
    "uix",
    "uiy",
    "uiz",
    "uox",
    "uoy",
    "uoz",
    "bx",
    "by",
    "bz",
    "film_inner",
    "film_outer",
)
N_RECORD = len(RECORD_FIELDS)

#: local condensation: absolute tolerance on the contact deflections [m] and the
#: iteration limit (a solve that does not converge counts in ``state``, see :func:`row_kernel`)
CONDENSE_TOL = 1e-13
CONDENSE_MAXIT = 50

#: ``jacobian`` mode of :func:`row_eval` for the local solve of quasi-static balls
#: (:func:`ball_equilibrium`): into ``jq`` of shape (3Z, 4) each ball's own 3x3 block
#: K_bb = d f_ball / d ball and, in column 3, K_bx x_t = (d f_ball / d x) x_t, the rate of
#: the ball's force from the motion of the frame and rings at a fixed ball (-K_c times
#: each groove centre's velocity, and the cage pocket's turn)
BALL_BLOCKS = 2
#: ``jacobian`` mode of :func:`row_eval` for quasi-static balls (rigid and modal rings): into
#: ``jq``, ``jv`` of shape (nx, nx) the Jacobians condensed onto the frame and modal
#: coordinates x, ball by ball (:func:`_condense_ball`), each ball's S = d b / d x into the
#: balls' work array (:func:`ball_workspace`)
CONDENSED_BALLS = 3


@njit(cache=True, inline="always")
def _mode(jacobian):
    """A ``jacobian`` mode (False, True, :data:`BALL_BLOCKS`, :data:`CONDENSED_BALLS`) as a run-time
    int64. Every call of a row phase passes its mode through here (and :func:`row_part` its
    ``absolute`` through :func:`_flag`): numba specializes a compiled callee on a literal or a
    boolean argument, and each specialization of a phase compiles its whole call tree again
    (~10-20 s each); the branches on the mode cost nothing at run time."""
    return np.int64(jacobian)


@njit(cache=True, inline="always")
def _flag(value):
    """``value`` as a run-time boolean (not a literal: see :func:`_mode`)."""
    return bool(value)


#: a row's geometry and cage (lengths [m]): ball count, inner and outer groove centre radius and z,
#: inner and outer offsets, ball radius over pitch radius, speed factor, cage ratio, cage stiffness
#: and damping, pocket stiffness; the balls' model (quasi-static: solved inside the element, else
#: element coordinates with inertia) and the quasi-static balls' relative force tolerance
RowGeometry = law_type(
    "RowGeometry",
    z=float,
    inner_center_radius=float,
    inner_center_z=float,
    outer_center_radius=float,
    outer_center_z=float,
    inner_offset=float,
    outer_offset=float,
    ball_radius_pitch=float,
    speed_factor=float,
    cage_ratio=float,
    cage_stiffness=float,
    cage_damping=float,
    pocket_stiffness=float,
    quasi_static_balls=bool,
    ball_force_tol=float,
)

#: the kernel inputs of a row (:func:`flexrv.model.flexible_bearing.kernel_inputs`), read by name:
#: ball reference positions (Z, 3) [m]; the row's geometry and cage (:data:`RowGeometry`); per ring
#: (``_i`` inner, ``_o`` outer): the contact law (:data:`PointLaw`), the cylindrical raceway table
#: (n_grid, 3, m) of a MODAL ring ((1, 3, 0): none), the compliance factors T K^-1/2 (n_grid, 3, m)
#: of a CONDENSED ring ((0, 3, 0): none) and the work array (:func:`condense_workspace`,
#: :func:`film_workspace`); ``zsign``: the inner and outer raceway tables' z sign (-1: mirrored);
#: ``balls``: the quasi-static balls' work array (:func:`ball_workspace`; empty with ball inertia);
#: ``state`` (int64, 8): the local solves' statistics (see :func:`row_eval`)
RowPack = pack_type(
    "RowPack",
    ("ball_ref", (np.float64, 2)),
    ("geometry", RowGeometry),
    ("law_i", PointLaw),
    ("law_o", PointLaw),
    ("tab_i", (np.float64, 3)),
    ("tab_o", (np.float64, 3)),
    ("comp_i", (np.float64, 3)),
    ("comp_o", (np.float64, 3)),
    ("ws_i", (np.float64, 1)),
    ("ws_o", (np.float64, 1)),
    ("zsign", (np.float64, (2,))),
    ("balls", (np.float64, 1)),
    ("state", (np.int64, (8,))),
)

#: what pass 1 of :func:`row_eval` (:func:`_row_geometry`) hands on, read by name: ball centres,
#: inner and outer azimuths, the outer azimuths' cos and sin, the arms A p of the inner groove
#: centres, ball minus groove centre e0 and relative velocity w0 of each ring's contacts, the
#: raceway displacements du at the contacts (global: modal rings here, condensed rings from their
#: local solves), the condensed rings' rotations to their cylindrical frames (empty: not
#: condensed) and the modal rings' raceway bases at every ball
RowPass1 = namedtuple(
    "RowPass1",
    "bpos psi_i psi_o cs_o arm e0_i w0_i e0_o w0_o du_i du_o rot_i rot_o bas_i bas_o",
    module=__name__,
)
#: what the contact phase of :func:`row_eval` (:func:`_row_contacts`) hands on, per ring (``_i``,
#: ``_o``): the contacts' loads, unit normals, dQ/d delta, damping coefficients, lengths |e|, central
#: films and the condensed rings' global compliance factors (3Z, m; empty: none or no Jacobian)
RowContacts = namedtuple(
    "RowContacts",
    "load_i load_o nrm_i nrm_o dq_i dq_o cd_i cd_o len_i len_o film_i film_o wg_i wg_o",
    module=__name__,
)

#: quasi-static balls (:func:`ball_equilibrium`): the load [N] below which the local solve's
#: force tolerance (relative to the row's largest contact load, ``geometry.ball_force_tol``) turns
#: absolute, and its Newton steps per call before a failure is reported
BALL_LOAD_SCALE = 1.0
BALL_MAXIT = 30
#: relative force tolerance of the quasi-static balls' local solve: 1e-6 of the row's largest
#: load (1e-4 N on rv221's 111 N balls, 2e-5 N on rv40e's 18 N): the sum over both rows'
#: 52-76 balls, at most 5e-3 / 1.5e-3 N, stays 20-70x below the absolute Newton tolerance of
#: the system (0.1 N per coordinate, flexrv.simulation.DEFAULT_NEWTON_TOLERANCE), and a ball
#: load error of 1e-6 is far below any output's meaning. Tighter costs Newton steps: 1e-8
#: took 1.14 steps per solve on rv40e against 0.77 (row force 73 -> 63 us per call of both
#: rows, replayed). The round-off floor is ~3e-11 of the loads (an absolute 1e-9 N stalls on
#: rv221)
BALL_FORCE_TOL = 1e-6

#: relative Newton step below which the film iteration of :func:`_normal_load` stops
#: (its next iterate is then exact to 0.75 FILM_STEP_STOP^2 relative, see there)
FILM_STEP_STOP = 1e-8

#: LLVM flags of the condensation's dense loops: reassociated sums (vectorised dot
#: products over the ring's modes) and fused multiply-adds; changes only the
#: round-off (measured <= 1e-13 relative on the ball loads), no NaN/Inf assumptions
_REASSOC = {"reassoc", "contract"}


def law_parameters(law) -> PointLaw | None:
    """Kernel parameters of a normal law (:data:`PointLaw`; for an EHL law in mode
    ``"map"`` with the map's packed table), or None if the kernel does not cover it."""
    from flexrv.contact.ball_raceway import HertzLaw
    from flexrv.ehl.film import HAMROCK_DOWSON_LOAD_EXPONENT
    from flexrv.ehl.law import EHLPointLaw

    if isinstance(law, HertzLaw) and np.ndim(law.k) == 0:
        return PointLaw.of(
            k=law.k,
            h_unit=0.0,
            load_exponent=0.0,
            speed_exponent=0.0,
            load_floor=1.0,
            c_max=law.c_max,
            depth=law.depth,
            iterations=0,
            film_map=np.zeros(0),
        )
    if isinstance(law, EHLPointLaw) and law.mode in ("dry", "hamrock_dowson", "map") and np.ndim(law.stiffness) == 0:
        h_unit = 0.0 if law.mode == "dry" else float(law._h_unit)
        return PointLaw.of(
            k=float(law.stiffness),
            h_unit=h_unit,
            load_exponent=HAMROCK_DOWSON_LOAD_EXPONENT,
            speed_exponent=0.67,
            load_floor=law.load_floor,
            c_max=law.c_max,
            depth=law.damping_depth,
            iterations=law.iterations,
            film_map=law.film_map.packed if law.mode == "map" else np.zeros(0),
        )
    return None


@njit(cache=True)
def _film(q, hu, lexp, lu, law):
    """Central film h [m] and d ln h / d ln Q at load q [N] (>= the load floor):
    Hamrock–Dowson hu q^lexp (hu: h at 1 N and the current speed), times the solver
    map's correction exp(c(ln q, lu)) when the law carries a map
    (flexrv.ehl.law.EHLPointLaw.film; c from flexrv.ehl.maps.packed_log_correction)."""
    h = hu * q**lexp
    if law.film_map.shape[0] > 0:
        c, dc = packed_log_correction(law.film_map, math.log(q), lu)
        return h * math.exp(c), lexp + dc
    return h, lexp


@njit(cache=True)
def _law_speed(speed, law):
    """Speed terms of the law, shared by all contacts of a row at one entrainment
    speed u [m/s]: (h at 1 N and u [m] (0: dry / at rest), ln u, film at the load
    floor [m])."""
    if not (law.h_unit > 0.0 and speed > 0.0):
        return 0.0, 0.0, 0.0
    hu = law.h_unit * speed**law.speed_exponent
    lu = math.log(speed)
    h_floor, _ = _film(law.load_floor, hu, law.load_exponent, lu, law)
    return hu, lu, h_floor


@njit(cache=True)
def _normal_load(delta, rate, hu, lu, h_floor, law, h_start=0.0):
    """(Q, dQ/d delta, dQ/d rate, film h_c [m]) of the EHL-corrected / dry law
    (flexrv.ehl.law._solve and flexrv.contact.laws.impact_force, n = 3/2; the film is
    0 out of contact, as in flexrv.ehl.law.EHLForce.film) with the speed terms
    (hu, lu, h_floor) of :func:`_law_speed`. The film offset s = delta + h(k s^1.5)
    takes at most ``iterations`` Newton steps; they stop early at a fixed point
    (s unchanged to the bit), or once a step is below ``FILM_STEP_STOP`` s with both
    iterates on the same side of the load floor and phi' >= 1 (film falling with
    load: Hamrock-Dowson, and the maps). Then phi is smooth between them and, with
    h ~ s^p (p = 1.5 d ln h/d ln Q <= 0), phi''/(2 phi') s <= |p - 1|/2 <= 0.75,
    so the relative error of the new iterate is <= 0.75 (step/s)^2 (< 1e-16); the
    film and phi' are carried to it to first order in the step (error
    O(step^2)). Measured (rv40e law, 0.05-0.2 m/s): 3 film evaluations (powers)
    per loaded contact instead of 4-5, the relative steps being ~3e-2, ~2e-5,
    ~1e-11; the result equals all ``iterations`` steps within round-off
    (tests/test_model_flexible_rings.py::test_kernel_normal_law_equals_ehl_law).

    ``h_start`` > 0 (the contact's film of the previous call, kept by the row kernel:
    the last Z entries of a ring's work array, :func:`condense_workspace`) starts the
    iteration at s = delta + h_start instead of delta + h_floor: within a time step
    the film moves by ~1e-6 of itself, so the first step is already below
    FILM_STEP_STOP and ONE film evaluation gives the same fixed point (the error
    bound above holds from any start; measured: the same loads within ~1e-15
    relative, tests/test_model_flexible_rings.py::test_film_warm_start_same_fixed_point)."""
    k, lexp, floor, c_max, depth, iters = law.k, law.load_exponent, law.load_floor, law.c_max, law.depth, law.iterations
    dphi = 1.0
    h = 0.0
    if hu == 0.0:
        s = max(delta, 0.0)
    else:
        s = max(delta + (h_start if h_start > 0.0 else h_floor), 0.0)
        for it in range(iters + 1):
            q = k * s * math.sqrt(s)
            above = q > floor
            h, slope = _film(max(q, floor), hu, lexp, lu, law)
            dphi = 1.0
            if above:
                dphi = 1.0 - 1.5 * slope * h / max(s, 1e-300)
            dphi = max(dphi, 1e-3)
            if it == iters:
                break
            s_next = max(s - (s - delta - h) / dphi, 0.0)
            step = s_next - s
            if step == 0.0:
                break
            if dphi >= 1.0 and abs(step) <= FILM_STEP_STOP * s and (k * s_next * math.sqrt(s_next) > floor) == above:
                if above:  # h(s_next) = h (s_next/s)^p to first order; phi' there
                    h *= 1.0 + 1.5 * slope * step / s
                    dphi = max(1.0 - 1.5 * slope * h / s_next, 1e-3)
                s = s_next
                break
            s = s_next
    if s <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    force = k * s * math.sqrt(s)
    dforce = 1.5 * k * math.sqrt(s) / dphi
    c = 0.0
    if c_max > 0.0:
        x = min(max(s / depth, 0.0), 1.0)
        c = c_max * x * x * (3.0 - 2.0 * x)
        force += c * rate
        dforce += c_max * 6.0 * x * (1.0 - x) / depth / dphi * rate
    if force <= 0.0:
        return 0.0, 0.0, 0.0, h
    return force, dforce, c, h


@njit(cache=True)
def _contact(ex, ey, ez, wx, wy, wz, offset, hu, lu, h_floor, law, h_start):
    """Ball-groove contact from the ball-minus-centre vector e and relative velocity w,
    with the law's speed terms (hu, lu, h_floor) of :func:`_law_speed` and the film
    iteration's start ``h_start`` (:func:`_normal_load`):
    (|e|, unit normal, Q, dQ/ddelta, dQ/drate, film h_c); the force on the ball is -Q n."""
    length = math.sqrt(ex * ex + ey * ey + ez * ez)
    nx, ny, nz = ex / length, ey / length, ez / length
    q, dq, c, h = _normal_load(length - offset, nx * wx + ny * wy + nz * wz, hu, lu, h_floor, law, h_start)
    return length, nx, ny, nz, q, dq, c, h


@njit(cache=True)
def _taps(psi, ng, idx, w):
    """Grid indices idx[4] and weights w[4] of the periodic Catmull–Rom cubic on the
    uniform grid 2 pi i / ng at azimuth psi (flexrv.fem.reduction.periodic_cubic)."""
    u = (psi % (2.0 * math.pi)) * (ng / (2.0 * math.pi))
    i = int(math.floor(u))
    t = u - i
    t2 = t * t
    t3 = t2 * t
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t)
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0)
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t)
    w[3] = 0.5 * (t3 - t2)
    for a in range(4):
        idx[a] = (i - 1 + a) % ng


@njit(cache=True)
def _basis(table, zsign, psi, out):
    """Cartesian raceway displacement per modal coordinate at azimuth psi -> out (3, m)
    (the periodic cubic of the cylindrical table, z mirrored by zsign)."""
    m = table.shape[2]
    idx = np.empty(4, np.int64)
    w = np.empty(4)
    _taps(psi, table.shape[0], idx, w)
    c, s = math.cos(psi), math.sin(psi)
    for j in range(m):
        ar = (
            w[0] * table[idx[0], 0, j]
            + w[1] * table[idx[1], 0, j]
            + w[2] * table[idx[2], 0, j]
            + w[3] * table[idx[3], 0, j]
        )
        at = (
            w[0] * table[idx[0], 1, j]
            + w[1] * table[idx[1], 1, j]
            + w[2] * table[idx[2], 1, j]
            + w[3] * table[idx[3], 1, j]
        )
        az = (
            w[0] * table[idx[0], 2, j]
            + w[1] * table[idx[1], 2, j]
            + w[2] * table[idx[2], 2, j]
            + w[3] * table[idx[3], 2, j]
        )
        out[0, j] = c * ar - s * at
        out[1, j] = s * ar + c * at
        out[2, j] = zsign * az


@njit(cache=True)
def _contact_blocks(q_load, dq, c, length, nx, ny, nz, etx, ety, stiff, damp):
    """d force_ball / d ball position and velocity (3x3) of one contact
    (d/db of -Q n: -(dQ n n^T + Q/L (I - n n^T)), plus the follower term Q/L e_t e_t^T:
    the groove centre follows the ball's azimuth, so a tangential ball motion does
    not rotate the contact normal)."""
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
def _contact_factors(q_load, dq, length, nx, ny, nz, etx, ety, out):
    """Factor V (3 x 2, its rows into ``out`` (2, 3)) of the contact stiffness block
    of :func:`_contact_blocks`, K = -V V^T: V = [sqrt(dQ/d delta) n, sqrt(Q/L) b]
    with b = n x e_t / |n x e_t|. Since I - n n^T - e_t e_t^T = b b^T for n normal
    to e_t, this is the block itself when the normal lies in the ball's meridian
    plane (the groove centre follows the ball's azimuth); a ring's tangential
    deflection tilts it by n.e_t ~ u_t / L (~1e-5), which changes the geometric
    term Q/L (itself ~1e-2 of dQ/d delta) by that fraction: the tangent of the
    condensed rings (:func:`_condensed_contact_matrix`), not the force."""
    bx, by, bz = -nz * ety, nz * etx, nx * ety - ny * etx  # n x e_t, e_t = (etx, ety, 0)
    bn = math.sqrt(bx * bx + by * by + bz * bz)
    sa = math.sqrt(max(dq, 0.0))
    sb = math.sqrt(max(q_load / length, 0.0)) / bn if (bn > 0.0 and length > 0.0) else 0.0
    out[0, 0], out[0, 1], out[0, 2] = sa * nx, sa * ny, sa * nz
    out[1, 0], out[1, 1], out[1, 2] = sb * bx, sb * by, sb * bz


@njit(cache=True)
def _local_factors(psi, wtab, zsign, out):
    """Compliance factors (Z, 3, m) of a condensed ring at the contact azimuths psi:
    out[j] = S B_cyl(psi_j) K^-1/2 in the ring's cylindrical components at contact j
    (the periodic cubic of ``wtab`` = T K^-1/2, (ng, 3, m)), S = diag(1, 1, zsign);
    the compliance blocks are C_jk = out[j] out[k]^T."""
    nz = psi.shape[0]
    ng = wtab.shape[0]
    m = wtab.shape[2]
    idx = np.empty(4, np.int64)
    w = np.empty(4)
    for j in range(nz):
        _taps(psi[j], ng, idx, w)
        for a in range(3):
            sg = zsign if a == 2 else 1.0
            r0, r1, r2, r3 = wtab[idx[0], a], wtab[idx[1], a], wtab[idx[2], a], wtab[idx[3], a]
            w0, w1, w2, w3 = sg * w[0], sg * w[1], sg * w[2], sg * w[3]
            for k in range(m):
                out[j, a, k] = w0 * r0[k] + w1 * r1[k] + w2 * r2[k] + w3 * r3[k]


def condense_workspace(ball_count: int, n_modes: int) -> np.ndarray:
    """Persistent work array of a condensed ring in a row (see :func:`_split_workspace`):
    the contact deflections (warm start), the last Newton tangent, the scratch
    of the local solve (:func:`_split_scratch`: no allocation per call) and, as for
    every ring (:func:`film_workspace`), the contacts' films of the last call in the
    last Z entries (the film iteration's warm start, :func:`_normal_load`)."""
    z, m = int(ball_count), int(n_modes)
    return np.zeros(3 * z + 1 + z + 3 * z + z * m + z * z + 3 * z * m + 4 * 3 * z + m + z + z)


def film_workspace(ball_count: int) -> np.ndarray:
    """Work array of a rigid or modal ring in a row: the contacts' films of the last
    call (Z,), the film iteration's warm start (:func:`_normal_load`; zero: from the
    load floor's film)."""
    return np.zeros(int(ball_count))


@njit(cache=True)
def _films(ws, nz):
    """The films' warm starts of a ring's contacts: the last Z entries of its work
    array (:func:`condense_workspace`, :func:`film_workspace`), or fresh zeros (a
    cold start every call) for a work array without them."""
    if ws.shape[0] >= nz:
        return ws[ws.shape[0] - nz :]
    return np.zeros(nz)


@njit(cache=True)
def _split_workspace(ws, nz, m):
    """Views of a condensed ring's work array: deflections u (Z,3), tangent-valid
    flag (1,), L^1/2 (Z,), normals (Z,3), P = W^T n (Z,m), Cholesky factor (Z,Z)."""
    o = 0
    u = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    valid = ws[o : o + 1]
    o += 1
    sq = ws[o : o + nz]
    o += nz
    nf = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    p = ws[o : o + nz * m].reshape((nz, m))
    o += nz * m
    smat = ws[o : o + nz * nz].reshape((nz, nz))
    return u, valid, sq, nf, p, smat


@njit(cache=True)
def _split_scratch(ws, nz, m):
    """Scratch views of a condensed ring's work array (after :func:`_split_workspace`'s):
    local factors W (Z,3,m), local approach and velocity (Z,3), local normals (Z,3),
    residual (Z,3), W^T g (m,), Z right-hand side (Z,)."""
    o = 3 * nz + 1 + nz + 3 * nz + nz * m + nz * nz
    wl = ws[o : o + 3 * nz * m].reshape((nz, 3, m))
    o += 3 * nz * m
    el = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    wv = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    nl = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    r = ws[o : o + 3 * nz].reshape((nz, 3))
    o += 3 * nz
    y = ws[o : o + m]
    o += m
    rhs = ws[o : o + nz]
    return wl, el, wv, nl, r, y, rhs


@njit(cache=True, fastmath=_REASSOC)
def _condense(e0, w0, wl, offset, speed, law, ws, loads, normals, dq, cd, lengths, films):
    """Contact deflections u of a condensed ring, everything in each contact's
    ring-cylindrical components: u_j = sum_k C_jk g_k(e0_k - u_k), C_jk = W_j W_k^T
    (wl: (Z, 3, m) factors W_j = S B_j K^-1/2), g_k = Q_k n_k the force on the
    ring. ``ws``: the ring's work array (u's warm start and the last tangent, see
    :func:`condense_workspace`). Fills the contact results at the solution
    (loads, normals, dQ/ddelta, damping coefficient, |e|, film); returns the number of
    iterations (-1: not converged).

    Chord (Newton-type) iterations with the normal contact stiffness only:
    (I + C N L N^T) du = -r, L = diag(dQ/d delta), solved by the Woodbury identity
    as the SPD Z x Z system (I + L^1/2 N^T C N L^1/2) with N^T C N = P P^T,
    P_k = W_k^T n_k. The tangent is kept (also from one call to the next) while
    the residual drops at least 10x per iteration, else refreshed; the
    convergence test is on the exact residual, so the tangent only sets the
    speed."""
    nz = e0.shape[0]
    m = wl.shape[2]
    u, valid, sq, nf, p, smat = _split_workspace(ws, nz, m)
    _, _, _, _, r, y, rhs = _split_scratch(ws, nz, m)
    err_prev = 0.0
    hu, lu, h_floor = _law_speed(speed, law)
    for it in range(CONDENSE_MAXIT + 1):
        for k in range(m):
            y[k] = 0.0
        for j in range(nz):
            length, nx, ny, nzz, q, d, c, hf = _contact(
                e0[j, 0] - u[j, 0],
                e0[j, 1] - u[j, 1],
                e0[j, 2] - u[j, 2],
                w0[j, 0],
                w0[j, 1],
                w0[j, 2],
                offset,
                hu,
                lu,
                h_floor,
                law,
                films[j],
            )
            loads[j], dq[j], cd[j], lengths[j], films[j] = q, d, c, length, hf
            normals[j, 0], normals[j, 1], normals[j, 2] = nx, ny, nzz
            if q != 0.0:
                g0, g1, g2 = q * nx, q * ny, q * nzz
                for k in range(m):
                    y[k] += wl[j, 0, k] * g0 + wl[j, 1, k] * g1 + wl[j, 2, k] * g2
        err = 0.0
        for j in range(nz):
            for a in range(3):
                v = u[j, a]
                for k in range(m):
                    v -= wl[j, a, k] * y[k]
                r[j, a] = v
                err = max(err, abs(v))
        if err <= CONDENSE_TOL:
            return it
        if it == CONDENSE_MAXIT:
            break
        if valid[0] == 0.0 or (it > 0 and err > 0.1 * err_prev):
            # tangent: P_k = W_k^T n_k; M = I + L^1/2 P P^T L^1/2, Cholesky-factored
            for j in range(nz):
                sq[j] = math.sqrt(max(dq[j], 0.0))
                n0, n1, n2 = normals[j, 0], normals[j, 1], normals[j, 2]
                nf[j, 0], nf[j, 1], nf[j, 2] = n0, n1, n2
                for k in range(m):
                    p[j, k] = wl[j, 0, k] * n0 + wl[j, 1, k] * n1 + wl[j, 2, k] * n2
            for j in range(nz):
                for i in range(j + 1):
                    v = 0.0
                    if sq[j] > 0.0 and sq[i] > 0.0:
                        for k in range(m):
                            v += p[j, k] * p[i, k]
                        v *= sq[j] * sq[i]
                    smat[j, i] = v
                    smat[i, j] = v
                smat[j, j] += 1.0
            cholesky(smat)
            valid[0] = 1.0
        for j in range(nz):
            rhs[j] = sq[j] * (nf[j, 0] * r[j, 0] + nf[j, 1] * r[j, 1] + nf[j, 2] * r[j, 2])
        cholesky_solve(smat, rhs)
        # correction C N L y' = W (P^T (L^1/2 z))
        for k in range(m):
            y[k] = 0.0
        for j in range(nz):
            zj = sq[j] * rhs[j]
            if zj != 0.0:
                for k in range(m):
                    y[k] += p[j, k] * zj
        for j in range(nz):
            for a in range(3):
                corr = 0.0
                for k in range(m):
                    corr += wl[j, a, k] * y[k]
                u[j, a] -= r[j, a] - corr
        err_prev = err
    return -1


@njit(cache=True)
def _condensed_ring(
    psi, rot, wtab, zsign, e0, w0, offset, speed, law, ws, loads, normals, dq, cd, lengths, films, du, wglobal
):
    """One condensed ring of a row: the contact geometry e0, w0 (Z,3, global) in
    each contact's ring-cylindrical frame (rot (Z,3,3): cylindrical -> global),
    the compliance factors, the contact solve (:func:`_condense`, deflections u
    kept in these local frames in the work array ``ws`` as the next call's warm
    start), and back to global
    normals and raceway displacements du. With ``wglobal`` of shape (3Z, m) the
    global compliance factors R_j W_j stacked (C_jk = R_j W_j W_k^T R_k^T: for the
    Jacobian, :func:`_condensed_contact_matrix`). Returns the iteration count."""
    nz = psi.shape[0]
    m = wtab.shape[2]
    wl, el, wv, nl, _, _, _ = _split_scratch(ws, nz, m)
    _local_factors(psi, wtab, zsign, wl)
    for j in range(nz):
        for a in range(3):
            el[j, a] = rot[j, 0, a] * e0[j, 0] + rot[j, 1, a] * e0[j, 1] + rot[j, 2, a] * e0[j, 2]
            wv[j, a] = rot[j, 0, a] * w0[j, 0] + rot[j, 1, a] * w0[j, 1] + rot[j, 2, a] * w0[j, 2]
    its = _condense(el, wv, wl, offset, speed, law, ws, loads, nl, dq, cd, lengths, films)
    u = ws[0 : 3 * nz].reshape((nz, 3))
    for j in range(nz):
        for a in range(3):
            normals[j, a] = rot[j, a, 0] * nl[j, 0] + rot[j, a, 1] * nl[j, 1] + rot[j, a, 2] * nl[j, 2]
            du[j, a] = rot[j, a, 0] * u[j, 0] + rot[j, a, 1] * u[j, 1] + rot[j, a, 2] * u[j, 2]
    if wglobal.shape[0] == 3 * nz:
        for j in range(nz):
            for a in range(3):
                for k in range(m):
                    wglobal[3 * j + a, k] = (
                        rot[j, a, 0] * wl[j, 0, k] + rot[j, a, 1] * wl[j, 1, k] + rot[j, a, 2] * wl[j, 2, k]
                    )
    return its


@njit(cache=True)
def _count_solve(state, k, its):
    """A local solve's statistics in state[k:k + 4] (:func:`row_eval`'s ``state``): its
    failure (its < 0) counted and flagged, or its iterations added; solves counted."""
    state[k + 3] += 1
    if its < 0:
        state[k] += 1
        state[k + 1] = 1
    else:
        state[k + 2] += its


@njit(cache=True)
def _ring_contacts(
    condensed,
    psi,
    rot,
    comp,
    zs,
    e0,
    w0,
    off,
    speed,
    law,
    ws,
    loads,
    normals,
    dq,
    cd,
    lengths,
    films,
    du,
    wglobal,
    state,
):
    """The ball contacts of one ring of a row: the condensed ring's local solve
    (:func:`_condensed_ring`, its iteration count and failures in ``state``) or, for a
    rigid / modal ring, each contact from its approach (:func:`_contact`)."""
    if condensed:
        its = _condensed_ring(
            psi, rot, comp, zs, e0, w0, off, speed, law, ws, loads, normals, dq, cd, lengths, films, du, wglobal
        )
        _count_solve(state, 0, its)
    else:
        hu, lu, h_floor = _law_speed(speed, law)
        for j in range(e0.shape[0]):
            lengths[j], normals[j, 0], normals[j, 1], normals[j, 2], loads[j], dq[j], cd[j], films[j] = _contact(
                e0[j, 0], e0[j, 1], e0[j, 2], w0[j, 0], w0[j, 1], w0[j, 2], off, hu, lu, h_floor, law, films[j]
            )


@njit(cache=True)
def _rotation_z(a, c, s, out):
    """out = a Rz(psi) with c, s = cos psi, sin psi: ring-cylindrical components at
    psi -> global."""
    for i in range(3):
        out[i, 0] = a[i, 0] * c + a[i, 1] * s
        out[i, 1] = -a[i, 0] * s + a[i, 1] * c
        out[i, 2] = a[i, 2]


@njit(cache=True)
def row_kernel(q, qt, p, jacobian, rec):
    """Generalized force (n,) of a row element and, with ``jacobian``, its
    derivatives d f / d q and d f / d q_t (n, n) (new arrays; :func:`row_eval`
    with its outputs allocated here). Quasi-static balls (``geometry.quasi_static_balls``):
    q, q_t, the force and the Jacobians cover the frame and modal coordinates only
    (:func:`quasi_static_balls`, warm-started from and updating ``p.balls``)."""
    nb = 3 * p.ball_ref.shape[0]
    n = 6 + p.tab_i.shape[2] + p.tab_o.shape[2] + nb
    f = np.empty(n)
    if p.geometry.quasi_static_balls:
        nx = n - nb
        qf = np.zeros(n)
        vf = np.zeros(n)
        qf[:nx] = q
        vf[:nx] = qt
        nk = nx if jacobian else 0
        kx = np.empty((nk, nk))
        cx = np.empty((nk, nk))
        quasi_static_balls(qf, vf, p, _mode(jacobian), rec, f, np.empty((nb, 4)), kx, cx)
        return f[:nx].copy(), kx, cx
    nj = n if jacobian else 0
    jq = np.zeros((nj, nj))  # (zero: row_eval clears only the entries it writes)
    jv = np.zeros((nj, nj))
    row_eval(q, qt, p, _mode(jacobian), rec, f, jq, jv)
    return f, jq, jv


@njit(cache=True)
def _add_block_jacobian(jac, kb, t, b, x0, nx):
    """Add one contact's Jacobian blocks to ``jac``: the contact block kb (3x3) on the
    ball coordinates b..b+2 and T (3 x nx, d contact point / d x for x at columns
    x0..x0+nx-1): d f_ball/d b = kb, d f_ball/d x = -kb T, d g_x/d b = -T^T kb,
    d g_x/d x = T^T kb T (block-sparse form of the dense products in :func:`row_eval`)."""
    for r in range(3):
        for c in range(3):
            jac[b + r, b + c] += kb[r, c]
    for c in range(nx):
        t0, t1, t2 = t[0, c], t[1, c], t[2, c]
        for r in range(3):
            jac[b + r, x0 + c] -= kb[r, 0] * t0 + kb[r, 1] * t1 + kb[r, 2] * t2
            jac[x0 + c, b + r] -= t0 * kb[0, r] + t1 * kb[1, r] + t2 * kb[2, r]
        tk0 = t0 * kb[0, 0] + t1 * kb[1, 0] + t2 * kb[2, 0]  # (T^T kb)[c, :]
        tk1 = t0 * kb[0, 1] + t1 * kb[1, 1] + t2 * kb[2, 1]
        tk2 = t0 * kb[0, 2] + t1 * kb[1, 2] + t2 * kb[2, 2]
        for d in range(nx):
            jac[x0 + c, x0 + d] += tk0 * t[0, d] + tk1 * t[1, d] + tk2 * t[2, d]


@njit(cache=True)
def _add_speed_column(jac, kb, t, b, x0, nx, col, dx, dy, dz):
    """Add to column ``col`` of ``jac`` the response to the ball displacement d (3,)
    of one contact with block kb and T (see :func:`_add_block_jacobian`):
    d f_ball = kb d, d g_x = -T^T kb d (the film-speed term of :func:`row_eval`)."""
    k0 = kb[0, 0] * dx + kb[0, 1] * dy + kb[0, 2] * dz
    k1 = kb[1, 0] * dx + kb[1, 1] * dy + kb[1, 2] * dz
    k2 = kb[2, 0] * dx + kb[2, 1] * dy + kb[2, 2] * dz
    jac[b, col] += k0
    jac[b + 1, col] += k1
    jac[b + 2, col] += k2
    for c in range(nx):
        jac[x0 + c, col] -= t[0, c] * k0 + t[1, c] * k1 + t[2, c] * k2


@njit(cache=True)
def _film_speed_gain(law, speed, film):
    """d h_c / d u [s] of a contact's film at entrainment speed u > 0 (Hamrock-Dowson
    h ~ u^0.67; a map's own speed dependence is left out: Jacobian only)."""
    if speed <= 0.0 or law.h_unit <= 0.0:
        return 0.0
    return law.speed_exponent * film / speed


@njit(cache=True)
def _modal_sums(bas, q, qt, off, m):
    """The ring's displacement and velocity at a ball (3 + 3 values): sum_k bas[:, k] q[off + k]
    and sum_k bas[:, k] qt[off + k] over its m modal coordinates."""
    d0 = d1 = d2 = 0.0
    v0 = v1 = v2 = 0.0
    for k in range(m):
        qk, vk = q[off + k], qt[off + k]
        d0 += bas[0, k] * qk
        d1 += bas[1, k] * qk
        d2 += bas[2, k] * qk
        v0 += bas[0, k] * vk
        v1 += bas[1, k] * vk
        v2 += bas[2, k] * vk
    return d0, d1, d2, v0, v1, v2


@njit(cache=True)
def _zero_written(jac, nx, nz):
    """Zero the entries of a row Jacobian (n, n) that :func:`row_eval` writes for rigid
    and modal rings: the nx rows and columns of the frame and modal coordinates and
    each ball's own 3x3 block (the ball-ball blocks of different balls are never
    written and stay zero from the array's allocation: ~(3Z)^2 entries not touched
    per call, 2 x 14,400 on rv40e)."""
    n = jac.shape[0]
    for r in range(nx):
        for c in range(n):
            jac[r, c] = 0.0
    for r in range(nx, n):
        for c in range(nx):
            jac[r, c] = 0.0
    for j in range(nz):
        b = nx + 3 * j
        for r in range(3):
            for c in range(3):
                jac[b + r, b + c] = 0.0


@njit(cache=True, inline="always")
def _frame_kinematics(q, qt):
    """The frame's rotation A = Rx(ax) Ry(ay) Rz(az), the map G of omega = G phi_t
    (Exudyn RotXYZ2RotationMatrix / RotXYZ2G) and omega's components."""
    ax, ay, az = q[3], q[4], q[5]
    sa, ca, sb, cb, sc, cc = math.sin(ax), math.cos(ax), math.sin(ay), math.cos(ay), math.sin(az), math.cos(az)
    a = np.empty((3, 3))
    a[0, 0], a[0, 1], a[0, 2] = cb * cc, -cb * sc, sb
    a[1, 0], a[1, 1], a[1, 2] = ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb
    a[2, 0], a[2, 1], a[2, 2] = sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb
    g = np.empty((3, 3))
    g[0, 0], g[0, 1], g[0, 2] = 1.0, 0.0, sb
    g[1, 0], g[1, 1], g[1, 2] = 0.0, ca, -sa * cb
    g[2, 0], g[2, 1], g[2, 2] = 0.0, sa, ca * cb
    om0 = g[0, 0] * qt[3] + g[0, 1] * qt[4] + g[0, 2] * qt[5]
    om1 = g[1, 0] * qt[3] + g[1, 1] * qt[4] + g[1, 2] * qt[5]
    om2 = g[2, 0] * qt[3] + g[2, 1] * qt[4] + g[2, 2] * qt[5]
    return a, g, om0, om1, om2


@njit(cache=True, inline="always")
def _row_geometry(q, qt, ball_ref, geometry, tab_i, zs_i, tab_o, zs_o, cond_i, cond_o, jacobian, a, om):
    """Pass 1 of :func:`row_eval`: the geometry of every ball with the rings undeflected
    (modal rings: with their coordinates), ball minus groove centre e0 and relative
    velocity w0 of both contacts: a :data:`RowPass1`."""
    om0, om1, om2 = om
    z_row, ci_r, ci_z = geometry.z, geometry.inner_center_radius, geometry.inner_center_z
    co_r, co_z = geometry.outer_center_radius, geometry.outer_center_z
    m_i = tab_i.shape[2]
    m_o = tab_o.shape[2]
    nz = ball_ref.shape[0]
    b0 = 6 + m_i + m_o
    bas_i = np.empty((3, m_i))
    bas_o = np.empty((3, m_o))
    bpos = np.empty((nz, 3))
    psi_i = np.empty(nz)
    psi_o = np.empty(nz)
    cs_o = np.empty((nz, 2))  # cos, sin of the outer azimuth
    arm = np.empty((nz, 3))  # A p: groove centre relative to the frame origin (global axes)
    e0_i = np.empty((nz, 3))
    w0_i = np.empty((nz, 3))
    e0_o = np.empty((nz, 3))
    w0_o = np.empty((nz, 3))
    du_i = np.zeros((nz, 3))  # raceway displacement at the contact (global), modal or condensed
    du_o = np.zeros((nz, 3))
    rot_i = np.empty((nz if cond_i else 0, 3, 3))
    rot_o = np.empty((nz if cond_o else 0, 3, 3))
    nzj = nz if jacobian else 0
    bas_i_all = np.empty((nzj if m_i > 0 else 0, 3, m_i))
    bas_o_all = np.empty((nzj if m_o > 0 else 0, 3, m_o))
    for j in range(nz):
        bj = b0 + 3 * j
        bx = ball_ref[j, 0] + q[bj]
        by = ball_ref[j, 1] + q[bj + 1]
        bz = ball_ref[j, 2] + q[bj + 2]
        bpos[j, 0], bpos[j, 1], bpos[j, 2] = bx, by, bz
        vx, vy, vz = qt[bj], qt[bj + 1], qt[bj + 2]
        # ---- inner ring (frame)
        dx, dy, dz = bx - q[0], by - q[1], bz - q[2]
        lx = dx * a[0, 0] + dy * a[1, 0] + dz * a[2, 0]
        ly = dx * a[0, 1] + dy * a[1, 1] + dz * a[2, 1]
        psi = math.atan2(ly, lx)
        psi_i[j] = psi
        rl = math.sqrt(lx * lx + ly * ly)  # cos, sin of psi without evaluating them
        cos_p, sin_p = lx / rl, ly / rl
        p0, p1, p2 = ci_r * cos_p, ci_r * sin_p, ci_z + z_row
        apv0 = apv1 = apv2 = 0.0  # velocity of the groove centre relative to the frame (modal ring)
        if m_i > 0:
            _basis(tab_i, zs_i, psi, bas_i)
            dp0, dp1, dp2, pv0, pv1, pv2 = _modal_sums(bas_i, q, qt, 6, m_i)
            p0, p1, p2 = p0 + dp0, p1 + dp1, p2 + dp2
            for r in range(3):
                du_i[j, r] = a[r, 0] * dp0 + a[r, 1] * dp1 + a[r, 2] * dp2
            apv0 = a[0, 0] * pv0 + a[0, 1] * pv1 + a[0, 2] * pv2
            apv1 = a[1, 0] * pv0 + a[1, 1] * pv1 + a[1, 2] * pv2
            apv2 = a[2, 0] * pv0 + a[2, 1] * pv1 + a[2, 2] * pv2
            if jacobian:
                bas_i_all[j] = bas_i
        if cond_i:
            _rotation_z(a, cos_p, sin_p, rot_i[j])
        ap0 = a[0, 0] * p0 + a[0, 1] * p1 + a[0, 2] * p2
        ap1 = a[1, 0] * p0 + a[1, 1] * p1 + a[1, 2] * p2
        ap2 = a[2, 0] * p0 + a[2, 1] * p1 + a[2, 2] * p2
        arm[j, 0], arm[j, 1], arm[j, 2] = ap0, ap1, ap2
        e0_i[j, 0], e0_i[j, 1], e0_i[j, 2] = bx - q[0] - ap0, by - q[1] - ap1, bz - q[2] - ap2
        w0_i[j, 0] = vx - (qt[0] + om1 * ap2 - om2 * ap1 + apv0)
        w0_i[j, 1] = vy - (qt[1] + om2 * ap0 - om0 * ap2 + apv1)
        w0_i[j, 2] = vz - (qt[2] + om0 * ap1 - om1 * ap0 + apv2)
        # ---- outer ring (housing)
        psi = math.atan2(by, bx)
        psi_o[j] = psi
        rl = math.sqrt(bx * bx + by * by)
        cos_p, sin_p = bx / rl, by / rl
        cs_o[j, 0], cs_o[j, 1] = cos_p, sin_p
        ox, oy, oz = co_r * cos_p, co_r * sin_p, co_z + z_row
        ovx = ovy = ovz = 0.0
        if m_o > 0:
            _basis(tab_o, zs_o, psi, bas_o)
            ux, uy, uz, ovx, ovy, ovz = _modal_sums(bas_o, q, qt, 6 + m_i, m_o)
            du_o[j, 0], du_o[j, 1], du_o[j, 2] = ux, uy, uz
            ox, oy, oz = ox + ux, oy + uy, oz + uz
            if jacobian:
                bas_o_all[j] = bas_o
        if cond_o:
            r_o = rot_o[j]
            r_o[0, 0], r_o[0, 1], r_o[0, 2] = cos_p, -sin_p, 0.0
            r_o[1, 0], r_o[1, 1], r_o[1, 2] = sin_p, cos_p, 0.0
            r_o[2, 0], r_o[2, 1], r_o[2, 2] = 0.0, 0.0, 1.0
        e0_o[j, 0], e0_o[j, 1], e0_o[j, 2] = bx - ox, by - oy, bz - oz
        w0_o[j, 0], w0_o[j, 1], w0_o[j, 2] = vx - ovx, vy - ovy, vz - ovz
    return RowPass1(
        bpos, psi_i, psi_o, cs_o, arm, e0_i, w0_i, e0_o, w0_o, du_i, du_o, rot_i, rot_o, bas_i_all, bas_o_all
    )


@njit(cache=True, inline="always")
def _row_contacts(geometry, zs_i, zs_o, law_i, law_o, comp_i, comp_o, ws_i, ws_o, jacobian, speed, pre, state):
    """The contacts of both rings at every ball (:func:`_ring_contacts`; condensed rings:
    their local solves, the inner one's deflection added to the arms ``pre.arm``): a
    :data:`RowContacts`."""
    psi_i, psi_o, arm, e0_i, w0_i, e0_o, w0_o = pre.psi_i, pre.psi_o, pre.arm, pre.e0_i, pre.w0_i, pre.e0_o, pre.w0_o
    du_i, du_o, rot_i, rot_o = pre.du_i, pre.du_o, pre.rot_i, pre.rot_o
    cond_i = comp_i.shape[0] > 0
    cond_o = comp_o.shape[0] > 0
    nz = psi_i.shape[0]
    load_i = np.empty(nz)
    load_o = np.empty(nz)
    nrm_i = np.empty((nz, 3))
    nrm_o = np.empty((nz, 3))
    dq_i = np.empty(nz)
    dq_o = np.empty(nz)
    cd_i = np.empty(nz)
    cd_o = np.empty(nz)
    len_i = np.empty(nz)
    len_o = np.empty(nz)
    film_i = _films(ws_i, nz)  # the last call's films (the film iteration's warm start), overwritten
    film_o = _films(ws_o, nz)
    nci = 3 * nz if (cond_i and jacobian) else 0
    nco = 3 * nz if (cond_o and jacobian) else 0
    wg_i = np.empty((nci, comp_i.shape[2]))  # condensed rings' global compliance factors (Jacobian only)
    wg_o = np.empty((nco, comp_o.shape[2]))
    off_i, off_o = geometry.inner_offset, geometry.outer_offset
    _ring_contacts(
        cond_i,
        psi_i,
        rot_i,
        comp_i,
        zs_i,
        e0_i,
        w0_i,
        off_i,
        speed,
        law_i,
        ws_i,
        load_i,
        nrm_i,
        dq_i,
        cd_i,
        len_i,
        film_i,
        du_i,
        wg_i,
        state,
    )
    if cond_i:
        for j in range(nz):
            for c in range(3):
                arm[j, c] += du_i[j, c]
    _ring_contacts(
        cond_o,
        psi_o,
        rot_o,
        comp_o,
        zs_o,
        e0_o,
        w0_o,
        off_o,
        speed,
        law_o,
        ws_o,
        load_o,
        nrm_o,
        dq_o,
        cd_o,
        len_o,
        film_o,
        du_o,
        wg_o,
        state,
    )
    return RowContacts(load_i, load_o, nrm_i, nrm_o, dq_i, dq_o, cd_i, cd_o, len_i, len_o, film_i, film_o, wg_i, wg_o)


@njit(cache=True, inline="always")
def _row_forces(q, qt, geometry, tab_i, zs_i, tab_o, zs_o, a, g, pre, con, f, rec):
    """Every ball's contact reactions on the frame and the rings' modes, its cage and pocket
    forces, into ``f`` (and ``rec`` when it has a row per ball); returns (Z, 3): each ball's
    cage direction (etx, ety) and radius in the housing (for the Jacobian blocks)."""
    bpos, psi_i, psi_o, cs_o, arm, du_i, du_o = pre.bpos, pre.psi_i, pre.psi_o, pre.cs_o, pre.arm, pre.du_i, pre.du_o
    load_i, load_o, nrm_i, nrm_o, film_i, film_o = con.load_i, con.load_o, con.nrm_i, con.nrm_o, con.film_i, con.film_o
    z_row, rb, cage_ratio = geometry.z, geometry.ball_radius_pitch, geometry.cage_ratio
    cage_k, cage_c, pocket_k = geometry.cage_stiffness, geometry.cage_damping, geometry.pocket_stiffness
    m_i = tab_i.shape[2]
    m_o = tab_o.shape[2]
    nz = bpos.shape[0]
    two_pi = 2.0 * math.pi
    bas_i = np.empty((3, m_i))
    bas_o = np.empty((3, m_o))
    record = rec.shape[0] == nz
    ebr = np.empty((nz, 3))
    for j in range(nz):
        bj = 6 + m_i + m_o + 3 * j
        bx, by, bz = bpos[j, 0], bpos[j, 1], bpos[j, 2]
        vx, vy = qt[bj], qt[bj + 1]
        qi, qo = load_i[j], load_o[j]
        fix, fiy, fiz = -qi * nrm_i[j, 0], -qi * nrm_i[j, 1], -qi * nrm_i[j, 2]
        fox, foy, foz = -qo * nrm_o[j, 0], -qo * nrm_o[j, 1], -qo * nrm_o[j, 2]
        # reaction on the frame: -f at c_i; moment -(Ap x f) mapped by G^T; modes -basis^T A^T f
        f[0] -= fix
        f[1] -= fiy
        f[2] -= fiz
        ap0, ap1, ap2 = arm[j, 0], arm[j, 1], arm[j, 2]
        mx = ap1 * fiz - ap2 * fiy
        my = ap2 * fix - ap0 * fiz
        mz = ap0 * fiy - ap1 * fix
        for r in range(3):
            f[3 + r] -= g[0, r] * mx + g[1, r] * my + g[2, r] * mz
        flx = a[0, 0] * fix + a[1, 0] * fiy + a[2, 0] * fiz
        fly = a[0, 1] * fix + a[1, 1] * fiy + a[2, 1] * fiz
        flz = a[0, 2] * fix + a[1, 2] * fiy + a[2, 2] * fiz
        if m_i > 0:
            _basis(tab_i, zs_i, psi_i[j], bas_i)
            for k in range(m_i):
                f[6 + k] -= bas_i[0, k] * flx + bas_i[1, k] * fly + bas_i[2, k] * flz
        if m_o > 0:
            _basis(tab_o, zs_o, psi_o[j], bas_o)
            for k in range(m_o):
                f[6 + m_i + k] -= bas_o[0, k] * fox + bas_o[1, k] * foy + bas_o[2, k] * foz
        # ---- cage (tangential spring-damper to the kinematic pocket) + pocket spring
        psi = psi_o[j]
        cos_p, sin_p = cs_o[j, 0], cs_o[j, 1]
        pocket = two_pi * j / nz + cage_ratio * q[5]
        dev = psi - pocket
        dev -= two_pi * math.floor(dev / two_pi + 0.5)  # wrapped to [-pi, pi)
        radius = math.sqrt(bx * bx + by * by)
        etx, ety = -sin_p, cos_p
        s_t = vx * etx + vy * ety - radius * cage_ratio * qt[5]
        fc = -(cage_k * radius * dev + cage_c * s_t)
        pr = radius - rb
        f[bj] = fix + fox + fc * etx - pocket_k * pr * cos_p
        f[bj + 1] = fiy + foy + fc * ety - pocket_k * pr * sin_p
        f[bj + 2] = fiz + foz - pocket_k * (bz - z_row)
        if record:
            rec[j, 0], rec[j, 1] = qi, qo
            for c in range(3):
                rec[j, 2 + c] = nrm_i[j, c]
                rec[j, 5 + c] = nrm_o[j, c]
                rec[j, 16 + c] = du_i[j, c]
                rec[j, 19 + c] = du_o[j, c]
                rec[j, 22 + c] = bpos[j, c]
            rec[j, 8], rec[j, 9] = psi_i[j], psi_o[j]
            rec[j, 25], rec[j, 26] = film_i[j], film_o[j]
            rec[j, 10], rec[j, 11], rec[j, 12] = -flx, -fly, -flz
            rec[j, 13], rec[j, 14], rec[j, 15] = -fox, -foy, -foz
        ebr[j, 0], ebr[j, 1], ebr[j, 2] = etx, ety, radius
    return ebr


@njit(cache=True, inline="always")
def _row_local_blocks(b0, qt, geometry, pre, con, ebr, jq):
    """Every ball's rows of the local ball solve (``jacobian`` BALL_BLOCKS): its own 3x3 block
    and, in column 3, the rate of its force from the frame's and rings' motion; ``ebr``:
    :func:`_row_forces`' cage directions and radii."""
    w0_i, w0_o = pre.w0_i, pre.w0_o
    load_i, load_o, nrm_i, nrm_o, dq_i, dq_o = con.load_i, con.load_o, con.nrm_i, con.nrm_o, con.dq_i, con.dq_o
    cd_i, cd_o, len_i, len_o = con.cd_i, con.cd_o, con.len_i, con.len_o
    cage_ratio, cage_k, pocket_k = geometry.cage_ratio, geometry.cage_stiffness, geometry.pocket_stiffness
    k_i = np.empty((3, 3))
    d_i = np.empty((3, 3))
    k_o = np.empty((3, 3))
    d_o = np.empty((3, 3))
    for j in range(load_i.shape[0]):
        etx, ety, radius = ebr[j, 0], ebr[j, 1], ebr[j, 2]
        bj = b0 + 3 * j
        vx, vy, vz = qt[bj], qt[bj + 1], qt[bj + 2]
        _contact_blocks(
            load_i[j], dq_i[j], cd_i[j], len_i[j], nrm_i[j, 0], nrm_i[j, 1], nrm_i[j, 2], etx, ety, k_i, d_i
        )
        _contact_blocks(
            load_o[j], dq_o[j], cd_o[j], len_o[j], nrm_o[j, 0], nrm_o[j, 1], nrm_o[j, 2], etx, ety, k_o, d_o
        )
        et = (etx, ety, 0.0)
        # groove centres' velocities (ball velocity minus the contacts' relative velocities)
        gi = (vx - w0_i[j, 0], vy - w0_i[j, 1], vz - w0_i[j, 2])
        go = (vx - w0_o[j, 0], vy - w0_o[j, 1], vz - w0_o[j, 2])
        for c1 in range(3):
            rate = cage_k * radius * cage_ratio * et[c1] * qt[5]
            for c2 in range(3):
                ee = et[c1] * et[c2]
                eye = 1.0 if c1 == c2 else 0.0
                jq[3 * j + c1, c2] = k_i[c1, c2] + k_o[c1, c2] - cage_k * ee - pocket_k * (eye - ee)
                rate -= k_i[c1, c2] * gi[c2] + k_o[c1, c2] * go[c2]
            jq[3 * j + c1, 3] = rate


@njit(cache=True, inline="always")
def _row_ball_jacobians(jacobian, geometry, law_i, law_o, m_i, m_o, speed, dudw, a, g, pre, con, wk, ebr, jq, jv):
    """Every ball's Jacobian blocks: its (b0 + 3)^2 square [x (0..b0-1), the ball
    (b0..b0+2)] into the work blocks jl, vl (the helpers at ball index b0), then scattered
    into jq, jv -- or, for quasi-static balls, condensed into them (CONDENSED_BALLS; between rigid
    rings each ball's share in closed form, :func:`_condense_rigid_ball`); the
    condensed rings' contacts keep their T rows and contact factors for
    :func:`_condensed_row_jacobian`. ``wk``: :func:`_row_pass2`'s work arrays; ``ebr``:
    :func:`_row_forces`' cage directions and radii."""
    arm, bas_i_all, bas_o_all = pre.arm, pre.bas_i, pre.bas_o
    load_i, load_o, nrm_i, nrm_o, dq_i, dq_o = con.load_i, con.load_o, con.nrm_i, con.nrm_o, con.dq_i, con.dq_o
    cd_i, cd_o, len_i, len_o, film_i, film_o = con.cd_i, con.cd_o, con.len_i, con.len_o, con.film_i, con.film_o
    k_i, d_i, k_o, d_o, t_i, jl, vl, inv3, tm3, s_balls, ti_all, vf_i, vf_o, bas_o = wk
    cage_ratio, cage_k, cage_c = geometry.cage_ratio, geometry.cage_stiffness, geometry.cage_damping
    pocket_k = geometry.pocket_stiffness
    cond_i = ti_all.shape[0] > 0
    cond_o = vf_o.shape[0] > 0
    b0 = 6 + m_i + m_o
    nx_i = 6 + m_i
    # quasi-static balls between rigid rings: each ball's condensed share in closed form (6 x 3 blocks)
    rigid = jacobian == CONDENSED_BALLS and m_i == 0 and m_o == 0 and not cond_i and not cond_o
    for j in range(load_i.shape[0]):
        etx, ety, radius = ebr[j, 0], ebr[j, 1], ebr[j, 2]
        bj = b0 + 3 * j
        qi, qo = load_i[j], load_o[j]
        if not cond_i:  # (condensed rings: the blocks' factors below)
            _contact_blocks(qi, dq_i[j], cd_i[j], len_i[j], nrm_i[j, 0], nrm_i[j, 1], nrm_i[j, 2], etx, ety, k_i, d_i)
        if not cond_o:
            _contact_blocks(qo, dq_o[j], cd_o[j], len_o[j], nrm_o[j, 0], nrm_o[j, 1], nrm_o[j, 2], etx, ety, k_o, d_o)
        et = (etx, ety, 0.0)
        ap0, ap1, ap2 = arm[j, 0], arm[j, 1], arm[j, 2]
        if rigid:
            for c in range(3):  # -(skew(Ap) G)[:, c]
                g0, g1, g2 = g[0, c], g[1, c], g[2, c]
                t_i[0, 3 + c] = -(-ap2 * g1 + ap1 * g2)
                t_i[1, 3 + c] = -(ap2 * g0 - ap0 * g2)
                t_i[2, 3 + c] = -(-ap1 * g0 + ap0 * g1)
            gain_i = _film_speed_gain(law_i, speed, film_i[j]) * dudw
            gain_o = _film_speed_gain(law_o, speed, film_o[j]) * dudw
            _condense_rigid_ball(
                k_i,
                d_i,
                k_o,
                d_o,
                t_i,
                etx,
                ety,
                radius * cage_ratio,
                geometry,
                gain_i,
                gain_o,
                nrm_i[j],
                nrm_o[j],
                jq,
                jv,
                s_balls[3 * j : 3 * j + 3],
                inv3,
                tm3,
            )
            continue
        jl[:, :] = 0.0
        vl[:, :] = 0.0
        for c1 in range(3):
            for c2 in range(3):
                ee = et[c1] * et[c2]
                eye = 1.0 if c1 == c2 else 0.0
                jl[b0 + c1, b0 + c2] += -cage_k * ee - pocket_k * (eye - ee)
                vl[b0 + c1, b0 + c2] += -cage_c * ee
            jl[b0 + c1, 5] += cage_k * radius * cage_ratio * et[c1]
            vl[b0 + c1, 5] += cage_c * radius * cage_ratio * et[c1]
        # T_i = [I | -[Ap]x G | A basis_i]
        for c in range(3):  # -(skew(Ap) G)[:, c]
            g0, g1, g2 = g[0, c], g[1, c], g[2, c]
            t_i[0, 3 + c] = -(-ap2 * g1 + ap1 * g2)
            t_i[1, 3 + c] = -(ap2 * g0 - ap0 * g2)
            t_i[2, 3 + c] = -(-ap1 * g0 + ap0 * g1)
        if m_i > 0:
            for r in range(3):
                for k in range(m_i):
                    t_i[r, 6 + k] = (
                        a[r, 0] * bas_i_all[j, 0, k] + a[r, 1] * bas_i_all[j, 1, k] + a[r, 2] * bas_i_all[j, 2, k]
                    )
        if cond_i:
            for r in range(3):
                for c in range(nx_i):
                    ti_all[3 * j + r, c] = t_i[r, c]
            _contact_factors(qi, dq_i[j], len_i[j], nrm_i[j, 0], nrm_i[j, 1], nrm_i[j, 2], etx, ety, vf_i[j])
        else:
            _add_block_jacobian(jl, k_i, t_i, b0, 0, nx_i)
            _add_block_jacobian(vl, d_i, t_i, b0, 0, nx_i)
            gain = _film_speed_gain(law_i, speed, film_i[j]) * dudw
            if gain != 0.0:
                _add_speed_column(
                    vl, k_i, t_i, b0, 0, nx_i, 5, gain * nrm_i[j, 0], gain * nrm_i[j, 1], gain * nrm_i[j, 2]
                )
        if cond_o:
            _contact_factors(qo, dq_o[j], len_o[j], nrm_o[j, 0], nrm_o[j, 1], nrm_o[j, 2], etx, ety, vf_o[j])
        else:
            bo = bas_o_all[j] if m_o > 0 else bas_o
            _add_block_jacobian(jl, k_o, bo, b0, 6 + m_i, m_o)
            _add_block_jacobian(vl, d_o, bo, b0, 6 + m_i, m_o)
            gain = _film_speed_gain(law_o, speed, film_o[j]) * dudw
            if gain != 0.0:
                _add_speed_column(
                    vl, k_o, bo, b0, 6 + m_i, m_o, 5, gain * nrm_o[j, 0], gain * nrm_o[j, 1], gain * nrm_o[j, 2]
                )
        if jacobian == CONDENSED_BALLS:
            _condense_ball(jl, vl, b0, jq, jv, s_balls[3 * j : 3 * j + 3], inv3, tm3)
        else:
            for r in range(b0 + 3):
                rr = r if r < b0 else bj + r - b0
                for c in range(b0 + 3):
                    cc = c if c < b0 else bj + c - b0
                    jq[rr, cc] += jl[r, c]
                    jv[rr, cc] += vl[r, c]


@njit(cache=True, inline="always")
def _row_pass2(
    q, qt, geometry, tab_i, zs_i, tab_o, zs_o, law_i, law_o, balls, jacobian, speed, a, g, pre, con, rec, f, jq, jv
):
    """Pass 2 of :func:`row_eval`: every ball's generalized forces (:func:`_row_forces`)
    and Jacobian blocks (:func:`_row_local_blocks`, :func:`_row_ball_jacobians`). Returns the
    condensed rings' T rows and contact factors of every ball and the entrainment speed's
    rate d u / d q_t[5] (for :func:`_condensed_row_jacobian`)."""
    cond_i = pre.rot_i.shape[0] > 0
    cond_o = pre.rot_o.shape[0] > 0
    m_i = tab_i.shape[2]
    m_o = tab_o.shape[2]
    nz = pre.bpos.shape[0]
    b0 = 6 + m_i + m_o
    nx_i = 6 + m_i
    bas_o = np.empty((3, m_o))
    k_i = np.empty((3, 3))
    d_i = np.empty((3, 3))
    k_o = np.empty((3, 3))
    d_o = np.empty((3, 3))
    t_i = np.zeros((3, nx_i))
    nl = b0 + 3 if (jacobian and jacobian != BALL_BLOCKS) else 0
    jl = np.empty((nl, nl))  # one ball's Jacobian blocks (see _row_ball_jacobians)
    vl = np.empty((nl, nl))
    inv3 = np.empty((3, 3))  # (work of _condense_ball)
    tm3 = np.empty((3, b0))
    s_balls = (
        balls[2 * 3 * nz : 2 * 3 * nz + 3 * nz * b0].reshape((3 * nz, b0))
        if jacobian == CONDENSED_BALLS
        else np.empty((0, b0))
    )
    for r in range(3):
        t_i[r, r] = 1.0
    nci = 3 * nz if (cond_i and jacobian) else 0
    nco = 3 * nz if (cond_o and jacobian) else 0
    ti_all = np.empty((nci, nx_i))  # condensed rings: T and the contact stiffness factors of every ball
    vf_i = np.empty((nci // 3, 2, 3))
    vf_o = np.empty((nco // 3, 2, 3))
    wk = (k_i, d_i, k_o, d_o, t_i, jl, vl, inv3, tm3, s_balls, ti_all, vf_i, vf_o, bas_o)
    # entrainment speed u = speed_factor |omega_z|: the films' speed dependence enters
    # d f / d q_t[5] as if each ball moved by n dh/du du/dq_t[5] (dQ/du = dQ/ddelta dh/du)
    dudw = geometry.speed_factor * (1.0 if qt[5] > 0.0 else -1.0)
    ebr = _row_forces(q, qt, geometry, tab_i, zs_i, tab_o, zs_o, a, g, pre, con, f, rec)
    if jacobian == BALL_BLOCKS:  # the local ball solve: see BALL_BLOCKS
        _row_local_blocks(b0, qt, geometry, pre, con, ebr, jq)
    elif jacobian:
        _row_ball_jacobians(jacobian, geometry, law_i, law_o, m_i, m_o, speed, dudw, a, g, pre, con, wk, ebr, jq, jv)
    return ti_all, vf_i, vf_o, dudw


@njit(cache=True, inline="always")
def _condensed_row_jacobian(law_i, law_o, speed, b0, nx_i, con, p2, jq, jv):
    """The dense Jacobian blocks of the condensed rings' contacts (:func:`row_eval`):
    the contacts in series with the ring, (I - K C)^-1 K and D, through the inner ring's
    T rows onto the frame and, for both rings, onto the balls; ``p2``: :func:`_row_pass2`'s
    result."""
    nrm_i, nrm_o, cd_i, cd_o, film_i, film_o = con.nrm_i, con.nrm_o, con.cd_i, con.cd_o, con.film_i, con.film_o
    wg_i, wg_o = con.wg_i, con.wg_o
    ti_all, vf_i, vf_o, dudw = p2
    nz = nrm_i.shape[0]
    ball = slice(b0, b0 + 3 * nz)
    if ti_all.shape[0] > 0:  # the dense condensed contacts of the inner ring (frame coordinates only: m_i = 0)
        kim = _condensed_contact_matrix(vf_i, nrm_i, cd_i, wg_i)
        for jac, km in ((jq, kim[0]), (jv, kim[1])):
            jac[ball, ball] += km
            kt = km @ ti_all
            jac[ball, 0:nx_i] -= kt
            tk = ti_all.T @ km
            jac[0:nx_i, ball] -= tk
            jac[0:nx_i, 0:nx_i] += tk @ ti_all
        kd = kim[0] @ _film_displacements(law_i, speed, film_i, nrm_i, dudw)
        jv[ball, 5] += kd
        jv[0:nx_i, 5] -= ti_all.T @ kd
    if vf_o.shape[0] > 0:  # outer ring in the housing: ball-ball only (m_o = 0)
        kom = _condensed_contact_matrix(vf_o, nrm_o, cd_o, wg_o)
        jq[ball, ball] += kom[0]
        jv[ball, ball] += kom[1]
        jv[ball, 5] += kom[0] @ _film_displacements(law_o, speed, film_o, nrm_o, dudw)


@njit(cache=True)
def row_eval(q, qt, p, jacobian, rec, f, jq, jv):
    """Generalized force of a row element into ``f`` (n,) and, with ``jacobian``, its
    derivatives d f / d q and d f / d q_t into ``jq``, ``jv`` (n, n) (overwritten; for
    rigid and modal rings only the entries it writes, :func:`_zero_written`: the
    other entries must be zero, as in a zero-allocated work array);
    coordinates ordered [frame(6), inner modes, outer modes, balls(3Z)].

    ``p``: the row's :data:`RowPack`: the modal rings' raceway tables ``tab_i`` / ``tab_o``
    (their m coordinates are element coordinates), the condensed rings' compliance
    factors ``comp_i`` / ``comp_o``, the rings' work arrays ``ws_i`` / ``ws_o`` (contact
    deflections and last tangent of a condensed ring; every ring: the contacts' films,
    the film iteration's warm start; updated), the quasi-static balls' work array
    ``balls`` (used by :func:`quasi_static_balls` only) and ``state`` (int64, 8):
    [non-converged condensations, 1 if the last call had one, sum of the local
    iterations, local solves, then the same four of the quasi-static balls' solve];
    rec: (Z, N_RECORD) per-ball record, or (0, N_RECORD).

    ``jacobian``: False (force only), True (the Jacobians), BALL_BLOCKS or
    CONDENSED_BALLS (the quasi-static balls' modes, see there).

    Jacobian blocks: d f_ball/d b = K, d f_ball/d x = -K T, d g_x/d b = -T^T K,
    d g_x/d x = T^T K T with T_j = d c_j / d x (x: frame and modal coordinates)
    and K the contact stiffness — block diagonal for rigid and modal rings
    (added ball by ball, :func:`_add_block_jacobian`), the dense condensed
    (I - K C)^-1 K for condensed rings (:func:`_condensed_contact_matrix`; geometric-stiffness
    terms of the frame rotation are dropped; the modified Newton iteration
    converges on the residual, which is exact). The azimuths' cosines and sines
    are the normalised in-plane coordinates (no sin/cos of the atan2).

    Phases (each its own compiled function): :func:`_row_front` -- the frame's kinematics
    (:func:`_frame_kinematics`), pass 1 with the rings undeflected
    (:func:`_row_geometry`), the contacts and the condensed rings' local solves
    (:func:`_row_contacts`) -- then :func:`_row_back` -- pass 2 with the forces and the
    Jacobian blocks of every ball (:func:`_row_pass2`), the condensed rings' dense blocks
    (:func:`_condensed_row_jacobian`)."""
    mode = _mode(jacobian)
    _row_back(q, qt, p, mode, rec, f, jq, jv, _row_front(q, qt, p, mode))


@njit(cache=True)
def _row_pass1(q, qt, p, jacobian):
    """The frame's kinematics and pass 1 of a row (:func:`_frame_kinematics`, :func:`_row_geometry`
    with the rings undeflected) from its pack ``p``: (A, G, :data:`RowPass1`)."""
    a, g, om0, om1, om2 = _frame_kinematics(q, qt)
    cond_i = p.comp_i.shape[0] > 0
    cond_o = p.comp_o.shape[0] > 0
    pre = _row_geometry(
        q,
        qt,
        p.ball_ref,
        p.geometry,
        p.tab_i,
        p.zsign[0],
        p.tab_o,
        p.zsign[1],
        cond_i,
        cond_o,
        jacobian,
        a,
        (om0, om1, om2),
    )
    return a, g, pre


@njit(cache=True)
def _row_front(q, qt, p, jacobian):
    """The first phases of :func:`row_eval` (the frame's kinematics, pass 1 and the contacts
    with the condensed rings' local solves): (A, G, entrainment speed, :data:`RowPass1`,
    :data:`RowContacts`), for :func:`_row_back`."""
    geometry = p.geometry
    p.state[1] = 0
    a, g, pre = _row_pass1(q, qt, p, _mode(jacobian))
    speed = geometry.speed_factor * abs(qt[5])
    con = _row_contacts(
        geometry,
        p.zsign[0],
        p.zsign[1],
        p.law_i,
        p.law_o,
        p.comp_i,
        p.comp_o,
        p.ws_i,
        p.ws_o,
        jacobian,
        speed,
        pre,
        p.state,
    )
    return a, g, speed, pre, con


@njit(cache=True)
def _row_back(q, qt, p, jacobian, rec, f, jq, jv, front):
    """The last phases of :func:`row_eval` from :func:`_row_front`'s results ``front`` (computed
    with a ``jacobian`` mode that allocates the same arrays: any true mode): the outputs
    cleared, pass 2 with the forces and the Jacobian blocks, the condensed rings' dense blocks.
    It writes only f, jq, jv, rec and the quasi-static balls' sensitivities, so one front
    serves several modes at the same state (:func:`_ball_solve`)."""
    a, g, speed, pre, con = front
    geometry, balls = p.geometry, p.balls
    tab_i, tab_o, zs_i, zs_o = p.tab_i, p.tab_o, p.zsign[0], p.zsign[1]
    m_i = tab_i.shape[2]
    m_o = tab_o.shape[2]
    cond_i = p.comp_i.shape[0] > 0
    cond_o = p.comp_o.shape[0] > 0
    nz = p.ball_ref.shape[0]
    b0 = 6 + m_i + m_o
    f[:] = 0.0
    if jacobian == BALL_BLOCKS or jacobian == CONDENSED_BALLS:
        jq[:, :] = 0.0
        if jacobian == CONDENSED_BALLS:
            jv[:, :] = 0.0
    elif jacobian:
        if cond_i or cond_o:
            jq[:, :] = 0.0
            jv[:, :] = 0.0
        else:  # block-sparse: only the x rows and columns and the balls' own 3x3 blocks are written
            _zero_written(jq, b0, nz)
            _zero_written(jv, b0, nz)
    p2 = _row_pass2(
        q,
        qt,
        geometry,
        tab_i,
        zs_i,
        tab_o,
        zs_o,
        p.law_i,
        p.law_o,
        balls,
        jacobian,
        speed,
        a,
        g,
        pre,
        con,
        rec,
        f,
        jq,
        jv,
    )
    if jacobian and (cond_i or cond_o):
        _condensed_row_jacobian(p.law_i, p.law_o, speed, b0, 6 + m_i, con, p2, jq, jv)


@njit(cache=True)
def _film_displacements(law, speed, films, normals, dudw):
    """(3Z,) ball displacements n_j dh_j/du du/dq_t[5] equivalent to the films'
    speed dependence (see :func:`row_eval`)."""
    nz = films.shape[0]
    out = np.zeros(3 * nz)
    for j in range(nz):
        gain = _film_speed_gain(law, speed, films[j]) * dudw
        for c in range(3):
            out[3 * j + c] = gain * normals[j, c]
    return out


@njit(cache=True)
def _condensed_contact_matrix(factors, normals, cd, wg):
    """(3Z, 3Z) contact stiffness and damping of a condensed ring's contacts in
    series with the ring: (I - K C)^-1 K and (I - K C)^-1 D, with the compliance
    C = W W^T (``wg``: the stacked global factors W, (3Z, m)), the contact blocks
    K_j = -V_j V_j^T of :func:`_contact_factors` (``factors`` (Z, 2, 3): the rows of
    V_j^T) and the damping blocks D_j = -c_j n_j n_j^T.

    By the push-through identity (I + V V^T C)^-1 V = V S^-1 with the SPD 2Z x 2Z
    matrix S = I + P P^T, P = V^T W: (I - K C)^-1 K = -V S^-1 V^T, and by Woodbury
    (I - K C)^-1 N = N - V S^-1 P (W^T N), so one 2Z x 2Z inverse and BLAS products
    of 2Z x m and m x Z replace the 3Z x 3Z Gram matrix W W^T and the inverse of
    I - K C (rv40e's rings, Z = 38, m = 165-181: 360 -> 190 us per ring
    and Jacobian, benchmarks/bench_flexible_model.py). Exact for the rank-2 blocks;
    tests/test_model_flexible_rings.py checks it against the direct solution."""
    nz = normals.shape[0]
    n3 = 3 * nz
    n2 = 2 * nz
    m = wg.shape[1]
    p = np.empty((n2, m))  # P = V^T W (V block sparse: three entries per column)
    g = np.empty((m, nz))  # W^T N
    for j in range(nz):
        for k in range(m):
            w0, w1, w2 = wg[3 * j, k], wg[3 * j + 1, k], wg[3 * j + 2, k]
            p[2 * j, k] = factors[j, 0, 0] * w0 + factors[j, 0, 1] * w1 + factors[j, 0, 2] * w2
            p[2 * j + 1, k] = factors[j, 1, 0] * w0 + factors[j, 1, 1] * w1 + factors[j, 1, 2] * w2
            g[k, j] = normals[j, 0] * w0 + normals[j, 1] * w1 + normals[j, 2] * w2
    s = p @ p.T
    for i in range(n2):
        s[i, i] += 1.0
    sinv = np.linalg.inv(s)
    r = sinv @ (p @ g)  # S^-1 P W^T N (2Z, Z)
    kq = np.empty((n3, n3))
    kv = np.empty((n3, n3))
    for j in range(nz):
        for lb in range(nz):
            s00, s01 = sinv[2 * j, 2 * lb], sinv[2 * j, 2 * lb + 1]
            s10, s11 = sinv[2 * j + 1, 2 * lb], sinv[2 * j + 1, 2 * lb + 1]
            for b in range(3):
                x0 = s00 * factors[lb, 0, b] + s01 * factors[lb, 1, b]  # (S^-1 V^T)[2j, 3l+b]
                x1 = s10 * factors[lb, 0, b] + s11 * factors[lb, 1, b]
                for a in range(3):
                    kq[3 * j + a, 3 * lb + b] = -(factors[j, 0, a] * x0 + factors[j, 1, a] * x1)
            for a in range(3):
                y = -(factors[j, 0, a] * r[2 * j, lb] + factors[j, 1, a] * r[2 * j + 1, lb])
                if j == lb:
                    y += normals[j, a]
                y *= -cd[lb]
                for b in range(3):
                    kv[3 * j + a, 3 * lb + b] = y * normals[lb, b]
    return kq, kv


@njit(cache=True)
def row_force_kernel(q, qt, p):
    """Generalized force of a row element (see :func:`row_kernel`)."""
    return row_kernel(q, qt, p, _flag(False), np.empty((0, N_RECORD)))[0]


@njit(cache=True)
def ball_equilibrium(q, qt, p, tol, max_iter, f, kbb, rec):
    """Quasi-static balls of a row (rigid or modal rings): the ball coordinates
    q[b0:] (displacements from ball_ref; in: the warm start, out: the solution) such
    that every ball's force of :func:`row_eval` (contacts, cage and pocket springs)
    vanishes, at the frame and modal coordinates and velocities in q, qt. The balls'
    velocities qt[b0:] (out) are those of the static equilibrium, b_t = S x_t with
    S = -K_bb^-1 K_bx (the contacts' damping and the cage's see the ball move with
    the stiffer side), from the blocks of each evaluation. Newton per ball on its own
    3x3 block (row_eval's BALL_BLOCKS mode into ``kbb`` (3Z, 4)); stops when the
    largest ball force is below ``tol`` times the largest contact load of the row
    (at least :data:`BALL_LOAD_SCALE`; relative, BALL_FORCE_TOL; an absolute 1e-9 N stalls at
    ~3e-9 N, the round-off of 111 N loads on rv221). ``f`` (n,): the row's forces
    and ``rec`` (Z, N_RECORD, or (0, N_RECORD): none) its per-ball records at the
    last evaluation (at the returned balls and velocities). Returns the number of
    Newton steps (-1: not converged in ``max_iter``). :func:`_ball_solve` with no Jacobian."""
    empty = np.empty((0, 0))
    return _ball_solve(q, qt, p, tol, max_iter, f, kbb, rec, empty, empty)


@njit(cache=True)
def _ball_solve(q, qt, p, tol, max_iter, f, kbb, rec, kx, cx):
    """:func:`ball_equilibrium`, and with kx, cx of shape (nx, nx) (else (0, 0)) the condensed
    Jacobians of the returned balls (:func:`row_eval`'s CONDENSED_BALLS mode) from the last
    evaluation's geometry and contacts (:func:`_row_back` on the same :func:`_row_front`):
    the contacts are evaluated once at the solution, not again for the Jacobian."""
    nz = p.ball_ref.shape[0]
    b0 = q.shape[0] - 3 * nz
    recs = rec if rec.shape[0] == nz else np.empty((nz, N_RECORD))
    jv = np.empty((0, 0))
    damping = max(p.law_i.c_max, p.law_o.c_max, p.geometry.cage_damping, 1e-300)
    step = np.empty((nz, 6))  # per ball: the Newton correction and the new velocity
    adj = np.empty((3, 3))
    for it in range(max_iter + 1):
        front = _row_front(q, qt, p, _mode(BALL_BLOCKS))
        _row_back(q, qt, p, _mode(BALL_BLOCKS), recs, f, kbb, jv, front)
        scale = BALL_LOAD_SCALE
        for j in range(nz):
            scale = max(scale, recs[j, 0], recs[j, 1])
        atol = tol * scale
        # a change of the balls' velocities below vtol changes their damping forces by less than atol
        vtol = atol / damping
        err = 0.0
        for e in range(b0, q.shape[0]):
            err = max(err, abs(f[e]))
        dv = 0.0
        for j in range(nz):  # -K^-1 f_j and b_t = -K^-1 (K_bx x_t) (3x3, cofactors)
            k = kbb[3 * j : 3 * j + 3]
            det = adjugate3(k, adj)
            for off in (0, 3):  # right-hand sides: the ball's force, then K_bx x_t
                r0, r1, r2 = (
                    (f[b0 + 3 * j], f[b0 + 3 * j + 1], f[b0 + 3 * j + 2]) if off == 0 else (k[0, 3], k[1, 3], k[2, 3])
                )
                step[j, off] = -(adj[0, 0] * r0 + adj[0, 1] * r1 + adj[0, 2] * r2) / det
                step[j, off + 1] = -(adj[1, 0] * r0 + adj[1, 1] * r1 + adj[1, 2] * r2) / det
                step[j, off + 2] = -(adj[2, 0] * r0 + adj[2, 1] * r1 + adj[2, 2] * r2) / det
            for c in range(3):
                dv = max(dv, abs(step[j, 3 + c] - qt[b0 + 3 * j + c]))
        done = err <= atol and dv <= vtol
        if (done or it == max_iter) and kx.shape[0] > 0:
            _row_back(q, qt, p, _mode(CONDENSED_BALLS), np.empty((0, N_RECORD)), f, kx, cx, front)
        if done:
            return it
        if it == max_iter:
            break
        for j in range(nz):
            for c in range(3):
                q[b0 + 3 * j + c] += step[j, c]
                qt[b0 + 3 * j + c] = step[j, 3 + c]
    return -1


@njit(cache=True, inline="always")
def _condense_rigid_ball(
    k_i, d_i, k_o, d_o, t, etx, ety, cage_arm, geometry, gain_i, gain_o, n_i, n_o, kx, cx, s_ball, inv, tm
):
    """:func:`_condense_ball` of one quasi-static ball between rigid rings, from its blocks
    without the (9 x 9) square: with the inner contact's K_i, D_i and T (3 x 6) the frame's
    blocks are J_xx = A T, J_xb = -A, V_xx = B T - (A d_i) e_5^T, V_xb = -B (A = T^T K_i,
    B = T^T D_i, d_i the inner film-speed displacement gain_i n_i); the ball's J_bb = K_i + K_o
    + K_cage, J_bx = -K_i T + k_c r c e_5^T, V_bb = D_i + D_o - c_c e_t e_t^T, V_bx = -D_i T +
    (c_c r c + K_i d_i + K_o d_o) e_5^T (r c = ``cage_arm``: the ball's radius times the cage
    ratio). Then kx += A (T - S) and cx += B (T - S) - (A d_i) e_5^T + A J_bb^-1 (V_bx + V_bb S)
    with S = -J_bb^-1 J_bx (into ``s_ball``): :func:`_condense_ball`'s sums, the same products
    of the same blocks regrouped (tests/test_model_flexible_bearing.py compares the two)."""
    cage_k, cage_c, pocket_k = geometry.cage_stiffness, geometry.cage_damping, geometry.pocket_stiffness
    et = (etx, ety, 0.0)
    jbb = np.empty((3, 3))
    vbb = np.empty((3, 3))
    for r in range(3):
        for c in range(3):
            ee = et[r] * et[c]
            eye = 1.0 if r == c else 0.0
            jbb[r, c] = k_i[r, c] + k_o[r, c] - cage_k * ee - pocket_k * (eye - ee)
            vbb[r, c] = d_i[r, c] + d_o[r, c] - cage_c * ee
    det = adjugate3(jbb, inv)
    for r in range(3):
        for c in range(3):
            inv[r, c] /= det
    c5k = np.empty(3)  # the ball's column 5 of J_bx and V_bx
    c5v = np.empty(3)
    for r in range(3):
        kd_i = gain_i * (k_i[r, 0] * n_i[0] + k_i[r, 1] * n_i[1] + k_i[r, 2] * n_i[2])
        kd_o = gain_o * (k_o[r, 0] * n_o[0] + k_o[r, 1] * n_o[1] + k_o[r, 2] * n_o[2])
        c5k[r] = cage_k * cage_arm * et[r]
        c5v[r] = cage_c * cage_arm * et[r] + kd_i + kd_o
    jbx = np.empty((3, 6))
    vbx = np.empty((3, 6))
    for r in range(3):
        for c in range(6):
            jbx[r, c] = -(k_i[r, 0] * t[0, c] + k_i[r, 1] * t[1, c] + k_i[r, 2] * t[2, c])
            vbx[r, c] = -(d_i[r, 0] * t[0, c] + d_i[r, 1] * t[1, c] + d_i[r, 2] * t[2, c])
        jbx[r, 5] += c5k[r]
        vbx[r, 5] += c5v[r]
    for r in range(3):  # S = -J_bb^-1 J_bx
        for c in range(6):
            s_ball[r, c] = -(inv[r, 0] * jbx[0, c] + inv[r, 1] * jbx[1, c] + inv[r, 2] * jbx[2, c])
    for c in range(6):  # Tm = J_bb^-1 (V_bx + V_bb S)
        w0 = vbx[0, c] + vbb[0, 0] * s_ball[0, c] + vbb[0, 1] * s_ball[1, c] + vbb[0, 2] * s_ball[2, c]
        w1 = vbx[1, c] + vbb[1, 0] * s_ball[0, c] + vbb[1, 1] * s_ball[1, c] + vbb[1, 2] * s_ball[2, c]
        w2 = vbx[2, c] + vbb[2, 0] * s_ball[0, c] + vbb[2, 1] * s_ball[1, c] + vbb[2, 2] * s_ball[2, c]
        for r in range(3):
            tm[r, c] = inv[r, 0] * w0 + inv[r, 1] * w1 + inv[r, 2] * w2
    for r in range(6):
        a0 = t[0, r] * k_i[0, 0] + t[1, r] * k_i[1, 0] + t[2, r] * k_i[2, 0]  # A = T^T K_i, row r
        a1 = t[0, r] * k_i[0, 1] + t[1, r] * k_i[1, 1] + t[2, r] * k_i[2, 1]
        a2 = t[0, r] * k_i[0, 2] + t[1, r] * k_i[1, 2] + t[2, r] * k_i[2, 2]
        v0 = t[0, r] * d_i[0, 0] + t[1, r] * d_i[1, 0] + t[2, r] * d_i[2, 0]  # B = T^T D_i, row r
        v1 = t[0, r] * d_i[0, 1] + t[1, r] * d_i[1, 1] + t[2, r] * d_i[2, 1]
        v2 = t[0, r] * d_i[0, 2] + t[1, r] * d_i[1, 2] + t[2, r] * d_i[2, 2]
        for c in range(6):
            e0, e1, e2 = t[0, c] - s_ball[0, c], t[1, c] - s_ball[1, c], t[2, c] - s_ball[2, c]
            kx[r, c] += a0 * e0 + a1 * e1 + a2 * e2
            cx[r, c] += v0 * e0 + v1 * e1 + v2 * e2 + a0 * tm[0, c] + a1 * tm[1, c] + a2 * tm[2, c]
        cx[r, 5] -= gain_i * (a0 * n_i[0] + a1 * n_i[1] + a2 * n_i[2])  # -(A d_i) e_5^T


@njit(cache=True)
def _condense_ball(jl, vl, nx, kx, cx, s_ball, inv, tm):
    """Add one quasi-static ball's share of the condensed Jacobians to kx, cx (nx, nx):
    from its blocks jl = d f / d q, vl = d f / d q_t over [x (nx), the ball (3)] (J, V
    below), with S = -J_bb^-1 J_bx (into ``s_ball`` (3, nx)),

        kx += J_xx + J_xb S,
        cx += V_xx + V_xb S - J_xb J_bb^-1 (V_bx + V_bb S),

    the ball following x statically (b_x = S) and moving with b_t = S x_t, whose
    change with x (second order, d S / d x x_t) is left out. The balls couple only
    through x, so the Schur complement over all balls is this sum. inv (3, 3), tm
    (3, nx): work."""
    det = adjugate3(jl[nx:, nx:], inv)
    for r in range(3):
        for c in range(3):
            inv[r, c] /= det
    for r in range(3):  # S = -J_bb^-1 J_bx
        for c in range(nx):
            s_ball[r, c] = -(inv[r, 0] * jl[nx, c] + inv[r, 1] * jl[nx + 1, c] + inv[r, 2] * jl[nx + 2, c])
    for c in range(nx):  # T = J_bb^-1 W, W = V_bx + V_bb S (column by column)
        w0 = vl[nx, c] + vl[nx, nx] * s_ball[0, c] + vl[nx, nx + 1] * s_ball[1, c] + vl[nx, nx + 2] * s_ball[2, c]
        w1 = (
            vl[nx + 1, c]
            + vl[nx + 1, nx] * s_ball[0, c]
            + vl[nx + 1, nx + 1] * s_ball[1, c]
            + vl[nx + 1, nx + 2] * s_ball[2, c]
        )
        w2 = (
            vl[nx + 2, c]
            + vl[nx + 2, nx] * s_ball[0, c]
            + vl[nx + 2, nx + 1] * s_ball[1, c]
            + vl[nx + 2, nx + 2] * s_ball[2, c]
        )
        for r in range(3):
            tm[r, c] = inv[r, 0] * w0 + inv[r, 1] * w1 + inv[r, 2] * w2
    for r in range(nx):
        for c in range(nx):
            acc_k = jl[r, c]
            acc_c = vl[r, c]
            for a in range(3):
                acc_k += jl[r, nx + a] * s_ball[a, c]
                acc_c += vl[r, nx + a] * s_ball[a, c] - jl[r, nx + a] * tm[a, c]
            kx[r, c] += acc_k
            cx[r, c] += acc_c


def ball_workspace(ball_count: int, nx: int) -> np.ndarray:
    """Work array of a row's quasi-static balls (:func:`quasi_static_balls`): the
    last solution's ball displacements b and velocities b_t (3Z each), the static
    ball sensitivity S = d b / d x (3Z x nx, of the last Jacobian), the frame and
    modal coordinates x and velocities x_t of the last solution (nx each) and a
    flag (1: a solution is stored). Views: :func:`_split_balls`."""
    return np.zeros(6 * ball_count + 3 * ball_count * nx + 2 * nx + 1)


@njit(cache=True)
def _split_balls(ws, nb, nx):
    """(b, b_t, S (3Z, nx), x, x_t, flag (1,)) views of :func:`ball_workspace` (nb = 3Z)."""
    sm = ws[2 * nb : 2 * nb + nb * nx].reshape((nb, nx))
    o = 2 * nb + nb * nx
    return ws[:nb], ws[nb : 2 * nb], sm, ws[o : o + nx], ws[o + nx : o + 2 * nx], ws[o + 2 * nx : o + 2 * nx + 1]


@njit(cache=True, inline="always")
def _predict_balls(q, qt, ball_ref, cage_ratio, b, bt, sm, xl, xtl):
    """The quasi-static balls' start from the last solution (:func:`quasi_static_balls`):
    turned about the axis with their cage by cage_ratio (phi_z - phi_z,last), then
    b += S (x - x_last) over the other coordinates and b_t = b_t,last + S (x_t - x_t,last),
    into q[nx:], qt[nx:]."""
    nz = ball_ref.shape[0]
    nb = 3 * nz
    nx = q.shape[0] - nb
    turn = cage_ratio * (q[5] - xl[5])
    ct, st = math.cos(turn), math.sin(turn)
    for j in range(nz):
        px, py = ball_ref[j, 0] + b[3 * j], ball_ref[j, 1] + b[3 * j + 1]
        q[nx + 3 * j] = ct * px - st * py - ball_ref[j, 0]
        q[nx + 3 * j + 1] = st * px + ct * py - ball_ref[j, 1]
        q[nx + 3 * j + 2] = b[3 * j + 2]
    for e in range(nb):
        acc = 0.0
        acc_t = bt[e]
        for c in range(nx):
            if c != 5:
                acc += sm[e, c] * (q[c] - xl[c])
            acc_t += sm[e, c] * (qt[c] - xtl[c])
        q[nx + e] += acc
        qt[nx + e] = acc_t


@njit(cache=True)
def quasi_static_balls(q, qt, p, jacobian, rec, f, kbb, kx, cx):
    """One evaluation of a row with quasi-static balls: q, q_t (n, the full element
    vectors, work arrays) hold the frame and modal coordinates x in their first
    nx = n - 3Z entries (set by the caller); ``balls`` (:func:`ball_workspace`)
    keeps the last solution (b, b_t at x_last, x_t_last; initially the preload
    equilibrium at x = 0). The balls start from its prediction: turned about the
    axis with their cage by cage_ratio (phi_z - phi_z,last) (exact for a rigid turn
    of any size: a history pass may jump), then b += S (x - x_last) over the other
    coordinates and b_t = b_t,last + S (x_t - x_t,last) (S: the static sensitivity d b /
    d x of the last Jacobian call, zero before it), and are solved by
    :func:`ball_equilibrium` (relative force tolerance ``geometry.ball_force_tol``,
    :data:`BALL_MAXIT` steps; if the prediction fails, once more from b_last; a
    failure is counted in state[4], flagged in state[5] and not stored). Out: f[:nx]
    the force on x (f (n,) work), the per-ball records ``rec`` and, with
    ``jacobian``, the condensed Jacobians kx, cx (nx, nx) (:func:`row_eval`'s
    CONDENSED_BALLS mode, from the solve's last evaluation: :func:`_ball_solve`), whose S is
    stored. A Jacobian call at the state of the last solution (Exudyn's usual order) reuses
    it without a new solve (f and rec are then not written). kbb (3Z, 4): work."""
    geometry, state = p.geometry, p.state
    nz = p.ball_ref.shape[0]
    nb = 3 * nz
    nx = q.shape[0] - nb
    b, bt, sm, xl, xtl, flag = _split_balls(p.balls, nb, nx)
    same = flag[0] > 0.0
    if same:
        for c in range(nx):
            if q[c] != xl[c] or qt[c] != xtl[c]:
                same = False
                break
    if same and jacobian:
        for e in range(nb):
            q[nx + e] = b[e]
            qt[nx + e] = bt[e]
    else:
        _predict_balls(q, qt, p.ball_ref, geometry.cage_ratio, b, bt, sm, xl, xtl)
        kxs = kx if jacobian else np.empty((0, 0))  # (the solve's last evaluation gives the Jacobians)
        cxs = cx if jacobian else np.empty((0, 0))
        its = -1
        for attempt in range(2):
            if attempt == 1:  # once more from the last solution
                for e in range(nb):
                    q[nx + e] = b[e]
                    qt[nx + e] = bt[e]
            its = _ball_solve(q, qt, p, geometry.ball_force_tol, BALL_MAXIT, f, kbb, rec, kxs, cxs)
            if its >= 0:
                break
        state[5] = 0
        _count_solve(state, 4, its)
        if its >= 0:
            for e in range(nb):
                b[e] = q[nx + e]
                bt[e] = qt[nx + e]
            for c in range(nx):
                xl[c] = q[c]
                xtl[c] = qt[c]
            flag[0] = 1.0
        return
    if jacobian:
        row_eval(q, qt, p, _mode(CONDENSED_BALLS), np.empty((0, N_RECORD)), f, kx, cx)


@njit(cache=True)
def row_part(qn, vn, absolute, jacobian, part):
    """One row of the bearing rows' elements (:func:`row_element`, :func:`rows_kernel`):
    ``part`` = (idx, qe, ve, f, jq, jv, rec, kbb, kx, cx, the row's :data:`RowPack`,
    :func:`flexrv.model.flexible_bearing.kernel_inputs`). Gathers the row's element
    coordinates and velocities qe[e] = qn[idx[e]], ve[e] = vn[idx[e]] (``absolute``: the
    nodes hold absolute ball positions, the reference ``p.ball_ref`` is subtracted), then
    :func:`row_eval` -- or, for quasi-static balls (``p.geometry.quasi_static_balls``; idx
    covers the frame and modal coordinates only, qe / ve are the full work vectors),
    :func:`quasi_static_balls`. Returns the row's Jacobians (d f / d q, d f / d q_t) over
    its idx coordinates (valid with ``jacobian``); its force is f[:idx.shape[0]]."""
    idx, qe, ve, f, jq, jv, rec, kbb, kx, cx, p = part
    n = idx.shape[0]
    for e in range(n):
        qe[e] = qn[idx[e]]
        ve[e] = vn[idx[e]]
    if p.geometry.quasi_static_balls:
        quasi_static_balls(qe, ve, p, _mode(jacobian), rec, f, kbb, kx, cx)
        return kx, cx
    if absolute:
        ball_ref = p.ball_ref
        nz = ball_ref.shape[0]
        b0 = n - 3 * nz
        for j in range(nz):
            for c in range(3):
                qe[b0 + 3 * j + c] -= ball_ref[j, c]
    row_eval(qe, ve, p, _mode(jacobian), rec, f, jq, jv)
    return jq, jv


@njit(cache=True)
def row_element(qn, vn, absolute, jacobian, f_q, f_v, out_f, out_j, parts):
    """One call of the bearing rows' Exudyn element (the glue of
    :class:`flexrv.model.flexible_bearing.RowElement`, compiled, into preallocated
    arrays). ``parts``: one tuple per row (:func:`row_part`). The rows' results summed
    in the nodes' coordinate order: the force out_f[idx[e]] += f[e], or with ``jacobian``
    Exudyn's -(f_q dF/dq + f_v dF/dq_t) into out_j (entries no row touches stay zero:
    the rows interact only through the carrier, so the row-row blocks are exact zeros,
    which Exudyn's sparse assembly skips)."""
    for part in parts:  # zero what the rows write
        idx = part[0]
        n = idx.shape[0]
        if jacobian:
            for r in range(n):
                for c in range(n):
                    out_j[idx[r], idx[c]] = 0.0
        else:
            for e in range(n):
                out_f[idx[e]] = 0.0
    for part in parts:
        idx, f = part[0], part[3]
        n = idx.shape[0]
        jq_, jv_ = row_part(qn, vn, _flag(absolute), _mode(jacobian), part)
        if jacobian:
            for r in range(n):
                ir = idx[r]
                for c in range(n):
                    out_j[ir, idx[c]] += -(f_q * jq_[r, c] + f_v * jv_[r, c])
        else:
            for e in range(n):
                out_f[idx[e]] += f[e]


#: the compiled force element of the bearing rows (:class:`flexrv.model.flexible_bearing.BallBearingGroup`):
#: ``parts``, one tuple per row (:func:`row_part`; idx into the model's coordinates, the balls' absolute)
BearingRowsPack = pack_type("BearingRowsPack", ("parts", tuple))


@njit(cache=True)
def rows_kernel(q, v, f, jq, jv, jac, pack):
    """The bearing rows as a compiled force element of the fused kernel
    (:mod:`flexrv.model.core.registry`): every row's force added into f and, if ``jac``,
    its Jacobians into jq, jv over the coordinates of its ``idx`` (:func:`row_part`, the
    balls' coordinates absolute positions). The same per-row evaluation as the Exudyn
    glue :func:`row_element`; the rows' sum is the force, the condensed Jacobians of
    quasi-static balls are the rows' Jacobians on the frame and modal coordinates."""
    for part in pack.parts:
        idx, fr = part[0], part[3]
        n = idx.shape[0]
        jq_, jv_ = row_part(q, v, _flag(True), _mode(jac), part)
        for e in range(n):
            f[idx[e]] += fr[e]
        if jac:
            for r in range(n):
                ir = idx[r]
                for c in range(n):
                    jq[ir, idx[c]] += jq_[r, c]
                    jv[ir, idx[c]] += jv_[r, c]


@njit(cache=True)
def row_history(qs, vts, p, recs):
    """:func:`row_eval` over a recorded history (the outputs pass, one compiled loop):
    element coordinates and velocities qs, vts (T, n) -> generalized forces (T, n),
    per-ball records into ``recs`` (T, Z, N_RECORD). The samples run in order, each
    condensed ring's local solve (and quasi-static balls' solve, whose qs, vts and
    forces cover the frame and modal coordinates only) warm-started from the
    previous sample (as one call per sample would)."""
    nt = qs.shape[0]
    out = np.zeros(qs.shape)
    empty = np.empty((0, 0))
    if p.geometry.quasi_static_balls:
        nx = qs.shape[1]
        nb = 3 * p.ball_ref.shape[0]
        qf = np.zeros(nx + nb)
        vf = np.zeros(nx + nb)
        f = np.empty(nx + nb)
        kbb = np.empty((nb, 4))
        for i in range(nt):
            qf[:nx] = qs[i]
            vf[:nx] = vts[i]
            quasi_static_balls(qf, vf, p, _mode(False), recs[i], f, kbb, empty, empty)
            out[i] = f[:nx]
        return out
    for i in range(nt):
        row_eval(qs[i], vts[i], p, _mode(False), recs[i], out[i], empty, empty)
    return out


@njit(cache=True)
def ring_modal_amplitudes(psi, g_local, table, zsign, compliance_diag):
    """Modal amplitudes q = K^-1 sum_j B(psi_j)^T g_j of a condensed ring from its
    contact loads g in the ring's own Cartesian frame at azimuths psi, for every
    sample of a history: psi (T, Z), g_local (T, Z, 3) -> (T, m)
    (K diagonal: ``compliance_diag`` = 1 / diag K). B^T g is accumulated tap by
    tap of the periodic cubic (:func:`_taps`) from the load's cylindrical
    components (the transpose of :func:`_basis`)."""
    ng, m = table.shape[0], table.shape[2]
    idx = np.empty(4, np.int64)
    w = np.empty(4)
    out = np.zeros((psi.shape[0], m))
    for i in range(psi.shape[0]):
        for j in range(psi.shape[1]):
            ph = psi[i, j]
            _taps(ph, ng, idx, w)
            c, s = math.cos(ph), math.sin(ph)
            gx, gy = g_local[i, j, 0], g_local[i, j, 1]
            gr, gt, gz = c * gx + s * gy, -s * gx + c * gy, zsign * g_local[i, j, 2]
            for t in range(4):
                ar, at, az = w[t] * gr, w[t] * gt, w[t] * gz
                row = table[idx[t]]
                for k in range(m):
                    out[i, k] += ar * row[0, k] + at * row[1, k] + az * row[2, k]
        for k in range(m):
            out[i, k] *= compliance_diag[k]
    return out
