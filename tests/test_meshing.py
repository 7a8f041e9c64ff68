"""Meshing: part builders, physical groups, cache, errors (gmsh 4.15 OCC)."""

import os

import numpy as np
import pytest

from flexrv.cache import temp_file_writer
from flexrv.design import load
from flexrv.errors import InputError
from flexrv.meshing import build_mesh, spec_for
from flexrv.meshing.mesh import MeshData


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE", str(tmp_path))


def test_outer_ring_groups_geometry_and_cache():
    """rv221 outer ring: raceway nodes lie on the groove torus (|dist - f D| < 1e-6 m,
    the gmsh geometry tolerance), fit nodes on r = OD/2, Tet10 connectivity, and a
    second call is served from the cache with identical arrays."""
    rv = load("rv221")
    spec = spec_for(rv, "outer_ring")
    res = build_mesh(rv, "outer_ring", size=0.012)
    d = res.data
    assert d.tets.shape[1] == 10 and d.n_nodes > 1000
    x = d.nodes[d.node_set("raceway")]
    r = np.hypot(x[:, 0], x[:, 1])
    dist = np.hypot(r - spec.groove_center_r, x[:, 2] - spec.groove_center_z)
    assert np.max(np.abs(dist - spec.groove_radius)) < 1e-6
    xf = d.nodes[d.node_set("fit")]
    assert np.max(np.abs(np.hypot(xf[:, 0], xf[:, 1]) - spec.r_outer)) < 1e-6
    # mid-nodes of tets are edge midpoints for interior straight edges (within curvature)
    mid = 0.5 * (d.nodes[d.tets[:, 0]] + d.nodes[d.tets[:, 1]])
    assert np.median(np.linalg.norm(d.nodes[d.tets[:, 4]] - mid, axis=1)) < 1e-9
    again = build_mesh(rv, "outer_ring", size=0.012)
    assert again.cached and np.array_equal(again.data.tets, d.tets)
    assert res.msh_path.exists() and res.vtu_path.exists()
    import meshio

    assert meshio.read(res.vtu_path).points.shape[0] == d.n_nodes
    # no leftover temp files of this process (another test worker may be writing the same cached mesh)
    mine = [p for p in res.npz_path.parent.glob(".*tmp*") if temp_file_writer(p.name) == os.getpid()]
    assert not mine


def test_crankshaft_eccentrics_and_disc_profile():
    """Eccentric journal nodes lie on circles of the journal radius about (+-e, 0);
    disc: the spline profile deviates < 1e-7 m from the exact modified profile."""
    rv = load("rv40e")
    d = build_mesh(rv, "crankshaft", size=0.004).data
    e = rv.second_stage.eccentricity
    rj = 0.5e-3 * rv.crankshaft.eccentric_journal_diameter_mm
    for name, sign in (("eccentric_1", 1), ("eccentric_2", -1)):
        x = d.nodes[d.node_set(name)]
        assert np.max(np.abs(np.hypot(x[:, 0] - sign * e, x[:, 1]) - rj)) < 1e-6
    disc = build_mesh(rv, "cycloid_disc", size=0.006).data
    assert disc.info["profile_deviation_m"] < 1e-7
    assert {"profile", "center_hole", "crank_hole_1", "crank_hole_3"} <= set(disc.group_names)


def test_bad_inputs_raise_clear_errors(tmp_path):
    rv = load("rv221")
    with pytest.raises(InputError, match="not a known part"):
        build_mesh(rv, "housing")
    with pytest.raises(InputError, match="too coarse"):
        build_mesh(rv, "outer_ring", size=0.05)
    with pytest.raises(InputError, match="too fine"):
        build_mesh(rv, "outer_ring", size=1e-4)
    assert not list(tmp_path.glob("outer_ring-*"))  # nothing half-written


def test_npz_roundtrip(tmp_path):
    d = build_mesh(load("rv40e"), "crankshaft", size=0.005).data
    d.save_npz(tmp_path / "m.npz")
    e = MeshData.load_npz(tmp_path / "m.npz")
    assert np.array_equal(e.nodes, d.nodes) and e.group_names == d.group_names


def test_self_intersecting_geometry_is_rejected():
    """A groove deeper than the ring section, and a looped (non-star-shaped)
    profile, are reported as self-intersecting before gmsh runs."""
    import dataclasses

    from flexrv.meshing.mesh import generate_mesh
    from flexrv.meshing.parts import profile_is_simple

    spec = spec_for(load("rv221"), "outer_ring")
    deep = dataclasses.replace(spec, groove_radius=spec.r_outer - spec.groove_center_r + 1e-3)
    with pytest.raises(InputError, match="self-intersects"):
        generate_mesh(deep, "outer_ring", 0.01)
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    limacon = np.stack([(0.5 + np.cos(t)) * np.cos(t), (0.5 + np.cos(t)) * np.sin(t)], axis=1)  # inner loop
    circle = np.stack([np.cos(t), np.sin(t)], axis=1)
    assert not profile_is_simple(limacon) and profile_is_simple(circle)


def test_carrier_part_groups_and_cli(tmp_path, monkeypatch):
    """`flexrv mesh rv40e --part carrier --json`: every interface group meshed
    (crank bores per plate, flange, seats, pillars), the bores on the crank circle
    a_w at 2 pi k / N; --compliance is refused for parts without a condensation."""
    import json

    from typer.testing import CliRunner

    from flexrv.cli import app

    monkeypatch.setenv("FLEXRV_CACHE_DIR", str(tmp_path))
    rv = load("rv40e")
    r = CliRunner().invoke(app, ["mesh", "rv40e", "--part", "carrier", "--size", "6", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    n = rv.first_stage.n_planets
    expected = {f"bore_{p}_{k}" for p in ("in", "out") for k in range(1, n + 1)} | {
        "flange",
        "seat_in",
        "seat_out",
        "pillar",
        "center_bore",
    }
    assert expected <= set(data["groups"]) and all(data["groups"][g] > 0 for g in expected)
    d = MeshData.load_npz(data["msh"].replace(".msh", ".npz"))
    spec = spec_for(rv, "carrier")
    for k in range(n):
        x = d.nodes[d.node_set(f"bore_in_{k + 1}")]
        c = 0.5 * (x[:, :2].max(axis=0) + x[:, :2].min(axis=0))  # bore axis (bounding-box centre)
        assert np.hypot(*c) == pytest.approx(spec.crank_circle_radius, rel=1e-4)
        off = np.arctan2(c[1], c[0]) - 2 * np.pi * k / n  # the bore angle, compared modulo a turn
        assert abs((off + np.pi) % (2 * np.pi) - np.pi) < 1e-4
    bad = CliRunner().invoke(app, ["mesh", "rv40e", "--part", "crankshaft", "--compliance"])
    assert isinstance(bad.exception, InputError) and "--compliance" in str(bad.exception)  # exit 2 via flexrv.cli.main
