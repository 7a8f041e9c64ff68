"""Stress recovery (nodal-averaged Tet10 stress modes)."""

import numpy as np
import pytest

from flexrv.fem.stress import nodal_stress, von_mises
from flexrv.meshing.mesh import generate_mesh
from flexrv.meshing.parts import PlainRingSpec

E, NU = 2.1e11, 0.3


@pytest.fixture(scope="module")
def mesh(tmp_path_factory):
    import os

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    m = generate_mesh(PlainRingSpec(0.09, 0.1, 0.02), "plain_ring", 0.012).data
    del os.environ["FLEXRV_CACHE"]
    return m


def test_patch_test_linear_field(mesh):
    """u = G x (constant strain, in the P2 space): every node gets Hooke's law
    sigma = lambda tr(eps) I + 2 mu eps exactly (1e-9 relative), and von Mises of
    uniaxial stress equals |sigma_xx|."""
    rng = np.random.default_rng(0)
    G = rng.normal(scale=1e-4, size=(3, 3))
    u = mesh.nodes @ G.T
    S = nodal_stress(mesh.nodes, mesh.tets, u.reshape(-1, 1), E, NU)
    eps = 0.5 * (G + G.T)
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    sig = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    ref = np.array([sig[0, 0], sig[1, 1], sig[2, 2], sig[1, 2], sig[0, 2], sig[0, 1]])
    assert np.allclose(S, ref[None, :], rtol=0, atol=1e-9 * np.abs(ref).max())
    assert np.isclose(von_mises(np.array([-3.0, 0, 0, 0, 0, 0])), 3.0)
