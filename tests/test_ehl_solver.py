"""Numerical EHL point-contact solver (flexrv.ehl.solver).

References: Hertz pressure from flexrv.contact.hertz (Hamrock 1994 ch. 17);
film formulas of Hamrock & Dowson (1977) and Nijenbanning, Venner & Moes (1994)
from flexrv.ehl.film. Default solver: 129^2 (refined to 257^2/513^2 until h_c changes < 2 %
from the next-coarser grid), second-order upwind wedge term, Richardson-extrapolated h_c.
Measured (default solve; tests/test_ehl_convergence.py):

case     M     L     ry/rx  grid  h_c [nm]  /HD    /NVM   change vs next-coarser
circ31   31    13.6  1      129   492.6     1.007  0.929  0.19 %
circ260  260   11.4  1      257   281.9     1.022  0.889  0.75 %
circ640  641   11.4  1      513   263.2     1.013  0.866  0.31 %
ell4     260   11.4  4      129   341.9     0.980  0.880  1.23 %
ell10    1298  11.4  10     257   320.8     0.946  0.853  0.68 %
rv221    719   6.7   28     129   130.3     1.069  0.990  0.66 %
"""

from functools import lru_cache

import numpy as np
import pytest

from flexrv.contact.hertz import point_contact
from flexrv.ehl.film import hamrock_dowson, moes_central
from flexrv.ehl.solver import LubricantProperties, influence_kernel, solve_point_contact
from flexrv.errors import ConvergenceError, InputError

E = 2.2e11
LUB = LubricantProperties(viscosity=0.05, pressure_viscosity=2e-8, roelands_z=0.67, roelands_p0=1.96e8, density=870.0)
CASES = {"circ260": (100.0, 1.0, 0.01, 0.01), "ell4": (100.0, 1.0, 0.01, 0.04), "circ31": (20.0, 2.0, 0.01, 0.01)}


@lru_cache(maxsize=None)
def solve(case, grid):
    q, u, rx, ry = CASES[case]
    return solve_point_contact(q, u, rx, ry, E, LUB, grid=grid)


def test_influence_kernel_uniform_square():
    """Centre deflection of a uniformly loaded square 2c x 2c (unit pressure, E' = 1 Pa):
    w = (2/pi) iint dA/r = (2/pi) 8 c asinh(1) (Love 1929; Johnson 1985, sec. 3.9), and a
    far cell acts as a point load w = (2/pi) A / r."""
    k = influence_kernel(1, 1, 2.0, 2.0)
    np.testing.assert_allclose(k[0, 0], 2.0 / np.pi * 8.0 * np.arcsinh(1.0), rtol=1e-14)
    # far field: a cell acts as a point load: w ~ (2/pi) A / r
    kf = influence_kernel(60, 1, 1.0, 1.0)
    np.testing.assert_allclose(kf[-1, 0], 2.0 / np.pi / 59.0, rtol=1e-4)


def test_hertz_limit_pressure():
    """Piezoviscous-elastic case (M = 260): the pressure follows the Hertz ellipse, p_max
    within 3 % of p_H (the small excess is the pressure spike), and away from inlet and
    spike (|x| < 0.6 b) within 5 % of p_H of the Hertz profile."""
    res = solve("circ260", 65)
    assert abs(res.p_max / res.hertz_pressure - 1.0) < 0.03
    jc = np.argmin(np.abs(res.y))
    xs = res.x / res.hertz_b
    mask = np.abs(xs) < 0.6
    hertz = res.hertz_pressure * np.sqrt(1.0 - xs[mask] ** 2)
    assert np.max(np.abs(res.pressure[mask, jc] - hertz)) < 0.05 * res.hertz_pressure
    pc = point_contact(100.0, 0.01, 0.01, E)
    np.testing.assert_allclose(res.hertz_pressure, pc.p_max, rtol=1e-12)


@pytest.mark.parametrize("case", ["circ260", "ell4"])
def test_film_vs_formulas(case):
    """h_c (default solve, extrapolated) within 8 % of Hamrock-Dowson (measured +2.2 %, -2.0 %) and
    15 % of Nijenbanning-Venner-Moes (measured -12 %); h_min between 0.4 h_c and h_c."""
    q, u, rx, ry = CASES[case]
    res = solve(case, 129)
    hc_hd, _ = hamrock_dowson(q, u, rx, ry, E, LUB.viscosity, LUB.pressure_viscosity)
    hc_moes = moes_central(q, u, rx, ry, E, LUB.viscosity, LUB.pressure_viscosity)
    assert res.extrapolated and res.wedge_order == 2
    assert abs(res.h_central / hc_moes - 1.0) < 0.15
    assert abs(res.h_central / hc_hd - 1.0) < 0.08
    assert 0.4 * res.h_central < res.h_min < res.h_central


@pytest.mark.parametrize("case", ["circ260", "ell4"])
def test_load_balance_and_extrapolation_bookkeeping(case):
    """Load balance |int p - Q|/Q < 1e-3 (measured ~1e-12) on 65^2 (first order, no
    extrapolation by default) and 129^2; h_central = (4 h_129 - h_65)/3 (Richardson, order 2)."""
    coarse, fine = solve(case, 65), solve(case, 129)
    assert not coarse.extrapolated and coarse.wedge_order == 1
    np.testing.assert_allclose(fine.h_central, (4.0 * fine.h_central_grid - fine.h_central_coarse) / 3.0, rtol=1e-12)
    assert fine.load_error < 1e-3 and coarse.load_error < 1e-3
    q = CASES[case][0]
    dx, dy = fine.x[1] - fine.x[0], fine.y[1] - fine.y[0]
    np.testing.assert_allclose(fine.pressure.sum() * dx * dy, q, rtol=1e-3)
    assert np.all(fine.pressure >= 0) and np.all(fine.film > 0)
    assert fine.residual < 1e-6 and fine.residual_history[-1] == fine.residual


def test_light_load_rigid_regime_converges():
    """Light, slow contact (M ~ 8, rv221-like elongated geometry): converges, pressure spread
    beyond the Hertz ellipse (p_max well below p_H), load balanced."""
    lub = LubricantProperties(0.13, 2e-8, 0.68, 1.96e8, 870.0, 0.6e-9, 1.7e-9)
    res = solve_point_contact(1.0, 0.05, 0.01389, 0.39, 2.2857e11, lub, grid=33)
    assert res.p_max < 0.6 * res.hertz_pressure
    assert res.load_error < 1e-3 and 1e-8 < res.h_central < 1e-6


@pytest.mark.parametrize(
    "bad,match",
    [
        (dict(load=0.0), "load"),
        (dict(speed=-1.0), "speed"),
        (dict(rx=0.0), "rx"),
        (dict(ry=-0.01), "ry"),
        (dict(grid=100), "grid"),
        (dict(max_grid=17), "max_grid"),
        (dict(max_grid=100), "max_grid"),
        (dict(grid_tol=0.0), "grid_tol"),
        (dict(grid_tol=2.0), "grid_tol"),
    ],
)
def test_bad_input(bad, match):
    args = dict(load=100.0, speed=1.0, rx=0.01, ry=0.01, e_eff=E, lubricant=LUB, grid=33)
    args.update(bad)
    with pytest.raises(InputError, match=match):
        solve_point_contact(**args)


def test_missing_pressure_viscosity_data():
    lub = LubricantProperties(0.05, 0.0, 0.67, 1.96e8, 870.0)
    with pytest.raises(InputError, match="pressure_viscosity"):
        solve_point_contact(100.0, 1.0, 0.01, 0.01, E, lub, grid=33)


def test_non_convergence_is_reported():
    with pytest.raises(ConvergenceError, match="residual reached .* after 1 Newton steps"):
        solve_point_contact(100.0, 1.0, 0.01, 0.01, E, LUB, grid=33, max_iter=1, coarsest=33)


def test_roelands_alpha():
    """alpha* = z (ln eta0 + 9.67)/p0 (Roelands 1966): 0.67 (ln 0.05 + 9.67)/1.96e8 = 2.2815e-8 1/Pa,
    and it is the p -> 0 slope of ln(eta) (central difference, 1e-6)."""
    assert LUB.roelands_alpha == pytest.approx(0.67 * (np.log(0.05) + 9.67) / 1.96e8, rel=1e-12)
    assert LUB.roelands_alpha == pytest.approx(2.2815e-8, rel=1e-4)
    dp = 1e3
    slope = (np.log(LUB.roelands_viscosity_ratio(dp)) - np.log(LUB.roelands_viscosity_ratio(-dp))) / (2 * dp)
    assert slope == pytest.approx(LUB.roelands_alpha, rel=1e-6)
