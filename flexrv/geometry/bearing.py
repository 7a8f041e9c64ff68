"""Geometry of the main bearing: a back-to-back (DB) pair of angular contact ball
bearings, SI units, pure functions.

Meridian-plane conventions (r radial, z axial), one row at a time, origin at the
row's ball-centre plane: the ball centre sits at (r, z) = (d_m/2, 0). The unit
contact direction of a row is n = (cos alpha, s sin alpha): the outer-race contact
is at ball centre + (D/2) n, the inner-race contact at ball centre - (D/2) n.
Groove (torus) curvature centres lie on the same line (Harris & Kotzalas 2007,
ch. 2): outer centre = ball centre - (f_o - 1/2) D n, inner centre = ball centre
+ (f_i - 1/2) D n; their distance is A = (f_i + f_o - 1) D.

Back-to-back: the contact lines meet the axis outside the pair span, which puts
the outer contact of each row on the side facing the other row, i.e.
s = -sign(z_row) with the rows at z = -/+ row_spacing/2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexrv.units import M_PER_MM, M_PER_UM

#: Radial offset of the ring lands (shoulders) from the pitch circle, as a
#: fraction of the ball diameter: inner land at d_m/2 - 0.25 D, outer at d_m/2 + 0.25 D.
LAND_OFFSET = 0.25


@dataclass(frozen=True)
class RingSection:
    """Meridian section of one ring of one row (SI).

    Attributes
    ----------
    r_inner, r_outer : radial extent of the plain ring before the groove is cut [m].
    width : axial width [m] (ring spans z in [-width/2, width/2] about the row plane).
    groove_center_r, groove_center_z : torus centre of the groove [m].
    groove_radius : torus tube radius f D [m].
    contact_r, contact_z : nominal contact point on the raceway [m].
    fit : which cylindrical face is the fit surface ("bore" for the inner ring,
        "outer" for the outer ring).
    """

    r_inner: float
    r_outer: float
    width: float
    groove_center_r: float
    groove_center_z: float
    groove_radius: float
    contact_r: float
    contact_z: float
    fit: str


@dataclass(frozen=True)
class BallBearingGeometry:
    """Main-bearing geometry in SI units (see module docstring for conventions)."""

    ball_diameter: float
    pitch_diameter: float
    ball_count: int
    contact_angle: float
    inner_conformity: float
    outer_conformity: float
    bore_diameter: float
    outer_diameter: float
    ring_width: float
    row_spacing: float
    axial_preload: float

    @classmethod
    def from_design(cls, main_bearing) -> "BallBearingGeometry":
        """Build from a :class:`flexrv.design.model.MainBearing`."""
        mb = main_bearing
        return cls(
            ball_diameter=mb.ball_diameter_mm * M_PER_MM,
            pitch_diameter=mb.pitch_diameter_mm * M_PER_MM,
            ball_count=mb.ball_count,
            contact_angle=math.radians(mb.contact_angle_deg),
            inner_conformity=mb.inner_conformity,
            outer_conformity=mb.outer_conformity,
            bore_diameter=mb.inner_ring_bore_diameter_mm * M_PER_MM,
            outer_diameter=mb.outer_ring_outer_diameter_mm * M_PER_MM,
            ring_width=mb.ring_width_mm * M_PER_MM,
            row_spacing=mb.row_spacing_mm * M_PER_MM,
            axial_preload=mb.axial_preload_um * M_PER_UM,
        )

    # ------------------------------------------------------------ basic sizes
    @property
    def curvature_center_distance(self) -> float:
        """A = (f_i + f_o - 1) D [m], distance of the groove curvature centres."""
        return (self.inner_conformity + self.outer_conformity - 1.0) * self.ball_diameter

    @property
    def diametral_clearance(self) -> float:
        """Free diametral clearance P_d [m] that gives the nominal contact angle
        at zero load: cos alpha0 = 1 - P_d/(2A) (Harris & Kotzalas 2007, eq. 2.19)."""
        return 2.0 * self.curvature_center_distance * (1.0 - math.cos(self.contact_angle))

    @property
    def gamma(self) -> float:
        """gamma = D cos(alpha) / d_m [-]."""
        return self.ball_diameter * math.cos(self.contact_angle) / self.pitch_diameter

    def row_positions(self) -> np.ndarray:
        """Axial positions of the two rows' ball-centre planes [m]."""
        return np.array([-0.5 * self.row_spacing, 0.5 * self.row_spacing])

    def row_sides(self) -> np.ndarray:
        """Axial sign s of the outer contact of each row (back-to-back)."""
        return -np.sign(self.row_positions())

    def ball_mass(self, density: float) -> float:
        """Mass of one ball [kg]."""
        return density * math.pi * self.ball_diameter**3 / 6.0

    # ------------------------------------------------------------ curvature
    def contact_radii(self, alpha=None):
        """Effective radii (rx, ry) of the inner and outer ball–raceway contacts [m].

        Harris & Kotzalas (2007) eqs. 2.27–2.34, rolling direction x:
        1/rx_i = 2/D + 2 cos a / (d_m - D cos a),   1/ry_i = 2/D - 1/(f_i D),
        1/rx_o = 2/D - 2 cos a / (d_m + D cos a),   1/ry_o = 2/D - 1/(f_o D).

        Parameters
        ----------
        alpha : array_like, optional
            Contact angle(s) [rad]; the nominal angle if omitted.

        Returns
        -------
        rx_i, ry_i, rx_o, ry_o : ndarray
        """
        a = self.contact_angle if alpha is None else np.asarray(alpha, dtype=float)
        d, dm = self.ball_diameter, self.pitch_diameter
        ca = np.cos(a)
        rx_i = 1.0 / (2.0 / d + 2.0 * ca / (dm - d * ca))
        rx_o = 1.0 / (2.0 / d - 2.0 * ca / (dm + d * ca))
        ry_i = np.broadcast_to(1.0 / (2.0 / d - 1.0 / (self.inner_conformity * d)), np.shape(rx_i)).copy()
        ry_o = np.broadcast_to(1.0 / (2.0 / d - 1.0 / (self.outer_conformity * d)), np.shape(rx_o)).copy()
        return rx_i, ry_i, rx_o, ry_o

    # ------------------------------------------------------------ kinematics
    def cage_speed(self, omega_inner, omega_outer, alpha=None):
        """Cage (ball orbital) angular speed [rad/s] for pure rolling:
        w_c = [w_i (1 - g) + w_o (1 + g)] / 2, g = D cos a / d_m (Harris, ch. 8)."""
        a = self.contact_angle if alpha is None else alpha
        g = self.ball_diameter * np.cos(a) / self.pitch_diameter
        return 0.5 * (np.asarray(omega_inner) * (1.0 - g) + np.asarray(omega_outer) * (1.0 + g))

    def entrainment_speed(self, omega_inner, omega_outer, alpha=None):
        """Mean rolling (entrainment) speed u [m/s] at both ball contacts for pure
        rolling: u = (d_m/4)(1 - g^2)|w_i - w_o| (Hamrock 1994, ch. 24)."""
        a = self.contact_angle if alpha is None else alpha
        g = self.ball_diameter * np.cos(a) / self.pitch_diameter
        return 0.25 * self.pitch_diameter * (1.0 - g**2) * np.abs(np.asarray(omega_inner) - omega_outer)

    # ------------------------------------------------------------ ring sections
    def ring_section(self, ring: str, side: float = 1.0) -> RingSection:
        """Meridian section of the inner or outer ring of a row with outer-contact
        side ``side`` (+1 or -1), in that row's frame (ball centre at z = 0).

        The plain ring spans bore/2 .. d_m/2 - 0.25 D (inner) or
        d_m/2 + 0.25 D .. OD/2 (outer) over the ring width; the groove is a torus of
        tube radius f D about the groove curvature centre, so the raceway contact
        angle is the nominal one.
        """
        d, rm = self.ball_diameter, 0.5 * self.pitch_diameter
        ca, sa = math.cos(self.contact_angle), side * math.sin(self.contact_angle)
        if ring == "inner":
            f = self.inner_conformity
            cr, cz = rm + (f - 0.5) * d * ca, (f - 0.5) * d * sa
            return RingSection(
                r_inner=0.5 * self.bore_diameter,
                r_outer=rm - LAND_OFFSET * d,
                width=self.ring_width,
                groove_center_r=cr,
                groove_center_z=cz,
                groove_radius=f * d,
                contact_r=rm - 0.5 * d * ca,
                contact_z=-0.5 * d * sa,
                fit="bore",
            )
        if ring == "outer":
            f = self.outer_conformity
            cr, cz = rm - (f - 0.5) * d * ca, -(f - 0.5) * d * sa
            return RingSection(
                r_inner=rm + LAND_OFFSET * d,
                r_outer=0.5 * self.outer_diameter,
                width=self.ring_width,
                groove_center_r=cr,
                groove_center_z=cz,
                groove_radius=f * d,
                contact_r=rm + 0.5 * d * ca,
                contact_z=0.5 * d * sa,
                fit="outer",
            )
        raise ValueError(f"ring must be 'inner' or 'outer', got {ring!r}")

    def groove_bottom_radius(self, ring: str) -> float:
        """Radius [m] of the deepest point of the groove (towards the fit)."""
        sec = self.ring_section(ring)
        if ring == "inner":
            return sec.groove_center_r - sec.groove_radius
        return sec.groove_center_r + sec.groove_radius
