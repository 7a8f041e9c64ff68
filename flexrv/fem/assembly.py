"""Linear-elastic P2 stiffness and mass matrices of a Tet10 mesh (scikit-fem).

Choice of assembler: scikit-fem assembles the isoparametric P2 (``MeshTet2`` +
``ElementVector(ElementTetP2)``) stiffness and consistent mass fully vectorised, in
seconds for a 100k-DOF ring (``benchmarks/bench_cms.py``). ``exudyn.FEM`` has no assembler for Tet10: its
``FEMinterface`` imports K and M (Abaqus/Ansys files, or NGsolve), and its
``Tet4`` class only serves stress post-processing; NGsolve is not installed and
would add a heavy dependency. Hence scikit-fem assembles, Exudyn reduces.

The DOF order of scikit-fem (vertex DOFs, then edge DOFs, components
interleaved per entity) is permuted to Exudyn's node-wise ``x0 y0 z0 x1 y1 z1 ...``
order of the mesh nodes (``FEMinterface.nodes['Position']``).

Linear elasticity: sigma = lambda tr(eps) I + 2 mu eps with
lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)) (any continuum
mechanics text, e.g. Zienkiewicz & Taylor, *The Finite Element Method*, vol. 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexrv.errors import InputError


def lame(youngs_modulus: float, poisson_ratio: float) -> tuple[float, float]:
    """Lamé parameters (lambda, mu) [Pa] from E [Pa] and nu [-]."""
    if not (youngs_modulus > 0 and -1.0 < poisson_ratio < 0.5):
        raise InputError(f"material: E = {youngs_modulus!r} Pa must be > 0 and nu = {poisson_ratio!r} in (-1, 0.5)")
    lam = youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio))
    mu = youngs_modulus / (2.0 * (1.0 + poisson_ratio))
    return lam, mu


@dataclass
class FEModel:
    """Assembled FE model in Exudyn node-wise DOF order.

    Attributes
    ----------
    nodes : (N, 3) [m]; K, M : CSR (3N x 3N) [N/m], [kg] (M None for a static-only
    model, ``assemble(..., mass=False)``);
    basis : the scikit-fem vector P2 basis (for stress recovery);
    perm : perm[i] = scikit-fem DOF of Exudyn DOF i.
    E, nu, rho : material [Pa], [-], [kg/m^3].
    """

    nodes: np.ndarray
    K: sp.csr_matrix
    M: sp.csr_matrix | None
    basis: object
    perm: np.ndarray
    E: float
    nu: float
    rho: float

    @property
    def n_dof(self) -> int:
        return int(self.K.shape[0])


def skfem_basis(nodes: np.ndarray, tets: np.ndarray, intorder: int = 2):
    """scikit-fem isoparametric P2 vector basis of a Tet10 mesh (VTK order).

    ``intorder`` 2 (4-point rule) integrates the P2 stiffness exactly on straight
    tetrahedra (grad u . grad v is quadratic); the mass matrix needs 4 (11 points).
    Measured on 100k DOF: stiffness 2.5 s with order 2 vs 14 s with order 4, max
    entry difference 0.17 % (curved boundary elements only).
    """
    import meshio
    import skfem
    from skfem.io.meshio import from_meshio

    mesh = from_meshio(meshio.Mesh(nodes, [("tetra10", tets)]))
    return skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP2()), intorder=intorder)


def dof_permutation(basis, nodes: np.ndarray) -> np.ndarray:
    """perm (3N,) with perm[3 i + c] = scikit-fem DOF of component c of node i.

    scikit-fem DOF locations are matched to the mesh nodes with a k-d tree
    (exact up to round-off; raises if any node is unmatched).
    """
    from scipy.spatial import cKDTree

    dofs = np.concatenate([basis.nodal_dofs, basis.edge_dofs], axis=1)  # (3, n_entities)
    locs = basis.doflocs[:, dofs[0]].T
    dist, idx = cKDTree(locs).query(nodes)
    scale = np.ptp(nodes, axis=0).max()
    if dofs.shape[1] != nodes.shape[0] or dist.max() > 1e-9 * scale or np.unique(idx).size != idx.size:
        raise InputError("mesh nodes do not match the P2 DOF locations (not a valid Tet10 mesh?)")
    return dofs[:, idx].T.reshape(-1)


def assemble(
    nodes: np.ndarray, tets: np.ndarray, youngs_modulus: float, poisson_ratio: float, density: float, mass: bool = True
) -> FEModel:
    """Assemble K and M (consistent mass) of a Tet10 mesh, Exudyn DOF order.

    Parameters
    ----------
    nodes : (N, 3) [m]; tets : (E, 10) VTK/Abaqus C3D10 order.
    youngs_modulus [Pa], poisson_ratio [-], density [kg/m^3].
    mass : also assemble M. The static condensations (carrier, disc, crank
        compliance) need K only; the mass matrix with its 11-point rule was about
        half the assembly time (measured: rv40e disc, 66.7k nodes).
    """
    import skfem
    from skfem.helpers import ddot, sym_grad, trace

    if density <= 0:
        raise InputError(f"density = {density!r} kg/m^3 must be > 0")
    lam, mu = lame(youngs_modulus, poisson_ratio)
    basis = skfem_basis(nodes, tets, intorder=2)

    @skfem.BilinearForm
    def stiffness(u, v, w):
        eu, ev = sym_grad(u), sym_grad(v)
        return lam * trace(eu) * trace(ev) + 2.0 * mu * ddot(eu, ev)

    @skfem.BilinearForm
    def mass_form(u, v, w):
        return density * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])

    K = skfem.asm(stiffness, basis)
    perm = dof_permutation(basis, nodes)
    K = K.tocsr()[perm][:, perm].tocsr()
    M = None
    if mass:
        M = skfem.asm(mass_form, skfem.Basis(basis.mesh, basis.elem, intorder=4))
        M = M.tocsr()[perm][:, perm].tocsr()
    return FEModel(nodes, K, M, basis, perm, youngs_modulus, poisson_ratio, density)
