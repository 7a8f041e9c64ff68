"""Plots of a quasi-static loaded-TE run (``flexrv te``): TE over the output
rotation with the crank revolutions marked, the TE order spectrum with labelled
lines, and the pin-force map (pin x position, every disc). They read the
Dataset of :func:`flexrv.post.te.te_dataset` by variable name only."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flexrv.viz.plots import TITLE_Y, _fixed_layout, _plt, _save


def _envelope(x: np.ndarray, y: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bin centres, minimum and maximum of ``y`` over ``bins`` equal bins of ``x``: an envelope
    that shows the range of a signal too dense to draw point by point."""
    edges = np.linspace(x[0], x[-1], bins + 1)
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    lo = np.full(bins, np.nan)
    hi = np.full(bins, np.nan)
    np.fmin.at(lo, idx, y)
    np.fmax.at(hi, idx, y)
    return 0.5 * (edges[:-1] + edges[1:]), lo, hi


def _zoom_window(deg: np.ndarray, te: np.ndarray, period: float) -> tuple[float, float]:
    """The crank revolution (of whole revolutions from the start) with the largest TE range."""
    n = max(int(np.floor((deg[-1] - deg[0]) / period + 1e-9)), 1)
    best, start = -1.0, deg[0]
    for k in range(n):
        a = deg[0] + k * period
        sel = (deg >= a) & (deg <= a + period)
        if sel.sum() > 1 and np.ptp(te[sel]) > best:
            best, start = float(np.ptp(te[sel])), a
    return start, min(start + period, deg[-1])


#: margins [in] of the TE curve (:func:`flexrv.viz.plots._fixed_layout`): the last x tick label
#: (the end of the run, an axis limit) overhangs the right edge by half its width; a 10-12 pt
#: title above; between the panels the upper one's x labels and the lower one's title
_CURVE_RIGHT_IN, _CURVE_TOP_IN, _CURVE_GAP_IN = 0.25, 0.36, 0.8


def plot_te_curve(ds, path) -> Path:
    """Loaded and no-load TE [arcsec], each about its mean (means in the legend), over the
    output angle [deg]. With more than one crank revolution (relative to the carrier) the
    upper panel shows the whole run as a min-max envelope per eighth of a crank revolution
    (a line per point would fill the panel), the lower panel one crank revolution at full
    resolution: the one with the largest loaded TE range, shaded in the upper panel."""
    plt = _plt()
    deg = np.degrees(ds["output_revolutions"].values * 2.0 * np.pi)
    te, nl = ds["te"].values, ds["te_no_load"].values
    te_c, nl_c = te - np.nanmean(te), nl - np.nanmean(nl)
    orders = json.loads(ds.attrs["orders"])
    period = 360.0 / orders["crank rotation"]
    revolutions = (deg[-1] - deg[0]) / period
    torque = ds.attrs["torque_Nm"]
    labels = (
        f"loaded ({torque:.4g} N m): p-p {np.ptp(te):.3g}″, mean {np.nanmean(te):.4g}″",
        f"no load: p-p {np.ptp(nl):.3g}″, mean {np.nanmean(nl):.4g}″",
    )
    if revolutions <= 1.5:
        fig, ax = plt.subplots(figsize=(9, 3.8))
        ax.plot(deg, te_c, lw=1.0, color="C0", label=labels[0])
        ax.plot(deg, nl_c, lw=1.0, color="C1", label=labels[1])
        ax.set_xlabel("output angle [deg]")
        ax.set_ylabel("TE − mean [arcsec]")
        ax.legend(loc="upper left", fontsize=8)
        ax.grid(alpha=0.3)
        ax.set_title(f"Quasi-static transmission error, {ds.attrs['preset']}", y=TITLE_Y)
        _fixed_layout(fig, right=_CURVE_RIGHT_IN, top=_CURVE_TOP_IN)
        return _save(fig, Path(path))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6.4), gridspec_kw={"height_ratios": [1, 1.15]})
    bins = int(np.ceil(revolutions * 8))
    for y, color, label in ((te_c, "C0", labels[0]), (nl_c, "C1", labels[1])):
        x, lo, hi = _envelope(deg, y, bins)
        top.fill_between(x, lo, hi, color=color, alpha=0.45, lw=0, label=label)
    a, b = _zoom_window(deg, te, period)
    top.axvspan(a, b, color="0.2", alpha=0.15, lw=0, label="crank revolution zoomed below")
    lo_all, hi_all = float(np.nanmin(te_c)), float(np.nanmax(te_c))
    top.set_ylim(lo_all - 0.05 * (hi_all - lo_all), hi_all + 0.55 * (hi_all - lo_all))  # room for the legend
    top.set_xlim(deg[0], deg[-1])
    top.set_xlabel("output angle [deg]")
    top.set_ylabel("TE − mean [arcsec]")
    top.set_title(
        f"Quasi-static transmission error, {ds.attrs['preset']}: {revolutions:.3g} crank revolutions "
        "(min-max envelope per 1/8 crank revolution)",
        fontsize=10,
        y=TITLE_Y,
    )
    top.legend(loc="upper left", fontsize=8, ncol=2)
    top.grid(alpha=0.3)
    sel = (deg >= a) & (deg <= b)
    bottom.plot(deg[sel], te_c[sel], lw=1.0, color="C0", marker=".", ms=2, label="loaded")
    bottom.plot(deg[sel], nl_c[sel], lw=1.0, color="C1", marker=".", ms=2, label="no load")
    mesh = orders.get("cycloid mesh")
    if mesh:
        for m in np.arange(a, b + 1e-9, 360.0 / mesh):
            bottom.axvline(m, color="0.85", lw=0.5, zorder=0)
    bottom.set_xlim(a, b)
    bottom.set_xlabel("output angle [deg]")
    bottom.set_ylabel("TE − mean [arcsec]")
    bottom.set_title(
        f"one crank revolution, {a:.4g}–{b:.4g}° ({int(np.sum(sel))} positions"
        + ("; grey lines: pin-mesh periods)" if mesh else ")"),
        fontsize=10,
        y=TITLE_Y,
    )
    lo_z, hi_z = float(np.nanmin(te_c[sel])), float(np.nanmax(te_c[sel]))
    bottom.set_ylim(lo_z - 0.05 * (hi_z - lo_z), hi_z + 0.3 * (hi_z - lo_z))
    bottom.legend(loc="upper right", fontsize=8, ncol=2)
    bottom.grid(alpha=0.3, axis="y")
    _fixed_layout(fig, right=_CURVE_RIGHT_IN, top=_CURVE_TOP_IN, gap=_CURVE_GAP_IN)
    return _save(fig, Path(path))


def plot_te_spectrum(ds, summary: dict, path) -> Path:
    """Amplitude of the loaded TE [arcsec] over orders of the output rotation, each of
    the largest lines labelled with its name (characteristic order, harmonic or crank
    sideband), its order and amplitude in a numbered key beside the axes."""
    from flexrv.post.te import order_spectrum

    plt = _plt()
    order, amp = order_spectrum(ds["te"].values, summary["output_revolutions"])
    fig, ax = plt.subplots(figsize=(10, 4.0))
    fig.subplots_adjust(left=0.07, right=0.68, bottom=0.13, top=0.9)
    if len(order):
        # one line from 0 to each amplitude: drawn as a single path with breaks (as ax.vlines draws
        # it, without a masked-array segment per order)
        o, a = order[1:], amp[1:]
        ax.plot(
            np.column_stack([o, o, np.full_like(o, np.nan)]).ravel(),
            np.column_stack([np.zeros_like(a), a, np.full_like(a, np.nan)]).ravel(),
            lw=0.8,
            color="C0",
        )
        lines = sorted(summary["spectrum_lines"], key=lambda x: -x["amplitude_arcsec"])
        top = max(amp[1:].max(), 1e-12)
        key = []
        for k, line in enumerate(lines, start=1):
            x, y = line["order"], line["amplitude_arcsec"]
            ax.annotate(
                str(k),
                (x, y),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                fontsize=7,
                color="C3",
                fontweight="bold",
            )
            key.append(f"{k}  {line['label']}\n    order {x:.5g}, {y:.3g}″")
        if key:
            ax.text(
                1.02, 1.0, "\n".join(key), transform=ax.transAxes, va="top", ha="left", fontsize=7, family="monospace"
            )
        ax.set_ylim(0, 1.12 * top)
        ax.set_xlim(0, order[-1])
    ax.set_xlabel("order [cycles per output revolution]")
    ax.set_ylabel("TE amplitude [arcsec]")
    res = summary.get("spectral_resolution_orders")
    ax.set_title(
        f"TE spectrum, {ds.attrs['preset']} (loaded, {summary['output_revolutions']:.3g} output rev., "
        f"resolution {res:.3g} order)"
        if res
        else f"TE spectrum, {ds.attrs['preset']}",
        y=TITLE_Y,
    )
    return _save(fig, Path(path))


def plot_pin_force_map(ds, path) -> Path:
    """Pin force [N] over pin number and output angle, one row per disc; with more than
    one crank revolution a right-hand column repeats the crank revolution zoomed in the TE
    plot (the load zone sweeps once around the pins per crank revolution, too fast to
    follow over a whole output revolution)."""
    plt = _plt()
    f = ds["pin_force"].values  # (position, disc, pin)
    deg = np.degrees(ds["output_revolutions"].values * 2.0 * np.pi)
    nd = f.shape[1]
    period = 360.0 / json.loads(ds.attrs["orders"])["crank rotation"]
    zoom = (deg[-1] - deg[0]) / period > 1.5
    cols = 2 if zoom else 1
    fig, axes = plt.subplots(
        nd,
        cols,
        figsize=(11 if zoom else 9, 2.4 * nd + 0.9),
        squeeze=False,
        gridspec_kw={"width_ratios": [2.2, 1] if zoom else [1]},
    )
    vmax = max(float(f.max()), 1e-9)
    windows = [(deg[0], deg[-1])]
    if zoom:
        windows.append(_zoom_window(deg, ds["te"].values, period))
    for c, (a, b) in enumerate(windows):
        sel = (deg >= a) & (deg <= b)
        for k in range(nd):
            ax = axes[k, c]
            im = ax.imshow(
                f[sel, k, :].T,
                aspect="auto",
                origin="lower",
                cmap="viridis",
                vmin=0.0,
                vmax=vmax,
                extent=(deg[sel][0], deg[sel][-1], 0.5, f.shape[2] + 0.5),
                interpolation="nearest",
            )
            ax.set_ylabel(f"disc {k + 1}: pin number" if c == 0 else "")
            if k < nd - 1:
                ax.tick_params(labelbottom=False)
        axes[0, c].set_title(
            "whole run" if c == 0 else f"one crank revolution, {a:.4g}–{b:.4g}°", fontsize=10, y=TITLE_Y
        )
        axes[-1, c].set_xlabel("output angle [deg]")
    fig.colorbar(im, ax=axes.ravel().tolist(), label="pin force [N]", fraction=0.03, pad=0.02)
    fig.suptitle(f"Pin forces, {ds.attrs['preset']} at {ds.attrs['torque_Nm']:.4g} N m")
    return _save(fig, Path(path))


def te_plots(ds, summary: dict, directory) -> list[Path]:
    """All three plots into ``directory`` (the cyclic collector paused meanwhile:
    :func:`flexrv.post.io.collector_paused`)."""
    from flexrv.post.io import collector_paused

    d = Path(directory)
    spectrum = summary.get("spectral_resolution_orders") is not None  # a run too short has none
    with collector_paused():
        return [
            plot_te_curve(ds, d / "te.png"),
            *([plot_te_spectrum(ds, summary, d / "te_spectrum.png")] if spectrum else []),
            plot_pin_force_map(ds, d / "pin_forces.png"),
        ]
