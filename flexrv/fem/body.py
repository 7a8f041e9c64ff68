"""Reduced flexible bodies of the reducer parts: build, cache, raceway
interpolation, and Exudyn loaders.

Not run as a doctest (meshing and reduction take minutes on a fresh cache; the tests in
tests/test_fem_reduction.py run them); ``u`` is (..., 3) [m] in the body frame, ``Q`` the
(..., m) modal forces [N]:

>>> from flexrv.design import load                        # doctest: +SKIP
>>> body = reduce_part(load("rv221"), "outer_ring")       # doctest: +SKIP
>>> u = body.raceway_displacement(q, azimuth)             # doctest: +SKIP
>>> Q = body.raceway_load_vector(azimuth, force)          # doctest: +SKIP

A reduced body file (``<part>-<key>.cms.npz`` under :func:`flexrv.cache.cache_dir`,
format :data:`BODY_FORMAT_VERSION`) holds the Ritz basis, the diagonal reduced
matrices (M_r = I, K_r = diag(omega^2)), the surface, the node sets and the raceway
interpolation table; it is keyed by the mesh key, the material, the reduction
settings and the library versions and is reused when nothing changed.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_path, cache_dir, cached_entry, content_hash, library_versions
from flexrv.errors import InputError
from flexrv.fem.reduction import (
    RacewaySpec,
    default_harmonics,
    fourier_loads,
    hcb_basis,
    nodal_areas,
    periodic_cubic,
    raceway_weights,
)

BODY_FORMAT_VERSION = 1

#: interface surface groups per part; the first defines the floating frame
INTERFACES = {
    "outer_ring": ["fit"],
    "inner_ring": ["fit"],
    "crankshaft": ["support_a", "support_b"],
    "cycloid_disc": None,
}  # disc: its crank holes, filled in from the mesh
MATERIAL_OF = {
    "outer_ring": "bearing_rings",
    "inner_ring": "bearing_rings",
    "crankshaft": "crankshaft",
    "cycloid_disc": "cycloid_disc",
}


def interface_groups(part: str, group_names) -> list[str]:
    """Interface group names of a part (frame interface first)."""
    if part not in MATERIAL_OF:
        raise InputError(f"part = {part!r} is not a known part: choose one of {', '.join(MATERIAL_OF)}")
    groups = INTERFACES[part]
    if groups is None:
        groups = sorted(g for g in group_names if g.startswith("crank_hole_"))
    return list(groups)


@dataclass
class ReducedBody:
    """A reduced flexible body (SI units, body frame = the part's mesh frame).

    Attributes
    ----------
    modes : (3N, m) M-orthonormal Ritz basis (node-wise x, y, z DOFs).
    omega2 : (m,) reduced stiffness diagonal [1/s^2] (reduced mass = identity).
    nodes : (N, 3) [m]; tris : (F, 6) surface Tri6.
    race_nodes : raceway node indices (empty for parts without raceway).
    raceway : :class:`RacewaySpec` or None; table : (n_grid, 3, m) raceway
        displacement per unit modal coordinate in cylindrical (r, t, z)
        components at the grid azimuths 2 pi i / n_grid.
    info : counts, timings, settings.
    """

    part: str
    modes: np.ndarray
    omega2: np.ndarray
    nodes: np.ndarray
    tris: np.ndarray
    node_sets: dict
    raceway: RacewaySpec | None
    table: np.ndarray | None
    info: dict = field(default_factory=dict)
    path: Path | None = None
    stress_modes: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return int(self.modes.shape[1])

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Eigenfrequencies of the reduced body with its frame interface clamped [Hz]."""
        return np.sqrt(self.omega2) / (2.0 * np.pi)

    @property
    def mass_matrix(self) -> np.ndarray:
        return np.eye(self.n_modes)

    @property
    def stiffness_matrix(self) -> np.ndarray:
        return np.diag(self.omega2)

    # ------------------------------------------------------------ raceway
    def _require_raceway(self):
        if self.raceway is None or self.table is None:
            raise InputError(f"part {self.part!r} has no raceway")

    def contact_normals(self, azimuth) -> np.ndarray:
        """Unit contact directions (..., 3) into the ring at the given azimuths."""
        self._require_raceway()
        a = np.asarray(azimuth, dtype=float)
        return np.stack(
            [self.raceway.n_r * np.cos(a), self.raceway.n_r * np.sin(a), np.full_like(a, self.raceway.n_z)], axis=-1
        )

    def raceway_matrix(self, azimuth) -> np.ndarray:
        """(..., 3, m) Cartesian raceway displacement per modal coordinate at ``azimuth``
        (patch-weighted mean over the contact patch; periodic cubic interpolation)."""
        self._require_raceway()
        a = np.asarray(azimuth, dtype=float)
        A = periodic_cubic(self.table, a)  # (..., 3, m) cylindrical
        c, s = np.cos(a)[..., None], np.sin(a)[..., None]
        return np.stack(
            [c * A[..., 0, :] - s * A[..., 1, :], s * A[..., 0, :] + c * A[..., 1, :], A[..., 2, :]], axis=-2
        )

    def raceway_compliance_factors(self, stiffness_scale: float = 1.0) -> np.ndarray:
        """(n_grid, 3, m) raceway table scaled by K^-1/2 (K = ``stiffness_scale``
        diag(omega^2)): the raceway compliance of the ring with its fit clamped
        between grid azimuths i and k is W_i W_k^T [m/N] (cylindrical components),
        and interpolated with the table's Catmull–Rom weights it is
        B(psi_j) K^-1 B(psi_k)^T of the interpolated basis exactly (static
        condensation of a quasi-static ring onto its ball contacts,
        :mod:`flexrv.model.bearing_kernel`). Kept with the body, per scale."""
        self._require_raceway()
        cache = self.__dict__.setdefault("_compliance_factors", {})
        key = float(stiffness_scale)
        if key not in cache:
            scale = 1.0 / np.sqrt(key * np.asarray(self.omega2, dtype=float))
            cache[key] = np.ascontiguousarray(np.asarray(self.table, dtype=float) * scale)
        return cache[key]

    def raceway_displacement(self, q_modal, azimuth) -> np.ndarray:
        """Raceway displacement (..., 3) [m] (body frame, Cartesian) at ``azimuth`` [rad]
        for modal coordinates ``q_modal`` (m,) or broadcastable (..., m)."""
        A = self.raceway_matrix(azimuth)
        return np.einsum("...im,...m->...i", A, np.asarray(q_modal, dtype=float))

    def raceway_load_vector(self, azimuth, force_vec) -> np.ndarray:
        """Modal forces (..., m) [N] of point loads ``force_vec`` (..., 3) [N] (body
        frame) acting at the raceway azimuths ``azimuth`` (...), by virtual work
        Q = A(theta)^T F — the transpose of :meth:`raceway_displacement`. Sum over the
        leading axes for several balls."""
        A = self.raceway_matrix(azimuth)
        return np.einsum("...im,...i->...m", A, np.asarray(force_vec, dtype=float))

    def displacement(self, q_modal) -> np.ndarray:
        """Nodal displacements (N, 3) [m] of modal coordinates q (m,)."""
        return (self.modes @ np.asarray(q_modal, dtype=float)).reshape(-1, 3)

    def von_mises(self, q_modal) -> np.ndarray:
        """Nodal von Mises stress (N,) [Pa] of modal coordinates q (needs the body
        built with ``stress=True``)."""
        from flexrv.fem.stress import von_mises

        if self.stress_modes is None:
            raise InputError(f"reduced body {self.part!r} has no stress modes; rebuild it with stress=True")
        q = np.asarray(q_modal, dtype=float)
        comps = np.stack([self.stress_modes[:, c::6] @ q for c in range(6)], axis=-1)
        return von_mises(comps)

    # ------------------------------------------------------------ Exudyn
    def add_modal_body(self, mbs, damping_ratio: float = 0.0, name: str = ""):
        """Add the body as plain modal coordinates (frame fixed in space):
        ``NodeGenericODE2`` (m coordinates) + ``ObjectGenericODE2`` with M_r = I,
        K_r = diag(omega^2), modal damping D = diag(2 zeta omega).
        Returns (node number, object number)."""
        import exudyn.itemInterface as eii

        m = self.n_modes
        node = mbs.AddNode(
            eii.NodeGenericODE2(
                referenceCoordinates=[0.0] * m,
                initialCoordinates=[0.0] * m,
                initialCoordinates_t=[0.0] * m,
                numberOfODE2Coordinates=m,
                name=name and f"{name}_modal",
            )
        )
        damp = np.diag(2.0 * damping_ratio * np.sqrt(self.omega2))
        obj = mbs.AddObject(
            eii.ObjectGenericODE2(
                nodeNumbers=[node],
                massMatrix=self.mass_matrix,
                stiffnessMatrix=self.stiffness_matrix,
                dampingMatrix=damp,
                visualization=eii.VObjectGenericODE2(show=False),
                name=name,
            )
        )
        return node, obj

    # ------------------------------------------------------------ file
    def save(self, path: Path) -> None:
        rw = None if self.raceway is None else json.dumps(self.raceway.__dict__)
        sets = {f"set_{k}": v for k, v in self.node_sets.items()}
        extra = {} if self.stress_modes is None else {"stress_modes": self.stress_modes.astype(np.float32)}
        np.savez(
            path,
            version=BODY_FORMAT_VERSION,
            part=self.part,
            modes=self.modes,
            omega2=self.omega2,
            nodes=self.nodes,
            tris=self.tris,
            raceway=json.dumps(rw),
            table=np.zeros(0) if self.table is None else self.table,
            info=json.dumps(self.info),
            **sets,
            **extra,
        )

    @classmethod
    def load(cls, path: str | Path) -> "ReducedBody":
        with np.load(path, allow_pickle=False) as z:
            if int(z["version"]) != BODY_FORMAT_VERSION:
                raise InputError(
                    f"reduced body file {path} has format {int(z['version'])}, expected "
                    f"{BODY_FORMAT_VERSION}; delete it to rebuild"
                )
            rw = json.loads(str(z["raceway"]))
            raceway = None if rw is None else RacewaySpec(**json.loads(rw))
            sets = {k[4:]: z[k] for k in z.files if k.startswith("set_")}
            stress = z["stress_modes"].astype(float) if "stress_modes" in z.files else None
            return cls(
                part=str(z["part"]),
                modes=z["modes"],
                omega2=z["omega2"],
                nodes=z["nodes"],
                tris=z["tris"],
                node_sets=sets,
                raceway=raceway,
                table=None if raceway is None else z["table"],
                info=json.loads(str(z["info"])),
                path=Path(path),
                stress_modes=stress,
            )


def _assemble(mesh, material: dict, mass: bool = True):
    """K (and M unless ``mass`` is False) of a mesh (:func:`flexrv.fem.assembly.assemble`)."""
    from flexrv.fem.assembly import assemble

    return assemble(mesh.nodes, mesh.tets, material["E"], material["nu"], material["rho"], mass=mass)


def material_dict(reducer, part: str) -> dict:
    mat = reducer.material(MATERIAL_OF[part])
    return {"E": mat.youngs_modulus, "nu": mat.poisson_ratio, "rho": mat.density_kg_m3}


def raceway_spec_for(ring_spec, load_width: float | None, n_harmonics: int | None) -> RacewaySpec:
    """Raceway load spec of a ring (see :mod:`flexrv.fem.reduction`)."""
    b = 0.25 * ring_spec.ball_diameter if load_width is None else float(load_width)
    if not b > 0:
        raise InputError(f"load_width = {load_width!r} m must be > 0")
    nr, nz = ring_spec.contact_normal()
    k = default_harmonics(ring_spec.contact_r, b) if n_harmonics is None else int(n_harmonics)
    if k < 0:
        raise InputError(f"n_harmonics = {n_harmonics!r} must be >= 0")
    return RacewaySpec(r=ring_spec.contact_r, z=ring_spec.contact_z, n_r=nr, n_z=nz, b=b, n_harmonics=k)


def build_reduced_body(
    mesh_result,
    material: dict,
    n_eig: int = 20,
    raceway: RacewaySpec | None = None,
    stress: bool = False,
    cache: bool = True,
    fe=None,
) -> ReducedBody:
    """Reduce a meshed part (see module doc); cached by mesh key + settings.

    Parameters
    ----------
    mesh_result : :class:`flexrv.meshing.MeshResult`.
    material : {"E" [Pa], "nu", "rho" [kg/m^3]}.
    n_eig : fixed-interface eigenmodes.
    raceway : raceway-load modes and interpolation (rings), or None.
    stress : also compute stress post-processing modes (nodal von Mises colouring).
    fe : an already assembled :class:`flexrv.fem.assembly.FEModel` (optional).
    """
    mesh = mesh_result.data
    part = mesh.part
    ifaces = interface_groups(part, mesh.group_names)
    settings = {
        "n_eig": int(n_eig),
        "raceway": None if raceway is None else raceway.__dict__,
        "interfaces": ifaces,
        "stress": bool(stress),
    }
    key = content_hash(
        mesh_result.key,
        material,
        settings,
        BODY_FORMAT_VERSION,
        library_versions("exudyn", "scikit-fem", "scipy", "numpy"),
    )
    path = cache_dir() / f"{part}-{key}.cms.npz"

    def _build() -> "ReducedBody":
        return _reduce_uncached(
            mesh_result, mesh, part, material, settings, ifaces, n_eig, raceway, stress, fe, path, cache
        )

    body, _ = cached_entry([path], key, lambda: ReducedBody.load(path), _build, enabled=cache)
    return body


def body_identity(body: ReducedBody) -> dict | None:
    """What identifies a cached reduced body for a saved run: its cache file name
    (``<part>-<content key>.cms.npz``, the key a hash of the mesh, material, settings,
    format and library versions), or None for a body that was not cached."""
    if body.path is None:
        return None
    name = Path(body.path).name
    return {"cache_file": name, "key": name.split("-", 1)[1].split(".", 1)[0]}


def load_cached_body(identity: dict) -> ReducedBody:
    """The reduced body of a saved run from the cache, verified against its stored key
    (:func:`flexrv.cache.entry_problem`); never meshes or reduces. A body that is gone or
    does not match raises :class:`InputError` saying how to rebuild it."""
    from flexrv.cache import entry_problem

    name, key = str(identity.get("cache_file", "")), str(identity.get("key", ""))
    if not name.endswith(".cms.npz") or "/" in name or not key:
        raise InputError(f"flexible_bodies: {identity!r} is not a reduced-body identity")
    path = cache_dir() / name
    problem = entry_problem([path], key)
    if problem is not None:
        raise InputError(
            f"the reduced body {name} this run used is not usable in the cache {cache_dir()} ({problem}); "
            "rebuild it by re-running the simulation with the saved config.toml "
            "(`flexrv simulate DIR/config.toml --model flexible ...`), or let `flexrv view --rebuild` "
            "mesh and reduce it again"
        )
    return ReducedBody.load(path)


def _reduce_uncached(mesh_result, mesh, part, material, settings, ifaces, n_eig, raceway, stress, fe, path, cache):
    """The reduction of :func:`reduce_mesh` without the cache lookup (writes ``path`` if ``cache``)."""
    t0 = time.perf_counter()
    if fe is None:
        fe = _assemble(mesh, material)
    t1 = time.perf_counter()
    sets = [mesh.node_set(g) for g in ifaces]
    node_sets = {g: s for g, s in zip(ifaces, sets)}
    loads, race_nodes, areas = None, np.zeros(0, dtype=np.int64), None
    if raceway is not None:
        race_nodes = mesh.node_set("raceway")
        areas = nodal_areas(mesh.nodes, mesh.faces("raceway"))
        loads = fourier_loads(mesh.nodes, race_nodes, areas, raceway)
    node_sets["raceway"] = race_nodes
    res = hcb_basis(fe.K, fe.M, mesh.nodes, sets, n_eig, loads)
    t2 = time.perf_counter()
    table = None
    if raceway is not None:
        ng = int(4 * math.ceil(2.0 * math.pi * raceway.r / (raceway.b / 4.0) / 4.0))
        grid = 2.0 * np.pi * np.arange(ng) / ng
        W = raceway_weights(mesh.nodes, race_nodes, areas, raceway, grid)
        phi = res.modes.reshape(-1, 3, res.modes.shape[1])[race_nodes]  # (n_race, 3, m)
        A = (W @ phi.reshape(race_nodes.size, -1)).reshape(ng, 3, -1)
        c, s = np.cos(grid)[:, None], np.sin(grid)[:, None]
        table = np.stack([c * A[:, 0] + s * A[:, 1], -s * A[:, 0] + c * A[:, 1], A[:, 2]], axis=1)
    stress_modes = None
    if stress:
        from flexrv.fem.stress import nodal_stress

        stress_modes = nodal_stress(mesh.nodes, mesh.tets, res.modes, material["E"], material["nu"])
    t3 = time.perf_counter()
    info = {
        "mesh_path": str(mesh_result.npz_path),
        "mesh_key": mesh_result.key,
        "material": material,
        "settings": settings,
        "n_nodes": mesh.n_nodes,
        "n_dof": 3 * mesh.n_nodes,
        "n_interface_modes": res.n_interface,
        "n_eig": res.n_eig,
        "n_raceway_modes": res.n_raceway,
        "fixed_interface_hz": res.fixed_interface_hz.tolist(),
        "t_assemble_s": t1 - t0,
        "t_reduce_s": t2 - t1,
        "t_table_stress_s": t3 - t2,
    }
    body = ReducedBody(
        part, res.modes, res.omega2, mesh.nodes, mesh.tris, node_sets, raceway, table, info, path, stress_modes
    )
    if cache:
        with atomic_path(path) as tmp:
            body.save(tmp)
    return body


def reduce_part(
    reducer,
    part: str,
    size: float | None = None,
    n_eig: int = 20,
    n_harmonics: int | None = None,
    load_width: float | None = None,
    stress: bool = False,
    cache: bool = True,
) -> ReducedBody:
    """Mesh (cached) and reduce (cached) a part of a reducer.

    Rings get raceway-load modes (``n_harmonics`` K, patch width ``load_width`` b
    [m], defaults in :func:`raceway_spec_for`); the crankshaft and the disc get
    HCB modes of their interfaces only.
    """
    from flexrv.meshing import build_mesh, spec_for

    mres = build_mesh(reducer, part, size, cache=cache)
    rw = None
    if part in ("outer_ring", "inner_ring"):
        rw = raceway_spec_for(spec_for(reducer, part), load_width, n_harmonics)
    return build_reduced_body(mres, material_dict(reducer, part), n_eig=n_eig, raceway=rw, stress=stress, cache=cache)


@dataclass
class PartModes:
    """Free-free and constrained (interfaces clamped) modes of a part's full FE model."""

    part: str
    mesh: object  # MeshData
    free_hz: np.ndarray
    free_modes: np.ndarray
    constrained_hz: np.ndarray
    constrained_modes: np.ndarray
    interfaces: list


def part_modes(reducer, part: str, n: int = 10, size: float | None = None, constrained: bool = True) -> PartModes:
    """Lowest ``n`` elastic free-free modes (6 rigid-body modes dropped) and the
    lowest ``n`` modes with the part's interfaces clamped (rings: fit surface;
    crankshaft: support journals; disc: crank holes), from the full FE model."""
    from flexrv.fem.modal import eigenmodes
    from flexrv.meshing import build_mesh

    if not 1 <= int(n) <= 200:
        raise InputError(f"n = {n!r} modes must be in [1, 200]")
    mres = build_mesh(reducer, part, size)
    mesh = mres.data
    fe = _assemble(mesh, material_dict(reducer, part))
    f, v = eigenmodes(fe.K, fe.M, int(n) + 6)
    groups = interface_groups(part, mesh.group_names)
    fc, vc = np.zeros(0), np.zeros((fe.n_dof, 0))
    if constrained:
        fixed = np.unique(np.concatenate([mesh.node_set(g) for g in groups]))
        fc, vc = eigenmodes(fe.K, fe.M, int(n), fixed_nodes=fixed)
    return PartModes(part, mesh, f[6:], v[:, 6:], fc, vc, groups)
