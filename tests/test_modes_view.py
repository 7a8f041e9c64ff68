"""Off-screen mode rendering (pyvista/EGL, no DISPLAY) and VTU export."""

import numpy as np
import pytest

from flexrv.fem.assembly import assemble
from flexrv.fem.modal import eigenmodes
from flexrv.meshing.mesh import generate_mesh
from flexrv.meshing.parts import PlainRingSpec


@pytest.fixture(scope="module")
def ring_mode(tmp_path_factory):
    import os

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    m = generate_mesh(PlainRingSpec(0.09, 0.1, 0.02), "plain_ring", 0.01).data
    fe = assemble(m.nodes, m.tets, 2.1e11, 0.3, 7850.0)
    f, v = eigenmodes(fe.K, fe.M, 8)
    del os.environ["FLEXRV_CACHE"]
    return m, f, v


def test_png_is_not_blank(ring_mode, tmp_path, monkeypatch):
    """The n = 2 mode renders headless to a PNG whose pixel values vary
    (std > 5 grey levels) and differ from the undeformed render."""
    from PIL import Image

    from flexrv.viz.modes import render_mode_png

    monkeypatch.delenv("DISPLAY", raising=False)
    m, f, v = ring_mode
    u = v[:, 6].reshape(-1, 3)
    p = render_mode_png(tmp_path / "mode.png", m.nodes, m.tris, u, title=f"{f[6]:.0f} Hz")
    img = np.asarray(Image.open(p).convert("L"), dtype=float)
    assert img.shape[0] > 100 and img.std() > 5.0


def test_vtu_export_roundtrip(ring_mode, tmp_path):
    import meshio

    from flexrv.viz.modes import export_modes_vtu

    m, f, v = ring_mode
    p = export_modes_vtu(tmp_path / "modes.vtu", m.nodes, m.tets, v[:, 6:8], f[6:8])
    back = meshio.read(p)
    assert len(back.point_data) == 2
    arr = next(iter(back.point_data.values()))
    assert np.allclose(arr, v[:, 6].reshape(-1, 3))
