"""Second stage: every pin–disc contact of every disc in one element.

For disc k with centre c_k and rotation psi_k, the housing-fixed pin centres P_i
are expressed in the disc frame and their exact signed gap g to the modified
profile is found as in :func:`flexrv.geometry.cycloid.pin_gap` (the same compiled
closest-point Newton, :func:`flexrv.geometry.cycloid._foot_point`, on the
pin-centre epitrochoid; warm-started per (disc, pin) from the previous
evaluation). Every evaluation is exact (no linearisation within a time step). A
warm-started closest point is a local minimum of the distance; it is accepted
only where the distance is below the curve's reach on its side
(:func:`_curve_reach`: 64 um outside, 4.2 mm inside on rv40e), which makes it the
nearest point, and is otherwise found again from the cold starts (after a long
solver excursion a warm start could otherwise stay on a neighbouring flank).

As-built geometry (:class:`PinParameters`, from :func:`flexrv.geometry.as_built.as_built`): actual pin
centres ``pins`` and radii r_i (``pin_radii``), per-disc modifications (dR_p,
dr_rp, d_rotation) (``disc_profile``) and profile harmonics A cos(order phi +
phase) (``profile_harmonics``, material added along the normal):

    g = s(P) + r_nom + dr_rp,k - r_i - sum A cos(order phi* + phase),

s(P) the signed distance of the pin centre from the pin-centre curve at its foot
point phi*, r_nom the nominal pin radius (to which the curve is offset). The
harmonics change the gap but not its direction: the tilt of the normal they
cause, O(order A / |C'|), is neglected (below 1e-3 rad for 10 um at order 10 on a
~100 mm curve). With the
housing-frame normal n (from the profile to the pin), the gap's derivatives are
(envelope theorem, the closest point being stationary)

    dg/dc_k = -n,   dg/dpsi_k = -(r x n)_z,   r = P_i - c_k,

so the gap rate is dg/dt = -n . (dc/dt + dpsi/dt z x r). The normal force is
the seeds' contact law on the signed gap (:func:`flexrv.contact.laws.impact_force`):
Hertz line contact Q = K delta^(10/9) (Palmgren, ``contact.pin_law =
"hertz_line"``, K from :func:`flexrv.contact.hertz.line_contact_stiffness` over
the disc width) or the impact law K delta^e, plus the damping ramp c_max
step(delta, 0, 0, d, 1). The generalized force on the disc is Q = F dg/dq (the
force -F n acts on the disc along the line through the pin centre), so
modification clearance, separation and the number of pins in mesh emerge from
the contact physics. The pins are rigidly fixed in the housing (their own
bending and the pin-housing contact are not modelled).

Jacobian (complete: the exact derivative of the residual as computed). With the
gradient G = (-n, -(r x n)_z) over (x, y, psi) of disc k, Q = F G and

    dQ/dq = dF/dg G (G + b w)^T + F (h w w^T + S) + dF/dg' G (dG/dq v)^T,
    dQ/dv = dF/dg' G G^T,

where, at the foot point (profile-frame curve derivatives C', C'', unit tangent t
turned into the housing frame, profile normal m, signed distance s),
w = (t, (r x t)_z); h = -(m . C'') / D with D = |C'|^2 - s (m . C'') (the second
derivative of |P - C|^2 / 2, > 0 at the minimum) is the normal's turn per unit
tangential motion (dm/dP = h t t^T, the curvature of the offset); S holds the
arm's turn: S[x, psi] = n_y, S[y, psi] = -n_x, S[psi, psi] = -(r . n); and
b = -|C'| sum A order sin(order phi* + phase) / D is the harmonics' change with
the foot point (dphi*/dq = -|C'| w / D), which the force direction G omits (see
above), so dQ/dq is not symmetric when harmonics are present. Verified against
central differences in tests/test_kernel.py (1e-6 of the largest entry;
measured 1-2e-8, the differences' round-off).

Friction: regularised Coulomb friction along the contact tangent
t = z x n (housing frame). The disc's material point at the contact,
X = P_i - r_i n, slides past the (fixed) pin at v_t = W . v, W = (t_x, t_y,
((X - c_k) x t)_z) = (t, (r x t)_z - r_i) over (x, y, psi) of disc k (n x t = 1);
the friction force on the disc is f_t t at X with f_t = -mu F s(v_t) (s the
regularised sign :func:`flexrv.contact.laws._friction_one`, v_reg = design
``contact.friction_velocity_mm_per_s``), so Q_f = f_t W and its power f_t v_t <= 0.
mu is the pin's effective coefficient min(mu_pin_disc, mu_pin_seat)
(:func:`flexrv.contact.laws.effective_pin_friction`: a massless pin free to turn
in its groove slides where friction is lower). Exact Jacobian:

    dQ_f/dv = -mu W (s dF/dg' G + F s' W)^T,
    dQ_f/dq = -mu W (s dF/dq + F s' (dW/dq)^T v)^T + f_t dW/dq,

dF/dq = dF/dg (G + b w) + dF/dg' (dG/dq v) as above and dW/dq = h N w'^T + T with
N = (n, (r x n)_z) = -G, w' = (t, (r x t)_z) (the tangent turns with the normal,
dt/dq = h n w'^T - n e_psi^T) and T[x, psi] = T[psi, x] = -n_x, T[y, psi] =
T[psi, y] = -n_y, T[psi, psi] = -(r x n)_z. mu = 0 or contact.friction = false
skips the friction code (the frictionless numbers exactly). Verified against
central differences in tests/test_friction.py.

Disc body (design ``second_stage.disc_body_model = "condensed_fe"``): the
pins act on the disc's rim (tooth region) whose pose is q_r = q_hub + delta, the
needle bearings on its hub (the disc member's coordinates); delta = C_d Q(q_r),
C_d the (3 x 3) rim compliance relative to the crank holes from the disc FE
(:func:`flexrv.fem.disc.rim_compliance`: the torsional compliance under the
rated pin-load pattern, its choice and error stated there). :func:`pin_body_kernel`
wraps :func:`pin_kernel` (unchanged) in a local Newton on delta with the
condensed Jacobians (I - J C_d)^-1 J and (I - J C_d)^-1 J_v. With C_d = 0 (and a
rigid housing) it is the plain pin kernel. Verified in tests/test_bodies.py.

Housing (design ``housing.body_model = "ring_estimate"``): the pin ring
turns elastically about the reducer axis by phi_h = c_h M_h, shared by all discs,
M_h the torque of all pin forces on the housing about the axis and c_h the
housing's energy-equivalent torsional compliance
(:func:`flexrv.analysis.torsional.housing_compliance`, ``total``: ring bending
under the pin loads + tube torsion; the ring's ovalisation enters only through
this energy equivalent, not as a pin-position pattern). A ring rotation phi_h is
a rotation of every disc rim by -phi_h about the axis, to first order a rim pose
change -phi_h a_k with a_k = (-y_k, x_k, 1) (hub centre c_k = (x_k, y_k)). The
torque of the pins' forces Q_k on disc k about the axis is a_k . Q_k (the force
acts at c_k + r: (c_k x F)_z + (r x F)_z), so M_h = -sum_k a_k . Q_k (action and
reaction; the generalized force conjugate to phi_h) and the rim offsets over all
discs are delta = C Q with C = blockdiag(C_d,k) + c_h A A^T (A stacks the a_k).
One local Newton on the 3 n_discs offsets (:func:`_pin_condensed_kernel`) serves
both bodies; as a_k follows the hub centre, the condensed Jacobian is
(I - J C)^-1 J (I + D) with D = d(C Q)/dq at fixed Q = c_h (dA/dq (A^T Q) + A
(dA/dq)^T Q); c_h = 0 decouples the discs (C block-diagonal, D = 0). Verified in
tests/test_housing.py.

Cost: in a run the condensation's cost is its pin-kernel evaluations.
Each call starts from a first-order predictor of the offsets (the previous call's
condensed sensitivities), stops where the quadratic convergence shows the next
evaluation would only confirm the tolerance (the records moved to the corrected pose,
:func:`_shift_records`), evaluates the pin kernel on the 3 n_discs local rim
coordinates (3 x 3 blocks, no n x n arrays) and solves the small systems without
LAPACK (:func:`inv_small`); a call at exactly the previous call's state adds that
call's result; a step's first call adds the previous first call's remaining predictor
error. See :func:`_pin_condensed_kernel`. Per pin the closest point starts from its
second-order prediction in the pin's motion (:func:`_pin_foot`), a pin proved open by
the bound chained from the disc's last pose costs one subtraction, one proved open by the
empty tangent ball of its last exact evaluation a rotation and a root, one at its predicted
foot point's ball a curve evaluation more (:func:`pin_kernel`),
the Jacobian's curvature terms reuse the curve's derivatives at the foot point from its
Newton iteration, and the foot point's half-lobe test needs no arctangent
(:func:`flexrv.geometry.cycloid._foot_point`). Measured per element and time step
in ``benchmarks/bench_rigid.py`` (docs/integrator.md, "The kernel's inner solves").

Skipping open pins (exact for the forces; :func:`_pins_at`): with the harmonics at their
worst the gap is at least s(P) + r_nom + dr_rp - r_i - sum|A|, s(P) the pin centre's signed
distance from the pin-centre curve, and s is at least rho - |P - O| for the empty tangent
ball (centre O, radius rho) at the foot point of the last exact evaluation
(:func:`_ball_record`: near contact the bound loses only the motion towards the profile and
the tangential motion's square over 2 rho, where the 1-Lipschitz bound g0 - |P - P0| loses
the whole motion; a pin open before and not proved open by it is tried against the ball at
its predicted foot point, :func:`_ball_predicted`). A pin whose bound is positive carries no
force (and no Jacobian); its closest point is not recomputed and out_gap holds the bound.
last[kd, i] holds g0, P0, the foot point's derivatives (:data:`GRAD`, :data:`HESS`,
:func:`_pin_foot`) and the ball (:data:`BALL`) of the last exact evaluation and the last
lower bound at the disc's pose of the last evaluation (:data:`SLACK`, ``pose``): s is
1-Lipschitz and no pin moved relative to the disc by more than |c - c0| + (max|pin| + |c0|)
|psi - psi0| since, so that bound less this motion is tried first (no rotation, no root;
never above the ball's bound, |P - O| being 1-Lipschitz in P, so the same pins are solved).

One compiled kernel (:func:`pin_kernel`, numba) is the only executor: the group's
evaluate/jacobian and the model's fused element call it. Solver calls skip pins
that are provably open (see :func:`pin_kernel`; exact for forces and Jacobians);
time histories (outputs) evaluate every gap exactly.
"""

from __future__ import annotations

import functools
from collections import namedtuple
from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.contact.laws import _friction_one, _impact_one
from flexrv.geometry.cycloid import _FOOT, _POINT, closest_point_settings
from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, law_type, pack_type
from flexrv.model.drive import DriveParameters
from flexrv.model.numerics.linalg import matmul_small
from flexrv.model.numerics.newton import (
    LAM,
    NEWTON_STATE,
    TOL,
    VALID,
    apply_predictor,
    newton_start,
    newton_update,
)
from flexrv.units import M_PER_UM

#: the pin contacts' scalar law: pin count, pin circle radius R_p [m], nominal pin radius [m],
#: eccentricity [m], contact law K, exponent, c_max, depth, the closest-point Newton's settings
#: (:func:`flexrv.geometry.cycloid.closest_point_settings`), friction coefficient and speed (0: off), the
#: penetration beyond which a run stops as failed [m] (:func:`pin_penetrated`)
PinLaw = law_type(
    "PinLaw",
    z_rp=int,
    pin_circle_radius=float,
    pin_radius=float,
    eccentricity=float,
    k=float,
    exponent=float,
    c_max=float,
    depth=float,
    max_step=float,
    tol=float,
    max_iter=int,
    cos_half=float,
    mu=float,
    v_reg=float,
    penetration_limit=float,
)
_F, _I = np.float64, np.int64
#: how :func:`pin_kernel` uses its warm starts: a cold restart of every closest point every
#: ``restart_every`` calls (0: never after the first), pins provably open skipped (``skip_open``)
PinControl = law_type("PinControl", restart_every=int, skip_open=bool)
#: the slots of a pin's ``last`` record (:func:`pin_kernel`, :func:`_pin_foot`): the exact gap g0 at the
#: profile-frame position P0 of its last exact evaluation (0, 1, 2), the foot point's gradient dphi/dP (3, 4)
#: and second derivatives d2phi/dP2 (xx, xy, yy: 5, 6, 7) there, the lower bound of the gap at the disc's
#: pose of the last evaluation (``pose``), the chained bound's start (8), and the empty tangent ball's bound
#: of the last exact evaluation (:func:`_ball_record`): its centre O (9, 10) and rho + r_nom + dr_rp - r_i -
#: sum|A| (11), so that the gap at P is at least that less |P - O|, and r_nom + dr_rp - r_i - sum|A| (12)
GRAD, HESS, SLACK, BALL, LAST_SIZE = 3, 5, 8, 9, 13
#: :func:`pin_kernel`'s pack: indices (x, y, psi per disc), law, per disc the curve's reach outside /
#: inside (:func:`_curve_reach`) and its outer medial radius over one lobe's bins
#: (:func:`_outer_ball_table`), as-built pins (z, 2) and radii, disc profile modifications (n_discs, 3) and
#: harmonics (n_discs, H, 3), closest-point warm starts, last exact evaluations (the slots above),
#: each disc's pose (x, y, psi) at its last evaluation, outputs per (disc, pin), per (disc, pin) the
#: normal's turn h and the harmonics' b of the last evaluation with the Jacobian (NaN: skipped;
#: :func:`_shift_records`), the warm starts' control, the counters of calls and of closest-point failures
PinPack = pack_type(
    "PinPack",
    ("idx", (_I, 1)),
    ("law", PinLaw),
    ("reach", (_F, 2)),
    ("ball", (_F, 2)),
    ("pins", (_F, 2)),
    ("radii", (_F, 1)),
    ("profile", (_F, 2)),
    ("harm", (_F, 3)),
    ("phi", (_F, 2)),
    ("last", (_F, 3)),
    ("pose", (_F, 2)),
    ("gap", (_F, 2)),
    ("force", (_F, 2)),
    ("nx", (_F, 2)),
    ("ny", (_F, 2)),
    ("rxn", (_F, 2)),
    ("ft", (_F, 2)),
    ("pw", (_F, 2)),
    ("curv", (_F, 3)),
    ("control", PinControl),
    ("calls", (_I, (1,))),
    ("failures", (_I, (1,))),
)
#: the pin housing's torsional compliance c_h [rad/(N m)] (0: rigid housing)
HousingLaw = law_type("HousingLaw", compliance=float)
#: the housing state's slots (PinBodyPack field ``housing``, the group's record "housing"): c_h, the
#: rotation phi_h, then per disc k the housing's part -phi_h a_k of the rim offset (x, y) at
#: HOUSING_RIM + 2 k, + 1
HOUSING_C, HOUSING_PHI, HOUSING_RIM = 0, 1, 2
#: :func:`pin_body_kernel`'s pack: the pins' pack, rim compliance (n_discs, 3, 3) (empty: rigid
#: discs), rim offsets (n_discs, 3), the housing's law and state (c_h, phi_h, per disc -phi_h a_k;
#: written), the local rim indices 0..3 n_discs - 1 and the rim Newton's work array (:func:`pin_work_size`)
PinBodyPack = pack_type(
    "PinBodyPack",
    ("pins", PinPack),
    ("disc_c", (_F, 3)),
    ("dstate", (_F, 2)),
    ("housing_law", HousingLaw),
    ("housing", (_F, 1)),
    ("idx_rim", (_I, 1)),
    ("work", (_F, 1)),
)


@njit(cache=True)
def _add_outer3(m, ix, iy, ip, w, g0, g1, g2):
    """m[a, b] += w g_a g_b over one disc's coordinates (a, b in x, y, psi): a
    pin's contribution w (dF/dgap or dF/dgap_rate) to the Jacobian through its gap
    gradient g."""
    _add_outer3ab(m, ix, iy, ip, w, g0, g1, g2, g0, g1, g2)


@njit(cache=True)
def _add_outer3ab(m, ix, iy, ip, w, a0, a1, a2, b0, b1, b2):
    """m[a, b] += w a_a b_b over one disc's coordinates (x, y, psi)."""
    ii = (ix, iy, ip)
    a = (a0, a1, a2)
    b = (b0, b1, b2)
    for r in range(3):
        for c in range(3):
            m[ii[r], ii[c]] += w * a[r] * b[c]


@njit(cache=True)
def _gap_curvature(ph, d1x, d1y, d2x, d2y, dist, nlx, nly, cr, sr, c, s, rx, ry, nx, ny, harm, kd):
    """Second-order terms of one pin's gap for the exact Jacobian (module
    docstring, "Jacobian"), from C' = (d1x, d1y) and C'' = (d2x, d2y) at the foot
    point ph (:func:`flexrv.geometry.cycloid._foot_point` returns them): returns
    (h, w0, w1, w2, b, s02, s12, s22) with the gradient's derivative d G / dq = h w
    w^T + S (S nonzero in the psi row and column only: S[0, 2] = s02, S[1, 2] =
    s12, S[2, 2] = s22) and the gap's exact gradient dg/dq = G + b w (b: the
    harmonics' change with the foot point)."""
    speed2 = d1x * d1x + d1y * d1y
    mc2 = nlx * d2x + nly * d2y
    den = speed2 - dist * mc2  # d2/dphi2 of |P - C|^2 / 2 at the foot point (> 0: a minimum)
    h = -mc2 / den
    speed = np.sqrt(speed2)
    tx, ty = d1x / speed, d1y / speed  # unit tangent, profile frame
    ux, uy = cr * tx - sr * ty, sr * tx + cr * ty  # disc frame
    tx, ty = c * ux - s * uy, s * ux + c * uy  # housing frame
    a_h = 0.0
    for k in range(harm.shape[1]):
        a_h += harm[kd, k, 1] * harm[kd, k, 0] * np.sin(harm[kd, k, 0] * ph + harm[kd, k, 2])
    return h, tx, ty, rx * ty - ry * tx, -a_h * speed / den, ny, -nx, -(rx * nx + ry * ny)


@njit(cache=True)
def pin_kernel(q, v, f, jq, jv, jac, pack):
    """Pin–disc contacts (module docstring) on the coordinates ``pack.idx``: :func:`_pins_at`."""
    _pins_at(q, v, f, jq, jv, jac, pack, pack.idx)


@njit(cache=True)
def _pins_at(q, v, f, jq, jv, jac, pack, idx):
    """Pin–disc contacts (module docstring): Q into f[idx], Jacobians into jq, jv (``idx``: the
    discs' (x, y, psi) coordinates, ``pack.idx`` or the rim condensation's local ones).
    Per (disc, pin): gap, force, housing normal (nx, ny) and arm torque r x n into
    the output arrays; phi is the closest-point warm start (updated; NaN: cold
    start; :func:`_pin_foot`). ``calls`` counts calls (a cold
    restart every ``control.restart_every`` calls), ``failures`` the closest-point
    failures; ``control.skip_open`` allows skipping pins that are provably open.

    Skipping: the module docstring ("Skipping open pins"). Friction (module docstring): law.mu,
    law.v_reg; per (disc, pin) the friction force on the disc along t = z x n into out_ft and
    its power f_t v_t (<= 0) into out_pw."""
    law, pins, radii, profile, harm, last = pack.law, pack.pins, pack.radii, pack.profile, pack.harm, pack.last
    out_gap, out_f, out_nx, out_ny = pack.gap, pack.force, pack.nx, pack.ny
    out_rxn, out_ft, out_pw = pack.rxn, pack.ft, pack.pw
    R_p, r_nom = law.pin_circle_radius, law.pin_radius
    k, expo, c_max, depth = law.k, law.exponent, law.c_max, law.depth
    mu, v_reg = law.mu, law.v_reg  # friction: effective coefficient, regularisation speed
    fric = mu > 0.0 and v_reg > 0.0
    every, calls = pack.control.restart_every, pack.calls
    reach, phi, failures, curv, pose = pack.reach, pack.phi, pack.failures, pack.curv, pack.pose
    cold = every > 0 and calls[0] % every == 0
    skip = pack.control.skip_open
    calls[0] += 1
    chain = skip and not cold
    arm2 = 0.0  # the largest |pin|^2 (the chained bound's arm)
    if chain:
        for i in range(pins.shape[0]):
            arm2 = max(arm2, pins[i, 0] * pins[i, 0] + pins[i, 1] * pins[i, 1])
    for kd in range(profile.shape[0]):
        ix, iy, ip = idx[3 * kd], idx[3 * kd + 1], idx[3 * kd + 2]
        xd, yd, psi = q[ix], q[iy], q[ip]
        # the largest motion of any pin relative to the disc since its last evaluation (NaN: none)
        x0, y0 = pose[kd, 0], pose[kd, 1]
        moved = np.sqrt((xd - x0) ** 2 + (yd - y0) ** 2) + (np.sqrt(arm2) + np.sqrt(x0 * x0 + y0 * y0)) * abs(
            psi - pose[kd, 2]
        )
        pose[kd, 0], pose[kd, 1], pose[kd, 2] = xd, yd, psi
        c, s = np.cos(psi), np.sin(psi)
        d_r, d_rp, d_rot = profile[kd, 0], profile[kd, 1], profile[kd, 2]
        cr, sr = np.cos(d_rot), np.sin(d_rot)
        radius = R_p + d_r
        margin = 0.0
        for h in range(harm.shape[1]):
            margin += 2.0 * abs(harm[kd, h, 1])
        fx = fy = fp = 0.0
        for i in range(pins.shape[0]):
            if chain:  # the chained bound: no rotation, no root (NaN: not skipped)
                bound = last[kd, i, SLACK] - moved
                if bound > 0.0:
                    last[kd, i, SLACK] = bound
                    out_gap[kd, i], out_f[kd, i], out_ft[kd, i], out_pw[kd, i] = bound, 0.0, 0.0, 0.0
                    curv[kd, i, 0] = np.nan
                    continue
            rx, ry = pins[i, 0] - xd, pins[i, 1] - yd  # housing frame, disc centre to pin
            lx, ly = c * rx + s * ry, -s * rx + c * ry  # disc frame
            px, py = cr * lx + sr * ly, -sr * lx + cr * ly  # profile frame (rotation modification removed)
            if chain:  # the empty tangent ball's bound (_ball_record)
                bound = last[kd, i, BALL + 2] - np.sqrt(
                    (px - last[kd, i, BALL]) ** 2 + (py - last[kd, i, BALL + 1]) ** 2
                )
                if not bound > 0.0 and last[kd, i, SLACK] > 0.0:  # open before: the ball at the predicted foot
                    bound = _ball_predicted(law, pack.ball, phi, last, kd, i, px, py, radius)
                if bound > 0.0:  # provably open (NaN: never skipped)
                    last[kd, i, SLACK] = bound
                    out_gap[kd, i], out_f[kd, i], out_ft[kd, i], out_pw[kd, i] = bound, 0.0, 0.0, 0.0
                    curv[kd, i, 0] = np.nan
                    continue
            ph, dist, nlx, nly, d1x, d1y, d2x, d2y = _pin_foot(
                law, reach, phi, last, failures, kd, i, px, py, radius, cold
            )
            base = r_nom + d_rp - radii[i]
            gap = dist + base
            base -= 0.5 * margin  # the gap less its harmonics at their worst, less s
            for h in range(harm.shape[1]):
                gap -= harm[kd, h, 1] * np.cos(harm[kd, h, 0] * ph + harm[kd, h, 2])
            last[kd, i, 0], last[kd, i, 1], last[kd, i, 2] = gap, px, py
            last[kd, i, SLACK] = _ball_record(last, kd, i, px, py, dist, nlx, nly, pack.ball[kd], law.z_rp, ph, base)
            mx, my = cr * nlx - sr * nly, sr * nlx + cr * nly  # disc frame
            nx, ny = c * mx - s * my, s * mx + c * my  # housing frame
            rxn = rx * ny - ry * nx
            g0, g1, g2 = -nx, -ny, -rxn  # d gap / d(x, y, psi)
            rate = g0 * v[ix] + g1 * v[iy] + g2 * v[ip]
            force, dfg, dfr = _impact_one(gap, rate, k, expo, c_max, depth)
            out_gap[kd, i], out_f[kd, i], out_nx[kd, i], out_ny[kd, i], out_rxn[kd, i] = gap, force, nx, ny, rxn
            fx += force * g0
            fy += force * g1
            fp += force * g2
            # friction (module docstring, "Friction"): tangent t = z x n, arm of the contact point P - r_i n
            tx, ty = -ny, nx
            wt2 = rx * ty - ry * tx - radii[i]
            ft = sfr = dsfr = 0.0
            if fric and force > 0.0:
                vt = tx * v[ix] + ty * v[iy] + wt2 * v[ip]
                sfr, dsfr = _friction_one(vt, v_reg)
                ft = -mu * force * sfr
                fx += ft * tx
                fy += ft * ty
                fp += ft * wt2
                out_ft[kd, i], out_pw[kd, i] = ft, ft * vt
            else:
                out_ft[kd, i], out_pw[kd, i] = 0.0, 0.0
            if not jac:
                continue
            h, w0, w1, w2, b, s02, s12, s22 = _gap_curvature(
                ph, d1x, d1y, d2x, d2y, dist, nlx, nly, cr, sr, c, s, rx, ry, nx, ny, harm, kd
            )
            curv[kd, i, 0], curv[kd, i, 1] = h, b
            if force != 0.0 or dfg != 0.0 or dfr != 0.0:
                # dF/dgap g (G + b w)^T: the force's change; the exact gap gradient includes the harmonics' b w
                _add_outer3ab(jq, ix, iy, ip, dfg, g0, g1, g2, g0 + b * w0, g1 + b * w1, g2 + b * w2)
                # F dG/dq = F (h w w^T + S): the turn of the normal and of the arm (curvature terms)
                _add_outer3(jq, ix, iy, ip, force * h, w0, w1, w2)
                jq[ix, ip] += force * s02
                jq[ip, ix] += force * s02
                jq[iy, ip] += force * s12
                jq[ip, iy] += force * s12
                jq[ip, ip] += force * s22
                # dF/drate d(rate)/dq = dF/drate G (dG/dq v)^T (zero at rest)
                wv = h * (w0 * v[ix] + w1 * v[iy] + w2 * v[ip])
                hv0, hv1 = wv * w0 + s02 * v[ip], wv * w1 + s12 * v[ip]
                hv2 = wv * w2 + s02 * v[ix] + s12 * v[iy] + s22 * v[ip]
                _add_outer3ab(jq, ix, iy, ip, dfr, g0, g1, g2, hv0, hv1, hv2)
                _add_outer3(jv, ix, iy, ip, dfr, g0, g1, g2)
                if ft != 0.0 or sfr != 0.0:
                    # friction Q = f_t W, f_t = -mu F s(W . v): W (df_t/dq)^T + f_t dW/dq, W (df_t/dv)^T
                    w2t = rx * ty - ry * tx  # W without the constant pin-radius arm
                    nv = nx * v[ix] + ny * v[iy] + rxn * v[ip]
                    tv0, tv1 = -nx * v[ip], -ny * v[ip]  # T v (dW/dq = h N w'^T + T, T symmetric)
                    tv2 = -nx * v[ix] - ny * v[iy] - rxn * v[ip]
                    a_s, a_d = -mu * sfr, -mu * force * dsfr
                    _add_outer3ab(jq, ix, iy, ip, a_s * dfg, tx, ty, wt2, g0 + b * w0, g1 + b * w1, g2 + b * w2)
                    _add_outer3ab(jq, ix, iy, ip, a_s * dfr, tx, ty, wt2, hv0, hv1, hv2)
                    # d(v_t)/dq = (dW/dq)^T v = h w' (N . v) + T v
                    _add_outer3ab(
                        jq, ix, iy, ip, a_d, tx, ty, wt2, h * tx * nv + tv0, h * ty * nv + tv1, h * w2t * nv + tv2
                    )
                    _add_outer3ab(jq, ix, iy, ip, ft * h, nx, ny, rxn, tx, ty, w2t)
                    jq[ix, ip] -= ft * nx
                    jq[ip, ix] -= ft * nx
                    jq[iy, ip] -= ft * ny
                    jq[ip, iy] -= ft * ny
                    jq[ip, ip] -= ft * rxn
                    _add_outer3ab(jv, ix, iy, ip, a_s * dfr, tx, ty, wt2, g0, g1, g2)
                    _add_outer3(jv, ix, iy, ip, a_d, tx, ty, wt2)
        f[ix] += fx
        f[iy] += fy
        f[ip] += fp


@njit(cache=True, inline="always")
def _pin_foot(law, reach, phi, last, failures, kd, i, px, py, radius, cold):
    """The closest point of pin i to disc k's pin-centre curve (radius R_p + dR_p) at its
    profile-frame position P = (px, py): (phi, s, n_x, n_y, C'_x, C'_y, C''_x, C''_y) of
    :func:`flexrv.geometry.cycloid._foot_point`, warm-started from the second-order prediction
    of phi from the last exact evaluation (``cold``: from the cold starts), phi into phi[kd, i],
    a failure counted in failures[0] (``law``, ``reach``, ``phi``, ``last``, ``failures``: the
    fields of :data:`PinPack`, taken from the pack once per call: a field read from the pack
    per pin costs an atomic reference count pair, a sixth of the kernel's time).

    The prediction: the foot point solves F(phi, P) = (P - C(phi)) . C'(phi) = 0, so with D =
    -dF/dphi = |C'|^2 - (P - C) . C'' (> 0 at a minimum) its derivatives are dphi/dP = g = C' / D
    and d2phi/dP2 = (F_pp g g^T + C'' g^T + g C''^T) / D, F_pp = -3 C' . C'' + (P - C) . C'''
    (:func:`_foot_derivatives`), stored in last[kd, i, GRAD:] at the last exact evaluation (P0 =
    last[kd, i, 1:3]): phi + g . dP + dP^T (d2phi/dP2) dP / 2, dP = P - P0, is within O(|dP|^3)
    of the foot point, so the Newton starts near the solution after a time step's motion as
    after a Newton correction of the solver (from phi itself the start is off by ~1e-4 rad after
    a step). A predicted change of more than ``max_step`` (a far jump, e.g. a solver restarting
    elsewhere) or missing derivatives (NaN) start from phi[kd, i] itself. A warm-started local
    minimum beyond the curve's reach on its side may not be the nearest point (another flank):
    it is found again from the cold starts (:func:`_curve_reach`)."""
    z_rp, ecc, max_step, tol, max_iter = law.z_rp, law.eccentricity, law.max_step, law.tol, law.max_iter
    ch = law.cos_half
    start = np.nan if cold else _predicted_foot(phi, last, kd, i, px, py, max_step)
    ph, ok, dist, nlx, nly, d1x, d1y, d2x, d2y = _FOOT(px, py, start, z_rp, radius, ecc, max_step, tol, max_iter, ch)
    if ok and not cold and not (0.0 <= dist < reach[kd, 0] or 0.0 < -dist < reach[kd, 1]):
        ph, ok, dist, nlx, nly, d1x, d1y, d2x, d2y = _FOOT(
            px, py, np.nan, z_rp, radius, ecc, max_step, tol, max_iter, ch
        )
    if not ok:
        failures[0] += 1
    phi[kd, i] = ph
    _foot_derivatives(last, kd, i, ok, px, py, z_rp, dist, nlx, nly, d1x, d1y, d2x, d2y)
    return ph, dist, nlx, nly, d1x, d1y, d2x, d2y


@njit(cache=True, inline="always")
def _predicted_foot(phi, last, kd, i, px, py, max_step):
    """The second-order prediction of pin i's foot point at P = (px, py) from its last exact
    evaluation (:func:`_pin_foot`): phi + g . dP + dP^T H dP / 2, or phi itself where the
    predicted change is ``max_step`` or more or the derivatives are missing (NaN)."""
    start = phi[kd, i]
    dx, dy = px - last[kd, i, 1], py - last[kd, i, 2]
    move = last[kd, i, GRAD] * dx + last[kd, i, GRAD + 1] * dy
    bend = last[kd, i, HESS] * dx * dx + 2.0 * last[kd, i, HESS + 1] * dx * dy + last[kd, i, HESS + 2] * dy * dy
    move += 0.5 * bend
    if abs(move) < max_step:  # (NaN: no prediction)
        start += move
    return start


@njit(cache=True, inline="always")
def _ball_predicted(law, table, phi, last, kd, i, px, py, radius):
    """The tangent-ball bound of pin i at P = (px, py) from the ball at its predicted foot point
    (:func:`_predicted_foot`), one curve evaluation: any curve point's outer tangent ball of
    radius rho below its medial radius is empty (:func:`_ball_record`), and at the predicted
    foot point P lies almost on the ball's axis, so the bound is the gap less the prediction's
    error squared over 2 rho. A positive bound replaces the ball record (the foot point's own
    records stay those of the last exact evaluation); returns the bound (NaN: none)."""
    ph = _predicted_foot(phi, last, kd, i, px, py, law.max_step)
    if not ph == ph:
        return np.nan
    cx, cy, d1x, d1y, _, _ = _POINT(ph, law.z_rp, radius, law.eccentricity)
    inv = 1.0 / np.sqrt(d1x * d1x + d1y * d1y)
    nx, ny = -d1y * inv, d1x * inv  # the outer normal (cycloid._closest_point_newton's n_out)
    n = table.shape[1]
    lobe = 2.0 * np.pi / (law.z_rp - 1)
    rho = table[kd, min(int((ph % lobe) * (n / lobe)), n - 1)]
    ox, oy = cx + rho * nx, cy + rho * ny
    base = last[kd, i, BALL + 3]  # r_nom + dr_rp - r_i - sum|A| (NaN after a failure)
    bound = rho + base - np.sqrt((px - ox) ** 2 + (py - oy) ** 2)
    if bound > 0.0:
        last[kd, i, BALL], last[kd, i, BALL + 1], last[kd, i, BALL + 2] = ox, oy, rho + base
    return bound


@njit(cache=True, inline="always")
def _foot_derivatives(last, kd, i, ok, px, py, z_rp, dist, nlx, nly, d1x, d1y, d2x, d2y):
    """dphi/dP and d2phi/dP2 of the foot point at P = (px, py) (:func:`_pin_foot`) into
    last[kd, i, GRAD:GRAD + 2] and last[kd, i, HESS:HESS + 3] (NaN if not ``ok``). The
    epitrochoid's third derivative from C and C'': with C = R e(phi) - a E(z phi), e(x) = (sin
    x, cos x), C + C'' = a (z^2 - 1) E and C''' = -C' + a z (z^2 - 1) E', E' = Rot(-90 deg) E,
    so C''' = -C' + z Rot(-90 deg)(C + C'')."""
    den = d1x * d1x + d1y * d1y - dist * (nlx * d2x + nly * d2y)  # D = d2/dphi2 of |P - C|^2 / 2
    if not (ok and den > 0.0):
        for c in range(GRAD, HESS + 3):
            last[kd, i, c] = np.nan
        return
    rx, ry = dist * nlx, dist * nly  # P - C at the foot point
    cx, cy = px - rx, py - ry
    d3x = -d1x + z_rp * (cy + d2y)
    d3y = -d1y - z_rp * (cx + d2x)
    fpp = -3.0 * (d1x * d2x + d1y * d2y) + rx * d3x + ry * d3y
    inv = 1.0 / den
    gx, gy = d1x * inv, d1y * inv
    last[kd, i, GRAD], last[kd, i, GRAD + 1] = gx, gy
    last[kd, i, HESS] = (fpp * gx * gx + 2.0 * d2x * gx) * inv
    last[kd, i, HESS + 1] = (fpp * gx * gy + d2x * gy + d2y * gx) * inv
    last[kd, i, HESS + 2] = (fpp * gy * gy + 2.0 * d2y * gy) * inv


@njit(cache=True, inline="always")
def _ball_record(last, kd, i, px, py, dist, nlx, nly, table, z_rp, ph, base):
    """The empty tangent ball of pin i's exact evaluation at P0 = (px, py) (signed distance s0 =
    ``dist`` from the pin-centre curve along its outer normal n = (nlx, nly); ``base`` = r_nom +
    dr_rp - r_i - sum|A|, so that the gap at any P is at least s(P) + base) into
    last[kd, i, BALL:BALL + 3]; returns the bound at P0 itself.

    The open ball of radius rho = max(R, s0) about O = C0 + rho n, C0 = P0 - s0 n the foot point
    ph, holds no point of the curve: for rho = R, a lower estimate of the curve's outer medial
    radius over ph's bin of the lobe (``table``, :func:`_outer_ball_table`; lobes of 2 pi /
    (z_rp - 1)), by the medial radius' definition; for rho = s0 > R it is the ball about P0
    whose radius is P0's distance to the curve. Being empty and touching the curve from outside,
    the ball lies outside, so every P has s(P) >= rho - |P - O|: a P outside the ball is at least
    as far from the curve's inner side as from the ball (a path from inside reaches the ball only
    across the curve), and a P in the ball is outside at least rho - |P - O| from the ball's
    boundary. Hence g(P) >= rho - |P - O| + base. Near contact (s0 << R) this is s0 + (motion
    along n) - (motion along the tangent)^2 / (2 R) to second order: a pin sliding along the
    profile at a step's motion keeps a bound near its gap, where the 1-Lipschitz bound g0 -
    |P - P0| (the ball's rho = s0 case, which the bound never falls below) loses the whole
    motion. A failed closest point (NaN) records nothing (never skipped)."""
    if not last[kd, i, GRAD] == last[kd, i, GRAD]:  # no converged foot point (_foot_derivatives)
        last[kd, i, BALL + 2] = last[kd, i, BALL + 3] = np.nan
        return np.nan
    n = table.shape[0]
    lobe = 2.0 * np.pi / (z_rp - 1)
    j = min(int((ph % lobe) * (n / lobe)), n - 1)
    rho = max(table[j], dist)
    last[kd, i, BALL] = px + (rho - dist) * nlx
    last[kd, i, BALL + 1] = py + (rho - dist) * nly
    last[kd, i, BALL + 2] = rho + base
    last[kd, i, BALL + 3] = base
    return dist + base


#: the rim Newton's caps and round-off rule (numerics.newton.newton_update: max_evals, max_steps,
#: roundoff_abs, roundoff_rel): 80 evaluations; round-off: a worse residual at max|R| <= 100 tol
RIM_NEWTON = (80, 80, 0.0, 100.0)
#: the rim Newton's quadratic stop (:func:`_rim_solve`): it stops after a full Newton step whose
#: predicted next residual K_est max|step|^2 is at most QUAD_SAFETY of the tolerance; the carried
#: K_est halves per call that measures a smaller K (QUAD_DECAY)
QUAD_SAFETY, QUAD_DECAY = 0.01, 0.5
#: the slots of the rim work flags (``st``, beside numerics.newton.VALID) that carry K_est and the
#: weighted hub motion of the last step's first call (0: none; :func:`_rim_solve`)
QUAD_EST, EXT_MOVE = 1, 2


@njit(cache=True)
def _shift_records(pins, ql, vh, dq):
    """Move the per-contact records of :func:`pin_kernel`'s last evaluation (with the
    Jacobian, at the local rim coordinates ``ql``, velocities ``vh``) to the rim pose ql + dq,
    exact to first order in dq (the rim Newton's last correction, applied linearised: the
    records then belong to the pose whose force the element returns). Per evaluated pin,
    from the gap gradient G = (-n, -(r x n)) and its derivative dG/dq = h w w^T + S of the
    Jacobian (module docstring, "Jacobian"; h and b stored in ``curv``): gap += (G + b w).dq,
    G += dG/dq dq (the normal and its arm), the gap rate G.v and then the contact law and
    friction evaluated again at the moved gap and rate (so a pin may enter or leave contact).
    A skipped pin (provably open, ``curv`` NaN) keeps a lower bound of its gap, less the
    largest displacement of the pin relative to the disc, |(dx, dy)| + |r| |dpsi|. The
    remainder is O(|dq|^2): ~h |dq|^2 ~ 1e-21 m in the gaps at the |dq| ~ 1e-12 m these
    corrections have."""
    law, pxy, radii, curv = pins.law, pins.pins, pins.radii, pins.curv
    out_gap, out_f, out_nx, out_ny, out_rxn, out_ft, out_pw = (
        pins.gap,
        pins.force,
        pins.nx,
        pins.ny,
        pins.rxn,
        pins.ft,
        pins.pw,
    )
    k, expo, c_max, depth, mu, v_reg = law.k, law.exponent, law.c_max, law.depth, law.mu, law.v_reg
    fric = mu > 0.0 and v_reg > 0.0
    for kd in range(curv.shape[0]):
        dx, dy, dp = dq[3 * kd], dq[3 * kd + 1], dq[3 * kd + 2]
        vx, vy, vp = vh[3 * kd], vh[3 * kd + 1], vh[3 * kd + 2]
        xd, yd = ql[3 * kd], ql[3 * kd + 1]
        move = np.sqrt(dx * dx + dy * dy)
        for i in range(pxy.shape[0]):
            rx, ry = pxy[i, 0] - xd, pxy[i, 1] - yd
            h = curv[kd, i, 0]
            if not h == h:  # skipped: a lower bound stays a lower bound
                out_gap[kd, i] -= move + np.sqrt(rx * rx + ry * ry) * abs(dp)
                continue
            nx, ny, rxn = out_nx[kd, i], out_ny[kd, i], out_rxn[kd, i]
            w0, w1, w2 = ny, -nx, -(rx * nx + ry * ny)  # (t, (r x t)_z), t the profile's unit tangent
            a = w0 * dx + w1 * dy + w2 * dp
            gap = out_gap[kd, i] - nx * dx - ny * dy - rxn * dp + curv[kd, i, 1] * a
            g0 = -nx + h * w0 * a + ny * dp  # G + (h w w^T + S) dq
            g1 = -ny + h * w1 * a - nx * dp
            g2 = -rxn + h * w2 * a + ny * dx - nx * dy + w2 * dp
            rate = g0 * vx + g1 * vy + g2 * vp
            force = _impact_one(gap, rate, k, expo, c_max, depth)[0]
            out_gap[kd, i], out_f[kd, i], out_nx[kd, i], out_ny[kd, i], out_rxn[kd, i] = gap, force, -g0, -g1, -g2
            out_ft[kd, i], out_pw[kd, i] = 0.0, 0.0
            if fric and force > 0.0:  # as pin_kernel, at the moved normal and arm
                tx, ty = g1, -g0
                wt2 = (rx - dx) * ty - (ry - dy) * tx - radii[i]
                vt = tx * vx + ty * vy + wt2 * vp
                ft = -mu * force * _friction_one(vt, v_reg)[0]
                out_ft[kd, i], out_pw[kd, i] = ft, ft * vt


@njit(cache=True)
def _rim_residual(qh, vh, ql, fl, jl, jvl, pins, idx_rim, cm, weight, delta, res):
    """The rim condensation's residual R = delta - C Q(q_hub + delta) into ``res`` (J = dQ/dq
    into jl) for :func:`~flexrv.model.numerics.newton.newton_update`; returns (max|R|,
    max|delta|) weighted (psi times R_p)."""
    m = delta.shape[0]
    for r in range(m):
        ql[r] = qh[r] + delta[r]
        fl[r] = 0.0
        for c in range(m):
            jl[r, c] = 0.0
            jvl[r, c] = 0.0
    jac = m >= 0  # True, typed bool: the literal True would compile _pins_at a second time
    _pins_at(ql, vh, fl, jl, jvl, jac, pins, idx_rim)
    r1 = 0.0
    scale = 0.0
    for r in range(m):
        acc = delta[r]
        for c in range(m):
            acc -= cm[r, c] * fl[c]
        res[r] = acc
        r1 = max(r1, abs(acc) * weight[r])
        scale = max(scale, abs(delta[r]) * weight[r])
    return r1, scale


def pin_work_size(m: int) -> int:
    """Length of the rim condensation's work array (:func:`_pin_condensed_kernel`)
    for m = 3 n_discs local coordinates."""
    return 4 + NEWTON_STATE + 17 * m + 11 * m * m


@njit(cache=True)
def pin_body_kernel(q, v, f, jq, jv, jac, pack):
    """The pins' kernel with elastic disc bodies and/or the elastic housing (module
    docstring, "Disc body", "Housing"). ``pack`` (:data:`PinBodyPack`): the pin kernel's
    pack, ``disc_c`` (n_discs, 3, 3) the rim compliance of each disc (empty: rigid discs),
    ``dstate`` (n_discs, 3) the rim offsets delta (x, y, psi) of the last call (output),
    ``housing_law.compliance`` c_h, ``housing`` the housing's state (c_h, phi_h, ...;
    written), ``work`` the condensation's work array (:func:`_pin_condensed_kernel`).
    Rigid discs and a rigid housing (c_h = 0): a plain :func:`pin_kernel` call."""
    pins, cd, ch = pack.pins, pack.disc_c, pack.housing_law.compliance
    if cd.shape[0] == 0 and not ch > 0.0:
        pin_kernel(q, v, f, jq, jv, jac, pins)
        return
    _pin_condensed_kernel(q, v, f, jq, jv, jac, pins, pack.idx_rim, cd, ch, pack.dstate, pack.housing, pack.work)


#: views of the rim condensation's work array (:func:`_rim_views`, layout of :func:`pin_work_size`):
#: st, the Newton state, 17 vectors (the last call's hub q, v, condensed force and rim offsets, the
#: hub state, the local rim coordinates and forces, delta, the Newton's base, step and residual,
#: a_k stacked, the condensed force, the norms' weights, the first-order prediction of this call and
#: the remaining error of the last step's first call, :func:`_rim_solve`), 11 matrices (S_q, S_v, the condensed
#: Jacobians, J, J_v, C, N, scratch, D, scratch)
RimWork = namedtuple(
    "RimWork",
    "st nw qp vp qfc dlast qh vh ql fl delta base step res av qf weight pred ext sq sv jc jvc jl jvl cm nm tmp dd t2",
)


@njit(cache=True, inline="always")
def _rim_views(wk, m):
    """The named views of the rim condensation's work array for m local coordinates."""
    mm = m * m
    st = wk[0:4]
    nw = wk[4 : 4 + NEWTON_STATE]
    o = 4 + NEWTON_STATE
    vec = wk[o : o + 17 * m].reshape((17, m))  # the layout of pin_work_size: 17 vectors, then 11 matrices
    mat = wk[o + 17 * m : o + 17 * m + 11 * mm].reshape((11, m, m))
    return RimWork(
        st, nw, vec[0], vec[1], vec[2], vec[3], vec[4], vec[5], vec[6], vec[7], vec[8], vec[9], vec[10], vec[11],
        vec[12], vec[13], vec[14], vec[15], vec[16], mat[0], mat[1], mat[2], mat[3], mat[4], mat[5], mat[6], mat[7],
        mat[8], mat[9], mat[10],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _add_condensed(f, jq, jv, jac, idx, qf, jc, jvc):
    """Add a condensed force qf and, with ``jac``, the condensed Jacobians at idx."""
    m = qf.shape[0]
    for r in range(m):
        f[idx[r]] += qf[r]
    if jac:
        for r in range(m):
            for c in range(m):
                jq[idx[r], idx[c]] += jc[r, c]
                jv[idx[r], idx[c]] += jvc[r, c]


@njit(cache=True, inline="always")
def _rim_reuse(dstate, w):
    """(valid, same): whether the previous call's predictor may be used (st[VALID] set and the
    rim offsets not set from outside since) and whether this call is at its hub state."""
    qh, st, dlast, qp, vh, vp = w.qh, w.st, w.dlast, w.qp, w.vh, w.vp
    m = qh.shape[0]
    valid = st[VALID] > 0.0
    if valid:
        for r in range(m):
            if dstate[r // 3, r % 3] != dlast[r]:  # rim offsets set from outside: a fresh start from them
                valid = False
    same = valid
    if valid:
        for r in range(m):
            if qh[r] != qp[r] or vh[r] != vp[r]:
                same = False
                break
    return valid, same


@njit(cache=True, inline="always")
def _rim_start(dstate, cd, ch, r_p, w):
    """The rim compliance C = blockdiag(C_d,k) + c_h A A^T at the hub centres, the
    Newton's start delta (the stored rim offsets) and its norms' weights."""
    qh, av, cm, delta, weight = w.qh, w.av, w.cm, w.delta, w.weight
    m = qh.shape[0]
    nd = m // 3
    for kd in range(nd):
        av[3 * kd], av[3 * kd + 1], av[3 * kd + 2] = -qh[3 * kd + 1], qh[3 * kd], 1.0
    for r in range(m):
        for c in range(m):
            cm[r, c] = ch * av[r] * av[c]
    if cd.shape[0] > 0:
        for kd in range(nd):
            for r in range(3):
                for c in range(3):
                    cm[3 * kd + r, 3 * kd + c] += cd[kd, r, c]
    for r in range(m):
        delta[r] = dstate[r // 3, r % 3]
        weight[r] = r_p if r % 3 == 2 else 1.0  # max|R|, max|delta| over x, y [m] and psi times R_p


@njit(cache=True, inline="always")
def _rim_solve(valid, first, pins, idx_rim, ch, dstate, hs, w):
    """The rim Newton (numerics.newton): R = delta - C Q(q_hub + delta), dR/d(delta) =
    I - C J, from the first-order predictor of the previous call (``valid``); the last
    correction applied linearised (condensed force into w.qf, offsets into dstate) and the
    housing's rotation and rim offsets into hs. Returns the pins' torque on the discs.

    A step's first call (``first``: the call with the Jacobian, which an integrator updating its
    iteration matrix every step makes at each step's predictor; later calls of the step come
    after small Newton corrections) moves the hub by a whole step's motion, and the first-order
    predictor then leaves an error e quadratic in that motion. Consecutive steps move alike,
    so the start adds the previous first call's error scaled by the square of the ratio of the
    two motions' sizes (max|dq_hub| weighted, 1 at a constant speed and step): e_n+1 ~ e_n to
    first order in the change between steps. A start farther than a tenth of max|delta| is not
    used (numerics.newton.apply_predictor); the Newton converges to the same tolerance from any
    start.

    Quadratic stop: after a full Newton step the residual is K |step|^2 (K the local
    constant of the quadratic convergence); each call that evaluates after a full step
    measures K = max|R| / max|step|^2 and carries K_est = max(K, K_est / 2) in the work
    flags (st[QUAD_EST]; 0 after a reset: the rule off until measured). Where K_est
    max|step|^2 <= QUAD_SAFETY tol the next evaluation would only confirm the tolerance: the
    iteration stops at the point just evaluated, its correction applied linearised leaves
    an error of that order (N R_next, N = (I - C J)^-1), and the records of that evaluation
    are moved to the corrected pose (:func:`_shift_records`, first order in the correction
    of ~1e-12 m: remainder ~1e-21 m in the gaps). Measured on rv40e's call sequence: 1.54
    pin-kernel evaluations per call (the residual stop alone: 2.41); recorded outputs
    against the history pass 1e-10 (rv40e) and 3.4e-10 (rv221) of their largest values
    (tests/test_rigspeed.py: 2e-9; 4e-6 without the records' move)."""
    qh, delta, step, qf, av, sq, qp, sv = w.qh, w.delta, w.step, w.qf, w.av, w.sq, w.qp, w.sv
    vh, vp, weight, nw, ql, fl, jl, jvl = w.vh, w.vp, w.weight, w.nw, w.ql, w.fl, w.jl, w.jvl
    cm, res, base, tmp, nm, dlast, qfc, st = w.cm, w.res, w.base, w.tmp, w.nm, w.dlast, w.qfc, w.st
    m = qh.shape[0]
    nd = m // 3
    pred, ext = w.pred, w.ext
    moved = 0.0  # max|q_hub - q_hub,prev| weighted: the size of this call's motion
    if valid:  # first-order predictor from the previous call (numerics.newton: trusted within a tenth)
        for r in range(m):
            acc = 0.0
            for c in range(m):
                acc += sq[r, c] * (qh[c] - qp[c]) + sv[r, c] * (vh[c] - vp[c])
            step[r] = acc
            pred[r] = delta[r] + acc
            moved = max(moved, abs(qh[r] - qp[r]) * weight[r])
        if first and st[EXT_MOVE] > 0.0:  # a step's first call: the last one's remaining error, scaled
            ratio = (moved / st[EXT_MOVE]) ** 2
            for r in range(m):
                step[r] += ratio * ext[r]
        apply_predictor(delta, step, weight)
    newton_start(nw)
    k_est, k_new, full, early = st[QUAD_EST], 0.0, 0.0, False
    while True:  # the rim Newton (numerics.newton): R = delta - C Q(q_hub + delta), dR/d(delta) = I - C J
        r1, scale = _rim_residual(qh, vh, ql, fl, jl, jvl, pins, idx_rim, cm, weight, delta, res)
        if full > 0.0:  # after a full Newton step: its quadratic constant K = max|R| / max|step|^2
            k_new = max(k_new, r1 / (full * full))
        if newton_update(nw, r1, scale, delta, base, step, res, cm, jl, -1.0, tmp, nm, *RIM_NEWTON):
            break
        full = 0.0
        if nw[LAM] == 1.0:  # a full step from the point just evaluated (base)
            for r in range(m):
                full = max(full, abs(step[r]) * weight[r])
            if k_est > 0.0 and k_est * full * full <= QUAD_SAFETY * nw[TOL]:  # the next evaluation would only confirm
                for r in range(m):
                    delta[r] = base[r]
                early = True
                break
    if k_new > 0.0:
        st[QUAD_EST] = max(k_new, QUAD_DECAY * k_est)
    if early:  # the records to the pose of the linearised correction
        for r in range(m):
            tmp[0, r] = -step[r]
        _shift_records(pins, ql, vh, tmp[0])
    # the last Newton correction c = -N R, linearised (O(|R|^2) exact): the result is smooth in q and v
    # down to round-off, below the Newton tolerance (a finite difference of 1e-10 sees the condensation)
    s = 0.0
    for r in range(m):
        acc = fl[r]
        for c in range(m):
            acc -= jl[r, c] * step[c]
        qf[r] = acc
        s += av[r] * acc  # torque of the pins on the discs about the axis = -(their torque on the housing)
    if ch > 0.0:
        phi = -ch * s  # housing rotation phi_h = c_h M_h, M_h = -s
        hs[HOUSING_PHI] = phi
        for kd in range(nd):
            hs[HOUSING_RIM + 2 * kd] = -phi * av[3 * kd]
            hs[HOUSING_RIM + 2 * kd + 1] = -phi * av[3 * kd + 1]
    for r in range(m):
        delta[r] -= step[r]
        dstate[r // 3, r % 3] = delta[r]
        dlast[r] = delta[r]
        qfc[r] = qf[r]
    if first:  # the first-order predictor's error at this step's motion, for the next step's first call
        st[EXT_MOVE] = moved if valid else 0.0
        for r in range(m):
            ext[r] = delta[r] - pred[r]
    return s


@njit(cache=True, inline="always")
def _rim_tangent(ch, s, w):
    """The condensed Jacobians J N (I + D) and (I + J N C) J_v into w.jc, w.jvc, and the
    predictor's sensitivities S_q = C dQ_eff/dq + D, S_v = C dQ_eff/dv with the hub
    state they belong to (also the repeated state's result)."""
    qh, dd, tmp, t2, av, qf, nm, jl = w.qh, w.dd, w.tmp, w.t2, w.av, w.qf, w.nm, w.jl
    jc, cm, jvl, jvc, sq, sv, qp, vp = w.jc, w.cm, w.jvl, w.jvc, w.sq, w.sv, w.qp, w.vp
    vh, st = w.vh, w.st
    m = qh.shape[0]
    nd = m // 3
    for r in range(m):
        for c in range(m):
            dd[r, c] = 0.0
    if ch > 0.0:  # a_k moves with the hub centre: D = d(C Q)/dq at fixed Q
        for kd in range(nd):
            cx, cy = 3 * kd, 3 * kd + 1
            dd[cy, cx] += ch * s
            dd[cx, cy] -= ch * s
            for r in range(m):
                dd[r, cx] += ch * av[r] * qf[cy]
                dd[r, cy] -= ch * av[r] * qf[cx]
    for r in range(m):
        for c in range(m):
            tmp[r, c] = dd[r, c] + (1.0 if r == c else 0.0)
    matmul_small(nm, tmp, t2)
    matmul_small(jl, t2, jc)  # J N (I + D)
    matmul_small(cm, jvl, tmp)
    matmul_small(nm, tmp, t2)
    matmul_small(jl, t2, jvc)
    for r in range(m):
        for c in range(m):
            jvc[r, c] += jvl[r, c]  # (I + J N C) J_v
    matmul_small(cm, jc, sq)
    matmul_small(cm, jvc, sv)
    for r in range(m):
        qp[r], vp[r] = qh[r], vh[r]
        for c in range(m):
            sq[r, c] += dd[r, c]
    st[VALID] = 1.0


@njit(cache=True)
def _pin_condensed_kernel(q, v, f, jq, jv, jac, pins, idx_rim, cd, ch, dstate, hs, wk):
    """The rim condensation (module docstring, "Disc body", "Housing"): the pins act
    on the rim poses q_r = q_hub + delta of all discs, delta = C(q) Q(q_r, v), C =
    blockdiag(C_d,k) + c_h A A^T (cd empty: rigid disc bodies; c_h = 0: the discs
    decouple), A stacking a_k = (-y_k, x_k, 1) at the hub centres. Local Newton on
    the 3 n_discs offsets, R = delta - C Q, dR/d(delta) = I - C J (J = dQ/dq from
    :func:`pin_kernel`, evaluated on the local rim coordinates: no n x n arrays),
    step halving on max|R| (x, y [m]; psi times R_p), the last correction applied
    linearised (Q + J d(delta), exact to O(|R|^2)). Condensed Jacobians, with N =
    (I - C J)^-1: dQ_eff/dq = J N (I + D) (= (I - J C)^-1 J (I + D)), D = d(C Q)/dq
    at fixed Q = c_h (dA/dq (A^T Q) + A (dA/dq)^T Q) (a_k follows the hub centre),
    and dQ_eff/dv = (I + J N C) J_v (= (I - J C)^-1 J_v; the rim's velocity is the
    hub's: the rate of delta is left out of the contact damping). phi_h = c_h M_h,
    M_h = -A^T Q into hs[HOUSING_PHI], the housing's part -phi_h a_k of each rim offset into
    hs[HOUSING_RIM + 2 k], hs[HOUSING_RIM + 2 k + 1].

    Cost per call (in a run the pin-kernel evaluations are the
    condensation's cost): the Newton starts from the first-order predictor delta_0 =
    delta_prev + S_q dq_hub + S_v dv_hub with the previous call's condensed
    sensitivities S_q = d(delta)/dq = C dQ_eff/dq + D, S_v = C dQ_eff/dv (used where
    the predicted change is below a tenth of max|delta|; larger jumps, e.g. a solver
    restarting elsewhere, start from delta_prev), so the start's residual is second
    order in the state change; it stops when max|R| <= tol (1e-10 of
    max|delta|, at least 1e-15 m) or, after a full Newton step, where the quadratic
    convergence measured in the element's earlier calls predicts the next residual below
    a hundredth of tol (:func:`_rim_solve`); the per-contact records are then moved to the
    pose of the linearised correction (:func:`_shift_records`), so they belong to the
    returned force in either case. Measured in a rv40e run: after a
    Newton correction of the solver (|dq| ~ 1e-7) the predicted start is within ~3e-12
    m of the solution (from delta_prev: ~5e-8), after a time step's rigid motion
    (|dq| ~ 1.6e-4) within ~4e-9 m. A call at exactly the previous call's hub state (q,
    v) and rim offsets (the solver's Jacobian after its residual) adds the stored
    result of that call without evaluating anything. ``wk`` (:func:`pin_work_size`)
    holds st = (valid, -, -, -) (numerics.newton.VALID), the last call's hub
    q and v, its condensed force, its rim offsets, S_q, S_v, the condensed Jacobians and
    the scratch arrays; st[VALID] = 0 (reset, history pass) starts from dstate without
    the predictor.

    Phases (each its own compiled function): the work array's views (:func:`_rim_views`),
    the reuse test (:func:`_rim_reuse`), the compliance and start (:func:`_rim_start`),
    the Newton (:func:`_rim_solve`), the condensed Jacobians (:func:`_rim_tangent`)."""
    idx = pins.idx
    m = 3 * pins.profile.shape[0]
    w = _rim_views(wk, m)
    qh, vh = w.qh, w.vh
    for r in range(m):
        qh[r], vh[r] = q[idx[r]], v[idx[r]]
    valid, same = _rim_reuse(dstate, w)
    if same:  # the previous call's state: its result
        _add_condensed(f, jq, jv, jac, idx, w.qfc, w.jc, w.jvc)
        return
    _rim_start(dstate, cd, ch, pins.law.pin_circle_radius, w)
    s = _rim_solve(valid, jac, pins, idx_rim, ch, dstate, hs, w)
    _rim_tangent(ch, s, w)
    _add_condensed(f, jq, jv, jac, idx, w.qf, w.jc, w.jvc)


@njit(cache=True)
def pin_penetrated(gap, calls, limit) -> bool:
    """Whether the last call's smallest pin gap is a penetration beyond ``limit`` [m] (no call
    yet: never): the pins' per-step check (:meth:`PinContacts.check`, and :func:`pin_step_check`
    in the compiled integrator's steps)."""
    if calls[0] == 0:
        return False
    low = np.inf
    for kd in range(gap.shape[0]):
        for i in range(gap.shape[1]):
            low = min(low, gap[kd, i])
    return low < -limit


@njit(cache=True)
def pin_step_check(pack) -> int:
    """The pins' per-step check on their pack (:data:`PinBodyPack`) after an accepted step of the
    compiled integrator (:mod:`flexrv.model.core.registry`): 1 if :func:`pin_penetrated`, else 0."""
    pins = pack.pins
    return 1 if pin_penetrated(pins.gap, pins.calls, pins.law.penetration_limit) else 0


@functools.lru_cache(maxsize=64)
def _medial_radii(z_rp: int, radius: float, eccentricity: float, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """The medial radius of the pin-centre curve C at ``samples`` points phi_i = i lobe /
    samples of one lobe (lobe = 2 pi / (z_rp - 1)), on its outer side (the side of n_out,
    positive signed distance) and its inner side [m]: the radius of the largest disc
    tangent to C at C_i on that side that contains no other point of C (the distance to the
    medial axis along the normal), min_j |C_j - C_i|^2 / (2 (C_j - C_i) . n_i) over the
    points C_j on that side, taken over the lobe and its two neighbours on each side (the
    curve repeats per lobe; farther parts are > 10 mm away). Unscaled samples: the callers
    take 0.9 of them for the sampling (400 and 2,000 samples agree to 1e-3)."""
    from flexrv.geometry.cycloid import center_curve

    lobe = 2.0 * np.pi / (z_rp - 1)
    phi_i = np.arange(samples) * (lobe / samples)
    phi_j = -2.0 * lobe + np.arange(5 * samples) * (lobe / samples)
    ci, d1, _ = center_curve(phi_i, z_rp, radius, eccentricity)
    cj, _, _ = center_curve(phi_j, z_rp, radius, eccentricity)
    t = d1 / np.linalg.norm(d1, axis=1)[:, None]
    n_out = np.stack([-t[:, 1], t[:, 0]], axis=1)  # as the closest-point iteration's n_out
    d = cj[None, :, :] - ci[:, None, :]
    dd = np.einsum("ijk,ijk->ij", d, d)
    dn = np.einsum("ijk,ik->ij", d, n_out)
    same = np.abs(phi_j[None, :] - phi_i[:, None]) > 0.5 * lobe / samples  # j is not point i itself
    out = []
    for side in (1.0, -1.0):
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where((side * dn > 0.0) & same, dd / (2.0 * side * dn), np.inf)
        out.append(np.min(r, axis=1))
    return out[0], out[1]


def _curve_reach(z_rp: int, radius: float, eccentricity: float) -> tuple[float, float]:
    """Lower estimates of the reach of the pin-centre curve C on its outer and its inner
    side [m]: the smallest medial radius on that side (:func:`_medial_radii`) times 0.9 for
    the sampling (rv40e: 71.4 um outside, at the lobe's tip, and 4.6 mm inside). A point P
    at distance d below the reach on the side of a foot point found by a local search has
    that foot point as its nearest point on C (the ball of radius d about P lies in the
    empty tangent ball), so the pin kernel trusts a warm-started closest point only then."""
    r_out, r_in = _medial_radii(z_rp, radius, eccentricity)
    return 0.9 * float(np.min(r_out)), 0.9 * float(np.min(r_in))


def _outer_ball_table(z_rp: int, radius: float, eccentricity: float) -> np.ndarray:
    """Lower estimates of the outer medial radius over the bins [phi_j, phi_j+1) of one lobe
    (the samples of :func:`_medial_radii`) [m]: 0.9 of the smaller of the bin's two end
    samples (below the cap the radius changes by at most 4.5 % per sample on rv40e, 6.5 % on
    rv221, most near the valley phi = 0), at most a twentieth of the lobe's arc (radius x lobe),
    so that the tangent ball (of diameter below a tenth of a lobe's arc) meets no part of C
    beyond the two neighbouring lobes the samples were taken over. Rv221: 47 um in the
    valley, the cap 0.88 mm over two thirds of the lobe. The pin kernel's tangent-ball bound
    (:func:`_ball_record`) takes the bin of each foot point."""
    r_out, _ = _medial_radii(z_rp, radius, eccentricity)
    lobe = 2.0 * np.pi / (z_rp - 1)
    return np.minimum(0.9 * np.minimum(r_out, np.roll(r_out, -1)), 0.05 * radius * lobe)


# ---------------------------------------------------------------- the element's parameters from the design
@dataclass(frozen=True)
class PinParameters:
    """The pin contacts' parameters (SI). Built by :func:`pin_parameters`."""

    drive: DriveParameters
    pin_circle_radius: float
    pin_radius: float  #: nominal pin radius [m]
    pins: np.ndarray  #: (z_rp, 2) as-built pin centres in the housing frame [m]
    pin_radii: np.ndarray  #: (z_rp,) as-built pin radii [m]
    disc_profile: np.ndarray  #: (n_discs, 3) as-built (d_radius [m], d_pin_radius [m], d_rotation [rad]) per disc
    #: (n_discs, H, 3) (order [-], amplitude [m], phase [rad]): material added along the profile normal,
    #: delta(phi) = sum A cos(order phi + phase), phi the curve parameter; it reduces the pin gap by
    #: delta(phi*) at the contact's foot point
    profile_harmonics: np.ndarray
    pin_k: float  #: pin-contact constant [N/m^e] (:func:`pin_parameters`)
    pin_exponent: float
    pin_c_max: float  #: impact law's full damping [N s/m]
    pin_penetration_limit: float  #: [m] a run stops as failed beyond it
    pin_friction: float  #: effective pin coefficient min(mu_pin_disc, mu_pin_seat) [-] (0: friction off)
    #: (n_discs, 3, 3) compliance of each disc's rim pose (x, y, psi) relative to its hub per unit pin force
    #: (:func:`flexrv.fem.disc.rim_compliance`); (0, 3, 3): rigid discs (``second_stage.disc_body_model``)
    disc_compliance: np.ndarray
    #: torsional compliance of the pin housing about the axis [rad/(N m)]
    #: (:func:`flexrv.analysis.torsional.housing_model_compliance`, design ``housing.body_model``); 0: rigid
    housing_compliance: float


def pin_parameters(reducer, drive: DriveParameters) -> PinParameters:
    """The pin contacts' parameters. The pin law's constant: the pin path = pin-disc contact,
    pin seat and pin bending in series (:func:`flexrv.analysis.pin_load.pin_contact_constant`,
    the one constant of every model, matched at the largest pin load of the analytic
    distribution: the only pin-load analysis of the model); the impact law takes the seeds'
    exponent, matched to the Hertz line law at the damping depth. The as-built pins and
    profiles (:func:`flexrv.geometry.as_built.as_built`), the elastic discs (FE build only if
    condensed, :func:`flexrv.model.bodies.body_compliance_matrix`) and the housing's compliance."""
    from flexrv.analysis.pin_load import pin_contact_constant
    from flexrv.analysis.torsional import housing_model_compliance
    from flexrv.contact.hertz import LINE_EXPONENT
    from flexrv.contact.laws import effective_pin_friction
    from flexrv.model.bodies import body_compliance_matrix

    ss, ct = reducer.second_stage, reducer.contact
    k_line = pin_contact_constant(reducer).k
    if ct.pin_law == "hertz_line":
        k, exponent = k_line, LINE_EXPONENT
    else:
        k, exponent = k_line * drive.contact_depth ** (LINE_EXPONENT - ct.impact_exponent), ct.impact_exponent
    ab = drive.as_built
    return PinParameters(
        drive=drive,
        pin_circle_radius=ss.pin_circle_radius,
        pin_radius=ss.pin_radius,
        pins=ab.pins,
        pin_radii=ab.pin_radii,
        disc_profile=ab.disc_profile,
        profile_harmonics=ab.profile_harmonics,
        pin_k=k,
        pin_exponent=exponent,
        pin_c_max=ct.pin_max_damping_Ns_per_m,
        pin_penetration_limit=ct.pin_penetration_limit_um * M_PER_UM,
        pin_friction=effective_pin_friction(ct.pin_friction_coefficient, ct.pin_seat_friction_coefficient)
        if ct.friction
        else 0.0,
        disc_compliance=body_compliance_matrix(reducer, "cycloid_disc"),
        housing_compliance=housing_model_compliance(reducer),
    )


class PinContacts(KernelGroup):
    """Pin–disc contacts (members: disc0..n_discs-1)."""

    name = "pins"
    kind = "pins"
    summary_rows = (
        SummaryRow("min_pin_gap_m", "m", "smallest pin-profile gap (negative: penetration)", "pin_gap", "min"),
    )
    kernel = staticmethod(pin_body_kernel)
    step_check = staticmethod(pin_step_check)
    friction_outputs = ("pin_friction_power",)
    failure_message = "pin gap: closest-point iteration did not converge"

    parameters = staticmethod(pin_parameters)

    def __init__(self, params: PinParameters, restart_every: int = 500):
        p = self.params = params
        d = p.drive
        self.nd = d.n_discs
        self.members = tuple(f"disc{k}" for k in range(self.nd))
        self.pins = np.ascontiguousarray(p.pins, dtype=float)  # (z, 2) actual centres
        self.radii = np.ascontiguousarray(p.pin_radii, dtype=float)
        self.profile = np.ascontiguousarray(p.disc_profile, dtype=float).reshape(self.nd, 3)
        self.harmonics = np.ascontiguousarray(p.profile_harmonics, dtype=float).reshape(self.nd, -1, 3)
        self.k, self.e = p.pin_k, p.pin_exponent
        self.c_max, self.depth = p.pin_c_max, d.contact_depth
        reach = [
            _curve_reach(int(d.z_rp), float(p.pin_circle_radius + self.profile[kd, 0]), float(d.eccentricity))
            for kd in range(self.nd)
        ]
        max_step, tol, max_iter, cos_half = closest_point_settings(d.z_rp, p.pin_circle_radius)
        self.law = PinLaw.of(
            z_rp=d.z_rp,
            pin_circle_radius=p.pin_circle_radius,
            pin_radius=p.pin_radius,
            eccentricity=d.eccentricity,
            k=p.pin_k,
            exponent=p.pin_exponent,
            c_max=p.pin_c_max,
            depth=d.contact_depth,
            max_step=max_step,
            tol=tol,
            max_iter=max_iter,
            cos_half=cos_half,
            mu=p.pin_friction,
            v_reg=d.friction_velocity,
            penetration_limit=p.pin_penetration_limit,
        )
        #: per disc the pin-centre curve's reach outside, inside [m] (:func:`_curve_reach`)
        self.reach = np.array(reach, dtype=float).reshape(self.nd, 2)
        #: per disc the outer medial radius over one lobe's bins [m] (:func:`_outer_ball_table`)
        self.ball = np.array(
            [
                _outer_ball_table(int(d.z_rp), float(p.pin_circle_radius + self.profile[kd, 0]), float(d.eccentricity))
                for kd in range(self.nd)
            ]
        )
        self.mu, self.v_reg = p.pin_friction, d.friction_velocity
        z = len(self.pins)
        self.phi = np.full((self.nd, z), np.nan)
        self.gap, self.force = np.zeros((self.nd, z)), np.zeros((self.nd, z))
        self.nx, self.ny, self.rxn = np.zeros((self.nd, z)), np.zeros((self.nd, z)), np.zeros((self.nd, z))
        self.ft, self.pw = np.zeros((self.nd, z)), np.zeros((self.nd, z))  # friction force on the disc, its power
        #: per (disc, pin) the normal's turn h and the harmonics' b of the last evaluation (_shift_records)
        self.curv = np.full((self.nd, z, 2), np.nan)
        self.last = np.full((self.nd, z, LAST_SIZE), np.nan)
        self.pose = np.full((self.nd, 3), np.nan)
        #: the solver's warm starts: a cold restart every restart_every calls, provably open pins skipped
        self.control = PinControl.of(restart_every=restart_every, skip_open=True)
        self.calls = np.zeros(1, dtype=np.int64)  # pin-kernel calls
        self.failures = np.zeros(1, dtype=np.int64)  # closest-point failures
        #: (n_discs, 3, 3) rim compliance of the elastic discs (pin_body_kernel); (0, 3, 3): rigid discs
        self.disc_c = np.ascontiguousarray(p.disc_compliance, dtype=float)
        if self.disc_c.size and self.disc_c.shape != (self.nd, 3, 3):
            raise ValueError(f"disc_compliance has shape {self.disc_c.shape}, expected {(self.nd, 3, 3)}")
        if not self.disc_c.size:
            self.disc_c = np.zeros((0, 3, 3))
        self.dstate = np.zeros((self.nd, 3))
        #: housing (module docstring, "Housing"): (c_h [rad/(N m)], phi_h [rad], per disc the housing's part
        #: -phi_h a_k of the rim offset (x, y) [m]); c_h = 0: rigid housing
        c_h = float(p.housing_compliance)
        if not (np.isfinite(c_h) and c_h >= 0.0):
            raise ValueError(f"housing_compliance = {c_h!r} must be a finite compliance >= 0 [rad/(N m)]")
        self.housing_law = HousingLaw.of(compliance=c_h)
        self.hstate = np.zeros(2 + 2 * self.nd)
        self.hstate[0] = c_h
        #: the rim condensation's work array (_pin_condensed_kernel: predictor state, last result, scratch)
        self.work = np.zeros(pin_work_size(3 * self.nd))
        self.idx_rim = np.arange(3 * self.nd, dtype=np.int64)  # the pin kernel on the local rim coordinates

    @property
    def elastic_housing(self) -> bool:
        return self.housing_law.compliance > 0.0

    @property
    def elastic_discs(self) -> bool:
        return self.disc_c.shape[0] > 0

    def pack(self, idx, history=False):
        phi, last, pose, control, calls, failures = (
            self.phi,
            self.last,
            self.pose,
            self.control,
            self.calls,
            self.failures,
        )
        if history:  # post-processing: cold start at the first sample, then warm; every gap exact
            phi, last, pose = (np.full_like(a, np.nan) for a in (self.phi, self.last, self.pose))
            control = PinControl.of(restart_every=0, skip_open=False)
            calls, failures = np.ones(1, dtype=np.int64), np.zeros(1, dtype=np.int64)
            # the rim Newton too starts cold (delta = 0) at the first sample: the history pass and a group's
            # own evaluate of the same samples are then bit-identical whatever ran before. In place: dstate is
            # also the rim record (record_sources "rim"); the solver's next call merely starts its Newton cold
            self.dstate[:] = 0.0
            self.work[VALID] = 0.0  # the solver's predictor state no longer matches dstate
        work = np.zeros_like(self.work) if history else self.work
        pins = PinPack(
            idx=idx,
            law=self.law,
            reach=self.reach,
            ball=self.ball,
            pins=self.pins,
            radii=self.radii,
            profile=self.profile,
            harm=self.harmonics,
            phi=phi,
            last=last,
            pose=pose,
            gap=self.gap,
            force=self.force,
            nx=self.nx,
            ny=self.ny,
            rxn=self.rxn,
            ft=self.ft,
            pw=self.pw,
            curv=self.curv,
            control=control,
            calls=calls,
            failures=failures,
        )
        return PinBodyPack(
            pins=pins,
            disc_c=self.disc_c,
            dstate=self.dstate,
            housing_law=self.housing_law,
            housing=self.hstate,
            idx_rim=self.idx_rim,
            work=work,
        )

    @staticmethod
    def empty_pack():
        return empty_pack(PinBodyPack)

    def failure_counter(self, pack):
        return pack.pins.failures

    @property
    def min_gap(self) -> float:
        return float(self.gap.min()) if self.calls[0] > 0 else np.inf

    def record_sources(self):
        return {
            "gap": self.gap,
            "force": self.force,
            "nx": self.nx,
            "ny": self.ny,
            "rxn": self.rxn,
            "ft": self.ft,
            "pw": self.pw,
            "rim": self.dstate,
            "housing": self.hstate,
        }

    def outputs(self, t, rec):
        f = rec["force"]
        dims = ("time", "disc", "pin")
        out = (
            {}
            if self.mu <= 0.0
            else {
                "pin_friction_force": Output(
                    rec["ft"], dims, "N", "pin-disc friction force on the disc along t = z x n"
                ),
                "pin_friction_power": Output(
                    -rec["pw"].sum(axis=-1),
                    ("time", "disc"),
                    "W",
                    "power dissipated by the pin-disc friction of each disc (>= 0)",
                ),
            }
        )
        out = out | {
            "pin_force": Output(f, dims, "N", "pin-disc contact force"),
            "pin_gap": Output(
                rec["gap"],
                dims,
                "m",
                "signed pin-profile gap (negative = penetration); "
                "of a pin proved open by the solver: a positive lower bound",
            ),
            "pins_in_contact": Output((f > 0).sum(axis=-1), ("time", "disc"), "1", "pins in contact per disc"),
            "disc_pin_torque": Output(
                -(f * rec["rxn"]).sum(axis=-1),
                ("time", "disc"),
                "N m",
                "torque of the pin normal forces on each disc about its centre (the friction "
                "forces' torque not included)",
            ),
            "housing_pin_torque": Output(
                self._housing_torque(rec),
                ("time", "disc"),
                "N m",
                "torque of each disc's pin forces (normal and friction) on the housing about the axis",
            ),
        }
        if self.elastic_housing:
            hs = rec["housing"]
            out["housing_rotation"] = Output(
                hs[..., 1],
                ("time",),
                "rad",
                "elastic rotation phi_h of the pin housing about the axis (c_h times the pins' torque on the housing)",
            )
        if self.elastic_discs:
            rim = rec["rim"]
            if "housing" in rec and self.elastic_housing:  # the disc body's part: the housing's -phi_h a_k removed
                hs = rec["housing"]
                rim = rim.copy()
                rim[..., 2] += hs[..., 1][..., None]
                rim[..., 0] -= hs[..., 2::2]
                rim[..., 1] -= hs[..., 3::2]
            out["disc_rim_rotation"] = Output(
                rim[..., 2],
                ("time", "disc"),
                "rad",
                "rotation of each disc's tooth region (rim) relative to its crank "
                "holes (hub): the elastic disc body's twist",
            )
            out["disc_rim_offset"] = Output(
                np.hypot(rim[..., 0], rim[..., 1]),
                ("time", "disc"),
                "m",
                "translation of each disc's rim relative to its hub",
            )
        return out

    def _housing_torque(self, rec):
        """Torque of the pin forces on the housing about the axis: the normal force -F n
        through the pin centre P, and the friction force -f_t t (t = z x n) at the contact
        point X = P - r n (a massless pin passes its contact force on to the housing),
        (X x t)_z = P . n - r."""
        f, nx, ny, px, py = rec["force"], rec["nx"], rec["ny"], self.pins[:, 0], self.pins[:, 1]
        torque = f * (px * ny - py * nx)
        if "ft" in rec:
            torque = torque - rec["ft"] * (px * nx + py * ny - self.radii)
        return torque.sum(axis=-1)

    def reset(self):
        """Forget the closest-point warm start and the call counter."""
        self.phi[:] = np.nan
        self.last[:] = np.nan
        self.pose[:] = np.nan
        self.calls[0] = 0
        self.gap[:] = 0.0
        self.dstate[:] = 0.0
        self.hstate[1:] = 0.0
        self.work[:] = 0.0

    def check(self) -> str | None:
        limit = self.law.penetration_limit  # design contact.pin_penetration_limit_um
        if pin_penetrated(self.gap, self.calls, limit):
            return f"pin-disc penetration {-self.min_gap * 1e6:.3g} um exceeds the physical limit {limit * 1e6:.3g} um"
        return None
