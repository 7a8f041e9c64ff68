"""Plots of a quasi-static loaded-TE run (``flexrv te``): TE over the output
rotation with the crank revolutions marked, the TE order spectrum with labelled
lines, and the pin-force map (pin x position, every disc). They read the
Dataset of :func:`flexrv.post.te.te_dataset` by variable name only."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flexrv.viz.plots import _plt, _save


def plot_te_curve(ds, path) -> Path:
    """Loaded and no-load TE [arcsec] (each about its mean, means in the legend)
    over the output angle [deg]; thin vertical lines mark crank revolutions
    (relative to the carrier) when they are few enough to read."""
    plt = _plt()
    deg = np.degrees(ds["output_revolutions"].values * 2.0 * np.pi)
    te, nl = ds["te"].values, ds["te_no_load"].values
    fig, ax = plt.subplots(figsize=(9, 3.8))
    ax.plot(deg, te - te.mean(), lw=0.9, label=f"loaded ({ds.attrs['torque_Nm']:.4g} N m), mean {te.mean():.4g}″")
    ax.plot(deg, nl - nl.mean(), lw=0.9, label=f"no load, mean {nl.mean():.4g}″")
    orders = json.loads(ds.attrs["orders"])
    period = 360.0 / orders["crank rotation"]
    marks = np.arange(deg[0], deg[-1] + 1e-9, period)
    if 1 < len(marks) <= 60:
        for m in marks[1:]:
            ax.axvline(m, color="0.8", lw=0.6, zorder=0)
        ax.text(
            0.99, 0.02, "grey lines: crank revolutions", transform=ax.transAxes, ha="right", fontsize=8, color="0.4"
        )
    ax.set_xlabel("output angle [deg]")
    ax.set_ylabel("TE − mean [arcsec]")
    ax.set_title(f"Quasi-static transmission error, {ds.attrs['preset']}")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_te_spectrum(ds, summary: dict, path) -> Path:
    """Amplitude of the loaded TE [arcsec] over orders of the output rotation,
    the largest lines labelled with the characteristic order they sit on."""
    from flexrv.post.te import order_spectrum

    plt = _plt()
    order, amp = order_spectrum(ds["te"].values, summary["output_revolutions"])
    fig, ax = plt.subplots(figsize=(9, 3.8))
    if len(order):
        ax.vlines(order[1:], 0.0, amp[1:], lw=0.8)
        for line in summary["spectrum_lines"][:6]:
            ax.annotate(
                f"{line['label']} ({line['order']:.4g})",
                (line["order"], line["amplitude_arcsec"]),
                textcoords="offset points",
                xytext=(3, 3),
                fontsize=7,
                rotation=20,
            )
        ax.set_xlim(0, order[-1])
        ax.set_ylim(0, 1.25 * max(amp[1:].max(), 1e-12))
    ax.set_xlabel("order [cycles per output revolution]")
    ax.set_ylabel("TE amplitude [arcsec]")
    res = summary.get("spectral_resolution_orders")
    ax.set_title(
        f"TE spectrum, {ds.attrs['preset']} ({summary['output_revolutions']:.3g} output revolutions, "
        f"resolution {res:.3g} orders)"
        if res
        else f"TE spectrum, {ds.attrs['preset']}"
    )
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_pin_force_map(ds, path) -> Path:
    """Pin force [N] over pin number and output angle, one panel per disc."""
    plt = _plt()
    f = ds["pin_force"].values  # (position, disc, pin)
    deg = np.degrees(ds["output_revolutions"].values * 2.0 * np.pi)
    nd = f.shape[1]
    fig, axes = plt.subplots(nd, 1, figsize=(9, 2.4 * nd + 0.8), sharex=True, squeeze=False)
    vmax = max(float(f.max()), 1e-9)
    for k in range(nd):
        ax = axes[k, 0]
        im = ax.imshow(
            f[:, k, :].T,
            aspect="auto",
            origin="lower",
            cmap="viridis",
            vmin=0.0,
            vmax=vmax,
            extent=(deg[0], deg[-1], -0.5, f.shape[2] - 0.5),
            interpolation="nearest",
        )
        ax.set_ylabel(f"disc {k}: pin")
    axes[-1, 0].set_xlabel("output angle [deg]")
    fig.colorbar(im, ax=axes[:, 0].tolist(), label="pin force [N]")
    fig.suptitle(f"Pin forces, {ds.attrs['preset']} at {ds.attrs['torque_Nm']:.4g} N m")
    return _save(fig, Path(path))


def te_plots(ds, summary: dict, directory) -> list[Path]:
    """All three plots into ``directory``."""
    d = Path(directory)
    spectrum = summary.get("spectral_resolution_orders") is not None  # a run too short has none
    return [
        plot_te_curve(ds, d / "te.png"),
        *([plot_te_spectrum(ds, summary, d / "te_spectrum.png")] if spectrum else []),
        plot_pin_force_map(ds, d / "pin_forces.png"),
    ]
