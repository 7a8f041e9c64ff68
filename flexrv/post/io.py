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
    """Write ``ds`` to ``path`` atomically as NetCDF-4 (HDF5).

    A dataset of numeric variables on dimensions that are either plain or indexed by their own
    one-dimensional coordinate, with text and number attributes and no encoding of its own (what
    flexrv builds) is written by :func:`_write_netcdf4` with h5py: the file xarray's h5netcdf
    writer makes (variables, dimensions, attributes, fill values, values), without that writer's
    per-variable bookkeeping (a dozen HDF5 look-ups per variable, ~4 ms each variable). Any other
    dataset goes through xarray (``engine="h5netcdf"``).

    xarray's writer asks dask for the active scheduler to choose its file lock, importing
    ``dask.base`` and ``distributed`` (~0.5 s CPU together). A process that has imported
    neither holds no dask collection and no distributed client, so the answer is xarray's
    default (the threaded lock) either way: a module not imported yet is hidden from that probe
    (:func:`_modules_hidden`)."""
    path = Path(path)
    direct = _netcdf4_writable(ds)
    with collector_paused(), _modules_hidden(("dask", "dask.base", "distributed")), atomic_path(path) as tmp:
        if direct:
            _write_netcdf4(ds, tmp)
        else:
            ds.to_netcdf(tmp, engine="h5netcdf")
    return path


#: the HDF5 dimension-scale name of a dimension without a coordinate variable (the NetCDF-4 convention)
_NOT_A_VARIABLE = b"This is a netCDF dimension but not a netCDF variable."

#: attribute names the NetCDF-4 layout or xarray's encoding own
_RESERVED_ATTRS = frozenset(
    {"_FillValue", "missing_value", "_Netcdf4Dimid", "_Netcdf4Coordinates", "_NCProperties", "CLASS", "NAME"}
    | {"REFERENCE_LIST", "DIMENSION_LIST", "coordinates", "dtype", "scale_factor", "add_offset", "calendar"}
)


def _plain_attrs(attrs) -> bool:
    """True if every attribute is text or a real number (not a bool) under a name of its own."""
    for key, value in attrs.items():
        if not isinstance(key, str) or key in _RESERVED_ATTRS or isinstance(value, (bool, np.bool_)):
            return False
        if not isinstance(value, (str, int, float, np.integer, np.floating)):
            return False
    return True


def _netcdf4_writable(ds) -> bool:
    """True if :func:`_write_netcdf4` writes ``ds`` as xarray's h5netcdf writer does: integer,
    float and text variables of at least one dimension, none of size 0; every coordinate the index of its
    own dimension; plain attributes (:func:`_plain_attrs`); no encoding set (a dataset read from
    a file carries its file's)."""
    if set(ds.encoding) - {"source"} or ds.encoding.get("unlimited_dims") or not _plain_attrs(ds.attrs):
        return False
    for name, var in ds.variables.items():
        if not isinstance(name, str) or var.encoding or var.dtype.kind not in "iufU" or var.ndim == 0:
            return False
        if (name in ds.coords or name in ds.dims) and var.dims != (name,):
            return False
        if 0 in var.shape or not _plain_attrs(var.attrs) or not all(isinstance(d, str) for d in var.dims):
            return False
    return True


def _attr_value(value):
    """An attribute as NetCDF-4 stores it: text as a UTF-8 string, a number as a 1-element array."""
    return value if isinstance(value, str) else np.atleast_1d(np.asarray(value))


def _write_netcdf4(ds, path) -> None:
    """Write ``ds`` (:func:`_netcdf4_writable`) to ``path`` in the NetCDF-4 layout xarray's
    h5netcdf writer makes: the dimensions numbered in order of first use over the variables;
    a dimension without a coordinate variable as an empty dimension scale (``>f4``, its size
    in its name); every variable a contiguous dataset (text as variable-length UTF-8) in the dataset's order with
    ``_Netcdf4Coordinates`` (its dimensions' numbers), ``_Netcdf4Dimid`` (its first one's), a
    float variable's fill value NaN (``_FillValue``) and its attributes, attached to its
    dimensions' scales; the file's attributes and ``_NCProperties`` (who wrote it)."""
    import h5py

    from flexrv._version import __version__

    dimids: dict[str, int] = {}
    for var in ds.variables.values():
        for dim in var.dims:
            dimids.setdefault(dim, len(dimids))
    with h5py.File(path, "w", track_order=True) as f:
        for key, value in ds.attrs.items():
            f.attrs[key] = _attr_value(value)
        scales = {}
        for dim, dimid in dimids.items():
            if dim not in ds.variables:
                scale = f.create_dataset(dim, shape=(ds.sizes[dim],), dtype=">f4", track_order=True)
                scale.attrs["_Netcdf4Dimid"] = np.int32(dimid)
                scale.make_scale(_NOT_A_VARIABLE + f"{ds.sizes[dim]:10}".encode("ascii"))
                scales[dim] = scale
        datasets = {}
        for name, var in ds.variables.items():
            values = np.ascontiguousarray(var.values)
            fill = np.nan if values.dtype.kind == "f" else None
            if values.dtype.kind == "U":
                h5 = f.create_dataset(name, data=values.astype(object), dtype=h5py.string_dtype(), track_order=True)
            else:
                h5 = f.create_dataset(name, data=values, fillvalue=fill, track_order=True)
            if var.dims == (name,):
                h5.make_scale(name)
                scales[name] = h5
            h5.attrs["_Netcdf4Coordinates"] = np.array([dimids[d] for d in var.dims], dtype=np.int32)
            h5.attrs["_Netcdf4Dimid"] = np.int32(dimids[var.dims[0]])
            if fill is not None:
                h5.attrs["_FillValue"] = np.array([fill], dtype=values.dtype)
            for key, value in var.attrs.items():
                h5.attrs[key] = _attr_value(value)
            datasets[name] = h5
        for name, var in ds.variables.items():
            if var.dims != (name,):
                for axis, dim in enumerate(var.dims):
                    datasets[name].dims[axis].attach_scale(scales[dim])
        provenance = f"version=2,flexrv={__version__},hdf5={h5py.version.hdf5_version},h5py={h5py.__version__}"
        f.attrs["_NCProperties"] = np.array(provenance, dtype=h5py.string_dtype("ascii", len(provenance)))


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
