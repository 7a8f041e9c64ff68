"""Overlay plots of a measurement and its prediction (``flexrv validate``, ``flexrv
calibrate``): loop on loop, TE on TE, spectrum on spectrum. They take arrays in SI
(torque [N m], angles [rad]) and draw in the bench's units."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexrv.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD, DEG_PER_RAD
from flexrv.viz.plots import _plt, _save


def plot_loop_overlay(measured, predicted, path, title: str, labels=("measured", "predicted")) -> Path:
    """Torque [N m] over output angle [arcmin] of the measured and the predicted loop."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for (t, a), label, style in zip((measured, predicted), labels, ("-", "--")):
        ax.plot(np.asarray(a) * ARCMIN_PER_RAD, t, style, lw=1.0, label=label)
    ax.axhline(0, color="0.8", lw=0.6, zorder=0)
    ax.axvline(0, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel("output angle [arcmin]")
    ax.set_ylabel("output torque [N m]")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_te_overlay(measured, predicted, path, title: str) -> Path:
    """TE [arcsec] over output angle [deg] of the measured and the predicted record."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for (x, y), label, style in zip((measured, predicted), ("measured", "predicted"), ("-", "--")):
        y = np.asarray(y) * ARCSEC_PER_RAD
        ax.plot(np.asarray(x) * DEG_PER_RAD, y, style, lw=0.9, label=f"{label}, mean {np.nanmean(y):.4g}″")
    ax.set_xlabel("output angle [deg]")
    ax.set_ylabel("TE [arcsec]")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_spectrum_overlay(measured, predicted, path, title: str, lines=None) -> Path:
    """TE amplitude [arcsec] over order (cycles per output revolution), measured and
    predicted, the measured record's largest lines labelled (``lines``: spectrum_lines)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for (o, amp), label, width in zip((measured, predicted), ("measured", "predicted"), (2.2, 1.0)):
        ax.vlines(o, 0, amp, lw=width, alpha=0.7, label=label, color="C0" if label == "measured" else "C1")
    for line in lines or []:
        if line["label"] != "-":
            ax.annotate(line["label"], (line["order"], line["amplitude_arcsec"]), fontsize=7, rotation=60)
    ax.set_xlabel("order [cycles per output revolution]")
    ax.set_ylabel("amplitude [arcsec]")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, Path(path))
