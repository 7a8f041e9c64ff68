"""Typed parameters of the compiled force elements, read by name.

A force element's compiled kernel receives ONE pack: a named tuple (numba types a
``collections.namedtuple`` as a ``NamedTuple`` and caches functions taking it) whose
fields are the element's coordinate indices, its scalar law (a named tuple of
scalars, :func:`law_type`), its as-built arrays, its live output arrays and its work
arrays. The kernel reads ``p.law.eccentricity`` and ``p.gap``, never a position in a
flat vector, so a wrong name fails at compile time instead of reading another
parameter. Pack sizes are derived: a law's length is its field list, an absent
element's pack is built by :func:`empty_pack` from the pack type's field kinds.

Field kinds of :func:`pack_type`: a law type (zeros of its fields; :func:`law_type`, or a
``typing.NamedTuple`` class of scalars with a ``zero()`` class method, as a contact law below
the model layer defines its constants, e.g. :class:`flexrv.contact.tapered_roller.SupportConstants`), ``(dtype,
ndim)`` (an array of that many dimensions, empty in an absent element's pack) or
``(dtype, shape)`` (a fixed shape the kernel reads even when it has nothing to do,
zeros in an absent element's pack) or ``tuple`` (a tuple of parts of one type, one per
repeated unit, e.g. a bearing row; empty in an absent element's pack).
"""

from __future__ import annotations

import sys
from collections import namedtuple

import numpy as np


def _caller_module() -> str:
    """The module that calls :func:`law_type` / :func:`pack_type` (two frames up)."""
    return sys._getframe(2).f_globals.get("__name__", __name__)


def _as_float_array(value) -> np.ndarray:
    return np.ascontiguousarray(value, dtype=np.float64).reshape(-1)


def law_type(name: str, **fields: type):
    """A named tuple of scalars (``float``, ``int`` or ``bool`` per field; ``np.ndarray``:
    a flat float64 table, e.g. a film map) with ``of(**values)`` (every field required,
    each converted to its type, unknown names rejected) and ``zero()``. Define it at
    module level under ``name``: the type belongs to the calling module, so that numba's
    cache pickles it by reference (``module.name``) and finds it again in the next
    process; a type that cannot be found by name is pickled by value, a new class in
    every process, and every cached kernel taking it would compile again."""
    cls = namedtuple(name, list(fields), module=_caller_module())
    cls._types = dict(fields)
    convert = {k: (_as_float_array if t is np.ndarray else t) for k, t in fields.items()}

    def of(**values):
        missing = set(fields) - set(values)
        extra = set(values) - set(fields)
        if missing or extra:
            raise TypeError(f"{name}: missing {sorted(missing)}, unknown {sorted(extra)}")
        return cls(**{k: convert[k](values[k]) for k in fields})

    def zero():
        return cls(**{k: (np.zeros(0) if t is np.ndarray else t(0)) for k, t in fields.items()})

    cls.of = staticmethod(of)
    cls.zero = staticmethod(zero)
    return cls


def pack_type(name: str, *fields: tuple):
    """A named tuple of kernel arguments; ``fields``: (field name, kind) pairs (module
    docstring). Define it at module level under ``name`` (see :func:`law_type`)."""
    cls = namedtuple(name, [f for f, _ in fields], module=_caller_module())
    cls._kinds = dict(fields)
    return cls


def _is_law(kind) -> bool:
    """A law type: a named tuple of scalars with ``zero()`` (not a pack type)."""
    return isinstance(kind, type) and issubclass(kind, tuple) and hasattr(kind, "zero") and not hasattr(kind, "_kinds")


def empty_pack(cls):
    """The pack of an absent element of pack type ``cls``: empty arrays (fixed-shape
    fields zero-filled), zero laws, nested packs empty; same numba types as a live pack."""
    values = []
    for field, kind in cls._kinds.items():
        if hasattr(kind, "_kinds"):
            values.append(empty_pack(kind))
        elif _is_law(kind):
            values.append(kind.zero())
        elif kind is tuple:
            values.append(())
        else:
            dtype, shape = kind
            values.append(np.zeros((0,) * shape if isinstance(shape, int) else shape, dtype=dtype))
    return cls(*values)


def check_pack(pack) -> None:
    """Raise TypeError if a field of ``pack`` does not match its declared kind (dtype,
    dimensions, C order): a kernel would otherwise be compiled for another type."""
    for field, kind in type(pack)._kinds.items():
        value = getattr(pack, field)
        if hasattr(kind, "_kinds"):
            check_pack(value)
        elif _is_law(kind):
            if type(value) is not kind:
                raise TypeError(f"{type(pack).__name__}.{field} must be a {kind.__name__}")
        elif kind is tuple:
            if not isinstance(value, tuple):
                raise TypeError(f"{type(pack).__name__}.{field} must be a tuple")
        else:
            dtype, shape = kind
            ndim = shape if isinstance(shape, int) else len(shape)
            if not (
                isinstance(value, np.ndarray)
                and value.dtype == np.dtype(dtype)
                and value.ndim == ndim
                and value.flags.c_contiguous
            ):
                raise TypeError(f"{type(pack).__name__}.{field} must be a C-contiguous {dtype} array of {ndim} dims")
