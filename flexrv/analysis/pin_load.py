"""Load distribution over the pins of a cycloid disc with profile modifications
and manufacturing errors (initial-clearance method).

Method (Li Lixing / Blanche & Yang 1989 / Chen et al. 2008 "initial clearance"
approach, here with EXACT clearances of the actual pins to the actual profile):

1. Put the disc at its nominal (conjugate) pose for the crank angle and turn it
   about its centre (crank bearings rigid; their compliance is in
   :mod:`flexrv.analysis.torsional`) to the no-load pose beta0 where the first pin
   touches: gap_i(beta) is evaluated exactly at every step
   (:func:`flexrv.geometry.as_built.as_built_pin_gap`: actual pin centres and
   radii, the disc's modifications and profile-error harmonics) and beta0 is the
   root of min_i gap_i(beta) / l_i(beta) over the pins approaching the profile
   (Newton steps on the exact gaps until |step| < 1e-15 rad).
2. The initial normal clearance delta_i of pin i is its exact gap at beta0, along
   the contact normal n_i whose moment arm about the disc centre is
   l_i = (P_i x n_i)_z (equal to :cite:`seed000`'s r'_c sin(phi)/sqrt(1 + K^2 - 2K cos(phi))
   for the unmodified profile), both taken at beta0.
3. Under load the disc turns on by the elastic rotation beta - beta0 (of order
   1e-4 rad, so the neglected second-order term R_p (beta - beta0)^2 is below
   1 nm): the approach of pin i is w_i = l_i (beta - beta0) - delta_i.
4. F_i = K w_i^e for w_i > 0 and beta is iterated (monotone scalar root, Brent)
   until sum F_i l_i = T_disc.

Until issue 17 the clearances were linear in the WHOLE no-load rotation
(delta_i = gap_i(0) - l_i(0) beta0): exact for the equidistant modification
(beta0 ~ 1e-4 rad) but up to 0.7 um wrong at the root pins for rotation-like
modifications and errors (beta0 of a few arcmin), which changed the maximum pin
force by several per cent.

Contact law (documented choice): ``"palmgren"`` (default) uses the lead's
:func:`flexrv.contact.hertz.line_contact_stiffness`, Q = K delta^(10/9)
(Palmgren's line-contact approach, Harris & Kotzalas 2007 eq. 6.74), which is the
physical, load-dependent law; ``"linear"`` uses :cite:`seed000`'s k_n = pi b E'/4 with
e = 1 (curvature- and load-independent, see
:func:`flexrv.geometry.cycloid.pin_stiffness_seed000`).

With zero modification all delta_i = 0, so every pin with l_i > 0 carries load:
the classic ideal result of about half the pins (z_rp/2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from flexrv.contact.hertz import LINE_EXPONENT, effective_modulus, line_contact, line_contact_stiffness
from flexrv.errors import ConvergenceError, InputError
from flexrv.geometry.as_built import as_built, as_built_pin_gap
from flexrv.geometry.cycloid import (nominal_disc_pose, pin_positions, pin_stiffness_seed000, profile_curvature_radius,
                                     to_disc_frame)


@dataclass(frozen=True)
class PinLoadResult:
    """Pin load distribution of one disc (SI; arrays over the z_rp pins, pin j at
    housing angle 2 pi j / z_rp clockwise from +y).

    torque : applied disc torque T_disc [N m]; rotation : disc rotation beta [rad]
    (signed like the torque); forces : pin forces F_i [N] (>= 0);
    clearance : initial normal clearance delta_i [m], exact, at the no-load pose
    (the disc turned by ``backlash_rotation`` to its first contact; at the nominal
    pose if pins interfere); arms : signed moment arms l_i [m] at that pose;
    approach : l_i (beta - beta0) - delta_i [m]; in_contact : bool mask; n_contact : number of
    loaded pins; max_force [N]; max_pressure : Hertz p_max of the most loaded pin [Pa];
    torsional_stiffness : dT/dbeta [N m/rad] of this disc's pin contacts;
    backlash_rotation : rotation [rad] to the first contact (lost motion from the
    modification); resultant : force of all pins on the disc (disc frame) [N];
    law, exponent, stiffness_constant : contact law used (F = K w^e).
    """

    torque: float
    rotation: float
    forces: np.ndarray
    clearance: np.ndarray
    arms: np.ndarray
    approach: np.ndarray
    in_contact: np.ndarray
    n_contact: int
    max_force: float
    max_pressure: float
    torsional_stiffness: float
    backlash_rotation: float
    resultant: np.ndarray
    law: str
    exponent: float
    stiffness_constant: float


def _law(law: str, width: float, e_eff: float):
    if law == "palmgren":
        return float(line_contact_stiffness(width, e_eff)), LINE_EXPONENT
    if law == "linear":
        return float(pin_stiffness_seed000(width, e_eff)), 1.0
    raise InputError(f"law = {law!r} must be 'palmgren' or 'linear'")


def pin_load_distribution(torque, z_rp: int, pin_circle_radius: float, pin_radius: float, eccentricity: float,
                          width: float, e_eff: float, d_radius: float = 0.0, d_pin_radius: float = 0.0,
                          d_rotation: float = 0.0, crank_angle: float = 0.0, law: str = "palmgren", *,
                          pins=None, pin_radii=None, harmonics=None) -> PinLoadResult:
    """Pin forces of one disc under the disc torque ``torque`` [N m] (see module
    docstring for the method and the laws).

    Parameters
    ----------
    torque : float
        Torque the pins must balance on this disc [N m] (either sign).
    z_rp, pin_circle_radius, pin_radius, eccentricity : nominal geometry (SI); the
        disc profile is generated by the nominal pin on the nominal pin circle.
    width : disc width b [m] (contact length).
    e_eff : Hamrock's effective modulus E' of disc and pin [Pa].
    d_radius, d_pin_radius, d_rotation : shift [m], equidistant [m] and rotation
        [rad] modifications of this disc (nominal + its errors).
    crank_angle : crank angle chi [rad] of the nominal pose
        (:func:`flexrv.geometry.cycloid.nominal_disc_pose`).
    law : "palmgren" (Q = K w^(10/9)) or "linear" (:cite:`seed000` k_n).
    pins : (z_rp, 2) actual pin centres in the housing frame [m] (default nominal).
    pin_radii : (z_rp,) actual pin radii [m] (default ``pin_radius``).
    harmonics : (H, 3) profile-error harmonics (order, amplitude [m], phase [rad])
        of this disc (:func:`flexrv.geometry.as_built.profile_deviation`).

    Raises
    ------
    InputError for non-finite torque or geometry; ConvergenceError if no rotation
    balances the torque.
    """
    torque = float(torque)
    if not np.isfinite(torque):
        raise InputError(f"torque = {torque!r} must be finite")
    if width <= 0 or e_eff <= 0:
        raise InputError(f"width = {width!r} and e_eff = {e_eff!r} must be > 0")
    k, e = _law(law, width, e_eff)
    pins_h = pin_positions(z_rp, pin_circle_radius) if pins is None else np.asarray(pins, dtype=float)
    radii = np.full(z_rp, float(pin_radius)) if pin_radii is None else np.asarray(pin_radii, dtype=float)
    if pins_h.shape != (z_rp, 2) or radii.shape != (z_rp,):
        raise InputError(f"pins must have shape ({z_rp}, 2) and pin_radii ({z_rp},), got {pins_h.shape} and {radii.shape}")
    if not (np.all(np.isfinite(pins_h)) and np.all(np.isfinite(radii)) and np.all(radii > 0)):
        raise InputError("pins and pin_radii must be finite, pin_radii > 0")
    if harmonics is not None:
        harmonics = np.asarray(harmonics, dtype=float).reshape(-1, 3)
    profile = (d_radius, d_pin_radius, d_rotation)
    center, rot = nominal_disc_pose(z_rp, eccentricity, crank_angle)
    sign = 1.0 if torque >= 0 else -1.0

    def state(beta, phi0=None):
        """Exact gaps, normals, foot points and arms with the disc turned on by
        sign * beta from the nominal pose."""
        p = to_disc_frame(pins_h, center, rot + sign * beta)
        gap, normal, phi = as_built_pin_gap(p, radii, z_rp, pin_circle_radius, pin_radius, eccentricity, profile,
                                            harmonics, phi0=phi0)
        return gap, normal, phi, p[:, 0] * normal[:, 1] - p[:, 1] * normal[:, 0]

    # no-load pose: first contact, Newton steps on the exact gaps
    gap, normal, phi, arms = state(0.0)
    tiny = 1e-9 * pin_circle_radius
    beta0 = 0.0
    for _ in range(40):
        sarm = sign * arms
        pos = sarm > tiny
        if not np.any(pos):
            raise ConvergenceError("pin_load_distribution: no pin has a positive moment arm")
        step = float(np.min(gap[pos] / sarm[pos]))
        if abs(step) <= 1e-15 + 1e-12 * abs(beta0):
            break
        beta0 += step
        gap, normal, phi, arms = state(beta0, phi0=phi if abs(step) < 1e-3 else None)
    else:
        raise ConvergenceError(f"pin_load_distribution: no-load pose not found (last step {step:.3g} rad)")
    sarm = sign * arms

    def approach(beta):
        return sarm * (beta - beta0) - gap

    def residual(beta):
        w = np.maximum(approach(beta), 0.0)
        return float(np.sum(k * w**e * sarm)) - abs(torque)

    lo = beta0 - 1e-12 - abs(beta0) * 1e-12
    if residual(lo) > 0:  # interference: pins already preloaded at beta0; search below
        step = max(abs(beta0), 1e-6)
        while residual(lo) > 0:
            lo -= step
            step *= 2
            if step > 1.0:
                raise ConvergenceError("pin_load_distribution: cannot bracket the disc rotation (preload too large)")
    hi = max(beta0, lo) + 1e-6
    step = 1e-6
    while residual(hi) < 0:
        hi += step
        step *= 2
        if step > 1.0:
            raise ConvergenceError(f"pin_load_distribution: torque {torque:g} N m not reachable")
    beta = brentq(residual, lo, hi, xtol=1e-18, rtol=4 * np.finfo(float).eps, maxiter=200)
    w = approach(beta)
    contact = w > 0
    wp = np.where(contact, w, 0.0)
    forces = k * wp**e
    with np.errstate(divide="ignore", invalid="ignore"):
        dforce = np.where(contact, k * e * wp ** (e - 1.0), 0.0)
    stiffness = float(np.sum(dforce * arms**2))
    resultant = -np.sum(forces[:, None] * normal, axis=0)
    imax = int(np.argmax(forces))
    p_max = 0.0
    if forces[imax] > 0:
        # curvature of the modified profile (the error harmonics' own curvature is neglected)
        rho = float(profile_curvature_radius(phi[imax], z_rp, pin_circle_radius, pin_radius, eccentricity,
                                             d_radius, d_pin_radius))
        r_eff = 1.0 / (1.0 / radii[imax] + 1.0 / rho)
        p_max = float(line_contact(forces[imax], width, r_eff, e_eff).p_max)
    return PinLoadResult(torque=torque, rotation=sign * beta, forces=forces, clearance=gap, arms=arms, approach=w,
                         in_contact=contact, n_contact=int(contact.sum()), max_force=float(forces[imax]),
                         max_pressure=p_max, torsional_stiffness=stiffness, backlash_rotation=sign * max(beta0, 0.0),
                         resultant=resultant, law=law, exponent=e, stiffness_constant=k)


def disc_effective_modulus(reducer) -> float:
    """E' [Pa] of the disc-pin contact of a design (Hamrock's effective modulus)."""
    d, p = reducer.material("cycloid_disc"), reducer.material("pins")
    return float(effective_modulus(d.youngs_modulus, d.poisson_ratio, p.youngs_modulus, p.poisson_ratio))


def reducer_pin_loads(reducer, output_torque: float, crank_angle: float = 0.0, law: str = "palmgren",
                      d_pin_radius: float | None = None, disc: int = 0) -> PinLoadResult:
    """Pin load distribution of disc ``disc`` of a design under the OUTPUT torque
    [N m], shared equally by the n_discs discs (rigid cranks): T_disc = T / n_discs.

    Reads the as-built geometry (:func:`flexrv.geometry.as_built.as_built`): actual
    pin centres and radii, the disc's modifications plus its errors and its
    profile-error harmonics; the disc sits at its nominal pose for the crank angle
    ``crank_angle`` + chi0_disc (disc k's eccentric leads by 2 pi k / n_discs).
    ``d_pin_radius`` overrides the design's nominal equidistant modification [m]
    (the disc's equidistant error is kept on top of it)."""
    ss = reducer.second_stage
    if not 0 <= disc < ss.n_discs:
        raise InputError(f"disc = {disc!r} must be within 0..{ss.n_discs - 1}")
    ab = as_built(reducer)
    d_radius, dr, d_rot = (float(v) for v in ab.disc_profile[disc])
    if d_pin_radius is not None:
        dr = d_pin_radius + (dr - ss.modification_equidistant)
    return pin_load_distribution(output_torque / ss.n_discs, ss.pin_count, ss.pin_circle_radius, ss.pin_radius,
                                 ss.eccentricity, ss.disc_width, disc_effective_modulus(reducer),
                                 d_radius, dr, d_rot, crank_angle + float(ab.chi0[disc]), law,
                                 pins=ab.pins, pin_radii=ab.pin_radii, harmonics=ab.profile_harmonics[disc])
