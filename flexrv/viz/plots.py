"""Matplotlib plots of simulation results (Agg backend, files only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    from flexrv.cache import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    _plt().close(fig)
    return path


def plot_te(res, path) -> Path:
    """TE(t) [arcsec] with the steady window shaded."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(res.time, res["te"].values, lw=0.8)
    t0, t1 = res.steady_window()
    ax.axvspan(t0, t1, color="0.9", zorder=0, label="steady window")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("TE [arcsec]")
    ax.set_title(f"Transmission error, {res.attrs.get('preset')} ({res.attrs.get('model')})")
    ax.legend(loc="best")
    fig.tight_layout()
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
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_pin_forces(res, path) -> Path:
    """Pin forces of disc 0 over time and pin number (map) and the largest pin force."""
    plt = _plt()
    f = res["pin_force"].values  # (time, disc, pin)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    t = res.time
    im = axes[0].pcolormesh(t, np.arange(f.shape[2]), f[:, 0, :].T, shading="auto", cmap="viridis")
    fig.colorbar(im, ax=axes[0], label="force [N]")
    axes[0].set_ylabel("pin (disc 0)")
    for k in range(f.shape[1]):
        axes[1].plot(t, f[:, k, :].max(axis=-1), lw=0.8, label=f"disc {k}: max pin force")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("force [N]")
    axes[1].legend(loc="best")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_te_spectrum(res, path) -> Path:
    """TE amplitude spectrum over the steady window with characteristic frequencies."""
    from flexrv.post.spectra import te_spectrum

    plt = _plt()
    freq, amp, marks = te_spectrum(res)
    fig, ax = plt.subplots(figsize=(8, 3.5))
    if len(freq):
        ax.semilogy(freq[1:], np.maximum(amp[1:], 1e-9), lw=0.8)
        ax.set_xlim(0, min(freq[-1], 5 * max(marks.values())))
    for name, f0 in marks.items():
        ax.axvline(f0, ls="--", lw=0.6, color="0.5")
        ax.text(f0, ax.get_ylim()[1], name, rotation=90, va="top", fontsize=7)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("TE amplitude [arcsec]")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_hysteresis(angle_arcmin, torque, path, title: str = "torsional hysteresis") -> Path:
    """Torque vs output rotation loop of the stiffness test."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(angle_arcmin, torque, lw=0.9)
    ax.set_xlabel("output rotation [arcmin]")
    ax.set_ylabel("output torque [N m]")
    ax.set_title(title)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    return _save(fig, Path(path))


def standard_plots(res, directory=None) -> list[Path]:
    """TE, speeds, pin forces and TE spectrum PNGs into ``directory`` (default cwd)."""
    d = Path(directory) if directory is not None else Path.cwd()
    d.mkdir(parents=True, exist_ok=True)
    paths = [plot_te(res, d / "te.png"), plot_speeds(res, d / "speeds.png")]
    if "pin_force" in res.ds:
        paths.append(plot_pin_forces(res, d / "pin_forces.png"))
    if res.steady("te").size > 16 and float(abs(res["omega_in"]).max()) > 0:
        paths.append(plot_te_spectrum(res, d / "te_spectrum.png"))
    return paths
