"""Quasi-static loaded TE results (:func:`flexrv.model.quasi_static.loaded_te`)
as an xarray Dataset with units, its order spectrum with labelled lines, the
summary numbers and the run directory (NetCDF, config, JSON, summary.md).

Everything here reads the result by output name; it never knows the model's
state layout.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from flexrv.cache import atomic_write_text, to_jsonable
from flexrv.post import definitions as defs
from flexrv.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD, RAD_PER_ARCMIN

if TYPE_CHECKING:  # xarray is imported where a Dataset is made (te_dataset)
    import xarray as xr


def te_dataset(result, reducer) -> xr.Dataset:
    """Dataset over the ``position`` dimension (coordinate: input angle [rad]).

    Variables: ``te`` and ``te_no_load`` [arcsec], ``output_angle`` [rad],
    ``output_revolutions`` [-] and every output the force groups declared
    (pin, needle, support and mesh forces, pins in contact, ...), with their
    units and long names. Catalog numbers and the solver figures are attributes.
    """
    import xarray as xr

    data = {
        "te": (("position",), result.te * ARCSEC_PER_RAD, {"units": "arcsec", "long_name": "loaded TE"}),
        "te_no_load": (
            ("position",),
            result.te_no_load * ARCSEC_PER_RAD,
            {"units": "arcsec", "long_name": "no-load (kinematic) TE"},
        ),
        "output_angle": (("position",), result.output_angle, {"units": "rad", "long_name": "output angle"}),
        "output_revolutions": (
            ("position",),
            result.input_angle / result.ratio / (2.0 * np.pi),
            {"units": "1", "long_name": "nominal output revolutions"},
        ),
    }
    for name, o in result.outputs.items():
        data[name] = (o.dims, np.asarray(o.values), {"units": o.units, "long_name": o.long_name})
    c = result.catalog
    for name, key, long in (
        ("catalog_lost_motion", "lost_motion_positions_rad", "rotation between -3 % and +3 % rated torque"),
        (
            "catalog_lost_motion_small",
            "backlash_positions_rad",
            "rotation between -T0 and +T0 (T0 = no_load_torque_Nm)",
        ),
    ):
        data[name] = (
            ("catalog_position",),
            np.asarray(c[key]) * ARCMIN_PER_RAD,
            {"units": "arcmin", "long_name": long},
        )
    play = np.asarray(c.get("play_positions_rad", np.zeros((len(c["lost_motion_positions_rad"]), 0))))
    data["catalog_play"] = (
        ("catalog_position", "play_fraction"),
        play * ARCMIN_PER_RAD,
        {"units": "arcmin", "long_name": "rotation between -f T_r and +f T_r (input locked)"},
    )
    ds = xr.Dataset(
        data,
        coords={
            "position": ("position", result.input_angle, {"units": "rad", "long_name": "input angle"}),
            "play_fraction": (
                "play_fraction",
                np.asarray(c.get("play_fractions", np.zeros(0)), dtype=float),
                {"units": "1", "long_name": "fraction of the rated torque of the play"},
            ),
        },
    )
    s = result.summary()
    ds.attrs.update(
        {
            "preset": reducer.name,
            "kind": "quasi-static loaded TE",
            "ratio": result.ratio,
            "torque_Nm": result.torque,
            "rated_torque_Nm": reducer.operating.rated_torque_Nm,
            "orders": json.dumps(result.orders),
            "summary": json.dumps(to_jsonable(s)),
        }
    )
    return ds


#: fewest positions of a TE spectrum: below, the DFT has fewer than four orders and no
#: line can be told from its neighbours (a run that short gets its summary without a spectrum)
MIN_SPECTRUM_POSITIONS = 8


def order_spectrum(te_arcsec: np.ndarray, output_revolutions: float):
    """Amplitude spectrum of TE sampled uniformly over ``output_revolutions``.

    Returns (order [cycles per output revolution], amplitude [arcsec]). A whole
    number of revolutions is one period of every error (pins fixed in the
    housing, discs turning with the output, cranks z_c times per revolution), so
    the plain DFT is exact there (a sine of amplitude A and integer order shows
    A); otherwise a Hann window (amplitude-corrected) limits the leakage.
    """
    x = np.asarray(te_arcsec, dtype=float)
    n = len(x)
    if n < MIN_SPECTRUM_POSITIONS:
        return np.zeros(0), np.zeros(0)
    x = x - x.mean()
    whole = abs(output_revolutions - round(output_revolutions)) < 1e-9 and round(output_revolutions) >= 1
    w = np.ones(n) if whole else np.hanning(n)
    amp = 2.0 * np.abs(np.fft.rfft(x * w)) / w.sum()
    order = np.fft.rfftfreq(n, d=output_revolutions / n)
    return order, amp


def spectrum_lines(order, amp, orders: dict[str, float], count: int = 8, harmonics: int = 12) -> list[dict]:
    """The ``count`` largest spectral lines (local maxima), each labelled with the
    characteristic order or harmonic ``h x name`` (h <= ``harmonics``) nearest to
    it within half a bin, else the simplest sideband ``h x name +- n x crank rotation``
    (n <= 6); ``-`` where none is."""
    if len(order) < 2:
        return []
    df = order[1] - order[0]
    a = amp.copy()
    a[0] = 0.0
    peaks = [i for i in range(1, len(a) - 1) if a[i] >= a[i - 1] and a[i] >= a[i + 1] and a[i] > 0]
    peaks.sort(key=lambda i: -a[i])
    out = []
    for i in peaks[:count]:
        best = None
        for name, o in orders.items():
            h = int(round(order[i] / o))
            if 1 <= h <= harmonics:
                d = abs(order[i] - h * o)
                if d <= 0.5 * df + 1e-9 and (best is None or (d, h) < best[:2]):
                    best = (d, h, name if h == 1 else f"{h} x {name}")
        if best is None:  # a sideband: h x mesh +- n x crank rotation (else the slowest order)
            base = "crank rotation" if "crank rotation" in orders else min(orders, key=orders.get)
            for name, o in orders.items():
                for h in range(1, harmonics + 1):
                    n = int(round((order[i] - h * o) / orders[base]))
                    d = abs(order[i] - h * o - n * orders[base])
                    if (
                        name != base
                        and 1 <= abs(n) <= 6
                        and d <= 0.5 * df + 1e-9
                        and (best is None or (d, abs(n) + h) < best[:2])
                    ):
                        head = name if h == 1 else f"{h} x {name}"
                        best = (d, abs(n) + h, f"{head} {'+' if n > 0 else '-'} {abs(n)} x {base}")
        out.append({"order": float(order[i]), "amplitude_arcsec": float(a[i]), "label": best[2] if best else "-"})
    return out


#: the quasi-static model's summary keys replaced by the named figures
_UNNAMED = (
    "torsional_rigidity_Nm_per_arcmin",
    "catalog_rigidity_Nm_per_arcmin",
    "low_torque_rigidity_Nm_per_arcmin",
)


def named_figures(ds: xr.Dataset, s: dict) -> dict:
    """The named figures (:mod:`flexrv.post.definitions`) of the quasi-static route: the
    plays at +-3 %, +-T0 and +-T0/2 of each catalog position (input locked) give the lost
    motions and the geometric backlash (from T0/2 and T0,
    :func:`flexrv.post.definitions.extrapolated_play`, per position, the largest over the
    positions as for the lost motion); the rigidities are the
    model's tangent (condensed Jacobian, at the operating torque), its 50-100 % and 3-50 %
    secants, and the loop secant 2 T_r / (theta(+T_r) - theta(-T_r)) of the loop these make
    with the largest lost motion, the loading branches point-symmetric:
    theta(+T_r) - theta(-T_r) = 2 (0.47 T_r / k_low + 0.5 T_r / k_50_100) + lost motion."""
    rated = float(ds.attrs.get("rated_torque_Nm", s["torque_Nm"]))
    t0 = float(s["no_load_torque_Nm"])
    lm = ds["catalog_lost_motion"].values
    small = ds["catalog_lost_motion_small"].values
    k50 = s["catalog_rigidity_Nm_per_arcmin"]
    k_low = s.get("low_torque_rigidity_Nm_per_arcmin", float("nan"))
    span = 2.0 * ((0.5 - defs.LOST_MOTION_FRACTION) * rated / k_low + 0.5 * rated / k50) + float(np.max(lm))
    out = {
        "rigidity_tangent_Nm_per_arcmin": s["torsional_rigidity_Nm_per_arcmin"],
        "rigidity_slope_50_100_Nm_per_arcmin": k50,
        "rigidity_low_torque_Nm_per_arcmin": k_low,
        "rigidity_loop_secant_Nm_per_arcmin": defs.loop_secant(rated, span),
        "lost_motion_arcmin": float(np.max(lm)),
        "lost_motion_small_torque_arcmin": float(np.max(small)),
        "backlash_arcmin": _backlash(ds, rated),
        "tangent_torque_Nm": s["torque_Nm"],
    }
    if abs(t0 - defs.ONE_PERCENT * rated) <= 1e-9 * rated:
        out["lost_motion_1pct_arcmin"] = out["lost_motion_small_torque_arcmin"]
    out.update(defs.te_figures(ds["position"].values, ds["te"].values / ARCSEC_PER_RAD))
    for key in _UNNAMED:
        s.pop(key, None)
    s.pop("backlash_arcmin", None)
    return out


def _backlash(ds: xr.Dataset, rated: float) -> float:
    """The geometric backlash of the quasi-static route: the plays at the two smallest
    ``play_fraction`` of each catalog position extrapolated to zero torque, the largest over
    the positions (NaN without two play fractions)."""
    if ds.sizes.get("play_fraction", 0) < 2:
        return float("nan")
    f = ds["play_fraction"].values
    p = ds["catalog_play"].values
    (i1, i2) = np.argsort(f)[:2]
    return float(np.max(defs.extrapolated_play(f[i1] * rated, p[:, i1], f[i2] * rated, p[:, i2])))


def te_summary(ds: xr.Dataset) -> dict:
    """The numbers ``flexrv te --json`` prints (keys name their unit)."""
    s = json.loads(ds.attrs["summary"])
    s.update(named_figures(ds, s))
    revs = float(ds["output_revolutions"].values[-1] - ds["output_revolutions"].values[0])
    n = ds.sizes["position"]
    revs = revs * n / max(n - 1, 1)  # the positions span [0, revs) with n uniform points
    order, amp = order_spectrum(ds["te"].values, revs)
    s["spectrum_lines"] = spectrum_lines(order, amp, json.loads(ds.attrs["orders"]))
    s["spectral_resolution_orders"] = float(order[1] - order[0]) if len(order) > 1 else None
    if len(order) < 2:
        s["spectrum_note"] = (
            f"no TE spectrum: {n} positions, a spectrum needs at least {MIN_SPECTRUM_POSITIONS} "
            "(a longer range or more points per mesh period)"
        )
    s["output_revolutions"] = revs
    for name, key in (
        ("pin_force", "max_pin_force_N"),
        ("needle_force", "max_needle_force_N"),
        ("crank_support_force", "max_support_force_N"),
        ("mesh_force", "max_mesh_force_N"),
    ):
        if name in ds:
            s[key] = float(np.max(ds[name].values))
    if "pins_in_contact" in ds:
        pic = ds["pins_in_contact"].values
        s["pins_in_contact_min"], s["pins_in_contact_max"] = int(pic.min()), int(pic.max())
    return s


#: the named figures of a te run's summary table
TE_ROWS = (
    "rigidity_tangent_Nm_per_arcmin",
    "rigidity_slope_50_100_Nm_per_arcmin",
    "rigidity_low_torque_Nm_per_arcmin",
    "rigidity_loop_secant_Nm_per_arcmin",
    "lost_motion_arcmin",
    "backlash_arcmin",
)


def te_summary_markdown(summary: dict, reducer, errors_note: str = "") -> str:
    """summary.md of a ``flexrv te`` run, every number from ``summary``."""
    s = summary
    rows = [
        ("loaded TE, peak to peak", s["te_pp_arcsec"], "arcsec"),
        ("loaded TE, mean (wind-up)", s["te_mean_arcsec"], "arcsec"),
        ("no-load TE, peak to peak", s["no_load_te_pp_arcsec"], "arcsec"),
        *[(f"`{k}`: {defs.DEFINITIONS[k][1]}", s.get(k, float("nan")), defs.DEFINITIONS[k][0]) for k in TE_ROWS],
        (
            f"`lost_motion_small_torque_arcmin`: rotation between ±{s['no_load_torque_Nm']:.3g} N m",
            s["lost_motion_small_torque_arcmin"],
            "arcmin",
        ),
        ("max pin force", s.get("max_pin_force_N"), "N"),
        ("max needle-bearing force", s.get("max_needle_force_N"), "N"),
        ("max crank-support force", s.get("max_support_force_N"), "N"),
        ("pins in contact per disc", f"{s.get('pins_in_contact_min')}–{s.get('pins_in_contact_max')}", "-"),
    ]
    lines = [
        f"# Quasi-static loaded TE: {reducer.name}",
        "",
        f"Output torque {s['torque_Nm']:.6g} N m, {s['positions']} positions over "
        f"{s['output_revolutions']:.4g} output revolutions, solved in {s['solve_time_s']:.3g} s "
        f"({s['mean_iterations']:.2f} Newton iterations per position).",
        "",
    ]
    if errors_note:
        lines += [errors_note, ""]
    if s.get("unconverged_positions"):
        lines += [
            f"{s['unconverged_positions']} positions did not converge (NaN in the curves; "
            "`unconverged_positions` in summary.json and `--json`).",
            "",
        ]
    lines += ["| quantity | value | unit |", "|---|---|---|"]
    for name, value, unit in rows:
        v = f"{value:.4g}" if isinstance(value, float) else str(value)
        lines.append(f"| {name} | {v} | {unit} |")
    budget = s.get("compliance_budget_percent") or {}
    if budget:
        lines += [
            "",
            "## Compliance budget at the operating torque (share of the torsional compliance)",
            "",
            "| element | share [%] |",
            "|---|---|",
        ]
        for name, share in sorted(budget.items(), key=lambda kv: -kv[1]):
            lines.append(f"| {name.replace('_', ' ')} | {share:.1f} |")
    lines += ["", "## Largest TE spectrum lines (orders of the output rotation)", ""]
    if s.get("spectral_resolution_orders") is None:
        lines.append(s.get("spectrum_note", "no TE spectrum") + ".")
    else:
        lines += [
            f"Resolution {s['spectral_resolution_orders']:.3g} orders.",
            "",
            "| order | amplitude [arcsec] | nearest characteristic order |",
            "|---|---|---|",
        ]
        for line in s["spectrum_lines"]:
            lines.append(f"| {line['order']:.4g} | {line['amplitude_arcsec']:.3g} | {line['label']} |")
    lines += [
        "",
        f"Definitions: TE = theta_out - theta_in / i; no-load TE at {s['no_load_torque_Nm']:.3g} N m; every "
        "other figure is named by its definition (flexrv.post.definitions, docs/definitions.md); lost motion "
        "and backlash are read with the input locked, the largest over the evaluated positions; the tangent "
        f"at {s['tangent_torque_Nm']:.6g} N m; rigidity in N m/arcmin (1 arcmin = {RAD_PER_ARCMIN:.4e} rad).",
    ]
    return "\n".join(lines) + "\n"


def save_te(ds: xr.Dataset, summary: dict, reducer, directory, errors_note: str = "") -> Path:
    """Write ``results.nc``, ``config.toml``, ``summary.json`` and ``summary.md``
    atomically into ``directory``; returns its path."""
    from flexrv.design import to_toml
    from flexrv.post.io import write_netcdf

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    write_netcdf(ds, d / "results.nc")
    atomic_write_text(d / "config.toml", to_toml(reducer))
    atomic_write_text(d / "summary.json", json.dumps(to_jsonable(summary), indent=2))
    atomic_write_text(d / "summary.md", te_summary_markdown(summary, reducer, errors_note))
    return d
