"""Hertz contact of elastic bodies: elliptical point contact and line contact.

All functions are vectorised over numpy arrays and use SI units. Conventions
follow Hamrock (Fundamentals of Fluid Film Lubrication, 1994, ch. 17) and
Harris & Kotzalas (Rolling Bearing Analysis, 5th ed., 2007, ch. 6):

* ``rx`` is the effective radius in the rolling (entrainment) direction x and
  ``ry`` in the transverse direction y, 1/R = 1/rx + 1/ry;
* E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) is Hamrock's effective modulus
  (Johnson's E* = E'/2);
* the contact ellipse has semi-axis ``a`` along y and ``b`` along x; with
  ry >= rx the ellipticity k = a/b >= 1.

The ellipticity is found exactly (complete elliptic integrals, scipy) rather than
from the Hamrock–Brewe curve fits, so the sphere–sphere case reproduces the
closed form to machine precision.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ellipe, ellipk

from flexrv.errors import InputError


def effective_modulus(e1, nu1, e2, nu2):
    """Hamrock's effective modulus E' [Pa] = 2 / ((1-nu1^2)/E1 + (1-nu2^2)/E2)."""
    return 2.0 / ((1.0 - np.asarray(nu1) ** 2) / np.asarray(e1, dtype=float) + (1.0 - np.asarray(nu2) ** 2) / e2)


def _positive(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"{name} must be finite and > 0, got {value!r}")
    return arr


# ---------------------------------------------------------------- ellipticity
def _curvature_ratio_of(m):
    """Curvature ratio ry/rx (>= 1) that yields the ellipse with e^2 = m.

    From Hertz's equations (Harris & Kotzalas 2007, eq. 6.36 rearranged):
    ry/rx = [E(m)/(1-m) - K(m)] / [K(m) - E(m)], K, E complete elliptic integrals
    of the first and second kind with parameter m = 1 - (b/a)^2.
    """
    kk, ee = ellipk(m), ellipe(m)
    return (ee / (1.0 - m) - kk) / (kk - ee)


_M_GRID = 1.0 - np.logspace(-14, 0, 4000)[::-1]  # m in (0, 1 - 1e-14], dense towards 1
_M_GRID = _M_GRID[(_M_GRID > 1e-10)]
_LOG_RATIO_GRID = np.log(_curvature_ratio_of(_M_GRID))


def ellipse_parameter(ratio):
    """Elliptic parameter m = e^2 = 1 - 1/k^2 for a curvature ratio ry/rx >= 1.

    Inverse of :func:`_curvature_ratio_of` by monotone interpolation in log space
    followed by two Newton steps (relative error < 1e-12).
    """
    ratio = np.asarray(ratio, dtype=float)
    lr = np.log(np.maximum(ratio, 1.0))
    m = np.interp(lr, _LOG_RATIO_GRID, _M_GRID, left=0.0)
    small = lr < _LOG_RATIO_GRID[0]
    # near the sphere: ratio - 1 ~ (3/4) m  (series of the Hertz relation)
    m = np.where(small, lr / 0.75, m)
    for _ in range(2):
        mm = np.clip(m, 1e-12, 1.0 - 1e-15)
        f = np.log(_curvature_ratio_of(mm)) - lr
        h = 1e-7 * np.maximum(mm, 1e-6)
        df = (np.log(_curvature_ratio_of(np.minimum(mm + h, 1 - 1e-15))) - np.log(_curvature_ratio_of(mm))) / h
        with np.errstate(divide="ignore", invalid="ignore"):  # df = 0 only where `small` selects m anyway
            m = np.where(small, m, np.clip(mm - f / df, 1e-12, 1.0 - 1e-15))
    return np.where(ratio <= 1.0, 0.0, m)


@dataclass(frozen=True)
class PointContact:
    """Result of :func:`point_contact` (arrays broadcast to the inputs' shape).

    Attributes
    ----------
    a, b : semi-axes [m] along y (transverse) and x (rolling).
    p_max : maximum Hertz pressure [Pa].
    approach : elastic approach of the two bodies delta [m].
    ellipticity : k = a/b [-].
    first_kind, second_kind : complete elliptic integrals F (=K(m)) and E(m) [-].
    reduced_radius : R = 1/(1/rx + 1/ry) [m].
    """

    a: np.ndarray
    b: np.ndarray
    p_max: np.ndarray
    approach: np.ndarray
    ellipticity: np.ndarray
    first_kind: np.ndarray
    second_kind: np.ndarray
    reduced_radius: np.ndarray


def _ellipse_constants(rx, ry):
    """(k, F, E, R, swapped) for principal radii rx, ry; ``swapped`` where rx > ry."""
    rx = np.asarray(rx, dtype=float)
    ry = np.asarray(ry, dtype=float)
    swapped = rx > ry
    r_small = np.where(swapped, ry, rx)
    r_large = np.where(swapped, rx, ry)
    m = ellipse_parameter(r_large / r_small)
    k = 1.0 / np.sqrt(1.0 - m)
    big_f = ellipk(m)
    big_e = ellipe(m)
    reduced = 1.0 / (1.0 / rx + 1.0 / ry)
    return k, big_f, big_e, reduced, swapped


def point_contact(load, rx, ry, e_eff) -> PointContact:
    """Hertz elliptical point contact under normal load.

    Hamrock (1994) eqs. 17.x with exact ellipticity:
    a = (6 k^2 E W R / (pi E'))^(1/3), b = (6 E W R / (pi k E'))^(1/3),
    delta = F [ (9 / (2 E R)) (W / (pi k E'))^2 ]^(1/3), p_max = 3 W / (2 pi a b).

    Parameters
    ----------
    load : array_like
        Normal load W [N] (>= 0).
    rx, ry : array_like
        Effective radii of curvature [m] in x and y (> 0; rx > ry is allowed, the
        semi-axes are then swapped so that ``a`` stays along y).
    e_eff : array_like
        Effective modulus E' [Pa].
    """
    load = np.asarray(load, dtype=float)
    if np.any(~np.isfinite(load)) or np.any(load < 0):
        raise InputError(f"load must be finite and >= 0 N, got {load!r}")
    _positive("rx", rx)
    _positive("ry", ry)
    e_eff = _positive("e_eff", e_eff)
    k, big_f, big_e, reduced, swapped = _ellipse_constants(rx, ry)
    major = np.cbrt(6.0 * k**2 * big_e * load * reduced / (np.pi * e_eff))
    minor = np.cbrt(6.0 * big_e * load * reduced / (np.pi * k * e_eff))
    delta = big_f * np.cbrt(9.0 / (2.0 * big_e * reduced) * (load / (np.pi * k * e_eff)) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        p_max = np.where(load > 0, 3.0 * load / (2.0 * np.pi * major * minor), 0.0)
    a = np.where(swapped, minor, major)
    b = np.where(swapped, major, minor)
    return PointContact(
        a=a,
        b=b,
        p_max=p_max,
        approach=delta,
        ellipticity=np.where(swapped, 1.0 / k, k),
        first_kind=big_f,
        second_kind=big_e,
        reduced_radius=reduced,
    )


def point_contact_stiffness(rx, ry, e_eff):
    """Load–deflection constant K [N/m^1.5] of a Hertz point contact, Q = K delta^1.5.

    Inverting Hamrock's approach equation:
    K = pi k E' sqrt(2 E R / (9 F^3)) (Harris & Kotzalas 2007, eq. 6.42 in SI).
    """
    _positive("rx", rx)
    _positive("ry", ry)
    e_eff = _positive("e_eff", e_eff)
    k, big_f, big_e, reduced, _ = _ellipse_constants(rx, ry)
    return np.pi * k * e_eff * np.sqrt(2.0 * big_e * reduced / (9.0 * big_f**3))


def series_stiffness(k1, k2, exponent: float = 1.5):
    """Combined constant of two power-law contacts in series, Q = K delta^n with
    delta = delta1 + delta2: K = (K1^(-1/n) + K2^(-1/n))^(-n) (Harris & Kotzalas
    2007, eq. 7.4 for n = 3/2)."""
    n = exponent
    return (np.asarray(k1, dtype=float) ** (-1.0 / n) + np.asarray(k2, dtype=float) ** (-1.0 / n)) ** (-n)


# ---------------------------------------------------------------- line contact
@dataclass(frozen=True)
class LineContact:
    """Result of :func:`line_contact`.

    Attributes
    ----------
    half_width : Hertz half-width b [m].
    p_max : maximum pressure [Pa] = 2 W / (pi b L).
    approach : approach delta [m] from Palmgren's roller formula.
    """

    half_width: np.ndarray
    p_max: np.ndarray
    approach: np.ndarray


#: Palmgren's roller constant: delta[mm] = 3.84e-5 Q[N]^0.9 / L[mm]^0.8 for steel
#: (E' = 2.275e11 Pa); rewritten for any E' as delta = C (Q/E')^0.9 / L^0.8 in SI.
_PALMGREN_EPRIME = 207e9 / (1.0 - 0.3**2)
_PALMGREN_C = 3.84e-5 * 1e-3 * (1e-3) ** 0.8 * _PALMGREN_EPRIME**0.9  # [m^1.8] so that delta [m]
LINE_EXPONENT = 10.0 / 9.0  #: Q ~ delta^(10/9) (Palmgren)


def line_contact(load, length, r_eff, e_eff) -> LineContact:
    """Hertz line contact of parallel cylinders (Johnson 1985, sec. 4.3).

    b = sqrt(8 W R / (pi L E')), p_max = 2 W / (pi b L); the approach uses
    Palmgren's empirical roller formula delta = 3.84e-5 Q^0.9 / L^0.8 [mm, N]
    (Harris & Kotzalas 2007, eq. 6.74), scaled with E'^-0.9 for other materials
    (a 2-D Hertz contact has no finite approach without a body size).

    Parameters
    ----------
    load : normal load W [N]; length : contact length L [m];
    r_eff : reduced radius R = 1/(1/r1 + 1/r2) [m] (negative r for concave);
    e_eff : effective modulus E' [Pa].
    """
    load = np.asarray(load, dtype=float)
    if np.any(~np.isfinite(load)) or np.any(load < 0):
        raise InputError(f"load must be finite and >= 0 N, got {load!r}")
    length = _positive("length", length)
    r_eff = _positive("r_eff", r_eff)
    e_eff = _positive("e_eff", e_eff)
    half = np.sqrt(8.0 * load * r_eff / (np.pi * length * e_eff))
    with np.errstate(invalid="ignore", divide="ignore"):
        p_max = np.where(load > 0, 2.0 * load / (np.pi * half * length), 0.0)
    delta = _PALMGREN_C * (load / e_eff) ** 0.9 / length**0.8
    return LineContact(half_width=half, p_max=p_max, approach=delta)


def line_contact_stiffness(length, e_eff):
    """Constant K [N/m^(10/9)] of Palmgren's line-contact law Q = K delta^(10/9).

    Inverse of the approach in :func:`line_contact`:
    K = E' (L^0.8 / C)^(10/9).
    """
    length = _positive("length", length)
    e_eff = _positive("e_eff", e_eff)
    return e_eff * (length**0.8 / _PALMGREN_C) ** (1.0 / 0.9)


def conformal_line_contact(load, length, pin_radius, groove_radius, e_eff):
    """Hertz line contact of a pin of radius r in a concave cylindrical seat
    (groove) of radius R_g > r, and how conformal it is.

    Reduced radius of the conformal pair (Johnson 1985, sec. 4.3, concave radius
    negative): 1/R = 1/r - 1/R_g, R = r R_g / (R_g - r); the half-width, pressure
    and (Palmgren) approach are those of :func:`line_contact` with that R.

    Returns (LineContact, semi_angle) with semi_angle = b / r [rad], the half-angle
    of the contact arc on the pin. Hertz's half-space idealisation needs b << r
    (Johnson 1985, sec. 4.1: the contact small against the radii); where b / r is not
    small (a close-fitting groove) the contact spreads over an arc (Persson 1964;
    Johnson 1985, sec. 5.3), and the 2-D approach, whose logarithmic term
    ln(4 r / b) falls as b grows (Johnson 1985, sec. 5.6), is expected smaller than a
    Hertz/Palmgren line contact's of the same length: the radius-free Palmgren
    approach is then a conservative (compliant) estimate of the seat. Callers report
    ``semi_angle`` so the range is visible.

    Parameters
    ----------
    load : normal load W [N] (>= 0); length : seat length L [m];
    pin_radius : r [m]; groove_radius : R_g [m] (> r); e_eff : E' [Pa].
    """
    r = _positive("pin_radius", pin_radius)
    rg = _positive("groove_radius", groove_radius)
    if np.any(rg <= r):
        raise InputError(
            f"groove_radius = {groove_radius!r} m must be > pin_radius = {pin_radius!r} m (a seat with clearance)"
        )
    contact = line_contact(load, length, r * rg / (rg - r), e_eff)
    return contact, contact.half_width / r
