"""Basic rating life L10 (ISO 281 form) and the dynamic load rating of the main
bearing's angular contact ball rows.

L10 = (C / P)^p  [10^6 revolutions],  p = 3 (ball), 10/3 (roller)
(ISO 281:2007 eqs. 7 and 12; Lundberg & Palmgren 1947/1952).
"""

from __future__ import annotations

import math

import numpy as np

from flexrv.errors import InputError

#: ISO 281:2007 material/manufacturing factor b_m for radial ball bearings.
B_M_BALL = 1.3


def l10(dynamic_rating, equivalent_load, kind: str = "ball"):
    """Basic rating life L10 [10^6 revolutions] = (C/P)^p, p = 3 for ball and
    10/3 for roller bearings (ISO 281:2007). P = 0 gives +inf."""
    p = {"ball": 3.0, "roller": 10.0 / 3.0}.get(kind)
    if p is None:
        raise InputError(f"kind = {kind!r} must be 'ball' or 'roller'")
    c = np.asarray(dynamic_rating, dtype=float)
    load = np.asarray(equivalent_load, dtype=float)
    if np.any(c <= 0) or np.any(load < 0) or not (np.all(np.isfinite(c)) and np.all(np.isfinite(load))):
        raise InputError(
            f"dynamic rating must be > 0 and load >= 0, got C = {dynamic_rating!r}, P = {equivalent_load!r}"
        )
    with np.errstate(divide="ignore"):
        return np.where(load > 0, (c / np.where(load > 0, load, 1.0)) ** p, np.inf)


def life_hours(l10_mrev, speed_rad_s):
    """L10h [h] = 1e6 L10 / (60 n), n in r/min from the speed [rad/s]."""
    n_rpm = abs(float(speed_rad_s)) * 60.0 / (2.0 * math.pi)
    if n_rpm == 0:
        return float("inf")
    return np.asarray(l10_mrev, dtype=float) * 1e6 / (60.0 * n_rpm)


def geometry_factor_fc(gamma, inner_conformity: float, outer_conformity: float, reduction: float = 0.95):
    """Lundberg–Palmgren geometry factor f_c of a ball bearing [N/mm^1.8 units]
    (Harris & Kotzalas 2007, Advanced Concepts, eq. for f_c; the basis of
    ISO 281 Table 2 / ISO/TR 1281-1):

    f_c = 39.9 lambda [1 + (1.04 ((1-g)/(1+g))^1.72 (f_i (2f_o - 1)/(f_o (2f_i - 1)))^0.41)^(10/3)]^(-0.3)
          g^0.3 (1-g)^1.39 / (1+g)^(1/3) (2 f_i/(2 f_i - 1))^0.41,

    g = D cos(a)/d_m, lambda = 0.95 (reduction for stress concentrations/edge
    effects). Uses the design's own conformities rather than ISO's standard ones,
    so it differs from ISO's tabulated f_c by a few percent.
    """
    g = float(gamma)
    fi, fo = inner_conformity, outer_conformity
    if not 0 < g < 1 or fi <= 0.5 or fo <= 0.5:
        raise InputError(f"gamma = {gamma} must lie in (0, 1) and conformities must be > 0.5")
    bracket = 1.0 + (1.04 * ((1 - g) / (1 + g)) ** 1.72 * (fi * (2 * fo - 1) / (fo * (2 * fi - 1))) ** 0.41) ** (10 / 3)
    return (
        39.9
        * reduction
        * bracket**-0.3
        * g**0.3
        * (1 - g) ** 1.39
        / (1 + g) ** (1 / 3)
        * (2 * fi / (2 * fi - 1)) ** 0.41
    )


def ball_dynamic_rating(
    ball_diameter: float,
    pitch_diameter: float,
    ball_count: int,
    contact_angle: float,
    inner_conformity: float,
    outer_conformity: float,
    rows: int = 1,
    b_m: float = B_M_BALL,
):
    """Basic dynamic radial load rating C_r [N] of a radial/angular contact ball
    bearing (ISO 281:2007 eqs. 2-3, N and mm inside):

    C_r = b_m f_c (i cos a)^0.7 Z^(2/3) D^1.8              for D <= 25.4 mm,
    C_r = 3.647 b_m f_c (i cos a)^0.7 Z^(2/3) D^1.4        for D >  25.4 mm,

    f_c from :func:`geometry_factor_fc`, i = rows.
    """
    d_mm = ball_diameter * 1e3
    gamma = ball_diameter * math.cos(contact_angle) / pitch_diameter
    fc = geometry_factor_fc(gamma, inner_conformity, outer_conformity)
    base = b_m * fc * (rows * math.cos(contact_angle)) ** 0.7 * ball_count ** (2.0 / 3.0)
    return base * (d_mm**1.8 if d_mm <= 25.4 else 3.647 * d_mm**1.4)


#: ISO 281:2007 Table 3, single-row angular contact ball bearings: (alpha_deg, e, X, Y).
_ISO281_XY = np.array(
    [
        [20, 0.57, 0.43, 1.00],
        [25, 0.68, 0.41, 0.87],
        [30, 0.80, 0.39, 0.76],
        [35, 0.95, 0.37, 0.66],
        [40, 1.14, 0.35, 0.57],
        [45, 1.34, 0.33, 0.50],
    ]
)


def equivalent_radial_load(radial, axial, contact_angle):
    """Dynamic equivalent radial load P [N] of a single-row angular contact ball
    bearing, P = X F_r + Y F_a (X = 1, Y = 0 for F_a/F_r <= e), factors from
    ISO 281:2007 Table 3 interpolated linearly in the contact angle (20-45 deg)."""
    a = math.degrees(contact_angle)
    if not 20.0 <= a <= 45.0:
        raise InputError(f"contact angle = {a:.3g} deg outside the ISO 281 table range 20-45 deg")
    e, x, y = (np.interp(a, _ISO281_XY[:, 0], _ISO281_XY[:, k]) for k in (1, 2, 3))
    fr, fa = np.abs(np.asarray(radial, dtype=float)), np.abs(np.asarray(axial, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        light = np.where(fr > 0, fa / np.where(fr > 0, fr, 1.0) <= e, fa == 0)
    return np.where(light, fr, x * fr + y * fa)


def system_life(lives, exponent: float = 10.0 / 9.0):
    """Life of components in series (Lundberg–Palmgren / Weibull slope e = 10/9
    for ball bearings): L = (sum L_k^-e)^(-1/e)."""
    lv = np.asarray(lives, dtype=float)
    with np.errstate(divide="ignore"):
        inv = np.sum(np.where(np.isfinite(lv), lv, np.inf) ** -exponent)
    return float("inf") if inv == 0 else float(inv ** (-1.0 / exponent))


def line_contact_fc(gamma, lambda_nu: float = 0.83):
    """Factor f_c of the basic dynamic radial load rating of roller bearings (line
    contact), ISO 281:2007 eq. (Lundberg–Palmgren):
    f_c = 207.9 lambda nu gamma^(2/9) (1 - gamma)^(29/27) (1 + gamma)^(-1/4)
    {1 + [1.04 ((1 - gamma)/(1 + gamma))^(143/108)]^(9/2)}^(-2/9), gamma = D cos(a)/D_pw,
    lambda nu = 0.83 (the value behind ISO 281's Table 7)."""
    g = np.asarray(gamma, dtype=float)
    if np.any((g <= 0) | (g >= 1)):
        raise InputError(f"gamma = {gamma!r} must lie in (0, 1)")
    ratio = (1.0 - g) / (1.0 + g)
    return (
        207.9
        * lambda_nu
        * g ** (2.0 / 9.0)
        * (1.0 - g) ** (29.0 / 27.0)
        * (1.0 + g) ** -0.25
        * (1.0 + (1.04 * ratio ** (143.0 / 108.0)) ** 4.5) ** (-2.0 / 9.0)
    )


def roller_dynamic_rating(
    roller_diameter: float,
    roller_length: float,
    roller_count: int,
    pitch_diameter: float,
    rows: int = 1,
    contact_angle: float = 0.0,
    b_m: float = 1.1,
) -> float:
    """Basic dynamic radial load rating C_r [N] of a roller (needle) bearing,
    ISO 281:2007: C_r = b_m f_c (i L_we cos a)^(7/9) Z^(3/4) D_we^(29/27) with lengths
    in mm; b_m = 1.1 (needle roller bearings with machined raceways; the crank's
    eccentric and the disc's bore are the raceways). Inputs in SI [m]."""
    for name, v in (
        ("roller_diameter", roller_diameter),
        ("roller_length", roller_length),
        ("pitch_diameter", pitch_diameter),
    ):
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} = {v!r} m must be > 0")
    if roller_count < 1 or rows < 1:
        raise InputError(f"roller_count = {roller_count!r} and rows = {rows!r} must be >= 1")
    d_mm, l_mm = 1e3 * roller_diameter, 1e3 * roller_length
    c = math.cos(contact_angle)
    fc = float(line_contact_fc(roller_diameter * c / pitch_diameter))
    return b_m * fc * (rows * l_mm * c) ** (7.0 / 9.0) * roller_count**0.75 * d_mm ** (29.0 / 27.0)
