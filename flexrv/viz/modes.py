"""Mode-shape views: off-screen PNG (pyvista, imported lazily) and VTU export.

Headless rendering: VTK 9.x wheels render off-screen through EGL when
``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` is set (done here with
``setdefault`` when no ``DISPLAY`` exists); this needs the system EGL/Mesa
libraries (Debian: ``libegl1 libegl-mesa0 libgl1-mesa-dri libglvnd0 libgl1``).
Verified on this machine without ``DISPLAY``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_path


def _pyvista():
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    return pv


#: scalar-bar placement of every 3-D view: vertical at the right, title above the bar
#: (never over a tick label), three significant figures
SCALAR_BAR = {
    "vertical": True,
    "position_x": 0.86,
    "position_y": 0.12,
    "width": 0.06,
    "height": 0.66,
    "title_font_size": 14,
    "label_font_size": 12,
    "fmt": "%.3g",
}


def surface_polydata(
    nodes: np.ndarray,
    tris6: np.ndarray,
    displacement: np.ndarray | None = None,
    scale: float = 1.0,
    scalars: np.ndarray | None = None,
    name: str = "|u|",
):
    """pyvista PolyData of the boundary (corner triangles of the Tri6 faces), nodes
    moved by ``scale * displacement``; point scalars default to |displacement|."""
    pv = _pyvista()
    used = np.unique(tris6[:, :3])
    remap = np.full(nodes.shape[0], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    pts = nodes[used].copy()
    if displacement is not None:
        pts += scale * displacement[used]
    faces = np.hstack([np.full((tris6.shape[0], 1), 3), remap[tris6[:, :3]]]).ravel()
    poly = pv.PolyData(pts, faces)
    if scalars is None and displacement is not None:
        scalars = np.linalg.norm(displacement, axis=1)
    if scalars is not None:
        poly.point_data[name] = np.asarray(scalars)[used]
    return poly


def warp_scale(nodes: np.ndarray, displacement: np.ndarray, fraction: float = 0.08) -> float:
    """Scale that makes the largest displacement ``fraction`` of the body size."""
    umax = float(np.max(np.linalg.norm(displacement, axis=1)))
    return 0.0 if umax == 0 else fraction * float(np.ptp(nodes, axis=0).max()) / umax


#: colour-bar title of a mode shape: displacement magnitude over its largest value, dimensionless
#: (VTK's fonts drop "|", so the bar says it in words)
MODE_SCALAR = "relative displacement [-]"


def render_part_modes(folder, part: str, pm) -> list[Path]:
    """PNGs of every free-free and every constrained mode of a part
    (:class:`flexrv.fem.body.PartModes`) into ``folder``: ``<part>_free_mode<k>.png`` and
    ``<part>_constrained_mode<k>.png``, each titled with the part, the boundary condition
    and the frequency."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    m = pm.mesh
    clamped = ", ".join(pm.interfaces) if pm.interfaces else "interfaces"
    sets = (
        ("free", "free-free", pm.free_hz, pm.free_modes),
        ("constrained", f"constrained ({clamped} clamped)", pm.constrained_hz, pm.constrained_modes),
    )
    files = []
    for tag, words, freqs, shapes in sets:
        for k, f in enumerate(freqs):
            files.append(
                render_mode_png(
                    folder / f"{part}_{tag}_mode{k + 1:02d}.png",
                    m.nodes,
                    m.tris,
                    shapes[:, k].reshape(-1, 3),
                    title=f"{part}, {words} mode {k + 1}: {f:.1f} Hz\n"
                    "colour: displacement magnitude / its largest value; shape exaggerated to 8 % of the body",
                )
            )
    return files


def render_mode_png(
    path: str | os.PathLike,
    nodes: np.ndarray,
    tris6: np.ndarray,
    displacement: np.ndarray,
    title: str = "",
    scalars: np.ndarray | None = None,
    scalar_name: str = MODE_SCALAR,
    window_size=(900, 700),
) -> Path:
    """Render a mode shape off-screen to a PNG, written atomically; returns the path.

    The surface is warped (largest displacement 8 % of the body size) and coloured by
    ``scalars`` (e.g. von Mises stress, named with its unit in ``scalar_name``) or, by
    default, by the displacement magnitude relative to its largest value, |u| / max |u|
    [-]: an eigenvector's amplitude is arbitrary, so only the relative shape has a unit
    that means something. The undeformed surface is drawn as a faint wireframe."""
    pv = _pyvista()
    if scalars is None:
        mag = np.linalg.norm(displacement, axis=1)
        scalars = mag / mag.max() if mag.max() > 0 else mag
    scale = warp_scale(nodes, displacement)
    poly = surface_polydata(nodes, tris6, displacement, scale, scalars, scalar_name)
    ref = surface_polydata(nodes, tris6)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.add_mesh(ref, style="wireframe", color="grey", opacity=0.15)
        plotter.add_mesh(
            poly,
            scalars=scalar_name,
            cmap="viridis",
            show_edges=False,
            scalar_bar_args={"title": scalar_name, **SCALAR_BAR},
        )
        if title:
            plotter.add_text(title, font_size=10)
        return save_screenshot(plotter, path)
    finally:
        plotter.close()


def save_screenshot(plotter, path) -> Path:
    """Isometric view of an off-screen plotter written atomically to a PNG."""
    plotter.view_isometric()
    path = Path(path)
    with atomic_path(path) as tmp:
        plotter.screenshot(str(tmp))
    return path


def show_mode(nodes: np.ndarray, tris6: np.ndarray, displacement: np.ndarray, title: str = "") -> bool:
    """Open an interactive window if a display exists; returns False (and does
    nothing) when headless."""
    if not os.environ.get("DISPLAY"):
        return False
    pv = _pyvista()
    poly = surface_polydata(nodes, tris6, displacement, warp_scale(nodes, displacement))
    plotter = pv.Plotter()
    plotter.add_mesh(poly, scalars="|u|", cmap="viridis")
    if title:
        plotter.add_text(title, font_size=10)
    plotter.show()
    return True


def export_modes_vtu(
    path: str | os.PathLike,
    nodes: np.ndarray,
    tets: np.ndarray,
    modes: np.ndarray,
    frequencies_hz=None,
    prefix: str = "mode",
) -> Path:
    """Write the Tet10 mesh with each mode as a point vector ``mode_<k>_<f>Hz`` to a
    VTU file for ParaView (meshio, atomic). ``modes`` is (3N, m) node-wise."""
    import meshio

    U = modes.reshape(nodes.shape[0], 3, -1)
    data = {}
    for k in range(U.shape[2]):
        tag = f"{prefix}_{k + 1:02d}" + (f"_{frequencies_hz[k]:.1f}Hz" if frequencies_hz is not None else "")
        data[tag] = U[:, :, k]
    path = Path(path)
    with atomic_path(path) as tmp:
        meshio.Mesh(nodes, [("tetra10", tets)], point_data=data).write(tmp, file_format="vtu")
    return path
