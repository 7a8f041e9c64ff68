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


def _map_window(x: np.ndarray, y: np.ndarray, result) -> tuple[np.ndarray, np.ndarray]:
    """Index masks of the map window [mm]: 1.6 Hertz semi-axes about the centre in each
    direction, widened to the inlet meniscus upstream (where the pressure rises above
    1 % of its maximum), clipped to the solver's domain: the contact, not the far field."""
    a, b = 1.6 * result.hertz_a * 1e3, 1.6 * result.hertz_b * 1e3
    p = result.pressure
    rows = np.nonzero(p.max(axis=1) > 0.01 * p.max())[0]
    x_lo = min(-b, x[rows[0]] - 0.1 * b) if len(rows) else -b
    return (x >= x_lo) & (x <= b), (y >= -a) & (y <= a)


def ehl_figure(result, title: str = ""):
    """The matplotlib figure of :func:`plot_ehl_solution` (not saved): pressure and film on
    the two centre lines, then the pressure and film maps over the contact at equal aspect.
    The maps span the figure's width with the contact's long axis horizontal, so an
    elongated contact (a ball on its raceway: semi-axes in ratio up to ~10) stays readable."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    x, y = result.x * 1e3, result.y * 1e3  # mm
    p, h = result.pressure * 1e-9, result.film * 1e6  # GPa, um
    hc = result.h_central * 1e6
    ic = int(np.argmin(np.abs(result.x)))
    jc = int(np.argmin(np.abs(result.y)))
    mx, my = _map_window(x, y, result)
    xs, ys, ps, hs = x[mx], y[my], p[np.ix_(mx, my)], h[np.ix_(mx, my)]
    wide = np.ptp(ys) >= 2.5 * np.ptp(xs)  # an elongated contact: long axis horizontal, full-width maps
    if wide:
        map_h = float(np.clip(9.4 * np.ptp(xs) / max(np.ptp(ys), 1e-12), 1.2, 4.5))  # inches, ~9.4 in wide
        fig = plt.figure(figsize=(11, 4.2 + 2 * (map_h + 0.9)))
        grid = fig.add_gridspec(3, 2, height_ratios=[3.2, map_h + 0.6, map_h + 0.6], hspace=0.55, wspace=0.35)
        map_axes = (grid[1, :], grid[2, :])
    else:
        fig = plt.figure(figsize=(11, 8.6))
        grid = fig.add_gridspec(2, 2, height_ratios=[1, 1.25], hspace=0.4, wspace=0.35)
        map_axes = (grid[1, 0], grid[1, 1])
    for col, (coord, pc, hl, name) in enumerate(
        ((x, p[:, jc], h[:, jc], "x (entrainment)"), (y, p[ic, :], h[ic, :], "y (transverse)"))
    ):
        ax = fig.add_subplot(grid[0, col])
        ax.plot(coord, pc, "b-")
        ax.set_xlabel(f"{name} [mm]")
        ax.set_ylabel("pressure p [GPa]", color="b")
        ax.grid(alpha=0.3)
        ax2 = ax.twinx()
        ax2.plot(coord, hl, "r-")
        ax2.axhline(hc, color="r", lw=0.6, ls=":")
        ax2.set_ylabel("film h [µm]", color="r")
        ax2.set_ylim(0, max(3.0 * hc, 1e-6))
        ax.set_title(f"centre line {'y' if col == 0 else 'x'} = 0 (dotted: h_c)", fontsize=10)
    maps = (
        (ps, "viridis", "pressure p [GPa]", "pressure"),
        (np.minimum(hs, 3.0 * hc), "magma", "film h [µm]\n(clipped at 3 h_c)", "film thickness"),
    )
    for where, (field, cmap, label, name) in zip(map_axes, maps):
        ax = fig.add_subplot(where)
        if wide:
            cs = ax.contourf(ys, xs, field, 30, cmap=cmap)
            ax.set_xlabel("y (transverse) [mm]")
            ax.set_ylabel("x (entr.) [mm]")
        else:
            cs = ax.contourf(xs, ys, field.T, 30, cmap=cmap)
            ax.set_xlabel("x (entrainment) [mm]")
            ax.set_ylabel("y (transverse) [mm]")
        ax.set_aspect("equal")
        ax.xaxis.set_major_locator(MaxNLocator(9 if wide else 5))
        ax.yaxis.set_major_locator(MaxNLocator(4 if wide else 5))
        cbar = fig.colorbar(cs, ax=ax, label=label, shrink=0.95, pad=0.02)
        cbar.locator = MaxNLocator(5)
        cbar.update_ticks()
        ax.set_title(f"{name} (equal aspect; ±1.6 Hertz semi-axes)", fontsize=10)
    fig.suptitle(
        title
        or f"EHL: h_c = {result.h_central * 1e9:.1f} nm, h_min = {result.h_min * 1e9:.1f} nm, "
        f"p_max = {result.p_max * 1e-9:.3f} GPa (p_H = {result.hertz_pressure * 1e-9:.3f} GPa)"
    )
    return fig
