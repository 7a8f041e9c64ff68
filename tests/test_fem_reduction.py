"""Reduced (HCB + Fourier raceway modes) body vs full FE, and in Exudyn.

Reference: the full FE static solution of the same patch-distributed ball load
(ring clamped at its fit), solved with the sparse LU of the interior stiffness.
"""

import numpy as np
import pytest

from flexrv.design import load
from flexrv.fem.body import _assemble, build_reduced_body, material_dict, raceway_spec_for
from flexrv.fem.modal import eigenmodes, factorize, free_dofs
from flexrv.fem.reduction import nodal_areas, raceway_weights
from flexrv.meshing import build_mesh, spec_for

SIZE, LOCAL = 0.015, 0.01  # coarse rv221 outer ring
AZ = np.deg2rad([0.0, 7.3, 100.0])  # 7.3 deg: not on any table grid point
FORCE = 5000.0  # N per ball


@pytest.fixture(scope="module")
def ring(tmp_path_factory):
    import os

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    rv = load("rv221")
    mres = build_mesh(rv, "outer_ring", size=SIZE, local_size=LOCAL)
    mat = material_dict(rv, "outer_ring")
    fe = _assemble(mres.data, mat)
    yield rv, mres, mat, fe
    del os.environ["FLEXRV_CACHE"]


def fe_patch_deflection(rv, mres, fe, az, forces, part="outer_ring"):
    """Full-FE patch-mean raceway displacement (n_az, 3) [m] under patch loads
    ``forces`` (n_az, 3) [N] at azimuths ``az``, ring clamped at its fit."""
    d = mres.data
    rs = raceway_spec_for(spec_for(rv, part), None, 0)
    race = d.node_set("raceway")
    W = raceway_weights(d.nodes, race, nodal_areas(d.nodes, d.faces("raceway")), rs, az).toarray()
    f = np.zeros(fe.n_dof)
    for c in range(3):
        f[3 * race + c] = W.T @ forces[:, c]
    idofs = free_dofs(fe.n_dof, d.node_set("fit"))
    u = np.zeros(fe.n_dof)
    u[idofs] = factorize(fe.K[idofs][:, idofs])(f[idofs])
    return W @ u.reshape(-1, 3)[race]


def reduced_deflection(body, az, forces):
    q = body.raceway_load_vector(az, forces).sum(axis=0) / body.omega2
    return body.raceway_displacement(q, az), q


def test_static_raceway_deflection_converges_with_harmonics(ring):
    """Normal deflection under three simultaneous 5 kN ball loads (one between grid
    points): the reduced error falls monotonically as harmonics are added
    (K = 8, 16, default) and is < 2 % with the default K (c_K/c_0 < 0.2)."""
    rv, mres, mat, fe = ring
    spec = spec_for(rv, "outer_ring")
    body0 = build_reduced_body(mres, mat, n_eig=0, raceway=raceway_spec_for(spec, None, 2), fe=fe, cache=False)
    n = body0.contact_normals(AZ)
    forces = FORCE * n
    ref = np.einsum("ij,ij->i", fe_patch_deflection(rv, mres, fe, AZ, forces), n)
    assert np.all(ref > 1e-7)  # a real, outward deflection of ~um
    errs = []
    for k in (8, 16, None):
        body = build_reduced_body(mres, mat, n_eig=0, raceway=raceway_spec_for(spec, None, k), fe=fe, cache=False)
        u, _ = reduced_deflection(body, AZ, forces)
        errs.append(np.max(np.abs(np.einsum("ij,ij->i", u, n) / ref - 1)))
    assert errs[0] > errs[1] > errs[2], errs
    assert errs[2] < 0.02, errs


def test_lowest_frequencies_match_full_fe(ring):
    """The reduced body's lowest frequencies (fit clamped) equal the full FE
    constrained eigenfrequencies within 1e-6 (the fixed-interface modes are in the
    Ritz basis); the cached body reloads identically."""
    rv, mres, mat, fe = ring
    spec = spec_for(rv, "outer_ring")
    body = build_reduced_body(mres, mat, n_eig=4, raceway=raceway_spec_for(spec, None, 8), fe=fe)
    f_full, _ = eigenmodes(fe.K, fe.M, 4, fixed_nodes=mres.data.node_set("fit"))
    assert np.allclose(body.frequencies_hz[:4], f_full, rtol=1e-6)
    again = build_reduced_body(mres, mat, n_eig=4, raceway=raceway_spec_for(spec, None, 8), fe=fe)
    assert np.array_equal(again.modes, body.modes) and again.path == body.path


def test_exudyn_static_matches_fe(ring):
    """Exudyn: the body as NodeGenericODE2 + ObjectGenericODE2 with the modal ball
    loads as LoadCoordinate, solved by mbs.SolveStatic, reproduces the reduced
    static solution (1e-8) and the full FE deflection within 2 %; the body file is
    cached and reloaded identically."""
    import exudyn as exu
    import exudyn.itemInterface as eii

    rv, mres, mat, fe = ring
    spec = spec_for(rv, "outer_ring")
    body = build_reduced_body(mres, mat, n_eig=0, raceway=raceway_spec_for(spec, None, None), fe=fe)
    again = build_reduced_body(mres, mat, n_eig=0, raceway=raceway_spec_for(spec, None, None), fe=fe)
    assert np.array_equal(again.table, body.table) and again.path == body.path
    n = body.contact_normals(AZ)
    forces = FORCE * n
    Q = body.raceway_load_vector(AZ, forces).sum(axis=0)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node, _ = body.add_modal_body(mbs)
    for i, qi in enumerate(Q):
        mk = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=node, coordinate=i))
        mbs.AddLoad(eii.LoadCoordinate(markerNumber=mk, load=float(qi)))
    mbs.Assemble()
    sset = exu.SimulationSettings()
    sset.staticSolver.newton.relativeTolerance = 1e-12
    assert mbs.SolveStatic(sset)
    q = np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))
    u_red, q_ref = reduced_deflection(body, AZ, forces)
    assert np.allclose(q, q_ref, rtol=1e-8, atol=1e-12 * np.abs(q_ref).max())
    u_exu = body.raceway_displacement(q, AZ)
    ref = np.einsum("ij,ij->i", fe_patch_deflection(rv, mres, fe, AZ, forces), n)
    assert np.all(np.abs(np.einsum("ij,ij->i", u_exu, n) / ref - 1) < 0.02)


def test_load_vector_is_transpose_of_displacement(ring):
    """Virtual work: F . u(q, theta) == Q(theta, F) . q for random q, F, theta."""
    rv, mres, mat, fe = ring
    body = build_reduced_body(
        mres, mat, n_eig=0, raceway=raceway_spec_for(spec_for(rv, "outer_ring"), None, 4), fe=fe, cache=False
    )
    rng = np.random.default_rng(1)
    th = rng.uniform(0, 2 * np.pi, 5)
    F = rng.normal(size=(5, 3))
    q = rng.normal(size=body.n_modes)
    lhs = np.einsum("ij,ij->i", F, body.raceway_displacement(q, th))
    rhs = body.raceway_load_vector(th, F) @ q
    assert np.allclose(lhs, rhs, rtol=1e-12, atol=1e-20)
