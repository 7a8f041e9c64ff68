"""The node-wise P2 stiffness assembly (flexrv.fem.assembly.p2_stiffness) against
scikit-fem's assembly of the same bilinear form (an independent assembler, same element
and rule: agreement to round-off, 1e-13 of the largest entry), and against closed forms:
rigid-body motions carry no force, and the strain energy of a linear displacement field
u = A x on straight-sided elements equals V (lam tr(eps)^2 / 2 + mu eps : eps),
eps = (A + A^T) / 2, V the mesh volume (P2 reproduces linear fields and the order-2
rule integrates the constant integrand exactly), to 1e-12."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.fem.assembly import assemble, dof_permutation, lame, p2_stiffness, skfem_basis
from flexrv.meshing.mesh import generate_mesh
from flexrv.meshing.parts import CrankshaftSpec

E, NU = 2.1e11, 0.3


@pytest.fixture(scope="module")
def mesh(tmp_path_factory):
    """A small stepped shaft (curved Tet10 boundary elements)."""
    import os

    os.environ["FLEXRV_CACHE_DIR"] = str(tmp_path_factory.mktemp("cache"))
    segs = (
        ("gear_seat", 0.010, 0.010, 0.0),
        ("support_a", 0.008, 0.030, 0.0),
        ("eccentric_1", 0.010, 0.010, 0.0),
        ("eccentric_2", 0.009, 0.004, 0.0),
        ("support_b", 0.007, 0.004, 0.0),
    )
    m = generate_mesh(CrankshaftSpec(segments=segs), "crankshaft", 0.004, cache=False).data
    del os.environ["FLEXRV_CACHE_DIR"]
    return m


def test_stiffness_equals_scikit_fem_assembly(mesh):
    import skfem
    from skfem.helpers import ddot, sym_grad, trace

    lam, mu = lame(E, NU)

    @skfem.BilinearForm
    def stiffness(u, v, w):
        eu, ev = sym_grad(u), sym_grad(v)
        return lam * trace(eu) * trace(ev) + 2.0 * mu * ddot(eu, ev)

    basis = skfem_basis(mesh.nodes, mesh.tets, intorder=2)
    perm = dof_permutation(basis, mesh.nodes)
    Kref = skfem.asm(stiffness, basis).tocsr()[perm][:, perm]
    K = p2_stiffness(mesh.nodes, mesh.tets, lam, mu)
    assert abs(K - Kref).max() <= 1e-13 * abs(Kref).max()
    fe = assemble(mesh.nodes, mesh.tets, E, NU, 7800.0, mass=False)
    assert fe.M is None and fe.basis is None and abs(fe.K - K).max() == 0.0


def test_rigid_motions_and_linear_field_energy(mesh):
    """Closed forms on the straight-sided version of the mesh (mid-edge nodes moved to
    the edge midpoints): K r = 0 for the six rigid-body motions, and
    u^T K u / 2 = V (lam tr(eps)^2 / 2 + mu eps : eps) for u = A x."""
    nodes = mesh.nodes.copy()
    tets = mesh.tets
    for k, (i, j) in enumerate([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]):
        nodes[tets[:, 4 + k]] = 0.5 * (nodes[tets[:, i]] + nodes[tets[:, j]])
    lam, mu = lame(E, NU)
    K = p2_stiffness(nodes, tets, lam, mu)
    x = nodes - nodes.mean(axis=0)
    rigid = [np.tile(np.eye(3)[c], (len(x), 1)) for c in range(3)]
    rigid += [np.cross(np.eye(3)[c], x) for c in range(3)]
    A = np.array([[1.0, 0.3, -0.2], [0.1, -0.5, 0.4], [0.25, 0.05, 0.7]]) * 1e-4
    u = (x @ A.T).ravel()
    for r in rigid:
        assert np.abs(K @ r.ravel()).max() <= 1e-11 * abs(K).max() * np.abs(r).max()
    p = nodes[tets[:, :4]]
    volume = np.abs(np.linalg.det(p[:, 1:] - p[:, :1])).sum() / 6.0
    eps = 0.5 * (A + A.T)
    energy = volume * (0.5 * lam * np.trace(eps) ** 2 + mu * np.sum(eps * eps))
    assert 0.5 * u @ (K @ u) == pytest.approx(energy, rel=1e-12)
