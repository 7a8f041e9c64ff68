"""Shared helpers of the CLI command modules: output in JSON or as a table."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

import numpy as np
from rich.console import Console
from rich.table import Table

from flexrv.cache import to_jsonable  # noqa: F401  (re-exported for the CLI modules)
from flexrv.post.format import fmt  # noqa: F401  (one number format for every table)

#: stdout console; markup off: paths, names and values are printed literally
#: (``[/x].toml`` is a valid file name, ``[s]`` a unit), styles are passed explicitly
console = Console(markup=False)

#: help of a command's design argument (a preset name or a TOML path)
PRESET_HELP = "Preset name (see `flexrv presets`) or path to a design TOML file."
JSON_HELP = "Print machine-readable JSON on stdout instead of a table."


def print_json(data: Any) -> None:
    """Write ``data`` as indented strict JSON to stdout."""
    print(json.dumps(to_jsonable(data), indent=2))


def emit(data: Any, as_json: bool, render: Callable[[Any], None]) -> None:
    """Print ``data`` as JSON (``as_json``) or through the human ``render`` function."""
    if as_json:
        print_json(data)
    else:
        render(data)


def kv_table(title: str, rows: list[tuple[str, Any, str]]) -> Table:
    """A three-column table (quantity, value, unit); long cells wrap, never cut, so that
    names and paths can be copied."""
    table = Table(title=title, title_justify="left")
    table.add_column("quantity", overflow="fold")
    table.add_column("value", justify="right", overflow="fold")
    table.add_column("unit", overflow="fold")
    for name, value, unit in rows:
        table.add_row(name, fmt(value), unit)
    return table


def render_nested(title: str, data: dict[str, Any]) -> None:
    """Render a nested result dict as one table per section.

    Leaves are shown as ``key | value``; the unit is read from the key suffix
    convention used throughout flexrv (``max_force_N``, ``stiffness_Nm_per_rad``).
    Lists of numbers are shown compactly; lists of dicts as sub-tables.
    """
    console.print(title, style="bold")
    flat: list[tuple[str, Any, str]] = []
    for key, value in data.items():
        if isinstance(value, dict):
            _render_section(key, value)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            _render_records(key, value)
        else:
            label, unit = split_unit(key)
            flat.append((label, _compact(value), unit))
    if flat:
        console.print(kv_table("", flat))


#: unit tokens of flexrv's unit-suffixed keys (``max_force_N``, ``C_W_seed004_Nm_per_rad``)
_UNIT_TOKENS = {
    "N",
    "Nm",
    "Pa",
    "kPa",
    "MPa",
    "GPa",
    "Hz",
    "W",
    "J",
    "m",
    "mm",
    "um",
    "nm",
    "s",
    "ms",
    "rad",
    "rpm",
    "deg",
    "arcsec",
    "arcmin",
    "kg",
    "m2",
    "m3",
    "percent",
}
#: suffixes whose plain reading (tokens joined by spaces) is wrong
_UNIT_SPECIAL = {("m", "s"): "m/s", ("rad", "s"): "rad/s", ("kg", "m3"): "kg/m³", ("mm", "s"): "mm/s"}
_UNIT_PRETTY = {"Nm": "N m", "um": "µm", "m2": "m²", "m3": "m³", "percent": "%"}


def split_unit(key: str) -> tuple[str, str]:
    """Split flexrv's unit-suffixed keys into (label, unit): the unit is the longest run
    of unit tokens (and ``per``) at the END of the key, leaving at least one label token:
    ``"max_force_N"`` -> (``"max_force"``, ``"N"``), ``"C_W_seed004_Nm_per_rad"`` ->
    (``"C_W_seed004"``, ``"N m/rad"``), ``"entrainment_speed_m_s"`` -> (``"entrainment_speed"``,
    ``"m/s"``), ``"entrainment_speed"`` -> (``"entrainment_speed"``, ``""``)."""
    tokens = key.split("_")
    k = len(tokens)
    while k > 1 and (tokens[k - 1] in _UNIT_TOKENS or (tokens[k - 1] == "per" and k < len(tokens))):
        k -= 1
    while k < len(tokens) and tokens[k] == "per":  # a unit cannot start with "per"
        k += 1
    unit_tokens = tokens[k:]
    if not unit_tokens:
        return key, ""
    label = "_".join(tokens[:k])
    special = _UNIT_SPECIAL.get(tuple(unit_tokens))
    if special:
        return label, special
    unit = " ".join(_UNIT_PRETTY.get(t, t) for t in unit_tokens).replace(" per ", "/")
    return label, unit


def _compact(value: Any) -> Any:
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = list(value)
        if len(arr) > 8:
            return "[" + ", ".join(fmt(v) for v in arr[:6]) + f", ... ({len(arr)} values)]"
        return "[" + ", ".join(fmt(v) for v in arr) + "]"
    return value


def _render_section(name: str, section: dict[str, Any], prefix: str = "") -> None:
    rows: list[tuple[str, Any, str]] = []
    nested: list[tuple[str, dict]] = []
    for key, value in section.items():
        if isinstance(value, dict):
            nested.append((key, value))
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            _render_records(f"{prefix}{name}.{key}", value)
        else:
            label, unit = split_unit(key)
            rows.append((label, _compact(value), unit))
    if rows:
        console.print(kv_table(f"{prefix}{name}", rows))
    for key, value in nested:
        _render_section(key, value, prefix=f"{prefix}{name}.")


def _render_records(name: str, records: list[dict[str, Any]]) -> None:
    table = Table(title=name, title_justify="left")
    columns = list(records[0].keys())
    for col in columns:
        table.add_column(col, justify="right", overflow="fold")
    for rec in records[:60]:
        table.add_row(*(fmt(_compact(rec.get(c))) for c in columns))
    console.print(table)


# ------------------------------------------------------------ output paths, before any work
#: files a run writes into its output directory (removed by --overwrite)
OVERWRITE_HELP = "Allow an existing non-empty --out directory (the files of the earlier run are removed)."

#: files of an earlier run that --overwrite removes
RUN_FILES = ("results.nc", "config.toml", "summary.json", "summary.md", "checkpoint.npz")


def _probe_writable(directory: Path, option: str) -> None:
    """InputError naming the option unless ``directory`` can be created and written:
    its nearest existing ancestor must be a directory in which a probe file can be
    created (and is removed again). Nothing else is created, so concurrent runs
    probing the same new path do not race."""
    import os
    import tempfile

    from flexrv.errors import InputError

    d = Path(directory)
    while not d.exists() and d.parent != d:
        d = d.parent
    if not d.is_dir():
        raise InputError(f"{option} {directory}: {d} exists and is not a directory")
    try:
        fd, probe = tempfile.mkstemp(prefix=".flexrv-probe.", dir=d)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"{option} {directory}: not writable ({d}: {exc.strerror or exc})") from None


#: output folders of this process that did not exist before it (the first new ancestor
#: of each): :func:`remove_unused_outputs` deletes them again if a failed or stopped
#: command left them empty
_NEW_OUTPUTS: list[Path] = []


def _register_new(path: Path) -> None:
    top = None
    d = Path(path).absolute()
    while not d.exists() and d.parent != d:
        top, d = d, d.parent
    if top is not None:
        _NEW_OUTPUTS.append(top)


def remove_unused_outputs() -> list[Path]:
    """Delete the output folders this process created (:func:`check_output_dir`) that
    hold no file (a command that failed or was stopped before writing anything leaves
    no empty run folder). Returns the removed folders."""
    removed = []
    for top in _NEW_OUTPUTS:
        if not top.is_dir():
            continue
        dirs = sorted((p for p in top.rglob("*") if p.is_dir()), key=lambda p: -len(p.parts)) + [top]
        if any(p.is_file() or p.is_symlink() for p in top.rglob("*")):
            continue
        for d in dirs:
            try:
                d.rmdir()
                removed.append(d)
            except OSError:
                break
    _NEW_OUTPUTS.clear()
    return removed


def check_output_dir(path: Path, option: str = "--out", overwrite: bool = False, allow_existing: bool = False) -> Path:
    """Check an output directory before any work: it must be a directory (or not
    exist) and be writable; an existing non-empty directory is refused unless
    ``overwrite`` (then the files of an earlier run are removed) or
    ``allow_existing`` (e.g. a resumable sweep). Raises InputError naming the option."""
    from flexrv.errors import InputError

    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{option} {path}: exists and is not a directory")
    if path.is_dir() and any(path.iterdir()) and not allow_existing:
        if not overwrite:
            raise InputError(
                f"{option} {path}: directory exists and is not empty; choose another directory or pass --overwrite"
            )
        for name in RUN_FILES:
            (path / name).unlink(missing_ok=True)
        for png in path.glob("*.png"):
            png.unlink()
    _probe_writable(path, option)
    _register_new(path)
    return path


def check_output_file(path: Path, option: str, suffixes: tuple[str, ...] = ()) -> Path:
    """Check an output file path before any work: not a directory, its folder
    writable, the suffix one of ``suffixes`` (if given). InputError naming the option."""
    from flexrv.errors import InputError

    path = Path(path)
    if path.is_dir():
        raise InputError(
            f"{option} {path}: is a directory; give a file name"
            + (f" ending in {'/'.join(suffixes)}" if suffixes else "")
        )
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputError(f"{option} {path}: the file name must end in {' or '.join(suffixes)}")
    _probe_writable(path.parent if str(path.parent) else Path("."), option)
    return path


def skip_final_collection() -> None:
    """At exit, skip the interpreter's last garbage collections over the objects of a run
    (numba's kernels and their LLVM objects, xarray, matplotlib: ~0.6 s CPU of a warm
    ``simulate`` or ``te`` process): :func:`gc.freeze` moves every tracked object into the
    permanent generation, which collections ignore. Objects are still released by reference
    counting and the atexit handlers run; only reference cycles are left to the end of the
    process. Registered once per process."""
    import atexit
    import gc

    if not getattr(skip_final_collection, "registered", False):
        atexit.register(gc.freeze)
        skip_final_collection.registered = True
