"""Tet10 meshes of the reducer parts: generation (gmsh), data container, cache.

A mesh is generated once per (part geometry, mesh size, gmsh/meshio versions)
and stored under :func:`flexrv.cache.cache_dir` as three files written atomically:
``<part>-<key>.msh`` (gmsh), ``<part>-<key>.vtu`` (meshio/ParaView) and
``<part>-<key>.npz`` (the arrays the FE layer reads; written last, so its presence
marks a complete cache entry).

Node order of the 10-node tetrahedra is VTK's ``tetra10`` = Abaqus C3D10 order
(corners 0-3, then mid-nodes of edges 01, 12, 20, 03, 13, 23); gmsh's own order
swaps the last two (edges 32 and 31), which :func:`_extract` converts.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_path, cache_dir, cached_entry, content_hash, library_versions
from flexrv.errors import InputError
from flexrv.meshing import parts as P

#: Version of the mesh file layout; part of every cache key.
MESH_FORMAT_VERSION = 1

#: gmsh element type ids
_TET10, _TRI6 = 11, 9
#: gmsh -> VTK/Abaqus tetra10 node permutation
_GMSH_TO_VTK_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])


@dataclass
class MeshData:
    """A second-order tetrahedral mesh with named boundary groups (SI units).

    Attributes
    ----------
    nodes : (N, 3) node coordinates [m].
    tets : (E, 10) Tet10 connectivity, VTK/Abaqus C3D10 order.
    tris : (F, 6) boundary Tri6 faces (corners, then mid-nodes 01, 12, 20).
    tri_group : (F,) index into ``group_names`` of each boundary face.
    group_names : names of the physical surface groups.
    part : part name; ``spec`` its geometry dict; ``size`` the global mesh size [m].
    info : extra metadata (local size, profile deviation, timing).
    """

    nodes: np.ndarray
    tets: np.ndarray
    tris: np.ndarray
    tri_group: np.ndarray
    group_names: tuple[str, ...]
    part: str
    spec: dict
    size: float
    info: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_elements(self) -> int:
        return int(self.tets.shape[0])

    def faces(self, *names: str) -> np.ndarray:
        """Tri6 faces of the named groups, shape (F, 6)."""
        bad = [n for n in names if n not in self.group_names]
        if bad:
            raise InputError(f"surface group(s) {bad} not in mesh of {self.part}; available: {list(self.group_names)}")
        ids = [self.group_names.index(n) for n in names]
        return self.tris[np.isin(self.tri_group, ids)]

    def node_set(self, *names: str) -> np.ndarray:
        """Sorted unique node indices on the named surface groups."""
        return np.unique(self.faces(*names))

    def save_npz(self, path: Path) -> None:
        import json

        np.savez(
            path,
            nodes=self.nodes,
            tets=self.tets,
            tris=self.tris,
            tri_group=self.tri_group,
            group_names=np.array(self.group_names),
            part=self.part,
            size=self.size,
            spec=json.dumps(self.spec),
            info=json.dumps(self.info),
            version=MESH_FORMAT_VERSION,
        )

    @classmethod
    def load_npz(cls, path: str | os.PathLike) -> "MeshData":
        import json

        with np.load(path, allow_pickle=False) as z:
            return cls(
                nodes=z["nodes"],
                tets=z["tets"],
                tris=z["tris"],
                tri_group=z["tri_group"],
                group_names=tuple(str(s) for s in z["group_names"]),
                part=str(z["part"]),
                size=float(z["size"]),
                spec=json.loads(str(z["spec"])),
                info=json.loads(str(z["info"])),
            )

    def to_meshio(self, point_data: dict | None = None):
        """meshio.Mesh with the tetra10 cells (and optional point data)."""
        import meshio

        return meshio.Mesh(self.nodes, [("tetra10", self.tets)], point_data=point_data or {})


@dataclass
class MeshResult:
    """Paths and data of a (cached) mesh."""

    data: MeshData
    msh_path: Path
    vtu_path: Path
    npz_path: Path
    cached: bool
    key: str


def default_max_nodes() -> int:
    """Node limit from the physical memory: ~25 kB per Tet10 node covers the P2
    stiffness/mass matrices and a sparse LU factorisation (measured ~15-20 kB)."""
    try:
        mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        mem = 8 * 2**30
    return int(mem / 25e3)


def _apply_size_field(gmsh, spec, groups: dict, size: float, local: float, edge: float | None = None) -> None:
    """Global size ``size``; ``local`` on the raceway (rings), the profile (disc) or
    the pillars (carrier); ``edge`` (carrier only, None: off) at the pillar roots,
    the re-entrant edges where the pillars meet the plates, graded linearly to
    ``size`` (:meth:`flexrv.meshing.parts.CarrierSpec.root_size`)."""
    opt = gmsh.option
    opt.setNumber("Mesh.MeshSizeMax", size)
    opt.setNumber("Mesh.MeshSizeMin", 0.2 * min(local, edge or local))
    opt.setNumber("Mesh.MeshSizeFromPoints", 0)
    opt.setNumber("Mesh.MeshSizeFromCurvature", 0)
    opt.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    fld = gmsh.model.mesh.field
    fields = []
    if edge is not None and edge < size and isinstance(spec, P.CarrierSpec):
        curves = {t for f in groups["pillar"] for _, t in gmsh.model.getBoundary([(2, f)], oriented=False)}
        droot = fld.add("Distance")
        fld.setNumbers(droot, "CurvesList", sorted(curves))
        fld.setNumber(droot, "Sampling", 200)
        troot = fld.add("Threshold")
        fld.setNumber(troot, "InField", droot)
        fld.setNumber(troot, "SizeMin", edge)
        fld.setNumber(troot, "SizeMax", size)
        fld.setNumber(troot, "DistMin", 0.0)
        fld.setNumber(troot, "DistMax", (size - edge) / P.CarrierSpec.ROOT_GRADING)
        fields.append(troot)
    if local >= size:
        if fields:
            fld.setAsBackgroundMesh(fields[0])
        return
    dist = fld.add("Distance")
    if isinstance(spec, P.RingSpec):
        fld.setNumbers(dist, "SurfacesList", groups["raceway"])
        reach = spec.groove_radius
    elif isinstance(spec, P.CarrierSpec):
        fld.setNumbers(dist, "SurfacesList", groups["pillar"])
        reach = spec.pillar_radius
    else:
        curves = {t for f in groups["profile"] for _, t in gmsh.model.getBoundary([(2, f)], oriented=False)}
        fld.setNumbers(dist, "CurvesList", sorted(curves))
        fld.setNumber(dist, "Sampling", 200)
        reach = 2.0 * spec.eccentricity + spec.tooth_pitch / 2.0
    thr = fld.add("Threshold")
    fld.setNumber(thr, "InField", dist)
    fld.setNumber(thr, "SizeMin", local)
    fld.setNumber(thr, "SizeMax", size)
    fld.setNumber(thr, "DistMin", 0.25 * reach)
    fld.setNumber(thr, "DistMax", 1.5 * reach)
    fields.append(thr)
    if len(fields) > 1:
        both = fld.add("Min")
        fld.setNumbers(both, "FieldsList", fields)
        fld.setAsBackgroundMesh(both)
    else:
        fld.setAsBackgroundMesh(thr)


def _extract(gmsh, groups: dict[str, list[int]]) -> tuple:
    """Nodes, Tet10 (VTK order), boundary Tri6 and their group index, 0-based."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3)
    lookup = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    _, etags, enodes = gmsh.model.mesh.getElements(3)
    tet = np.asarray(enodes[0], dtype=np.int64).reshape(-1, 10)[:, _GMSH_TO_VTK_TET10]
    used = np.unique(tet)
    lookup[used] = np.arange(used.size)
    nodes = np.empty((used.size, 3))
    order = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    order[tags.astype(np.int64)] = np.arange(tags.size)
    nodes[:] = coords[order[used]]
    tris, gid = [], []
    names = tuple(groups)
    for k, name in enumerate(names):
        for face in groups[name]:
            types, _, fnodes = gmsh.model.mesh.getElements(2, face)
            for t, fn in zip(types, fnodes):
                if t == _TRI6:
                    tri = lookup[np.asarray(fn, dtype=np.int64).reshape(-1, 6)]
                    tris.append(tri)
                    gid.append(np.full(tri.shape[0], k, dtype=np.int32))
    return nodes, lookup[tet], np.concatenate(tris), np.concatenate(gid), names


def mesh_key(spec, size: float, local: float, edge: float | None = None) -> str:
    """Cache key of a mesh: geometry spec, sizes, format version, library versions
    (the edge size only where a part has one, so the other parts keep their keys)."""
    extra = () if edge is None else (("edge", edge),)
    return content_hash(P.spec_dict(spec), size, local, *extra, MESH_FORMAT_VERSION, library_versions("gmsh", "meshio"))


def generate_mesh(
    spec,
    part: str,
    size: float | None = None,
    *,
    local_size: float | None = None,
    edge_size: float | None = None,
    max_nodes: int | None = None,
    cache: bool = True,
    threads: int = 1,
) -> MeshResult:
    """Mesh a part spec with Tet10 elements and cache the result.

    Parameters
    ----------
    spec : a ``*Spec`` of :mod:`flexrv.meshing.parts` (SI).
    part : part name (file prefix).
    size : global mesh size [m]; the spec's ``default_size()`` if None.
    local_size : mesh size on the raceway / tooth flanks [m] (default from the spec:
        a third of the groove radius, an eighth of the tooth pitch); must be <= size.
    max_nodes : node-count limit (memory guard); :func:`default_max_nodes` if None.
    cache : reuse/write the cached files.
    threads : gmsh meshing threads.

    Raises
    ------
    InputError
        Size too coarse/fine, self-intersecting geometry, meshing failure.
    """
    from flexrv.meshing.session import gmsh_session

    size = float(spec.default_size() if size is None else size)
    chk = P.check_size(spec, size, max_nodes or default_max_nodes())
    if local_size is not None:
        if not (0 < local_size <= size):
            raise InputError(f"local mesh size = {local_size!r} m must be in (0, size = {size:g} m]")
        chk["local_size"] = float(local_size)
    if edge_size is not None:
        if not (0 < edge_size <= size):
            raise InputError(f"edge mesh size = {edge_size!r} m must be in (0, size = {size:g} m]")
        chk["edge_size"] = float(edge_size)
    edge = chk.get("edge_size")
    key = mesh_key(spec, size, chk["local_size"], edge)
    folder = cache_dir()
    stem = f"{part}-{key}"
    msh, vtu, npz = (folder / f"{stem}{ext}" for ext in (".msh", ".vtu", ".npz"))

    def _build() -> MeshData:
        t0 = time.perf_counter()
        with gmsh_session(stem, threads=threads) as gmsh:
            groups = P.BUILDERS[part](gmsh, spec, size)
            for name, faces in groups.items():
                gmsh.model.addPhysicalGroup(2, faces, name=name)
            vol = gmsh.model.getEntities(3)[0][1]
            gmsh.model.addPhysicalGroup(3, [vol], name=part)
            _apply_size_field(gmsh, spec, groups, size, chk["local_size"], edge)
            gmsh.option.setNumber("Mesh.ElementOrder", 2)
            gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
            gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
            gmsh.option.setNumber("Mesh.Algorithm3D", 10 if threads > 1 else 1)
            t1 = time.perf_counter()
            try:
                gmsh.model.mesh.generate(3)
            except Exception as exc:  # gmsh raises a bare Exception
                raise InputError(f"meshing {part} with size {size * 1e3:.4g} mm failed: {exc}") from None
            t2 = time.perf_counter()
            info = {
                "local_size": chk["local_size"],
                "edge_size": edge,
                "estimated_nodes": chk["estimated_nodes"],
                "t_geometry_s": t1 - t0,
                "t_mesh_s": t2 - t1,
            }
            if isinstance(spec, P.CycloidDiscSpec):
                info["profile_deviation_m"] = P.profile_deviation(gmsh, spec)
            nodes, tets, tris, tri_group, names = _extract(gmsh, groups)
            if tets.shape[0] == 0:
                raise InputError(f"meshing {part} produced no volume elements")
            data = MeshData(nodes, tets, tris, tri_group, names, part, P.spec_dict(spec), size, info)
            gmsh.option.setNumber("Mesh.Binary", 1)
            with atomic_path(msh) as tmp:
                gmsh.write(str(tmp))
        with atomic_path(vtu) as tmp:
            data.to_meshio().write(tmp, file_format="vtu")
        with atomic_path(npz) as tmp:
            data.save_npz(tmp)
        return data

    data, hit = cached_entry([msh, vtu, npz], key, lambda: MeshData.load_npz(npz), _build, enabled=cache)
    return MeshResult(data, msh, vtu, npz, hit, key)


def build_mesh(reducer, part: str, size: float | None = None, **kw) -> MeshResult:
    """Mesh ``part`` (one of :data:`flexrv.meshing.parts.PARTS`) of a reducer.

    ``size`` is the global mesh size [m] (part default if None); see
    :func:`generate_mesh` for the other keywords and the errors raised.
    """
    spec = P.spec_for(reducer, part)
    return generate_mesh(spec, part, size, **kw)
