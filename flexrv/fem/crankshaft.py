"""Crankshaft compliance from the FE model (gmsh Tet10 mesh, scikit-fem P2).

The crank's torque path in an RV reducer runs from the planet gear on the gear
seat, through support journal A, into the two eccentrics that drive the cycloid
discs through the needle bearings. :func:`crank_compliance` condenses the FE
crankshaft (Guyan, :func:`flexrv.fem.reduction.interface_stiffness`) onto rigid
(RBE2) interfaces and returns:

* the **torsional stiffness** k_t of the gear seat against the eccentrics (both
  eccentric journals held together by the discs; the support journals free — a
  rolling bearing carries no torque), the quantity that shows in TE;
* the **lateral stiffness** k_l of the gear seat against the two support journals
  (the overhung gear seat bending under the gear mesh force);
* the lowest eigenfrequency of the shaft with gear seat, eccentrics and supports
  clamped — the frequency below which a static (Guyan) condensation of the shaft
  is exact enough (its inertia lumped onto the two members of
  :mod:`flexrv.model.flexible_crank`).

:func:`crank_bending_compliance` condenses the crank onto the **lateral DOF of
its eccentrics relative to its support journals** (the bending of the shaft
between them under the needle forces) with distributing (area-weighted mean)
interfaces, since rigid journal surfaces would stiffen the short, contiguous
segments of a crank; it verifies the Timoshenko stepped-shaft law
(:func:`flexrv.analysis.torsional.crank_bending`) that the models put in series
with the crank-support bearings (:mod:`flexrv.contact.tapered_roller`): rv40e
+0.6 %, rv221 +4.7 % (tests/test_fem_crank_bending.py).

The torsion/lateral results are cached as JSON under :func:`flexrv.cache.cache_dir` keyed by the mesh key, the
material and the library versions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.cache import cache_dir, cached_dataclass, content_hash, library_versions

FORMAT_VERSION = 1


@dataclass(frozen=True)
class CrankCompliance:
    """Condensed crankshaft stiffness (SI)."""

    torsional: float  #: k_t gear seat vs eccentrics [N m/rad]
    lateral_x: float  #: gear seat vs supports, along x (eccentric direction) [N/m]
    lateral_y: float  #: ... along y [N/m]
    lowest_clamped_hz: float  #: lowest eigenfrequency, all interfaces clamped [Hz]
    n_nodes: int
    mesh_key: str

    @property
    def lateral(self) -> float:
        """Mean lateral stiffness [N/m] (the anisotropy is stated in the docstring of
        :mod:`flexrv.model.flexible_crank`)."""
        return 0.5 * (self.lateral_x + self.lateral_y)


def _disjoint(*sets):
    """Node sets with nodes shared with an earlier set removed (adjacent segments
    share their edge circle)."""
    out, seen = [], np.zeros(0, dtype=np.int64)
    for s in sets:
        s = np.setdiff1d(np.asarray(s, dtype=np.int64), seen)
        out.append(s)
        seen = np.union1d(seen, s)
    return out


def seat_compliance(K, nodes, seat, held) -> np.ndarray:
    """6x6 compliance [m/N, rad/(N m)] of the ``seat`` interface with the ``held``
    interfaces clamped (Guyan condensation onto [seat, held...])."""
    from flexrv.fem.reduction import interface_stiffness

    kc = interface_stiffness(K, nodes, [seat, *held])
    return np.linalg.inv(kc[:6, :6])


def crank_compliance(reducer, size: float | None = None, cache: bool = True) -> CrankCompliance:
    """Torsional and lateral stiffness of a design's crankshaft (see module doc)."""
    from flexrv.fem.body import _assemble, material_dict
    from flexrv.fem.modal import eigenmodes
    from flexrv.meshing import build_mesh

    mres = build_mesh(reducer, "crankshaft", size, cache=cache)
    mat = material_dict(reducer, "crankshaft")
    key = content_hash(mres.key, mat, FORMAT_VERSION, library_versions("scikit-fem", "scipy", "numpy"))
    path = cache_dir() / f"crankshaft-{key}.compliance.json"

    def _build() -> CrankCompliance:
        d = mres.data
        fe = _assemble(d, mat)
        seat, ecc1, ecc2, sup_a, sup_b = (
            d.node_set(g) for g in ("gear_seat", "eccentric_1", "eccentric_2", "support_a", "support_b")
        )
        seat_t, ecc = _disjoint(seat, np.union1d(ecc1, ecc2))
        k_t = 1.0 / seat_compliance(fe.K, d.nodes, seat_t, [ecc])[5, 5]
        seat_l, a, b = _disjoint(seat, sup_a, sup_b)
        c_l = seat_compliance(fe.K, d.nodes, seat_l, [a, b])
        fixed = np.unique(np.concatenate([seat, ecc1, ecc2, sup_a, sup_b]))
        f_hz, _ = eigenmodes(fe.K, fe.M, 1, fixed_nodes=fixed)
        out = CrankCompliance(
            torsional=float(k_t),
            lateral_x=float(1.0 / c_l[0, 0]),
            lateral_y=float(1.0 / c_l[1, 1]),
            lowest_clamped_hz=float(f_hz[0]),
            n_nodes=int(d.n_nodes),
            mesh_key=mres.key,
        )
        return out

    return cached_dataclass(path, key, CrankCompliance, _build, enabled=cache)


@dataclass(frozen=True)
class CrankBendingFE:
    """FE bending compliance of the crankshaft (SI): ``compliance`` (2, 2) [m/N],
    C_ij = mean lateral displacement of eccentric i under a unit lateral force on
    eccentric j, relative to the support journals (mean of the x and y directions;
    ``compliance_x``, ``compliance_y`` each); ``k_symmetric`` = 4 / sum C_ij, the
    crank-centre stiffness of :class:`flexrv.analysis.torsional.CrankBending`."""

    compliance: np.ndarray
    compliance_x: np.ndarray
    compliance_y: np.ndarray
    k_symmetric: float
    n_nodes: int


def _area_weights(mesh, group: str) -> tuple[np.ndarray, np.ndarray]:
    """(node indices, area weights summing to 1) of a surface group (Tri6 nodal areas)."""
    from flexrv.fem.reduction import nodal_areas

    tris = mesh.faces(group)
    a = nodal_areas(mesh.nodes, tris)
    nodes = np.unique(tris)
    return nodes, a[nodes] / a[nodes].sum()


def bending_compliance_of_mesh(mesh, youngs_modulus: float, poisson_ratio: float) -> CrankBendingFE:
    """Condense a meshed crankshaft (groups ``support_a``, ``eccentric_1``,
    ``eccentric_2``, ``support_b``) onto the lateral DOF of its eccentrics
    relative to its supports, with distributing (RBE3-type, area-weighted mean)
    interfaces instead of the rigid (RBE2) ones of :func:`crank_compliance` (a rigid
    journal surface would stiffen the short, contiguous segments of a crank):

    * supports: simple supports, the area-weighted mean displacement of support A
      (x, y, z) and of support B (x, y) and the mean rotation of A about the shaft
      axis are held (Lagrange multipliers; the six rigid-body modes removed, the
      journals free to tilt, as a single rolling bearing allows);
    * loads: a unit lateral force spread over eccentric j's lateral surface in
      proportion to the nodal areas (uniform traction with that resultant);
    * response: the area-weighted mean lateral displacement of eccentric i.

    Full sparse solve of the saddle-point system [[K, G^T], [G, 0]] (Zienkiewicz &
    Taylor vol. 1, ch. 2 and 3), per direction x, y."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    from flexrv.fem.assembly import assemble

    fe = assemble(mesh.nodes, mesh.tets, youngs_modulus, poisson_ratio, 1.0)
    n_dof = fe.K.shape[0]
    sa, wa = _area_weights(mesh, "support_a")
    sb, wb = _area_weights(mesh, "support_b")
    ecc = [_area_weights(mesh, g) for g in ("eccentric_1", "eccentric_2")]
    rows, cols, vals = [], [], []
    for r, (nodes, w, comp) in enumerate([(sa, wa, 0), (sa, wa, 1), (sa, wa, 2), (sb, wb, 0), (sb, wb, 1)]):
        rows += [r] * len(nodes)
        cols += list(3 * nodes + comp)
        vals += list(w)
    # mean rotation of support A about z: sum w (x u_y - y u_x) / (x^2 + y^2), about its centroid
    p = mesh.nodes[sa] - (wa[:, None] * mesh.nodes[sa]).sum(axis=0)
    r2 = p[:, 0] ** 2 + p[:, 1] ** 2
    rows += [5] * (2 * len(sa))
    cols += list(3 * sa + 1) + list(3 * sa)
    vals += list(wa * p[:, 0] / r2) + list(-wa * p[:, 1] / r2)
    g = sp.csr_matrix((vals, (rows, cols)), shape=(6, n_dof))
    a = sp.bmat([[fe.K, g.T], [g, None]], format="csc")
    lu = splu(a)
    out = []
    for comp in (0, 1):
        c = np.zeros((2, 2))
        for j, (nodes, w) in enumerate(ecc):
            rhs = np.zeros(n_dof + 6)
            rhs[3 * nodes + comp] = w
            u = lu.solve(rhs)[:n_dof]
            for i, (ni, wi) in enumerate(ecc):
                c[i, j] = float(wi @ u[3 * ni + comp])
        out.append(0.5 * (c + c.T))
    cm = 0.5 * (out[0] + out[1])
    return CrankBendingFE(
        compliance=cm,
        compliance_x=out[0],
        compliance_y=out[1],
        k_symmetric=float(4.0 / cm.sum()),
        n_nodes=int(mesh.n_nodes),
    )


def crank_bending_compliance(reducer, size: float | None = None, cache: bool = True) -> CrankBendingFE:
    """FE bending compliance of a design's crankshaft (:func:`bending_compliance_of_mesh`
    on the mesh of :func:`flexrv.meshing.build_mesh`, the crankshaft's material); the
    check of the Timoshenko law :func:`flexrv.analysis.torsional.crank_bending` that
    the models use."""
    from flexrv.fem.body import material_dict
    from flexrv.meshing import build_mesh

    mres = build_mesh(reducer, "crankshaft", size, cache=cache)
    mat = material_dict(reducer, "crankshaft")
    return bending_compliance_of_mesh(mres.data, mat["E"], mat["nu"])
