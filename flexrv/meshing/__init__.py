"""gmsh (OCC) builders of the reducer parts -> cached second-order tet meshes.

>>> from flexrv.design import load                      # doctest: +SKIP
>>> from flexrv.meshing import build_mesh
>>> res = build_mesh(load("rv221"), "outer_ring", size=6e-3)
>>> res.data.n_nodes, res.msh_path

Only this package imports gmsh.
"""

from flexrv.meshing.mesh import MeshData, MeshResult, build_mesh, generate_mesh, mesh_key
from flexrv.meshing.parts import PARTS, CrankshaftSpec, CycloidDiscSpec, RingSpec, spec_for

__all__ = ["MeshData", "MeshResult", "build_mesh", "generate_mesh", "mesh_key", "PARTS", "RingSpec",
           "CrankshaftSpec", "CycloidDiscSpec", "spec_for"]
