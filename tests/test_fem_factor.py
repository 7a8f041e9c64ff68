"""The FE factorisation (METIS nested-dissection order, SuperLU) and the condensation
B^T K^-1 B by the supernodal forward substitution (flexrv.fem.factor), against SciPy's
SuperLU with its own MMD(A^T + A) order (an independent route: other order, other
solve). Tolerance 1e-10 relative to the largest entry: both are direct solves of a
well-conditioned clamped stiffness, so they agree to round-off (measured ~1e-14)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from flexrv.design import load
from flexrv.errors import InputError
from flexrv.fem.assembly import assemble
from flexrv.fem.body import material_dict
from flexrv.fem.carrier import bore_groups, clamped_flexibility, rbe3_loads, rigid_master_transform
from flexrv.fem.disc import (
    PinContactCase,
    body_design,
    contact_geometry,
    disc_patch_sweep,
    hole_masters,
    pin_patch_loads,
)
from flexrv.fem.factor import _supervariables, factorize, nested_dissection_order
from flexrv.fem.modal import free_dofs
from flexrv.meshing import build_mesh
from flexrv.meshing.mesh import generate_mesh
from tests._parts import MINI_CARRIER

SIZE, LOCAL = 0.008, 0.004
REL = 1e-10
#: crank angles of disc_patch_sweep(n_angles=2) on the rv40e (N = 3 cranks): 2 pi k / (N 2)
ANGLES = [0.0, np.pi / 3]


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE_DIR", str(tmp_path))


def _mmd_solve(A, B):
    """The reference route: SuperLU, MMD(A^T + A) column order, symmetric mode."""
    lu = sla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return lu.solve(np.asarray(B, dtype=float)), lu.nnz


MINI = MINI_CARRIER


@pytest.fixture(scope="module")
def carrier():
    """Clamped stiffness K_ff of the small carrier, its RBE3 bore loads W (full and on
    the free DOFs) and the MMD route's K_ff^-1 W and fill."""
    m = generate_mesh(MINI, "carrier", 0.004, local_size=0.002, cache=False).data
    fe = assemble(m.nodes, m.tets, 2.1e11, 0.3, 7800.0, mass=False)
    W = rbe3_loads(m.nodes, [m.faces(g) for g in bore_groups(MINI.n_cranks)])
    flange = m.node_set("flange")
    idofs = free_dofs(fe.K.shape[0], flange)
    Kff = sp.csc_matrix(fe.K[idofs][:, idofs])
    Wf = W.tocsr()[idofs].toarray()
    Xr, nnz_mmd = _mmd_solve(Kff, Wf)
    return fe.K, flange, W, Kff, Wf, Xr, nnz_mmd


@pytest.fixture(scope="module")
def disc():
    """The held coarse rv40e disc body (crank holes eliminated as rigid masters,
    one kept DOF each, so the DOF runs are not all triples) and its pin-patch loads
    at the two crank angles of disc_patch_sweep(n_angles=2)."""
    rv = body_design(load("rv40e"))
    d = build_mesh(rv, "cycloid_disc", SIZE, local_size=LOCAL, cache=False).data
    mat = material_dict(rv, "cycloid_disc")
    fe = assemble(d.nodes, d.tets, mat["E"], mat["nu"], mat["rho"], mass=False)
    Z, _ = rigid_master_transform(fe.K.shape[0], d.nodes, hole_masters(d))
    Kr = sp.csc_matrix(Z.T @ (sp.csr_matrix(fe.K) @ Z))
    Kr = sp.csc_matrix(0.5 * (Kr + Kr.T))
    Ws = []
    for a in ANGLES:
        p, dirs = contact_geometry(rv, a)
        case = PinContactCase(points=p, directions=dirs, forces=np.zeros(len(p)), disc_torque=1.0)
        Ws.append((Z.T @ pin_patch_loads(d, case, 0.5 * rv.second_stage.pin_radius)).toarray())
    Xr = _mmd_solve(Kr, np.hstack(Ws))[0]
    return rv, Kr, Ws, Xr


def test_supervariables_and_order(carrier):
    """Every supervariable run holds columns of one identical pattern, most runs are the
    nodes' DOF triples (an exactly zero coupling, dropped by the assembly, splits a few),
    and the expanded order is a reproducible permutation that keeps each run together and
    in order."""
    Kff = carrier[3]
    Kff = sp.csc_matrix(Kff)
    Kff.sort_indices()
    bounds = _supervariables(Kff)
    assert bounds[0] == 0 and bounds[-1] == Kff.shape[0] and np.all(np.diff(bounds) > 0)
    for a, b in zip(bounds[:-1], bounds[1:]):
        first = Kff.indices[Kff.indptr[a] : Kff.indptr[a + 1]]
        for j in range(a + 1, b):
            assert np.array_equal(Kff.indices[Kff.indptr[j] : Kff.indptr[j + 1]], first)
    triples = (np.diff(bounds) == 3) & (bounds[:-1] % 3 == 0)
    assert 3 * triples.sum() > 0.9 * Kff.shape[0]
    perm = nested_dissection_order(Kff)
    assert np.array_equal(np.sort(perm), np.arange(Kff.shape[0]))
    assert np.array_equal(nested_dissection_order(Kff), perm)  # deterministic (METIS's fixed seed)
    pos = np.empty_like(perm)
    pos[perm] = np.arange(perm.size)
    for a, b in zip(bounds[:-1], bounds[1:]):
        assert np.array_equal(pos[a:b], pos[a] + np.arange(b - a))


def test_factor_solves_like_superlu_mmd_with_less_fill(carrier):
    """Solutions and C = W^T K^-1 W of the carrier's bore loads agree with the MMD route
    to 1e-10; the nested-dissection factor keeps less fill than MMD on this 3-D mesh."""
    _, _, _, Kff, W, Xr, nnz_mmd = carrier
    f = factorize(Kff)
    X = f(W)
    assert np.max(np.abs(X - Xr)) <= REL * np.max(np.abs(Xr))
    x1 = f(W[:, 0])
    assert x1.shape == (Kff.shape[0],) and np.allclose(x1, X[:, 0], rtol=0, atol=1e-14 * np.abs(X).max())
    assert f.nnz < nnz_mmd


def test_whitened_condensation_matches_full_solves(carrier, disc):
    """V^T V from the forward substitution equals W^T K^-1 W of the MMD route, for the
    carrier (dense W, 2B columns) and the held disc (sparse W, 2 z_rp columns, master
    DOFs appended to the node triples), to 1e-10 of the largest entry."""
    _, _, _, Kff, W, Xr, _ = carrier
    V = factorize(Kff).whitened(W)
    Cr = W.T @ Xr
    assert np.max(np.abs(V.T @ V - Cr)) <= REL * np.max(np.abs(Cr))
    _, Kr, Ws, Xr = disc
    Wd = np.hstack(Ws)
    V = factorize(Kr).whitened(sp.csc_matrix(Wd))
    Cr = Wd.T @ Xr
    assert np.max(np.abs(V.T @ V - Cr)) <= REL * np.max(np.abs(Cr))


def test_disc_patch_sweep_matches_the_mmd_route(disc):
    """disc_patch_sweep's per-angle patch compliances (its own mesh of the same spec,
    gmsh being deterministic) equal W_a^T K^-1 W_a solved by the MMD route on the
    fixture's held disc, to 1e-10."""
    rv, Kr, Ws, Xr = disc
    ps = disc_patch_sweep(load("rv40e"), n_angles=2, size=SIZE, local_size=LOCAL)
    assert ps.angles == pytest.approx(ANGLES)
    assert 3 * ps.n_nodes > Kr.shape[0]
    for C, Wr, X in zip(ps.matrices, Ws, np.split(Xr, len(Ws), axis=1)):
        Cr = Wr.T @ X
        assert np.max(np.abs(np.asarray(C) - Cr)) <= REL * np.max(np.abs(Cr))


def test_whitened_rejects_an_indefinite_matrix(carrier):
    """A matrix with a negative pivot has no D^-1/2: one clear error, no silent result."""
    Kff, W = carrier[3], carrier[4]
    A = sp.csc_matrix(Kff - 2.0 * Kff.diagonal().max() * sp.identity(Kff.shape[0]))
    with pytest.raises(InputError, match="symmetric positive definite"):
        factorize(A).whitened(W)


def test_clamped_flexibility_matches_the_mmd_route(carrier):
    """The carrier condensation (clamped_flexibility through factorize) equals the MMD route."""
    K, flange, W, _, Wf, Xr, _ = carrier
    C, _ = clamped_flexibility(K, flange, W)
    Cr = Wf.T @ Xr
    Cr = 0.5 * (Cr + Cr.T)
    assert np.max(np.abs(C - Cr)) <= REL * np.max(np.abs(Cr))
