"""Save/load of a run directory: ``results.nc`` (NetCDF4 via h5netcdf),
``config.toml`` (the design used), ``summary.json``, ``summary.md``, PNGs and,
while a run is going, ``checkpoint.npz`` (the recorded states, for
``flexrv simulate --resume``). Every file is written atomically
(:func:`flexrv.cache.atomic_path`); ``results.nc`` is written last, so a
``results.nc`` with status "completed" implies the other files are there."""

from __future__ import annotations

import contextlib
import gc
import io
import json
import sys
from pathlib import Path

import numpy as np

from flexrv.cache import atomic_path, atomic_write_text
from flexrv.post.format import fmt as _fmt
from flexrv.post.stats import summary_table


def summary_markdown(res, summ: dict) -> str:
    """summary.md: run info, kinematic validation table, the run's summary keys
    (:data:`flexrv.post.stats.SUMMARY_KEYS`, units from the declared outputs) and the force
    elements' declared summary rows."""
    lines = [
        f"# Simulation {summ['preset']} ({summ['model']} model)",
        "",
        f"status: **{summ['status']}**" + (f" — {summ['failure']}" if summ.get("failure") else ""),
        "",
        f"steady window: {summ['steady_window_s'][0]:.4g} – {summ['steady_window_s'][1]:.4g} s, "
        f"dt = {res.attrs.get('dt_s')} s, needle model {res.attrs.get('needle_model')}, "
        f"pin law {res.attrs.get('pin_law')}",
        "",
        *[f"> {note}\n" for note in summ.get("notes", [])],
        "## Kinematic validation (mean over the steady window)",
        "",
        "| quantity | unit | theory | simulated | error [%] |",
        "|---|---|---|---|---|",
    ]
    for row in summ["kinematics"]:
        lines.append(
            f"| {row['quantity']} | {row['unit']} | {_fmt(row['theory'])} | {_fmt(row['simulated'])} | "
            f"{_fmt(row['error_percent'])} |"
        )
    lines += [
        "",
        "## Transmission error TE = theta_out - theta_in / i (steady window)",
        "",
        "| quantity | value | unit |",
        "|---|---|---|",
    ]
    for key, value, unit in summary_table(summ):  # the listed keys of flexrv.post.stats.SUMMARY_KEYS
        lines.append(f"| {key} | {_fmt(value)} | {unit} |")
    rows = summ.get("elements") or {}
    if rows:
        lines += ["", "## Force elements (steady window)", "", "| quantity | value | unit | description |"]
        lines.append("|---|---|---|---|")
        for key, row in rows.items():
            lines.append(f"| {key} | {_fmt(row['value'])} | {row['units']} | {row['description']} |")
    return "\n".join(lines) + "\n"


def save(res, directory, figures=None) -> Path:
    """Write a run directory; returns its path. ``figures(directory)``, if given, writes the
    run's PNGs (runs of more than one record) before ``results.nc``, which comes last."""
    from flexrv.design import to_toml

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    if res.reducer is not None:
        atomic_write_text(d / "config.toml", to_toml(res.reducer))
    summ = res.summary()
    from flexrv.cache import to_jsonable

    if figures is not None and len(res.time) > 1:
        with collector_paused():
            figures(d)
    atomic_write_text(d / "summary.json", json.dumps(to_jsonable(summ), indent=2))
    atomic_write_text(d / "summary.md", summary_markdown(res, summ))
    write_netcdf(res.ds, d / "results.nc")
    return d


@contextlib.contextmanager
def _modules_hidden(names):
    """Inside the block, each module of ``names`` not imported yet cannot be imported
    (``sys.modules[name] = None`` makes its import fail, which xarray reads as "not
    installed"); afterwards the names are importable again."""
    hidden = [name for name in names if name not in sys.modules]
    for name in hidden:
        sys.modules[name] = None
    try:
        yield
    finally:
        for name in hidden:
            if sys.modules.get(name, 0) is None:
                del sys.modules[name]


@contextlib.contextmanager
def collector_paused():
    """Inside the block Python's cyclic garbage collector does not run (reference counting
    still frees everything that is not in a cycle); afterwards it runs as before and collects
    the block's cycles with its next young-generation pass. Writing figures and NetCDF files
    makes tens of thousands of short-lived container objects (matplotlib artists, ticks,
    transforms; h5py handles), which under Python's default thresholds (a notebook, a script;
    the CLI raises them) trigger full collections: each one walks the whole heap of a process
    that has imported numba, Exudyn and scipy (~2e5 objects), ~0.1 s a pass, for no garbage of
    the process's own. A block inside another one (or with the collector
    switched off by the caller) leaves the collector as it found it."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def xarray_without_dask() -> None:
    """Let xarray know, once per process, that this process uses no dask arrays: xarray asks
    on its first variable whether its data is a dask array, importing ``dask.array`` (~0.4 s
    CPU) to find out, and keeps the answer. For a command that never makes dask arrays (``te``,
    ``simulate``) dask is hidden from that first question (:func:`_modules_hidden`). Nothing
    happens where dask is imported already (a study that uses it, a test session)."""
    if "dask" in sys.modules:
        return
    import xarray as xr

    with _modules_hidden(("dask",)):
        xr.Variable(("x",), np.zeros(1))


def write_netcdf(ds, path) -> Path:
    """Write ``ds`` to ``path`` atomically (NetCDF4 via h5netcdf), with the cyclic collector
    paused (:func:`collector_paused`).

    xarray's writer asks dask for the active scheduler to choose its file lock, importing
    ``dask.base`` and ``distributed`` (~0.5 s CPU together). A process that has imported
    neither holds no dask collection and no distributed client, so the answer is xarray's
    default (the threaded lock) either way: a module not imported yet is hidden from that probe
    (:func:`_modules_hidden`)."""
    path = Path(path)
    with collector_paused(), _modules_hidden(("dask", "dask.base", "distributed")), atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
    return path


def save_partial(res, directory) -> Path:
    """Checkpoint of a running simulation: ``results.nc`` (status "running") and
    ``config.toml`` only (no summary, no plots: cheap enough to repeat)."""
    from flexrv.design import to_toml

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    if res.reducer is not None and not (d / "config.toml").exists():
        atomic_write_text(d / "config.toml", to_toml(res.reducer))
    write_netcdf(res.ds, d / "results.nc")
    return d


CHECKPOINT = "checkpoint.npz"


def save_checkpoint(directory, t, q, v, meta: dict, reducer, a_last=None, records=None) -> Path:
    """Write the recorded states (t, q, v) of a run, its run options ``meta`` and
    its design atomically to ``<directory>/checkpoint.npz``; ``records``: (list of
    arrays, valid (elements, samples)) of the recording elements' records at the samples before the last row
    (:meth:`flexrv.model.kernels.HistoryRecorder.arrays`)."""
    from flexrv.cache import atomic_write_bytes, to_jsonable
    from flexrv.design import to_toml

    extra = {} if a_last is None else {"a": np.asarray(a_last, dtype=float)}
    if records is not None:
        arrays, valid = records
        extra["rec_valid"] = np.asarray(valid, dtype=bool)
        extra.update({f"rec_{i}": np.asarray(a, dtype=float) for i, a in enumerate(arrays)})
    buf = io.BytesIO()
    np.savez(
        buf,
        t=np.asarray(t, dtype=float),
        q=np.asarray(q, dtype=float),
        v=np.asarray(v, dtype=float),
        meta=np.array(json.dumps(to_jsonable(meta))),
        config=np.array(to_toml(reducer)),
        **extra,
    )
    return atomic_write_bytes(Path(directory) / CHECKPOINT, buf.getvalue())


def load_checkpoint(directory) -> dict:
    """Read ``checkpoint.npz`` of a run directory: t, q, v, meta, reducer.

    Raises InputError naming the directory if there is none or it is unreadable."""
    from flexrv.design import loads
    from flexrv.errors import InputError

    path = Path(directory) / CHECKPOINT
    if not path.is_file():
        raise InputError(
            f"--resume {directory}: no {CHECKPOINT} there (not a run directory of flexrv simulate, "
            "or the run was killed before its first checkpoint)"
        )
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {
                "t": z["t"],
                "q": z["q"],
                "v": z["v"],
                "meta": json.loads(str(z["meta"])),
                "config": str(z["config"]),
                "a": z["a"] if "a" in z.files else None,
                "records": None,
            }
            if "rec_valid" in z.files:
                n_rec = sum(1 for f in z.files if f.startswith("rec_") and f != "rec_valid")
                data["records"] = ([z[f"rec_{i}"] for i in range(n_rec)], z["rec_valid"])
    except Exception as exc:  # truncated / foreign file
        raise InputError(f"--resume {directory}: {CHECKPOINT} is unreadable ({type(exc).__name__}: {exc})") from None
    if not data["meta"].get("resumable", True):
        raise InputError(f"--resume {directory}: the run used a custom drive or load program and cannot be resumed")
    if len(data["t"]) < 1:
        raise InputError(f"--resume {directory}: {CHECKPOINT} holds no state")
    data["reducer"] = loads(data["config"], source=f"{path} (config)")
    return data


def read_run(directory):
    """(dataset, design or None) of a run directory written by :func:`save`.

    Raises InputError naming the directory if it holds no readable ``results.nc``."""
    import xarray as xr

    from flexrv.design import load
    from flexrv.errors import InputError

    d = Path(directory)
    try:
        ds = xr.load_dataset(d / "results.nc", engine="h5netcdf")
    except FileNotFoundError:
        raise InputError(f"{d} is not a result folder (no results.nc)") from None
    except Exception as exc:  # not NetCDF / truncated
        raise InputError(
            f"{d / 'results.nc'} is not a readable flexrv NetCDF file "
            f"({type(exc).__name__}: {' '.join(str(exc).split())[:200]})"
        ) from None
    reducer = load(d / "config.toml") if (d / "config.toml").exists() else None
    return ds, reducer
