"""Deformed main-bearing rings of a flexible-model result (pyvista, off-screen).

A result of ``model="flexible"`` records the rings' modal coordinates
(``ring_modal_outer`` / ``ring_modal_inner``, dims time, bearing_row, mode) and,
in ``attrs["flexible_bodies"]``, the :func:`flexrv.fem.body.reduce_part`
settings of each ring, so the reduced bodies are rebuilt from the cache (or
re-meshed and reduced if the cache was cleared). Every ring is placed in the
housing frame: mesh frame = the row's frame (ball centre at z = 0), shifted to the
row's axial position; the second row is the mirror image z -> -z of the meshed
ring (:class:`flexrv.model.flexible_bearing.ModalRing`); the inner rings turn and
move with the carrier (its angle and x, y at that instant).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_path, atomic_write_text
from flexrv.errors import InputError
from flexrv.viz.modes import SCALAR_BAR, _pyvista, save_screenshot, surface_polydata

FIELDS = ("displacement", "von_mises")


@dataclass
class RingState:
    """One ring of one row at one instant (housing frame, SI)."""

    label: str  #: "outer" / "inner"
    row: int
    nodes: np.ndarray  #: (N, 3) undeformed node positions [m]
    tris: np.ndarray  #: (F, 6) surface Tri6
    displacement: np.ndarray  #: (N, 3) [m]
    von_mises: np.ndarray | None  #: (N,) [Pa] if the body has stress modes


def ring_bodies(res, stress: bool = False, rebuild: bool = False) -> dict:
    """{"outer": ReducedBody, "inner": ReducedBody} of a flexible-model result.

    The run stored the identity of each reduced body it used (cache file and content
    key, :func:`flexrv.fem.body.body_identity`); the body is loaded from the cache,
    verified, and never meshed or reduced again: if it is gone, the error says how to
    rebuild it. ``rebuild=True`` (``flexrv view --rebuild``) meshes and reduces it from
    the saved design instead, as does ``stress`` (the von Mises modes are not part of the
    run's body: they are reduced from the cached mesh of the part)."""
    from flexrv.fem.body import load_cached_body, reduce_part

    raw = res.attrs.get("flexible_bodies")
    if raw is None:
        raise InputError(
            f"result of model {res.attrs.get('model')!r} has no flexible rings to show: run "
            "`flexrv simulate PRESET --model flexible` (main_bearing flexible)"
        )
    settings = json.loads(raw) if isinstance(raw, str) else raw
    out = {}
    for part, opts in settings.items():
        opts = dict(opts)
        identity = opts.pop("identity", None)
        if not (stress or rebuild):
            if identity is None:
                raise InputError(
                    f"this result does not record which reduced {part} it used (saved before "
                    "flexrv recorded body identities): `flexrv view --rebuild` meshes and reduces it "
                    "again from the saved design"
                )
            out[part.split("_")[0]] = load_cached_body(identity)
            continue
        if res.reducer is None:
            raise InputError("the result folder has no config.toml: cannot rebuild the reduced rings")
        out[part.split("_")[0]] = reduce_part(res.reducer, part, stress=stress, **opts)
    return out


def ring_states(
    res, time: float | None = None, stress: bool = False, bodies: dict | None = None, rebuild: bool = False
) -> list[RingState]:
    """The deformed rings at the record nearest ``time`` [s] (default: last)."""
    from flexrv.geometry.bearing import BallBearingGeometry

    bodies = bodies or ring_bodies(res, stress, rebuild)
    t = res.time
    i = len(t) - 1 if time is None else int(np.argmin(np.abs(t - time)))
    z_rows = BallBearingGeometry.from_design(res.reducer.main_bearing).row_positions()
    theta = float(res["theta_out"].values[i])
    cx, cy = float(res["carrier_x"].values[i]), float(res["carrier_y"].values[i])
    c, s = np.cos(theta), np.sin(theta)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out = []
    for label, body in bodies.items():
        name = f"ring_modal_{label}"
        if name not in res:
            continue
        q_all = res[name].values[i]  # (rows, modes)
        for k in range(q_all.shape[0]):
            mirror = np.array([1.0, 1.0, -1.0 if k == 1 else 1.0])
            nodes = body.nodes * mirror + np.array([0.0, 0.0, z_rows[k]])
            disp = body.displacement(q_all[k]) * mirror
            if label == "inner":
                nodes = nodes @ rot.T + np.array([cx, cy, 0.0])
                disp = disp @ rot.T
            vm = body.von_mises(q_all[k]) if (stress and body.stress_modes is not None) else None
            out.append(RingState(label, k, nodes, body.tris, disp, vm))
    if not out:
        raise InputError("the result has no ring modal coordinates (ring_modal_outer / ring_modal_inner)")
    return out


def _polydata(state: RingState, scale: float, field: str):
    if field == "von_mises":
        if state.von_mises is None:
            raise InputError(
                "field von_mises needs the rings' stress modes: they are built on request "
                "(flexrv view ... --field von_mises rebuilds them, ~1 min per ring)"
            )
        return surface_polydata(
            state.nodes, state.tris, state.displacement, scale, 1e-6 * state.von_mises, FIELD_TITLES["von_mises"]
        )
    return surface_polydata(
        state.nodes,
        state.tris,
        state.displacement,
        scale,
        1e6 * np.linalg.norm(state.displacement, axis=1),
        FIELD_TITLES["displacement"],
    )


#: scalar-bar titles (one unit style: quantity [unit], engineering units for display)
FIELD_TITLES = {"displacement": "displacement |u| [µm]", "von_mises": "von Mises stress [MPa]"}


def ring_label_points(states: list[RingState]) -> tuple[np.ndarray, list[str]]:
    """One label point per ring (its outermost node at the top, +y) and the label text
    ("outer ring, row 1", ...) to identify rings and rows in a 3-D view."""
    pts, labels = [], []
    for st in states:
        j = int(np.argmax(st.nodes[:, 1] + (1e-3 if st.label == "outer" else 0.0) * st.nodes[:, 2]))
        pts.append(st.nodes[j])
        labels.append(f"{st.label} ring, row {st.row + 1}")
    return np.array(pts), labels


def auto_scale(states: list[RingState], fraction: float = 0.03) -> float:
    """Display scale that makes the largest ring displacement ``fraction`` of the
    bearing's outer diameter."""
    umax = max(float(np.linalg.norm(s.displacement, axis=1).max()) for s in states)
    size = max(float(np.ptp(s.nodes[:, :2], axis=0).max()) for s in states)
    return 0.0 if umax == 0 else fraction * size / umax


def render_rings_png(
    res,
    path,
    time: float | None = None,
    scale: float | None = None,
    field: str = "displacement",
    rebuild: bool = False,
    window_size=(1000, 800),
) -> Path:
    """Render the deformed rings (coloured by |u| or von Mises) off-screen to a PNG."""
    if field not in FIELDS:
        raise InputError(f"field = {field!r} is not allowed: choose one of {', '.join(FIELDS)}")
    pv = _pyvista()
    states = ring_states(res, time, stress=field == "von_mises", rebuild=rebuild)
    scale = auto_scale(states) if scale is None else float(scale)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        name = FIELD_TITLES[field]
        for st in states:
            plotter.add_mesh(
                _polydata(st, scale, field),
                scalars=name,
                cmap="viridis",
                show_edges=False,
                scalar_bar_args={"title": name, **SCALAR_BAR},
            )
        pts, labels = ring_label_points(states)
        plotter.add_point_labels(pts, labels, font_size=12, point_size=6, always_visible=True)
        t = res.time
        i = len(t) - 1 if time is None else int(np.argmin(np.abs(t - time)))
        plotter.add_text(
            f"{res.attrs.get('preset')} main-bearing rings, t = {t[i]:.4f} s, scale x{scale:.3g}", font_size=10
        )
        return save_screenshot(plotter, path)
    finally:
        plotter.close()


def show_rings(
    res, time: float | None = None, scale: float | None = None, field: str = "displacement", rebuild: bool = False
) -> bool:
    """Interactive window if a display exists; False (nothing done) when headless."""
    if not os.environ.get("DISPLAY"):
        return False
    pv = _pyvista()
    states = ring_states(res, time, stress=field == "von_mises", rebuild=rebuild)
    scale = auto_scale(states) if scale is None else float(scale)
    plotter = pv.Plotter()
    for st in states:
        plotter.add_mesh(_polydata(st, scale, field), cmap="viridis")
    plotter.show()
    return True


def write_pvd(res, directory, every: int = 10, field: str = "displacement", notice=None, rebuild: bool = False) -> Path:
    """Write the ring surfaces of every ``every``-th record as VTU files (point data
    ``displacement`` [m] and |u| [µm], undeformed coordinates: warp in ParaView) and a
    ParaView PVD collection ``rings.pvd`` with the simulation times. Atomic writes.
    ``notice(frames, bytes_estimate)`` is called once, after the first frame, with
    the number of frames and an upper bound of the series' size: the first frame's
    uncompressed arrays (points, point data, cells) times the frames; the files
    are zlib-compressed VTU, so they come out smaller."""
    if every < 1:
        raise InputError(f"every = {every!r} must be >= 1")
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    bodies = ring_bodies(res, stress=field == "von_mises", rebuild=rebuild)
    t = res.time
    entries = []
    frames = range(0, len(t), every)
    frame_bytes = 0
    for i in frames:
        if notice is not None and i == every:
            notice(len(frames), len(frames) * frame_bytes)
        for st in ring_states(res, float(t[i]), stress=field == "von_mises", bodies=bodies):
            poly = _polydata(st, 0.0, field)
            for name in list(poly.point_data.keys()):  # ASCII array names in files for other tools
                poly.point_data[name.replace("µm", "um")] = poly.point_data.pop(name)
            used = np.unique(st.tris[:, :3])
            poly.point_data["displacement"] = st.displacement[used]
            fname = f"{st.label}_row{st.row}_{i:06d}.vtu"
            grid = poly.cast_to_unstructured_grid()
            if i == 0:
                frame_bytes += (
                    grid.points.nbytes
                    + sum(grid.point_data[k].nbytes for k in grid.point_data.keys())
                    + grid.cells.nbytes
                    + grid.celltypes.nbytes
                )
            with atomic_path(d / fname) as tmp:
                grid.save(str(tmp), binary=True)
            entries.append((float(t[i]), f"{st.label}_row{st.row}", fname))
    parts = sorted({e[1] for e in entries})
    lines = ['<?xml version="1.0"?>', '<VTKFile type="Collection" version="0.1">', "  <Collection>"]
    for time_s, part, fname in entries:
        lines.append(f'    <DataSet timestep="{time_s:.9g}" part="{parts.index(part)}" file="{fname}"/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    path = d / "rings.pvd"
    atomic_write_text(path, "\n".join(lines))
    return path
