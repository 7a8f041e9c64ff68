"""Involute (first-stage) mesh stiffness and damping: ISO 6336-1 method B,
:cite:`seed000,seed001`, and a time-varying mesh-stiffness function for the dynamic model.

Units: SI inside (stiffness per face width in N/m^2 = N/(m m)); ISO 6336 writes
c' in N/(mm um) = 1e9 N/m^2 (converted by :data:`ISO_UNIT`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.errors import InputError
from flexrv.geometry.involute import base_radius, contact_ratio, tooth_pair_count, working_center_distance

#: 1 N/(mm um) in N/m^2.
ISO_UNIT = 1e9

#: ISO 6336-1:2006 Table (method B) coefficients C1..C9 of q' [mm um / N].
ISO6336_C = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)

#: Correction factor C_M for the theoretical single-tooth stiffness (ISO 6336-1).
C_M = 0.8


def min_flexibility(z1, z2, x1, x2):
    """Minimum tooth flexibility q' [mm um/N] of a spur pair, ISO 6336-1 method B:

    q' = C1 + C2/z_n1 + C3/z_n2 + C4 x1 + C5 x1/z_n1 + C6 x2 + C7 x2/z_n2 + C8 x1^2 + C9 x2^2

    (z_n = z for spur gears; ISO's validity range x1 >= x2, -0.5 <= x1 + x2 <= 2).
    Returned in ISO units (mm um/N) as ISO tabulates it."""
    c1, c2, c3, c4, c5, c6, c7, c8, c9 = ISO6336_C
    z1, z2, x1, x2 = (np.asarray(v, dtype=float) for v in (z1, z2, x1, x2))
    return c1 + c2 / z1 + c3 / z2 + c4 * x1 + c5 * x1 / z1 + c6 * x2 + c7 * x2 / z2 + c8 * x1**2 + c9 * x2**2


def basic_rack_factor(alpha, dedendum_coefficient: float = 1.25):
    """C_B = [1 + 0.5 (1.2 - h_fP/m)] [1 - 0.02 (20 deg - alpha_n)] (ISO 6336-1:2006,
    alpha in degrees inside the bracket); 0.975 for the standard 20 deg rack with
    h_fP = 1.25 m."""
    alpha_deg = np.degrees(np.asarray(alpha, dtype=float))
    return (1.0 + 0.5 * (1.2 - dedendum_coefficient)) * (1.0 - 0.02 * (20.0 - alpha_deg))


def single_tooth_stiffness(
    z1,
    z2,
    x1,
    x2,
    alpha,
    helix_angle: float = 0.0,
    c_m: float = C_M,
    c_r: float = 1.0,
    dedendum_coefficient: float = 1.25,
):
    """Single tooth-pair stiffness c' [N/m^2, per unit face width] (ISO 6336-1 method B):

    c'_th = 1/q',  c' = c'_th C_M C_R C_B cos(beta),

    C_M = 0.8, C_R = 1 (solid gear blanks), C_B from the basic rack
    (:func:`basic_rack_factor`). :cite:`seed001` writes c' = 1/q (= c'_th, without the
    corrections); the corrected value is the ISO one.
    """
    q = min_flexibility(z1, z2, x1, x2)
    c_th = 1.0 / q
    return c_th * c_m * c_r * basic_rack_factor(alpha, dedendum_coefficient) * np.cos(helix_angle) * ISO_UNIT


def mesh_stiffness_per_width(c_single, eps_alpha):
    """Mean mesh stiffness c_gamma_alpha = (0.75 eps_alpha + 0.25) c' [N/m^2]
    (ISO 6336-1 eq. for c_gamma_alpha; :cite:`seed000,seed001`)."""
    return (0.75 * np.asarray(eps_alpha, dtype=float) + 0.25) * np.asarray(c_single, dtype=float)


def mesh_damping(k, r1, r2, j1, j2, damping_ratio):
    """Mesh damping c12 [N s/m] along the line of action:

    c12 = 2 xi sqrt(k m_e),  m_e = J1 J2 / (J1 r2^2 + J2 r1^2)

    (equivalent mass of the two gears' rotations reduced to the line of action;
    Kahraman & Singh, J. Sound Vib. 1991; Parker et al. 2000). r1, r2 are the
    BASE radii [m] (the line-of-action lever arms), J1, J2 the rotational inertias
    [kg m^2]. :cite:`seed001` writes c12 = 2 xi sqrt(k r1^2 r2^2 J1 J2 / (r1^2 J1 + r2^2 J2)),
    which has units kg m^2/s (a torsional damping, with the radii misplaced);
    for J_i = m_i r_i^2 our form reduces to 2 xi sqrt(k m1 m2/(m1 + m2)) as it must.
    """
    k, r1, r2, j1, j2 = (np.asarray(v, dtype=float) for v in (k, r1, r2, j1, j2))
    if np.any(k < 0) or np.any(j1 <= 0) or np.any(j2 <= 0):
        raise InputError("mesh_damping: k must be >= 0 and J1, J2 > 0")
    m_e = j1 * j2 / (j1 * r2**2 + j2 * r1**2)
    return 2.0 * np.asarray(damping_ratio) * np.sqrt(k * m_e)


def time_varying_mesh_stiffness(phase, k_single, eps_alpha, ramp: float = 0.0):
    """Time-varying mesh stiffness k(phase) [N/m] over the mesh cycle.

    Rectangular alternation consistent with eps_alpha and ISO 6336-1: one base
    pitch (phase in [0, 1)) has a double-contact zone of length eps_alpha - 1
    (phase in [0, eps_alpha - 1)) and a single-contact zone of 2 - eps_alpha.
    The single zone has k_s = c' b; the double zone 1.75 k_s. Then the cycle
    mean is k_s (2 - eps + 1.75 (eps - 1)) = (0.75 eps + 0.25) c' b = c_gamma b,
    i.e. exactly ISO's mean mesh stiffness (the 1.75 expresses that in the double
    zone both pairs sit near tip/root where each is ~0.875 c'). With ``ramp`` > 0
    each jump becomes a linear ramp of that phase width centred on the jump
    (trapezoidal, same mean; ramp < min(eps - 1, 2 - eps)).

    Parameters
    ----------
    phase : array_like
        Mesh phase [-] = (path along the line of action / p_bt), any real value
        (taken mod 1); 0 = engagement of a new tooth pair.
    k_single : float
        Single-pair stiffness c' b [N/m].
    eps_alpha : float
        Transverse contact ratio, 1 <= eps_alpha < 2.
    ramp : float
        Width of the transition ramps in phase units [-].
    """
    eps = float(eps_alpha)
    if not 1.0 <= eps < 2.0:
        raise InputError(f"eps_alpha = {eps_alpha} must lie in [1, 2) for the single/double model")
    w1 = eps - 1.0
    if ramp < 0 or (ramp > 0 and ramp >= min(w1, 1.0 - w1)):
        raise InputError(f"ramp = {ramp} must lie in [0, {min(w1, 1.0 - w1):.4g})")
    ph = np.mod(np.asarray(phase, dtype=float), 1.0)
    if ramp == 0.0:
        pairs = tooth_pair_count(ph, eps)
        return np.where(pairs == 2, 1.75, 1.0) * k_single
    flat = np.ascontiguousarray(ph).ravel()
    return _RAMPED_ARRAY(flat, float(k_single), eps, float(ramp)).reshape(ph.shape)


def _mesh_stiffness_ramped(phase, k_single, eps_alpha, ramp):
    """k(phase) of :func:`time_varying_mesh_stiffness` with ramps (ramp > 0) at one
    phase (numba-compiled; the gear-stage kernel calls it per mesh): the
    box-filtered square wave, level = (F(ph + h) - F(ph - h)) / ramp with h =
    ramp/2 and F the cumulative length of double-contact zone, F(x) = floor(x) w1
    + clip(frac(x), 0, w1), w1 = eps_alpha - 1; k = k_single (1 + 0.75 level)."""
    w1 = eps_alpha - 1.0
    ph = phase % 1.0
    h = 0.5 * ramp
    hi, lo = ph + h, ph - h
    f_hi = np.floor(hi) * w1 + min(max(hi - np.floor(hi), 0.0), w1)
    f_lo = np.floor(lo) * w1 + min(max(lo - np.floor(lo), 0.0), w1)
    return k_single * (1.0 + 0.75 * (f_hi - f_lo) / ramp)


def _ramped_array(phase, k_single, eps_alpha, ramp):
    out = np.empty(phase.shape[0])
    for i in range(phase.shape[0]):
        out[i] = mesh_stiffness_ramped(phase[i], k_single, eps_alpha, ramp)
    return out


mesh_stiffness_ramped = njit(cache=True)(_mesh_stiffness_ramped)
_RAMPED_ARRAY = njit(cache=True)(_ramped_array)


@dataclass(frozen=True)
class InvoluteStage:
    """First-stage numbers (SI).

    eps_alpha [-]; q_min [mm um/N] (ISO units); c_th, c_single, c_gamma [N/m^2];
    k12 [N/m] mean mesh stiffness c_gamma b; k_single [N/m] = c' b; c12 [N s/m];
    base radii rb_sun, rb_planet [m]; center_distance a_w [m];
    planet_inertia [kg m^2] (solid-disc estimate of the planet alone).
    """

    eps_alpha: float
    q_min: float
    c_th: float
    c_single: float
    c_gamma: float
    k_single: float
    k12: float
    c12: float
    rb_sun: float
    rb_planet: float
    center_distance: float
    planet_inertia: float


def involute_stage(reducer) -> InvoluteStage:
    """Evaluate the first stage of a :class:`flexrv.design.model.Reducer`.

    J1 = ``inertia.input_shaft_inertia_kg_m2`` (sun + input shaft); J2 = planet as
    a solid steel disc of pitch radius and face width, rho pi b r^4 / 2 (estimate;
    the crankshaft's inertia is not included)."""
    fs = reducer.first_stage
    z1, z2, m, al, x1, x2, b = (
        fs.sun_teeth,
        fs.planet_teeth,
        fs.module,
        fs.pressure_angle,
        fs.sun_profile_shift,
        fs.planet_profile_shift,
        fs.face_width,
    )
    eps = float(contact_ratio(z1, z2, m, al, x1, x2))
    q = float(min_flexibility(z1, z2, x1, x2))
    c_s = float(single_tooth_stiffness(z1, z2, x1, x2, al))
    c_g = float(mesh_stiffness_per_width(c_s, eps))
    rb1, rb2 = float(base_radius(z1, m, al)), float(base_radius(z2, m, al))
    rho = reducer.material("gears").density_kg_m3
    j2 = rho * math.pi * b * (0.5 * m * z2) ** 4 / 2.0
    k12 = c_g * b
    c12 = float(mesh_damping(k12, rb1, rb2, reducer.inertia.input_shaft_inertia_kg_m2, j2, fs.mesh_damping_ratio))
    return InvoluteStage(
        eps_alpha=eps,
        q_min=q,
        c_th=ISO_UNIT / q,
        c_single=c_s,
        c_gamma=c_g,
        k_single=c_s * b,
        k12=k12,
        c12=c12,
        rb_sun=rb1,
        rb_planet=rb2,
        center_distance=float(working_center_distance(z1, z2, m, al, x1, x2)),
        planet_inertia=j2,
    )
