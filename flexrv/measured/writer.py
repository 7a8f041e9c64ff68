"""Writers of the measured-data format (:mod:`flexrv.measured.format`): what flexrv
exports is exactly what the reader reads (``flexrv stiffness-test --csv``, ``flexrv te
--csv``). Values are written with 17 significant digits, so a float64 comes back
within one unit in the last place of its unit conversion."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexrv.errors import InputError
from flexrv.measured.format import FORMAT, KINDS, SIMULATED_PREFIX, UNITS


def simulated_origin(command: str) -> str:
    """The ``origin`` of a file flexrv wrote: it says it is simulated, and by which command."""
    from flexrv._version import __version__

    return f"{SIMULATED_PREFIX} {__version__}: {command} (not a measurement)"


def format_measured(kind: str, meta: dict, columns: list[tuple[str, str, np.ndarray]]) -> str:
    """The file's text: metadata (``format`` and ``kind`` first), the header and the rows.
    ``columns`` are (name, unit, values in SI); each is divided by its unit's factor."""
    if kind not in KINDS:
        raise InputError(f"kind {kind!r}: allowed {', '.join(KINDS)}")
    lines = [f"# format = {FORMAT}", f"# kind = {kind}"]
    for key, value in meta.items():
        if value is None:
            continue
        text = f"{value:.17g}" if isinstance(value, float) else str(value)
        if "\n" in text or "\r" in text:
            raise InputError(f"metadata {key}: a value must be one line")
        lines.append(f"# {key} = {text}")
    lines.append(",".join(f"{name} [{unit}]" for name, unit, _ in columns))
    data = np.column_stack([np.asarray(v, dtype=float) / UNITS[u][1] for _, u, v in columns])
    body = "\n".join(",".join(f"{x:.17g}" for x in row) for row in data)
    return "\n".join(lines) + "\n" + body + "\n"


def write_measured(path, kind: str, meta: dict, columns: list[tuple[str, str, np.ndarray]]) -> Path:
    """Write a measured-data file atomically; return its path."""
    from flexrv.cache import atomic_write_text

    return atomic_write_text(Path(path), format_measured(kind, meta, columns))


def write_loop(
    path, torque_Nm, angle_rad, time_s=None, origin: str = "measured", angle_unit: str = "arcmin", **meta
) -> Path:
    """A ``stiffness_loop`` file: torque [N m] and output angle [rad] (positive with
    positive torque), optionally time [s]; ``meta`` adds keys of the format (e.g.
    ``quarter_time_s``, ``design``)."""
    cols = [("torque", "N·m", torque_Nm), ("angle", angle_unit, angle_rad)]
    if time_s is not None:
        cols.append(("time", "s", time_s))
    return write_measured(path, "stiffness_loop", {"origin": origin, "input": "locked", **meta}, cols)


def write_te_record(
    path,
    output_angle_rad,
    te_rad,
    torque_Nm: float,
    direction: str = "forward",
    origin: str = "measured",
    **meta,
) -> Path:
    """A ``te_record`` file: output angle [rad] and TE = theta_out - theta_in / i [rad]
    (``te_sign = output_minus_input``) at one torque [N m] and direction."""
    cols = [("output_angle", "deg", output_angle_rad), ("te", "arcsec", te_rad)]
    head = {
        "origin": origin,
        "te_sign": "output_minus_input",
        "direction": direction,
        "torque_Nm": float(torque_Nm),
        **meta,
    }
    return write_measured(path, "te_record", head, cols)


def export_stiffness_test(path, res, command: str, quarter_time_s: float | None = None) -> Path:
    """The loop of a virtual stiffness test (its Results: ``loop_torque`` [N m], ``loop_angle``
    [arcmin] over ``time`` [s], read by name; the program's peak torque from the stiffness
    budget's ``budget_torque_Nm`` attribute, the budget being read at the program's peak) as a
    ``stiffness_loop`` file labelled simulated."""
    from flexrv.units import RAD_PER_ARCMIN

    ds = res.ds
    peak = float(ds.attrs["budget_torque_Nm"]) if "budget_torque_Nm" in ds.attrs else None
    return write_loop(
        path,
        ds["loop_torque"].values,
        ds["loop_angle"].values * RAD_PER_ARCMIN,
        time_s=ds["time"].values,
        origin=simulated_origin(command),
        design=ds.attrs.get("preset"),
        rated_torque_Nm=peak,
        quarter_time_s=None if quarter_time_s is None else float(quarter_time_s),
    )


def export_te(path, result, design_name: str, command: str) -> Path:
    """The loaded TE of ``flexrv te`` (:class:`flexrv.model.quasi_static.LoadedTE`: output
    angle and TE [rad] at its torque) as a forward ``te_record`` file labelled simulated."""
    return write_te_record(
        path,
        result.output_angle,
        result.te,
        result.torque,
        origin=simulated_origin(command),
        design=design_name,
    )
