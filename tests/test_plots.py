"""Every plot type rendered headless (Agg / pyvista off-screen): the PNG is not blank
(pixel variance) and, where cheap, one plotted value is checked against its data.

Synthetic inputs with known values are used where a real run would be slow (the
flexible model's ball loads and ring deflections, an EHL solution); the time-history
plots use a 20 ms rigid rv40e run."""

from __future__ import annotations

import os
from types import SimpleNamespace

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")


def _not_blank(path, min_var=1e-3):
    import matplotlib.image as mpimg

    img = mpimg.imread(path)[..., :3]
    assert img.size > 1000 and float(img.var()) > min_var, f"{path} looks blank (variance {img.var():.2g})"
    return img


@pytest.fixture
def captured(monkeypatch):
    """Keep the figures the plot functions save (they close them after saving)."""
    import flexrv.viz.compare_plots as cp
    import flexrv.viz.plots as vp

    figs = []
    orig = vp._save

    def keep(fig, path):
        figs.append(fig)
        from flexrv.cache import atomic_path

        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=60, format="png")
        return path

    monkeypatch.setattr(vp, "_save", keep)
    monkeypatch.setattr(cp, "_save", keep)
    yield figs
    import matplotlib.pyplot as plt

    for f in figs:
        plt.close(f)
    assert orig is not None


@pytest.fixture(scope="module")
def run():
    from flexrv.simulation import Simulation

    return Simulation("rv40e").run(t_end=0.02, dt=1e-4)


def test_te_and_speed_plots(run, tmp_path, captured):
    from flexrv.viz.plots import plot_speeds, plot_te

    _not_blank(plot_te(run, tmp_path / "te.png"))
    line = captured[-1].axes[0].lines[0]
    assert np.allclose(line.get_ydata(), run["te"].values)
    _not_blank(plot_speeds(run, tmp_path / "speeds.png"))


def test_pin_force_map_shows_every_disc_aligned(run, tmp_path, captured):
    """One map per disc (both discs of rv40e), pin angle in degrees, map and line panels of
    equal width (aligned time axes); the line panel plots each disc's largest pin force."""
    from flexrv.viz.plots import plot_pin_forces

    _not_blank(plot_pin_forces(run, tmp_path / "pins.png"))
    fig = captured[-1]
    f = run["pin_force"].values
    maps = [ax for ax in fig.axes if (ax.collections or ax.images) and "pin angle" in ax.get_ylabel()]
    assert len(maps) == f.shape[1] == 2
    line_ax = [ax for ax in fig.axes if "largest pin force" in ax.get_ylabel()][0]
    widths = {round(ax.get_position().width, 4) for ax in maps + [line_ax]}
    lefts = {round(ax.get_position().x0, 4) for ax in maps + [line_ax]}
    assert len(widths) == 1 and len(lefts) == 1
    assert np.allclose(line_ax.lines[1].get_ydata(), f[:, 1, :].max(axis=-1))


def test_te_spectrum_labels_in_words_with_window_and_resolution(tmp_path, captured):
    """A 2 arcsec sine at the rv40e cycloid-mesh frequency (390 Hz at 1215 r/min, :cite:`seed002`):
    the plotted peak is 2 +- 0.1 arcsec; every characteristic line is numbered and named in
    words (not snake_case) with its frequency in the key; the title states
    the window (0.3 s) and resolution (1/0.3 s); the log axis spans 4 decades, not 1e-9..1."""
    import xarray as xr

    from flexrv.design import load
    from flexrv.post.results import Results
    from flexrv.viz.plots import plot_te_spectrum

    red = load("rv40e")
    w_in = red.operating.input_speed
    t = np.arange(0, 0.6, 1e-4)
    ds = xr.Dataset(
        {"te": ("time", 2.0 * np.sin(2 * np.pi * 390.0 * t)), "theta_in": ("time", w_in * t)}, coords={"time": t}
    )
    ds.attrs.update(
        {"steady_start_s": 0.3, "steady_end_s": float(t[-1]), "preset": "rv40e", "model": "rigid", "steady": 1}
    )
    _not_blank(plot_te_spectrum(Results(ds, red), tmp_path / "spec.png"))
    ax = captured[-1].axes[0]
    y = ax.lines[0].get_ydata()
    assert y.max() == pytest.approx(2.0, abs=0.1)
    x = ax.lines[0].get_xdata()
    assert x[np.argmax(y)] == pytest.approx(390.0, abs=4.0)
    texts = [tx.get_text() for tx in ax.texts]
    key = "\n".join(texts).splitlines()
    assert any(line.split(None, 1)[1].startswith("cycloid mesh 390") for line in key if " " in line)
    assert not any("_" in tx for tx in texts)
    numbers = [tx.get_text() for tx in ax.texts if tx.get_text().isdigit()]
    assert numbers == [str(k) for k in range(1, len(numbers) + 1)] and len(numbers) >= 3  # each mark numbered
    assert "window 0.3 s" in ax.get_title() and "resolution 3.33 Hz" in ax.get_title()
    lo, hi = ax.get_ylim()
    assert hi / lo == pytest.approx(3e4, rel=1e-6)


def test_log_axis_labels_plain_text_the_same_ticks_as_matplotlib():
    """The spectrum's log axis labels the same ticks with the same values as matplotlib's default
    formatter (LogFormatterSciNotation, mathtext), written as plain text with Unicode
    superscripts: 10^-3 -> "10⁻³", 2 x 10^-3 -> "2×10⁻³"; no label needs the mathtext parser
    (no "$"). Reference: the default formatter's labels on the same axis, converted by hand."""
    from matplotlib.ticker import LogFormatterSciNotation

    from flexrv.viz.plots import _plt, plain_log_label, spectrum_axis

    assert plain_log_label(r"$\mathdefault{10^{-3}}$") == "10\u207b\u00b3"
    assert plain_log_label(r"$\mathdefault{2\times10^{-3}}$") == "2\u00d710\u207b\u00b3"
    assert plain_log_label(r"$\mathdefault{10^{12}}$") == "10\u00b9\u00b2"
    assert plain_log_label("") == "" and plain_log_label(r"$\mathdefault{0}$") == "0"
    assert plain_log_label(r"$x^{\alpha}$") == r"$x^{\alpha}$"  # not a log label: unchanged
    expected = {
        "-": "\u207b",
        **{str(d): "\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079"[d] for d in range(10)},
    }
    for span in (4.0, 0.6):  # four decades: decades labelled; less than one: minor ticks labelled too
        fig, ax = _plt().subplots(figsize=(6, 3))
        f = np.linspace(0.0, 100.0, 201)
        spectrum_axis(ax, f, 1e-3 * (1.0 + np.sin(f)) + 1e-4, {}, 1.0, decades=span)
        fig.canvas.draw()
        for minor in (False, True):
            ticks = ax.yaxis.get_minorticklocs() if minor else ax.yaxis.get_majorticklocs()
            shown = [t.get_text() for t in ax.yaxis.get_ticklabels(minor=minor)]
            default = LogFormatterSciNotation(10.0, labelOnlyBase=False)
            default.set_axis(ax.yaxis)
            default.set_locs(ticks)
            for label, tick in zip(shown, ticks):
                ref = default(tick)
                assert "$" not in label
                if ref:
                    body = ref[len(r"$\mathdefault{") : -2].replace(r"\times", "\u00d7")
                    head, _, exp = body.partition("^{")
                    assert label == head + "".join(expected[c] for c in exp.rstrip("}"))
                else:
                    assert label == ""
        assert any(t.get_text() for t in ax.yaxis.get_ticklabels())


def test_plot_figures_are_not_kept_by_pyplot():
    """The plots' figures (``_plt()``) live on their own Agg canvas: pyplot's figure manager
    holds none of them (a loop of runs frees each figure with its last reference), and they
    save PNGs."""
    import io

    import matplotlib.pyplot as plt

    from flexrv.viz.plots import _plt

    before = plt.get_fignums()
    fig, axes = _plt().subplots(2, 1, figsize=(4, 3), sharex=True)
    axes[0].plot([0, 1], [0, 1])
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=50)
    assert buf.getvalue()[:8] == b"\x89PNG\r\n\x1a\n"
    assert plt.get_fignums() == before
    assert _plt().figure(figsize=(2, 2)).canvas.get_renderer() is not None


def test_hysteresis_plot_marks_fit_range_lost_motion_hysteresis(tmp_path, captured):
    """Bilinear loop (k = 100 N m/arcmin, band +-0.5 arcmin) with a 0.2 arcmin hysteresis: the
    legend states the figures; the lost-motion marker spans the figures' two angles."""
    from flexrv.post.stiffness import evaluate_stiffness_test
    from flexrv.units import ARCMIN_PER_RAD
    from flexrv.viz.plots import plot_hysteresis

    t = np.linspace(0, 4, 4001)
    torque = np.interp(t, [0, 1, 3, 4], [0, 400.0, -400.0, 0])
    shift = np.where((t > 1) & (t < 3), 0.1, -0.1) * (t > 1)
    angle_arcmin = torque / 100.0 + np.sign(torque) * 0.5 + shift
    fig = evaluate_stiffness_test(t, torque, angle_arcmin / ARCMIN_PER_RAD, (0.0, 1.0, 3.0, 4.0))
    _not_blank(plot_hysteresis(angle_arcmin, torque, tmp_path / "loop.png", figures=fig))
    ax = captured[-1].axes[0]
    labels = [ln.get_label() for ln in ax.lines]
    assert any(lab.startswith("lost motion") for lab in labels) and any(lab.startswith("hysteresis") for lab in labels)
    assert any("rigidity fit" in lab and f"{fig.rigidity_Nm_per_arcmin:.4g}" in lab for lab in labels)
    lm = [ln for ln in ax.lines if ln.get_label().startswith("lost motion")][0]
    assert np.ptp(lm.get_xdata()) == pytest.approx(fig.lost_motion_arcmin)
    assert len(ax.patches) >= 2  # the two shaded fit bands


def _synthetic_flexible(red, n_ball=20, rows=2):
    import xarray as xr

    from flexrv.post.results import Results

    t = np.arange(0, 0.3, 1e-4)
    ball = np.zeros((len(t), rows, n_ball))
    ball[:, :, 5] = 150.0  # ball 6 (pocket angle 90 deg) carries 150 N
    ds = xr.Dataset(
        {
            "ball_load_inner": (("time", "bearing_row", "ball"), ball),
            "ring_deformation_outer": (("time", "bearing_row"), np.full((len(t), rows), 0.8e-6)),
            "te": ("time", 0.5 * np.sin(2 * np.pi * 100 * t)),
            "theta_in": ("time", red.operating.input_speed * t),
        },
        coords={"time": t},
    )
    ds.attrs.update({"steady_start_s": 0.1, "steady_end_s": float(t[-1]), "preset": red.name, "model": "flexible"})
    return Results(ds, red)


def test_compare_plots(tmp_path, captured):
    """Ball loads over the pocket angle (the 150 N ball at 90 deg), ring deflection in µm
    (0.8), TE overlay and spectra render non-blank."""
    from flexrv.design import load
    from flexrv.viz import compare_plots as cp

    red = load("rv40e")
    res = _synthetic_flexible(red)
    _not_blank(cp.plot_ball_loads(res, tmp_path / "balls.png"))
    ax = captured[-1].axes[0]
    x, y = ax.lines[1].get_xdata(), ax.lines[1].get_ydata()
    assert x[np.argmax(y)] == pytest.approx(90.0) and "angle" in ax.get_xlabel()
    _not_blank(cp.plot_ring_deformation(res, tmp_path / "ring.png"))
    ax = captured[-1].axes[0]
    assert ax.lines[0].get_ydata()[0] == pytest.approx(0.8) and "µm" in ax.get_ylabel()
    _not_blank(cp.plot_te_overlay(res, res, tmp_path / "overlay.png"))
    _not_blank(cp.plot_te_spectra(res, res, tmp_path / "spectra.png"))
    ax = captured[-1].axes[0]
    assert ax.get_ylim()[1] / ax.get_ylim()[0] == pytest.approx(3e4, rel=1e-6)


def test_ehl_maps_equal_aspect_and_micrometres(tmp_path):
    """An 8:1 elliptic film/pressure field: both maps drawn with equal aspect, labels in µm,
    the maps wide (the contact's long axis horizontal: each map at least 4x wider than high
    on the page) and no two tick labels of a map overlapping; the PNG is not blank."""
    import matplotlib.pyplot as plt

    from flexrv.viz.ehl_plots import ehl_figure, plot_ehl_solution

    x = np.linspace(-2e-4, 2e-4, 41)
    y = np.linspace(-1.6e-3, 1.6e-3, 81)
    X, Y = np.meshgrid(x, y, indexing="ij")
    r2 = (X / 1e-4) ** 2 + (Y / 8e-4) ** 2
    p = 1.5e9 * np.sqrt(np.clip(1 - r2, 0, None))
    h = 0.2e-6 + 1e-6 * np.clip(r2 - 1, 0, None)
    result = SimpleNamespace(
        x=x,
        y=y,
        pressure=p,
        film=h,
        h_central=0.2e-6,
        h_min=0.18e-6,
        p_max=1.5e9,
        hertz_pressure=1.5e9,
        hertz_a=8e-4,
        hertz_b=1e-4,
    )
    fig = ehl_figure(result)
    maps = [ax for ax in fig.axes if ax.get_title().startswith(("pressure", "film thickness"))]
    assert len(maps) == 2 and all(ax.get_aspect() == 1.0 for ax in maps)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in maps:
        box = ax.get_window_extent(renderer)
        assert box.width > 4 * box.height, (box.width, box.height)
        for ticks in (ax.get_xticklabels(), ax.get_yticklabels()):
            boxes = [t.get_window_extent(renderer) for t in ticks if t.get_text() and t.get_visible()]
            assert len(boxes) >= 3
            assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
    labels = " ".join(ax.get_ylabel() for ax in fig.axes)
    assert "µm" in labels and "um]" not in labels
    plt.close(fig)
    _not_blank(plot_ehl_solution(result, tmp_path / "ehl.png"))


def _tet10_surface():
    """One quadratic tetrahedron: its 10 nodes (VTK order) and its 4 six-node surface triangles."""
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0],
                      [0, 0, 0.5], [0.5, 0, 0.5], [0, 0.5, 0.5]], float)  # fmt: skip
    tris = np.array([[0, 1, 2, 4, 5, 6], [0, 1, 3, 4, 8, 7], [0, 2, 3, 6, 9, 7], [1, 2, 3, 5, 9, 8]])
    return nodes, tris


def test_mode_png_offscreen(tmp_path):
    """pyvista off-screen render of a warped tetrahedron surface is not blank."""
    pytest.importorskip("pyvista")
    from flexrv.viz.modes import render_mode_png

    nodes, tris = _tet10_surface()
    disp = np.zeros_like(nodes)
    disp[3] = [0.1, 0.1, 0.2]
    _not_blank(render_mode_png(tmp_path / "mode.png", nodes, tris, disp, title="test mode"), min_var=1e-4)


def test_hysteresis_rebound_marked_near_zero_only():
    """A bilinear loop with a decaying 0.1 arcmin oscillation (the rebound after crossing the
    clearance) added just after each torque reversal: :func:`rebound_mask` flags the ringing
    samples near T = 0 and nothing on the loaded parts of the loop; the same loop without
    the oscillation has nothing flagged."""
    from flexrv.viz.plots import rebound_mask

    t = np.linspace(0, 4, 8001)
    torque = np.interp(t, [0, 1, 3, 4], [0, 400.0, -400.0, 0])
    clean = torque / 100.0 + np.sign(torque) * 0.5
    crossing = t > 2.0
    ring = np.where(crossing, 0.1 * np.exp(-(t - 2.0) / 0.02) * np.sin(2 * np.pi * (t - 2.0) / 0.004), 0.0)
    mask = rebound_mask(clean + ring, torque, 100.0)
    assert mask[(t > 2.0) & (t < 2.02)].mean() > 0.9  # the first ring-down time constant
    assert not mask[np.abs(torque) > 150.0].any()
    assert not rebound_mask(clean, torque, 100.0).any()


def _te_dataset(crank_revolutions: int = 3, per_rev: int = 400):
    """A synthetic quasi-static TE record: pin-mesh ripple (39 per crank revolution) whose
    amplitude is largest in the second crank revolution."""
    import json

    import xarray as xr

    n = crank_revolutions * per_rev
    rev_out = np.arange(n) / (per_rev * 40.0)  # output revolutions: 40 crank revolutions per output revolution
    crank = rev_out * 40.0
    amp = np.where((crank >= 1) & (crank < 2), 0.3, 0.1)
    te = -160.0 + amp * np.sin(2 * np.pi * 39 * crank)
    ds = xr.Dataset(
        {
            "te": ("position", te),
            "te_no_load": ("position", -40.0 + 0.05 * np.sin(2 * np.pi * 39 * crank)),
            "output_revolutions": ("position", rev_out),
        }
    )
    ds.attrs.update(
        {
            "preset": "rv40e",
            "torque_Nm": 412.0,
            "orders": json.dumps({"crank rotation": 40.0, "cycloid mesh": 1560.0, "first-stage mesh": 1280.0}),
        }
    )
    return ds


def test_te_curve_envelope_and_one_crank_revolution_zoom(tmp_path, monkeypatch):
    """Three crank revolutions: two panels; the upper spans the whole record (envelope), the
    lower exactly one crank revolution (9 deg of output), the one with the largest TE range
    (the second), at full resolution; the legend states p-p and mean."""
    import flexrv.viz.te_plots as tp

    figs = []
    monkeypatch.setattr(tp, "_save", lambda fig, path: figs.append(fig) or path)
    tp.plot_te_curve(_te_dataset(), tmp_path / "te.png")
    fig = figs[0]
    top, bottom = fig.axes[:2]
    a, b = bottom.get_xlim()
    assert b - a == pytest.approx(9.0, rel=1e-3) and a == pytest.approx(9.0, abs=0.05)
    assert len(bottom.lines[0].get_xdata()) >= 399
    assert top.get_xlim()[1] == pytest.approx(27.0, abs=0.1)
    legend = " ".join(t.get_text() for t in top.get_legend().get_texts())
    assert "p-p 0.6" in legend and "mean -160" in legend
    import matplotlib.pyplot as plt

    plt.close(fig)
    monkeypatch.undo()
    _not_blank(tp.plot_te_curve(_te_dataset(), tmp_path / "te.png"))


def test_te_order_spectrum_names_every_line_with_its_order(tmp_path, monkeypatch):
    """Lines at a mesh order, a crank harmonic and a crank sideband of the first-stage mesh
    (1280 + 2 x 40 = 1360): every line is named (no "-") and the key gives its order."""
    from flexrv.post.te import order_spectrum, spectrum_lines

    n = 12480
    x = np.arange(n) / n
    te = 0.06 * np.sin(2 * np.pi * 1560 * x) + 0.05 * np.sin(2 * np.pi * 240 * x) + 0.02 * np.sin(2 * np.pi * 1360 * x)
    orders = {"crank rotation": 40.0, "cycloid mesh": 1560.0, "first-stage mesh": 1280.0}
    order, amp = order_spectrum(te, 1.0)
    lines = spectrum_lines(order, amp, orders, count=3)
    labels = {round(line["order"]): line["label"] for line in lines}
    assert labels == {1560: "cycloid mesh", 240: "6 x crank rotation", 1360: "first-stage mesh + 2 x crank rotation"}
    import xarray as xr

    import flexrv.viz.te_plots as tp

    figs = []
    monkeypatch.setattr(tp, "_save", lambda fig, path: figs.append(fig) or path)
    ds = xr.Dataset({"te": ("position", te)}, attrs={"preset": "rv40e"})
    summary = {"output_revolutions": 1.0, "spectrum_lines": lines, "spectral_resolution_orders": 1.0}
    tp.plot_te_spectrum(ds, summary, tmp_path / "s.png")
    key = " ".join(t.get_text() for t in figs[0].axes[0].texts)
    for line in lines:
        assert line["label"] in key and f"order {line['order']:.5g}" in key


def test_part_modes_render_free_and_constrained(tmp_path):
    """render_part_modes writes one PNG per free-free and per constrained mode, named by kind."""
    pytest.importorskip("pyvista")
    from flexrv.viz.modes import render_part_modes

    nodes, tris = _tet10_surface()
    modes = np.zeros((30, 2))
    modes[9:12, 0] = [0.1, 0.1, 0.2]
    modes[3:6, 1] = [0.2, 0.0, 0.1]
    pm = SimpleNamespace(
        mesh=SimpleNamespace(nodes=nodes, tris=tris),
        free_hz=np.array([100.0, 200.0]),
        free_modes=modes,
        constrained_hz=np.array([300.0]),
        constrained_modes=modes[:, :1],
        interfaces=["fit"],
    )
    files = render_part_modes(tmp_path, "ring", pm)
    assert [p.name for p in files] == ["ring_free_mode01.png", "ring_free_mode02.png", "ring_constrained_mode01.png"]
    for p in files:
        _not_blank(p, min_var=1e-4)


def test_force_map_image_draws_the_same_pixels_as_the_quad_mesh():
    """On a uniform grid the force map is one image (cheap) that renders the same pixels as
    ``pcolormesh(shading="nearest")`` (reference: the quad mesh of the same data, same axes
    limits; a load zone sweeping around the pins as in a run: at most 0.5 % of the pixels
    differ by more than 8 of 255 levels, where the two sample a cell edge differently); on a
    non-uniform grid it stays a quad mesh."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flexrv.viz.plots import _force_map

    t = np.arange(3000) * 1e-4
    angle = np.arange(40) * 9.0
    # a load zone sweeping around the pins, as in a run: cos^2 lobes over a quarter of the pins
    phase = np.radians(angle[:, None]) - 2.0 * np.pi * 7.0 * t[None, :]
    c = 500.0 * np.clip(np.cos(2.0 * phase), 0.0, None) ** 2 * (np.cos(phase) > 0)
    pixels = []
    for image in (True, False):
        fig, ax = plt.subplots(figsize=(6, 3), dpi=100)
        if image:
            artist = _force_map(ax, t, angle, c, 500.0)
            assert artist in ax.images
        else:
            ax.pcolormesh(t, angle, c, shading="nearest", cmap="viridis", vmin=0.0, vmax=500.0)
        fig.canvas.draw()
        pixels.append((np.asarray(fig.canvas.buffer_rgba())[..., :3], ax.get_xlim(), ax.get_ylim()))
        plt.close(fig)
    (a, xa, ya), (b, xb, yb) = pixels
    assert np.allclose(xa, xb) and np.allclose(ya, yb)
    assert np.mean(np.any(np.abs(a.astype(int) - b.astype(int)) > 8, axis=-1)) < 5e-3
    fig, ax = plt.subplots()
    assert _force_map(ax, t**2, angle, c, 500.0) in ax.collections
    plt.close(fig)


def test_save_draws_a_tight_layout_figure_once_with_the_same_pixels(tmp_path, monkeypatch):
    """A figure laid out by ``tight_layout`` is drawn once by ``_save`` (matplotlib's ``savefig``
    draws it twice while the figure keeps tight_layout's placeholder layout engine), and its PNG
    has exactly the pixels of the same figure saved by plain ``savefig`` (reference: matplotlib
    itself, the placeholder kept)."""
    from matplotlib.figure import Figure
    from PIL import Image

    from flexrv.viz.plots import FIGURE_DPI, _plt, _save

    def figure():
        fig, axes = _plt().subplots(2, 1, figsize=(5, 4))
        t = np.linspace(0.0, 1.0, 500)
        axes[0].plot(t, np.sin(20 * t), label="a long legend entry")
        axes[0].legend(loc="best")
        axes[1].semilogy(t, 1e-3 + t**2)
        axes[1].set_xlabel("time [s]")
        fig.suptitle("a title")
        fig.tight_layout()
        return fig

    reference = figure()
    reference.savefig(tmp_path / "reference.png", dpi=FIGURE_DPI, format="png")
    draws = []
    original = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(1) or original(self, renderer))
    _save(figure(), tmp_path / "saved.png")
    assert len(draws) == 1
    a = np.asarray(Image.open(tmp_path / "reference.png"))
    b = np.asarray(Image.open(tmp_path / "saved.png"))
    assert a.shape == b.shape and np.array_equal(a, b)
