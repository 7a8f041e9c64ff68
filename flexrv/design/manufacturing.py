"""Manufacturing and assembly errors of a reducer: the optional ``[errors]`` table.

Every field is a deviation from the nominal design, in the unit its name carries
(``_um``, ``_arcmin``, ``_deg``); all are zero by default, so a design without an
``[errors]`` table is the ideal reducer. The geometry layer
(:func:`flexrv.geometry.as_built.as_built`) turns them into the actual pin
centres and radii, disc profiles, crank-hole and bore positions, eccentrics,
clearances and gear runouts that every model reads.

Shapes (``z_rp`` pins, ``N`` cranks = planets, ``n_discs`` discs): a field marked
*per pin* / *per crank* takes one number (the same for every element) or a list of
exactly z_rp / N values; a field marked *[crank][disc]* takes one number or a list
of N lists of n_discs values. ``[[errors.discs]]`` is absent (no disc errors) or a
list of exactly n_discs tables.

Sign conventions (housing / carrier / disc frames of :mod:`flexrv.geometry.cycloid`
and :mod:`flexrv.model.drive`): radial errors positive outward, tangential
errors positive counter-clockwise; a positive ``pin_radius_um`` enlarges the pin
(less clearance); ``equidistant_um`` / ``shift_um`` / ``rotation_arcmin`` add to the
disc's nominal modifications dr_rp, dR_p and d_delta; a profile harmonic
(order n, amplitude A, phase p) adds material A cos(n phi + p) along the profile
normal at the curve parameter phi (less clearance where positive);
``eccentric_phase_arcmin`` is added to the clockwise eccentric angle chi.

Bounds (checked with one message naming the full field path, e.g.
``errors.cranks.eccentricity_um[2][1]``, the value and the allowed range):
displacements and clearances |value| <= 500 um (0.5 mm: far beyond any
manufacturing tolerance of a precision reducer, so a larger value is a unit
mistake), runout and harmonic amplitudes 0..500 um, angles |value| <= 60 arcmin,
harmonic order 1..4 z_rp, phases finite, list lengths equal to z_rp / N / n_discs
of the design, the total needle-bearing clearance >= 0, and no interference of
the as-built pins with the discs at assembly beyond
:data:`ASSEMBLY_PENETRATION_LIMIT_UM`.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from typing import Any

from pydantic import BaseModel, Field, model_validator

from flexrv.design._base import _bad, _Strict

#: Largest pin penetration into a disc at assembly [um] accepted from an error set.
#: Why 20 um: the pin contact law (Palmgren line contact, rv40e's 12 mm wide steel
#: disc) carries about 10 kN per pin at 20 um approach, 8-15 times the rated
#: maximum pin force of the presets (0.7 kN rv40e, 1.2 kN rv221, from
#: :func:`flexrv.analysis.pin_load.reducer_pin_loads`); an error set needing more
#: preload to assemble describes no real reducer.
ASSEMBLY_PENETRATION_LIMIT_UM = 20.0

#: bounds by kind: (low, high, unit text)
_BOUNDS = {
    "disp": (-500.0, 500.0, "um"),
    "amp": (0.0, 500.0, "um"),
    "clear": (0.0, 500.0, "um"),
    "angle": (-60.0, 60.0, "arcmin"),
    "phase": (-math.inf, math.inf, "deg"),
}


def _meta(shape: str, bound: str, description: str):
    """Field default 0 with its shape and bound kind recorded for the validators."""
    return Field(default=0.0, description=description, json_schema_extra={"shape": shape, "bound": bound})


class PinErrors(_Strict):
    """Pin errors (per pin: one number or z_rp values, pin j at housing angle
    2 pi j / z_rp clockwise from +y)."""

    pin_radius_um: float | list[float] = _meta("pin", "disp", "Pin radius error (+ larger pin) [um]")
    pin_radial_position_um: float | list[float] = _meta(
        "pin", "disp", "Pin centre radial position error (+ outward) [um]"
    )
    pin_tangential_position_um: float | list[float] = _meta(
        "pin", "disp", "Pin centre tangential position error (+ counter-clockwise) [um]"
    )


class Harmonic(_Strict):
    """One profile/pitch error harmonic of a disc: material A cos(order phi + phase)
    added along the profile normal at curve parameter phi."""

    order: int = Field(description="Order n in the profile curve parameter (1..4 z_rp)")
    amplitude_um: float = Field(description="Amplitude A [um] (0..500)")
    phase_deg: float = Field(default=0.0, description="Phase [deg]")


class DiscErrors(_Strict):
    """Errors of one cycloid disc (deviations on top of the nominal modification)."""

    equidistant_um: float = _meta("one", "disp", "Extra equidistant modification dr_rp [um]")
    shift_um: float = _meta("one", "disp", "Extra shift modification dR_p [um]")
    rotation_arcmin: float = _meta("one", "angle", "Extra rotation modification [arcmin]")
    harmonics: list[Harmonic] = Field(default_factory=list, description="Profile/pitch error harmonics")
    hole_radial_um: float | list[float] = _meta(
        "crank", "disp", "Crank-hole centre radial error in the disc (+ outward) [um]"
    )
    hole_tangential_um: float | list[float] = _meta(
        "crank", "disp", "Crank-hole centre tangential error in the disc (+ counter-clockwise) [um]"
    )


class CrankErrors(_Strict):
    """Crankshaft errors: eccentrics [crank][disc], crank bores in the carrier per crank."""

    eccentricity_um: float | list[list[float]] = _meta(
        "crank_disc", "disp", "Eccentricity error of each eccentric [um]"
    )
    eccentric_phase_arcmin: float | list[list[float]] = _meta(
        "crank_disc", "angle", "Eccentric phase error (added to the clockwise angle chi) [arcmin]"
    )
    bore_radial_um: float | list[float] = _meta("crank", "disp", "Crank bore radial position error in the carrier [um]")
    bore_tangential_um: float | list[float] = _meta(
        "crank", "disp", "Crank bore tangential position error in the carrier [um]"
    )


class FirstStageErrors(_Strict):
    """Involute first stage: sun and planet runout, planet assembly phase errors."""

    sun_runout_um: float = _meta("one", "amp", "Sun runout amplitude along the lines of action [um]")
    sun_runout_phase_deg: float = _meta("one", "phase", "Sun runout phase [deg]")
    planet_runout_um: float | list[float] = _meta("crank", "amp", "Planet runout amplitude [um]")
    planet_runout_phase_deg: float | list[float] = _meta("crank", "phase", "Planet runout phase [deg]")
    planet_phase_arcmin: float | list[float] = _meta(
        "crank", "angle", "Planet assembly phase error on its crank [arcmin]"
    )


class ClearanceErrors(_Strict):
    """Bearing clearances: needle bearings [crank][disc], crank supports per crank."""

    needle_extra_clearance_um: float | list[list[float]] = _meta(
        "crank_disc",
        "disp",
        "Added to each side's gap of the needle bearing, half the design's radial internal clearance (ISO 5593 "
        "total play); the gap stays >= 0 [um]",
    )
    support_clearance_um: float | list[float] = _meta(
        "crank",
        "clear",
        "Free radial travel of each crank in its support bearings from the centred position, per side: half "
        "their radial internal clearance as ISO 5593 defines it (the total play) [um]",
    )


_GROUPS = {"pins": PinErrors, "cranks": CrankErrors, "first_stage": FirstStageErrors, "clearances": ClearanceErrors}


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _check_value(path: str, v: Any, bound: str) -> None:
    lo, hi, unit = _BOUNDS[bound]
    rng = "a finite number" if bound == "phase" else f"a number within {lo:g}..{hi:g} {unit}"
    if not _is_number(v):
        raise _bad(path, v, f"must be {rng}")
    if not math.isfinite(v):
        raise _bad(path, v, f"must be {rng}", "NaN and infinity are not allowed")
    if not lo <= v <= hi:
        raise _bad(path, v, f"must be {rng}")


def _check_field(path: str, v: Any, shape: str, bound: str) -> None:
    """Type, finiteness and bounds of one field value (any allowed shape)."""
    if _is_number(v) or shape == "one":
        _check_value(path, v, bound)
        return
    if not isinstance(v, list):
        raise _bad(path, v, "must be one number or a list" + (" of lists" if shape == "crank_disc" else ""))
    for i, item in enumerate(v):
        if shape == "crank_disc":
            if not isinstance(item, list):
                raise _bad(f"{path}[{i}]", item, "must be a list with one value per disc ([crank][disc] indexing)")
            for k, x in enumerate(item):
                _check_value(f"{path}[{i}][{k}]", x, bound)
        else:
            _check_value(f"{path}[{i}]", item, bound)


def _check_group(path: str, model: type[BaseModel], data: Any) -> None:
    if isinstance(data, BaseModel):
        data = data.model_dump()
    if not isinstance(data, dict):
        return  # pydantic reports the wrong type
    for name, info in model.model_fields.items():
        extra = info.json_schema_extra or {}
        if name in data and "shape" in extra:
            _check_field(f"{path}.{name}", data[name], extra["shape"], extra["bound"])


def _check_harmonics(path: str, data: Any) -> None:
    if not isinstance(data, list):
        return
    for h, item in enumerate(data):
        if isinstance(item, BaseModel):
            item = item.model_dump()
        if not isinstance(item, dict):
            continue
        p = f"{path}[{h}]"
        if "order" in item and (
            not isinstance(item["order"], int) or isinstance(item["order"], bool) or item["order"] < 1
        ):
            raise _bad(f"{p}.order", item["order"], "must be an integer >= 1 (at most 4 z_rp)")
        if "amplitude_um" in item:
            _check_value(f"{p}.amplitude_um", item["amplitude_um"], "amp")
        if "phase_deg" in item:
            _check_value(f"{p}.phase_deg", item["phase_deg"], "phase")


def _length(path: str, value: Any, n: int, what: str) -> None:
    if isinstance(value, list) and len(value) != n:
        raise _bad(
            path,
            value if len(value) <= 8 else f"<list of {len(value)} values>",
            f"must be one number or a list of exactly {n} values ({what})",
        )


def _nonzero(path: str, value: Any, out: list[tuple[str, Any]]) -> None:
    if isinstance(value, list):
        if any(_flat_nonzero(v) for v in value):
            out.append((path, value))
    elif value:
        out.append((path, value))


def _flat_nonzero(v: Any) -> bool:
    return any(_flat_nonzero(x) for x in v) if isinstance(v, list) else bool(v)


class ManufacturingErrors(_Strict):
    """The ``[errors]`` table of a design (see the module docstring)."""

    pins: PinErrors = Field(default_factory=PinErrors)
    discs: list[DiscErrors] = Field(default_factory=list, description="Absent or one table per disc")
    cranks: CrankErrors = Field(default_factory=CrankErrors)
    first_stage: FirstStageErrors = Field(default_factory=FirstStageErrors)
    clearances: ClearanceErrors = Field(default_factory=ClearanceErrors)

    @model_validator(mode="before")
    @classmethod
    def _values(cls, data: Any) -> Any:
        """Types, NaN/inf and bounds of every value, named by its full path."""
        if isinstance(data, BaseModel):
            data = data.model_dump()
        if not isinstance(data, dict):
            return data
        for group, model in _GROUPS.items():
            _check_group(f"errors.{group}", model, data.get(group, {}))
        discs = data.get("discs", [])
        if isinstance(discs, list):
            for k, disc in enumerate(discs):
                _check_group(f"errors.discs[{k}]", DiscErrors, disc)
                d = disc.model_dump() if isinstance(disc, BaseModel) else disc
                if isinstance(d, dict):
                    _check_harmonics(f"errors.discs[{k}].harmonics", d.get("harmonics", []))
        return data

    # ------------------------------------------------------------------ queries
    def nonzero_items(self) -> list[tuple[str, Any]]:
        """(field path, value) of every non-zero error, in table order."""
        out: list[tuple[str, Any]] = []
        for group in _GROUPS:
            for name, value in getattr(self, group):
                _nonzero(f"errors.{group}.{name}", value, out)
        for k, disc in enumerate(self.discs):
            for name, value in disc:
                if name == "harmonics":
                    for h, harm in enumerate(value):
                        if harm.amplitude_um:
                            out.append(
                                (
                                    f"errors.discs[{k}].harmonics[{h}]",
                                    f"order {harm.order}, {harm.amplitude_um:g} um, {harm.phase_deg:g} deg",
                                )
                            )
                else:
                    _nonzero(f"errors.discs[{k}].{name}", value, out)
        return out

    def is_zero(self) -> bool:
        """True if every error is zero (the design is the ideal reducer)."""
        return not self.nonzero_items()

    def only(self, group: str) -> "ManufacturingErrors":
        """A copy with only one error group (``pins``, ``discs``, ``cranks``,
        ``first_stage`` or ``clearances``) kept, every other group zero."""
        if group not in ManufacturingErrors.model_fields:
            raise ValueError(f"unknown error group {group!r}: one of {list(ManufacturingErrors.model_fields)}")
        return ManufacturingErrors(**{group: getattr(self, group)})

    # ------------------------------------------------------------------ design-level checks
    def validate_for(self, reducer) -> None:
        """Checks that need the design: list lengths against z_rp / N / n_discs,
        harmonic order <= 4 z_rp, total needle clearance >= 0, and no interference
        of the as-built pins with the discs at assembly. Raises ValueError naming
        the field (the Reducer validator reports it)."""
        z = reducer.second_stage.pin_count
        nd = reducer.second_stage.n_discs
        n = reducer.first_stage.n_planets
        for name, value in self.pins:
            _length(f"errors.pins.{name}", value, z, f"z_rp = {z} pins")
        if self.discs and len(self.discs) != nd:
            raise _bad(
                "errors.discs",
                f"<{len(self.discs)} tables>",
                f"must be absent or exactly n_discs = {nd} [[errors.discs]] tables",
            )
        for k, disc in enumerate(self.discs):
            for name in ("hole_radial_um", "hole_tangential_um"):
                _length(f"errors.discs[{k}].{name}", getattr(disc, name), n, f"N = {n} cranks")
            for h, harm in enumerate(disc.harmonics):
                if harm.order > 4 * z:
                    raise _bad(
                        f"errors.discs[{k}].harmonics[{h}].order", harm.order, f"must be within 1..4 z_rp = {4 * z}"
                    )
        groups = (
            (self.cranks, "errors.cranks"),
            (self.first_stage, "errors.first_stage"),
            (self.clearances, "errors.clearances"),
        )
        for obj, path in groups:
            for name, info in type(obj).model_fields.items():
                shape = (info.json_schema_extra or {}).get("shape")
                value = getattr(obj, name)
                if shape == "crank":
                    _length(f"{path}.{name}", value, n, f"N = {n} cranks")
                elif shape == "crank_disc" and isinstance(value, list):
                    _length(f"{path}.{name}", value, n, f"one list per crank, N = {n}")
                    for j, row in enumerate(value):
                        _length(f"{path}.{name}[{j}]", row, nd, f"one value per disc, n_discs = {nd}")
        c0 = 0.5 * reducer.needle_bearing.radial_clearance_um  # the per-side gap the extra clearance adds to
        extra = self.clearances.needle_extra_clearance_um
        rows = extra if isinstance(extra, list) else [[extra]]
        for j, row in enumerate(rows):
            for k, v in enumerate(row):
                if c0 + v < 0.0:
                    where = f"[{j}][{k}]" if isinstance(extra, list) else ""
                    raise _bad(
                        f"errors.clearances.needle_extra_clearance_um{where}",
                        v,
                        f"must be >= {-c0:g} um",
                        f"the total needle clearance {c0:g} + ({v:g}) um would be negative",
                    )
        if not self.is_zero():
            self._check_assembly(reducer)

    def _check_assembly(self, reducer) -> None:
        """Interference of the as-built pins with the discs at assembly
        (:func:`flexrv.geometry.as_built.assembly_penetration`): an error if it
        exceeds :data:`ASSEMBLY_PENETRATION_LIMIT_UM` and the nominal design's own
        penetration; the message names the error groups that cause it."""
        from flexrv.geometry.as_built import assembly_penetration
        from flexrv.units import UM_PER_M

        pen, disc, pin = assembly_penetration(reducer, self)
        nominal = assembly_penetration(reducer, ManufacturingErrors())[0]
        if pen * UM_PER_M <= ASSEMBLY_PENETRATION_LIMIT_UM or pen <= nominal:
            return
        alone = []
        for group in ("pins", "discs", "cranks"):
            sub = self.only(group)
            if not sub.is_zero():
                alone.append((assembly_penetration(reducer, sub)[0] * UM_PER_M, f"errors.{group}"))
        alone.sort(reverse=True)
        detail = ", ".join(
            f"{name} alone: " + (f"{p:.3g} um interference" if p > 0 else f"{-p:.3g} um clearance") for p, name in alone
        )
        culprit = (
            alone[0][1] if alone and alone[0][0] > max(nominal * UM_PER_M, 0.0) + 1e-3 else "the combination of errors"
        )
        nominal_text = f"{nominal * UM_PER_M:.3g} um" if nominal > 0 else "none"
        raise ValueError(
            f"{culprit}: the as-built parts interfere at assembly: pin {pin} penetrates disc {disc} by "
            f"{pen * UM_PER_M:.3g} um at the best common disc rotation, more than the "
            f"{ASSEMBLY_PENETRATION_LIMIT_UM:g} um the pin contact law can carry (allowed: <= "
            f"{ASSEMBLY_PENETRATION_LIMIT_UM:g} um; nominal design's interference: {nominal_text}; {detail}); "
            f"reduce {culprit}"
        )


def nominal_design(reducer):
    """The design without its manufacturing errors (``[errors]`` all zero; the profile
    modifications, which set how many pins share the load, are kept). The
    design-level compliance constants of the torque path (the disc body's pin-load
    pattern, the housing ring's estimate) are evaluated on it, so every error set and
    tolerance sample of a design shares them; the errors act through the models'
    contacts. (Evaluated on the analytic as-built pin loads instead, a grade-5 error set
    that preloads a few pins concentrated the pattern into unphysical constants: 79 of
    1,380 rv40e tolerance samples fell to 6-50 N m/arcmin and 35 found no pin-load pose
    at all. Stripping the modifications too would load half the pins and
    halve the housing estimate: the modifications belong to the design.)"""
    return reducer.model_copy(update={"errors": ManufacturingErrors()})


#: memo of :func:`nominal_shared` while :func:`shared_nominal_constants` is active (None: off)
_NOMINAL_MEMO: contextvars.ContextVar[dict | None] = contextvars.ContextVar("nominal_memo", default=None)


@contextlib.contextmanager
def shared_nominal_constants(memo: dict | None = None):
    """Within the block, the constants that depend on the design without its errors only
    (:func:`nominal_shared`: the body compliances, the pin law's constant, the housing
    compliance) are computed once per such design and shared by its error sets: a batch of
    tolerance draws builds its models with the same numbers, computed once. ``memo``: a
    dict to keep them in (the caller bounds it), a fresh one by default."""
    token = _NOMINAL_MEMO.set({} if memo is None else memo)
    try:
        yield
    finally:
        _NOMINAL_MEMO.reset(token)


def nominal_shared(reducer, name: str, compute):
    """``compute(reducer)``, a function of the design without its errors
    (:func:`nominal_design`; ``name`` tells the functions apart): inside
    :func:`shared_nominal_constants` taken from the memo of that design when computed
    before (numpy arrays copied: each caller owns its own)."""
    memo = _NOMINAL_MEMO.get()
    if memo is None:
        return compute(reducer)
    key = (name, nominal_design(reducer).model_dump_json())
    if key not in memo:
        memo[key] = compute(reducer)
    return _copied(memo[key])


def _copied(value):
    import numpy as np

    if isinstance(value, tuple):
        return tuple(_copied(v) for v in value)
    return value.copy() if isinstance(value, np.ndarray) else value
