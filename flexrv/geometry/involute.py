"""Involute spur-gear geometry (ISO 21771 / ISO 6336-1 notation), SI units.

Pure vectorised functions; no I/O.
"""

from __future__ import annotations

import numpy as np


def involute(alpha):
    """inv(alpha) = tan(alpha) - alpha [rad]."""
    alpha = np.asarray(alpha, dtype=float)
    return np.tan(alpha) - alpha


def inverse_involute(value, iterations: int = 30):
    """Angle alpha [rad] with inv(alpha) = value (Newton from a cubic-root start)."""
    value = np.asarray(value, dtype=float)
    alpha = np.cbrt(3.0 * value)  # inv(a) ~ a^3/3 for small a
    for _ in range(iterations):
        f = np.tan(alpha) - alpha - value
        alpha = alpha - f / np.tan(alpha) ** 2
    return alpha


def working_pressure_angle(z1, z2, alpha, x1, x2):
    """Working (operating) transverse pressure angle alpha_w [rad] of an external
    spur pair with profile shifts x1, x2 (no backlash): ISO 21771 eq.
    inv(alpha_w) = inv(alpha) + 2 tan(alpha) (x1 + x2) / (z1 + z2)."""
    return inverse_involute(involute(alpha) + 2.0 * np.tan(alpha) * (np.asarray(x1) + x2) / (np.asarray(z1) + z2))


def working_center_distance(z1, z2, module, alpha, x1, x2):
    """Working centre distance a_w [m] = m (z1+z2)/2 cos(alpha)/cos(alpha_w)."""
    alpha_w = working_pressure_angle(z1, z2, alpha, x1, x2)
    return 0.5 * module * (np.asarray(z1) + z2) * np.cos(alpha) / np.cos(alpha_w)
