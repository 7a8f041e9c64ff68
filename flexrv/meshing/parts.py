"""Part geometry specifications (pure, SI) and their gmsh OCC builders.

Each part is described by a frozen ``*Spec`` dataclass built from a
:class:`flexrv.design.model.Reducer` (``spec_for(reducer, part)``); the spec is
everything the mesh depends on (it is hashed into the cache key). The builders
``build_<part>(gmsh, spec)`` create one OCC volume and return the physical
surface groups ``{name: [surface tags]}``.

Coordinate conventions (metres): the part axis is z; rings span
z in [-width/2, width/2] about their row's ball-centre plane (one row; the model
mirrors it for the other row); the crankshaft starts at z = 0 with the gear seat;
the cycloid disc spans z in [-b/2, b/2] with its centre at the origin; the
carrier's input plate spans z in [0, t_in], the plate gap [t_in, t_in + L] and the
output (flange) plate [t_in + L, t_in + L + t_out], crank k at the angle 2 pi k / N
on the crank circle (as the disc's crank holes).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from flexrv.errors import InputError
from flexrv.units import M_PER_MM

PARTS = ("outer_ring", "inner_ring", "crankshaft", "cycloid_disc", "carrier")

#: Tet10 nodes per unit volume ~ C / h^3 for the memory guard. gmsh 4.15 gives
#: C = 10..14 on the ring meshes; with the refinement terms the estimate is
#: 1.5-3x above the actual count (rv221 outer ring: 59k estimated, 33.5k meshed),
#: deliberately conservative.
NODE_DENSITY = 16.0


# ------------------------------------------------------------------ specs
@dataclass(frozen=True)
class RingSpec:
    """One main-bearing ring of one row (from flexrv.geometry.bearing.RingSection)."""

    ring: str  # "inner" | "outer"
    r_inner: float
    r_outer: float
    width: float
    groove_center_r: float
    groove_center_z: float
    groove_radius: float
    contact_r: float
    contact_z: float
    contact_angle: float
    ball_diameter: float
    n_balls: int
    fit: str  # "bore" | "outer"

    @property
    def wall(self) -> float:
        """Thinnest wall between groove bottom and fit surface [m]."""
        if self.ring == "outer":
            return self.r_outer - (self.groove_center_r + self.groove_radius)
        return (self.groove_center_r - self.groove_radius) - self.r_inner

    def volume(self) -> float:
        """Volume of the plain ring [m^3] (groove not subtracted; for node estimates)."""
        return math.pi * (self.r_outer**2 - self.r_inner**2) * self.width

    def default_size(self) -> float:
        """Default global mesh size [m]: a third of the section's smaller extent."""
        return min(self.width, self.r_outer - self.r_inner) / 3.0

    def raceway_size(self, size: float) -> float:
        """Mesh size on the raceway [m]: <= a third of the groove radius."""
        return min(size, self.groove_radius / 3.0)

    def contact_normal(self) -> tuple[float, float]:
        """Unit (r, z) direction of a ball force on this ring's raceway (pointing
        from the ball into the ring): outer ring +(cos a, sin a) towards the contact
        point, inner ring the opposite (Harris & Kotzalas 2007, ch. 2)."""
        dr = self.contact_r - self.groove_center_r
        dz = self.contact_z - self.groove_center_z
        n = math.hypot(dr, dz)
        return dr / n, dz / n


@dataclass(frozen=True)
class PlainRingSpec:
    """Plain rectangular-section ring (verification: thin-ring theory)."""

    r_inner: float
    r_outer: float
    width: float

    def volume(self) -> float:
        return math.pi * (self.r_outer**2 - self.r_inner**2) * self.width

    def default_size(self) -> float:
        return min(self.width, self.r_outer - self.r_inner) / 2.0


@dataclass(frozen=True)
class CrankshaftSpec:
    """Crankshaft segments along z (gear seat, support A, eccentric 1, eccentric 2,
    support B); each entry (name, radius, length, x offset)."""

    segments: tuple[tuple[str, float, float, float], ...]

    def volume(self) -> float:
        return sum(math.pi * r * r * length for _, r, length, _ in self.segments)

    def default_size(self) -> float:
        return min(r for _, r, _, _ in self.segments) / 2.0


@dataclass(frozen=True)
class CycloidDiscSpec:
    """Cycloid disc: modified profile parameters (flexrv.geometry.cycloid) + holes."""

    z_rp: int
    pin_circle_radius: float
    pin_radius: float
    eccentricity: float
    d_radius: float
    d_pin_radius: float
    d_rotation: float
    width: float
    crank_circle_radius: float
    crank_hole_radius: float
    n_crank_holes: int
    center_hole_radius: float
    points_per_lobe: int = 160

    @property
    def tooth_pitch(self) -> float:
        """Circular pitch of the disc teeth on the pin circle [m]."""
        return 2.0 * math.pi * self.pin_circle_radius / (self.z_rp - 1)

    def volume(self) -> float:
        r = self.pin_circle_radius
        holes = self.n_crank_holes * self.crank_hole_radius**2 + self.center_hole_radius**2
        return math.pi * (r * r - holes) * self.width

    def default_size(self) -> float:
        return min(self.width / 2.0, self.crank_hole_radius / 2.0)

    def profile_size(self, size: float) -> float:
        """Mesh size at the tooth flanks [m]: <= the pin radius r_rp, i.e. twice the
        pin patch half-width r_rp / 2 of :mod:`flexrv.fem.disc` (about a third of the
        tooth pitch on the presets).

        Chosen from a convergence study of the disc body's torsional compliance as
        the models and the budget use it (mean over six crank angles of
        :func:`flexrv.fem.disc.disc_torsion_sweep`, consistent patch loads, default
        global size, flank sizes in ratio sqrt 2):

        * rv40e, 4.24 / 3 / 2.12 mm (11.3k / 16.9k / 28.8k nodes): 1.45218 /
          1.46257 / 1.46803e-7 rad/(N m), observed order 1.86, Richardson value
          1.4741e-7: the default (3 mm) is 0.8 % below it (1.4 % with the order 0.88
          of the coarser triple at 8 mm global size);
        * rv221, 7.07 / 5 / 3.54 / 2.5 mm (21.1k / 32.5k / 47.7k / 81.4k nodes):
          2.27175 / 2.27992 / 2.28140 / 2.28413e-8, not in the asymptotic range
          (differences 8.2e-11, 1.5e-11, 2.7e-11); the default (5 mm) is 0.18 %
          below the finest and 0.5 % below its order-1 extrapolation.

        The former default (rv40e 1.29 mm, 66.7k nodes; rv221 2.2 mm, 107k nodes)
        cost 120 / 189 s CPU and 4.0 / 5.6 GB for the sweep (benchmarks/bench_bodies.py)."""
        return min(size, self.pin_radius)


@dataclass(frozen=True)
class CarrierSpec:
    """Carrier: two end plates joined by round pillars, crank bores through both
    plates, optional centre bore (from :class:`flexrv.design.model.Carrier`)."""

    plate_radius: float
    input_thickness: float
    output_thickness: float
    gap: float
    crank_circle_radius: float
    crank_bore_radius: float
    n_cranks: int
    center_bore_radius: float
    pillar_circle_radius: float
    pillar_radius: float
    pillar_angles: tuple[float, ...]

    @property
    def length(self) -> float:
        """Overall axial length [m]."""
        return self.input_thickness + self.gap + self.output_thickness

    def crank_angles(self) -> tuple[float, ...]:
        return tuple(2.0 * math.pi * k / self.n_cranks for k in range(self.n_cranks))

    def volume(self) -> float:
        plates = (
            math.pi
            * (self.plate_radius**2 - self.center_bore_radius**2 - self.n_cranks * self.crank_bore_radius**2)
            * (self.input_thickness + self.output_thickness)
        )
        return plates + len(self.pillar_angles) * math.pi * self.pillar_radius**2 * self.gap

    def default_size(self) -> float:
        """Default global mesh size [m]: a third of the thinnest plate, at most the
        thinnest ligament around a crank bore."""
        return min(min(self.input_thickness, self.output_thickness) / 3.0, self.min_feature())

    #: growth of the mesh size away from the pillar roots (size increase per unit distance)
    ROOT_GRADING = 0.5

    def root_size(self, size: float) -> float | None:
        """Mesh size at the pillar roots [m] (None: no extra refinement)."""
        return None

    def pillar_size(self, size: float) -> float:
        """Mesh size on the pillars [m]: <= half the pillar radius (beam bending
        of the pillars is the carrier's main compliance)."""
        return min(size, 0.5 * self.pillar_radius)

    def min_feature(self) -> float:
        """Smallest wall [m]: plate thickness, ligaments around the crank bores."""
        lig = min(
            self.plate_radius - self.crank_circle_radius - self.crank_bore_radius,
            self.crank_circle_radius - self.crank_bore_radius - self.center_bore_radius,
        )
        return min(self.input_thickness, self.output_thickness, lig)


def spec_for(reducer, part: str):
    """Geometry spec of ``part`` of ``reducer`` (SI).

    Raises
    ------
    InputError
        Unknown part name.
    """
    if part in ("outer_ring", "inner_ring"):
        from flexrv.geometry.bearing import BallBearingGeometry

        geo = BallBearingGeometry.from_design(reducer.main_bearing)
        ring = part.split("_")[0]
        sec = geo.ring_section(ring)
        return RingSpec(
            ring=ring,
            r_inner=sec.r_inner,
            r_outer=sec.r_outer,
            width=sec.width,
            groove_center_r=sec.groove_center_r,
            groove_center_z=sec.groove_center_z,
            groove_radius=sec.groove_radius,
            contact_r=sec.contact_r,
            contact_z=sec.contact_z,
            contact_angle=geo.contact_angle,
            ball_diameter=geo.ball_diameter,
            n_balls=geo.ball_count,
            fit=sec.fit,
        )
    if part == "crankshaft":
        cs = reducer.crankshaft
        e = reducer.second_stage.eccentricity
        segs = (
            ("gear_seat", 0.5e-3 * cs.gear_seat_diameter_mm, M_PER_MM * cs.gear_seat_length_mm, 0.0),
            ("support_a", 0.5e-3 * cs.support_journal_diameter_mm, M_PER_MM * cs.support_journal_length_mm, 0.0),
            ("eccentric_1", 0.5e-3 * cs.eccentric_journal_diameter_mm, M_PER_MM * cs.eccentric_journal_length_mm, e),
            ("eccentric_2", 0.5e-3 * cs.eccentric_journal_diameter_mm, M_PER_MM * cs.eccentric_journal_length_mm, -e),
            ("support_b", 0.5e-3 * cs.support_journal_diameter_mm, M_PER_MM * cs.support_journal_length_mm, 0.0),
        )
        return CrankshaftSpec(segments=segs)
    if part == "cycloid_disc":
        ss = reducer.second_stage
        return CycloidDiscSpec(
            z_rp=ss.pin_count,
            pin_circle_radius=ss.pin_circle_radius,
            pin_radius=ss.pin_radius,
            eccentricity=ss.eccentricity,
            d_radius=ss.modification_shift,
            d_pin_radius=ss.modification_equidistant,
            d_rotation=ss.modification_rotation,
            width=ss.disc_width,
            crank_circle_radius=reducer.first_stage.center_distance,
            crank_hole_radius=reducer.crank_hole_radius,
            n_crank_holes=reducer.first_stage.n_planets,
            center_hole_radius=ss.center_hole_radius,
        )
    if part == "carrier":
        c = reducer.carrier
        if c is None:
            raise InputError(
                f"design {reducer.name!r} has no [carrier] table: the carrier part needs its geometry "
                "(plate diameter and thicknesses, gap, crank bores, pillars; see the rv40e preset)"
            )
        return CarrierSpec(
            plate_radius=0.5e-3 * c.plate_outer_diameter_mm,
            input_thickness=M_PER_MM * c.input_plate_thickness_mm,
            output_thickness=M_PER_MM * c.output_plate_thickness_mm,
            gap=M_PER_MM * c.plate_gap_mm,
            crank_circle_radius=reducer.first_stage.center_distance,
            crank_bore_radius=0.5e-3 * c.crank_bore_diameter_mm,
            n_cranks=reducer.first_stage.n_planets,
            center_bore_radius=0.5e-3 * c.center_bore_diameter_mm,
            pillar_circle_radius=M_PER_MM * c.pillar_circle_radius_mm,
            pillar_radius=0.5e-3 * c.pillar_diameter_mm,
            pillar_angles=tuple(c.pillar_angles()),
        )
    raise InputError(f"part = {part!r} is not a known part: choose one of {', '.join(PARTS)}")


def spec_dict(spec) -> dict:
    """Plain dict of a spec (for hashing and metadata)."""
    return {"type": type(spec).__name__, **asdict(spec)}


# ------------------------------------------------------------------ checks
def check_size(spec, size: float, max_nodes: int) -> dict:
    """Validate the mesh size against the geometry and estimate the node count.

    Returns
    -------
    dict with ``size``, ``local_size`` [m] and ``estimated_nodes``.

    Raises
    ------
    InputError
        Size not positive/finite, too coarse to resolve the groove / wall /
        teeth, or an estimated node count above ``max_nodes`` (memory).
    """
    if not (math.isfinite(size) and size > 0.0):
        raise InputError(f"mesh size = {size!r} m must be a positive finite number")
    est_local = 0.0
    if isinstance(spec, RingSpec):
        if spec.wall <= 0.0:
            raise InputError(
                f"{spec.ring} ring: the groove cuts through the ring (wall under the groove "
                f"{spec.wall * 1e3:.3g} mm); the geometry self-intersects"
            )
        limit = min(spec.groove_radius, 2.0 * spec.wall)
        if size > limit:
            raise InputError(
                f"mesh size = {size * 1e3:.4g} mm is too coarse to resolve the {spec.ring} ring: "
                f"must be <= {limit * 1e3:.4g} mm (min of the groove radius f D = "
                f"{spec.groove_radius * 1e3:.4g} mm and twice the wall under the groove "
                f"{spec.wall * 1e3:.4g} mm)"
            )
        local = spec.raceway_size(size)
        race_area = 2.0 * math.pi * spec.groove_center_r * spec.groove_radius * math.pi / 2.0
        est_local = NODE_DENSITY * race_area * local / local**3
    elif isinstance(spec, PlainRingSpec):
        local = size
        if not spec.r_outer > spec.r_inner > 0:
            raise InputError("plain ring: need 0 < r_inner < r_outer")
    elif isinstance(spec, CrankshaftSpec):
        rmin = min(r for _, r, _, _ in spec.segments)
        if size > rmin:
            raise InputError(
                f"mesh size = {size * 1e3:.4g} mm is too coarse for the crankshaft: must be <= "
                f"the smallest journal radius {rmin * 1e3:.4g} mm"
            )
        local = size
    elif isinstance(spec, CycloidDiscSpec):
        limit = min(spec.width, spec.crank_hole_radius)
        if size > limit:
            raise InputError(
                f"mesh size = {size * 1e3:.4g} mm is too coarse for the cycloid disc: must be <= "
                f"{limit * 1e3:.4g} mm (min of disc width and crank hole radius)"
            )
        local = spec.profile_size(size)
        band = 2.0 * math.pi * spec.pin_circle_radius * spec.width * 4.0 * spec.eccentricity
        est_local = NODE_DENSITY * band / local**3
    elif isinstance(spec, CarrierSpec):
        limit = spec.min_feature()
        if limit <= 0:
            raise InputError(
                "carrier: a crank bore cuts the plate rim or the centre bore; the geometry self-intersects"
            )
        if size > limit:
            raise InputError(
                f"mesh size = {size * 1e3:.4g} mm is too coarse for the carrier: must be <= "
                f"{limit * 1e3:.4g} mm (thinnest plate or ligament around a crank bore)"
            )
        local = spec.pillar_size(size)
        edge = spec.root_size(size)
        est_local = NODE_DENSITY * len(spec.pillar_angles) * math.pi * spec.pillar_radius**2 * spec.gap / local**3
    else:  # pragma: no cover - spec_for guards the type
        raise InputError(f"unknown spec {type(spec).__name__}")
    est = int(NODE_DENSITY * spec.volume() / size**3 + est_local)
    out = {"size": size, "local_size": local, "estimated_nodes": est}
    if isinstance(spec, CarrierSpec) and edge is not None:
        out["edge_size"] = edge
    if est > max_nodes:
        raise InputError(
            f"mesh size = {size * 1e3:.4g} mm is too fine: about {est:,} nodes estimated, more than "
            f"the memory limit of {max_nodes:,} nodes; use a larger size"
        )
    return out


def profile_is_simple(points: np.ndarray) -> bool:
    """True if a closed 2-D profile is star-shaped about the origin (its polar
    angle increases or decreases strictly monotonically), which implies it does
    not self-intersect."""
    ang = np.unwrap(np.arctan2(points[:, 1], points[:, 0]))
    d = np.diff(ang)
    return bool(np.all(d > 0) or np.all(d < 0))


# ------------------------------------------------------------------ builders
def _faces_of(gmsh, vol_tag: int) -> list[int]:
    return [t for _, t in gmsh.model.getBoundary([(3, vol_tag)], oriented=False, combined=False)]


def _single_volume(gmsh, what: str) -> int:
    vols = gmsh.model.getEntities(3)
    if len(vols) != 1:
        raise InputError(
            f"{what}: the geometry gives {len(vols)} volumes instead of one; it self-intersects or falls apart"
        )
    return vols[0][1]


def build_ring(gmsh, spec: RingSpec, size: float) -> dict[str, list[int]]:
    """Ring = annulus cylinder minus the groove torus. Groups: ``raceway`` (torus
    faces), ``fit`` (bore of the inner / outer face of the outer ring), ``land``,
    ``side``."""
    occ = gmsh.model.occ
    z0 = -0.5 * spec.width
    outer = occ.addCylinder(0, 0, z0, 0, 0, spec.width, spec.r_outer)
    inner = occ.addCylinder(0, 0, z0, 0, 0, spec.width, spec.r_inner)
    torus = occ.addTorus(0, 0, spec.groove_center_z, spec.groove_center_r, spec.groove_radius, zAxis=[0, 0, 1])
    occ.cut([(3, outer)], [(3, inner), (3, torus)])
    occ.synchronize()
    vol = _single_volume(gmsh, f"{spec.ring} ring")
    groups: dict[str, list[int]] = {"raceway": [], "fit": [], "land": [], "side": []}
    r_fit = spec.r_outer if spec.fit == "outer" else spec.r_inner
    for tag in _faces_of(gmsh, vol):
        kind = gmsh.model.getType(2, tag)
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, tag)
        if kind == "Plane":
            groups["side"].append(tag)
        elif kind == "Torus" or "Torus" in kind:
            groups["raceway"].append(tag)
        elif abs(0.5 * (xmax - xmin) - r_fit) < 1e-3 * r_fit:
            groups["fit"].append(tag)
        else:
            groups["land"].append(tag)
    if not groups["raceway"] or not groups["fit"]:
        raise InputError(
            f"{spec.ring} ring: raceway or fit surface not found; the groove does not cut the ring "
            "(check contact angle, conformity and ring section)"
        )
    return groups


def build_plain_ring(gmsh, spec: PlainRingSpec, size: float) -> dict[str, list[int]]:
    """Plain annulus. Groups: ``outer``, ``bore``, ``side``."""
    occ = gmsh.model.occ
    z0 = -0.5 * spec.width
    a = occ.addCylinder(0, 0, z0, 0, 0, spec.width, spec.r_outer)
    b = occ.addCylinder(0, 0, z0, 0, 0, spec.width, spec.r_inner)
    occ.cut([(3, a)], [(3, b)])
    occ.synchronize()
    vol = _single_volume(gmsh, "plain ring")
    groups: dict[str, list[int]] = {"outer": [], "bore": [], "side": []}
    for tag in _faces_of(gmsh, vol):
        if gmsh.model.getType(2, tag) == "Plane":
            groups["side"].append(tag)
        else:
            xmin, _, _, xmax, _, _ = gmsh.model.getBoundingBox(2, tag)
            groups["outer" if 0.5 * (xmax - xmin) > 0.5 * (spec.r_inner + spec.r_outer) else "bore"].append(tag)
    return groups


def build_crankshaft(gmsh, spec: CrankshaftSpec, size: float) -> dict[str, list[int]]:
    """Fused coaxial/eccentric cylinders. Groups: one per segment's lateral
    surface (``gear_seat``, ``support_a``, ``eccentric_1``, ``eccentric_2``,
    ``support_b``) and ``end`` (plane faces)."""
    occ = gmsh.model.occ
    z = 0.0
    tags, spans = [], []
    for name, r, length, dx in spec.segments:
        tags.append((3, occ.addCylinder(dx, 0, z, 0, 0, length, r)))
        spans.append((name, z, z + length, r, dx))
        z += length
    if len(tags) > 1:
        occ.fuse(tags[:1], tags[1:])
    occ.synchronize()
    vol = _single_volume(gmsh, "crankshaft")
    groups: dict[str, list[int]] = {name: [] for name, *_ in spans}
    groups["end"] = []
    for tag in _faces_of(gmsh, vol):
        if gmsh.model.getType(2, tag) == "Plane":
            groups["end"].append(tag)
            continue
        x, y, zc = occ.getCenterOfMass(2, tag)
        xmin, _, _, xmax, _, _ = gmsh.model.getBoundingBox(2, tag)
        best = min(
            spans,
            key=lambda s: (
                not (s[1] - 1e-9 <= zc <= s[2] + 1e-9),
                abs(0.5 * (xmax + xmin) - s[4]) + abs(0.5 * (xmax - xmin) - s[3]),
            ),
        )
        groups[best[0]].append(tag)
    missing = [k for k, v in groups.items() if not v]
    if missing:
        raise InputError(f"crankshaft: surfaces {missing} not found; the segments overlap or self-intersect")
    return groups


def cycloid_profile(spec: CycloidDiscSpec, points_per_lobe: int | None = None) -> np.ndarray:
    """Profile points [m] of the modified disc profile, shape (z_c, n + 1, 2): one
    row per lobe (tooth), equally spaced in arc length (so an interpolating spline
    through them has a uniform, small error), first/last point shared with the
    neighbouring lobes. The curve itself is :func:`flexrv.geometry.cycloid.profile_points`."""
    from flexrv.geometry.cycloid import profile_points

    n = points_per_lobe or spec.points_per_lobe
    z_c = spec.z_rp - 1
    args = (
        spec.z_rp,
        spec.pin_circle_radius,
        spec.pin_radius,
        spec.eccentricity,
        spec.d_radius,
        spec.d_pin_radius,
        spec.d_rotation,
    )
    fine = np.linspace(0.0, 2.0 * np.pi / z_c, 20 * n + 1)
    seg = np.linalg.norm(np.diff(profile_points(fine, *args), axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    phi0 = np.interp(np.linspace(0.0, s[-1], n + 1), s, fine)
    phi = np.arange(z_c)[:, None] * (2.0 * np.pi / z_c) + phi0[None, :]
    return profile_points(phi, *args)


def build_cycloid_disc(gmsh, spec: CycloidDiscSpec, size: float) -> dict[str, list[int]]:
    """Planar face bounded by one interpolating spline per tooth (lobe), minus the
    crank holes and the centre hole, extruded by the disc width. Groups:
    ``profile``, ``crank_hole_<k>`` (k = 1..n), ``center_hole``, ``side``."""
    occ = gmsh.model.occ
    pts = cycloid_profile(spec)
    if not profile_is_simple(pts[:, :-1].reshape(-1, 2)):
        raise InputError(
            "cycloid disc: the modified profile self-intersects (loops); reduce the eccentricity, "
            "the pin radius or the modifications"
        )
    rmin = float(np.min(np.hypot(pts[..., 0], pts[..., 1])))
    if spec.crank_circle_radius + spec.crank_hole_radius >= rmin or (
        spec.center_hole_radius and spec.center_hole_radius >= spec.crank_circle_radius - spec.crank_hole_radius
    ):
        raise InputError("cycloid disc: crank holes cut the profile or the centre hole; the geometry self-intersects")
    z0 = -0.5 * spec.width
    z_c, n1, _ = pts.shape
    tags = np.empty((z_c, n1), dtype=int)
    for i in range(z_c):
        for j in range(n1 - 1):
            tags[i, j] = occ.addPoint(pts[i, j, 0], pts[i, j, 1], z0)
    tags[:, -1] = np.roll(tags[:, 0], -1)
    curves = [occ.addSpline([int(t) for t in tags[i]]) for i in range(z_c)]
    loops = [occ.addCurveLoop(curves)]
    holes = []
    for k in range(spec.n_crank_holes):
        ang = 2.0 * math.pi * k / spec.n_crank_holes
        c = occ.addCircle(
            spec.crank_circle_radius * math.cos(ang),
            spec.crank_circle_radius * math.sin(ang),
            z0,
            spec.crank_hole_radius,
        )
        holes.append(("crank_hole_%d" % (k + 1), ang))
        loops.append(occ.addCurveLoop([c]))
    if spec.center_hole_radius > 0:
        loops.append(occ.addCurveLoop([occ.addCircle(0, 0, z0, spec.center_hole_radius)]))
    face = occ.addPlaneSurface(loops)
    occ.extrude([(2, face)], 0, 0, spec.width)
    occ.synchronize()
    vol = _single_volume(gmsh, "cycloid disc")
    groups: dict[str, list[int]] = {"profile": [], "center_hole": [], "side": []}
    groups.update({name: [] for name, _ in holes})
    for tag in _faces_of(gmsh, vol):
        if gmsh.model.getType(2, tag) == "Plane":
            groups["side"].append(tag)
            continue
        x, y, _ = occ.getCenterOfMass(2, tag)
        rc = math.hypot(x, y)
        if rc < 0.5 * spec.crank_circle_radius and spec.center_hole_radius > 0:
            groups["center_hole"].append(tag)
        elif rc < spec.crank_circle_radius + 0.5 * spec.crank_hole_radius:
            ang = math.atan2(y, x)
            name = min(holes, key=lambda h: abs(math.remainder(ang - h[1], 2 * math.pi)))[0]
            groups[name].append(tag)
        else:
            groups["profile"].append(tag)
    if spec.center_hole_radius <= 0:
        groups.pop("center_hole")
    return groups


def profile_deviation(gmsh, spec: CycloidDiscSpec, samples_per_curve: int = 200) -> float:
    """Largest distance [m] between the meshed profile curves (the OCC splines,
    on the bottom face) and the exact modified profile, measured on
    ``samples_per_curve`` points per spline against 400 exact points per lobe
    refined by local projection (distance to the exact chord polyline of a
    1e5-point sampling, whose own chordal error is < 1e-9 m)."""
    from scipy.spatial import cKDTree

    exact = cycloid_profile(spec, 4000)[:, :-1].reshape(-1, 2)
    tree = cKDTree(exact)
    worst = 0.0
    z0 = -0.5 * spec.width
    for dim, tag in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, tag)
        xyz = np.asarray(gmsh.model.getValue(1, tag, np.linspace(lo[0], hi[0], samples_per_curve))).reshape(-1, 3)
        if (
            not np.allclose(xyz[:, 2], z0)
            or np.hypot(xyz[:, 0], xyz[:, 1]).min() < spec.crank_circle_radius + spec.crank_hole_radius * 1.01
        ):
            continue
        d, idx = tree.query(xyz[:, :2])
        # distance to the polyline through the nearest exact point's neighbours
        n = len(exact)
        a, b, c = exact[(idx - 1) % n], exact[idx], exact[(idx + 1) % n]
        worst = max(worst, float(np.max(np.minimum(_seg_dist(xyz[:, :2], a, b), _seg_dist(xyz[:, :2], b, c)))))
    return worst


def _seg_dist(p, a, b):
    ab = b - a
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / den, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def build_carrier(gmsh, spec: CarrierSpec, size: float) -> dict[str, list[int]]:
    """Input plate + pillars + output plate fused, minus the crank bores and the
    centre bore. Groups: ``bore_in_<k>`` / ``bore_out_<k>`` (crank support-bearing
    seats of crank k in the input / output plate), ``flange`` (outer face of the
    output plate), ``seat_in`` / ``seat_out`` (plate rims, main-bearing seats),
    ``pillar`` (pillar lateral faces), ``center_bore`` and ``side`` (other plane faces)."""
    occ = gmsh.model.occ
    t_in, gap, t_out = spec.input_thickness, spec.gap, spec.output_thickness
    total = spec.length
    plate_in = occ.addCylinder(0, 0, 0, 0, 0, t_in, spec.plate_radius)
    plate_out = occ.addCylinder(0, 0, t_in + gap, 0, 0, t_out, spec.plate_radius)
    pillars = [
        (
            3,
            occ.addCylinder(
                spec.pillar_circle_radius * math.cos(a),
                spec.pillar_circle_radius * math.sin(a),
                t_in,
                0,
                0,
                gap,
                spec.pillar_radius,
            ),
        )
        for a in spec.pillar_angles
    ]
    occ.fuse([(3, plate_in)], [(3, plate_out)] + pillars)
    tools = [
        (
            3,
            occ.addCylinder(
                spec.crank_circle_radius * math.cos(a),
                spec.crank_circle_radius * math.sin(a),
                -total,
                0,
                0,
                3 * total,
                spec.crank_bore_radius,
            ),
        )
        for a in spec.crank_angles()
    ]
    if spec.center_bore_radius > 0:
        tools.append((3, occ.addCylinder(0, 0, -total, 0, 0, 3 * total, spec.center_bore_radius)))
    occ.cut(occ.getEntities(3)[:1], tools)
    occ.synchronize()
    vol = _single_volume(gmsh, "carrier")
    cranks = [
        (k + 1, spec.crank_circle_radius * math.cos(a), spec.crank_circle_radius * math.sin(a))
        for k, a in enumerate(spec.crank_angles())
    ]
    groups: dict[str, list[int]] = {f"bore_{p}_{k}": [] for p in ("in", "out") for k, _, _ in cranks}
    groups.update({"flange": [], "seat_in": [], "seat_out": [], "pillar": [], "side": []})
    if spec.center_bore_radius > 0:
        groups["center_bore"] = []
    tol = 1e-3 * min(t_in, gap, t_out)  # OCC bounding boxes are inflated by the geometric tolerance
    for tag in _faces_of(gmsh, vol):
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, tag)
        zc = 0.5 * (zmin + zmax)
        plate = "in" if zc < t_in + 0.5 * gap else "out"
        if gmsh.model.getType(2, tag) == "Plane":
            groups["flange" if abs(zmin - total) < tol and abs(zmax - total) < tol else "side"].append(tag)
            continue
        x, y, _ = gmsh.model.occ.getCenterOfMass(2, tag)
        half = 0.5 * max(xmax - xmin, ymax - ymin)
        if zmin > t_in - tol and zmax < t_in + gap + tol:
            groups["pillar"].append(tag)
        elif abs(half - spec.plate_radius) < 1e-3 * spec.plate_radius and math.hypot(x, y) < 0.5 * spec.plate_radius:
            groups[f"seat_{plate}"].append(tag)
        elif spec.center_bore_radius > 0 and math.hypot(x, y) < 0.5 * spec.center_bore_radius:
            groups["center_bore"].append(tag)
        else:
            k = min(cranks, key=lambda c: math.hypot(x - c[1], y - c[2]))[0]
            groups[f"bore_{plate}_{k}"].append(tag)
    missing = [k for k, v in groups.items() if not v]
    if missing:
        raise InputError(f"carrier: surfaces {missing} not found; the plates, pillars and bores intersect wrongly")
    return groups


BUILDERS = {
    "outer_ring": build_ring,
    "inner_ring": build_ring,
    "crankshaft": build_crankshaft,
    "cycloid_disc": build_cycloid_disc,
    "carrier": build_carrier,
    "plain_ring": build_plain_ring,
    "shaft": build_crankshaft,
}
