"""Plots of the rigid-vs-flexible comparison (:mod:`flexrv.post.compare`), matplotlib Agg."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexrv.viz.plots import _plt, _save


def plot_te_overlay(rigid, flexible, path) -> Path:
    """TE [arcsec] of both runs over time; the steady window shaded."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for res, label in ((rigid, "rigid"), (flexible, "flexible")):
        te = res["te"]
        ax.plot(te["time"], te, lw=0.8, label=label)
    t0, t1 = rigid.steady_window()
    ax.axvspan(t0, t1, color="0.9", zorder=0, label="steady window")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("TE [arcsec]")
    ax.legend(loc="best")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_te_spectra(rigid, flexible, path) -> Path:
    """TE amplitude spectra of both runs (steady window) with the characteristic
    frequencies marked and labelled."""
    from flexrv.post.spectra import te_spectrum

    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    marks, f_max = {}, 0.0
    for res, label in ((rigid, "rigid"), (flexible, "flexible")):
        freq, amp, marks = te_spectrum(res)
        if len(freq) > 1:
            ax.semilogy(freq[1:], np.maximum(amp[1:], 1e-9), lw=0.8, label=label)
            f_max = max(f_max, freq[-1])
    if marks:
        ax.set_xlim(0, min(f_max, 5 * max(marks.values())) if f_max else 5 * max(marks.values()))
    for name, f0 in marks.items():
        ax.axvline(f0, ls="--", lw=0.6, color="0.4")
        ax.text(f0, 1.0, f" {name} {f0:.3g} Hz", rotation=90, va="top", fontsize=7,
                transform=ax.get_xaxis_transform())
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("TE amplitude [arcsec]")
    ax.legend(loc="lower right")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_ball_loads(res, path) -> Path:
    """Inner-contact ball loads of both rows over the ball index at start-up (the
    instant of the largest load before the steady window) and at the end of the run."""
    plt = _plt()
    loads = res["ball_load_inner"]
    t = loads["time"].values
    t0, _ = res.steady_window()
    early = t < t0
    i_start = int(np.argmax(loads.values[early].max(axis=(1, 2)))) if early.any() else 0
    fig, axes = plt.subplots(1, loads.shape[1], figsize=(10, 3.6), sharey=True, squeeze=False)
    for k, ax in enumerate(axes[0]):
        balls = np.arange(loads.shape[2])
        ax.plot(balls, loads.values[i_start, k], "o-", ms=3, label=f"start-up, t = {t[i_start]:.3f} s")
        ax.plot(balls, loads.values[-1, k], "s-", ms=3, label=f"steady, t = {t[-1]:.3f} s")
        ax.set_title(f"row {k}")
        ax.set_xlabel("ball")
    axes[0, 0].set_ylabel("ball-inner raceway load [N]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_ring_deformation(res, path) -> Path:
    """Raceway deflection at the most-loaded contact [um] of the flexible rings over time."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for name in ("ring_deformation_outer", "ring_deformation_inner"):
        if name not in res:
            continue
        da = res[name]
        for k in range(da.shape[1]):
            ax.plot(da["time"], 1e6 * da.values[:, k], lw=0.8, label=f"{name.split('_')[-1]} ring, row {k}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("deflection at the most-loaded ball [um]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, Path(path))
