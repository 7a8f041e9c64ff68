"""Static FE (full model) vs beam theory; ISO 281 roller-bearing rating."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.fem.assembly import assemble
from flexrv.fem.static import sector_loads, solve_static, von_mises_field
from flexrv.meshing.mesh import generate_mesh
from flexrv.meshing.parts import CrankshaftSpec

E, NU, RHO = 2.1e11, 0.3, 7850.0
G = E / (2 * (1 + NU))


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    """Steel shaft span r = 8 mm, L = 120 mm between a clamped end piece C and a
    loaded end piece A (r = 10 mm, 10 mm long); tip load F = 1 kN along x spread
    over A's lateral nodes (sector_loads over the full circle)."""
    import os

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    r, span, r_end, a = 0.008, 0.12, 0.010, 0.010
    segs = (
        ("gear_seat", r_end, a, 0.0),
        ("support_a", r, span, 0.0),
        ("eccentric_1", r_end, a, 0.0),
        ("eccentric_2", 0.009, 2e-3, 0.0),
        ("support_b", 0.007, 2e-3, 0.0),
    )
    m = generate_mesh(CrankshaftSpec(segments=segs), "crankshaft", 0.0025).data
    fe = assemble(m.nodes, m.tets, E, NU, RHO)
    tip = m.node_set("gear_seat")
    f = sector_loads(m.nodes, tip, (0.0, 0.0), [0.0], [[1000.0, 0.0, 0.0]], np.pi)
    u = solve_static(fe.K, m.node_set("eccentric_1"), f)
    del os.environ["FLEXRV_CACHE"]  # the private cache only while the fixture builds
    return m, u, f, dict(r=r, span=span, a=a)


def test_sector_loads_keep_the_resultant(cantilever):
    m, u, f, g = cantilever
    np.testing.assert_allclose(f.sum(axis=0), [1000.0, 0.0, 0.0], atol=1e-9)
    f2 = sector_loads(
        m.nodes, m.node_set("gear_seat"), (0.0, 0.0), [0.3, 2.0], [[10.0, 20.0, 0.0], [0.0, 0.0, 5.0]], np.pi / 15
    )
    np.testing.assert_allclose(f2.sum(axis=0), [10.0, 20.0, 5.0], atol=1e-12)


def test_tip_deflection_matches_timoshenko_cantilever(cantilever):
    """Mean x-displacement of the loaded end piece vs a Timoshenko cantilever of
    length L loaded at a/2 beyond its end (see tests/test_model_flexible_crank.py):
    the ideal wall is a lower bound; the shoulder at the clamp adds < 8 %."""
    m, u, f, g = cantilever
    r, span, e = g["r"], g["span"], g["a"] / 2
    inertia, area = np.pi * r**4 / 4, np.pi * r**2
    kappa = 6 * (1 + NU) / (7 + 6 * NU)
    ref = 1000.0 * (
        span**3 / (3 * E * inertia)
        + e * span**2 / (2 * E * inertia)
        + e * (span**2 / (2 * E * inertia) + e * span / (E * inertia))
        + span / (kappa * G * area)
    )
    tip = u[m.node_set("gear_seat"), 0].mean()
    assert 0.0 <= tip / ref - 1 < 0.08, tip / ref


def test_bending_stress_matches_beam_theory_at_mid_span(cantilever):
    """Surface von Mises stress near mid-span = |M(z)| |x| / I with the local
    moment M(z) = F (z - a/2) about the load's centroid z = a/2 and |x| the node's
    distance from the neutral axis (Euler–Bernoulli; the transverse shear stress
    vanishes at the extreme fibre), every selected node within 3 %
    (Saint-Venant: far from the load and the clamp)."""
    m, u, f, g = cantilever
    vm = von_mises_field(m.nodes, m.tets, u, E, NU)
    r, span, a = g["r"], g["span"], g["a"]
    z_mid = a + span / 2
    rad = np.hypot(m.nodes[:, 0], m.nodes[:, 1])
    sel = (np.abs(m.nodes[:, 2] - z_mid) < 0.003) & (rad > 0.98 * r) & (np.abs(m.nodes[:, 1]) < 0.25 * r)
    assert sel.sum() >= 2
    ref = 1000.0 * (m.nodes[sel, 2] - a / 2) * np.abs(m.nodes[sel, 0]) / (np.pi * r**4 / 4)
    np.testing.assert_allclose(vm[sel] / ref, 1.0, atol=0.03)


def test_iso281_line_contact_fc_and_rating():
    """f_c of ISO 281:2007 Table 7 (line contact): 84.2 at gamma = 0.10, 88.8 at
    0.18 (within 0.1); C_r scales as Z^(3/4) and L^(7/9)."""
    from flexrv.analysis.life import line_contact_fc, roller_dynamic_rating

    assert line_contact_fc(0.10) == pytest.approx(84.2, abs=0.1)
    assert line_contact_fc(0.18) == pytest.approx(88.8, abs=0.1)
    c = roller_dynamic_rating(3.5e-3, 10e-3, 15, 18.5e-3)
    assert roller_dynamic_rating(3.5e-3, 10e-3, 30, 18.5e-3) / c == pytest.approx(2**0.75, rel=1e-12)
    assert roller_dynamic_rating(3.5e-3, 20e-3, 15, 18.5e-3) / c == pytest.approx(2 ** (7 / 9), rel=1e-12)


def test_static_helpers_reject_bad_input():
    """Bad input raises InputError naming the problem (no silent NaN): a free body
    (no clamped node), a force array of the wrong size, a sector with no node, a
    half-width outside (0, pi]."""
    import scipy.sparse as sp

    from flexrv.errors import InputError

    nodes = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    surf = np.arange(3)
    with pytest.raises(InputError, match="clamped"):
        solve_static(sp.identity(9, format="csr"), np.array([], dtype=int), np.zeros((3, 3)))
    with pytest.raises(InputError, match="DOFs"):
        solve_static(sp.identity(9, format="csr"), np.array([0]), np.zeros((2, 3)))
    with pytest.raises(InputError, match="no surface node"):
        sector_loads(nodes, surf, (0.0, 0.0), [-np.pi / 2], [[1.0, 0.0, 0.0]], 0.1)
    with pytest.raises(InputError, match="half_width"):
        sector_loads(nodes, surf, (0.0, 0.0), [0.0], [[1.0, 0.0, 0.0]], 0.0)
    # two loads sharing the node at 90 deg: each is split over its own sector exactly
    f = sector_loads(nodes, surf, (0.0, 0.0), [0.0, np.pi], [[2.0, 0.0, 0.0], [0.0, 4.0, 0.0]], np.pi / 2 + 1e-9)
    np.testing.assert_allclose(f, [[1.0, 0, 0], [1.0, 2.0, 0], [0, 2.0, 0]], atol=1e-12)
