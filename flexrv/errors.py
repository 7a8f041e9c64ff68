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
