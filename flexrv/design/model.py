"""Validated data model of an RV reducer (pydantic v2).

Field names carry their unit whenever it is not SI (``module_mm``,
``pressure_angle_deg``); the ``Reducer`` object exposes SI accessors for everything
the lower layers need (``reducer.first_stage.module`` in metres, etc.).

Every model forbids unknown fields and NaN/inf, and every number has an allowed
range; cross-field consistency (pin count vs disc teeth, undercut, parts that do
not fit) is checked in ``model_validator``s so a bad design fails with one clear
message naming the field, the value and the allowed range.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import Field, field_validator, model_serializer, model_validator

from flexrv.design._base import _bad, _Strict, floor
from flexrv.units import M_PER_MM, M_PER_UM, RAD_PER_DEG

#: allowed transverse contact ratio of the first stage: below 1 the mesh loses
#: contact between pairs; above 2.5 a spur pair needs unusually long addenda
#: (an RV first stage runs at 1.2-1.8). A mesh outside this range made ``simulate``
#: fail at t = 0 instead of being refused here.
CONTACT_RATIO_RANGE = (1.0, 2.5)


# --------------------------------------------------------------------------- stages
class FirstStage(_Strict):
    """Involute planetary first stage: sun on the input shaft, N planets each fixed
    to one crankshaft (N planets = N crankshafts)."""

    sun_teeth: int = Field(ge=8, le=200, description="Sun gear teeth z_s [-]")
    planet_teeth: int = Field(ge=8, le=400, description="Planet gear teeth z_p [-]")
    module_mm: float = Field(gt=0.2, le=20.0, description="Normal module m_n [mm]")
    pressure_angle_deg: float = Field(ge=14.5, le=30.0, description="Pressure angle alpha_n [deg]")
    sun_profile_shift: float = Field(ge=-1.0, le=1.5, description="Sun profile shift coefficient x_1 [-]")
    planet_profile_shift: float = Field(ge=-1.5, le=1.5, description="Planet profile shift coefficient x_2 [-]")
    face_width_mm: float = Field(
        ge=1.0,
        le=200.0,
        description="Common face width b [mm]",
        json_schema_extra=floor("a gear face narrower than 1 mm carries no load and cannot be meshed"),
    )
    n_planets: int = Field(ge=2, le=6, description="Number of planets = crankshafts [-]")
    backlash_um: float = Field(ge=0.0, le=500.0, description="Circumferential backlash on the pitch circle [um]")
    mesh_damping_ratio: float = Field(ge=0.0, le=0.5, description="Mesh damping ratio xi_12 [-]")

    @property
    def module(self) -> float:
        """Module [m]."""
        return self.module_mm * M_PER_MM

    @property
    def pressure_angle(self) -> float:
        """Pressure angle [rad]."""
        return self.pressure_angle_deg * RAD_PER_DEG

    @property
    def face_width(self) -> float:
        """Face width [m]."""
        return self.face_width_mm * M_PER_MM

    @property
    def backlash(self) -> float:
        """Circumferential backlash [m]."""
        return self.backlash_um * M_PER_UM

    @property
    def center_distance(self) -> float:
        """Working centre distance sun-planet [m] (= crank circle radius).

        Computed from the operating pressure angle of the shifted pair
        (inv alpha_w = inv alpha + 2 tan(alpha) (x1+x2)/(z1+z2)); ISO 21771.
        """
        from flexrv.geometry.involute import working_center_distance

        return float(
            working_center_distance(
                self.sun_teeth,
                self.planet_teeth,
                self.module,
                self.pressure_angle,
                self.sun_profile_shift,
                self.planet_profile_shift,
            )
        )

    @property
    def contact_ratio(self) -> float:
        """Transverse contact ratio eps_alpha of the sun-planet mesh [-]
        (:func:`flexrv.geometry.involute.contact_ratio`)."""
        import numpy as np

        from flexrv.geometry.involute import contact_ratio

        with np.errstate(invalid="ignore"):  # tips that miss the line of action: NaN, refused by the validator
            return float(
                contact_ratio(
                    self.sun_teeth,
                    self.planet_teeth,
                    self.module,
                    self.pressure_angle,
                    self.sun_profile_shift,
                    self.planet_profile_shift,
                )
            )

    @model_validator(mode="after")
    def _mesh(self) -> "FirstStage":
        lo, hi = CONTACT_RATIO_RANGE
        eps = self.contact_ratio
        if not (math.isfinite(eps) and lo < eps < hi):
            shown = f"{eps:.3g}" if math.isfinite(eps) else "undefined (tips do not reach the line of action)"
            raise _bad(
                "first_stage.sun_profile_shift",
                self.sun_profile_shift,
                f"the transverse contact ratio eps_alpha = {shown} of sun_teeth = {self.sun_teeth}, "
                f"planet_teeth = {self.planet_teeth}, planet_profile_shift = {self.planet_profile_shift:g} "
                f"must lie in {lo:g} < eps_alpha < {hi:g}",
                "change the profile shifts or tooth numbers",
            )
        # involute undercut (practical limit, DIN 3960 / Niemann & Winter: slight undercut allowed
        # down to z' = 5/6 of the theoretical 2 h_a / sin^2(alpha), i.e. 14 teeth at 20 deg):
        # x >= 5/6 h_a - z sin^2(alpha) / 2 with the addendum h_a = 1 module
        s2 = math.sin(self.pressure_angle) ** 2
        for name, z, x in (
            ("sun", self.sun_teeth, self.sun_profile_shift),
            ("planet", self.planet_teeth, self.planet_profile_shift),
        ):
            x_min = 5.0 / 6.0 - 0.5 * z * s2
            if x < x_min - 1e-12:
                raise _bad(
                    f"first_stage.{name}_profile_shift",
                    x,
                    f"must be >= {x_min:.3f} for {z} teeth at {self.pressure_angle_deg:g} deg "
                    "(involute undercut; practical limit 5/6 h_a - z sin^2(alpha)/2)",
                    "the tooth root would be cut away by the generating tool",
                )
        return self


class SecondStage(_Strict):
    """Cycloid-pin second stage with profile modifications (equidistant, shift,
    rotation), the profile being the envelope of a pin of radius r_rp + dr_rp on a
    pin circle of radius R_p + dR_p."""

    disc_teeth: int = Field(ge=10, le=200, description="Cycloid disc teeth z_c [-]")
    pin_count: int = Field(ge=11, le=201, description="Number of pins z_rp [-]")
    pin_circle_radius_mm: float = Field(gt=5.0, le=1000.0, description="Pin centre circle radius R_p [mm]")
    pin_radius_mm: float = Field(gt=0.2, le=50.0, description="Pin radius r_rp [mm]")
    eccentricity_mm: float = Field(gt=0.05, le=20.0, description="Crank eccentricity a [mm]")
    disc_width_mm: float = Field(gt=0.5, le=200.0, description="Width of one disc b_c [mm]")
    n_discs: int = Field(ge=1, le=3, description="Number of discs (phased 360/n deg) [-]")
    modification_equidistant_mm: float = Field(ge=-0.2, le=0.2, description="Equidistant modification dr_rp [mm]")
    modification_shift_mm: float = Field(ge=-0.2, le=0.2, description="Shift (pin-circle) modification dR_p [mm]")
    modification_rotation_deg: float = Field(ge=-1.0, le=1.0, description="Rotation modification d_delta [deg]")
    center_hole_radius_mm: float = Field(ge=0.0, le=500.0, description="Radius of the disc's centre hole [mm]")
    mesh_damping_ratio: float = Field(ge=0.0, le=0.5, description="Pin-disc contact damping ratio xi_34 [-]")
    disc_body_model: Literal["condensed_fe", "rigid"] = Field(
        default="condensed_fe",
        description="Cycloid-disc body between the crank holes and the tooth region: "
        "'condensed_fe' (FE condensation, flexrv.fem.disc, in series in every model) or 'rigid'",
    )

    @property
    def pin_circle_radius(self) -> float:
        return self.pin_circle_radius_mm * M_PER_MM

    @property
    def pin_radius(self) -> float:
        return self.pin_radius_mm * M_PER_MM

    @property
    def eccentricity(self) -> float:
        return self.eccentricity_mm * M_PER_MM

    @property
    def disc_width(self) -> float:
        return self.disc_width_mm * M_PER_MM

    @property
    def modification_equidistant(self) -> float:
        return self.modification_equidistant_mm * M_PER_MM

    @property
    def modification_shift(self) -> float:
        return self.modification_shift_mm * M_PER_MM

    @property
    def modification_rotation(self) -> float:
        return self.modification_rotation_deg * RAD_PER_DEG

    @property
    def center_hole_radius(self) -> float:
        return self.center_hole_radius_mm * M_PER_MM

    @property
    def shortening_coefficient(self) -> float:
        """K1 = a z_rp / R_p [-] (must be < 1 for a usable epitrochoid)."""
        return self.eccentricity_mm * self.pin_count / self.pin_circle_radius_mm

    @model_validator(mode="after")
    def _consistent(self) -> "SecondStage":
        if self.pin_count - self.disc_teeth != 1:
            raise _bad(
                "second_stage.pin_count",
                self.pin_count,
                f"must equal disc_teeth + 1 = {self.disc_teeth + 1}",
                "an RV cycloid stage has one pin more than disc teeth",
            )
        spacing = 2.0 * self.pin_circle_radius_mm * math.sin(math.pi / self.pin_count)
        if 2.0 * self.pin_radius_mm >= spacing:
            raise _bad(
                "second_stage.pin_radius_mm",
                self.pin_radius_mm,
                f"must be < {spacing / 2:.4g} mm (half the pin spacing on R_p = {self.pin_circle_radius_mm:g} mm)",
                "neighbouring pins would overlap",
            )
        k1 = self.shortening_coefficient
        if k1 >= 1.0:
            raise _bad(
                "second_stage.eccentricity_mm",
                self.eccentricity_mm,
                f"must be < R_p/z_rp = {self.pin_circle_radius_mm / self.pin_count:.4g} mm "
                f"(shortening coefficient K1 = a z_rp / R_p = {k1:.3f} must be < 1)",
                "the pin-centre curve loops and the disc profile undercuts",
            )
        from flexrv.geometry.cycloid import min_convex_curvature_radius

        rho_min = min_convex_curvature_radius(
            self.pin_count, self.pin_circle_radius + self.modification_shift, self.eccentricity
        )
        offset = self.pin_radius + self.modification_equidistant
        if offset >= rho_min:
            raise _bad(
                "second_stage.pin_radius_mm",
                self.pin_radius_mm,
                f"pin radius + equidistant modification must be < {rho_min * 1e3:.4g} mm, the minimum "
                "convex curvature radius of the pin-centre epitrochoid",
                "the disc profile would undercut; reduce the eccentricity or the pin radius",
            )
        return self


class Crankshaft(_Strict):
    """Crankshaft: planet-gear seat, two eccentric journals 180 deg apart, two
    support journals in the carrier (axial order: gear seat, support A, eccentric 1,
    eccentric 2, support B)."""

    gear_seat_diameter_mm: float = Field(gt=1.0, le=200.0)
    gear_seat_length_mm: float = Field(gt=1.0, le=200.0)
    support_journal_diameter_mm: float = Field(gt=1.0, le=200.0)
    support_journal_length_mm: float = Field(gt=1.0, le=200.0)
    eccentric_journal_diameter_mm: float = Field(
        gt=1.0, le=200.0, description="Needle-bearing inner raceway diameter [mm]"
    )
    eccentric_journal_length_mm: float = Field(gt=1.0, le=200.0)
    support_bearing_model: Literal["tapered_rollers", "linear"] = Field(
        default="tapered_rollers",
        description="Crank support law: roller-resolved preloaded tapered-roller pair "
        "(flexrv.contact.tapered_roller) or the linear spring of support_bearing_radial_stiffness_N_per_m",
    )
    support_bearing_roller_count: int | None = Field(
        default=None, ge=6, le=60, description="Rollers per support bearing Z [-]"
    )
    support_bearing_roller_diameter_mm: float | None = Field(
        default=None, gt=0.5, le=50.0, description="Mean roller diameter D [mm]"
    )
    support_bearing_roller_length_mm: float | None = Field(
        default=None, gt=0.5, le=100.0, description="Effective roller contact length l [mm]"
    )
    support_bearing_pitch_diameter_mm: float | None = Field(
        default=None, gt=2.0, le=500.0, description="Roller-set pitch diameter d_m [mm]"
    )
    support_bearing_contact_angle_deg: float | None = Field(
        default=None, ge=5.0, le=35.0, description="Cup (outer raceway) half-angle alpha [deg]"
    )
    support_bearing_axial_preload_um: float | None = Field(
        default=None,
        ge=-50.0,
        le=50.0,
        description="Axial ring approach of each bearing from the pair's preload (+), or half the pair's end "
        "play (-) [um]",
    )
    support_bearing_radial_stiffness_N_per_m: float | None = Field(
        default=None, gt=1e6, le=1e12, description="Radial stiffness of one crank support bearing (linear model only)"
    )
    support_bearing_damping_Ns_per_m: float = Field(ge=0.0, le=1e7)
    structural_damping_ratio: float = Field(
        ge=0.0, le=1.0, description="Damping ratio of the flexible crankshafts' elastic coordinates"
    )
    bending_model: Literal["timoshenko", "rigid"] = Field(
        default="timoshenko",
        description="Crank bending between the support journals and the eccentrics in series with the supports",
    )
    torsion_model: Literal["st_venant", "rigid"] = Field(
        default="st_venant",
        description="Crank torsion between the planet spline and the eccentrics in series with each planet's mesh",
    )

    @model_serializer(mode="wrap")
    def _drop_unused(self, handler):
        """Dump without the fields of the other support law (None): TOML has no null,
        and a dump loads back unchanged."""
        return {k: v for k, v in handler(self).items() if v is not None}

    @model_validator(mode="after")
    def _support_bearing(self) -> "Crankshaft":
        tapered = (
            "support_bearing_roller_count",
            "support_bearing_roller_diameter_mm",
            "support_bearing_roller_length_mm",
            "support_bearing_pitch_diameter_mm",
            "support_bearing_contact_angle_deg",
            "support_bearing_axial_preload_um",
        )
        if self.support_bearing_model == "linear":
            if self.support_bearing_radial_stiffness_N_per_m is None:
                raise _bad(
                    "crankshaft.support_bearing_radial_stiffness_N_per_m",
                    None,
                    "missing required field of support_bearing_model = 'linear' (1e6 < value <= 1e12 N/m)",
                )
            given = [f for f in tapered if getattr(self, f) is not None]
            if given:
                raise _bad(
                    f"crankshaft.{given[0]}",
                    getattr(self, given[0]),
                    "only used with support_bearing_model = 'tapered_rollers'; remove it",
                )
            return self
        for f in tapered:
            if getattr(self, f) is None:
                raise _bad(
                    f"crankshaft.{f}", None, "missing required field of support_bearing_model = 'tapered_rollers'"
                )
        if self.support_bearing_radial_stiffness_N_per_m is not None:
            raise _bad(
                "crankshaft.support_bearing_radial_stiffness_N_per_m",
                self.support_bearing_radial_stiffness_N_per_m,
                "only used with support_bearing_model = 'linear'; remove it (the tapered-roller law computes it)",
            )
        d_j, dm = self.support_journal_diameter_mm, self.support_bearing_pitch_diameter_mm
        dw, z = self.support_bearing_roller_diameter_mm, self.support_bearing_roller_count
        wall = 0.15 * dw  # cone (inner ring) section under the roller
        if dm - dw * math.cos(self.support_bearing_contact_angle_deg * RAD_PER_DEG) < d_j + 2.0 * wall:
            raise _bad(
                "crankshaft.support_bearing_pitch_diameter_mm",
                dm,
                f"must be >= "
                f"{d_j + 2.0 * wall + dw * math.cos(self.support_bearing_contact_angle_deg * RAD_PER_DEG):.4g} mm: "
                f"the cone raceway (d_m - D cos alpha) must clear the {d_j:g} mm support journal by a "
                f"ring wall of 0.15 D = {wall:.3g} mm",
                "the bearing does not fit on the journal",
            )
        z_max = int(math.pi * dm / (1.05 * dw))
        if z > z_max:
            raise _bad(
                "crankshaft.support_bearing_roller_count",
                z,
                f"must be <= {z_max}: {z} rollers of {dw:g} mm on the {dm:g} mm pitch circle need a 5 % cage bar gap",
                "the rollers would overlap",
            )
        if self.support_bearing_roller_length_mm > self.support_journal_length_mm:
            raise _bad(
                "crankshaft.support_bearing_roller_length_mm",
                self.support_bearing_roller_length_mm,
                f"must be <= support_journal_length_mm = {self.support_journal_length_mm:g} mm",
                "the bearing sits on the support journal",
            )
        return self


class NeedleBearing(_Strict):
    """Needle bearing between an eccentric journal and its disc hole."""

    roller_count: int = Field(ge=6, le=80)
    roller_diameter_mm: float = Field(gt=0.5, le=50.0)
    roller_length_mm: float = Field(gt=0.5, le=100.0)
    radial_clearance_um: float = Field(
        ge=0.0,
        le=100.0,
        description="Radial internal clearance as ISO 5593 defines it: the total radial play of the eccentric "
        "in its hole (diametral, one extreme position to the opposite one) [um]; each side has half",
    )
    model: Literal["empirical", "rollers"] = Field(description="seed004 empirical stiffness or roller-resolved Hertz")

    @property
    def clearance_per_side(self) -> float:
        """Half the radial internal clearance [m]: the gap on one side with the eccentric centred."""
        return 0.5 * self.radial_clearance_um * M_PER_UM


class MainBearing(_Strict):
    """Back-to-back pair of angular contact ball bearings carrying the carrier.

    ``inner_ring_bore_diameter_mm`` / ``outer_ring_outer_diameter_mm`` are the ring
    fit diameters; groove-bottom (raceway) diameters follow from the pitch diameter,
    ball diameter and contact angle (see :mod:`flexrv.geometry.bearing`).
    """

    ball_diameter_mm: float = Field(gt=1.0, le=200.0)
    pitch_diameter_mm: float = Field(gt=10.0, le=3000.0)
    ball_count: int = Field(ge=6, le=200)
    contact_angle_deg: float = Field(ge=10.0, le=60.0)
    inner_conformity: float = Field(ge=0.501, le=0.6, description="f_i = groove radius / ball diameter")
    outer_conformity: float = Field(ge=0.501, le=0.6, description="f_o = groove radius / ball diameter")
    inner_ring_bore_diameter_mm: float = Field(gt=1.0, le=3000.0)
    outer_ring_outer_diameter_mm: float = Field(gt=1.0, le=3000.0)
    ring_width_mm: float = Field(gt=1.0, le=300.0, description="Axial width of one ring (one row)")
    row_spacing_mm: float = Field(gt=1.0, le=1000.0, description="Axial distance between the two rows' ball centres")
    axial_preload_um: float = Field(
        ge=-100.0, le=100.0, description="Axial interference per row (+ preload, - clearance)"
    )
    ball_damping_Ns_per_m: float = Field(ge=0.0, le=1e7, description="Max contact damping c_max of the impact law")
    rigid_radial_stiffness_N_per_m: float = Field(
        gt=1e6,
        le=1e12,
        description="Radial stiffness of the pair in the rigid main-bearing model (the ball model resolves it)",
    )
    rigid_axial_stiffness_N_per_m: float = Field(
        gt=1e6, le=1e12, description="Axial stiffness of the pair in the rigid main-bearing model"
    )
    rigid_damping_ratio: float = Field(
        ge=0.0, le=1.0, description="Damping ratio of the rigid main bearing's carrier modes (c = 2 zeta sqrt(k m))"
    )
    cage_stiffness_N_per_m: float = Field(
        gt=0.0, le=1e9, description="Tangential spring of each ball to its cage pocket (ball-resolved models)"
    )
    cage_damping_Ns_per_m: float = Field(ge=0.0, le=1e6, description="Tangential damper of each ball to its pocket")
    pocket_stiffness_N_per_m: float = Field(
        ge=0.0, le=1e9, description="Weak radial/axial spring of each ball to its pocket (ball-resolved models)"
    )
    ring_damping_ratio: float = Field(ge=0.0, le=1.0, description="Modal damping ratio of dynamic flexible rings")

    @model_validator(mode="after")
    def _fits(self) -> "MainBearing":
        d, dm = self.ball_diameter_mm, self.pitch_diameter_mm
        bore, od = self.inner_ring_bore_diameter_mm, self.outer_ring_outer_diameter_mm
        min_wall = 0.1 * d
        if not bore < dm < od:
            raise _bad(
                "main_bearing.pitch_diameter_mm",
                dm,
                f"must lie between the inner bore {bore:g} mm and outer diameter {od:g} mm",
            )
        from flexrv.geometry.bearing import BallBearingGeometry
        from flexrv.units import M_PER_MM

        # groove bottoms [mm] (torus of radius f D about the curvature centres)
        geo = BallBearingGeometry.from_design(self)
        bottom_i = geo.groove_bottom_radius("inner") / M_PER_MM
        bottom_o = geo.groove_bottom_radius("outer") / M_PER_MM
        if bottom_i - bore / 2 < min_wall:
            raise _bad(
                "main_bearing.ball_diameter_mm",
                d,
                f"too large for the inner ring section: the wall under the groove is {bottom_i - bore / 2:.4g} mm, "
                f"must be >= 0.1 D = {min_wall:.4g} mm",
                "ball larger than the ring section",
            )
        if od / 2 - bottom_o < min_wall:
            raise _bad(
                "main_bearing.ball_diameter_mm",
                d,
                f"too large for the outer ring section: the wall under the groove is {od / 2 - bottom_o:.4g} mm, "
                f"must be >= 0.1 D = {min_wall:.4g} mm",
                "ball larger than the ring section",
            )
        half_contact = 0.5 * d * math.sin(self.contact_angle_deg * RAD_PER_DEG)
        if self.ring_width_mm < 2.2 * half_contact:
            raise _bad(
                "main_bearing.ring_width_mm",
                self.ring_width_mm,
                f"must be >= {2.2 * half_contact:.4g} mm so the contact point (axial offset {half_contact:.3g} "
                f"mm) lies on the raceway",
            )
        if math.pi * dm / self.ball_count <= d * 1.05:
            raise _bad(
                "main_bearing.ball_count",
                self.ball_count,
                f"must be <= {int(math.pi * dm / (1.05 * d))} for D = {d:g} mm on d_m = {dm:g} mm",
                "balls would touch",
            )
        if self.row_spacing_mm < self.ring_width_mm:
            raise _bad(
                "main_bearing.row_spacing_mm", self.row_spacing_mm, f"must be >= ring_width_mm = {self.ring_width_mm:g}"
            )
        return self

    @property
    def ball_diameter(self) -> float:
        return self.ball_diameter_mm * M_PER_MM

    @property
    def pitch_diameter(self) -> float:
        return self.pitch_diameter_mm * M_PER_MM

    @property
    def contact_angle(self) -> float:
        return self.contact_angle_deg * RAD_PER_DEG


#: thinnest ligament [mm] left between two holes of the carrier, or between a hole
#: and a plate edge: below it the parts touch (the geometry self-intersects) or a
#: Tet10 mesh of the part cannot resolve the wall. A check constant, not a physical
#: estimate.
MIN_LIGAMENT_MM = 1.0


class Carrier(_Strict):
    """Carrier of the second stage: two end plates (input side and output flange)
    joined by pillars that pass through the cycloid discs; each plate has one bore
    per crankshaft for its support bearing, on the crank circle a_w. Pillar k sits at
    the angle pi/N_p + 2 pi k/N_p (midway between the cranks when N_p = N), the
    cranks at 2 pi k/N (the disc's crank holes). The plates' rims seat the main
    bearing; the output plate's outer face is the output flange."""

    plate_outer_diameter_mm: float = Field(
        gt=10.0, le=3000.0, description="End-plate outer diameter = main-bearing inner-ring seat [mm]"
    )
    input_plate_thickness_mm: float = Field(
        gt=1.0, le=300.0, description="Axial thickness of the input-side end plate [mm]"
    )
    output_plate_thickness_mm: float = Field(
        gt=1.0, le=300.0, description="Axial thickness of the output-flange plate [mm]"
    )
    plate_gap_mm: float = Field(
        gt=1.0, le=1000.0, description="Axial gap between the plates (disc stack + clearances) [mm]"
    )
    crank_bore_diameter_mm: float = Field(
        gt=1.0, le=600.0, description="Bore of a crank support-bearing seat in a plate [mm]"
    )
    center_bore_diameter_mm: float = Field(
        ge=0.0, le=2000.0, description="Central through-bore (input shaft) [mm]; 0 = none"
    )
    pillar_count: int = Field(ge=2, le=12, description="Number of pillars N_p [-]")
    pillar_circle_radius_mm: float = Field(gt=1.0, le=1500.0, description="Radius of the pillar-centre circle [mm]")
    pillar_diameter_mm: float = Field(gt=1.0, le=600.0, description="Diameter of a (round) pillar [mm]")
    body_model: Literal["condensed_fe", "rigid"] = Field(
        default="condensed_fe",
        description="Carrier body between the crank bores and the output flange: "
        "'condensed_fe' (FE condensation, flexrv.fem.carrier, in series with the crank supports in every model) "
        "or 'rigid'",
    )

    def pillar_angles(self) -> list[float]:
        """Angles [rad] of the pillar centres."""
        n = self.pillar_count
        return [math.pi / n + 2.0 * math.pi * k / n for k in range(n)]

    @model_validator(mode="after")
    def _fits(self) -> "Carrier":
        lig = MIN_LIGAMENT_MM
        r_o, r_c = 0.5 * self.plate_outer_diameter_mm, 0.5 * self.center_bore_diameter_mm
        rp, rc_p = 0.5 * self.pillar_diameter_mm, self.pillar_circle_radius_mm
        if rc_p + rp + lig > r_o:
            raise _bad(
                "carrier.pillar_circle_radius_mm",
                rc_p,
                f"must be <= {r_o - rp - lig:.4g} mm (plate_outer_diameter_mm / 2 = {r_o:g} mm - pillar radius "
                f"{rp:g} mm "
                f"- ligament {lig:g} mm)",
                "the pillars would stick out of the plates",
            )
        if r_c > 0 and rc_p - rp - lig < r_c:
            raise _bad(
                "carrier.center_bore_diameter_mm",
                self.center_bore_diameter_mm,
                f"must be <= {2 * (rc_p - rp - lig):.4g} mm (pillar_circle_radius_mm = {rc_p:g}, pillar_diameter_mm = "
                f"{self.pillar_diameter_mm:g})",
                "the centre bore would cut the pillars",
            )
        spacing = 2.0 * rc_p * math.sin(math.pi / self.pillar_count)
        if spacing < 2.0 * rp + lig:
            raise _bad(
                "carrier.pillar_diameter_mm",
                self.pillar_diameter_mm,
                f"must be <= {spacing - lig:.4g} mm for pillar_count = {self.pillar_count} on "
                f"pillar_circle_radius_mm = {rc_p:g}",
                "neighbouring pillars would overlap",
            )
        return self

    def validate_for(self, reducer) -> None:
        """Checks against the rest of the design (raised as ValueError naming the
        carrier field): bores on the crank circle inside the plates, apart from each
        other, around the support journals; pillars clear of the bores; the pillars'
        holes in the discs (pillar radius + eccentricity) inside the disc between its
        crank holes, centre hole and tooth root; the discs between the plates; the
        plates inside the main bearing's inner ring."""
        lig = MIN_LIGAMENT_MM
        fs, ss, cs = reducer.first_stage, reducer.second_stage, reducer.crankshaft
        a_w = fs.center_distance * 1e3
        n = fs.n_planets
        r_o, r_b = 0.5 * self.plate_outer_diameter_mm, 0.5 * self.crank_bore_diameter_mm
        if self.crank_bore_diameter_mm <= cs.support_journal_diameter_mm:
            raise _bad(
                "carrier.crank_bore_diameter_mm",
                self.crank_bore_diameter_mm,
                f"must be > crankshaft.support_journal_diameter_mm = {cs.support_journal_diameter_mm:g} mm",
                "the support bearing sits between journal and bore",
            )
        if n > 1 and 2.0 * a_w * math.sin(math.pi / n) < 2.0 * r_b + lig:
            raise _bad(
                "carrier.crank_bore_diameter_mm",
                self.crank_bore_diameter_mm,
                f"must be <= {2.0 * a_w * math.sin(math.pi / n) - lig:.4g} mm for {n} bores on the crank "
                f"circle a_w = {a_w:.4g} mm",
                "neighbouring crank bores would overlap",
            )
        if a_w + r_b + lig > r_o:
            raise _bad(
                "carrier.plate_outer_diameter_mm",
                self.plate_outer_diameter_mm,
                f"must be >= {2 * (a_w + r_b + lig):.4g} mm (crank circle {a_w:.4g} mm + crank_bore_diameter_mm / 2 = "
                f"{r_b:g} mm + ligament {lig:g} mm)",
                "the crank bores would cut the plate rim",
            )
        if self.center_bore_diameter_mm > 0 and 0.5 * self.center_bore_diameter_mm + lig > a_w - r_b:
            raise _bad(
                "carrier.center_bore_diameter_mm",
                self.center_bore_diameter_mm,
                f"must be <= {2 * (a_w - r_b - lig):.4g} mm",
                "the centre bore would cut the crank bores",
            )
        rp, rc_p = 0.5 * self.pillar_diameter_mm, self.pillar_circle_radius_mm
        e = ss.eccentricity_mm
        r_hole = reducer.crank_hole_radius * 1e3
        for ang in self.pillar_angles():
            for k in range(n):
                psi = 2.0 * math.pi * k / n
                dist = math.sqrt(max(rc_p**2 + a_w**2 - 2.0 * rc_p * a_w * math.cos(ang - psi), 0.0))
                if dist < rp + r_b + lig:
                    raise _bad(
                        "carrier.pillar_circle_radius_mm",
                        rc_p,
                        f"a pillar (pillar_diameter_mm = {self.pillar_diameter_mm:g}) at "
                        f"{math.degrees(ang):.4g} deg is {dist:.4g} mm from the "
                        f"crank bore at {math.degrees(psi):.4g} deg; need >= {rp + r_b + lig:.4g} mm",
                        "pillar and crank bore would intersect",
                    )
                if dist < rp + e + r_hole + lig:
                    raise _bad(
                        "carrier.pillar_diameter_mm",
                        self.pillar_diameter_mm,
                        f"the pillar's hole in the disc (pillar radius + eccentricity {rp + e:.4g} mm) comes "
                        f"within {dist - rp - e - r_hole:.3g} mm of the disc's crank hole; need >= {lig:g} mm",
                        "pillar hole and crank hole of the disc would intersect",
                    )
        r_root = ss.pin_circle_radius_mm - ss.pin_radius_mm - e
        if rc_p + rp + e + lig > r_root:
            raise _bad(
                "carrier.pillar_circle_radius_mm",
                rc_p,
                f"must be <= {r_root - rp - e - lig:.4g} mm: the pillar's hole in the disc (pillar_diameter_mm / 2 + "
                f"eccentricity = {rp + e:.4g} mm) "
                f"must stay inside the disc root radius {r_root:.4g} mm",
                "the pillars would cut the disc teeth",
            )
        if ss.center_hole_radius_mm > 0 and rc_p - rp - e - lig < ss.center_hole_radius_mm:
            raise _bad(
                "carrier.pillar_circle_radius_mm",
                rc_p,
                f"must be >= {ss.center_hole_radius_mm + rp + e + lig:.4g} mm (disc centre hole "
                f"{ss.center_hole_radius_mm:g} mm, pillar_diameter_mm = {self.pillar_diameter_mm:g})",
                "the pillar holes would cut the disc's centre hole",
            )
        stack = ss.n_discs * ss.disc_width_mm
        if self.plate_gap_mm < stack:
            raise _bad(
                "carrier.plate_gap_mm",
                self.plate_gap_mm,
                f"must be >= n_discs x disc_width = {stack:g} mm",
                "the discs run between the plates",
            )
        bore = reducer.main_bearing.inner_ring_bore_diameter_mm
        if self.plate_outer_diameter_mm > bore:
            raise _bad(
                "carrier.plate_outer_diameter_mm",
                self.plate_outer_diameter_mm,
                f"must be <= main_bearing.inner_ring_bore_diameter_mm = {bore:g} mm",
                "the main bearing's inner ring sits on the plate rim",
            )


class Housing(_Strict):
    """Pin housing (pin gear ring): the pins lie in semicircular grooves of the
    housing bore on the pin circle R_p; each pin's groove (seat) is a concave
    cylinder of radius r_rp + clearance. Where the groove is interrupted (lands
    only), a pin spans ``pin_unsupported_length_mm`` between two lands at each
    disc. The ring section around the pins (outer diameter, axial length) carries
    the pin loads to the housing's fixture."""

    pin_seat_clearance_um: float = Field(
        gt=0.0, le=500.0, description="Radial clearance of a pin in its groove, groove radius - pin radius [um]"
    )
    pin_seat_length_mm: float = Field(
        gt=0.0, le=2000.0, description="Length of a pin's groove seat that carries the disc loads (all discs) [mm]"
    )
    pin_unsupported_length_mm: float = Field(
        ge=0.0, le=2000.0, description="Span of a pin between groove lands at each disc [mm]; 0 = fully supported"
    )
    ring_outer_diameter_mm: float = Field(
        gt=1.0, le=5000.0, description="Outer diameter of the housing ring around the pins [mm]"
    )
    ring_length_mm: float = Field(
        gt=0.0, le=2000.0, description="Axial length of the housing ring section that carries the pin loads [mm]"
    )
    body_model: Literal["ring_estimate", "rigid"] = Field(
        default="ring_estimate",
        description="Pin housing in the models: 'ring_estimate' (elastic rotation of the pin "
        "ring about the axis with the thin-ring + tube compliance, flexrv.analysis.torsional.housing_compliance, in "
        "every model and budget) or 'rigid' (left out of every model and budget)",
    )

    @property
    def pin_seat_clearance(self) -> float:
        """Groove radius - pin radius [m]."""
        return self.pin_seat_clearance_um * M_PER_UM

    def validate_for(self, reducer) -> None:
        """The ring encloses the pins by at least a ligament; the seat and the unsupported span fit the ring."""
        ss = reducer.second_stage
        r_groove = ss.pin_circle_radius_mm + ss.pin_radius_mm
        if 0.5 * self.ring_outer_diameter_mm < r_groove + MIN_LIGAMENT_MM:
            raise _bad(
                "housing.ring_outer_diameter_mm",
                self.ring_outer_diameter_mm,
                f"must be >= {2 * (r_groove + MIN_LIGAMENT_MM):.4g} mm (pin circle {ss.pin_circle_radius_mm:g} mm + "
                f"pin radius {ss.pin_radius_mm:g} mm + ligament {MIN_LIGAMENT_MM:g} mm)",
                "the pin grooves would cut through the ring",
            )
        if self.pin_seat_length_mm > self.ring_length_mm:
            raise _bad(
                "housing.pin_seat_length_mm",
                self.pin_seat_length_mm,
                f"must be <= housing.ring_length_mm = {self.ring_length_mm:g} mm",
                "the grooves lie in the ring",
            )
        if self.pin_unsupported_length_mm > self.ring_length_mm:
            raise _bad(
                "housing.pin_unsupported_length_mm",
                self.pin_unsupported_length_mm,
                f"must be <= housing.ring_length_mm = {self.ring_length_mm:g} mm",
                "the span lies in the ring",
            )


class Material(_Strict):
    """Isotropic linear-elastic material."""

    youngs_modulus_GPa: float = Field(gt=1.0, le=1000.0)
    poisson_ratio: float = Field(ge=0.0, lt=0.5)
    density_kg_m3: float = Field(gt=100.0, le=25000.0)

    @property
    def youngs_modulus(self) -> float:
        """E [Pa]."""
        return self.youngs_modulus_GPa * 1e9


class PartMaterials(_Strict):
    """Which material (a key of ``materials``) each part is made of."""

    gears: str
    crankshaft: str
    cycloid_disc: str
    pins: str
    carrier: str
    housing: str
    bearing_rings: str
    rolling_elements: str


class Lubricant(_Strict):
    """Lubricant for the EHL contacts (isothermal).

    Roelands: eta(p) = eta0 exp{(ln eta0 + 9.67)[(1 + p/p0)^z - 1]},
    Dowson-Higginson: rho(p) = rho0 (1 + a p / (1 + b p)).
    """

    name: str
    viscosity_Pa_s: float = Field(gt=1e-4, le=10.0, description="Dynamic viscosity eta0 at the operating temperature")
    pressure_viscosity_1_per_GPa: float = Field(
        gt=1.0, le=60.0, description="Barus coefficient alpha (for Hamrock-Dowson)"
    )
    roelands_z: float = Field(gt=0.2, le=1.5)
    roelands_p0_Pa: float = Field(gt=1e7, le=1e9)
    density_kg_m3: float = Field(gt=500.0, le=2000.0)
    dowson_higginson_a_1_per_GPa: float = Field(ge=0.0, le=5.0)
    dowson_higginson_b_1_per_GPa: float = Field(ge=0.0, le=10.0)

    @property
    def viscosity(self) -> float:
        return self.viscosity_Pa_s

    @property
    def pressure_viscosity(self) -> float:
        """alpha [1/Pa]."""
        return self.pressure_viscosity_1_per_GPa * 1e-9


#: reason of the lower bounds of the mass properties
_LIGHT = (
    "lighter than %s: the member's frequency on its contact stiffness would exceed what the "
    "implicit integrator converges on at the time steps flexrv uses"
)


class Inertia(_Strict):
    """Mass properties not derivable from the modelled geometry."""

    input_shaft_inertia_kg_m2: float = Field(
        ge=1e-7,
        le=10.0,
        description="Input shaft + sun about its axis",
        json_schema_extra=floor(_LIGHT % "a steel shaft of 5 mm diameter and 20 mm length (1e-7 kg m2)"),
    )
    carrier_mass_kg: float = Field(ge=0.01, le=1000.0, json_schema_extra=floor(_LIGHT % "a 10 g carrier (0.01 kg)"))
    carrier_inertia_kg_m2: float = Field(
        ge=1e-6,
        le=100.0,
        description="Carrier + output flange about the axis",
        json_schema_extra=floor(_LIGHT % "a 10 g carrier of 20 mm radius (1e-6 kg m2)"),
    )


class ContactSettings(_Strict):
    """Contact-law settings shared by the pin, roller and ball contacts."""

    pin_law: Literal["hertz_line", "impact"] = Field(description="Pin-disc force law")
    impact_exponent: float = Field(ge=1.0, le=3.0, description="Exponent e of the impact law")
    impact_damping_depth_mm: float = Field(
        gt=0.0, le=1.0, description="Penetration d over which damping ramps to c_max"
    )
    pin_max_damping_Ns_per_m: float = Field(ge=0.0, le=1e7)
    ehl: Literal["dry", "hamrock_dowson", "map"] = Field(description="EHL correction of lubricated contacts")
    pin_penetration_limit_um: float = Field(
        gt=0.0, le=1000.0, description="Pin-disc penetration beyond which a run is stopped as failed [um]"
    )
    needle_penetration_limit_um: float = Field(
        gt=0.0,
        le=1000.0,
        description="Needle-bearing penetration beyond which a run is stopped as failed [um] "
        "(at least 20 x the impact law's damping depth)",
    )
    # friction: regularised Coulomb friction, flexrv.contact.laws.friction_force
    friction: bool = Field(
        description="Friction at the pin-disc/pin-seat and needle contacts on (true) or off "
        "(false: exactly the frictionless model)"
    )
    pin_friction_coefficient: float = Field(ge=0.0, le=0.5, description="Coulomb coefficient pin-disc flank [-]")
    pin_seat_friction_coefficient: float = Field(
        ge=0.0,
        le=0.5,
        description="Coulomb coefficient pin-housing groove [-] (the pin slides where friction is "
        "lower: flexrv.contact.laws.effective_pin_friction)",
    )
    needle_friction_coefficient: float = Field(
        ge=0.0,
        le=0.05,
        description="Constant friction coefficient of the needle bearings (rolling-bearing "
        "model M = mu F d/2, d the journal diameter) [-]",
    )
    friction_velocity_mm_per_s: float = Field(
        gt=0.0, le=100.0, description="Regularisation speed v_reg of the Coulomb law [mm/s]: s = v/sqrt(v^2+v_reg^2)"
    )


class OperatingPoint(_Strict):
    """Drive and load as in the seeds: input speed step 0 -> n_in over
    [0, speed_ramp_time], load torque T_max * step(t, t1, 0, t2, 1) on the carrier."""

    input_speed_rpm: float = Field(gt=0.0, le=20000.0)
    speed_ramp_time_s: float = Field(ge=0.0, le=100.0)
    load_torque_Nm: float = Field(ge=-1e5, le=1e5, description="Load torque on the output")
    load_ramp_start_s: float = Field(ge=0.0, le=100.0)
    load_ramp_end_s: float = Field(ge=0.0, le=100.0)
    rated_torque_Nm: float = Field(
        ge=1.0,
        le=1e5,
        description="Rated output torque (stiffness test range)",
        json_schema_extra=floor(
            "the smallest cycloidal drives are rated at a few N m; the no-load and lost-motion torques are "
            "fractions of the rated torque and would fall below the contact laws' force resolution"
        ),
    )
    external_axial_force_N: float = Field(ge=-1e6, le=1e6)
    external_radial_force_N: float = Field(ge=-1e6, le=1e6)
    tilting_moment_Nm: float = Field(ge=-1e6, le=1e6)
    temperature_C: float = Field(ge=-40.0, le=200.0)

    @model_validator(mode="after")
    def _ramp(self) -> "OperatingPoint":
        if self.load_ramp_end_s < self.load_ramp_start_s:
            raise _bad(
                "operating.load_ramp_end_s",
                self.load_ramp_end_s,
                f"must be >= load_ramp_start_s = {self.load_ramp_start_s:g} s",
            )
        return self

    @property
    def input_speed(self) -> float:
        """Input angular speed [rad/s]."""
        return self.input_speed_rpm * 2.0 * math.pi / 60.0


class PathEstimates(_Strict):
    """Estimated inputs of the torque-path compliances of :mod:`flexrv.analysis.path_compliances`
    (in every model and the analytic budget): carrier pillar joints, support-bearing rings,
    planet spline (the crank torsion needs only the crank's geometry)."""

    carrier_joint_torque_fraction: float = Field(
        gt=0.0, le=1.0, description="Fraction of the output torque that passes the pillar-to-plate joints [-]"
    )
    carrier_joint_clamp_length_mm: float = Field(
        gt=0.5, le=300.0, description="Clamp length l_K of a pillar joint's bolt (VDI 2230) [mm]"
    )
    carrier_joint_compliance_factor: float = Field(
        ge=1.0, le=10.0, description="Joint's bending resilience over VDI 2230's solid substitute body [-]"
    )
    support_ring_seat_factor: float = Field(
        gt=0.0,
        le=10.0,
        description="Winkler modulus of the support rings' seats over E b / R [-]",
    )
    planet_spline_teeth: int = Field(ge=6, le=200, description="Teeth of the planet-to-crank spline [-]")
    planet_spline_engaged_fraction: float = Field(
        gt=0.0, le=1.0, description="Fraction of the spline's teeth that carry load [-]"
    )
    spline_tooth_stiffness_N_per_mm_um: float = Field(
        gt=0.5, le=50.0, description="Stiffness of one engaged tooth pair per unit face width c' [N/(mm um)]"
    )


class PlausibleRange(_Strict):
    """The plausible range of an estimated value and why (the prediction intervals sample it)."""

    low: float
    high: float
    reason: str = Field(min_length=3)


def field_value(reducer, path: str):
    """The value of a dotted field path of a design (``section.field``; None inside an optional
    table the design leaves out), or raise ValueError."""
    obj = reducer
    for part in path.split("."):
        if obj is None:  # an optional table the design leaves out: the field is unused
            return None
        if isinstance(obj, dict) and part in obj:
            obj = obj[part]
        elif hasattr(obj, part) and not part.startswith("_"):
            obj = getattr(obj, part)
        else:
            raise _bad(f"ranges.{path!r}", path, "must name a numeric field of the design (section.field)")
    return obj


# --------------------------------------------------------------------------- reducer
from flexrv.design.manufacturing import ManufacturingErrors  # noqa: E402


def _names_field(model: type, dotted: str) -> bool:
    """Whether ``dotted`` (``"first_stage.module_mm"``, ``"materials.steel.poisson_ratio"``)
    names a field of the pydantic ``model`` (optional tables and fields included)."""
    import typing

    parts = dotted.split(".")
    current: Any = model
    i = 0
    while i < len(parts):
        fields = getattr(current, "model_fields", None)
        if not fields or parts[i] not in fields:
            return False
        ann = fields[parts[i]].annotation
        i += 1
        args = [a for a in typing.get_args(ann) if a is not type(None)]
        if typing.get_origin(ann) is dict:  # dict[str, Model]: a free key, then the model's fields
            if i == len(parts):
                return True
            i += 1
            current = args[-1]
        else:
            current = next((a for a in args if hasattr(a, "model_fields")), ann)
    return True


class Reducer(_Strict):
    """A complete RV reducer design. Load one with :func:`flexrv.design.load`."""

    name: str = Field(min_length=1, max_length=64)
    description: str
    sources: list[str] = Field(description="Where the values come from (seeds, handbooks)")
    provenance: dict[str, str] = Field(
        default_factory=dict,
        description="field path -> note, for every estimated value (optional; `flexrv show` warns where it is missing)",
    )
    first_stage: FirstStage
    second_stage: SecondStage
    crankshaft: Crankshaft
    needle_bearing: NeedleBearing
    main_bearing: MainBearing
    materials: dict[str, Material]
    parts: PartMaterials
    lubricant: Lubricant
    inertia: Inertia
    contact: ContactSettings
    operating: OperatingPoint
    errors: ManufacturingErrors = Field(
        default_factory=ManufacturingErrors, description="Manufacturing and assembly errors (all zero: ideal reducer)"
    )
    carrier: Carrier | None = Field(
        default=None,
        description="Carrier geometry (end plates, pillars, crank bores); optional: the carrier FE needs it",
    )
    housing: Housing | None = Field(
        default=None,
        description="Pin housing: pin seats (grooves), pin supports and the "
        "ring around the pins; optional: without it the pins "
        "are rigidly seated and the housing rigid",
    )
    path_estimates: PathEstimates | None = Field(
        default=None,
        description="Estimated inputs of the torque-path compliances (carrier joints, support-bearing rings, "
        "planet spline) in every model; optional: without it the models and the budget leave them out",
    )
    ranges: dict[str, PlausibleRange] = Field(
        default_factory=dict,
        description="field path -> plausible range of an estimated value with its reason (prediction intervals)",
    )

    @model_serializer(mode="wrap")
    def _omit_absent_carrier(self, handler):
        """A design without a [carrier] table dumps without the key (TOML has no null)."""
        data = handler(self)
        if isinstance(data, dict):
            for key in ("carrier", "housing", "path_estimates"):
                if key in data and data[key] is None:
                    data.pop(key)
            if "ranges" in data and not data["ranges"]:
                data.pop("ranges")
        return data

    def material(self, part: str) -> Material:
        """Material of a part (``gears``, ``crankshaft``, ``cycloid_disc``, ...)."""
        return self.materials[getattr(self.parts, part)]

    @property
    def crank_hole_radius(self) -> float:
        """Radius of a crank-bearing hole in the disc = needle outer raceway [m]."""
        nb, cs = self.needle_bearing, self.crankshaft
        return 0.5e-3 * (cs.eccentric_journal_diameter_mm + 2.0 * nb.roller_diameter_mm) + nb.clearance_per_side

    @model_validator(mode="after")
    def _ranges(self) -> "Reducer":
        """A range names a numeric field (or an unused optional one) and has low < high; the
        value itself may leave it (an override, a sweep)."""
        for path, r in self.ranges.items():
            value = field_value(self, path)
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))):
                raise _bad(f"ranges.{path!r}", value, "must name a numeric field of the design")
            if not r.low < r.high:
                raise _bad(f"ranges.{path!r}", [r.low, r.high], "must have low < high")
        return self

    @field_validator("name")
    @classmethod
    def _printable_name(cls, value: str) -> str:
        bad = [c for c in value if not c.isprintable()]
        if bad or not value.strip():
            raise _bad(
                "name",
                value,
                "must be printable text, not blank (no newline, tab or control characters)",
                "the name appears in file names, table titles and result attributes",
            )
        return value

    @model_validator(mode="after")
    def _known_provenance(self) -> "Reducer":
        unknown = [k for k in self.provenance if not _names_field(type(self), k)]
        if unknown:
            raise _bad(
                "provenance",
                unknown[0],
                f"{len(unknown)} of {len(self.provenance)} provenance key(s) name no field of the design "
                f"(first: {unknown[0][:80]!r}); each key is the dotted path of a field, e.g. 'first_stage.module_mm'",
            )
        return self

    @model_validator(mode="after")
    def _cross(self) -> "Reducer":
        for part, key in self.parts.model_dump().items():
            if key not in self.materials:
                raise _bad(f"parts.{part}", key, f"must be one of the materials {sorted(self.materials)}")
        fs, ss = self.first_stage, self.second_stage
        a_w = fs.center_distance
        r_root = ss.pin_circle_radius - ss.pin_radius - ss.eccentricity
        r_hole = self.crank_hole_radius
        if a_w + r_hole >= r_root:
            raise _bad(
                "first_stage.module_mm",
                fs.module_mm,
                f"crank circle radius a_w = {a_w * 1e3:.4g} mm plus crank hole radius {r_hole * 1e3:.4g} mm "
                f"must stay inside the disc root radius R_p - r_rp - a = {r_root * 1e3:.4g} mm",
                "the crank-bearing holes would cut through the cycloid teeth",
            )
        if ss.center_hole_radius >= a_w - r_hole:
            raise _bad(
                "second_stage.center_hole_radius_mm",
                ss.center_hole_radius_mm,
                f"must be < {(a_w - r_hole) * 1e3:.4g} mm (crank circle radius minus crank hole radius)",
                "centre hole would cut into the crank-bearing holes",
            )
        n = fs.n_planets
        if 2.0 * a_w * math.sin(math.pi / n) <= 2.0 * r_hole:
            raise _bad("first_stage.n_planets", n, "crank-bearing holes would overlap; use fewer planets")
        tip_planet = 0.5 * fs.module * (fs.planet_teeth + 2.0 + 2.0 * fs.planet_profile_shift)
        if 2.0 * a_w * math.sin(math.pi / n) <= 2.0 * tip_planet:
            raise _bad(
                "first_stage.n_planets",
                n,
                f"planet tip circles (r_a = {tip_planet * 1e3:.4g} mm) would overlap on a_w = {a_w * 1e3:.4g} mm",
            )
        if self.crankshaft.eccentric_journal_diameter_mm / 2.0 <= ss.eccentricity_mm:
            raise _bad(
                "crankshaft.eccentric_journal_diameter_mm",
                self.crankshaft.eccentric_journal_diameter_mm,
                f"must be > 2 a = {2 * ss.eccentricity_mm:g} mm",
            )
        nb, cs, mb = self.needle_bearing, self.crankshaft, self.main_bearing
        # needles side by side on their pitch circle (journal diameter + one roller diameter)
        d_j, d_r = cs.eccentric_journal_diameter_mm, nb.roller_diameter_mm
        n_max = int(math.pi * (d_j + d_r) / d_r)
        if nb.roller_count > n_max:
            raise _bad(
                "needle_bearing.roller_count",
                nb.roller_count,
                f"must be <= {n_max}: {nb.roller_count} rollers of {d_r:g} mm need "
                f"{nb.roller_count * d_r:.4g} mm > pi (d_journal + d_roller) = {math.pi * (d_j + d_r):.4g} mm "
                f"on the {d_j:g} mm journal",
                "the needles would overlap",
            )
        if nb.roller_length_mm > ss.disc_width_mm:
            raise _bad(
                "needle_bearing.roller_length_mm",
                nb.roller_length_mm,
                f"must be <= second_stage.disc_width_mm = {ss.disc_width_mm:g} mm",
                "the needles run in the disc's crank hole",
            )
        r_crank_out = (a_w + r_hole) * 1e3
        if mb.pitch_diameter_mm / 2.0 <= r_crank_out:
            raise _bad(
                "main_bearing.pitch_diameter_mm",
                mb.pitch_diameter_mm,
                f"must be > {2 * r_crank_out:.4g} mm: the main-bearing pitch circle must lie outside the "
                f"crank-hole circle (crank circle radius {a_w * 1e3:.4g} mm + crank hole radius "
                f"{r_hole * 1e3:.4g} mm)",
                "the main bearing would sit inside the crank circle",
            )
        if self.carrier is not None:
            self.carrier.validate_for(self)
        if self.housing is not None:
            self.housing.validate_for(self)
        self.errors.validate_for(self)  # list lengths vs z_rp / N / n_discs, clearances, assembly interference
        return self
