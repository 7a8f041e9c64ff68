"""Plots of the rigid-vs-flexible comparison (:mod:`flexrv.studies.compare`), matplotlib Agg."""

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
    frequencies marked and labelled in words, window length and resolution stated
    (:func:`flexrv.viz.plots.spectrum_axis`)."""
    from flexrv.post.spectra import te_spectrum
    from flexrv.viz.plots import spectrum_axis

    plt = _plt()
    fig, ax = plt.subplots(figsize=(10.5, 4.2))
    spectra = {label: te_spectrum(res) for res, label in ((rigid, "rigid"), (flexible, "flexible"))}
    top = max((float(a[1:].max()) for f, a, _ in spectra.values() if len(a) > 1), default=1.0)
    t0, t1 = rigid.steady_window()
    for k, (label, (freq, amp, marks)) in enumerate(spectra.items()):
        if len(freq) > 1:
            amp = amp.copy()
            amp[1:] = np.maximum(amp[1:], top * 1e-4)
            spectrum_axis(ax, freq, amp, marks if k == 0 else {}, t1 - t0, label=label)
    ax.set_ylim(top * 1e-4, top * 3.0)
    ax.set_ylabel("TE amplitude [arcsec]")
    ax.legend(loc="lower right")
    fig.suptitle(f"TE spectra, {rigid.attrs.get('preset')}: rigid vs flexible", fontsize=10)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_ball_loads(res, path) -> Path:
    """Inner-contact ball loads of each row over the ball's pocket angle in the cage
    (ball 1 at 0 deg) at start-up (the instant of the largest load before the steady
    window) and at the end of the run; markers on every ball so no curve hides another."""
    plt = _plt()
    loads = res["ball_load_inner"]
    t = loads["time"].values
    t0, _ = res.steady_window()
    early = t < t0
    i_start = int(np.argmax(loads.values[early].max(axis=(1, 2)))) if early.any() else 0
    n_ball = loads.shape[2]
    angle = np.arange(n_ball) * 360.0 / n_ball
    fig, axes = plt.subplots(1, loads.shape[1], figsize=(10, 3.8), sharey=True, squeeze=False)
    for k, ax in enumerate(axes[0]):
        ax.plot(
            angle, loads.values[i_start, k], "o-", ms=4, lw=1.6, alpha=0.8, label=f"start-up, t = {t[i_start]:.3f} s"
        )
        ax.plot(angle, loads.values[-1, k], "s--", ms=3, lw=1.0, label=f"end of run, t = {t[-1]:.3f} s")
        ax.set_title(f"row {k + 1}")
        ax.set_xlabel("ball pocket angle in the cage [deg]")
        ax.set_xticks(np.arange(0, 361, 90))
        ax.grid(True, lw=0.3)
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
            ax.plot(
                da["time"],
                1e6 * da.values[:, k],
                lw=1.4 if k == 0 else 0.8,
                ls="-" if k == 0 else "--",
                label=f"{name.split('_')[-1]} ring, row {k + 1}",
            )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("deflection at the most-loaded ball [µm]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, Path(path))
