"""Matplotlib plots of simulation results (Agg backend, files only)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from flexrv.post.results import Results

#: resolution of the PNGs [dots per inch]
FIGURE_DPI = 110

#: zlib settings of the PNGs (Pillow's ``compress_level`` and ``compress_type``): the fastest level
#: with run-length matching (``zlib.Z_RLE`` = 3), suited to plots' long runs of one colour; the
#: pixels are those of the default settings (the format is lossless). On the four figures of a
#: run: ~0.66 of the default's encoding time for ~1.09 of its file size.
PNG_COMPRESSION = {"compress_level": 1, "compress_type": 3}


class _AggFigures:
    """The part of ``matplotlib.pyplot`` the plots use (``figure``, ``subplots``, ``close``),
    without pyplot: each figure is a :class:`matplotlib.figure.Figure` on its own Agg canvas,
    drawn only into files. Nothing is registered with pyplot's figure manager, so no figure
    stays alive after its last reference and no GUI backend is chosen or imported. A figure is
    made at the resolution it is saved at (:data:`FIGURE_DPI`), so the text laid out for
    ``tight_layout`` is reused by the drawing of the PNG instead of being laid out again at
    another resolution."""

    @staticmethod
    def figure(figsize=None, **kwargs):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        kwargs.setdefault("dpi", FIGURE_DPI)
        fig = Figure(figsize=figsize, **kwargs)
        FigureCanvasAgg(fig)
        return fig

    @classmethod
    def subplots(
        cls, nrows=1, ncols=1, *, figsize=None, sharex=False, sharey=False, squeeze=True, gridspec_kw=None, **kwargs
    ):
        fig = cls.figure(figsize=figsize, **kwargs)
        axes = fig.subplots(nrows, ncols, sharex=sharex, sharey=sharey, squeeze=squeeze, gridspec_kw=gridspec_kw)
        return fig, axes

    @staticmethod
    def close(fig=None) -> None:
        """Nothing to release: the figure is not registered anywhere."""


def _plt() -> _AggFigures:
    """The figure factory of the plots (:class:`_AggFigures`)."""
    return _AggFigures()


def _save(fig, path: Path) -> Path:
    """Write ``fig`` as a PNG at :data:`FIGURE_DPI` (zlib settings :data:`PNG_COMPRESSION`),
    atomically. A figure laid out by
    ``tight_layout`` keeps a placeholder layout engine, for which matplotlib's ``savefig``
    draws the whole figure once more before the drawing it saves (a pass that only a
    constrained layout needs); the placeholder is dropped first, so the figure is drawn once
    (the same pixels)."""
    from matplotlib.layout_engine import PlaceHolderLayoutEngine

    from flexrv.cache import atomic_path

    if isinstance(fig.get_layout_engine(), PlaceHolderLayoutEngine):
        fig.set_layout_engine(None)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=FIGURE_DPI, format="png", pil_kwargs=dict(PNG_COMPRESSION))
    return path


#: height of an axes title (axes fraction, plus matplotlib's title pad): the top of the axes.
#: Given explicitly, it fixes the title there; left to matplotlib, the title's place is found
#: again on every drawing by measuring the y axis's ticks and labels (a sixth of the drawing of
#: these figures) to lift it above top x tick labels or a y offset text under it, which the
#: figures given it do not have (x ticks at the bottom; a y offset text sits at the left corner,
#: clear of a centred title)
TITLE_Y = 1.0

#: margins [in] of a figure laid out by :func:`_fixed_layout`: room for y tick labels of up to
#: seven characters and the y label (10 pt), x tick labels and the x label (10 pt), an axes title
#: (12 pt) above; the edge beside labelled sides
LAYOUT_MARGINS_IN = {"left": 0.9, "bottom": 0.58, "title": 0.36, "edge": 0.15}


def _fixed_layout(fig, *, left=None, right=None, bottom=None, top=None, gap=None) -> None:
    """Place the subplots of ``fig`` with margins and the gap between rows given in inches
    (default :data:`LAYOUT_MARGINS_IN`, no title), so the layout follows from the figure's size:
    the same room for the labels on every figure of a kind, computed without drawing.
    matplotlib's ``tight_layout`` measures every tick label and title first, which costs an
    extra pass over the ticks (a fifth to a quarter of such a figure's drawing)."""
    m = LAYOUT_MARGINS_IN
    w, h = fig.get_size_inches()
    left = m["left"] if left is None else left
    right = m["edge"] if right is None else right
    bottom = m["bottom"] if bottom is None else bottom
    top = m["edge"] if top is None else top
    kw = {}
    if gap is not None:  # matplotlib's hspace: the gap over the mean height of a row's axes
        rows = fig.axes[0].get_subplotspec().get_gridspec().nrows if fig.axes else 1
        kw["hspace"] = gap * rows / max(h - top - bottom - (rows - 1) * gap, 1e-9)
    fig.subplots_adjust(left=left / w, right=1.0 - right / w, bottom=bottom / h, top=1.0 - top / h, **kw)


def plot_te(res, path) -> Path:
    """TE(t) [arcsec] with the steady window shaded."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(res.time, res["te"].values, lw=0.8)
    t0, t1 = res.steady_window()
    ax.axvspan(t0, t1, color="0.9", zorder=0, label="steady window")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("TE [arcsec]")
    ax.set_title(f"Transmission error, {res.attrs.get('preset')} ({res.attrs.get('model')})", y=TITLE_Y)
    ax.legend(loc="best")
    _fixed_layout(fig, top=LAYOUT_MARGINS_IN["title"])
    return _save(fig, Path(path))


def plot_speeds(res, path) -> Path:
    """Input, output, crank and disc speeds [r/min]."""
    plt = _plt()
    rpm = 60.0 / (2 * np.pi)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    t = res.time
    axes[0].plot(t, res["omega_in"].values * rpm, label="input")
    axes[0].plot(t, res["crank_speed"].values[:, 0] * rpm, label="crank 0 (absolute)", lw=0.8)
    axes[0].set_ylabel("speed [r/min]")
    axes[0].legend(loc="best")
    axes[1].plot(t, res["omega_out"].values * rpm, lw=0.8, label="output")
    axes[1].plot(t, res["omega_in"].values * rpm / res.attrs["ratio"], "--", lw=0.8, label="input / i")
    axes[1].set_ylabel("speed [r/min]")
    axes[1].set_xlabel("time [s]")
    axes[1].legend(loc="best")
    _fixed_layout(fig, gap=0.2)
    return _save(fig, Path(path))


def _force_map(ax, x: np.ndarray, y: np.ndarray, c: np.ndarray, vmax: float):
    """Map of ``c`` (len(y), len(x)) over the grid x, y, each value a cell centred on its grid
    point (``pcolormesh(..., shading="nearest")``). On uniform grids (recorded time steps, pin
    angles) drawn as one image, which looks the same and costs a fraction of ~10^5 quadrilaterals."""
    kw = {"cmap": "viridis", "vmin": 0.0, "vmax": vmax}
    if len(x) > 2 and len(y) > 1:
        dx, dy = np.diff(x), np.diff(y)
        if np.allclose(dx, dx[0], rtol=1e-6, atol=0.0) and np.allclose(dy, dy[0], rtol=1e-6, atol=0.0):
            extent = (x[0] - dx[0] / 2, x[-1] + dx[0] / 2, y[0] - dy[0] / 2, y[-1] + dy[0] / 2)
            return ax.imshow(c, origin="lower", aspect="auto", interpolation="nearest", extent=extent, **kw)
    return ax.pcolormesh(x, y, c, shading="nearest", **kw)


def plot_pin_forces(res, path) -> Path:
    """Pin force maps (pin angle vs time) of every disc, one panel each, and the largest
    pin force per disc below; all panels share the time axis and the same width (the
    colour bar sits in its own column so the panels stay aligned)."""
    plt = _plt()
    f = res["pin_force"].values  # (time, disc, pin)
    n_disc, n_pin = f.shape[1], f.shape[2]
    t = res.time
    fig = plt.figure(figsize=(8, 2.4 * n_disc + 2.6))
    gs = fig.add_gridspec(n_disc + 1, 2, width_ratios=[40, 1], hspace=0.35, wspace=0.04)
    angle = np.arange(n_pin) * 360.0 / n_pin  # pin angle on the pin circle [deg]
    vmax = float(f.max()) if f.size and f.max() > 0 else 1.0
    axes = []
    for k in range(n_disc):
        ax = fig.add_subplot(gs[k, 0], sharex=axes[0] if axes else None)
        im = _force_map(ax, t, angle, f[:, k, :].T, vmax)
        ax.set_ylabel(f"disc {k + 1}\npin angle [deg]")
        ax.set_yticks(np.arange(0, 361, 90))
        ax.tick_params(labelbottom=False)
        axes.append(ax)
    cax = fig.add_subplot(gs[:n_disc, 1])
    fig.colorbar(im, cax=cax, label="pin force [N]")
    ax = fig.add_subplot(gs[n_disc, 0], sharex=axes[0])
    for k in range(n_disc):
        ax.plot(t, f[:, k, :].max(axis=-1), lw=0.8, label=f"disc {k + 1}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("largest pin force [N]")
    ax.legend(loc="best", fontsize=8)
    axes[0].set_title(
        f"Pin forces, {res.attrs.get('preset')} ({res.attrs.get('model')} model), {n_pin} pins, {n_disc} discs",
        y=TITLE_Y,
    )
    return _save(fig, Path(path))


#: digits and signs of an exponent as Unicode superscripts
_SUPERSCRIPT = str.maketrans(
    "0123456789-\u2212", "\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079\u207b\u207b"
)


def plain_log_label(label: str) -> str:
    """A log axis's tick label of matplotlib's default formatter (``LogFormatterSciNotation``:
    ``$\\mathdefault{10^{-3}}$``, ``$\\mathdefault{2\\times10^{-3}}$``) as plain text with
    Unicode superscripts (``10⁻³``, ``2×10⁻³``): the same label without matplotlib's mathtext
    parser, whose construction costs ~0.1 s CPU in a process that draws no other mathtext.
    A label of any other form is returned unchanged."""
    m = re.fullmatch(r"\$\\mathdefault\{(.*)\}\$", label)
    if m is None:
        return label
    body = m.group(1).replace("\\times", "\u00d7")
    body = re.sub(r"\^\{([-\u2212]?\d+)\}", lambda e: e.group(1).translate(_SUPERSCRIPT), body)
    return label if ("\\" in body or "$" in body or "{" in body) else body


def _plain_log_ticks(axis) -> None:
    """The major and minor tick labels of the log ``axis`` as matplotlib's default formatters
    make them (which ticks are labelled included), written by :func:`plain_log_label`."""
    from matplotlib.ticker import LogFormatterSciNotation

    class PlainLogFormatter(LogFormatterSciNotation):
        def __call__(self, x, pos=None):
            return plain_log_label(super().__call__(x, pos))

    axis.set_major_formatter(PlainLogFormatter(10.0))
    axis.set_minor_formatter(PlainLogFormatter(10.0, labelOnlyBase=False))


#: characteristic frequencies in words (plot labels)
FREQUENCY_LABELS = {
    "crank_rotation": "crank revolution (rel. carrier)",
    "first_stage_mesh": "first-stage mesh",
    "cycloid_mesh": "cycloid mesh",
    "input": "input shaft",
    "carrier": "output (carrier)",
    "pin_passing": "pin passing",
    "crank_absolute": "crank (absolute)",
}


def spectrum_axis(ax, freq, amp, marks: dict, window_s: float, label: str | None = None, decades: float = 4.0):
    """Draw an amplitude spectrum on ``ax``: log amplitude axis limited to ``decades``
    below the peak (not down to numerical zero), the characteristic frequencies as
    numbered dashed lines with a key beside the axes giving each one's name in words and
    its frequency (numbers of coinciding lines are staggered, never overprinted), and the
    window length and frequency resolution in the title. A call without ``marks`` (a
    second spectrum on the same axes) keeps the frequency range of the first."""
    line = None
    if len(freq) > 1:
        f, a = freq[1:], amp[1:]
        top = float(a.max()) if a.size and a.max() > 0 else 1.0
        first = not ax.lines
        line = ax.semilogy(f, np.maximum(a, top * 10**-decades), lw=0.8, label=label)[0]
        _plain_log_ticks(ax.yaxis)
        if first:
            ax.set_ylim(top * 10**-decades, top * 3.0)
        if marks or first:
            hi = max(marks.values()) if marks else f[-1]
            ax.set_xlim(0, min(f[-1], 1.25 * hi))
    res_hz = float(freq[1] - freq[0]) if len(freq) > 1 else float("nan")
    lo_x, hi_x = ax.get_xlim()
    shown = [(n, f0) for n, f0 in sorted(marks.items(), key=lambda kv: kv[1]) if lo_x <= f0 <= hi_x]
    placed: list[float] = []
    key = []
    for k, (name, f0) in enumerate(shown, start=1):
        ax.axvline(f0, ls="--", lw=0.6, color="0.5")
        level = sum(1 for p in placed if abs(f0 - p) < 0.03 * (hi_x - lo_x))
        placed.append(f0)
        ax.annotate(
            str(k),
            (f0, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(2, -3 - 9 * level),
            textcoords="offset points",
            va="top",
            ha="left",
            fontsize=7,
            color="0.25",
            fontweight="bold",
        )
        key.append(f"{k}  {FREQUENCY_LABELS.get(name, name.replace('_', ' '))} {f0:.4g} Hz")
    if key:
        ax.text(1.01, 1.0, "\n".join(key), transform=ax.transAxes, va="top", ha="left", fontsize=7, color="0.25")
    ax.set_xlabel("frequency [Hz]")
    ax.set_title(f"window {window_s:.3g} s, resolution {res_hz:.3g} Hz (Hann)", fontsize=9, y=TITLE_Y)
    return line


def plot_te_spectrum(res, path) -> Path:
    """TE amplitude spectrum over the steady window with characteristic frequencies
    (labels in words), window length and resolution stated."""
    from flexrv.post.spectra import te_spectrum

    plt = _plt()
    freq, amp, marks = te_spectrum(res)
    t0, t1 = res.steady_window()
    fig, ax = plt.subplots(figsize=(10, 3.8))
    spectrum_axis(ax, freq, amp, marks, t1 - t0)
    ax.set_ylabel("TE amplitude [arcsec]")
    if not getattr(res, "is_steady", True):
        ax.text(
            0.5,
            0.5,
            "NOT STEADY: window in the ramps or < 1 crank revolution",
            transform=ax.transAxes,
            ha="center",
            color="red",
            fontsize=9,
        )
    fig.suptitle(f"TE spectrum, {res.attrs.get('preset')} ({res.attrs.get('model')} model)", fontsize=10)
    _fixed_layout(fig, right=_beside_right_in(fig, ax), top=_SPECTRUM_TOP_IN)
    return _save(fig, Path(path))


#: top margin [in] of the spectrum figure: its title (10 pt) above the axes' title (9 pt)
_SPECTRUM_TOP_IN = 0.62


def _beside_right_in(fig, ax) -> float:
    """Right margin [in] that holds the texts ``ax`` places beside its right edge (the key of
    :func:`spectrum_axis`, anchored at 1.01 of the axes' width), their widths measured with the
    figure's renderer; the default edge if there are none. The anchor moves with the axes'
    width, so the margin m solves m = 0.01 (W - left - m) + width + edge."""
    m = LAYOUT_MARGINS_IN
    beside = [t for t in ax.texts if t.get_transform() == ax.transAxes and t.get_position()[0] > 1.0]
    if not beside:
        return m["edge"]
    renderer = fig.canvas.get_renderer()
    width = max(t.get_window_extent(renderer).width for t in beside) / fig.dpi
    x = max(t.get_position()[0] for t in beside) - 1.0
    return (x * (fig.get_size_inches()[0] - m["left"]) + width + m["edge"]) / (1.0 + x)


def rebound_mask(angle: np.ndarray, torque: np.ndarray, band: float) -> np.ndarray:
    """Samples of a torque loop that belong to the rebound after the output crosses its
    clearance: on a branch of monotone torque the quasi-static response is monotone in
    angle (the loop's overall slope), so every sample between the first and the last
    reversal of the angle's direction within ``band`` [N m] of a torque zero crossing is
    the dynamic transient (free flight across the clearance, impact on the opposite
    flanks, rebound damped by the contacts)."""
    a, t = np.asarray(angle, dtype=float), np.asarray(torque, dtype=float)
    mask = np.zeros(a.size, dtype=bool)
    if a.size < 3:
        return mask
    slope = np.sign(np.polyfit(t, a, 1)[0]) or 1.0
    da, dt = np.diff(a), np.diff(t)
    against = (da * np.sign(dt) * slope < 0) & (np.abs(t[1:]) < band)
    crossings = np.nonzero(np.sign(t[1:]) != np.sign(t[:-1]))[0]
    for c in crossings:
        near = np.nonzero(against)[0]
        near = near[np.abs(near - c) < a.size // 4]
        if near.size:
            lo = max(int(near.min()) - 1, 0)
            hi = min(int(near.max()) + 2, a.size)
            mask[lo:hi] = True
    return mask


def plot_hysteresis(angle_arcmin, torque, path, title: str = "torsional hysteresis", figures=None) -> Path:
    """Torque vs output rotation loop of the stiffness test; with ``figures``
    (:class:`flexrv.post.stiffness.StiffnessTest`) the rigidity fit range (shaded
    bands and the fitted slope), the lost motion (at +-3 % T_r on the mean curve) and
    the hysteresis (loop width at T = 0, and the loop's energy) and the low-torque
    fit range (3-50 % T_r) with its slope are marked and stated in the legend.

    Near T = 0 the dynamic test shows a transient: when the torque reverses, the output
    crosses its clearance with no pin in contact, hits the opposite flanks and rebounds
    for some milliseconds until the contact damping settles it. It is physics of a
    torque ramp through zero (a bench sees it unless the torque reverses slowly), not a
    numerical artefact; it is drawn in grey (:func:`rebound_mask`), stated in a note,
    and an inset shows the loop within 10 % of the rated torque."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 6))
    a, tq = np.asarray(angle_arcmin, dtype=float), np.asarray(torque, dtype=float)
    rated = float(getattr(figures, "rated_torque", np.max(np.abs(tq)) if tq.size else 1.0))
    ring = rebound_mask(a, tq, 0.25 * rated)
    ax.plot(a, np.where(ring, np.nan, tq), lw=0.9, color="C0", label="loop")
    if ring.any():
        ax.plot(
            a,
            np.where(ring, tq, np.nan),
            lw=0.8,
            color="C7",
            label="rebound after crossing the clearance (dynamic, see note)",
        )
    if figures is not None:
        f = figures
        lo, hi = f.fit_range_low_Nm, f.rated_torque
        for sgn in (1, -1):
            ax.axhspan(sgn * lo, sgn * hi, color="C2", alpha=0.12, lw=0)
        ax.plot(
            [],
            [],
            color="C2",
            alpha=0.4,
            lw=6,
            label=f"rigidity fit |T| {lo:.3g}..{hi:.3g} N m: {f.rigidity_Nm_per_arcmin:.4g} N m/arcmin",
        )
        low = getattr(f, "low_range_low_Nm", float("nan"))
        if np.isfinite(low):
            for sgn in (1, -1):
                ax.axhspan(sgn * low, sgn * lo, color="C4", alpha=0.10, lw=0)
            ax.plot(
                [],
                [],
                color="C4",
                alpha=0.4,
                lw=6,
                label=f"low-torque fit |T| {low:.3g}..{lo:.3g} N m: {f.rigidity_low_Nm_per_arcmin:.4g} N m/arcmin",
            )
        ax.plot(
            [f.lost_motion_negative_arcmin, f.lost_motion_positive_arcmin],
            [-f.lost_motion_torque_Nm, f.lost_motion_torque_Nm],
            "o-",
            color="C3",
            ms=4,
            label=f"lost motion (±3 % T_r): {f.lost_motion_arcmin:.3g} arcmin",
        )
        ax.plot(
            [f.hysteresis_returning_arcmin, f.hysteresis_descending_arcmin],
            [0.0, 0.0],
            "s-",
            color="C1",
            ms=4,
            label=f"hysteresis (at T = 0): {f.hysteresis_arcmin:.3g} arcmin, "
            f"loss {getattr(f, 'hysteresis_loss_J', float('nan')):.3g} J per cycle",
        )
        ax.axhline(0, color="0.6", lw=0.5)
        ax.axvline(0, color="0.6", lw=0.5)
        ax.legend(loc="upper left", fontsize=8)
    ax.set_xlabel("output rotation [arcmin]")
    ax.set_ylabel("output torque [N m]")
    ax.set_title(title)
    ax.grid(True, lw=0.3)
    near = np.abs(tq) <= 0.1 * rated
    if near.sum() > 10:
        inset = ax.inset_axes([0.62, 0.07, 0.35, 0.33])
        inset.plot(a[near], np.where(ring, np.nan, tq)[near], lw=0.8, color="C0")
        inset.plot(a[near], np.where(ring, tq, np.nan)[near], lw=0.7, color="C7")
        inset.axhline(0, color="0.6", lw=0.5)
        inset.set_title("|T| ≤ 10 % of rated", fontsize=7)
        inset.tick_params(labelsize=6)
        inset.grid(True, lw=0.3)
    if ring.any():
        fig.text(
            0.01,
            0.005,
            "note: at each torque reversal the output crosses its clearance with no pin in contact and rebounds on the "
            "opposite flanks (grey);\nthe contact damping settles it within milliseconds. Figures read near T = 0 "
            "(lost motion, hysteresis) carry part of it; `flexrv te` gives the quasi-static lost motion.",
            fontsize=6.5,
            color="0.3",
            va="bottom",
        )
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return _save(fig, Path(path))


def standard_plots(res, directory=None) -> list[Path]:
    """TE, speeds, pin forces and TE spectrum PNGs into ``directory`` (default cwd), the
    cyclic collector paused meanwhile (:func:`flexrv.post.io.collector_paused`)."""
    from flexrv.post.io import collector_paused

    d = Path(directory) if directory is not None else Path.cwd()
    d.mkdir(parents=True, exist_ok=True)
    with collector_paused():
        paths = [plot_te(res, d / "te.png"), plot_speeds(res, d / "speeds.png")]
        if "pin_force" in res.ds:
            paths.append(plot_pin_forces(res, d / "pin_forces.png"))
        if res.steady("te").size > 16 and float(np.abs(res["omega_in"].values).max()) > 0:
            paths.append(plot_te_spectrum(res, d / "te_spectrum.png"))
    return paths


class PlottedResults(Results):
    """:class:`flexrv.post.results.Results` that write their standard PNGs with the data:
    :meth:`save` adds TE, speeds, pin forces and TE spectrum (:func:`standard_plots`). The
    results of :class:`flexrv.simulation.Simulation` are of this class."""

    def write_figures(self, directory: Path) -> list[Path]:
        return standard_plots(self, directory)

    def plot(self, directory: str | Path | None = None) -> list[Path]:
        """Write the standard PNGs into ``directory`` (default cwd); returns their paths."""
        return standard_plots(self, directory)
