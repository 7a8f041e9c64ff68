"""Cycloid-disc geometry: pin-centre epitrochoid and the modified tooth profile.

Conventions (disc frame, origin at the disc centre, SI units): with the curve
parameter phi in [0, 2 pi) and R = R_p + dR_p (shift-modified pin circle),

    C(phi) = R (sin phi, cos phi) - a (sin(z_rp phi), cos(z_rp phi))

is the path of a pin centre relative to the disc (an epitrochoid with
z_c = z_rp - 1 lobes, |C| between R - a and R + a). The tooth profile is its inward
offset by r = r_rp + dr_rp (equidistant-modified pin radius), rotated by the
rotation modification d_delta. Sources: Litvin & Fuentes, *Gear Geometry and
Applied Theory* (2004), ch. 19; Li et al. seed 004 for the curvature formula.
"""

from __future__ import annotations

import numpy as np


def center_curve(phi, z_rp: int, radius: float, eccentricity: float):
    """Pin-centre epitrochoid C(phi) and its first two derivatives.

    Returns
    -------
    c, dc, ddc : ndarray, shape (..., 2)
        Position [m] and derivatives w.r.t. phi.
    """
    phi = np.asarray(phi, dtype=float)
    s, c = np.sin(phi), np.cos(phi)
    sz, cz = np.sin(z_rp * phi), np.cos(z_rp * phi)
    pos = np.stack([radius * s - eccentricity * sz, radius * c - eccentricity * cz], axis=-1)
    d1 = np.stack([radius * c - eccentricity * z_rp * cz, -radius * s + eccentricity * z_rp * sz], axis=-1)
    d2 = np.stack([-radius * s + eccentricity * z_rp**2 * sz, -radius * c + eccentricity * z_rp**2 * cz], axis=-1)
    return pos, d1, d2


def center_curve_curvature(phi, z_rp: int, radius: float, eccentricity: float):
    """Signed curvature kappa [1/m] of the pin-centre curve; kappa > 0 where the
    curve bends towards the disc centre (convex lobes)."""
    _, d1, d2 = center_curve(phi, z_rp, radius, eccentricity)
    cross = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
    speed = np.hypot(d1[..., 0], d1[..., 1])
    return -cross / speed**3


def min_convex_curvature_radius(z_rp: int, radius: float, eccentricity: float, samples: int = 4001) -> float:
    """Smallest radius of curvature [m] over the convex part of the pin-centre
    curve. The profile (inward offset by r_rp + dr_rp) is free of undercut only if
    that offset is smaller than this radius."""
    phi = np.linspace(0.0, 2.0 * np.pi / (z_rp - 1), samples)
    kappa = center_curve_curvature(phi, z_rp, radius, eccentricity)
    convex = kappa > 0
    if not np.any(convex):
        return float("inf")
    return float(1.0 / kappa[convex].max())


def profile_points(phi, z_rp: int, pin_circle_radius: float, pin_radius: float, eccentricity: float,
                   d_radius: float = 0.0, d_pin_radius: float = 0.0, d_rotation: float = 0.0):
    """Points [m] of the modified disc profile, shape (..., 2).

    The profile is the inward offset of the pin-centre curve (pin circle
    R_p + dR_p) by r_rp + dr_rp, rotated by d_rotation about the disc centre.
    """
    pos, d1, _ = center_curve(phi, z_rp, pin_circle_radius + d_radius, eccentricity)
    tangent = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
    # clockwise traversal: inward normal is the tangent rotated by -90 deg
    inward = np.stack([tangent[..., 1], -tangent[..., 0]], axis=-1)
    pts = pos + (pin_radius + d_pin_radius) * inward
    if d_rotation:
        cr, sr = np.cos(d_rotation), np.sin(d_rotation)
        pts = np.stack([cr * pts[..., 0] - sr * pts[..., 1], sr * pts[..., 0] + cr * pts[..., 1]], axis=-1)
    return pts
