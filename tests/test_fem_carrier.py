"""Carrier FE condensation (flexrv.fem.carrier): exactness against full FE solves,
closed-form pillar frame, mesh convergence, cache, design checks."""

import json
import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexrv.design import load, override
from flexrv.errors import ConfigError, InputError
from flexrv.fem.assembly import assemble
from flexrv.fem.carrier import (
    bore_groups,
    carrier_compliance,
    clamped_flexibility,
    pillar_frame_stiffness,
    rbe2_bore_compliance,
    rbe3_loads,
    rigid_plate_frame_stiffness,
    torque_load_vector,
)
from flexrv.fem.static import solve_static
from flexrv.meshing import build_mesh
from flexrv.meshing.mesh import generate_mesh
from flexrv.meshing.parts import spec_for
from flexrv.units import RAD_PER_ARCMIN
from tests._parts import MINI_CARRIER, PILLAR_FRAME
from tests._parts import RV40E_CARRIER_COARSE as COARSE


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE_DIR", str(tmp_path))


MINI = MINI_CARRIER


@pytest.fixture(scope="module")
def mini():
    """The small carrier, assembled (steel)."""
    mesh = generate_mesh(MINI, "carrier", 0.006, local_size=0.002, cache=False).data
    fe = assemble(mesh.nodes, mesh.tets, 2.1e11, 0.3, 7800.0)
    return MINI, mesh, fe


def _area_weights(mesh, group):
    """Independent nodal area weights of a surface group (Tri6: 1/6 of the flat
    corner triangle to each of its six nodes)."""
    f = mesh.faces(group)
    p = mesh.nodes[f[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    w = np.zeros(mesh.n_nodes)
    np.add.at(w, f.ravel(), np.repeat(area / 6.0, 6))
    return w / w.sum()


def test_carrier_mesh_groups_lie_on_the_geometry():
    """Bore nodes lie on their bore cylinders (crank k at 2 pi k / N on a_w), the
    flange nodes on the output plate's outer face, pillar nodes on the pillar
    cylinders (within 1e-6 m, the gmsh geometry tolerance)."""
    rv = load("rv40e")
    mesh = build_mesh(rv, "carrier", COARSE, local_size=COARSE, cache=False).data
    spec = spec_for(rv, "carrier")
    for name in bore_groups(spec.n_cranks):
        k = int(name.rsplit("_", 1)[1]) - 1
        a = 2 * math.pi * k / spec.n_cranks
        x = mesh.nodes[mesh.node_set(name)]
        r = np.hypot(x[:, 0] - spec.crank_circle_radius * math.cos(a), x[:, 1] - spec.crank_circle_radius * math.sin(a))
        assert np.max(np.abs(r - spec.crank_bore_radius)) < 1e-6
        z = x[:, 2]
        if "_in_" in name:
            assert z.max() <= spec.input_thickness + 1e-9
        else:
            assert z.min() >= spec.input_thickness + spec.gap - 1e-9
    assert np.max(np.abs(mesh.nodes[mesh.node_set("flange"), 2] - spec.length)) < 1e-9
    xp = mesh.nodes[mesh.node_set("pillar")]
    d = np.min(
        [
            np.hypot(
                xp[:, 0] - spec.pillar_circle_radius * math.cos(a), xp[:, 1] - spec.pillar_circle_radius * math.sin(a)
            )
            for a in spec.pillar_angles
        ],
        axis=0,
    )
    assert np.max(np.abs(d - spec.pillar_radius)) < 1e-6


def test_condensed_compliance_reproduces_full_fe_solve(mini):
    """C = W^T K_ff^-1 W (RBE3 bores, flange held) times a bore-force vector (the
    torque path's tangential crank forces plus arbitrary radial forces) equals the
    area-weighted bore displacements of an independent full FE solve
    (flexrv.fem.static.solve_static with loads built here) to 1e-8 relative; the
    carrier twist from the full solve equals g^T C g."""
    spec, mesh, fe = mini
    n = spec.n_cranks
    names = bore_groups(n)
    W = rbe3_loads(mesh.nodes, [mesh.faces(g) for g in names])
    np.testing.assert_allclose(np.asarray(W.sum(axis=0)).ravel(), 1.0, rtol=1e-12)  # unit resultants
    flange = mesh.node_set("flange")
    C, _ = clamped_flexibility(fe.K, flange, W)
    rng = np.random.default_rng(14)
    g = torque_load_vector(n, spec.crank_circle_radius, 0.5)
    for f in (412.0 * g, 412.0 * g + 800.0 * rng.standard_normal(g.size)):
        forces = np.zeros((mesh.n_nodes, 3))
        weights = [_area_weights(mesh, name) for name in names]
        for b, w in enumerate(weights):
            forces[:, 0] += f[2 * b] * w
            forces[:, 1] += f[2 * b + 1] * w
        u = solve_static(fe.K, flange, forces)
        ub = np.array([[w @ u[:, 0], w @ u[:, 1]] for w in weights]).ravel()
        np.testing.assert_allclose(C @ f, ub, rtol=1e-8, atol=1e-8 * np.abs(ub).max())
    theta = g @ (C @ g)
    assert theta > 0 and np.all(np.linalg.eigvalsh(C) > 0)


def test_rigid_bore_bound_matches_lagrange_solve(mini):
    """The RBE2 (rigid bore) compliance from the Guyan condensation equals a
    Lagrange-multiplier solve of the constrained full model (u_bore nodes = T q,
    flange clamped) to 1e-8, and is stiffer than the RBE3 (averaging) value in
    the torque path."""
    from flexrv.fem.crankshaft import _disjoint
    from flexrv.fem.modal import free_dofs
    from flexrv.fem.reduction import rbe2_mapping

    spec, mesh, fe = mini
    n = spec.n_cranks
    names = bore_groups(n)
    C2 = rbe2_bore_compliance(fe.K, mesh, names)
    sets = _disjoint(mesh.node_set("flange"), *[mesh.node_set(g) for g in names])
    flange, bores = sets[0], sets[1:]
    free = free_dofs(fe.K.shape[0], flange)
    pos = -np.ones(fe.K.shape[0], dtype=np.int64)
    pos[free] = np.arange(free.size)
    nf, nq = free.size, 6 * len(bores)
    rows, cols, vals = [], [], []
    r0 = 0
    for b, s in enumerate(bores):  # u_s - T q_b = 0
        T = rbe2_mapping(mesh.nodes, s)
        d = (3 * s[:, None] + np.arange(3)).ravel()
        rows += list(r0 + np.arange(d.size))
        cols += list(pos[d])
        vals += [1.0] * d.size
        rr, cc = np.nonzero(T)
        rows += list(r0 + rr)
        cols += list(nf + 6 * b + cc)
        vals += list(-T[rr, cc])
        r0 += d.size
    scale = float(fe.K.diagonal().mean())  # balances the saddle-point system (K ~ 1e10 N/m, B ~ 1)
    B = scale * sp.csr_matrix((vals, (rows, cols)), shape=(r0, nf + nq))
    Kf = sp.block_diag([fe.K.tocsr()[free][:, free], sp.csr_matrix((nq, nq))])
    A = sp.bmat([[Kf, B.T], [B, None]]).tocsc()
    g = torque_load_vector(n, spec.crank_circle_radius, 0.3)
    rhs = np.zeros(A.shape[0])
    for b in range(len(bores)):
        rhs[nf + 6 * b : nf + 6 * b + 2] = g[2 * b : 2 * b + 2]
    x = spla.spsolve(A, rhs)
    qxy = np.array([x[nf + 6 * b : nf + 6 * b + 2] for b in range(len(bores))]).ravel()
    np.testing.assert_allclose(C2 @ g, qxy, rtol=1e-8, atol=1e-8 * np.abs(qxy).max())
    W = rbe3_loads(mesh.nodes, [mesh.faces(gname) for gname in names])
    C3, _ = clamped_flexibility(fe.K, mesh.node_set("flange"), W)
    g5 = torque_load_vector(n, spec.crank_circle_radius, 0.5)
    assert g5 @ C2 @ g5 < g5 @ C3 @ g5


def test_pillars_between_rigid_plates_match_the_built_in_frame():
    """Both plates rigid (input plate one RBE2 master, output plate clamped): the
    FE torsional stiffness of three slender pillars (L/d = 6.7) equals the closed
    form N_p (R^2 / (L^3/(12 EI) + L/(kappa G A)) + G J / L) (built-in Timoshenko
    sway + pillar torsion, :func:`pillar_frame_stiffness`) within 1.5 % (observed
    0.3-0.5 % on three meshes; the residual is the 3-D clamp effect at the
    pillar roots and the mesh)."""
    spec = PILLAR_FRAME
    mesh = generate_mesh(spec, "carrier", 0.008, local_size=0.0015, cache=False).data
    E, nu = 2.1e11, 0.3
    fe = assemble(mesh.nodes, mesh.tets, E, nu, 7800.0)
    k_fe = rigid_plate_frame_stiffness(fe.K, mesh, spec)
    k_cf = pillar_frame_stiffness(3, spec.pillar_circle_radius, spec.pillar_radius, spec.gap, E, nu)
    assert k_fe == pytest.approx(k_cf, rel=0.015)
    # the sway term dominates (the closed form is not carried by the torsion term alone)
    G = E / (2 * (1 + nu))
    assert 3 * G * math.pi * spec.pillar_radius**4 / 2 / spec.gap < 0.2 * k_cf


@pytest.mark.slow
def test_carrier_compliance_cached_and_consistent():
    """carrier_compliance: JSON cache hit gives identical numbers (also asked without the
    rigid-bore bound, a cached result with it is reused); torsional =
    g^T C g of the stored matrix; RBE2 bound stiffer; rv40e carrier stiffness at the
    coarse mesh between 500 and 10000 N m/arcmin (plausibility band around the
    1780 N m/arcmin of the default mesh: the flange-held pillars-and-plates frame)."""
    rv = load("rv40e")
    a = carrier_compliance(rv, size=COARSE, local_size=COARSE)
    b = carrier_compliance(rv, size=COARSE, local_size=COARSE)
    assert a == b
    # without the bound: the cached result with the bound is reused as it is (no second build),
    # and a fresh build without it gives the same matrix with no bound
    assert carrier_compliance(rv, size=COARSE, local_size=COARSE, rigid_bound=False) == a
    lean = carrier_compliance(rv, size=COARSE, local_size=COARSE, rigid_bound=False, cache=False)
    assert lean.torsional_rbe2 is None and lean.matrix == a.matrix
    g = torque_load_vector(a.n_cranks, a.crank_circle_radius, a.split_input)
    assert a.torsional == pytest.approx(float(g @ np.array(a.matrix) @ g), rel=1e-12)
    assert a.torsional_rbe2 < a.torsional
    assert 500.0 < a.torsional_stiffness_Nm_per_arcmin < 1e4
    assert a.torsional_stiffness_Nm_per_arcmin == pytest.approx(RAD_PER_ARCMIN / a.torsional)
    json.dumps(a.matrix)


def _observed_rate(h, c):
    """Richardson: c(h) = c_inf + A h^p from three meshes with a common ratio."""
    r = h[0] / h[1]
    return math.log(abs((c[0] - c[1]) / (c[1] - c[2]))) / math.log(r)


def test_mesh_convergence_fast():
    """Pillar-frame stiffness (rigid plates) on three pillar mesh sizes, ratio
    sqrt 2 (3, 2.12, 1.5 mm on r = 3 mm pillars): the displacement FE converges
    from above (stiffness decreases monotonically: 5288, 5255, 5229 N m/rad
    observed), the observed rate p > 0.3 (0.62 observed: non-nested meshes and
    the re-entrant pillar roots), the finest within 1 % of the closed form."""
    spec = PILLAR_FRAME
    E, nu = 2.1e11, 0.3
    k_cf = pillar_frame_stiffness(3, spec.pillar_circle_radius, spec.pillar_radius, spec.gap, E, nu)
    h = [0.003, 0.003 / math.sqrt(2), 0.0015]
    ks = []
    for loc in h:
        mesh = generate_mesh(spec, "carrier", 0.008, local_size=loc, cache=False).data
        fe = assemble(mesh.nodes, mesh.tets, E, nu, 7800.0)
        ks.append(rigid_plate_frame_stiffness(fe.K, mesh, spec))
    assert ks[0] > ks[1] > ks[2]
    assert _observed_rate(h, ks) > 0.3
    assert abs(ks[-1] / k_cf - 1) < 0.01


@pytest.mark.slow
def test_mesh_convergence_carrier_slow():
    """rv40e carrier torsional compliance (RBE3 bores, flange held) on global sizes
    6, 5.05, 4.24 mm (ratio 2^(1/4), pillar size 0.6875 x global; the coarsest the 6.5 mm
    ligament beside the 27 mm crank bores allows; 34k-85k nodes, ~80 s CPU, 4 GB): the
    compliance increases monotonically (displacement FE converges from the stiff side),
    observed Richardson rate p > 0.5, the extrapolated value within 8 % of the finest mesh.
    Measured: 1.6512e-7, 1.6643e-7, 1.6731e-7 rad/(N m), p = 2.3, extrapolated 1.691e-7
    (1.1 % above the finest)."""
    rv = load("rv40e")
    h = [COARSE, COARSE / 2**0.25, COARSE / math.sqrt(2)]
    c = [carrier_compliance(rv, size=x, local_size=0.6875 * x, rigid_bound=False, cache=False).torsional for x in h]
    assert c[0] < c[1] < c[2]
    p = _observed_rate(h, c)
    assert p > 0.5
    c_inf = c[2] + (c[2] - c[1]) / ((h[1] / h[2]) ** p - 1)
    assert abs(c_inf / c[2] - 1) < 0.08


def test_carrier_design_errors_name_the_field(tmp_path):
    """Bores that overlap, pillars that hit a bore or cut the disc teeth, a plate
    larger than the main bearing's bore, discs that do not fit between the plates:
    ConfigError naming the carrier field; a design without [carrier] refuses the part."""
    cases = [
        ({"carrier.crank_bore_diameter_mm": 63.0}, "carrier.crank_bore_diameter_mm"),
        ({"carrier.pillar_circle_radius_mm": 50.0}, "carrier.pillar_circle_radius_mm"),
        ({"carrier.pillar_diameter_mm": 40.0}, "pillar_diameter_mm"),
        ({"carrier.plate_outer_diameter_mm": 150.0}, "carrier.plate_outer_diameter_mm"),
        ({"carrier.plate_gap_mm": 20.0}, "carrier.plate_gap_mm"),
        ({"carrier.center_bore_diameter_mm": 45.0}, "carrier.center_bore_diameter_mm"),
        ({"carrier.crank_bore_diameter_mm": 12.0}, "support_journal_diameter_mm"),
    ]
    for ov, field in cases:
        with pytest.raises(ConfigError, match=field):
            override("rv40e", ov)
    from flexrv.design import from_dict

    data = load("rv40e").model_dump()
    data.pop("carrier")
    bare = from_dict(data)
    assert bare.carrier is None and "carrier" not in bare.model_dump()
    with pytest.raises(InputError, match="no \\[carrier\\] table"):
        spec_for(bare, "carrier")
    with pytest.raises(InputError, match="too coarse for the carrier"):
        build_mesh(load("rv40e"), "carrier", 0.02)


def test_pillar_root_refinement_grades_the_mesh():
    """The optional edge size (generate_mesh(..., edge_size=), CarrierSpec.root_size) refines
    the mesh at the pillar roots, the re-entrant edges that limit the carrier's convergence
    rate (tests/test_convergence.py::TestConvergenceCarrierTorsion): the mean corner-edge length
    of the tetrahedra whose centroid lies within 1 mm of a root circle is below twice the edge size
    and under 0.6 times the default's (no edge size: above the 2 mm pillar size there; measured
    1.32 against 2.83 mm); its key differs from the default's."""

    def root_edge_length(mesh):
        p = mesh.nodes[mesh.tets[:, :4]]
        c = p.mean(axis=1)
        z_roots = (MINI.input_thickness, MINI.input_thickness + MINI.gap)
        near = np.zeros(len(c), dtype=bool)
        for a in MINI.pillar_angles:
            ctr = MINI.pillar_circle_radius * np.array([math.cos(a), math.sin(a)])
            r = np.hypot(*(c[:, :2] - ctr).T)
            for z in z_roots:
                near |= np.hypot(r - MINI.pillar_radius, c[:, 2] - z) < 1e-3
        e = np.linalg.norm(p[near][:, [0, 0, 0, 1, 1, 2]] - p[near][:, [1, 2, 3, 2, 3, 3]], axis=2)
        return float(e.mean())

    base = generate_mesh(MINI, "carrier", 0.006, local_size=0.002, cache=False)
    fine = generate_mesh(MINI, "carrier", 0.006, local_size=0.002, edge_size=0.0007, cache=False)
    assert fine.key != base.key and fine.data.info["edge_size"] == 0.0007
    h_fine, h_base = root_edge_length(fine.data), root_edge_length(base.data)
    assert h_fine < 2.0 * 0.0007 and h_fine < 0.6 * h_base
    assert h_base > 0.002
    with pytest.raises(InputError, match="edge mesh size"):
        generate_mesh(MINI, "carrier", 0.006, edge_size=0.01, cache=False)
