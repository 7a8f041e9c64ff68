"""Manufacturing tolerances: the optional ``[tolerances]`` table, a statistical
description of the ``[errors]`` table (:mod:`flexrv.design.manufacturing`) of a
production batch.

One entry per error field, keyed by its path inside ``[errors]``::

    [tolerances."pins.pin_radius_um"]        # ISO 286 IT5 rollers
    distribution = "band"                    # truncated normal inside +-band
    band_um = 1.25                           # half width of the tolerance zone
    sigma_fraction = 0.3333333333            # sigma = band x sigma_fraction ("band = 3 sigma")
    scope = "per_element"                    # one draw per pin

    [tolerances."cranks.eccentric_phase_arcmin"]
    distribution = "normal"
    sigma_arcmin = 3.5

    [tolerances."clearances.support_clearance_um"]
    distribution = "uniform"
    mean_um = 4.0
    band_um = 2.0                            # uniform within 2..6 um

    [[tolerances.correlations]]              # optional correlation groups
    fields = ["pins.pin_radial_position_um", "pins.pin_tangential_position_um"]
    coefficient = 0.5

Distributions (each value in the unit its error field carries: ``_um`` or ``_arcmin``):

* ``normal``: mean ``mean_<unit>`` (default 0), standard deviation ``sigma_<unit>`` >= 0;
* ``band``: a tolerance zone mean +- ``band_<unit>``, drawn from a normal of
  sigma = ``sigma_fraction`` x band truncated to the zone (parts outside are
  rejected at inspection); the default ``sigma_fraction`` = 1/3 is the common
  "band = 3 sigma" convention (process capability C_p = 1);
* ``uniform``: uniform within mean +- ``band_<unit>``.

Scopes: ``per_element`` draws every pin / crank / [crank][disc] / disc element
independently; ``per_reducer`` draws one value per reducer, shared by all its
elements (a pin lot's oversize); ``batch`` draws one value for the whole batch
(seeded), the same in every reducer: a systematic offset that shifts the
distribution and carries no sensitivity.

Fields: every numeric error field of ``[errors]`` (pins, cranks, discs,
first_stage, clearances, e.g. ``discs.hole_radial_um`` for every disc's crank
holes). Fields with an amplitude and a phase are described by their two
quadrature components, each drawn from the entry's distribution (so a normal
gives a Rayleigh amplitude and a uniform phase): the disc profile/pitch
harmonics ``discs.harmonic_order_<n>_um`` (order n = 1..4 z_rp, amplitude A cos
(n phi + p)), ``first_stage.sun_runout_um`` and ``first_stage.planet_runout_um``.
Their ``*_phase_deg`` fields follow from the components and take no tolerance.

Correlations: the fields of a group must have the same scope and number of
elements; element i of every member is correlated with coefficient rho with
element i of the others (a Gaussian copula: the members' standard-normal scores
are mixed by the Cholesky factor of the equicorrelation matrix, then mapped
through each member's own inverse CDF, so the marginals are unchanged).

A field drawn by the tolerance model replaces that field of the design's own
``[errors]`` table; fields without a tolerance keep the design's value.
Bad input (unknown field, negative sigma, unknown scope or distribution, a band
that reaches a negative clearance) raises :class:`flexrv.errors.ConfigError`
naming the entry and value.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from flexrv.errors import ConfigError

_HARMONIC = re.compile(r"^discs\.harmonic_order_(\d+)_um$")
_VECTOR_FIELDS = {"first_stage.sun_runout_um", "first_stage.planet_runout_um"}


class Tolerance(BaseModel):
    """One ``[tolerances."<group>.<field>"]`` entry (values in the field's unit,
    normalised: ``sigma`` / ``band`` / ``mean`` after the unit check)."""

    model_config = ConfigDict(extra="forbid", strict=True)

    distribution: Literal["normal", "band", "uniform"]
    scope: Literal["per_element", "per_reducer", "batch"] = "per_element"
    sigma: float | None = Field(default=None, ge=0.0, allow_inf_nan=False)
    band: float | None = Field(default=None, ge=0.0, allow_inf_nan=False)
    mean: float = Field(default=0.0, allow_inf_nan=False)
    sigma_fraction: float = Field(default=1.0 / 3.0, gt=0.0, le=1.0, allow_inf_nan=False)
    source: str = ""


class Correlation(BaseModel):
    """A ``[[tolerances.correlations]]`` group."""

    model_config = ConfigDict(extra="forbid", strict=True)

    fields: list[str] = Field(min_length=2)
    coefficient: float = Field(ge=-1.0, le=1.0, allow_inf_nan=False)


@dataclass(frozen=True)
class FieldInfo:
    """An error field that can carry a tolerance."""

    key: str  #: e.g. "pins.pin_radius_um"
    unit: str  #: "um" or "arcmin"
    shape: tuple[int, ...]  #: element shape of the per_element draw
    labels: tuple[str, ...]  #: one label per element ("[3]", "[2][1]", "[0].cos")
    vector: bool  #: quadrature components (last shape axis = 2: cos, sin)
    lower: float  #: lowest allowed value of the field [unit]


@dataclass
class ToleranceSet:
    """A validated tolerance table for one design."""

    entries: dict[str, Tolerance]
    fields: dict[str, FieldInfo]
    correlations: list[Correlation]

    def sigma_of(self, key: str) -> float:
        """Standard deviation [field unit] of one component of an entry's draw."""
        t = self.entries[key]
        if t.distribution == "normal":
            return float(t.sigma)
        if t.distribution == "uniform":
            return float(t.band) / math.sqrt(3.0)
        from scipy.stats import truncnorm

        c = 1.0 / t.sigma_fraction
        return float(truncnorm.std(-c, c, scale=t.band * t.sigma_fraction))

    def to_dict(self) -> dict[str, Any]:
        """The table as plain data (normalised field names, for records)."""
        out: dict[str, Any] = {}
        for key, t in self.entries.items():
            u = self.fields[key].unit
            d = {"distribution": t.distribution, "scope": t.scope, f"mean_{u}": t.mean}
            if t.sigma is not None:
                d[f"sigma_{u}"] = t.sigma
            if t.band is not None:
                d[f"band_{u}"] = t.band
            if t.distribution == "band":
                d["sigma_fraction"] = t.sigma_fraction
            if t.source:
                d["source"] = t.source
            out[key] = d
        if self.correlations:
            out["correlations"] = [c.model_dump() for c in self.correlations]
        return out


def error_fields(reducer) -> dict[str, FieldInfo]:
    """Every tolerance-able error field of a design, with its element shape
    (harmonic orders listed as ``discs.harmonic_order_<n>_um`` for n = 1, 2, z_c,
    z_rp; any order 1..4 z_rp is accepted by :func:`field_info`)."""
    z = reducer.second_stage.pin_count
    zc = reducer.second_stage.disc_teeth
    out = {}
    names = [*_allowed_names(), *(f"discs.harmonic_order_{n}_um" for n in sorted({1, 2, zc, z}))]
    for key in names:
        out[key] = field_info(reducer, key)
    return out


def field_info(reducer, key: str) -> FieldInfo:
    """Shape, unit and lower bound of one error field (ConfigError if unknown)."""
    from flexrv.design.manufacturing import _GROUPS, DiscErrors

    z = reducer.second_stage.pin_count
    nd = reducer.second_stage.n_discs
    n = reducer.first_stage.n_planets

    def labels(shape):
        import itertools

        return tuple("".join(f"[{i}]" for i in idx) for idx in itertools.product(*(range(s) for s in shape)))

    m = _HARMONIC.match(key)
    if m:
        order = int(m.group(1))
        if not 1 <= order <= 4 * z:
            raise ConfigError(f'tolerances."{key}": harmonic order {order} must lie within 1..4 z_rp = {4 * z}')
        lab = tuple(f"[{k}].{c}" for k in range(nd) for c in ("cos", "sin"))
        return FieldInfo(key, "um", (nd, 2), lab, True, -math.inf)
    group, _, name = key.partition(".")
    model = DiscErrors if group == "discs" else _GROUPS.get(group)
    finfo = model.model_fields.get(name) if model is not None and name != "harmonics" else None
    if finfo is None or name.endswith("_deg"):
        hint = (
            "phases follow from the quadrature components of their runout"
            if name.endswith("_deg") and finfo
            else "see flexrv.design.tolerances.error_fields"
        )
        raise ConfigError(
            f'tolerances."{key}": no such tolerance-able error field ({hint}); allowed: '
            f"{', '.join(_allowed_names())}, discs.harmonic_order_<n>_um"
        )
    extra = finfo.json_schema_extra or {}
    shape_kind, bound = extra["shape"], extra["bound"]
    unit = name.rsplit("_", 1)[-1]
    if group == "discs":
        shape = (nd,) if shape_kind == "one" else (nd, n)
    else:
        shape = {"pin": (z,), "crank": (n,), "crank_disc": (n, nd), "one": ()}[shape_kind]
    vector = key in _VECTOR_FIELDS
    if vector:
        shape = shape + (2,)
    lab = labels(shape)
    if vector:
        lab = tuple(s[:-3] + (".cos" if s.endswith("[0]") else ".sin") for s in lab)
    lower = -math.inf
    if bound == "clear":
        lower = 0.0
    elif key == "clearances.needle_extra_clearance_um":
        lower = -0.5 * reducer.needle_bearing.radial_clearance_um
    return FieldInfo(key, unit, shape, lab, vector, lower)


def _allowed_names() -> list[str]:
    """The tolerance-able error fields other than the disc profile's harmonics (whose orders
    depend on the design: :func:`error_fields`)."""
    return [
        "pins.pin_radius_um",
        "pins.pin_radial_position_um",
        "pins.pin_tangential_position_um",
        "cranks.eccentricity_um",
        "cranks.eccentric_phase_arcmin",
        "cranks.bore_radial_um",
        "cranks.bore_tangential_um",
        "discs.equidistant_um",
        "discs.shift_um",
        "discs.rotation_arcmin",
        "discs.hole_radial_um",
        "discs.hole_tangential_um",
        "first_stage.sun_runout_um",
        "first_stage.planet_runout_um",
        "first_stage.planet_phase_arcmin",
        "clearances.needle_extra_clearance_um",
        "clearances.support_clearance_um",
    ]


def _entry(key: str, raw: Any, info: FieldInfo) -> Tolerance:
    where = f'tolerances."{key}"'
    if not isinstance(raw, dict):
        raise ConfigError(
            f"{where} = {raw!r}: must be a table (distribution, scope, sigma_{info.unit} / band_{info.unit})"
        )
    data = dict(raw)
    u = info.unit
    for k in list(data):
        m = re.match(r"^(sigma|band|mean)_(\w+)$", k)
        if m and k != "sigma_fraction":
            if m.group(2) != u:
                raise ConfigError(f"{where}.{k}: wrong unit for this field: use {m.group(1)}_{u}")
            val = data.pop(k)
            if isinstance(val, int) and not isinstance(val, bool):
                val = float(val)
            data[m.group(1)] = val
    if isinstance(data.get("sigma_fraction"), int) and not isinstance(data.get("sigma_fraction"), bool):
        data["sigma_fraction"] = float(data["sigma_fraction"])
    try:
        t = Tolerance.model_validate(data)
    except ValidationError as exc:
        err = exc.errors(include_url=False)[0]
        loc = ".".join(str(p) for p in err["loc"])
        name = f"{loc}_{u}" if loc in ("sigma", "band", "mean") else loc
        allowed = {
            "distribution": "'normal', 'band' or 'uniform'",
            "scope": "'per_element', 'per_reducer' or 'batch'",
            "sigma": ">= 0 (finite)",
            "band": ">= 0 (finite)",
            "sigma_fraction": "within (0, 1]",
        }.get(loc, "")
        if err["type"] == "extra_forbidden":
            raise ConfigError(
                f"{where}.{name}: unknown key; allowed: distribution, scope, sigma_{u}, band_{u}, "
                f"mean_{u}, sigma_fraction, source"
            ) from None
        raise ConfigError(
            f"{where}.{name} = {err.get('input')!r}: {err['msg']}" + (f" (allowed: {allowed})" if allowed else "")
        ) from None
    need = "sigma" if t.distribution == "normal" else "band"
    if getattr(t, need) is None:
        raise ConfigError(f"{where}: distribution {t.distribution!r} needs {need}_{u}")
    other = "band" if need == "sigma" else "sigma"
    if getattr(t, other) is not None:
        raise ConfigError(f"{where}: {other}_{u} does not apply to distribution {t.distribution!r} (give {need}_{u})")
    if math.isfinite(info.lower):
        if t.distribution == "normal" and t.sigma > 0:
            raise ConfigError(
                f"{where}: distribution 'normal' is unbounded but the field must stay >= "
                f"{info.lower:g} {u}: use 'band' or 'uniform'"
            )
        low = t.mean - (t.band or 0.0)
        if low < info.lower:
            raise ConfigError(
                f"{where}: mean_{u} - band_{u} = {low:g} {u} is below the field's lower bound {info.lower:g} {u}"
            )
    if info.vector and t.mean != 0.0:
        raise ConfigError(
            f"{where}.mean_{u} = {t.mean!r}: a runout/harmonic is drawn as two zero-mean quadrature "
            "components; mean must be 0"
        )
    return t


def parse_tolerances(table: Any, reducer, source: str = "[tolerances]") -> ToleranceSet:
    """Validate a ``[tolerances]`` table (dict as read from TOML) for a design."""
    if not isinstance(table, dict) or not table:
        raise ConfigError(f"{source}: [tolerances] must be a non-empty table of entries keyed by error field")
    data = dict(table)
    corr_raw = data.pop("correlations", [])
    entries: dict[str, Tolerance] = {}
    fields: dict[str, FieldInfo] = {}
    for key, raw in data.items():
        info = field_info(reducer, key)
        entries[key] = _entry(key, raw, info)
        fields[key] = info
    if not isinstance(corr_raw, list):
        raise ConfigError("tolerances.correlations: must be an array of tables [[tolerances.correlations]]")
    correlations = []
    seen: set[str] = set()
    for i, c in enumerate(corr_raw):
        where = f"tolerances.correlations[{i}]"
        try:
            corr = Correlation.model_validate(c)
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            loc = ".".join(str(p) for p in err["loc"])
            raise ConfigError(
                f"{where}.{loc} = {err.get('input')!r}: {err['msg']} "
                "(fields: >= 2 tolerance keys; coefficient within -1..1)"
            ) from None
        for f in corr.fields:
            if f not in entries:
                raise ConfigError(f"{where}.fields: {f!r} has no [tolerances] entry")
            if f in seen:
                raise ConfigError(f"{where}.fields: {f!r} is already in another correlation group")
            seen.add(f)
        first = corr.fields[0]
        for f in corr.fields[1:]:
            if fields[f].shape != fields[first].shape or entries[f].scope != entries[first].scope:
                raise ConfigError(
                    f"{where}.fields: {f!r} and {first!r} must have the same scope and element shape "
                    f"({entries[f].scope} {fields[f].shape} vs {entries[first].scope} {fields[first].shape})"
                )
        if corr.coefficient < -1.0 / (len(corr.fields) - 1):
            raise ConfigError(
                f"{where}.coefficient = {corr.coefficient!r}: an equicorrelation of "
                f"{len(corr.fields)} fields must be >= {-1.0 / (len(corr.fields) - 1):g}"
            )
        correlations.append(corr)
    return ToleranceSet(entries, fields, correlations)


def load_tolerances(path_or_table: str | Path | dict, reducer) -> ToleranceSet:
    """A tolerance set from a TOML file (its ``[tolerances]`` table, e.g. the design
    file itself or a separate file), a preset name (``tolerances/<name>.toml`` in
    the presets) or a dict."""
    if isinstance(path_or_table, dict):
        return parse_tolerances(path_or_table, reducer)
    from flexrv.design import read_named_table

    text = str(path_or_table)
    table = read_named_table(text, "tolerances", "tolerances", "tolerance file")
    return parse_tolerances(table, reducer, source=text)


def design_tolerance_table(path: str | Path) -> tuple[dict | None, dict | None]:
    """(``[tolerances]`` table, design dict without it) of a design TOML file;
    (None, None) for a preset name or a file without the table (load the design
    as usual then)."""
    p = Path(str(path))
    if not p.is_file():
        return None, None
    from flexrv.design import parse_toml, read_text_file

    data = parse_toml(read_text_file(p, "design file"), str(p))
    table = data.pop("tolerances", None)
    return (table, data) if table is not None else (None, None)
