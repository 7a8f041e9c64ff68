"""The drive's parameters shared by several force elements and the members (SI units).

Every force element builds its own typed parameters from the design (the element's
``parameters(reducer, drive)``: :mod:`flexrv.model.gear_stage`, :mod:`flexrv.model.cranks_discs`,
:mod:`flexrv.model.pins`, :mod:`flexrv.model.main_bearing_rigid`, :mod:`flexrv.model.loads`);
the quantities several of them and the members read (counts, ratio, nominal positions of
cranks and discs, masses and inertias, the operating point) are built once here
(:func:`drive_parameters`) and passed to each element's builder, never copied into it.

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

Why frozen dataclasses (not numba NamedTuples) for the element parameters: they are
host-side inputs of the groups (arrays of any shape, dicts of part compliances, the
design's model switches), pickled to dask workers with the model; the kernels read
the groups' typed packs (:mod:`flexrv.model.core.params`), built from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexrv.geometry.as_built import AsBuilt, as_built
from flexrv.geometry.kinematics import total_ratio
from flexrv.units import M_PER_MM


@dataclass(frozen=True)
class DriveParameters:
    """The drive's shared numbers (SI). Built by :func:`drive_parameters`."""

    # counts and ratio
    n_cranks: int
    n_discs: int
    z_s: int
    z_p: int
    z_c: int
    z_rp: int
    ratio: float
    # nominal kinematics of the members
    center_distance: float  #: working centre distance a_w of the first stage = crank circle radius [m]
    crank_angles: np.ndarray  #: (N,) angular positions beta_j0 of the cranks on the carrier [rad]
    eccentricity: float
    chi0: np.ndarray  #: (n_discs,) initial clockwise eccentric angle of each disc (as built) [rad]
    disc_rot0: np.ndarray  #: (n_discs,) initial disc rotation psi_k0 = chi0_k / z_c [rad]
    # masses and inertias of the members
    crank_mass: float
    crank_inertia: float
    planet_mass: float  #: planet gear + gear seat (part of crank_mass) [kg]
    planet_inertia: float  #: its inertia about the crank axis (part of crank_inertia) [kg m^2]
    disc_mass: float
    disc_inertia: float
    carrier_mass: float
    carrier_inertia: float
    input_inertia: float
    # operating point (design [operating])
    input_speed: float
    speed_ramp_time: float
    load_torque: float
    load_ramp: tuple[float, float]
    # contact settings of the pins and the needle bearings (design [contact])
    contact_depth: float  #: penetration depth of the impact law's full damping [m]
    friction_velocity: float  #: regularisation speed v_reg of the friction laws [m/s] (0 = friction off)
    #: the as-built geometry (:func:`flexrv.geometry.as_built.as_built`: nominal + the design's [errors]),
    #: built once and read by every element's builder
    as_built: AsBuilt = field(repr=False, compare=False)


def _cyl_mass(rho, d, length):
    return rho * math.pi * 0.25 * d * d * length


def _masses(reducer) -> dict:
    """Crank (planet gear + shaft), planet, disc and carrier masses and inertias
    (homogeneous cylinders, see :func:`drive_parameters`)."""
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
    m_shaft = sum(k * _cyl_mass(rho_c, d * M_PER_MM, l * M_PER_MM) for d, l, k in parts)
    crank_inertia = 0.5 * m_planet * r_pitch_p**2 + sum(
        k * 0.5 * _cyl_mass(rho_c, d * M_PER_MM, l * M_PER_MM) * (0.5 * M_PER_MM * d) ** 2 for d, l, k in parts
    )
    d_seat, l_seat = cs.gear_seat_diameter_mm * M_PER_MM, cs.gear_seat_length_mm * M_PER_MM
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


def drive_parameters(reducer) -> DriveParameters:
    """Derive :class:`DriveParameters` from a design (no FE build, no pin-load analysis).

    Mass estimates (homogeneous cylinders, density of the part's material):
    crank = planet gear (pitch-circle disc, face width b) + gear seat + two support
    journals + two eccentric journals; disc = annulus between the centre hole and
    the root circle R_p - r_rp - a minus the crank holes (J = m (R^2 + r^2)/2 of
    the annulus, hole correction by parallel axes). The discs' initial eccentric
    angles are the as-built ones (:func:`flexrv.geometry.as_built.as_built`)."""
    fs, ss, op, ct = reducer.first_stage, reducer.second_stage, reducer.operating, reducer.contact
    n = fs.n_planets
    z_s, z_p, z_c, z_rp = fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count
    ab = as_built(reducer)
    return DriveParameters(
        n_cranks=n,
        n_discs=ss.n_discs,
        z_s=z_s,
        z_p=z_p,
        z_c=z_c,
        z_rp=z_rp,
        ratio=float(total_ratio(z_s, z_p, z_c, z_rp)),
        center_distance=fs.center_distance,
        crank_angles=2.0 * math.pi * np.arange(n) / n,
        eccentricity=ss.eccentricity,
        chi0=ab.chi0,
        disc_rot0=ab.disc_rot0,
        **_masses(reducer),
        input_speed=op.input_speed,
        speed_ramp_time=op.speed_ramp_time_s,
        load_torque=op.load_torque_Nm,
        load_ramp=(op.load_ramp_start_s, op.load_ramp_end_s),
        contact_depth=ct.impact_damping_depth_mm * M_PER_MM,
        friction_velocity=ct.friction_velocity_mm_per_s * M_PER_MM if ct.friction else 0.0,
        as_built=ab,
    )
