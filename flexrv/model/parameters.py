"""Derived parameters of the rigid multibody model (SI units).

Everything the model's builders need that is not a field of the design is
computed here once from a validated :class:`flexrv.design.Reducer`: member
masses and inertias (from the modelled geometry, homogeneous steel cylinders),
base radii of the first stage, nominal positions of cranks, eccentrics and disc
holes, and the contact constants.

Planar model (why): every force path that produces transmission error lies in
the reducer's transverse plane (gear meshes along the line of action, pin–disc
and needle contacts with normals in the plane, crank supports radial). Members
therefore carry the planar coordinates (x, y, rotation) of their centre; the
carrier additionally carries the out-of-plane coordinates (z, rx, ry) of the
main bearing so that external axial force and tilting moment load it. With rigid
members and frictionless contacts the out-of-plane motion is decoupled from the
in-plane motion, so a 3-D rigid-body formulation would add twelve DOF per
member group without changing TE, speeds or contact forces; the flexible-bearing
model that tilts the carrier replaces the main-bearing element, not this choice.

Sign conventions: all rotations counter-clockwise positive about +z (the input
turns positive, so does the output). The crank's eccentric direction is written
as in :mod:`flexrv.geometry.cycloid`: e (sin chi, cos chi) with the clockwise
angle chi = chi0_k - phi_crank; disc k's profile frame is turned by its
rotation coordinate psi_k, which starts at the conjugate value chi0_k / z_c
(:func:`flexrv.geometry.cycloid.nominal_disc_pose`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexrv.analysis.path_compliances import model_compliances, planet_torsion_compliances
from flexrv.analysis.pin_load import pin_contact_constant
from flexrv.analysis.torsional import housing_model_compliance, support_constants
from flexrv.contact.hertz import LINE_EXPONENT, effective_modulus, line_contact_stiffness, series_stiffness
from flexrv.contact.laws import effective_pin_friction
from flexrv.geometry.as_built import as_built
from flexrv.geometry.kinematics import total_ratio
from flexrv.units import M_PER_MM


class _Lazy:
    """The value of a :class:`RigidParameters` field that is built on first access."""

    def __repr__(self) -> str:
        return "LAZY"

    def __reduce__(self):
        return "LAZY"  # pickled by reference: the one sentinel in every process


#: a field's default: built on first access from the design (:data:`_LAZY_BUILDERS`)
LAZY = _Lazy()


@dataclass(frozen=True)
class RigidParameters:
    """All numbers of the rigid model (SI). Built by :func:`rigid_parameters`."""

    # counts
    n_cranks: int
    n_discs: int
    z_s: int
    z_p: int
    z_c: int
    z_rp: int
    ratio: float
    # first stage
    base_radius_sun: float
    base_radius_planet: float
    center_distance: float
    working_pressure_angle: float
    normal_backlash: float
    crank_angles: np.ndarray  #: (N,) angular positions beta_j0 of the cranks on the carrier [rad]
    # second stage
    eccentricity: float
    pin_circle_radius: float
    pin_radius: float
    d_radius: float
    d_pin_radius: float
    d_rotation: float
    disc_width: float
    pins: np.ndarray  #: (z_rp, 2) pin centres in the housing frame [m]
    chi0: np.ndarray  #: (n_discs,) initial clockwise eccentric angle of each disc [rad]
    disc_rot0: np.ndarray  #: (n_discs,) initial disc rotation psi_k0 = chi0_k / z_c [rad]
    holes: np.ndarray  #: (n_discs, N, 2) crank-hole centres in each disc's frame [m]
    # masses
    crank_mass: float
    crank_inertia: float
    planet_mass: float  #: planet gear + gear seat (part of crank_mass) [kg]
    planet_inertia: float  #: its inertia about the crank axis (part of crank_inertia) [kg m^2]
    disc_mass: float
    disc_inertia: float
    carrier_mass: float
    carrier_inertia: float
    input_inertia: float
    # compliances
    support_stiffness: (
        float  #: linear support law only: radial stiffness of one crank (two bearings) [N/m]; NaN otherwise
    )
    support_damping: float
    support_law: np.ndarray  #: (7,) constants of flexrv.contact.tapered_roller.crank_support_force
    support_roller_angles: np.ndarray  #: (Z,) roller spacing of a support bearing [rad] (empty: linear law)
    support_linear: bool  #: the linear support law (crankshaft.support_bearing_model = "linear")
    main_bearing_stiffness: np.ndarray  #: (5,) x, y, z, rx, ry [N/m, N m/rad]
    main_bearing_damping: np.ndarray
    pin_c_max: float
    contact_depth: float
    pin_penetration_limit: float  #: [m] a run stops as failed beyond it
    needle_penetration_limit: float  #: [m]
    needle_roller_count: int
    needle_roller_k: float  #: roller constant (inner + outer line contacts in series) [N/m^(10/9)]
    needle_pitch_ratio: float  #: gamma = D / d_m of the needle bearing
    needle_c_max: float
    # drive and load
    input_speed: float
    speed_ramp_time: float
    load_torque: float
    load_ramp: tuple[float, float]
    rated_torque: float
    external_axial_force: float
    external_radial_force: float
    tilting_moment: float
    # ---- actual (as-built) geometry, one entry per element. Nominal values for an ideal
    # design; manufacturing and assembly errors (design ``[errors]``) enter only here, so
    # every model (analytic, dynamic, quasi-static) reads the same as-built geometry.
    pin_radii: np.ndarray  #: (z_rp,) actual pin radii [m] (pins: actual centres)
    disc_profile: np.ndarray  #: (n_discs, 3) actual (d_radius [m], d_pin_radius [m], d_rotation [rad]) per disc
    profile_harmonics: np.ndarray  #: (n_discs, H, 3) (order [-], amplitude [m], phase [rad]): material added
    #: along the profile normal, delta(phi) = sum A cos(order phi + phase), phi the curve parameter;
    #: it reduces the pin gap by delta(phi*) at the contact's foot point
    eccentricities: np.ndarray  #: (N, n_discs) eccentric radius of crank j under disc k [m]
    eccentric_phase_errors: np.ndarray  #: (N, n_discs) added to chi0_k: chi = chi0_k + err_jk - phi_j [rad]
    crank_bores: np.ndarray  #: (N, 2) crank-bore centres in the carrier frame [m]
    needle_clearances: np.ndarray  #: (N, n_discs) radial clearance of each needle bearing [m]
    support_clearances: np.ndarray  #: (N,) radial clearance of each crank's support bearings [m]
    sun_runout: np.ndarray  #: (2,) amplitude [m] along the lines of action, phase [rad]
    planet_runout: np.ndarray  #: (N, 2) amplitude [m], phase [rad]
    planet_phase_errors: np.ndarray  #: (N,) assembly phase error of each planet on its crank [rad]
    # ---- built on first access (:data:`LAZY`): only the element that reads one pays for it
    #: (2N, 2N) compliance [m/N] of the cranks' support points in the carrier frame (FE carrier,
    #: :func:`flexrv.fem.carrier.crank_support_compliance`, plus ``carrier_parts``); (0, 0): rigid
    #: carrier (``carrier.body_model``) without parts
    carrier_compliance: np.ndarray = field(default=LAZY, repr=False)
    #: element -> its (2N, 2N) part of ``carrier_compliance`` [m/N]: support-bearing rings, carrier joints
    #: (:func:`flexrv.analysis.path_compliances.model_compliances`)
    carrier_parts: dict = field(default=LAZY, repr=False)
    #: torsional compliances per crank between planet gear and eccentrics [rad/(N m)], in series with
    #: each mesh (:mod:`flexrv.model.gear_stage`): crank torsion, planet spline
    crank_torsion_compliance: float = 0.0
    planet_spline_compliance: float = 0.0
    #: (n_discs, 3, 3) compliance of each disc's rim pose (x, y, psi) relative to its hub per unit pin force
    #: (:func:`flexrv.fem.disc.rim_compliance`); (0, 3, 3): rigid discs (``second_stage.disc_body_model``)
    disc_compliance: np.ndarray = field(default=LAZY, repr=False)
    #: torsional compliance of the pin housing about the axis [rad/(N m)]
    #: (:func:`flexrv.analysis.torsional.housing_model_compliance`, design ``housing.body_model``); 0: rigid
    housing_compliance: float = field(default=LAZY, repr=False)
    #: pin-contact constant [N/m^e] and exponent (:func:`_pin_law`: the analytic pin-load distribution)
    pin_k: float = field(default=LAZY, repr=False)
    pin_exponent: float = field(default=LAZY, repr=False)
    # friction (design [contact] friction fields; 0 = off)
    pin_friction: float = 0.0  #: effective pin coefficient min(mu_pin_disc, mu_pin_seat) [-]
    needle_friction: float = 0.0  #: constant friction coefficient of the needle bearings [-]
    needle_friction_radius: float = 0.0  #: d/2 of the needle friction moment, the eccentric journal radius [m]
    friction_velocity: float = 0.0  #: regularisation speed v_reg [m/s] (0 = friction off)
    #: the design the :data:`LAZY` fields are built from
    reducer: object = field(default=None, repr=False, compare=False)

    def __getattribute__(self, name):
        value = object.__getattribute__(self, name)
        if value is LAZY:  # built once, on first access (frozen: set through object.__setattr__)
            for key, built in _LAZY_BUILDERS[name](object.__getattribute__(self, "reducer")).items():
                if object.__getattribute__(self, key) is LAZY:
                    object.__setattr__(self, key, built)
            value = object.__getattribute__(self, name)
        return value


def _cyl_mass(rho, d, length):
    return rho * math.pi * 0.25 * d * d * length


def body_compliance_matrices(reducer) -> tuple[np.ndarray, np.ndarray]:
    """The elastic bodies' matrices of the models, per the design's switches:
    the carrier's (2N, 2N) support-point compliance if ``carrier.body_model =
    "condensed_fe"`` (and the design has a ``[carrier]`` table), else (0, 0); the
    discs' (n_discs, 3, 3) rim compliance if ``second_stage.disc_body_model =
    "condensed_fe"``, else (0, 3, 3). From the cached FE condensations
    (:mod:`flexrv.fem.carrier`, :mod:`flexrv.fem.disc`; cold: about a minute each).
    Functions of the design without its errors: shared by its error sets inside
    :func:`flexrv.design.manufacturing.shared_nominal_constants`."""
    from flexrv.design.manufacturing import nominal_shared

    return nominal_shared(reducer, "body_compliance_matrices", _body_compliance_matrices)


def _body_compliance_matrices(reducer) -> tuple[np.ndarray, np.ndarray]:
    carrier_c = np.zeros((0, 0))
    cr = reducer.carrier
    if cr is not None and cr.body_model == "condensed_fe":
        from flexrv.fem.carrier import crank_support_compliance

        carrier_c = crank_support_compliance(reducer)
    disc_c = np.zeros((0, 3, 3))
    if reducer.second_stage.disc_body_model == "condensed_fe":
        from flexrv.fem.disc import rim_compliance

        disc_c = np.repeat(rim_compliance(reducer)[None], reducer.second_stage.n_discs, axis=0)
    return np.ascontiguousarray(carrier_c, dtype=float), np.ascontiguousarray(disc_c, dtype=float)


def with_bodies(reducer, bodies) -> object:
    """The design with its elastic-body switches set from ``bodies`` (names among
    ``carrier``, ``cycloid_disc``): a named body becomes ``condensed_fe``, an unnamed
    one ``rigid`` (the one parameter route of ``--parts``: the switches are design
    fields)."""
    bodies = set(bodies)
    ss = reducer.second_stage.model_copy(
        update={"disc_body_model": "condensed_fe" if "cycloid_disc" in bodies else "rigid"}
    )
    update = {"second_stage": ss}
    if reducer.carrier is not None:
        update["carrier"] = reducer.carrier.model_copy(
            update={"body_model": "condensed_fe" if "carrier" in bodies else "rigid"}
        )
    elif "carrier" in bodies:
        from flexrv.errors import ConfigError

        raise ConfigError("parts = carrier needs the design's [carrier] table (carrier geometry); this design has none")
    return reducer.model_copy(update=update)


def _first_stage(reducer) -> dict:
    """Counts, ratio and the first stage's base radii, working pressure angle and crank positions."""
    fs, ss = reducer.first_stage, reducer.second_stage
    n = fs.n_planets
    z_s, z_p, z_c, z_rp = fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count
    alpha = fs.pressure_angle
    rb_s = 0.5 * fs.module * z_s * math.cos(alpha)
    rb_p = 0.5 * fs.module * z_p * math.cos(alpha)
    a_w = fs.center_distance
    alpha_w = math.acos((rb_s + rb_p) / a_w)
    return dict(
        n_cranks=n,
        n_discs=ss.n_discs,
        z_s=z_s,
        z_p=z_p,
        z_c=z_c,
        z_rp=z_rp,
        ratio=float(total_ratio(z_s, z_p, z_c, z_rp)),
        base_radius_sun=rb_s,
        base_radius_planet=rb_p,
        center_distance=a_w,
        working_pressure_angle=alpha_w,
        normal_backlash=fs.backlash * math.cos(alpha_w),
        crank_angles=2.0 * math.pi * np.arange(n) / n,
        **dict(zip(("crank_torsion_compliance", "planet_spline_compliance"), planet_torsion_compliances(reducer))),
    )


def _masses(reducer) -> dict:
    """Crank (planet gear + shaft), planet, disc and carrier masses and inertias
    (homogeneous cylinders, see :func:`rigid_parameters`)."""
    fs, ss, cs = reducer.first_stage, reducer.second_stage, reducer.crankshaft
    n, nd = fs.n_planets, ss.n_discs
    rho_g = reducer.material("gears").density_kg_m3
    rho_c = reducer.material("crankshaft").density_kg_m3
    rho_d = reducer.material("cycloid_disc").density_kg_m3
    r_pitch_p = 0.5 * fs.module * fs.planet_teeth
    m_planet = rho_g * math.pi * r_pitch_p**2 * fs.face_width
    parts = [
        (cs.gear_seat_diameter_mm, cs.gear_seat_length_mm, 1),
        (cs.support_journal_diameter_mm, cs.support_journal_length_mm, 2),
        (cs.eccentric_journal_diameter_mm, cs.eccentric_journal_length_mm, nd),
    ]
    m_shaft = sum(k * _cyl_mass(rho_c, d * 1e-3, l * 1e-3) for d, l, k in parts)
    crank_inertia = 0.5 * m_planet * r_pitch_p**2 + sum(
        k * 0.5 * _cyl_mass(rho_c, d * 1e-3, l * 1e-3) * (0.5e-3 * d) ** 2 for d, l, k in parts
    )
    d_seat, l_seat = cs.gear_seat_diameter_mm * 1e-3, cs.gear_seat_length_mm * 1e-3
    m_seat = _cyl_mass(rho_c, d_seat, l_seat)
    r_out = ss.pin_circle_radius - ss.pin_radius - ss.eccentricity
    r_in = ss.center_hole_radius
    r_h = reducer.crank_hole_radius
    b = ss.disc_width
    a_w = fs.center_distance
    m_ann = rho_d * math.pi * (r_out**2 - r_in**2) * b
    m_hole = rho_d * math.pi * r_h**2 * b
    return dict(
        crank_mass=m_planet + m_shaft,
        crank_inertia=crank_inertia,
        planet_mass=m_planet + m_seat,
        planet_inertia=0.5 * m_planet * r_pitch_p**2 + 0.5 * m_seat * (0.5 * d_seat) ** 2,
        disc_mass=m_ann - n * m_hole,
        disc_inertia=0.5 * m_ann * (r_out**2 + r_in**2) - n * m_hole * (0.5 * r_h**2 + a_w**2),
        carrier_mass=reducer.inertia.carrier_mass_kg,
        carrier_inertia=reducer.inertia.carrier_inertia_kg_m2,
        input_inertia=reducer.inertia.input_shaft_inertia_kg_m2,
    )


def _contacts(reducer) -> dict:
    """Pin, needle and crank-support contact constants, limits and friction. The pin path
    is the pin-disc contact, pin seat and pin bending in series
    (:func:`flexrv.analysis.pin_load.pin_contact_constant`, the one constant of every model)."""
    cs, nb, ct = reducer.crankshaft, reducer.needle_bearing, reducer.contact
    depth = ct.impact_damping_depth_mm * 1e-3
    e_nb = effective_modulus(
        reducer.material("crankshaft").youngs_modulus,
        reducer.material("crankshaft").poisson_ratio,
        reducer.material("rolling_elements").youngs_modulus,
        reducer.material("rolling_elements").poisson_ratio,
    )
    k_roll = float(line_contact_stiffness(nb.roller_length_mm * 1e-3, e_nb))
    d_roll = nb.roller_diameter_mm * 1e-3
    dm = cs.eccentric_journal_diameter_mm * 1e-3 + d_roll
    support_law, support_angles, support_linear = support_constants(reducer)
    return dict(
        support_stiffness=(2.0 * cs.support_bearing_radial_stiffness_N_per_m if support_linear else float("nan")),
        support_damping=2.0 * cs.support_bearing_damping_Ns_per_m,
        support_law=support_law,
        support_roller_angles=support_angles,
        support_linear=support_linear,
        pin_c_max=ct.pin_max_damping_Ns_per_m,
        contact_depth=depth,
        pin_penetration_limit=ct.pin_penetration_limit_um * 1e-6,
        needle_penetration_limit=ct.needle_penetration_limit_um * 1e-6,
        needle_roller_count=nb.roller_count,
        needle_roller_k=float(series_stiffness(k_roll, k_roll, LINE_EXPONENT)),
        needle_pitch_ratio=d_roll / dm,
        needle_c_max=ct.pin_max_damping_Ns_per_m,
        pin_friction=effective_pin_friction(ct.pin_friction_coefficient, ct.pin_seat_friction_coefficient)
        if ct.friction
        else 0.0,
        needle_friction=ct.needle_friction_coefficient if ct.friction else 0.0,
        needle_friction_radius=0.5 * M_PER_MM * cs.eccentric_journal_diameter_mm,
        friction_velocity=ct.friction_velocity_mm_per_s * M_PER_MM if ct.friction else 0.0,
    )


def _pin_law(reducer) -> dict:
    """The pin law's constant and exponent: the pin path = pin-disc contact, pin seat and pin
    bending in series (:func:`flexrv.analysis.pin_load.pin_contact_constant`, the one constant
    of every model, matched at the largest pin load of the analytic distribution); the impact
    law takes the seeds' exponent, matched to the Hertz line law at the damping depth."""
    ct = reducer.contact
    k_line = pin_contact_constant(reducer).k
    depth = ct.impact_damping_depth_mm * 1e-3
    if ct.pin_law == "hertz_line":
        return {"pin_k": k_line, "pin_exponent": LINE_EXPONENT}
    return {"pin_k": k_line * depth ** (LINE_EXPONENT - ct.impact_exponent), "pin_exponent": ct.impact_exponent}


def _bodies(reducer) -> dict:
    """The elastic bodies' compliance matrices (:func:`body_compliance_matrices`), the carrier's
    with the support-bearing rings and the pillar joints at the as-built support points
    (:func:`flexrv.analysis.path_compliances.model_compliances`)."""
    carrier_c, disc_c = body_compliance_matrices(reducer)
    path = model_compliances(reducer, as_built(reducer).crank_bores)
    return {
        "carrier_compliance": path.support_compliance(carrier_c),
        "carrier_parts": path.support_parts,
        "disc_compliance": disc_c,
    }


#: field -> builder(reducer) -> {field: value} of the :data:`LAZY` fields (one builder may fill several)
_LAZY_BUILDERS = {
    "carrier_compliance": _bodies,
    "carrier_parts": _bodies,
    "disc_compliance": _bodies,
    "housing_compliance": lambda reducer: {"housing_compliance": housing_model_compliance(reducer)},
    "pin_k": _pin_law,
    "pin_exponent": _pin_law,
}


def _main_bearing(reducer) -> dict:
    """The rigid main bearing's stiffness (x, y, z, rx, ry) and carrier-mode damping."""
    mb = reducer.main_bearing
    k_r = mb.rigid_radial_stiffness_N_per_m
    s = mb.row_spacing_mm * 1e-3
    kmb = np.array([k_r, k_r, mb.rigid_axial_stiffness_N_per_m, k_r * (s / 2) ** 2, k_r * (s / 2) ** 2])
    cmb = (
        2.0
        * mb.rigid_damping_ratio
        * np.sqrt(
            kmb * np.array([reducer.inertia.carrier_mass_kg] * 3 + [reducer.inertia.carrier_inertia_kg_m2 / 2] * 2)
        )
    )
    return dict(main_bearing_stiffness=kmb, main_bearing_damping=cmb)


def _operating(reducer) -> dict:
    """Drive and load of the run (design ``[operating]``)."""
    op = reducer.operating
    return dict(
        input_speed=op.input_speed,
        speed_ramp_time=op.speed_ramp_time_s,
        load_torque=op.load_torque_Nm,
        load_ramp=(op.load_ramp_start_s, op.load_ramp_end_s),
        rated_torque=op.rated_torque_Nm,
        external_axial_force=op.external_axial_force_N,
        external_radial_force=op.external_radial_force_N,
        tilting_moment=op.tilting_moment_Nm,
    )


def _second_stage(reducer) -> dict:
    """The second stage's nominal geometry and the as-built geometry of every element
    (nominal + the design's [errors], :func:`flexrv.geometry.as_built.as_built`, one place)."""
    ss = reducer.second_stage
    ab = as_built(reducer)
    return dict(
        eccentricity=ss.eccentricity,
        pin_circle_radius=ss.pin_circle_radius,
        pin_radius=ss.pin_radius,
        d_radius=ss.modification_shift,
        d_pin_radius=ss.modification_equidistant,
        d_rotation=ss.modification_rotation,
        disc_width=ss.disc_width,
        pins=ab.pins,
        chi0=ab.chi0,
        disc_rot0=ab.disc_rot0,
        holes=ab.holes,
        pin_radii=ab.pin_radii,
        disc_profile=ab.disc_profile,
        profile_harmonics=ab.profile_harmonics,
        eccentricities=ab.eccentricities,
        eccentric_phase_errors=ab.eccentric_phase_errors,
        crank_bores=ab.crank_bores,
        needle_clearances=ab.needle_clearances,
        support_clearances=ab.support_clearances,
        sun_runout=ab.sun_runout,
        planet_runout=ab.planet_runout,
        planet_phase_errors=ab.planet_phase_errors,
    )


def rigid_parameters(reducer) -> RigidParameters:
    """Derive :class:`RigidParameters` from a design.

    Mass estimates (homogeneous cylinders, density of the part's material):
    crank = planet gear (pitch-circle disc, face width b) + gear seat + two support
    journals + two eccentric journals; disc = annulus between the centre hole and
    the root circle R_p - r_rp - a minus the crank holes (J = m (R^2 + r^2)/2 of
    the annulus, hole correction by parallel axes). Rigid main bearing: the
    design's radial and axial stiffness (``main_bearing.rigid_*``, estimates with
    provenance in the presets), tilting k_r (s/2)^2 with the row spacing s, and
    carrier-mode damping 2 zeta sqrt(k m) (the ball-resolved and flexible
    main-bearing models replace it).

    The expensive parameters are built on first access (:data:`LAZY`): the elastic bodies'
    FE condensations when the crank supports or the pins are built, the analytic pin-load
    distribution behind the pin law and the housing's compliance when the pins are built; a
    caller that reads masses or geometry only (e.g. a workflow's moment balance) builds none.
    """
    return RigidParameters(
        **_first_stage(reducer),
        **_second_stage(reducer),
        **_masses(reducer),
        **_contacts(reducer),
        **_main_bearing(reducer),
        **_operating(reducer),
        reducer=reducer,
    )
