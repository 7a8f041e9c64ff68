"""Exception types of flexrv.

Every error a user can provoke with bad input derives from :class:`FlexrvError`;
the CLI turns it into one clear message and exit code 2 (no traceback).
"""

from __future__ import annotations


class FlexrvError(Exception):
    """Base class of all user-facing flexrv errors (bad input, failed run)."""


class ConfigError(FlexrvError):
    """A design/config file or value is invalid. The message names the field,
    the value and the allowed range."""


class InputError(FlexrvError):
    """A function argument is out of its physical range (e.g. negative load)."""


class ConvergenceError(FlexrvError):
    """A numerical solver did not converge; the message names the residual
    reached and the iterations used."""


class SimulationError(FlexrvError):
    """A dynamic simulation failed (Newton failure, NaN, excessive penetration).
    Partial results are saved before this is raised."""


def check_options(where: str, given: dict | None, allowed: dict[str, object]) -> dict:
    """Validate keyword options against ``allowed`` (name -> an example value of the
    accepted type, or None for any value): an unknown name, or a value of another type
    (no bool where a number is expected, no str where a number is expected; an int is
    accepted for a float), raises :class:`InputError` naming ``where``, the option and
    what is allowed. Returns the options as a new dict.

    >>> check_options("newton_options", {"maxIterations": 30}, {"maxIterations": 25})
    {'maxIterations': 30}
    >>> check_options("ring_options", {"harmonic": 8}, {"harmonics": 16, "size": None})
    Traceback (most recent call last):
    ...
    flexrv.errors.InputError: ring_options: unknown option 'harmonic'; allowed: harmonics, size
    """
    given = dict(given or {})
    if not all(isinstance(k, str) for k in given):
        raise InputError(f"{where}: option names must be strings, got {sorted(map(repr, given))}")
    for key, value in given.items():
        if key not in allowed:
            raise InputError(f"{where}: unknown option {key!r}; allowed: {', '.join(sorted(allowed)) or '(none)'}")
        ref = allowed[key]
        if ref is None or value is None:
            continue
        if isinstance(ref, bool):
            ok = isinstance(value, bool)
        elif isinstance(ref, (int, float)):
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            if isinstance(ref, int) and isinstance(value, float):
                ok = False  # a count or a switch: no fractional value
        else:
            ok = isinstance(value, type(ref)) or isinstance(ref, (tuple, list)) and isinstance(value, (tuple, list))
        if not ok:
            raise InputError(
                f"{where}.{key} = {value!r} is not allowed: expected a value of type "
                f"{type(ref).__name__} (like {ref!r})"
            )
    return given


def signature_options(fn, skip: int = 0, exclude: tuple[str, ...] = ()) -> dict[str, object]:
    """The keyword options of ``fn`` with their defaults (for :func:`check_options`):
    every parameter after the first ``skip`` positional ones, except ``exclude``."""
    import inspect

    def example(p):
        if p.default is not inspect.Parameter.empty and p.default is not None:
            return p.default
        # no default value to compare with: the annotation's scalar type, if it names one
        ann = p.annotation if isinstance(p.annotation, str) else getattr(p.annotation, "__name__", "")
        kinds = [t.strip() for t in str(ann).split("|")]
        for name, value in (("bool", False), ("int", 0), ("float", 0.0), ("str", "")):
            if name in kinds:
                return value
        return None

    params = list(inspect.signature(fn).parameters.values())[skip:]
    return {
        p.name: example(p)
        for p in params
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name not in exclude
    }
