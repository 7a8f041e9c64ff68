"""Base of every validated design table: strict pydantic model and the uniform
error message (one place for both, imported by :mod:`flexrv.design.model` and
:mod:`flexrv.design.manufacturing`)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class _Strict(BaseModel):
    """Base: unknown fields and non-finite numbers are errors, values are frozen,
    types are strict: a string (``"12.0"``) or a boolean (``true``) is never coerced
    into a number, a float never into an integer; an integer is accepted for a float
    field (TOML ``12`` for ``12.0``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, validate_default=True, strict=True)


def _bad(field: str, value, allowed: str, why: str = "") -> ValueError:
    """Build the uniform cross-field error message."""
    msg = f"{field} = {value!r} is not allowed: {allowed}"
    if why:
        msg += f" ({why})"
    return ValueError(msg)


def floor(why: str) -> dict:
    """Field metadata of a physical lower bound: the reason, printed with the bound when a
    value falls below it (``Field(ge=1.0, json_schema_extra=floor("..."))``)."""
    return {"floor_reason": why}
