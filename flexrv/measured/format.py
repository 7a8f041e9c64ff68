"""The measured-data file format (``flexrv-measured-1``) and its reader.

A file is UTF-8 text: ``# key = value`` metadata lines, then one header line that
names every column with its unit in square brackets, then comma-separated rows::

    # format = flexrv-measured-1
    # kind = stiffness_loop
    # origin = measured
    # input = locked
    torque [N·m],angle [arcmin]
    0.0,0.0
    41.2,0.52
    ...

Units are declared, never guessed: a column without a unit, with a unit that is not
one of :data:`UNITS`, or with a unit of another quantity is an error. Three kinds
(:data:`KINDS`):

``stiffness_loop``
    torsional stiffness / hysteresis loop, input locked, torque at the output:
    ``torque`` and ``angle`` (the output rotation, positive in the direction of
    positive torque), optional ``time``; any number of cycles. The loop must load,
    unload and reverse (both torque signs).
``te_record``
    one transmission-error record at one direction, speed and torque: ``te`` with
    ``output_angle`` (strictly monotonic) or ``time`` (strictly increasing, with
    ``output_speed_rpm``). The sign convention is declared by ``te_sign``:
    ``output_minus_input`` (TE = theta_out - theta_in / i, flexrv's) or
    ``input_minus_output`` (read as its negative).
``lost_motion``
    lost-motion / backlash test points, input locked: ``torque`` and ``angle`` at
    small torques of both signs, with ``rated_torque_Nm`` (lost motion at +-3 %).

A bad file raises :class:`MeasuredFileError` naming the file, the line and the column.
Values are returned in SI (N m, rad, s, rad/s).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexrv.errors import ConfigError
from flexrv.units import RAD_PER_ARCMIN, RAD_PER_ARCSEC, RAD_PER_DEG, RAD_S_PER_RPM

FORMAT = "flexrv-measured-1"

#: unit spelling -> (quantity, factor to SI)
UNITS: dict[str, tuple[str, float]] = {
    "N·m": ("torque", 1.0),
    "N m": ("torque", 1.0),
    "Nm": ("torque", 1.0),
    "N*m": ("torque", 1.0),
    "rad": ("angle", 1.0),
    "deg": ("angle", RAD_PER_DEG),
    "arcmin": ("angle", RAD_PER_ARCMIN),
    "arcsec": ("angle", RAD_PER_ARCSEC),
    "s": ("time", 1.0),
    "rpm": ("speed", RAD_S_PER_RPM),
}

#: kind -> (required columns, optional columns); column -> quantity in :data:`COLUMNS`
KINDS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "stiffness_loop": (("torque", "angle"), ("time",)),
    "te_record": (("te",), ("output_angle", "time")),
    "lost_motion": (("torque", "angle"), ()),
}
COLUMNS = {"torque": "torque", "angle": "angle", "time": "time", "te": "angle", "output_angle": "angle"}

#: metadata key -> (type, kinds it belongs to (None: all), kinds that require it (None: all))
META: dict[str, tuple[str, tuple[str, ...] | None, tuple[str, ...] | None]] = {
    "format": ("text", None, None),
    "kind": ("text", None, None),
    "origin": ("text", None, None),
    "description": ("text", None, ()),
    "design": ("text", None, ()),
    "temperature_C": ("number", None, ()),
    "input": ("text", ("stiffness_loop", "lost_motion"), ("stiffness_loop", "lost_motion")),
    "rated_torque_Nm": ("positive", ("stiffness_loop", "lost_motion"), ("lost_motion",)),
    "quarter_time_s": ("positive", ("stiffness_loop",), ()),
    "angle_uncertainty_arcmin": ("positive", ("stiffness_loop", "lost_motion"), ()),
    "te_sign": ("text", ("te_record",), ("te_record",)),
    "direction": ("text", ("te_record",), ("te_record",)),
    "torque_Nm": ("nonnegative", ("te_record",), ("te_record",)),
    "output_speed_rpm": ("positive", ("te_record",), ()),
    "te_uncertainty_arcsec": ("positive", ("te_record",), ()),
}
CHOICES = {
    "format": (FORMAT,),
    "kind": tuple(KINDS),
    "input": ("locked",),
    "te_sign": ("output_minus_input", "input_minus_output"),
    "direction": ("forward", "backward"),
}
#: the ``origin`` of a file flexrv wrote (simulated, not measured)
SIMULATED_PREFIX = "simulated by flexrv"

#: data rows: fewest per kind, most in any file (a bench loop at 1 kHz over 15 min has 9e5)
MIN_ROWS = {"stiffness_loop": 8, "te_record": 8, "lost_motion": 4}
MAX_ROWS = 1_000_000
_HEADER = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\[([^\]]*)\])?\s*$")


class MeasuredFileError(ConfigError):
    """A measured-data file is invalid; the message names the file, line and column."""

    def __init__(self, path, line: int, column: str, message: str):
        self.path, self.line, self.column = str(path), line, column
        super().__init__(f"{path}, line {line}, {column}: {message}")


@dataclass
class Measurement:
    """One measured-data file, in SI (N m, rad, s, rad/s)."""

    path: str
    kind: str
    meta: dict  #: metadata as given (numbers as floats)
    columns: dict[str, np.ndarray]  #: column name -> values [SI]
    units: dict[str, str]  #: column name -> unit as declared
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  #: file line of each row

    @property
    def simulated(self) -> bool:
        """True for a file flexrv wrote (its origin says so)."""
        return str(self.meta.get("origin", "")).startswith(SIMULATED_PREFIX)

    @property
    def rows(self) -> int:
        return len(self.lines)


def _text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MeasuredFileError(path, 0, "column -", f"cannot read the file: {exc.strerror or exc}") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise MeasuredFileError(path, 1, "column 1", "the file is UTF-16 encoded: save it as UTF-8")
    nul = raw.find(b"\x00")
    if nul >= 0:
        line = raw.count(b"\n", 0, nul) + 1
        col = nul - (raw.rfind(b"\n", 0, nul) + 1) + 1
        raise MeasuredFileError(path, line, f"character {col}", "binary content (NUL byte): a UTF-8 CSV is required")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise MeasuredFileError(
            path, line, f"character {col}", f"not valid UTF-8 (byte 0x{raw[exc.start]:02x}): save the file as UTF-8"
        ) from None


def _meta_value(path, line: int, key: str, value: str, seen: dict):
    if key not in META:
        raise MeasuredFileError(path, line, "metadata", f"unknown key {key!r}; allowed: {', '.join(META)}")
    if key in seen:
        raise MeasuredFileError(path, line, "metadata", f"key {key!r} given twice (first on line {seen[key][1]})")
    kind, _, _ = META[key]
    if key in CHOICES and value not in CHOICES[key]:
        raise MeasuredFileError(
            path, line, "metadata", f"{key} = {value!r} is not allowed; allowed: {', '.join(CHOICES[key])}"
        )
    if kind == "text":
        if not value:
            raise MeasuredFileError(path, line, "metadata", f"{key} is empty")
        return value
    try:
        x = float(value)
    except ValueError:
        x = float("nan")
    ok = math.isfinite(x) and (kind == "number" or (x > 0 if kind == "positive" else x >= 0))
    if not ok:
        rule = {"number": "a finite number", "positive": "a finite number > 0", "nonnegative": "a number >= 0"}[kind]
        raise MeasuredFileError(path, line, "metadata", f"{key} = {value!r} is not allowed: must be {rule}")
    return x


def _header(path, line: int, text: str, kind: str):
    """Column names and units of the header line; checked against the kind."""
    required, optional = KINDS[kind]
    names, units, factors = [], [], []
    for j, cell in enumerate(text.split(","), start=1):
        m = _HEADER.match(cell)
        where = f"column {j}"
        if not m:
            raise MeasuredFileError(path, line, where, f"header {cell.strip()!r} is not 'name [unit]'")
        name, unit = m.group(1), m.group(2)
        if name not in required + optional:
            raise MeasuredFileError(
                path, line, where, f"unknown column {name!r} for kind {kind}; allowed: {', '.join(required + optional)}"
            )
        if name in names:
            raise MeasuredFileError(path, line, where, f"column {name!r} given twice")
        if unit is None or not unit.strip():
            raise MeasuredFileError(
                path, line, where, f"column {name!r} declares no unit: write '{name} [unit]' (units are never guessed)"
            )
        unit = unit.strip()
        if unit not in UNITS:
            raise MeasuredFileError(path, line, where, f"unknown unit {unit!r}; allowed: {', '.join(UNITS)}")
        qty, factor = UNITS[unit]
        if qty != COLUMNS[name]:
            allowed = [u for u, (q, _) in UNITS.items() if q == COLUMNS[name]]
            raise MeasuredFileError(
                path, line, where, f"unit {unit!r} of column {name!r} is a {qty}; allowed: {', '.join(allowed)}"
            )
        names.append(name)
        units.append(unit)
        factors.append(factor)
    missing = [c for c in required if c not in names]
    if kind == "te_record" and not ({"output_angle", "time"} & set(names)):
        missing.append("output_angle or time")
    if kind == "te_record" and {"output_angle", "time"} <= set(names):
        raise MeasuredFileError(path, line, "header", "give output_angle or time, not both")
    if missing:
        raise MeasuredFileError(path, line, "header", f"missing column(s) {', '.join(missing)} for kind {kind}")
    return names, units, np.array(factors)


def _rows(path, lines, start: int, names: list[str]):
    """Parse the data rows (streaming: stops at :data:`MAX_ROWS` + 1)."""
    ncol = len(names)
    values: list[list[float]] = []
    where: list[int] = []
    for k in range(start, len(lines)):
        text = lines[k].strip()
        if not text:
            continue
        if text.startswith("#"):
            raise MeasuredFileError(path, k + 1, "column 1", "a comment or metadata line after the header")
        cells = text.split(",")
        if len(cells) != ncol:
            raise MeasuredFileError(
                path, k + 1, f"column {min(len(cells), ncol + 1)}", f"{len(cells)} values, the header has {ncol}"
            )
        row = []
        for j, cell in enumerate(cells):
            try:
                x = float(cell)
            except ValueError:
                x = None
            if x is None or not math.isfinite(x):
                what = "not a number" if x is None else "not a finite number"
                raise MeasuredFileError(path, k + 1, f"column {j + 1} ({names[j]})", f"{cell.strip()!r} is {what}")
            row.append(x)
        values.append(row)
        where.append(k + 1)
        if len(values) > MAX_ROWS:
            raise MeasuredFileError(
                path, k + 1, "column 1", f"more than {MAX_ROWS:,} data rows: split the record or decimate it"
            )
    return np.array(values, dtype=float).reshape(-1, ncol), np.array(where, dtype=int)


def read_measured(path) -> Measurement:
    """Read and check one measured-data file (see the module docstring).

    Raises :class:`MeasuredFileError` naming file, line and column on any defect."""
    path = Path(path)
    if path.is_dir():
        raise MeasuredFileError(path, 0, "column -", "is a directory, not a measured-data file")
    lines = _text(path).splitlines()
    meta: dict = {}
    seen: dict = {}
    header_at = None
    for k, raw in enumerate(lines):
        text = raw.strip()
        if not text:
            continue
        if not text.startswith("#"):
            header_at = k
            break
        body = text[1:].strip()
        if not body:
            continue
        if "=" not in body:
            raise MeasuredFileError(path, k + 1, "metadata", f"{body!r} is not 'key = value'")
        key, value = (s.strip() for s in body.split("=", 1))
        meta[key] = _meta_value(path, k + 1, key, value, seen)
        seen[key] = (meta[key], k + 1)
    first = 1
    if "format" not in meta:
        raise MeasuredFileError(path, first, "metadata", f"missing '# format = {FORMAT}' line")
    if "kind" not in meta:
        raise MeasuredFileError(path, first, "metadata", f"missing '# kind = ...' line; allowed: {', '.join(KINDS)}")
    kind = meta["kind"]
    for key, (_, kinds, required) in META.items():
        if key in meta and kinds is not None and kind not in kinds:
            raise MeasuredFileError(path, seen[key][1], "metadata", f"key {key!r} does not belong to kind {kind}")
        if key not in meta and (required is None or kind in required):
            hint = f" ({', '.join(CHOICES[key])})" if key in CHOICES else ""
            raise MeasuredFileError(path, first, "metadata", f"missing required key {key!r}{hint} for kind {kind}")
    if header_at is None:
        raise MeasuredFileError(path, len(lines) + 1, "header", "no column header line ('name [unit],...')")
    names, units, factors = _header(path, header_at + 1, lines[header_at], kind)
    data, where = _rows(path, lines, header_at + 1, names)
    if len(data) < MIN_ROWS[kind]:
        last = int(where[-1]) if len(where) else header_at + 1
        raise MeasuredFileError(
            path, last, "column 1", f"{len(data)} data row(s); a {kind} needs at least {MIN_ROWS[kind]}"
        )
    cols = {n: data[:, j] * factors[j] for j, n in enumerate(names)}
    m = Measurement(str(path), kind, meta, cols, dict(zip(names, units)), where)
    if kind == "te_record" and meta["te_sign"] == "input_minus_output":
        m.columns["te"] = -m.columns["te"]
    _CHECKS[kind](m, names)
    return m


def _col(m: Measurement, names, name: str) -> str:
    return f"column {names.index(name) + 1} ({name} [{m.units[name]}])"


def _check_loop(m: Measurement, names) -> None:
    from flexrv.measured.branches import loop_branches

    t, a = m.columns["torque"], m.columns["angle"]
    if "time" in m.columns:
        _strictly_monotonic(m, names, "time", increasing=True)
    tc = _col(m, names, "torque")
    if not (t.max() > 0 > t.min()):
        raise MeasuredFileError(
            m.path,
            int(m.lines[int(np.argmin(np.abs(t)))]),
            tc,
            f"the loop must reach both torque signs (it spans {t.min():.6g} .. {t.max():.6g} N m): "
            "a stiffness loop is loaded, unloaded and reversed",
        )
    branches = loop_branches(t)
    if not any(b.direction < 0 for b in branches):
        raise MeasuredFileError(
            m.path,
            int(m.lines[-1]),
            tc,
            "the loop has no unloading branch: torque never falls back from its maximum (a loop is 0 -> +T -> -T -> 0)",
        )
    if not any(b.direction > 0 and t[b.start] < 0 for b in branches):
        raise MeasuredFileError(
            m.path,
            int(m.lines[-1]),
            tc,
            "the loop has no returning branch: torque never rises again from its negative peak (0 -> +T -> -T -> 0)",
        )
    slope = np.polyfit(t, a, 1)[0]
    if not slope > 0:
        raise MeasuredFileError(
            m.path,
            int(m.lines[int(np.argmax(t))]),
            _col(m, names, "angle"),
            "the angle falls as the torque rises: the format measures the output angle in the direction of "
            "positive torque (change the sign of the column)",
        )


def _strictly_monotonic(m: Measurement, names, name: str, increasing: bool | None = None) -> None:
    x = m.columns[name]
    d = np.diff(x)
    sign = 1.0 if increasing or (increasing is None and x[-1] >= x[0]) else -1.0
    bad = np.flatnonzero(sign * d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        order = "increasing" if sign > 0 else "decreasing"
        f = UNITS[m.units[name]][1]
        raise MeasuredFileError(
            m.path,
            int(m.lines[i]),
            _col(m, names, name),
            f"{name} must be strictly {order} (sorted): {x[i - 1] / f:.9g} then {x[i] / f:.9g} {m.units[name]}",
        )


def _check_te(m: Measurement, names) -> None:
    if "time" in m.columns:
        _strictly_monotonic(m, names, "time", increasing=True)
        if "output_speed_rpm" not in m.meta:
            raise MeasuredFileError(
                m.path, 1, "metadata", "a TE record over time needs '# output_speed_rpm = ...' (the output speed)"
            )
    else:
        _strictly_monotonic(m, names, "output_angle")


def _check_lost_motion(m: Measurement, names) -> None:
    t = m.columns["torque"]
    band = 0.03 * m.meta["rated_torque_Nm"]
    if not (t.max() >= band * (1 - 1e-9) and t.min() <= -band * (1 - 1e-9)):
        raise MeasuredFileError(
            m.path,
            int(m.lines[-1]),
            _col(m, names, "torque"),
            f"lost-motion points must reach +-3 % of the rated torque (+-{band:.6g} N m); "
            f"they span {t.min():.6g} .. {t.max():.6g} N m",
        )


_CHECKS = {"stiffness_loop": _check_loop, "te_record": _check_te, "lost_motion": _check_lost_motion}


def te_output_angle(m: Measurement) -> np.ndarray:
    """Output angle [rad] of a TE record: the column, or speed x time."""
    if "output_angle" in m.columns:
        return m.columns["output_angle"]
    speed = m.meta["output_speed_rpm"] * RAD_S_PER_RPM
    sign = 1.0 if m.meta["direction"] == "forward" else -1.0
    return sign * speed * (m.columns["time"] - m.columns["time"][0])
