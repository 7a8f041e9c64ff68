"""Torsional stiffness of the RV reducer's second stage (:cite:`seed004` series model)
and :cite:`seed004`'s meshing-zone identification from a measured stiffness.

Model (:cite:`seed004`): the output torque passes in series through
(1) the needle (crank) bearings between the discs and the eccentrics and
(2) the pin-disc contacts:

    C_W = C_Hc C_c / (C_Hc + C_c),
    C_Hc = n_discs sum_k K_Hc,k l_c^2       (seed: 2 (K_A + K_B + K_C) l_c^2),
    C_c  = n_discs sum_j K_c,j L_j^2         (seed: 2 sum K_cj L_j^2),

with the empirical needle-bearing radial stiffness
K_Hc = 0.34e4 F_r^0.1 Z^0.9 l^0.8 cos(alpha)^1.9 [N/mm; F_r in N, l in mm].
The first stage and the crank/carrier compliances are neglected (as in :cite:`seed004`).

Lever arm l_c: turning a disc by beta about its centre moves each crank hole by
a_w beta tangentially (a_w = crank-circle radius = first-stage centre distance),
so l_c = a_w. :cite:`seed004`'s force split writes the couple term as F_t r'_c/(3a);
moment balance of the disc about its centre requires the hole radius a_w in that
denominator (with the eccentricity a = 1.3 mm the bearing forces of the RV-40E
would be ~28x too large), so a_w is used (physics over seed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.analysis.pin_load import shear_coefficient
from flexrv.errors import InputError
from flexrv.units import M_PER_MM, M_PER_UM, RAD_PER_DEG

#: K_Hc [N/mm] = NEEDLE_COEFF * F^0.1 [N] * Z^0.9 * l^0.8 [mm] * cos^1.9 (:cite:`seed004`).
NEEDLE_COEFF = 0.34e4


def needle_radial_stiffness(radial_force, roller_count, roller_length, contact_angle=0.0):
    """Empirical radial stiffness of a needle/roller bearing [N/m] (:cite:`seed004`):

    K_Hc = 0.34e4 F_r^0.1 Z^0.9 l^0.8 cos(alpha)^1.9   in N/mm with F_r [N], l [mm].

    SI conversion: K [N/m] = 1e3 * 0.34e4 * F_r^0.1 * Z^0.9 * (1e3 l[m])^0.8 cos^1.9
    = 3.4e6 * 10^2.4 * F_r^0.1 Z^0.9 l^0.8 cos^1.9 = 8.541e8 F_r^0.1 Z^0.9 l[m]^0.8 cos^1.9.

    Parameters
    ----------
    radial_force : bearing radial load F_r [N] (>= 0; F_r = 0 gives K = 0, the
        formula's limit, so callers should not use it unloaded).
    roller_count : Z [-]; roller_length : effective length l [m];
    contact_angle : alpha [rad] (0 for needle bearings).
    """
    f = np.asarray(radial_force, dtype=float)
    if np.any(~np.isfinite(f)) or np.any(f < 0):
        raise InputError(f"radial_force must be finite and >= 0 N, got {radial_force!r}")
    if np.any(np.asarray(roller_length) <= 0) or np.any(np.asarray(roller_count) <= 0):
        raise InputError("roller_count and roller_length must be > 0")
    l_mm = np.asarray(roller_length, dtype=float) * 1e3
    k_n_per_mm = (
        NEEDLE_COEFF * f**0.1 * np.asarray(roller_count, dtype=float) ** 0.9 * l_mm**0.8 * np.cos(contact_angle) ** 1.9
    )
    return k_n_per_mm * 1e3


def crank_hole_angles(n_cranks: int, first: float = 0.0):
    """Angles [rad] of the crank holes in the disc frame (math convention, ccw from +x):
    first + 2 pi k / n."""
    return first + 2.0 * np.pi * np.arange(n_cranks) / n_cranks


def crank_bearing_forces(pin_resultant, disc_torque, crank_circle_radius, n_cranks: int = 3, first_angle=0.0):
    """Forces [N] on the n crank bearings of one disc (:cite:`seed004`'s F_A/F_B/F_C,
    generalised to n cranks), shape (..., n, 2):

        F_k = F / n + T / (n a_w) t_k,   t_k = (-sin th_k, cos th_k),

    the force the disc exerts on crank bearing k at hole angle th_k, with F the
    resultant of the pin forces on the disc and T their moment about the disc
    centre (= the disc torque). Equal sharing of the force and of the couple is
    the statically determinate split of :cite:`seed004`; it satisfies force and moment
    balance of the disc exactly: sum_k F_k = F (the t_k sum to zero) and
    sum_k a_w e_k x F_k = sum_k T/n = T (the F/n terms have no moment since
    sum_k e_k = 0 for evenly spaced holes), e_k = (cos th_k, sin th_k).

    Parameters
    ----------
    pin_resultant : (..., 2) resultant pin force on the disc [N].
    disc_torque : (...) moment of the pin forces about the disc centre [N m].
    crank_circle_radius : a_w [m]; n_cranks : number of cranks (>= 2);
    first_angle : angle of the first hole [rad].
    """
    if n_cranks < 2:
        raise InputError(f"n_cranks = {n_cranks} must be >= 2")
    if crank_circle_radius <= 0:
        raise InputError(f"crank_circle_radius = {crank_circle_radius} must be > 0")
    th = crank_hole_angles(n_cranks, first_angle)
    t = np.stack([-np.sin(th), np.cos(th)], axis=-1)
    f = np.asarray(pin_resultant, dtype=float)[..., None, :] / n_cranks
    couple = np.asarray(disc_torque, dtype=float)[..., None, None] / (n_cranks * crank_circle_radius) * t
    return f + couple


def bearing_torsional_stiffness(bearing_stiffness, lever_arm, n_discs: int = 2):
    """C_Hc = n_discs sum_k K_Hc,k l_c^2 [N m/rad] (:cite:`seed004`, n_discs = 2)."""
    return n_discs * np.sum(np.asarray(bearing_stiffness, dtype=float), axis=-1) * lever_arm**2


def mesh_torsional_stiffness(pin_stiffness, arms, n_discs: int = 2, engaged=None):
    """C_c = n_discs sum_j K_c,j L_j^2 [N m/rad] over the engaged pins (:cite:`seed004`)."""
    c = np.asarray(pin_stiffness, dtype=float) * np.asarray(arms, dtype=float) ** 2
    if engaged is not None:
        c = np.where(engaged, c, 0.0)
    return n_discs * np.sum(c, axis=-1)


def series_stiffness(c1, c2):
    """Two torsional springs in series: C = C1 C2 / (C1 + C2) [N m/rad] (:cite:`seed004`'s C_W)."""
    c1, c2 = np.asarray(c1, dtype=float), np.asarray(c2, dtype=float)
    return c1 * c2 / (c1 + c2)


def required_mesh_stiffness(measured, bearing):
    """Invert the series model: C_c = 1 / (1/C_W - 1/C_Hc) [N m/rad] (:cite:`seed004`).

    Raises InputError if C_W >= C_Hc (no positive mesh stiffness explains the
    measurement)."""
    if measured <= 0 or bearing <= measured:
        raise InputError(
            f"measured stiffness {measured:.4g} N m/rad must be > 0 and below the bearing "
            f"stiffness C_Hc = {bearing:.4g} N m/rad"
        )
    return 1.0 / (1.0 / measured - 1.0 / bearing)


@dataclass(frozen=True)
class MeshingZone:
    """Result of :func:`identify_meshing_zone` (pins numbered from 1 like :cite:`seed004`).

    target : required C_c [N m/rad]; first, last : best consecutive pin set;
    n_pins; total : its summed stiffness; rel_error = (total - target)/target;
    angles : phase angles of first/last pin [rad]; best_by_count : for every set
    size n, (first, last, total) of the best n-pin set.
    """

    target: float
    first: int
    last: int
    n_pins: int
    total: float
    rel_error: float
    angles: tuple[float, float]
    best_by_count: dict[int, tuple[int, int, float]]


def identify_meshing_zone(contributions, target, phase_angles=None, n_pins: int | None = None) -> MeshingZone:
    """:cite:`seed004`'s meshing-zone identification: the consecutive set of pins whose
    summed single-pin contributions KTC_j (= n_discs K_cj L_j^2) best match the
    required mesh stiffness ``target`` (all consecutive sets are enumerated; with
    ``n_pins`` only sets of that size).

    Parameters
    ----------
    contributions : (m,) KTC_j [N m/rad] of pins 1..m (:cite:`seed004` Table: m = 21 over 0-180 deg).
    target : required C_c [N m/rad]; phase_angles : (m,) [rad], optional.
    """
    c = np.asarray(contributions, dtype=float)
    m = len(c)
    cum = np.concatenate([[0.0], np.cumsum(c)])
    i, j = np.triu_indices(m + 1, k=1)  # sets c[i:j]
    totals = cum[j] - cum[i]
    sizes = j - i
    best_by = {}
    for n in range(1, m + 1):
        sel = np.flatnonzero(sizes == n)
        b = sel[np.argmin(np.abs(totals[sel] - target))]
        best_by[n] = (int(i[b]) + 1, int(j[b]), float(totals[b]))
    cand = np.flatnonzero(sizes == n_pins) if n_pins else np.arange(len(totals))
    b = cand[np.argmin(np.abs(totals[cand] - target))]
    first, last = int(i[b]) + 1, int(j[b])
    ang = (
        (float("nan"), float("nan"))
        if phase_angles is None
        else (float(phase_angles[first - 1]), float(phase_angles[last - 1]))
    )
    return MeshingZone(
        target=float(target),
        first=first,
        last=last,
        n_pins=last - first + 1,
        total=float(totals[b]),
        rel_error=float((totals[b] - target) / target),
        angles=ang,
        best_by_count=best_by,
    )


#: :cite:`seed004` table: single-point equivalent torsional stiffness KTC_j [N mm/rad]
#: of pins 1..21 at meshing phase 0, 9, ..., 180 deg (RV-40E, two discs).
SEED004_KTC_NMM = np.array(
    [
        0.0,
        2.20e6,
        1.97e7,
        1.33e8,
        1.84e8,
        1.76e8,
        1.66e8,
        1.52e8,
        1.38e8,
        1.22e8,
        1.06e8,
        8.93e7,
        7.33e7,
        5.79e7,
        4.38e7,
        3.12e7,
        2.03e7,
        1.16e7,
        5.25e6,
        1.33e6,
        0.0,
    ]
)
#: :cite:`seed004`: measured C_W = 3.06e8 N mm/rad and derived C_c = 6.24e8 N mm/rad.
SEED004_CW_NMM = 3.06e8
SEED004_CC_NMM = 6.24e8


# --------------------------------------------------------------------------- design-level evaluation
@dataclass(frozen=True)
class SecondStageStiffness:
    """Second-stage torsional stiffness of a design at one load and crank angle (SI).

    bearing_forces : (n, 2) force on each crank bearing of one disc [N];
    bearing_loads : (n,) their magnitudes [N]; bearing_stiffness : (n,) K_Hc [N/m];
    lever_arm : l_c = a_w [m]; c_bearings : C_Hc [N m/rad];
    c_mesh_seed : C_c with :cite:`seed004`'s K_cj over the loaded pins [N m/rad];
    c_mesh_tangent : n_discs dT/dbeta of the Palmgren pin-load solution [N m/rad];
    c_w_seed, c_w_tangent : series C_W with either mesh stiffness [N m/rad];
    n_contact : loaded pins per disc.
    """

    bearing_forces: np.ndarray
    bearing_loads: np.ndarray
    bearing_stiffness: np.ndarray
    lever_arm: float
    c_bearings: float
    c_mesh_seed: float
    c_mesh_tangent: float
    c_w_seed: float
    c_w_tangent: float
    n_contact: int


def seed004_pin_contributions(reducer, n_pins: int | None = None):
    """Single-pin equivalent torsional stiffness KTC_j = n_discs K_cj L_j^2 [N m/rad]
    of pins j = 1..n at meshing phase (j - 1) 2 pi / z_rp (:cite:`seed004`'s table,
    recomputed with the design's width and E'): K_cj from
    :func:`flexrv.geometry.cycloid.pin_stiffness_seed004` with the profile radius
    of :func:`flexrv.geometry.cycloid.seed004_curvature_radius` (:cite:`seed004` phase
    theta = pin angle from the eccentric direction; the formula is even in theta),
    L_j from :func:`flexrv.geometry.cycloid.moment_arm`.

    Returns (phase angles [rad], KTC [N m/rad]); default n = z_rp/2 + 1 (0..180 deg)."""
    from flexrv.analysis.pin_load import disc_effective_modulus
    from flexrv.geometry.cycloid import moment_arm, pin_stiffness_seed004, seed004_curvature_radius

    ss = reducer.second_stage
    n = ss.pin_count // 2 + 1 if n_pins is None else n_pins
    th = 2.0 * np.pi * np.arange(n) / ss.pin_count
    rho = seed004_curvature_radius(th, ss.pin_count, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = pin_stiffness_seed004(rho, ss.pin_radius, ss.disc_width, disc_effective_modulus(reducer))
    arms = moment_arm(th, ss.pin_count, ss.pin_circle_radius, ss.eccentricity)
    return th, np.nan_to_num(ss.n_discs * k * arms**2)


def second_stage_stiffness(
    reducer, output_torque: float, crank_angle: float = 0.0, first_hole_angle: float = 0.0
) -> SecondStageStiffness:
    """:cite:`seed004` series model evaluated for a design under ``output_torque`` [N m]:
    pin loads (initial-clearance method, :mod:`flexrv.analysis.pin_load`) give the
    pin resultant and the loaded pins; the crank-bearing forces
    (:func:`crank_bearing_forces`) give K_Hc (:func:`needle_radial_stiffness`)."""
    from flexrv.analysis.pin_load import disc_effective_modulus, reducer_pin_loads
    from flexrv.geometry.cycloid import pin_stiffness_seed004, seed004_curvature_radius

    ss, fs, nb = reducer.second_stage, reducer.first_stage, reducer.needle_bearing
    if output_torque == 0:
        raise InputError("output_torque must be non-zero for the load-dependent stiffness model")
    res = reducer_pin_loads(reducer, output_torque, crank_angle)
    t_disc = output_torque / ss.n_discs
    a_w = fs.center_distance
    forces = crank_bearing_forces(res.resultant, t_disc, a_w, fs.n_planets, first_hole_angle)
    loads = np.linalg.norm(forces, axis=-1)
    k_hc = needle_radial_stiffness(loads, nb.roller_count, nb.roller_length_mm * 1e-3)
    c_hc = float(bearing_torsional_stiffness(k_hc, a_w, ss.n_discs))
    # seed-004 pin stiffness at each loaded pin's phase angle (from its arm: |l| = r'_c sin/S)
    psi = 2.0 * np.pi * np.arange(ss.pin_count) / ss.pin_count
    phase = np.mod(psi - crank_angle + np.pi, 2 * np.pi) - np.pi
    rho = seed004_curvature_radius(phase, ss.pin_count, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_c = np.nan_to_num(pin_stiffness_seed004(rho, ss.pin_radius, ss.disc_width, disc_effective_modulus(reducer)))
    c_c_seed = float(mesh_torsional_stiffness(k_c, res.arms, ss.n_discs, res.in_contact))
    c_c_tan = ss.n_discs * res.torsional_stiffness
    return SecondStageStiffness(
        bearing_forces=forces,
        bearing_loads=loads,
        bearing_stiffness=k_hc,
        lever_arm=a_w,
        c_bearings=c_hc,
        c_mesh_seed=c_c_seed,
        c_mesh_tangent=c_c_tan,
        c_w_seed=float(series_stiffness(c_hc, c_c_seed)),
        c_w_tangent=float(series_stiffness(c_hc, c_c_tan)),
        n_contact=res.n_contact,
    )


# --------------------------------------------------------------------------- crank bending and supports
@dataclass(frozen=True)
class CrankBending:
    """Bending of the crankshaft between its support journals (simply supported at
    their centres) under the needle forces at the eccentrics' centres (SI).

    compliance : (2, 2) lateral compliance matrix C_ij [m/N] of eccentric i under a
        unit force at eccentric j (deflection relative to the line through the
        support centres); k_symmetric : stiffness [N/m] of the crank centre in the
        planar model, 1 / (sum_ij C_ij / 4): the crank's total force split equally
        between the two eccentrics (the torque-carrying couple of the needle forces
        is the same on both discs); k_antisymmetric : 1 / ((C11 + C22 - 2 C12) / 4),
        equal and opposite forces (the discs' radial pin resultants), which tilt the
        crank and do not enter the planar model; positions : (z_A, z_1, z_2, z_B) [m].
    """

    compliance: np.ndarray
    k_symmetric: float
    k_antisymmetric: float
    positions: tuple[float, float, float, float]


#: Timoshenko shear coefficient of a solid circle (Cowper 1966), one executor in pin_load
_shear_coefficient = shear_coefficient


def stepped_shaft_bending(segments, youngs_modulus: float, poisson_ratio: float) -> CrankBending:
    """Timoshenko bending of a stepped shaft of four coaxial solid segments
    (support A, eccentric 1, eccentric 2, support B), ``segments`` = ((d, L), ...)
    [m], simply supported at the support segments' centres, unit loads at the
    eccentric segments' centres (see :class:`CrankBending`). Unit-load method
    (Castigliano; Timoshenko & Gere, *Mechanics of Materials*, ch. 9; shear term of
    Timoshenko 1921):

        C_ij = int_A^B [ m_i m_j / (E I(z)) + v_i v_j / (kappa G A(z)) ] dz,

    m_i, v_i the bending moment and shear of the simply supported span A-B under a
    unit load at eccentric i, kappa = 6 (1 + nu)/(7 + 6 nu) (Cowper 1966, solid
    circle); 3-point Gauss quadrature on every interval between section changes and
    load points is exact (m_i m_j is quadratic there)."""
    if len(segments) != 4 or any(d <= 0 or length <= 0 for d, length in segments):
        raise InputError(f"segments = {segments!r}: need four (diameter > 0, length > 0) pairs")
    e_mod, nu = youngs_modulus, poisson_ratio
    g_mod, kappa = e_mod / (2.0 * (1.0 + nu)), _shear_coefficient(nu)
    edges = np.cumsum([0.0] + [length for _, length in segments])
    z_a, z_b = 0.5 * (edges[0] + edges[1]), 0.5 * (edges[3] + edges[4])
    z1, z2 = 0.5 * (edges[1] + edges[2]), 0.5 * (edges[2] + edges[3])
    span = z_b - z_a
    loads = np.array([z1, z2]) - z_a
    breaks = np.unique(np.r_[z_a, z_b, edges[1:4], z1, z2])
    gx, gw = np.polynomial.legendre.leggauss(3)
    c = np.zeros((2, 2))
    for lo, hi in zip(breaks[:-1], breaks[1:]):
        zm = 0.5 * (lo + hi)
        d = segments[min(int(np.searchsorted(edges, zm)) - 1, 3)][0]
        area, inertia = np.pi * d * d / 4.0, np.pi * d**4 / 64.0
        z = zm + 0.5 * (hi - lo) * gx - z_a
        w = 0.5 * (hi - lo) * gw
        m = np.array([np.where(z <= a, (1.0 - a / span) * z, a * (1.0 - z / span)) for a in loads])
        v = np.array([np.where(z <= a, 1.0 - a / span, -a / span) for a in loads])
        c += (m * w) @ m.T / (e_mod * inertia) + (v * w) @ v.T / (kappa * g_mod * area)
    return CrankBending(
        compliance=c,
        k_symmetric=float(4.0 / c.sum()),
        k_antisymmetric=float(4.0 / (c[0, 0] + c[1, 1] - 2.0 * c[0, 1])),
        positions=(float(z_a), float(z1), float(z2), float(z_b)),
    )


def crank_bending(reducer) -> CrankBending:
    """Bending of a design's crankshaft between its support journals and its
    eccentrics: :func:`stepped_shaft_bending` of the journals of
    :class:`flexrv.design.model.Crankshaft` (support A, eccentric 1, eccentric 2,
    support B; each a solid circle of its journal diameter; the eccentric sections
    bend about their own centroids, the offset does not change a circle's I; the
    overhung gear seat carries no needle force), material of the crankshaft.
    Verified against the FE condensation
    (:func:`flexrv.fem.crankshaft.crank_bending_compliance`) in
    tests/test_fem_crank_bending.py."""
    cs = reducer.crankshaft
    mat = reducer.material("crankshaft")
    segs = [
        (M_PER_MM * d, M_PER_MM * length)
        for d, length in (
            (cs.support_journal_diameter_mm, cs.support_journal_length_mm),
            (cs.eccentric_journal_diameter_mm, cs.eccentric_journal_length_mm),
            (cs.eccentric_journal_diameter_mm, cs.eccentric_journal_length_mm),
            (cs.support_journal_diameter_mm, cs.support_journal_length_mm),
        )
    ]
    return stepped_shaft_bending(segs, mat.youngs_modulus, mat.poisson_ratio)


def support_constants(reducer) -> tuple:
    """(sc, roller angles, is_linear) of a design's crank support for
    :func:`flexrv.contact.tapered_roller.crank_support_force` (the one law of the
    kernel and the budget; ``sc`` a :class:`~flexrv.contact.tapered_roller.SupportConstants`):
    roller constant K = series(K_cone, K_cup) of two Palmgren line contacts of length l
    (E' of crankshaft/rolling-element steel), cos(alpha), delta_0 = s_a sin(alpha), k_bend
    (0: rigid crank), g = D cos(alpha)/d_m."""
    from flexrv.contact.hertz import LINE_EXPONENT, effective_modulus, line_contact_stiffness, series_stiffness
    from flexrv.contact.tapered_roller import SupportConstants

    cs = reducer.crankshaft
    linear = cs.support_bearing_model == "linear"
    k_bend = crank_bending(reducer).k_symmetric if cs.bending_model == "timoshenko" else 0.0
    if linear:
        sc = SupportConstants.of(
            linear=2.0 * cs.support_bearing_radial_stiffness_N_per_m,
            k_roller=0.0,
            cos_a=0.0,
            delta0=0.0,
            k_bend=k_bend,
            exponent=LINE_EXPONENT,
            g=0.0,
        )
        return sc, np.zeros(0), True
    mc, mr = reducer.material("crankshaft"), reducer.material("rolling_elements")
    e_eff = effective_modulus(mc.youngs_modulus, mc.poisson_ratio, mr.youngs_modulus, mr.poisson_ratio)
    k_line = float(line_contact_stiffness(cs.support_bearing_roller_length_mm * M_PER_MM, e_eff))
    a = cs.support_bearing_contact_angle_deg * RAD_PER_DEG
    sc = SupportConstants.of(
        linear=0.0,
        k_roller=series_stiffness(k_line, k_line, LINE_EXPONENT),
        cos_a=np.cos(a),
        delta0=cs.support_bearing_axial_preload_um * M_PER_UM * np.sin(a),
        k_bend=k_bend,
        exponent=LINE_EXPONENT,
        g=cs.support_bearing_roller_diameter_mm * np.cos(a) / cs.support_bearing_pitch_diameter_mm,
    )
    z = cs.support_bearing_roller_count
    return sc, 2.0 * np.pi * np.arange(z) / z, False


# --------------------------------------------------------------------------- housing ring
def ring_displacements(
    angles,
    radial,
    tangential,
    mean_radius: float,
    bending_stiffness: float,
    axial_stiffness: float,
    harmonics: int = 400,
):
    """Displacements of a thin circular ring under point loads (curved-beam theory,
    Fourier series; Timoshenko & Goodier / Roark's *Formulas for Stress and Strain*,
    ch. 9 thin rings): loads f_r (outward) and f_t (in +theta) at ``angles`` [rad];
    returns (w, v) radial and tangential displacements [m] there.

    Harmonic n >= 2 (inextensional bending, v' = -w): with the load densities
    q_r = sum (A_n cos n th + B_n sin n th), q_t = sum (C_n cos n th + D_n sin n th),
    A_n = sum_j f_rj cos(n th_j) / (pi R) etc., minimum potential energy gives
    w_n = R^4 [(A_n - D_n / n) cos n th + (B_n + C_n / n) sin n th] / (EI (n^2 - 1)^2),
    v_n = -int w_n. Harmonic 0: hoop extension w_0 = q_r0 R^2 / (EA). Harmonic 1 and
    the mean tangential load (the net force and torque) are rigid-body motions,
    reacted by the ring's support (shear flow), and give no deformation. Truncated at
    ``harmonics`` (terms fall like n^-4). Verified against Roark's diametrically
    loaded ring (tests/test_pin_seat.py)."""
    th = np.asarray(angles, dtype=float)
    fr, ft = np.asarray(radial, dtype=float), np.asarray(tangential, dtype=float)
    r = mean_radius
    w = np.full(th.shape, np.sum(fr) / (2.0 * np.pi * r) * r * r / axial_stiffness)
    v = np.zeros(th.shape)
    n = np.arange(2, harmonics + 1)[:, None]
    cn, sn = np.cos(n * th), np.sin(n * th)
    a, b = (cn @ fr) / (np.pi * r), (sn @ fr) / (np.pi * r)
    c, d = (cn @ ft) / (np.pi * r), (sn @ ft) / (np.pi * r)
    scale = r**4 / (bending_stiffness * (n[:, 0] ** 2 - 1.0) ** 2)
    wa, wb = scale * (a - d / n[:, 0]), scale * (b + c / n[:, 0])
    w += wa @ cn + wb @ sn
    v += (-wa / n[:, 0]) @ sn + (wb / n[:, 0]) @ cn
    return w, v


@dataclass(frozen=True)
class HousingCompliance:
    """Torsional compliance of the pin housing at the output [rad/(N m)] (SI):
    ``ring`` the in-plane deformation of the ring under the pin loads, ``tube`` its
    torsion as a tube, ``total`` their sum; ``max_displacement`` the largest radial
    ring displacement at a pin [m]."""

    ring: float
    tube: float
    total: float
    max_displacement: float


def housing_compliance(reducer, output_torque: float | None = None, crank_angle: float = 0.0) -> HousingCompliance:
    """Estimate of the pin housing's torsional compliance (design ``[housing]``).

    Each pin passes its disc force to its groove along the contact normal, which
    runs through the pitch point (on the line of centres, z_rp a from the housing
    centre; Litvin & Fuentes 2004, ch. 19): f_j = F_j (C_j - P)/|C_j - P| with the
    pin forces F_j of :func:`flexrv.analysis.pin_load.reducer_pin_loads`. Disc k loads
    its own slice of the ring (axial length L / n_discs, radial section from the pin
    circle R_p to the outer radius, mean radius the centre of the section): in-plane
    ring deformation by :func:`ring_displacements` (each disc's slice on its own, no
    axial coupling between the slices: an upper bound), and the energy gives the
    compliance at the output, C_ring = sum_j f_j . u_j / T^2 (Clapeyron: the
    strain energy sum f.u / 2 = C T^2 / 2). The torque then passes axially through
    the ring as a tube (polar moment pi (r_o^4 - R_p^4)/2) over its length L to the
    fixture: C_tube = L / (G J). Thin-ring theory on a ring whose thickness is ~0.4 of
    its radius and the slice length are estimates (stated in the budget's notes).
    Checked against a Tet10 FE solve of the same annulus slice under the same loads
    (tests/test_pin_seat.py): the FE energy is 1.3-1.6x the thin ring's, growing
    with mesh refinement by the load-introduction near field that the seat's contact
    law already counts, so the thin-ring bending is the right magnitude and not an
    overestimate; the ring length (``housing.ring_length_mm``, compliance ~ 1/L) is
    the larger uncertainty."""
    from flexrv.analysis.pin_load import reducer_pin_loads
    from flexrv.geometry.as_built import as_built
    from flexrv.geometry.cycloid import nominal_disc_pose

    h = reducer.housing
    if h is None:
        return HousingCompliance(0.0, 0.0, 0.0, 0.0)
    ss = reducer.second_stage
    torque = reducer.operating.rated_torque_Nm if output_torque is None else float(output_torque)
    mat = reducer.material("housing")
    e_mod, nu = mat.youngs_modulus, mat.poisson_ratio
    r_i, r_o = ss.pin_circle_radius, 0.5 * M_PER_MM * h.ring_outer_diameter_mm
    length = M_PER_MM * h.ring_length_mm
    width = length / ss.n_discs
    thick = r_o - r_i
    ei, ea = e_mod * width * thick**3 / 12.0, e_mod * width * thick
    r_mean = 0.5 * (r_i + r_o)
    ab = as_built(reducer)
    pins = np.asarray(ab.pins, dtype=float)
    th = np.arctan2(pins[:, 1], pins[:, 0])
    e_r = pins / np.linalg.norm(pins, axis=1)[:, None]
    e_t = np.stack([-e_r[:, 1], e_r[:, 0]], axis=1)
    energy, w_max = 0.0, 0.0
    for k in range(ss.n_discs):
        res = reducer_pin_loads(reducer, torque, crank_angle, disc=k)
        center, _ = nominal_disc_pose(ss.pin_count, ss.eccentricity, crank_angle + float(ab.chi0[k]))
        pitch = ss.pin_count * np.asarray(center)
        u = pins - pitch
        f = res.forces[:, None] * u / np.linalg.norm(u, axis=1)[:, None]
        fr, ft = np.sum(f * e_r, axis=1), np.sum(f * e_t, axis=1)
        w, v = ring_displacements(th, fr, ft, r_mean, ei, ea)
        energy += float(np.sum(fr * w + ft * v))
        w_max = max(w_max, float(np.max(np.abs(w[res.forces > 0])))) if np.any(res.forces > 0) else w_max
    g_mod = e_mod / (2.0 * (1.0 + nu))
    tube = length / (g_mod * 0.5 * np.pi * (r_o**4 - r_i**4))
    ring = energy / torque**2
    return HousingCompliance(ring=ring, tube=float(tube), total=ring + float(tube), max_displacement=w_max)


def housing_model_compliance(reducer) -> float:
    """The pin housing's torsional compliance c_h in the models and every budget
    [rad/(N m)]: :func:`housing_compliance` ``total`` (ring bending under
    the pin loads + tube torsion, an energy equivalent: the ring's ovalisation enters
    only through its strain energy) at the rated torque and crank angle 0 of the design without its errors
    (:func:`flexrv.design.manufacturing.nominal_design`), if the
    design has a ``[housing]`` table with ``body_model = "ring_estimate"``; else 0
    (rigid housing). One constant: the ring estimate is linear in the load (its
    pin-load pattern changes it only through the pins in mesh). The dynamic and
    quasi-static models turn the pin ring by phi_h = c_h M_h
    (:func:`flexrv.model.pins.pin_body_kernel`), the analytic budget adds c_h in series."""
    from flexrv.design.manufacturing import nominal_design, nominal_shared

    h = reducer.housing
    if h is None or h.body_model != "ring_estimate":
        return 0.0
    return nominal_shared(
        reducer, "housing_model_compliance", lambda r: float(housing_compliance(nominal_design(r)).total)
    )


@dataclass(frozen=True)
class StiffnessBudget:
    """Analytic series model of the torsional compliance at the output (SI).

    compliances : element -> torsional compliance [rad/(N m)] referred to the
    output; total : their sum; rigidity = 1 / total [N m/rad]; shares : element ->
    fraction of the total; torque : output torque [N m]; support_forces : (N,) force
    on each crank's support [N]."""

    compliances: dict
    total: float
    rigidity: float
    shares: dict
    torque: float
    support_forces: np.ndarray
    notes: tuple = ()  #: elements estimated but left out (below HOUSING_THRESHOLD), with their share


#: budget element names, shared with the quasi-static model's force groups where they coincide
BUDGET_ELEMENTS = (
    "pins",
    "needle_bearings",
    "support_bearings",
    "crank_bending",
    "pin_seats",
    "pin_bending",
    "housing",
    "carrier",
    "cycloid_disc",
)
#: budget elements that the dynamic and quasi-static models may lack (:func:`unmodelled_elements`): none since
#: the housing entered the models (``housing.body_model``); kept for the budgets' "unmodelled" entry
UNMODELLED_ELEMENTS = ()


def split_pin_path(compliances: dict, reducer) -> dict:
    """Split a budget's "pins" element (the whole pin path of the models' pin law,
    :func:`flexrv.analysis.pin_load.pin_contact_constant`) into the pin-disc contact
    ("pins"), the pin seats ("pin_seats") and the pin bending ("pin_bending", only
    where a pin has an unsupported span) by the path's tangent-compliance shares; the
    elements in series sum to the path's compliance."""
    from flexrv.analysis.pin_load import pin_contact_constant

    out = dict(compliances)
    if "pins" not in out or reducer.housing is None:
        return out
    shares = pin_contact_constant(reducer).shares
    path = out.pop("pins")
    for name in ("pins", "pin_seats", "pin_bending"):
        if name != "pin_bending" or shares[name] > 0.0:
            out[name] = shares[name] * path
    return out


def budget_from_group_shares(
    shares: dict, total: float, bending_fraction: float, reducer=None, torque: float | None = None
) -> tuple[dict, tuple]:
    """Budget elements [rad/(N m)] of a model's strain-energy shares
    (:meth:`flexrv.model.quasi_static.StaticModel.compliance_budget`, group -> fraction)
    times its tangent compliance ``total``: the crank-support group (bearings and crank
    bending in series) split by ``bending_fraction`` (the model's output
    ``crank_bending_fraction``) into support_bearings and crank_bending; with a
    ``reducer``, the pin path split (:func:`split_pin_path`) and the elements the model
    does not contain added (:func:`unmodelled_elements`). The one mapping of ``flexrv
    te`` (quasi-static) and ``flexrv stiffness-test`` (dynamic). Returns (compliances, notes)."""
    comp = {}
    for name, frac in shares.items():
        if frac <= 1e-8:  # groups that carry no strain energy (the load) are no element
            continue
        c = float(frac * total)
        if name == "crank_supports":
            comp["support_bearings"] = (1.0 - bending_fraction) * c
            comp["crank_bending"] = bending_fraction * c
        else:
            comp[name] = c
    if reducer is None:
        return comp, ()
    comp = split_pin_path(comp, reducer)
    extra, notes = unmodelled_elements(reducer, total, torque)
    comp.update(extra)
    return comp, notes


def unmodelled_elements(reducer, model_total: float, torque: float | None = None) -> tuple[dict, tuple]:
    """Budget elements that the dynamic and quasi-static models do not contain, and
    the budget notes on the housing and the pin seats. Since the housing is in the
    models (``housing.body_model = "ring_estimate"``: the elastic pin-ring rotation,
    :func:`housing_model_compliance`, the quasi-static budget's own ``housing``
    share) or rigid everywhere (``"rigid"``: left out of every budget, its estimate
    in a note), nothing is added: returns ({}, notes). Every budget (analytic,
    quasi-static, dynamic) gets the same notes; ``model_total`` [rad/(N m)] is the
    total the housing estimate's share refers to."""
    from flexrv.analysis.pin_load import pin_contact_constant

    if reducer.housing is None:
        return {}, ("housing: no [housing] table, pins rigidly seated, rigid housing",)
    pc = pin_contact_constant(reducer)
    seat = (
        f"pin seats: Palmgren line contact in series with the pin-disc contact; the groove's Hertz half-width "
        f"is {pc.seat_semi_angle:.2g} pin radii at the largest pin load ({pc.reference_load:.4g} N): a conformal "
        "seat spreads wider and is expected stiffer, so the element is a conservative (compliant) estimate"
    )
    if reducer.housing.body_model == "ring_estimate":
        return {}, (
            "housing: elastic rotation of the pin ring about the axis in every model (thin-ring + tube "
            "estimate, energy-equivalent torsional compliance: the ring's ovalisation enters only through "
            "its strain energy)",
            seat,
        )
    hc = housing_compliance(reducer, torque)
    share = hc.total / (model_total + hc.total)
    return {}, (
        f"housing: rigid (housing.body_model = 'rigid'); its thin-ring estimate would be {100 * share:.3g} % "
        "of the total",
        seat,
    )


def stiffness_budget(
    reducer, output_torque: float | None = None, crank_angle: float = 0.0, bodies: dict | None = None
) -> StiffnessBudget:
    """Torsional compliance of each element of the torque path, in series
    (output carrier held against the housing through the path carrier -> crank
    supports -> crank shaft -> eccentrics -> needle bearings -> discs -> pins):

    * pins: 1 / C_c with the tangent pin stiffness of the Palmgren pin-load solution
      (:func:`second_stage_stiffness`, ``c_mesh_tangent``);
    * needle_bearings: the needle bearings of all discs and cranks in parallel on
      the lever a_w, each with the direction-resolved tangent of :cite:`seed004`'s
      empirical law as the models integrate it (F = (0.9 C delta)^(10/9),
      delta = |d| - c_r with the radial clearance c_r, K_Hc = C F^0.1): along its
      load K_Hc, across it F / |d| (the load's direction turns with d), so a
      bearing whose force F_jk (:func:`crank_bearing_forces`; disc k's pin
      resultant turned by 2 pi k / n_discs with its eccentric) makes the angle
      beta with the tangent t_j gives a_w^2 (K_Hc cos^2 beta + F/|d| sin^2 beta);
      :cite:`seed004`'s C_Hc is the limit beta = 0;
    * support_bearings and crank_bending: each crank's support carries the couple
      part of its needle forces, T / (N a_w) tangential (the discs' radial pin
      resultants, equal and opposite for two discs 180 deg apart, cancel on the
      crank; :func:`crank_bearing_forces`), through the law of the dynamic and
      quasi-static models (:func:`flexrv.contact.tapered_roller.support_deflection`
      with :func:`support_constants`): the bearings' tangent K_b and the shaft's
      k_bend in series per crank, the N cranks in parallel on the lever a_w:
      1 / (a_w^2 sum_j t_j . K_b,j t_j) and 1 / (N a_w^2 k_bend);
    * pins, pin_seats, pin_bending: the pin path's compliance (disc contact, seat,
      bending in series, :func:`flexrv.analysis.pin_load.pin_contact_constant`) split
      by :func:`split_pin_path`;
    * housing: the pin housing ring and tube, c_h of the models
      (:func:`housing_model_compliance`, rated torque; ``housing.body_model =
      "rigid"``: left out, its estimate in ``notes``);
    * carrier and cycloid_disc: the elastic bodies' torsional compliances
      at the output, passed in ``bodies`` ({"carrier": c, "cycloid_disc": c} [rad/(N m)],
      e.g. from :func:`flexrv.fem.disc.body_compliances`: the FE lives in a layer above
      this module, so the caller computes it); an element absent from ``bodies`` (or
      None) is rigid and not listed. The carrier's g^T C g (bore forces per unit
      torque, flange held) and the discs' mean f^T C f / n_discs are series terms
      (the disc's with T / n_discs per disc; in the models the pins carry 0.964 of
      it on the rv40e, the first stage the rest, so the quasi-static disc share is
      7 % lower, tests/test_bodies.py).

    Neglected (stated): the first stage (its mesh compliance reaches the output
    only through the eccentricity's lever, < 0.1 % in the quasi-static budget), the
    crank torsion and the main bearing (not in the torque path of the
    rigid model either).
    """
    from flexrv.analysis.pin_load import reducer_pin_loads
    from flexrv.contact.tapered_roller import crank_support_force, support_deflection

    torque = reducer.operating.rated_torque_Nm if output_torque is None else float(output_torque)
    st = second_stage_stiffness(reducer, torque, crank_angle)
    n = reducer.first_stage.n_planets
    a_w = reducer.first_stage.center_distance
    sc, angles, linear = support_constants(reducer)
    rigid = sc._replace(k_bend=0.0)
    th = crank_hole_angles(n)
    f_sup = abs(torque) / (n * a_w)
    k_bear = 0.0
    for j in range(n):
        t = np.array([-np.sin(th[j]), np.cos(th[j])])
        _, _, b = support_deflection(f_sup * t, sc, angles, linear)
        _, _, kxx, kxy, kyy, *_ = crank_support_force(b[0], b[1], 0.0, 0.0, rigid, angles, linear, b[0], b[1])
        k_bear += t @ np.array([[kxx, kxy], [kxy, kyy]]) @ t
    nb, nd = reducer.needle_bearing, reducer.second_stage.n_discs
    c_emp = float(needle_radial_stiffness(1.0, nb.roller_count, nb.roller_length_mm * M_PER_MM))  # K_Hc = C F^0.1
    clear = nb.clearance_per_side
    k_needle = 0.0
    pins = reducer_pin_loads(reducer, torque, crank_angle)
    for k in range(nd):
        turn = 2.0 * np.pi * k / nd
        rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
        forces = crank_bearing_forces(rot @ pins.resultant, torque / nd, a_w, n)
        for j in range(n):
            fm = float(np.linalg.norm(forces[j]))
            cos2 = (forces[j] @ np.array([-np.sin(th[j]), np.cos(th[j])]) / fm) ** 2
            k_along = c_emp * fm**0.1
            k_across = fm / (fm**0.9 / (0.9 * c_emp) + clear)
            k_needle += a_w**2 * (k_along * cos2 + k_across * (1.0 - cos2))
    comp = {
        "pins": float(1.0 / st.c_mesh_tangent),
        "needle_bearings": float(1.0 / k_needle),
        "support_bearings": float(1.0 / (a_w**2 * k_bear)),
        "crank_bending": float(1.0 / (n * a_w**2 * sc.k_bend)) if sc.k_bend > 0.0 else 0.0,
    }
    for name in ("carrier", "cycloid_disc"):
        value = (bodies or {}).get(name)
        if value is not None:
            if not (np.isfinite(value) and value >= 0.0):
                raise ValueError(f"bodies[{name!r}] = {value!r} must be a finite compliance >= 0 [rad/(N m)]")
            comp[name] = float(value)
    comp = split_pin_path(comp, reducer)
    c_h = housing_model_compliance(reducer)
    if c_h > 0.0:
        comp["housing"] = c_h
    extra, notes = unmodelled_elements(reducer, float(sum(comp.values())), torque)
    comp.update(extra)
    total = float(sum(comp.values()))
    return StiffnessBudget(
        compliances=comp,
        total=total,
        rigidity=1.0 / total,
        shares={k: v / total for k, v in comp.items()},
        torque=torque,
        support_forces=np.full(n, f_sup),
        notes=notes,
    )
