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


# ---------------------------------------------------------------- pair geometry
def base_radius(z, module, alpha):
    """Base radius r_b = m z cos(alpha) / 2 [m] (ISO 21771)."""
    return 0.5 * np.asarray(module) * np.asarray(z) * np.cos(alpha)


def tip_radius(z, module, x, x_other=None, z_other=None, alpha=None, addendum: float = 1.0):
    """Tip radius r_a [m] of an external spur gear (ISO 21771):

    r_a = m (z/2 + h*_a + x - k),   k = x1 + x2 - (a_w - a)/m  (tip alteration),

    so that the standard bottom clearance is kept when a_w differs from
    a + (x1 + x2) m. ASSUMPTION: without the mating data (``x_other`` etc.) k = 0,
    which is exact for zero-sum shifts x1 + x2 = 0 (the presets: rv221 +0.5/-0.5,
    rv40e 0/0) and for unshifted pairs.
    """
    z = np.asarray(z, dtype=float)
    k = 0.0
    if x_other is not None:
        if z_other is None or alpha is None:
            from flexrv.errors import InputError

            raise InputError("tip_radius: z_other and alpha are needed with x_other")
        a_w = working_center_distance(z, z_other, module, alpha, x, x_other)
        a0 = 0.5 * module * (z + z_other)
        k = np.maximum(np.asarray(x) + x_other - (a_w - a0) / module, 0.0)
    return module * (0.5 * z + addendum + np.asarray(x) - k)


def line_of_action(z1, z2, module, alpha, x1, x2):
    """Active length of the line of action g_alpha [m] of an external spur pair
    (ISO 6336-1 / ISO 21771):

    g_alpha = sqrt(r_a1^2 - r_b1^2) + sqrt(r_a2^2 - r_b2^2) - a_w sin(alpha_w),

    tip radii from :func:`tip_radius` with tip alteration for the pair."""
    rb1, rb2 = base_radius(z1, module, alpha), base_radius(z2, module, alpha)
    ra1 = tip_radius(z1, module, x1, x2, z2, alpha)
    ra2 = tip_radius(z2, module, x2, x1, z1, alpha)
    alpha_w = working_pressure_angle(z1, z2, alpha, x1, x2)
    a_w = working_center_distance(z1, z2, module, alpha, x1, x2)
    return np.sqrt(ra1**2 - rb1**2) + np.sqrt(ra2**2 - rb2**2) - a_w * np.sin(alpha_w)


def base_pitch(module, alpha):
    """Transverse base pitch p_bt = pi m cos(alpha) [m]."""
    return np.pi * np.asarray(module) * np.cos(alpha)


def contact_ratio(z1, z2, module, alpha, x1, x2):
    """Transverse contact ratio eps_alpha = g_alpha / p_bt [-] of an external spur
    pair (ISO 6336-1 eq. for eps_alpha; tip radii as in :func:`tip_radius`)."""
    return line_of_action(z1, z2, module, alpha, x1, x2) / base_pitch(module, alpha)


def tooth_pair_count(phase, eps_alpha):
    """Number of tooth pairs in contact (1 or 2) at the mesh phase [-] for
    1 <= eps_alpha < 2.

    The phase runs over one base pitch, 0 at the engagement of a new pair: the
    double-contact zone occupies [0, eps_alpha - 1), the single zone
    [eps_alpha - 1, 1) (ISO 6336-1 points A-B double, B-D single, D-E double,
    periodic in p_bt)."""
    eps = np.asarray(eps_alpha, dtype=float)
    if np.any((eps < 1.0) | (eps >= 2.0)):
        from flexrv.errors import InputError

        raise InputError(f"eps_alpha = {eps_alpha!r} must lie in [1, 2) for the single/double-contact model")
    ph = np.mod(np.asarray(phase, dtype=float), 1.0)
    return np.where(ph < eps - 1.0, 2, 1)
