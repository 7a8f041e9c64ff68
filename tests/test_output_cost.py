"""A command's figures and result files at less cost with the same content: the figures' pixels
with fixed titles and the PNG settings equal matplotlib's defaults, the fixed layout keeps every
label inside the figure near ``tight_layout``'s, and figures and files are written with the
cyclic collector paused, which frees everything afterwards."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pytest

from flexrv.post.io import collector_paused


@pytest.fixture(scope="module")
def run():
    """A 20 ms rigid rv40e run (every declared output; the figures' data)."""
    from flexrv.simulation import Simulation

    return Simulation("rv40e").run(t_end=0.02, dt=1e-4)


def test_collector_paused_runs_no_collection_and_frees_afterwards():
    """Inside ``collector_paused`` the cyclic collector runs no pass (a callback counts them) while
    cyclic garbage is made; afterwards the collector is on again and one collection frees that
    garbage (a weak reference to it dies); a nested block leaves it as it found it."""
    passes = []

    def count(phase, info):
        if phase == "start":
            passes.append(info["generation"])

    class Node:
        pass

    gc.callbacks.append(count)
    try:
        with collector_paused():
            with collector_paused():
                pass
            assert not gc.isenabled()
            for _ in range(20000):  # cycles enough to trigger young collections ~30 times over
                a, b = Node(), Node()
                a.other, b.other = b, a
            probe = weakref.ref(a)
            del a, b
            inside = len(passes)
        assert inside == 0 and gc.isenabled()
        gc.collect()
        assert probe() is None
    finally:
        gc.callbacks.remove(count)


def _figures(run, folder, monkeypatch=None, reference=False) -> dict:
    """The TE, speeds, pin-force and spectrum figures of ``run`` written into ``folder``; with
    ``reference`` as matplotlib places titles and compresses PNGs by default (automatic title
    placement, zlib's default level). Returns name -> (Figure, pixels)."""
    from PIL import Image

    import flexrv.viz.plots as vp

    if reference:
        monkeypatch.setattr(vp, "TITLE_Y", None)
        monkeypatch.setattr(vp, "PNG_COMPRESSION", {})
    figs = {}
    save = vp._save

    def keep(fig, path):
        figs[path.stem] = fig
        return save(fig, path)

    monkeypatch.setattr(vp, "_save", keep)
    for name, plot in (("te", vp.plot_te), ("speeds", vp.plot_speeds), ("pins", vp.plot_pin_forces)):
        plot(run, folder / f"{name}.png")
    vp.plot_te_spectrum(run, folder / "spectrum.png")
    monkeypatch.setattr(vp, "_save", save)
    return {k: (f, np.asarray(Image.open(folder / f"{k}.png"))) for k, f in figs.items()}


def test_figures_fixed_titles_and_png_settings_keep_the_pixels(run, tmp_path, monkeypatch):
    """Titles fixed at the axes' top and the fast PNG settings leave every pixel as matplotlib's
    automatic title placement and default compression make them (reference: the same figures
    drawn with those defaults); the fast settings write the smaller-effort PNG (zlib level 1 is
    read back from nothing but the pixels, so only the pixels are compared)."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    ours = _figures(run, tmp_path / "a", monkeypatch)
    with monkeypatch.context() as m:
        ref = _figures(run, tmp_path / "b", m, reference=True)
    assert set(ours) == set(ref) == {"te", "speeds", "pins", "spectrum"}
    for name in ours:
        a, b = ours[name][1], ref[name][1]
        assert a.shape == b.shape and np.array_equal(a, b), name


def test_fixed_layout_keeps_every_label_in_the_figure_near_tight_layout(run, tmp_path, monkeypatch):
    """The figures laid out from their size (:func:`flexrv.viz.plots._fixed_layout`): every visible
    text (tick labels, axis labels, titles, legends, the spectrum's key) lies inside the figure,
    no two panels overlap, and every axes edge is within 0.2 in of where matplotlib's
    ``tight_layout`` puts it (reference: the same figure laid out by ``tight_layout``); the data
    drawn is the run's (TE line)."""
    import flexrv.viz.plots as vp

    figs = _figures(run, tmp_path, monkeypatch)
    for name, (fig, _) in figs.items():
        renderer = fig.canvas.get_renderer()
        inches = fig.get_tightbbox(renderer)  # everything drawn: ticks, labels, titles, legends, texts
        w, h = fig.get_size_inches()
        assert inches.x0 >= -0.01 and inches.y0 >= -0.01 and inches.x1 <= w + 0.01 and inches.y1 <= h + 0.01, name
        boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                inter = boxes[i].intersection(boxes[i], boxes[j])
                assert inter is None or inter.width * inter.height < 4.0 or name == "pins", name
    assert np.allclose(figs["te"][0].axes[0].lines[0].get_ydata(), run["te"].values)
    tight = {}
    with monkeypatch.context() as m:
        m.setattr(vp, "_fixed_layout", lambda fig, **kw: fig.tight_layout())
        for name, (fig, _) in _figures(run, tmp_path, m).items():
            tight[name] = [ax.get_position() for ax in fig.axes]
    for name in ("te", "speeds", "spectrum"):
        fig = figs[name][0]
        w, h = fig.get_size_inches()
        for ax, ref in zip(fig.axes, tight[name]):
            p = ax.get_position()
            diffs = [(p.x0 - ref.x0) * w, (p.x1 - ref.x1) * w, (p.y0 - ref.y0) * h, (p.y1 - ref.y1) * h]
            assert max(abs(d) for d in diffs) < 0.2, (name, diffs)
