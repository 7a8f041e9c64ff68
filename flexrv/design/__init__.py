"""Reducer designs: the validated data model, the built-in presets, load/export.

>>> from flexrv.design import load
>>> rv = load("rv40e")            # a preset name, or a path to a TOML file
>>> rv.second_stage.pin_count
40
"""

from __future__ import annotations

import copy
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import BaseModel, ValidationError

from flexrv.design.model import Reducer
from flexrv.errors import ConfigError

__all__ = [
    "Reducer",
    "load",
    "loads",
    "from_dict",
    "list_presets",
    "to_toml",
    "preset_path",
    "override",
    "apply_overrides",
    "read_text_file",
    "parse_toml",
]

_PRESET_PACKAGE = "flexrv.design.presets"


def list_presets() -> list[str]:
    """Names of the built-in presets."""
    folder = resources.files(_PRESET_PACKAGE)
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def preset_path(name: str) -> Path:
    """Path of a built-in preset's TOML file."""
    return Path(str(resources.files(_PRESET_PACKAGE) / f"{name}.toml"))


def load(preset_or_path: str | Path | Reducer) -> Reducer:
    """Load a design by preset name (``"rv221"``) or TOML path; validate it.

    Raises
    ------
    ConfigError
        Unknown preset, unreadable file, invalid TOML, or any field invalid; the
        message names the field, the value and the allowed range.
    """
    if isinstance(preset_or_path, Reducer):
        return preset_or_path
    text_name = str(preset_or_path)
    if not text_name.strip():
        raise ConfigError(
            f"design {text_name!r} is empty: give a preset name {list_presets()} or a path to a .toml file"
        )
    path = Path(text_name)
    if text_name in list_presets():
        path = preset_path(text_name)
    elif not (path.suffix == ".toml" or path.exists()):
        raise ConfigError(
            f"unknown preset {text_name!r}: choose one of {list_presets()} or give a path to a .toml file"
        )
    if not path.is_file():
        what = "is not a regular file" if path.exists() else "does not exist"
        raise ConfigError(f"design file {str(path)!r} {what}")
    return loads(read_text_file(path, "design file"), source=str(path))


def read_text_file(path: str | Path, what: str) -> str:
    """The text of a UTF-8 file (a UTF-8 byte-order mark is allowed).

    Raises ConfigError naming the file if it cannot be read, is not UTF-8
    (e.g. UTF-16 or Latin-1) or is binary (contains NUL bytes)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {str(path)!r}: {exc.strerror or exc}") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise ConfigError(f"{what} {str(path)!r} is UTF-16 encoded: save it as UTF-8")
    if b"\x00" in raw:
        raise ConfigError(f"{what} {str(path)!r} is not a text file (binary content): a UTF-8 TOML file is required")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{what} {str(path)!r} is not valid UTF-8 (byte {exc.start}): save it as UTF-8") from None


def loads(text: str, source: str = "<string>") -> Reducer:
    """Parse and validate a design from TOML text."""
    return from_dict(parse_toml(text, source), source=source)


#: deepest nesting a flexrv TOML file may have (arrays, inline tables, dotted keys and
#: table headers counted alike): the design has 4 levels, a sweep spec or a tolerance
#: table 5; the parser recurses once per level, so a deeper file is refused before parsing
MAX_TOML_DEPTH = 32
#: largest flexrv TOML file [characters] (the largest preset is ~12 kB)
MAX_TOML_CHARS = 2_000_000


def toml_depth(text: str) -> int:
    """Deepest nesting of ``text`` read as TOML without parsing it: brackets and braces
    outside strings and comments, plus the parts of a dotted key or table header.
    A cheap upper bound of what the parser would recurse into."""
    depth = deepest = 0
    i, n = 0, len(text)
    key_parts, at_line_start = 1, True
    while i < n:
        c = text[i]
        if c in "\"'":
            triple = text.startswith(c * 3, i)
            end_tok = c * 3 if triple else c
            j = i + len(end_tok)
            while j < n and not text.startswith(end_tok, j):
                j += 2 if (c == '"' and text[j] == "\\") else 1
                if not triple and j < n and text[j] == "\n":
                    break
            i = j + len(end_tok)
            continue
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if c == "\n":
            at_line_start, key_parts = True, 1
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth = max(depth - 1, 0)
        elif c == ".":
            key_parts += 1
        elif c == "=":
            at_line_start = False
        deepest = max(deepest, depth + (key_parts - 1 if at_line_start else 0))
        i += 1
    return deepest


def parse_toml(text: str, source: str = "<string>") -> dict[str, Any]:
    """Parse flexrv TOML text; ConfigError naming ``source`` for invalid TOML, a file
    nested deeper than :data:`MAX_TOML_DEPTH` or larger than :data:`MAX_TOML_CHARS`
    (both refused before parsing), and a key given twice (named, with its line)."""
    if len(text) > MAX_TOML_CHARS:
        raise ConfigError(f"{source}: {len(text)} characters; a flexrv TOML file may have at most {MAX_TOML_CHARS}")
    depth = toml_depth(text)
    if depth > MAX_TOML_DEPTH:
        raise ConfigError(
            f"{source}: nested {depth} levels deep (arrays, tables or dotted keys); "
            f"a flexrv TOML file may nest at most {MAX_TOML_DEPTH} levels"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: invalid TOML: {_toml_message(exc, text)}") from None
    except RecursionError:
        raise ConfigError(f"{source}: nested too deeply to parse") from None


def _toml_message(exc: Exception, text: str) -> str:
    """tomllib's message, with the key named where it says a value is given twice."""
    import re

    msg = str(exc)
    m = re.search(r"\(at line (\d+), column \d+\)", msg)
    if m and ("overwrite" in msg or "twice" in msg):
        lines = text.splitlines()
        k = int(m.group(1)) - 1
        line = lines[k].strip() if 0 <= k < len(lines) else ""
        key = line.split("=", 1)[0].strip() if "=" in line else line.strip("[] ")
        return f"key {key!r} is defined twice (line {k + 1}: {line[:80]!r}); each key may appear once"
    return msg


def from_dict(data: dict[str, Any], source: str = "<dict>") -> Reducer:
    """Validate a nested dict (as read from TOML) into a :class:`Reducer`."""
    try:
        return Reducer.model_validate(_plain(data))
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, source)) from None


def _plain(value: Any) -> Any:
    """numpy scalars -> the Python number they hold (the strict model accepts
    ``np.float64`` but not ``np.int64``); a numpy bool stays a (rejected) bool."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    item = getattr(value, "item", None)
    if item is not None and type(value).__module__ == "numpy" and getattr(value, "ndim", None) == 0:
        return item()
    return value


def apply_overrides(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of a design dict with dotted-path overrides applied
    (``{"contact.ehl": "dry", "second_stage.eccentricity_mm": 1.5}``).

    Raises ConfigError for a path that does not exist in the design."""
    data = copy.deepcopy(base)
    for dotted, value in overrides.items():
        keys = dotted.split(".")
        node = data
        for key in keys[:-1]:
            if not isinstance(node, dict) or key not in node:
                raise ConfigError(f"override {dotted!r}: no field {key!r} in the design")
            node = node[key]
        if not isinstance(node, dict) or keys[-1] not in node:
            raise ConfigError(f"override {dotted!r}: no field {keys[-1]!r} in the design")
        node[keys[-1]] = value
    return data


def override(reducer: Reducer | str | Path, overrides: dict[str, Any]) -> Reducer:
    """A validated copy of a design (or preset) with dotted-path overrides, e.g.
    ``override("rv40e", {"contact.ehl": "dry"})``; every check of the data model
    applies to the result (ConfigError naming the field otherwise)."""
    base = load(reducer)
    return from_dict(apply_overrides(base.model_dump(), overrides), source=f"{base.name} + {sorted(overrides)}")


def to_toml(reducer: Reducer, comments: bool = False) -> str:
    """Serialise a design to TOML that :func:`loads` reads back unchanged.

    With ``comments`` every field is preceded by a comment with its description
    and allowed range (the template ``flexrv show --toml`` prints); comments do
    not change what loads back.
    """
    data = reducer.model_dump(mode="python")
    data.pop("errors", None)
    if not reducer.errors.is_zero():  # the [errors] table only when there are errors, non-zero fields only
        data["errors"] = reducer.errors.model_dump(mode="python", exclude_defaults=True)
    head = {k: data.pop(k) for k in ("name", "description", "sources")}
    provenance = data.pop("provenance")
    ordered = {**head, **data, "provenance": provenance}
    text = tomli_w.dumps(ordered)
    return _commented(text) if comments else text


def _commented(text: str) -> str:
    """Insert ``# description; allowed: range`` above every ``key = value`` line whose
    field the data model describes (table headers give the path)."""
    out: list[str] = []
    section: tuple = ()
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("["):
            section = tuple(p.strip().strip('"') for p in stripped.strip("[]").split("."))
        elif "=" in stripped and not stripped.startswith("#") and section[:1] != ("provenance",):
            key = stripped.split("=", 1)[0].strip().strip('"')
            info = _field_info(Reducer, section + (key,))
            if info is not None:
                rng = _allowed_range(info)
                text = info.description or key.replace("_", " ")  # the unit is in the key's name
                if info.description or rng:
                    out.append(f"# {text}" + (f"; allowed: {rng}" if rng else ""))
        out.append(line)
    return "\n".join(out) + "\n"


# ----------------------------------------------------------------- error messages
def _field_info(model: type[BaseModel], loc: tuple) -> Any:
    """FieldInfo of the field addressed by a pydantic error location (or None)."""
    info = None
    current: Any = model
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(current, "model_fields", None)
        if not fields or part not in fields:
            return info if part == loc[-1] else None
        info = fields[part]
        current = info.annotation
        args = getattr(current, "__args__", None)
        if args:  # dict[str, Material] -> Material
            current = args[-1]
    return info


def _allowed_range(info: Any) -> str:
    """Human description of a field's numeric bounds, from its metadata."""
    if info is None:
        return ""
    lo = hi = None
    lo_op = hi_op = ""
    for meta in info.metadata:
        for attr, op in (("gt", "<"), ("ge", "<=")):
            if getattr(meta, attr, None) is not None:
                lo, lo_op = getattr(meta, attr), op
        for attr, op in (("lt", "<"), ("le", "<=")):
            if getattr(meta, attr, None) is not None:
                hi, hi_op = getattr(meta, attr), op
    if lo is None and hi is None:
        return ""
    left = f"{lo:g} {lo_op} " if lo is not None else ""
    right = f" {hi_op} {hi:g}" if hi is not None else ""
    return f"{left}value{right}"


def format_validation_error(exc: ValidationError, source: str) -> str:
    """One line per problem: ``field = value: reason (allowed: range)``."""
    lines = [f"{source}: invalid design ({exc.error_count()} problem{'s' if exc.error_count() > 1 else ''})"]
    for err in exc.errors(include_url=False):
        loc = tuple(err["loc"])
        field = ".".join(str(p) for p in loc) or "<design>"
        kind = err["type"]
        value = err.get("input")
        info = _field_info(Reducer, loc)
        rng = _allowed_range(info)
        if kind == "extra_forbidden":
            parent = _field_info(Reducer, loc[:-1])
            allowed = ""
            sub = getattr(parent, "annotation", Reducer) if parent is not None else Reducer
            if hasattr(sub, "model_fields"):
                allowed = f"; allowed fields here: {', '.join(sub.model_fields)}"
            lines.append(f"  {field}: unknown field{allowed}")
        elif kind == "missing":
            desc = f" ({info.description})" if info is not None and info.description else ""
            lines.append(f"  {field}: missing required field{desc}" + (f"; allowed: {rng}" if rng else ""))
        elif kind == "value_error":
            msg = str(err["msg"]).removeprefix("Value error, ")
            lines.append(f"  {msg}")
        else:
            shown = value
            if isinstance(value, float) and not math.isfinite(value):
                shown = str(value)
            text = f"  {field} = {shown!r}: {err['msg']}"
            if rng:
                text += f" (allowed: {rng})"
            why = (getattr(info, "json_schema_extra", None) or {}).get("floor_reason")
            if why and kind in ("greater_than", "greater_than_equal"):
                text += f": {why}"
            lines.append(text)
    return "\n".join(lines)


# --------------------------------------------------------------------------- example error sets
def error_set_names() -> list[str]:
    """Names of the built-in example error sets (``flexrv/design/presets/errors/*.toml``)."""
    from importlib import resources

    folder = resources.files("flexrv.design.presets") / "errors"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def error_set_path(name: str):
    """Path of a built-in example error set."""
    from importlib import resources
    from pathlib import Path

    return Path(str(resources.files("flexrv.design.presets") / "errors" / f"{name}.toml"))


def read_named_table(name_or_path: str, folder: str, table: str, what: str) -> dict[str, Any]:
    """The ``[table]`` of a built-in TOML under ``presets/<folder>/<name>.toml`` (by
    name) or of any TOML file (by path), as a plain dict; ConfigError naming the
    file for a missing file, an unreadable one or one without the table. ``what``
    names the kind of file in the messages (e.g. "error set")."""
    from pathlib import Path

    text_name = str(name_or_path)
    builtin = Path(str(resources.files("flexrv.design.presets") / folder / f"{text_name}.toml"))
    path = Path(text_name)
    if not path.is_file() and builtin.is_file():
        path = builtin
    if not path.is_file():
        known = sorted(
            p.name[:-5]
            for p in (resources.files("flexrv.design.presets") / folder).iterdir()
            if p.name.endswith(".toml")
        )
        raise ConfigError(f"unknown {what} {text_name!r}: choose one of {known} or give a TOML file")
    data = parse_toml(read_text_file(path, what), str(path))
    if not isinstance(data.get(table), dict):
        raise ConfigError(f"{what} {str(path)!r} has no [{table}] table")
    return data[table]


def load_error_set(name_or_path: str) -> dict[str, Any]:
    """The ``[errors]`` table of a built-in example error set (by name, see
    :func:`error_set_names`) or of any TOML file with an ``[errors]`` table, as a
    plain dict (validate it with :func:`with_errors`)."""
    return read_named_table(name_or_path, "errors", "errors", "error set")


def with_errors(reducer, errors):
    """A validated copy of a design (or preset name / path) whose ``[errors]``
    table is replaced by ``errors``; every check applies (ConfigError naming the
    field otherwise)."""
    from flexrv.design.manufacturing import ManufacturingErrors

    base = load(reducer)
    data = base.model_dump()
    data["errors"] = errors.model_dump() if isinstance(errors, ManufacturingErrors) else errors
    return from_dict(data, source=f"{base.name} + errors")
