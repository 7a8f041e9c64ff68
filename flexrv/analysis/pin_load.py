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
   (Newton steps on the exact gaps until a step moves the pins by less than the
   gaps' resolution, :data:`GAP_RESOLUTION`; an unmodified profile is degenerate
   there: every pin touches at once).
2. The initial normal clearance delta_i of pin i is its exact gap at beta0, along
   the contact normal n_i whose moment arm about the disc centre is
   l_i = (P_i x n_i)_z (equal to :cite:`seed000`'s r'_c sin(phi)/sqrt(1 + K^2 - 2K cos(phi))
   for the unmodified profile), both taken at beta0.
3. Under load the disc turns on by the elastic rotation beta - beta0 (of order
   1e-4 rad, so the neglected second-order term R_p (beta - beta0)^2 is below
   1 nm): the approach of pin i is w_i = l_i (beta - beta0) - delta_i.
4. F_i = K w_i^e for w_i > 0 and beta is iterated (monotone scalar root, Brent)
   until sum F_i l_i = T_disc.

Why the clearances are not linearised in the whole no-load rotation
(delta_i = gap_i(0) - l_i(0) beta0): that is exact for the equidistant modification
(beta0 ~ 1e-4 rad) but up to 0.7 um wrong at the root pins for rotation-like
modifications and errors (beta0 of a few arcmin), which changes the maximum pin
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
from flexrv.geometry.cycloid import (
    nominal_disc_pose,
    pin_positions,
    pin_stiffness_seed000,
    profile_curvature_radius,
    to_disc_frame,
)
from flexrv.units import M_PER_MM


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


#: resolution of the exact pin gaps [m]: the closest-point iteration accepts a foot point whose
#: first-order residual is below 1e-12 m (:func:`flexrv.geometry.cycloid.pin_gap`); the
#: no-load pose is converged when its last rotation step moves the pins by less than this
GAP_RESOLUTION = 1e-12
#: pins whose moment arm is below this fraction of the largest arm do not define the no-load pose
#: (they carry at most this fraction of a pin's torque per unit force)
FIRST_CONTACT_ARM_FRACTION = 0.02


def pin_load_distribution(
    torque,
    z_rp: int,
    pin_circle_radius: float,
    pin_radius: float,
    eccentricity: float,
    width: float,
    e_eff: float,
    d_radius: float = 0.0,
    d_pin_radius: float = 0.0,
    d_rotation: float = 0.0,
    crank_angle: float = 0.0,
    law: str = "palmgren",
    *,
    pins=None,
    pin_radii=None,
    harmonics=None,
    stiffness_constant: float | None = None,
) -> PinLoadResult:
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
    stiffness_constant : K [N/m^(10/9)] of the whole pin path for the palmgren law
        (:func:`pin_contact_constant`: disc contact, pin seat and pin bending in
        series); default the disc contact alone, :func:`flexrv.contact.hertz.line_contact_stiffness`.

    Raises
    ------
    InputError for non-finite torque or geometry; ConvergenceError if no rotation
    balances the torque.
    """
    torque = float(torque)
    k, e, pins_h, radii, harmonics = _checked_inputs(
        torque, z_rp, pin_circle_radius, pin_radius, width, e_eff, law, pins, pin_radii, harmonics, stiffness_constant
    )
    profile = (d_radius, d_pin_radius, d_rotation)
    center, rot = nominal_disc_pose(z_rp, eccentricity, crank_angle)
    sign = 1.0 if torque >= 0 else -1.0

    def state(beta, phi0=None):
        """Exact gaps, normals, foot points and arms with the disc turned on by
        sign * beta from the nominal pose."""
        p = to_disc_frame(pins_h, center, rot + sign * beta)
        gap, normal, phi = as_built_pin_gap(
            p, radii, z_rp, pin_circle_radius, pin_radius, eccentricity, profile, harmonics, phi0=phi0
        )
        return gap, normal, phi, p[:, 0] * normal[:, 1] - p[:, 1] * normal[:, 0]

    beta0, (gap, normal, phi, arms) = _no_load_pose(state, sign, z_rp, pin_circle_radius, crank_angle)
    sarm = sign * arms
    beta = _balancing_rotation(k, e, sarm, gap, beta0, torque)
    w = sarm * (beta - beta0) - gap
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
        rho = float(
            profile_curvature_radius(
                phi[imax], z_rp, pin_circle_radius, pin_radius, eccentricity, d_radius, d_pin_radius
            )
        )
        r_eff = 1.0 / (1.0 / radii[imax] + 1.0 / rho)
        p_max = float(line_contact(forces[imax], width, r_eff, e_eff).p_max)
    return PinLoadResult(
        torque=torque,
        rotation=sign * beta,
        forces=forces,
        clearance=gap,
        arms=arms,
        approach=w,
        in_contact=contact,
        n_contact=int(contact.sum()),
        max_force=float(forces[imax]),
        max_pressure=p_max,
        torsional_stiffness=stiffness,
        backlash_rotation=sign * max(beta0, 0.0),
        resultant=resultant,
        law=law,
        exponent=e,
        stiffness_constant=k,
    )


def _checked_inputs(torque, z_rp, pin_circle_radius, pin_radius, width, e_eff, law, pins, pin_radii, harmonics, k_path):
    """The law's constant and exponent and the actual pins, radii and harmonics of
    :func:`pin_load_distribution`, checked (InputError naming what is wrong)."""
    if not np.isfinite(torque):
        raise InputError(f"torque = {torque!r} must be finite")
    if width <= 0 or e_eff <= 0:
        raise InputError(f"width = {width!r} and e_eff = {e_eff!r} must be > 0")
    k, e = _law(law, width, e_eff)
    if k_path is not None:
        if law != "palmgren" or not (np.isfinite(k_path) and k_path > 0):
            raise InputError(f"stiffness_constant = {k_path!r} needs law 'palmgren' and a value > 0")
        k = float(k_path)
    pins_h = pin_positions(z_rp, pin_circle_radius) if pins is None else np.asarray(pins, dtype=float)
    radii = np.full(z_rp, float(pin_radius)) if pin_radii is None else np.asarray(pin_radii, dtype=float)
    if pins_h.shape != (z_rp, 2) or radii.shape != (z_rp,):
        raise InputError(
            f"pins must have shape ({z_rp}, 2) and pin_radii ({z_rp},), got {pins_h.shape} and {radii.shape}"
        )
    if not (np.all(np.isfinite(pins_h)) and np.all(np.isfinite(radii)) and np.all(radii > 0)):
        raise InputError("pins and pin_radii must be finite, pin_radii > 0")
    if harmonics is not None:
        harmonics = np.asarray(harmonics, dtype=float).reshape(-1, 3)
    return k, e, pins_h, radii, harmonics


def _no_load_pose(state, sign: float, z_rp: int, pin_circle_radius: float, crank_angle: float):
    """The no-load rotation beta0 of first contact (Newton steps on the exact gaps of
    ``state(beta, phi0)``) and the state there."""
    gap, normal, phi, arms = state(0.0)
    overlap = -float(np.min(gap))  # at the nominal pose
    tiny = 1e-9 * pin_circle_radius
    beta0 = 0.0
    for _ in range(40):
        sarm = sign * arms
        # pins that the rotation moves towards the profile; a pin near the line of centres
        # (arm -> 0) defines no rotation: its gap over its arm is round-off (or, under an
        # interference fit, a step of radians), so the pose comes from the pins with a real arm
        pos = sarm > max(tiny, FIRST_CONTACT_ARM_FRACTION * float(np.max(sarm)))
        if not np.any(pos):
            raise ConvergenceError("pin_load_distribution: no pin has a positive moment arm")
        step = float(np.min(gap[pos] / sarm[pos]))
        if abs(step) * pin_circle_radius <= GAP_RESOLUTION or abs(step) <= 1e-15 + 1e-12 * abs(beta0):
            # the step moves no pin by more than the gaps are resolved: first contact found. In the
            # degenerate pose of an unmodified profile every pin touches at once and the gaps are
            # round-off of either sign, so the steps never fall below an absolute 1e-15 rad
            return beta0, (gap, normal, phi, arms)
        beta0 += step
        if abs(beta0) > 0.25 * 2.0 * np.pi / z_rp:
            raise InputError(
                f"pin_load_distribution: no no-load pose within a quarter pin pitch ({np.degrees(beta0):.3g} deg "
                f"reached at crank angle {crank_angle:g} rad): the modifications or errors make the disc overlap "
                "the pins on both sides (interference fit, largest overlap at the nominal pose "
                f"{1e6 * overlap:.3g} um); "
                "the initial-clearance method needs a clearance somewhere"
            )
        gap, normal, phi, arms = state(beta0, phi0=phi if abs(step) < 1e-3 else None)
    raise ConvergenceError(f"pin_load_distribution: no-load pose not found (last step {step:.3g} rad)")


def _balancing_rotation(k: float, e: float, sarm, gap, beta0: float, torque: float) -> float:
    """The rotation beta at which the pins' moments sum to ``|torque|`` (bracketed from the
    no-load pose beta0, Brent's method to round-off)."""

    def residual(beta):
        w = np.maximum(sarm * (beta - beta0) - gap, 0.0)
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
    return brentq(residual, lo, hi, xtol=1e-18, rtol=4 * np.finfo(float).eps, maxiter=200)


def disc_effective_modulus(reducer) -> float:
    """E' [Pa] of the disc-pin contact of a design (Hamrock's effective modulus)."""
    d, p = reducer.material("cycloid_disc"), reducer.material("pins")
    return float(effective_modulus(d.youngs_modulus, d.poisson_ratio, p.youngs_modulus, p.poisson_ratio))


def reducer_pin_loads(
    reducer,
    output_torque: float,
    crank_angle: float = 0.0,
    law: str = "palmgren",
    d_pin_radius: float | None = None,
    disc: int = 0,
    stiffness_constant: float | None = None,
) -> PinLoadResult:
    """Pin load distribution of disc ``disc`` of a design under the OUTPUT torque
    [N m], shared equally by the n_discs discs (rigid cranks): T_disc = T / n_discs.

    Reads the as-built geometry (:func:`flexrv.geometry.as_built.as_built`): actual
    pin centres and radii, the disc's modifications plus its errors and its
    profile-error harmonics; the disc sits at its nominal pose for the crank angle
    ``crank_angle`` + chi0_disc (disc k's eccentric leads by 2 pi k / n_discs).
    ``d_pin_radius`` overrides the design's nominal equidistant modification [m]
    (the disc's equidistant error is kept on top of it). The palmgren law uses the
    design's whole pin path (:func:`pin_contact_constant`: disc contact, pin seat,
    pin bending) unless ``stiffness_constant`` is given."""
    ss = reducer.second_stage
    if law == "palmgren" and stiffness_constant is None:
        stiffness_constant = pin_contact_constant(reducer).k
    if not 0 <= disc < ss.n_discs:
        raise InputError(f"disc = {disc!r} must be within 0..{ss.n_discs - 1}")
    ab = as_built(reducer)
    d_radius, dr, d_rot = (float(v) for v in ab.disc_profile[disc])
    if d_pin_radius is not None:
        dr = d_pin_radius + (dr - ss.modification_equidistant)
    return pin_load_distribution(
        output_torque / ss.n_discs,
        ss.pin_count,
        ss.pin_circle_radius,
        ss.pin_radius,
        ss.eccentricity,
        ss.disc_width,
        disc_effective_modulus(reducer),
        d_radius,
        dr,
        d_rot,
        crank_angle + float(ab.chi0[disc]),
        law,
        pins=ab.pins,
        pin_radii=ab.pin_radii,
        harmonics=ab.profile_harmonics[disc],
        stiffness_constant=stiffness_constant,
    )


def shear_coefficient(nu: float) -> float:
    """Timoshenko shear coefficient of a solid circular section, Cowper (1966):
    kappa = 6 (1 + nu) / (7 + 6 nu) (pins here, crankshaft journals in
    :func:`flexrv.analysis.torsional.stepped_shaft_bending`)."""
    return 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)


def pin_bending_stiffness(span: float, radius: float, youngs_modulus: float, poisson_ratio: float) -> float:
    """Lateral stiffness [N/m] of a pin (solid circle of ``radius``) spanning ``span``
    [m] between two groove lands, simply supported there, under the disc's load at
    mid-span (Timoshenko beam; Timoshenko & Gere, *Mechanics of Materials*, ch. 9;
    shear coefficient of a solid circle kappa = 6 (1 + nu)/(7 + 6 nu), Cowper 1966):

        delta / Q = L^3 / (48 E I) + L / (4 kappa G A),   I = pi r^4 / 4, A = pi r^2.

    ``span`` = 0 (a fully supported pin) gives inf."""
    if not (np.isfinite(span) and span >= 0 and radius > 0 and youngs_modulus > 0 and 0 <= poisson_ratio < 0.5):
        raise InputError(
            f"span = {span!r} m must be >= 0, radius = {radius!r} m and youngs_modulus > 0, 0 <= poisson_ratio < 0.5"
        )
    if span == 0:
        return float("inf")
    g_mod = youngs_modulus / (2.0 * (1.0 + poisson_ratio))
    area, inertia = np.pi * radius**2, 0.25 * np.pi * radius**4
    return 1.0 / (
        span**3 / (48.0 * youngs_modulus * inertia) + span / (4.0 * shear_coefficient(poisson_ratio) * g_mod * area)
    )


@dataclass(frozen=True)
class PinContactConstant:
    """Constant of the pin law Q = K delta^(10/9) of a design's whole pin path
    (:func:`pin_contact_constant`), its parts and their shares (SI).

    k : constant of the path [N/m^(10/9)]; exponent : 10/9; k_disc, k_seat :
    Palmgren constants of the pin-disc and pin-seat contacts (k_seat inf without a
    housing); k_bending : linear pin-bending stiffness [N/m] (inf: fully supported);
    reference_load : pin load [N] at which the bending is matched (largest pin force
    at the rated torque); seat_semi_angle : Hertz half-width / pin radius of the
    seat at that load [rad] (:func:`flexrv.contact.hertz.conformal_line_contact`);
    shares : element -> fraction of the path's tangent compliance at the reference
    load ("pins" the disc contact, "pin_seats", "pin_bending"; they sum to 1).
    """

    k: float
    exponent: float
    k_disc: float
    k_seat: float
    k_bending: float
    reference_load: float
    seat_semi_angle: float
    shares: dict


def pin_contact_constant(reducer) -> PinContactConstant:
    """The pin law's constant of a design: the load passes from the disc into the
    pin (pin-disc line contact over the disc width b) and from the pin into its
    groove in the housing (pin-seat line contact over the seat length per disc
    L_s = ``housing.pin_seat_length_mm`` / n_discs), and, where the pin spans
    ``housing.pin_unsupported_length_mm`` between lands, through its bending
    (:func:`pin_bending_stiffness`). The two contacts are Palmgren line contacts
    (:func:`flexrv.contact.hertz.line_contact_stiffness`; E' of disc/pin and of
    pin/housing) in series (:func:`flexrv.contact.hertz.series_stiffness`, exact
    for equal exponents: delta = delta_disc + delta_seat). Palmgren's approach is
    radius-free; the seat is conformal (groove radius r + c), and its Hertz
    half-width (:func:`flexrv.contact.hertz.conformal_line_contact`) at the largest
    pin load is reported as ``seat_semi_angle``: where it is not small against the
    pin radius the seat spreads over an arc and is expected stiffer than Palmgren's
    law, which is then a conservative (compliant) estimate (rv40e: 0.27 pin radii at
    597 N). A linear bending spring in series
    has no exact power-law form: the path's constant is matched to the series
    deflection at the reference load Q_ref (the largest pin force at the rated
    torque, of the design without its errors, :func:`flexrv.design.manufacturing.nominal_design`): K = Q_ref /
    (delta_contacts(Q_ref) + Q_ref / k_bend)^(10/9).
    Without a [housing] table the pins are rigidly seated: K = k_disc. A function of the
    design without its errors: shared by its error sets inside
    :func:`flexrv.design.manufacturing.shared_nominal_constants`."""
    from flexrv.design.manufacturing import nominal_shared

    return nominal_shared(reducer, "pin_contact_constant", _pin_contact_constant)


def _pin_contact_constant(reducer) -> PinContactConstant:
    from flexrv.contact.hertz import conformal_line_contact, effective_modulus, series_stiffness

    ss, h = reducer.second_stage, reducer.housing
    n = LINE_EXPONENT
    k_disc = float(line_contact_stiffness(ss.disc_width, disc_effective_modulus(reducer)))
    if h is None:
        return PinContactConstant(
            k=k_disc,
            exponent=n,
            k_disc=k_disc,
            k_seat=float("inf"),
            k_bending=float("inf"),
            reference_load=float("nan"),
            seat_semi_angle=float("nan"),
            shares={"pins": 1.0, "pin_seats": 0.0, "pin_bending": 0.0},
        )
    mp, mh = reducer.material("pins"), reducer.material("housing")
    e_seat = float(effective_modulus(mp.youngs_modulus, mp.poisson_ratio, mh.youngs_modulus, mh.poisson_ratio))
    length = M_PER_MM * h.pin_seat_length_mm / ss.n_discs
    k_seat = float(line_contact_stiffness(length, e_seat))
    k_contacts = float(series_stiffness(k_disc, k_seat, n))
    from flexrv.design.manufacturing import nominal_design

    # Q_ref of the design without its errors (a design-level constant, shared by every error set)
    q_ref = reducer_pin_loads(
        nominal_design(reducer), reducer.operating.rated_torque_Nm, stiffness_constant=k_contacts
    ).max_force
    _, semi = conformal_line_contact(q_ref, length, ss.pin_radius, ss.pin_radius + h.pin_seat_clearance, e_seat)
    k_bend = pin_bending_stiffness(
        M_PER_MM * h.pin_unsupported_length_mm, ss.pin_radius, mp.youngs_modulus, mp.poisson_ratio
    )
    # tangent compliances at Q_ref: power law delta / (n Q), linear spring 1 / k
    d_disc, d_seat = (q_ref / k_disc) ** (1.0 / n), (q_ref / k_seat) ** (1.0 / n)
    c = {"pins": d_disc / (n * q_ref), "pin_seats": d_seat / (n * q_ref), "pin_bending": 1.0 / k_bend}
    k = k_contacts if np.isinf(k_bend) else q_ref / (d_disc + d_seat + q_ref / k_bend) ** n
    total = sum(c.values())
    return PinContactConstant(
        k=float(k),
        exponent=n,
        k_disc=k_disc,
        k_seat=k_seat,
        k_bending=float(k_bend),
        reference_load=float(q_ref),
        seat_semi_angle=float(semi),
        shares={key: v / total for key, v in c.items()},
    )
