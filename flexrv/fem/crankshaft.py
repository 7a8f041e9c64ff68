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

Cached as JSON under :func:`flexrv.cache.cache_dir` keyed by the mesh key, the
material and the library versions.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from flexrv.cache import atomic_write_text, cache_dir, cached_entry, content_hash, library_versions

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
        seat, ecc1, ecc2, sup_a, sup_b = (d.node_set(g) for g in ("gear_seat", "eccentric_1", "eccentric_2",
                                                                  "support_a", "support_b"))
        seat_t, ecc = _disjoint(seat, np.union1d(ecc1, ecc2))
        k_t = 1.0 / seat_compliance(fe.K, d.nodes, seat_t, [ecc])[5, 5]
        seat_l, a, b = _disjoint(seat, sup_a, sup_b)
        c_l = seat_compliance(fe.K, d.nodes, seat_l, [a, b])
        fixed = np.unique(np.concatenate([seat, ecc1, ecc2, sup_a, sup_b]))
        f_hz, _ = eigenmodes(fe.K, fe.M, 1, fixed_nodes=fixed)
        out = CrankCompliance(torsional=float(k_t), lateral_x=float(1.0 / c_l[0, 0]), lateral_y=float(1.0 / c_l[1, 1]),
                              lowest_clamped_hz=float(f_hz[0]), n_nodes=int(d.n_nodes), mesh_key=mres.key)
        if cache:
            atomic_write_text(path, json.dumps(asdict(out)))
        return out

    out, _ = cached_entry([path], key, lambda: CrankCompliance(**json.loads(path.read_text())), _build,
                          enabled=cache)
    return out
