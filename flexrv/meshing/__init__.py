"""gmsh (OCC) builders of the reducer parts -> cached second-order tet meshes.

Not run as a doctest (gmsh meshing of a part takes seconds to minutes; tests/test_meshing.py
runs it):

>>> from flexrv.design import load                      # doctest: +SKIP
>>> from flexrv.meshing import build_mesh               # doctest: +SKIP
>>> res = build_mesh(load("rv221"), "outer_ring", size=6e-3)   # doctest: +SKIP
>>> res.data.n_nodes, res.msh_path                      # doctest: +SKIP

Only this package imports gmsh.
"""

from flexrv.meshing.mesh import MeshData, MeshResult, build_mesh, generate_mesh, mesh_key
from flexrv.meshing.parts import PARTS, CrankshaftSpec, CycloidDiscSpec, RingSpec, spec_for

__all__ = [
    "MeshData",
    "MeshResult",
    "build_mesh",
    "generate_mesh",
    "mesh_key",
    "PARTS",
    "RingSpec",
    "CrankshaftSpec",
    "CycloidDiscSpec",
    "spec_for",
]
