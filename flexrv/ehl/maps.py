"""Precomputed central-film maps h_c(Q, u) of one point-contact geometry + lubricant.

The numerical solver (:mod:`flexrv.ehl.solver`) is far too slow to call inside a
dynamic simulation, so it is run once on a grid of loads x entrainment speeds and
the result is stored as the *correction factor* to Hamrock–Dowson,

    h_c(Q, u) = h_HD(Q, u) * exp(c(ln Q, ln u)),  c = ln(h_solver / h_HD),

bilinear in (ln Q, ln u). Interpolating the ratio rather than h itself keeps the
known power-law dependence exact between nodes, and outside the tabulated range
the ratio is held at its edge value (constant extrapolation), so the map falls
back to Hamrock–Dowson scaling there. The interpolation is one compiled
function, :func:`packed_log_correction`, called by :meth:`FilmMap.log_correction`
and by the compiled bearing row kernel on the same packed table
(:meth:`FilmMap.packed`). Grid points where the solver fails (e.g. a
film the grid cannot resolve at very high load, see the solver's limits) take the
ratio of the nearest converged point; they are flagged in ``valid``.

Maps are cached under ``flexrv.cache.cache_dir()/ehl_maps`` keyed by a content
hash of all inputs, the solver settings and the library versions, and written
atomically (.npz).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from flexrv.cache import atomic_path, cache_dir, cached_entry, content_hash, library_versions
from flexrv.ehl.film import hamrock_dowson
from flexrv.ehl.solver import LubricantProperties, solve_point_contact
from flexrv.errors import ConvergenceError, InputError

#: Bump when the solver or the map layout changes (part of the cache key).
#: 4: the maps store the ratio to Hamrock–Dowson, whose ellipticity is now the exact Hertz k
#: (1.0 for circular contacts); 3: fixed map grid (no adaptive refinement), half-domain solver;
#: 2: second-order + Richardson
MAP_SCHEMA = 4


@dataclass(frozen=True)
class FilmMap:
    """Central-film correction table of one contact geometry + lubricant.

    Attributes
    ----------
    rx, ry, e_eff : geometry [m] and effective modulus [Pa].
    lubricant : the lubricant the map was computed for.
    log_load, log_speed : uniform grids of ln Q [ln N] and ln u [ln(m/s)].
    log_ratio : ln(h_solver / h_HD) at the nodes, shape (n_load, n_speed).
    h_central : solver central film [m] at the nodes (NaN where it failed).
    valid : nodes where the solver converged.
    grid : solver grid used.
    """

    rx: float
    ry: float
    e_eff: float
    lubricant: LubricantProperties
    log_load: np.ndarray
    log_speed: np.ndarray
    log_ratio: np.ndarray
    h_central: np.ndarray
    valid: np.ndarray
    grid: int

    def __post_init__(self):
        object.__setattr__(self, "_packed", pack_map_table(self.log_load, self.log_speed, self.log_ratio))

    @property
    def packed(self) -> np.ndarray:
        """The table as one float array (layout :data:`PACKED_HEADER`, then ``log_ratio``
        row-major): the input of :func:`packed_log_correction`, also inside compiled kernels."""
        return self._packed

    def log_correction(self, load, speed):
        """c(ln Q, ln u) and dc/d ln Q (bilinear interpolation, edge-clamped) at loads [N]
        and speeds [m/s] (broadcast): :func:`packed_log_correction` at each point."""
        lq = np.log(np.maximum(np.asarray(load, dtype=float), 1e-300))
        lu = np.log(np.maximum(np.asarray(speed, dtype=float), 1e-300))
        lq, lu = np.broadcast_arrays(lq, lu)
        c, dc = _log_correction_many(
            self._packed, np.ascontiguousarray(lq).reshape(-1), np.ascontiguousarray(lu).reshape(-1)
        )
        return c.reshape(lq.shape), dc.reshape(lq.shape)


#: header of :meth:`FilmMap.packed`: node counts, first ln Q, ln Q step, last ln Q,
#: first ln u, ln u step; the table log_ratio (n_load x n_speed, row-major) follows
PACKED_HEADER = (
    "n_load",
    "n_speed",
    "log_load_first",
    "log_load_step",
    "log_load_last",
    "log_speed_first",
    "log_speed_step",
)
_NH = len(PACKED_HEADER)


def pack_map_table(log_load, log_speed, log_ratio) -> np.ndarray:
    """One float array of a map's uniform grids and table (layout :data:`PACKED_HEADER`)."""
    gx, gy = np.asarray(log_load, dtype=float), np.asarray(log_speed, dtype=float)
    table = np.asarray(log_ratio, dtype=float)
    if table.shape != (gx.size, gy.size):
        raise InputError(f"EHL map table shape {table.shape} does not match the grids ({gx.size}, {gy.size})")
    step_x = gx[1] - gx[0] if gx.size > 1 else 1.0
    step_y = gy[1] - gy[0] if gy.size > 1 else 1.0
    return np.concatenate([[gx.size, gy.size, gx[0], step_x, gx[-1], gy[0], step_y], table.reshape(-1)])


@njit(cache=True)
def packed_log_correction(packed, lq, lu):
    """THE map interpolation: c = ln(h_solver / h_HD) at (ln Q, ln u) = (lq, lu) and
    dc/d ln Q, bilinear on the uniform grids of ``packed`` (:meth:`FilmMap.packed`).
    Outside the grid the nodes' edge values are held (clamped), and there the
    derivative is 0 (also exactly on the first and last ln Q node). Used by
    :meth:`FilmMap.log_correction` and by the compiled bearing row kernel
    (flexrv.model.bearing_kernel)."""
    nx, ny = int(packed[0]), int(packed[1])
    ix, tx, iy, ty = 0, 0.0, 0, 0.0
    inside = False
    if nx > 1:
        fx = min(max((lq - packed[2]) / packed[3], 0.0), nx - 1.0)
        ix = min(int(fx), nx - 2)
        tx = fx - ix
        inside = lq > packed[2] and lq < packed[4]
    if ny > 1:
        fy = min(max((lu - packed[5]) / packed[6], 0.0), ny - 1.0)
        iy = min(int(fy), ny - 2)
        ty = fy - iy
    ix1 = min(ix + 1, nx - 1)
    iy1 = min(iy + 1, ny - 1)
    f00 = packed[_NH + ix * ny + iy]
    f10 = packed[_NH + ix1 * ny + iy]
    f01 = packed[_NH + ix * ny + iy1]
    f11 = packed[_NH + ix1 * ny + iy1]
    val = (f00 * (1.0 - tx) + f10 * tx) * (1.0 - ty) + (f01 * (1.0 - tx) + f11 * tx) * ty
    dval = 0.0
    if inside:
        dval = ((f10 - f00) * (1.0 - ty) + (f11 - f01) * ty) / packed[3]
    return val, dval


@njit(cache=True)
def _log_correction_many(packed, lq, lu):
    """:func:`packed_log_correction` over flat arrays."""
    c = np.empty(lq.shape[0])
    dc = np.empty(lq.shape[0])
    for i in range(lq.shape[0]):
        c[i], dc[i] = packed_log_correction(packed, lq[i], lu[i])
    return c, dc


def _check_range(name, lo, hi, n):
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo <= hi):
        raise InputError(f"{name} range must satisfy 0 < min <= max, got ({lo!r}, {hi!r})")
    if n < 1 or (lo == hi and n != 1):
        raise InputError(f"{name} points must be >= 1 (1 when min == max), got {n}")


def build_film_map(
    rx,
    ry,
    e_eff,
    lubricant: LubricantProperties,
    load_range,
    speed_range,
    *,
    n_load: int = 6,
    n_speed: int = 4,
    grid: int = 129,
    **solver_kw,
) -> FilmMap:
    """Run the solver over a log-spaced load x speed grid (no caching; see
    :func:`film_map` for the cached version).

    Parameters
    ----------
    rx, ry : effective radii [m]; e_eff : E' [Pa]; lubricant : LubricantProperties.
    load_range : (Q_min, Q_max) [N]; speed_range : (u_min, u_max) [m/s].
    n_load, n_speed : nodes per axis (log-spaced).
    grid : solver grid (2^k + 1); default 129^2: second-order wedge + Richardson h_c (rv221 ball:
        130.3 nm against 141.8 nm from the first-order 65^2 grid; a 6 x 4 map takes ~36 s on one
        core, once, then it is cached).
    solver_kw : passed to :func:`flexrv.ehl.solver.solve_point_contact`; unless given,
        ``max_grid = grid``: the map is computed on the fixed grid (no adaptive refinement, so a
        node at an extreme load/speed cannot cost minutes; the grid change stays <= 1.3 % for
        the main-bearing balls, tests/test_ehl_convergence.py).

    Raises
    ------
    ConvergenceError
        If the solver converges at no node at all.
    """
    solver_kw.setdefault("max_grid", grid)
    _check_range("load", *load_range, n_load)
    _check_range("speed", *speed_range, n_speed)
    lubricant.check()
    lq = np.linspace(np.log(load_range[0]), np.log(load_range[1]), n_load)
    lu = np.linspace(np.log(speed_range[0]), np.log(speed_range[1]), n_speed)
    h = np.full((n_load, n_speed), np.nan)
    errors = []
    coarse_nodes: list = []
    for i, q in enumerate(np.exp(lq)):  # one solver run per node (each is a full 2-D solve)
        for j, u in enumerate(np.exp(lu)):
            try:
                with warnings.catch_warnings():  # per-node grid warnings: summarised below
                    warnings.simplefilter("ignore", RuntimeWarning)
                    res = solve_point_contact(q, u, rx, ry, e_eff, lubricant, grid=grid, **solver_kw)
                h[i, j] = res.h_central
                if not res.grid_converged:
                    coarse_nodes.append(res.grid_change)
            except ConvergenceError as exc:
                errors.append(str(exc))
    if coarse_nodes:
        warnings.warn(
            f"EHL map: at {len(coarse_nodes)} of {h.size} nodes h_c changed by more than the grid "
            f"tolerance from the next-coarser grid, or the grid has no coarser level to tell "
            f"(max {100 * np.nanmax(np.r_[coarse_nodes, 0.0]):.1f} %); "
            f"use a finer map grid",
            RuntimeWarning,
            stacklevel=2,
        )
    valid = np.isfinite(h)
    if not valid.any():
        raise ConvergenceError("EHL map: the solver converged at no node; first failure: " + errors[0])
    qq, uu = np.meshgrid(np.exp(lq), np.exp(lu), indexing="ij")
    h_hd, _ = hamrock_dowson(qq, uu, rx, ry, e_eff, lubricant.viscosity, lubricant.pressure_viscosity)
    ratio = np.log(h / h_hd)
    if not valid.all():  # nearest converged node in index space
        vi, vj = np.nonzero(valid)
        bi, bj = np.nonzero(~valid)
        d = (bi[:, None] - vi[None, :]) ** 2 + (bj[:, None] - vj[None, :]) ** 2
        k = np.argmin(d, axis=1)
        ratio[bi, bj] = ratio[vi[k], vj[k]]
    return FilmMap(
        rx=float(rx),
        ry=float(ry),
        e_eff=float(e_eff),
        lubricant=lubricant,
        log_load=lq,
        log_speed=lu,
        log_ratio=ratio,
        h_central=h,
        valid=valid,
        grid=grid,
    )


def film_map(
    rx,
    ry,
    e_eff,
    lubricant: LubricantProperties,
    load_range,
    speed_range,
    *,
    n_load: int = 6,
    n_speed: int = 4,
    grid: int = 129,
    **solver_kw,
) -> FilmMap:
    """Cached :func:`build_film_map`: loaded from ``cache_dir()/ehl_maps/<hash>.npz`` if present."""
    solver_kw.setdefault("max_grid", grid)
    key_inputs = dict(
        schema=MAP_SCHEMA,
        rx=float(rx),
        ry=float(ry),
        e_eff=float(e_eff),
        lubricant=asdict(lubricant),
        load_range=[float(v) for v in load_range],
        speed_range=[float(v) for v in speed_range],
        n_load=int(n_load),
        n_speed=int(n_speed),
        grid=int(grid),
        solver_kw=solver_kw,
        versions=library_versions("numpy", "scipy", "flexrv"),
    )
    key = content_hash(key_inputs)
    path = cache_dir() / "ehl_maps" / f"film_map_{key}.npz"

    def _load() -> FilmMap:
        with np.load(path) as data:
            return FilmMap(
                rx=float(rx),
                ry=float(ry),
                e_eff=float(e_eff),
                lubricant=lubricant,
                log_load=data["log_load"],
                log_speed=data["log_speed"],
                log_ratio=data["log_ratio"],
                h_central=data["h_central"],
                valid=data["valid"],
                grid=int(grid),
            )

    def _build() -> FilmMap:
        fmap = build_film_map(
            rx, ry, e_eff, lubricant, load_range, speed_range, n_load=n_load, n_speed=n_speed, grid=grid, **solver_kw
        )
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(
                    fh,
                    log_load=fmap.log_load,
                    log_speed=fmap.log_speed,
                    log_ratio=fmap.log_ratio,
                    h_central=fmap.h_central,
                    valid=fmap.valid,
                    inputs=np.array(json.dumps(key_inputs, default=str)),
                )
        return fmap

    fmap, _ = cached_entry([path], key, _load, _build)
    return fmap
