"""CLI `flexrv mesh` / `flexrv modes` (typer CliRunner)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.cli import app


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE", str(tmp_path))


def test_mesh_json_counts_match_files():
    """--json reports the node/element counts of the written .vtu (meshio)."""
    import meshio

    r = CliRunner().invoke(app, ["mesh", "rv40e", "--part", "crankshaft", "--size", "4", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    back = meshio.read(data["vtu"])
    assert data["nodes"] == back.points.shape[0] and data["elements"] == back.cells[0].data.shape[0]
    assert data["groups"]["eccentric_1"] > 0


def test_modes_json_ordering_and_bad_part(tmp_path):
    """Free-free frequencies positive and ascending; with both support journals
    clamped the first frequency is higher than the free-free one (clamped-clamped
    and free-free beams share beta_1 L = 4.730, Blevins table 8-1, but the clamped
    span between the journals is shorter than the whole shaft). Bad part -> exit 2
    with a message naming it."""
    r = CliRunner().invoke(
        app, ["modes", "rv40e", "--part", "crankshaft", "--size", "5", "--n", "3", "--json", "--vtu", str(tmp_path)]
    )
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    f, fc = np.array(data["free_hz"]), np.array(data["constrained_hz"])
    assert f.size == 3 and np.all(f > 1000) and np.all(np.diff(f) >= 0)
    assert fc.size == 3 and np.all(np.diff(fc) >= 0) and fc[0] > f[0]
    assert len(data["files"]) == 2
    bad = CliRunner().invoke(app, ["mesh", "rv40e", "--part", "housing"])
    assert bad.exit_code == 2 and "housing" in bad.output
