"""Linear-elastic P2 stiffness and mass matrices of a Tet10 mesh.

Choice of assembler: the stiffness, which every static condensation needs, is
assembled here (:func:`p2_stiffness`), vectorised over the elements straight into
Exudyn's node-wise ``x0 y0 z0 x1 y1 z1 ...`` DOF order of the mesh nodes, with
scikit-fem's P2 element and quadrature rule; it equals scikit-fem's own assembly
of the same bilinear form to round-off (tests/test_fem_assembly.py) at about a
third of its CPU time (docs/benchmarks.md). The consistent
mass (an 11-point rule, needed by the modal reductions only) is assembled by
scikit-fem's isoparametric P2 (``MeshTet2`` + ``ElementVector(ElementTetP2)``),
whose DOF order (vertex DOFs, then edge DOFs, components interleaved per entity)
is permuted to the node-wise order. ``exudyn.FEM`` has no assembler for Tet10:
its ``FEMinterface`` imports K and M (Abaqus/Ansys files, or NGsolve), and its
``Tet4`` class only serves stress post-processing; NGsolve is not installed and
would add a heavy dependency. Hence flexrv and scikit-fem assemble, Exudyn reduces.

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
    basis : the scikit-fem vector P2 basis of the mass matrix (None without M);
    perm : perm[i] = scikit-fem DOF of Exudyn DOF i (None without M).
    E, nu, rho : material [Pa], [-], [kg/m^3].
    """

    nodes: np.ndarray
    K: sp.csr_matrix
    M: sp.csr_matrix | None
    basis: object | None
    perm: np.ndarray | None
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


def _p2_reference_gradients() -> tuple[np.ndarray, np.ndarray]:
    """Quadrature weights (q,) and reference-tetrahedron gradients (q, 10, 3) of the ten
    P2 shape functions (VTK Tet10 order: vertices, then edges 01, 12, 02, 03, 13, 23)
    at the points of scikit-fem's order-2 rule (its 4-point rule and its
    ``ElementTetP2`` shape functions: the same element as :func:`skfem_basis`)."""
    import skfem
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTet

    X, w = get_quadrature(RefTet, 2)
    elem = skfem.ElementTetP2()
    dN = np.stack([np.asarray(elem.lbasis(X, i)[1]).T for i in range(10)], axis=1)
    return np.asarray(w), dN


def p2_stiffness(nodes: np.ndarray, tets: np.ndarray, lam: float, mu: float, chunk: int = 4096) -> sp.csr_matrix:
    """Linear-elastic stiffness (3N x 3N, node-wise DOFs x0 y0 z0 x1 ...) of a Tet10 mesh
    with the isoparametric P2 element and scikit-fem's order-2 rule (the element and
    rule of :func:`skfem_basis`; tests/test_fem_assembly.py checks the two against each
    other), assembled directly in node-wise order.

    Per element, with the physical gradients G_ia = dN_i/dx_a and the weights
    w_q |det J_q| at the quadrature points:
    K_(ia)(jb) = sum_q w_q |J_q| [lam G_ia G_jb + mu (G_ib G_ja + delta_ab G_i . G_j)],
    the bilinear form lam tr(eps_u) tr(eps_v) + 2 mu eps_u : eps_v written out."""
    w, dN = _p2_reference_gradients()
    nodes = np.asarray(nodes, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)
    n_el = tets.shape[0]
    data = np.empty((n_el, 30, 30))
    for a in range(0, n_el, chunk):
        X = nodes[tets[a : a + chunk]]  # (e, 10, 3)
        J = np.einsum("eia,qib->eqab", X, dN)  # dx_a / dxi_b
        det = np.linalg.det(J)
        G = np.einsum("qib,eqba->eqia", dN, np.linalg.inv(J)).reshape(X.shape[0], w.size, 30)
        Gw = G * (w[None, :] * np.abs(det))[:, :, None]
        T = np.matmul(Gw.transpose(0, 2, 1), G).reshape(-1, 10, 3, 10, 3)  # sum_q w G_ia G_jb
        S = np.einsum("eiaja->eij", T)  # sum_q w G_i . G_j
        Ke = lam * T + mu * T.transpose(0, 1, 4, 3, 2)
        Ke += mu * S[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        data[a : a + chunk] = Ke.reshape(-1, 30, 30)
    dofs = (3 * tets[:, :, None] + np.arange(3)).reshape(n_el, 30).astype(np.int32)
    rows = np.broadcast_to(dofs[:, :, None], (n_el, 30, 30)).ravel()
    cols = np.broadcast_to(dofs[:, None, :], (n_el, 30, 30)).ravel()
    n = 3 * nodes.shape[0]
    return sp.coo_matrix((data.ravel(), (rows, cols)), shape=(n, n)).tocsr()


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

    if density <= 0:
        raise InputError(f"density = {density!r} kg/m^3 must be > 0")
    lam, mu = lame(youngs_modulus, poisson_ratio)
    K = p2_stiffness(nodes, tets, lam, mu)
    M = basis = perm = None
    if mass:

        @skfem.BilinearForm
        def mass_form(u, v, w):
            return density * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])

        basis = skfem_basis(nodes, tets, intorder=4)
        perm = dof_permutation(basis, nodes)
        M = skfem.asm(mass_form, basis).tocsr()[perm][:, perm].tocsr()
    return FEModel(nodes, K, M, basis, perm, youngs_modulus, poisson_ratio, density)
