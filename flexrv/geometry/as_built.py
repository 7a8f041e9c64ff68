"""As-built geometry: the nominal design plus its manufacturing and assembly errors.

:func:`as_built` is the ONE place where the design's ``[errors]`` table
(:class:`flexrv.design.manufacturing.ManufacturingErrors`) becomes geometry: the
actual pin centres and radii, the per-disc profile (modifications + error
harmonics), the crank-hole centres in each disc, the eccentrics, the crank bores
in the carrier, the bearing clearances and the first-stage runouts, all SI. The
rigid/quasi-static model parameters (:func:`flexrv.model.drive.drive_parameters` and the elements' ``parameters``)
and the analytic pin-load distribution (:mod:`flexrv.analysis.pin_load`) read it,
so every model sees the same reducer.

Frames and signs (as :mod:`flexrv.geometry.cycloid` and :mod:`flexrv.model.drive`):
pin j sits at psi_j = 2 pi j / z_rp clockwise from +y, R_p (sin psi_j, cos psi_j);
crank j at beta_j = 2 pi j / N counter-clockwise from +x, a_w (cos beta_j, sin beta_j)
in the carrier; radial errors along the element's outward radius, tangential errors
along the counter-clockwise tangent (the radius turned by +90 deg). The eccentric
of crank j under disc k points along e (sin chi, cos chi) with the clockwise angle
chi = chi0_k + err_jk - phi_j.

Profile errors: a disc's harmonic (order n, amplitude A, phase p) adds material
delta(phi) = A cos(n phi + p) along the profile normal at the curve parameter phi
of the (rotation-modified) profile; to first order in A it reduces the gap of a pin
whose foot point is at phi* by delta(phi*) and leaves the contact normal unchanged
(slope A n / R_p of order 1e-3 rad for a 5 um, n = z_rp error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexrv.geometry.cycloid import pin_gap, pin_positions, to_disc_frame
from flexrv.units import M_PER_UM, RAD_PER_ARCMIN, RAD_PER_DEG


@dataclass(frozen=True)
class AsBuilt:
    """Actual geometry of one reducer (SI). Shapes: z_rp pins, N cranks, nd discs,
    H harmonics (rows of zero amplitude pad discs with fewer harmonics)."""

    pins: np.ndarray  #: (z_rp, 2) pin centres, housing frame [m]
    pin_radii: np.ndarray  #: (z_rp,) pin radii [m]
    disc_profile: np.ndarray  #: (nd, 3) (d_radius [m], d_pin_radius [m], d_rotation [rad]) per disc
    profile_harmonics: np.ndarray  #: (nd, H, 3) (order [-], amplitude [m], phase [rad])
    chi0: np.ndarray  #: (nd,) nominal clockwise eccentric angle of each disc at t = 0 [rad]
    disc_rot0: np.ndarray  #: (nd,) nominal disc rotation chi0_k / z_c at t = 0 [rad]
    holes: np.ndarray  #: (nd, N, 2) crank-hole centres in each disc's frame [m]
    eccentricities: np.ndarray  #: (N, nd) eccentric radii [m]
    eccentric_phase_errors: np.ndarray  #: (N, nd) [rad]
    crank_bores: np.ndarray  #: (N, 2) crank-bore centres, carrier frame [m]
    needle_clearances: np.ndarray  #: (N, nd) radial clearance of each needle bearing [m]
    support_clearances: np.ndarray  #: (N,) radial clearance of each crank's supports [m]
    sun_runout: np.ndarray  #: (2,) amplitude [m], phase [rad]
    planet_runout: np.ndarray  #: (N, 2) amplitude [m], phase [rad]
    planet_phase_errors: np.ndarray  #: (N,) [rad]


def _per(value, n: int) -> np.ndarray:
    """One number or a list of n numbers -> float array (n,)."""
    return np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()


def _per2(value, n: int, nd: int) -> np.ndarray:
    """One number or [n][nd] lists -> float array (n, nd)."""
    return np.broadcast_to(np.asarray(value, dtype=float), (n, nd)).copy()


def _radial_tangential(radial_unit: np.ndarray, dr: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Displacement dr u + dt (u turned +90 deg) for unit vectors u (..., 2)."""
    tangent = np.stack([-radial_unit[..., 1], radial_unit[..., 0]], axis=-1)
    return dr[..., None] * radial_unit + dt[..., None] * tangent


def as_built(reducer, errors=None) -> AsBuilt:
    """The as-built geometry of a design: nominal values plus ``errors``
    (default: the design's own ``[errors]`` table). With all errors zero every
    array equals the nominal one bit for bit (the errors are added as exact zeros).
    """
    err = reducer.errors if errors is None else errors
    fs, ss, nb = reducer.first_stage, reducer.second_stage, reducer.needle_bearing
    z, nd, n = ss.pin_count, ss.n_discs, fs.n_planets
    # pins
    pins0 = pin_positions(z, ss.pin_circle_radius)
    psi = 2.0 * np.pi * np.arange(z) / z
    u_pin = np.stack([np.sin(psi), np.cos(psi)], axis=-1)
    pins = pins0 + _radial_tangential(
        u_pin,
        _per(err.pins.pin_radial_position_um, z) * M_PER_UM,
        _per(err.pins.pin_tangential_position_um, z) * M_PER_UM,
    )
    pin_radii = ss.pin_radius + _per(err.pins.pin_radius_um, z) * M_PER_UM
    # discs: profile and harmonics
    nominal = np.array([ss.modification_shift, ss.modification_equidistant, ss.modification_rotation])
    profile = np.tile(nominal, (nd, 1))
    n_h = max((len(d.harmonics) for d in err.discs), default=0)
    harmonics = np.zeros((nd, n_h, 3))
    harmonics[:, :, 0] = 1.0
    hole_dr = np.zeros((nd, n))
    hole_dt = np.zeros((nd, n))
    for k, d in enumerate(err.discs):
        profile[k] += [d.shift_um * M_PER_UM, d.equidistant_um * M_PER_UM, d.rotation_arcmin * RAD_PER_ARCMIN]
        for h, harm in enumerate(d.harmonics):
            harmonics[k, h] = (harm.order, harm.amplitude_um * M_PER_UM, harm.phase_deg * RAD_PER_DEG)
        hole_dr[k] = _per(d.hole_radial_um, n) * M_PER_UM
        hole_dt[k] = _per(d.hole_tangential_um, n) * M_PER_UM
    # cranks in the carrier, holes in the discs
    a_w = fs.center_distance
    beta = 2.0 * np.pi * np.arange(n) / n
    u_crank = np.stack([np.cos(beta), np.sin(beta)], axis=-1)
    crank_pos = a_w * u_crank
    bores = crank_pos + _radial_tangential(
        u_crank, _per(err.cranks.bore_radial_um, n) * M_PER_UM, _per(err.cranks.bore_tangential_um, n) * M_PER_UM
    )
    chi0 = 2.0 * np.pi * np.arange(nd) / nd
    rot0 = chi0 / ss.disc_teeth
    holes = np.empty((nd, n, 2))
    for k in range(nd):
        c, s = math.cos(rot0[k]), math.sin(rot0[k])
        # hole centre (housing, t=0) = crank centre + eccentric vector; disc centre = eccentric vector
        h0 = np.stack([c * crank_pos[:, 0] + s * crank_pos[:, 1], -s * crank_pos[:, 0] + c * crank_pos[:, 1]], -1)
        u_h = h0 / np.linalg.norm(h0, axis=-1, keepdims=True)
        holes[k] = h0 + _radial_tangential(u_h, hole_dr[k], hole_dt[k])
    ecc = ss.eccentricity + _per2(err.cranks.eccentricity_um, n, nd) * M_PER_UM
    phase = _per2(err.cranks.eccentric_phase_arcmin, n, nd) * RAD_PER_ARCMIN
    needle = nb.clearance_per_side + _per2(err.clearances.needle_extra_clearance_um, n, nd) * M_PER_UM
    support = _per(err.clearances.support_clearance_um, n) * M_PER_UM
    e1 = err.first_stage
    sun = np.array([e1.sun_runout_um * M_PER_UM, e1.sun_runout_phase_deg * RAD_PER_DEG])
    planet = np.stack([_per(e1.planet_runout_um, n) * M_PER_UM, _per(e1.planet_runout_phase_deg, n) * RAD_PER_DEG], -1)
    planet_phase = _per(e1.planet_phase_arcmin, n) * RAD_PER_ARCMIN
    return AsBuilt(
        pins=pins,
        pin_radii=pin_radii,
        disc_profile=profile,
        profile_harmonics=harmonics,
        chi0=chi0,
        disc_rot0=rot0,
        holes=holes,
        eccentricities=ecc,
        eccentric_phase_errors=phase,
        crank_bores=bores,
        needle_clearances=needle,
        support_clearances=support,
        sun_runout=sun,
        planet_runout=planet,
        planet_phase_errors=planet_phase,
    )


def profile_deviation(phi, harmonics) -> np.ndarray:
    """Material added along the profile normal [m] at curve parameter ``phi``:
    delta(phi) = sum_h A_h cos(n_h phi + p_h) for ``harmonics`` rows (n, A, p)."""
    phi = np.asarray(phi, dtype=float)
    h = np.asarray(harmonics, dtype=float).reshape(-1, 3)
    if h.shape[0] == 0:
        return np.zeros_like(phi)
    return np.sum(h[:, 1] * np.cos(h[:, 0] * phi[..., None] + h[:, 2]), axis=-1)


def as_built_pin_gap(
    points,
    pin_radii,
    z_rp: int,
    pin_circle_radius: float,
    pin_radius: float,
    eccentricity: float,
    profile,
    harmonics=None,
    phi0=None,
):
    """Signed gap [m] of actual pins (centres ``points`` (..., 2) in the disc frame,
    radii ``pin_radii``) to one as-built disc profile.

    The disc profile is generated by the nominal pin (radius ``pin_radius``, circle
    ``pin_circle_radius``, eccentricity) with the disc's modifications ``profile`` =
    (d_radius, d_pin_radius, d_rotation) and error ``harmonics`` (H, 3). Exactly:
    gap = pin_gap(P) - (r_i - r_rp) - delta(phi*): a pin larger by e_r has e_r less
    gap (so a uniform pin-radius error +d equals an equidistant modification - d),
    and the harmonic material delta(phi*) at the foot point phi* reduces it further
    (first order in the harmonic amplitude, see the module docstring).

    Returns gap (...), normal (..., 2) (disc frame, profile -> pin) and phi (...)
    as :func:`flexrv.geometry.cycloid.pin_gap`.
    """
    d_radius, d_pin_radius, d_rotation = (float(v) for v in profile)
    gap, normal, phi = pin_gap(
        points, z_rp, pin_circle_radius, pin_radius, eccentricity, d_radius, d_pin_radius, d_rotation, phi0=phi0
    )
    gap = gap - (np.asarray(pin_radii, dtype=float) - pin_radius)
    if harmonics is not None and np.size(harmonics):
        gap = gap - profile_deviation(phi, harmonics)
    return gap, normal, phi


def assembly_disc_poses(reducer, ab: AsBuilt):
    """Pose of every disc at assembly (t = 0, nominal crank angles): the rigid
    least-squares (Procrustes) fit of the disc's crank holes onto the as-built hole
    positions crank bore + eccentric vector e_jk (sin chi_jk, cos chi_jk),
    chi_jk = chi0_k + err_jk (carrier at rest, housing frame = carrier frame). With
    no errors it is the nominal pose (disc centre a (sin chi0_k, cos chi0_k),
    rotation chi0_k / z_c) to round-off.

    Returns centres (nd, 2) [m] and rotations (nd,) [rad, counter-clockwise]."""
    nd = reducer.second_stage.n_discs
    centres = np.empty((nd, 2))
    rots = np.empty(nd)
    for k in range(nd):
        chi = ab.chi0[k] + ab.eccentric_phase_errors[:, k]
        target = ab.crank_bores + ab.eccentricities[:, k, None] * np.stack([np.sin(chi), np.cos(chi)], -1)
        h = ab.holes[k]
        hc, tc = h - h.mean(0), target - target.mean(0)
        rot = np.arctan2(
            np.sum(hc[:, 0] * tc[:, 1] - hc[:, 1] * tc[:, 0]), np.sum(hc[:, 0] * tc[:, 0] + hc[:, 1] * tc[:, 1])
        )
        c, s = np.cos(rot), np.sin(rot)
        hm = h.mean(0)
        centres[k] = target.mean(0) - np.array([c * hm[0] - s * hm[1], s * hm[0] + c * hm[1]])
        rots[k] = rot
    return centres, rots


def _max_min_lines(g, slope, lo: float, hi: float) -> float:
    """argmax over x in [lo, hi] of min_i (g_i + slope_i x) (concave, piecewise
    linear): bisection on the slope of the active line."""
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        i = int(np.argmin(g + slope * mid))
        if slope[i] > 0:
            lo = mid
        elif slope[i] < 0:
            hi = mid
        else:
            return mid
    return 0.5 * (lo + hi)


def assembly_penetration(reducer, errors=None) -> tuple[float, int, int]:
    """Largest pin penetration [m] into the discs at assembly, with its disc and pin.

    The discs sit at their assembly poses (:func:`assembly_disc_poses`); the
    conjugate motion (turning the input) leaves every gap unchanged, so the one
    free rotation is a common turn beta of all discs about their centres (the
    carrier's rotation). The result is -max_beta min_{k,i} gap_ki(beta): > 0 if
    no rotation lets every pin clear its disc (the parts interfere), < 0 the
    smallest clearance at the best rotation. With d gap_ki / d beta = -l_ki (the
    moment arm of the contact normal), min_{k,i} gap_ki is concave and piecewise
    linear to first order; its maximum over |beta| <= 0.02 rad (beyond the 1 mm of
    gap any error set within the field bounds can open on the 40-60 mm arms) is
    found on the linearised gaps, which are then re-evaluated exactly at the new
    beta until beta changes by less than 1e-13 rad.
    """
    ss = reducer.second_stage
    ab = as_built(reducer, errors)
    centres, rots = assembly_disc_poses(reducer, ab)
    nd, z = ss.n_discs, ss.pin_count

    def gaps(beta, phi0):
        g, arm, phi = np.empty((nd, z)), np.empty((nd, z)), np.empty((nd, z))
        for k in range(nd):
            p = to_disc_frame(ab.pins, centres[k], rots[k] + beta)
            g[k], n, phi[k] = as_built_pin_gap(
                p,
                ab.pin_radii,
                z,
                ss.pin_circle_radius,
                ss.pin_radius,
                ss.eccentricity,
                ab.disc_profile[k],
                ab.profile_harmonics[k],
                phi0=None if phi0 is None else phi0[k],
            )
            arm[k] = p[:, 0] * n[:, 1] - p[:, 1] * n[:, 0]
        return g, arm, phi

    beta = 0.0
    g, arm, phi = gaps(beta, None)
    for _ in range(20):
        new = _max_min_lines((g + arm * beta).ravel(), -arm.ravel(), -0.02, 0.02)
        step, beta = new - beta, new
        g, arm, phi = gaps(beta, phi if abs(step) < 1e-3 else None)
        if abs(step) < 1e-13:
            break
    k, i = np.unravel_index(int(np.argmin(g)), g.shape)
    return float(-g[k, i]), int(k), int(i)
