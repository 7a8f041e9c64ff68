"""Ball–raceway contacts of an angular contact ball bearing row, vectorised over balls.

Model (Harris & Kotzalas 2007, ch. 7 "groove curvature centre" formulation, written
for free balls): each ball is a point mass at its centre b. A raceway is
represented, at the ball's azimuth psi, by its groove curvature centre c (on a
circle of radius R_c at axial position z_c of the ring, moved by the ring's rigid
motion and by the ring's elastic raceway displacement at psi). The ball touches
the groove (torus of radius f D) when |b - c| = (f - 1/2) D, so the contact
approach is

    delta = |b - c| - (f - 1/2) D          (> 0: Hertzian overlap),

acting along n = (b - c)/|b - c|: the ring pushes the ball with -Q n and the ball
pushes the ring with +Q n at c. The contact angle is the angle of n to the radial
plane. Q(delta, delta_dot) is any normal law (Hertz Q = K delta^1.5 with the
impact-law damping, or the EHL-corrected law); it is passed in as a function.

The circumferential (rolling) direction carries no normal force; the cage keeps
the balls' azimuths (a separate spring in the model). The groove centre moves with
psi tangentially only, so its dependence on the ball's position is neglected in
the Jacobian (second order in the normal force).

Why point masses: at carrier speeds of ~7-15 r/min the ball spin (~ d_m/D times
the cage speed) makes gyroscopic moments and centrifugal forces ~1e-3 N, five
orders below the ball loads, and friction is neglected, so ball rotation does not
enter the normal contact problem.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from flexrv.contact.hertz import point_contact_stiffness
from flexrv.contact.laws import impact_force

#: A normal law maps (approach delta [m], approach rate [m/s]) -> (Q, dQ/ddelta, dQ/ddelta_rate).
NormalLaw = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class HertzLaw:
    """Dry Hertz point contact Q = K delta^1.5 with the seeds' impact-law damping
    (a :data:`NormalLaw`; its parameters are readable, e.g. by the compiled row
    kernel :mod:`flexrv.model.bearing_kernel`)."""

    k: float
    c_max: float = 0.0
    depth: float = 1e-6

    def __call__(self, delta, delta_rate):
        q, dq_dgap, dq_drate = impact_force(-delta, -delta_rate, self.k, 1.5, self.c_max, self.depth)
        return q, -dq_dgap, -dq_drate


def hertz_law(k: float | np.ndarray, c_max: float = 0.0, depth: float = 1e-6) -> NormalLaw:
    """Dry Hertz point contact Q = K delta^1.5 with the seeds' impact-law damping."""
    return HertzLaw(k, c_max, depth)


@dataclass(frozen=True)
class RowContactGeometry:
    """Groove-centre loci and Hertz constants of one bearing row (SI, row frame:
    z = 0 at the nominal ball-centre plane).

    Attributes
    ----------
    inner_center_radius, inner_center_z : locus of the inner groove curvature centres.
    outer_center_radius, outer_center_z : locus of the outer groove curvature centres.
    inner_offset, outer_offset : (f - 1/2) D [m].
    k_inner, k_outer : Hertz constants [N/m^1.5] at the nominal contact angle.
    ball_radius_pitch : nominal ball-centre radius d_m/2 [m].
    side : axial sign s of the outer contact (back-to-back: s = -sign(z_row)).
    """

    inner_center_radius: float
    inner_center_z: float
    outer_center_radius: float
    outer_center_z: float
    inner_offset: float
    outer_offset: float
    k_inner: float
    k_outer: float
    ball_radius_pitch: float
    side: float

    @classmethod
    def from_bearing(cls, geom, e_eff: float, side: float, preload: float = 0.0) -> "RowContactGeometry":
        """From a :class:`flexrv.geometry.bearing.BallBearingGeometry`.

        ``preload`` (> 0) moves the inner groove centres axially away from the
        outer ones by that amount (axial interference of the row)."""
        si = geom.ring_section("inner", side)
        so = geom.ring_section("outer", side)
        rx_i, ry_i, rx_o, ry_o = geom.contact_radii()
        d = geom.ball_diameter
        return cls(
            inner_center_radius=si.groove_center_r,
            inner_center_z=si.groove_center_z + side * preload,
            outer_center_radius=so.groove_center_r,
            outer_center_z=so.groove_center_z,
            inner_offset=(geom.inner_conformity - 0.5) * d,
            outer_offset=(geom.outer_conformity - 0.5) * d,
            k_inner=float(point_contact_stiffness(rx_i, ry_i, e_eff)),
            k_outer=float(point_contact_stiffness(rx_o, ry_o, e_eff)),
            ball_radius_pitch=0.5 * geom.pitch_diameter,
            side=side,
        )

    def groove_centers(self, azimuth, ring: str) -> np.ndarray:
        """Undeformed groove-centre positions (N,3) at the given azimuths (ring frame)."""
        azimuth = np.asarray(azimuth, dtype=float)
        if ring == "inner":
            r, z = self.inner_center_radius, self.inner_center_z
        else:
            r, z = self.outer_center_radius, self.outer_center_z
        return np.stack([r * np.cos(azimuth), r * np.sin(azimuth), np.full_like(azimuth, z)], axis=-1)


@dataclass
class ContactState:
    """Forces and kinematics of one ring's contacts with all balls (arrays over balls).

    force_ball : (N,3) force of this ring on each ball [N].
    load : (N,) normal load Q [N]; approach : (N,) delta [m]; normal : (N,3) unit n.
    contact_angle : (N,) angle of n to the radial plane [rad].
    stiffness : (N,3,3) d force_ball / d ball position [N/m] (also = d force_ring / d c).
    damping : (N,3,3) d force_ball / d ball velocity [N s/m].
    """

    force_ball: np.ndarray
    load: np.ndarray
    approach: np.ndarray
    normal: np.ndarray
    contact_angle: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray


def raceway_contacts(ball_pos, ball_vel, center_pos, center_vel, offset: float, law: NormalLaw) -> ContactState:
    """Contacts of N balls with one raceway given the groove centres at the balls'
    azimuths (all arrays (N,3), same frame).

    Returns the force of the ring on each ball and its Jacobians; the force on the
    ring at the groove centre is ``-state.force_ball``.
    """
    d = np.asarray(ball_pos, dtype=float) - center_pos
    length = np.linalg.norm(d, axis=-1)
    n = d / length[:, None]
    delta = length - offset
    rate = np.einsum("ij,ij->i", n, np.asarray(ball_vel, dtype=float) - center_vel)
    q, dq_dd, dq_dr = law(delta, rate)
    force = -q[:, None] * n
    nn = n[:, :, None] * n[:, None, :]
    eye = np.eye(3)[None]
    stiffness = -(dq_dd[:, None, None] * nn + (q / length)[:, None, None] * (eye - nn))
    damping = -dq_dr[:, None, None] * nn
    radial = np.hypot(n[:, 0], n[:, 1])
    angle = np.arctan2(np.abs(n[:, 2]), radial)
    return ContactState(
        force_ball=force, load=q, approach=delta, normal=n, contact_angle=angle, stiffness=stiffness, damping=damping
    )


def solve_ball_positions(
    row: RowContactGeometry,
    inner_centers,
    outer_centers,
    law_inner: NormalLaw,
    law_outer: NormalLaw,
    ball_pos0=None,
    external=None,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> tuple[np.ndarray, ContactState, ContactState]:
    """Quasi-static positions of the balls between given groove centres.

    Each ball's meridian-plane position is found by a vectorised damped Newton
    iteration on the force balance f_inner + f_outer + f_external = 0. Balls that
    touch neither raceway are placed midway between the groove centres (a cage
    holds them).

    Returns
    -------
    ball_pos, inner_state, outer_state
    """
    inner_centers = np.asarray(inner_centers, dtype=float)
    outer_centers = np.asarray(outer_centers, dtype=float)
    n = len(inner_centers)
    if ball_pos0 is None:
        # start touching the inner groove, on the line of the two centres
        axis = outer_centers - inner_centers
        pos = inner_centers + axis / np.linalg.norm(axis, axis=-1, keepdims=True) * row.inner_offset
    else:
        pos = np.array(ball_pos0, dtype=float)
    ext = np.zeros((n, 3)) if external is None else np.asarray(external, dtype=float)
    zero = np.zeros((n, 3))
    for _ in range(max_iter):
        si = raceway_contacts(pos, zero, inner_centers, zero, row.inner_offset, law_inner)
        so = raceway_contacts(pos, zero, outer_centers, zero, row.outer_offset, law_outer)
        residual = si.force_ball + so.force_ball + ext
        jac = si.stiffness + so.stiffness
        # regularise balls with no contact (singular Jacobian) with a weak spring to the start
        weak = 1e-6 * max(row.k_inner, row.k_outer) * 1e-3
        jac = jac - weak * np.eye(3)[None]
        step = np.linalg.solve(jac, -residual[..., None])[..., 0]
        # limit the step to a fraction of the contact scale to stay robust
        scale = 0.2 * min(row.inner_offset, row.outer_offset)
        norm = np.linalg.norm(step, axis=-1, keepdims=True)
        step = np.where(norm > scale, step * scale / norm, step)
        pos = pos + step
        if np.max(np.abs(residual)) < tol * max(1.0, np.max(np.abs(si.load))) and np.max(norm) < 1e-15 + 1e-9 * scale:
            break
    si = raceway_contacts(pos, zero, inner_centers, zero, row.inner_offset, law_inner)
    so = raceway_contacts(pos, zero, outer_centers, zero, row.outer_offset, law_outer)
    return pos, si, so
