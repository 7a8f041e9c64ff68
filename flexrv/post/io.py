"""Save/load of a run directory: ``results.nc`` (NetCDF4 via h5netcdf),
``config.toml`` (the design used), ``summary.json``, ``summary.md`` and PNGs.
Every file is written atomically (:func:`flexrv.cache.atomic_path`)."""

from __future__ import annotations

import json
from pathlib import Path

from flexrv.cache import atomic_path, atomic_write_text


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def summary_markdown(res, summ: dict) -> str:
    """summary.md: run info, kinematic validation table, TE statistics."""
    lines = [f"# Simulation {summ['preset']} ({summ['model']} model)", "",
             f"status: **{summ['status']}**" + (f" — {summ['failure']}" if summ.get("failure") else ""), "",
             f"steady window: {summ['steady_window_s'][0]:.4g} – {summ['steady_window_s'][1]:.4g} s, "
             f"dt = {res.attrs.get('dt_s')} s, needle model {res.attrs.get('needle_model')}, "
             f"pin law {res.attrs.get('pin_law')}", "",
             *[f"> {note}\n" for note in summ.get("notes", [])],
             "## Kinematic validation (mean over the steady window)", "",
             "| quantity | unit | theory | simulated | error [%] |", "|---|---|---|---|---|"]
    for row in summ["kinematics"]:
        lines.append(f"| {row['quantity']} | {row['unit']} | {_fmt(row['theory'])} | {_fmt(row['simulated'])} | "
                     f"{_fmt(row['error_percent'])} |")
    lines += ["", "## Transmission error TE = theta_out - theta_in / i (steady window)", "",
              "| quantity | value | unit |", "|---|---|---|"]
    for key, unit in (("te_min_arcsec", "arcsec"), ("te_max_arcsec", "arcsec"), ("te_pp_arcsec", "arcsec"),
                      ("te_mean_arcsec", "arcsec"), ("te_rms_fluctuation_arcsec", "arcsec"),
                      ("max_pin_force_N", "N"), ("pins_in_contact_mean", "-"), ("pins_in_contact_max", "-"),
                      ("mean_input_power_W", "W"), ("mean_output_power_W", "W"), ("mean_dissipation_W", "W")):
        lines.append(f"| {key} | {_fmt(summ.get(key))} | {unit} |")
    return "\n".join(lines) + "\n"


def save(res, directory) -> Path:
    """Write a run directory; returns its path."""
    from flexrv.design import to_toml

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    with atomic_path(d / "results.nc") as tmp:
        res.ds.to_netcdf(tmp, engine="h5netcdf")
    if res.reducer is not None:
        atomic_write_text(d / "config.toml", to_toml(res.reducer))
    summ = res.summary()
    from flexrv.cache import to_jsonable

    atomic_write_text(d / "summary.json", json.dumps(to_jsonable(summ), indent=2))
    atomic_write_text(d / "summary.md", summary_markdown(res, summ))
    if len(res.time) > 1:
        res.plot(d)
    return d


def load_results(directory):
    """Read a run directory written by :func:`save`."""
    import xarray as xr

    from flexrv.design import load
    from flexrv.post.results import Results

    d = Path(directory)
    ds = xr.load_dataset(d / "results.nc", engine="h5netcdf")
    reducer = load(d / "config.toml") if (d / "config.toml").exists() else None
    return Results(ds, reducer=reducer)
