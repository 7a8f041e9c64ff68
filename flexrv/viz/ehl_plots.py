"""Plots of an EHL point-contact solution (matplotlib, Agg backend, files only).

Maps are drawn with equal aspect (an elongated contact ellipse looks elongated);
films in µm, pressures in GPa, coordinates in mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_ehl_solution(result, path, title: str = "") -> Path:
    """Pressure and film along the centre lines (y = 0 and x = 0) and 2-D maps.

    Parameters
    ----------
    result : :class:`flexrv.ehl.solver.EHLResult`.
    path : output PNG file (written atomically).
    title : optional figure title.
    """
    import matplotlib.pyplot as plt

    from flexrv.cache import atomic_path

    fig = ehl_figure(result, title)
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


def ehl_figure(result, title: str = ""):
    """The matplotlib figure of :func:`plot_ehl_solution` (not saved)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, y = result.x * 1e3, result.y * 1e3  # mm
    p, h = result.pressure * 1e-9, result.film * 1e6  # GPa, um
    ic = int(np.argmin(np.abs(result.x)))
    jc = int(np.argmin(np.abs(result.y)))
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    ax = axes[0, 0]
    ax.plot(x, p[:, jc], "b-", label="pressure")
    ax.set_xlabel("x (entrainment) [mm]")
    ax.set_ylabel("pressure p [GPa]", color="b")
    ax2 = ax.twinx()
    ax2.plot(x, h[:, jc], "r-", label="film")
    ax2.set_ylabel("film h [µm]", color="r")
    ax2.set_ylim(0, max(3.0 * result.h_central * 1e6, 1e-6))
    ax.set_title("centre line y = 0")
    ax = axes[0, 1]
    ax.plot(y, p[ic, :], "b-")
    ax.set_xlabel("y (transverse) [mm]")
    ax.set_ylabel("pressure p [GPa]", color="b")
    ax2 = ax.twinx()
    ax2.plot(y, h[ic, :], "r-")
    ax2.set_ylabel("film h [µm]", color="r")
    ax2.set_ylim(0, max(3.0 * result.h_central * 1e6, 1e-6))
    ax.set_title("centre line x = 0")
    ax = axes[1, 0]
    cs = ax.contourf(x, y, p.T, 30, cmap="viridis")
    fig.colorbar(cs, ax=ax, label="pressure p [GPa]", shrink=0.9)
    ax.set_aspect("equal")
    ax.set_xlabel("x (entrainment) [mm]")
    ax.set_ylabel("y (transverse) [mm]")
    ax.set_title("pressure (equal aspect)")
    ax = axes[1, 1]
    cs = ax.contourf(x, y, np.minimum(h, 3.0 * result.h_central * 1e6).T, 30, cmap="magma")
    fig.colorbar(cs, ax=ax, label="film h [µm] (clipped at 3 h_c)", shrink=0.9)
    ax.set_aspect("equal")
    ax.set_xlabel("x (entrainment) [mm]")
    ax.set_ylabel("y (transverse) [mm]")
    ax.set_title("film thickness (equal aspect)")
    fig.suptitle(
        title
        or f"EHL: h_c = {result.h_central * 1e9:.1f} nm, h_min = {result.h_min * 1e9:.1f} nm, "
        f"p_max = {result.p_max * 1e-9:.3f} GPa (p_H = {result.hertz_pressure * 1e-9:.3f} GPa)"
    )
    fig.tight_layout()
    return fig
