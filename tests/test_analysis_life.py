"""L10 life and ISO 281 dynamic load rating."""

import math

import numpy as np
import pytest

from flexrv.analysis.life import (
    ball_dynamic_rating,
    equivalent_radial_load,
    geometry_factor_fc,
    l10,
    life_hours,
    system_life,
)
from flexrv.errors import InputError


def test_l10_power_law():
    """L10 = (C/P)^3 (ball), (C/P)^(10/3) (roller) [1e6 rev] (ISO 281)."""
    assert np.isclose(l10(30e3, 3e3), 1000.0)
    assert np.isclose(l10(30e3, 3e3, "roller"), 10 ** (10 / 3))
    assert np.isinf(l10(30e3, 0.0))
    assert np.isclose(life_hours(1.0, 2 * math.pi), 1e6 / 3600)  # 60 r/min
    with pytest.raises(InputError):
        l10(-1.0, 1.0)
    with pytest.raises(InputError):
        l10(1.0, 1.0, "needle")


def test_fc_hand_calc():
    """f_c at g = 0.1, f_i = 0.52, f_o = 0.53 by hand: bracket term
    1 + (1.04 * 0.8182^1.72 * 1.4717^0.41)^(10/3) = 1.6125 -> ^-0.3 = 0.8666;
    0.1^0.3 * 0.9^1.39 / 1.1^(1/3) = 0.4194; 26^0.41 = 3.803;
    f_c = 39.9 * 0.95 * 0.8666 * 0.4194 * 3.803 = 52.39 (rel. 1e-3)."""
    assert np.isclose(geometry_factor_fc(0.1, 0.52, 0.53), 52.39, rtol=1e-3)


def test_rating_formula_and_continuity():
    """C_r = b_m f_c (cos a)^0.7 Z^(2/3) D^1.8 (D <= 25.4 mm) and the D^1.4 branch
    joins it continuously (3.647 = 25.4^0.4)."""
    a = math.radians(40)
    d = 0.009525
    g = d * math.cos(a) / 0.16
    ref = 1.3 * geometry_factor_fc(g, 0.52, 0.53) * math.cos(a) ** 0.7 * 38 ** (2 / 3) * 9.525**1.8
    assert np.isclose(ball_dynamic_rating(d, 0.16, 38, a, 0.52, 0.53), ref, rtol=1e-12)
    lo = ball_dynamic_rating(0.0254 - 1e-9, 0.31, 26, a, 0.52, 0.53)
    hi = ball_dynamic_rating(0.0254 + 1e-9, 0.31, 26, a, 0.52, 0.53)
    assert abs(hi / lo - 1) < 1e-3


def test_equivalent_load_iso281():
    """40 deg single row: e = 1.14; P = F_r below e, 0.35 F_r + 0.57 F_a above."""
    a = math.radians(40)
    assert np.isclose(equivalent_radial_load(1000.0, 1000.0, a), 1000.0)
    assert np.isclose(equivalent_radial_load(1000.0, 2000.0, a), 0.35 * 1000 + 0.57 * 2000)
    assert np.isclose(equivalent_radial_load(0.0, 100.0, a), 57.0)
    assert np.isclose(system_life([1e3, 1e3]), 1e3 * 2 ** (-0.9))
