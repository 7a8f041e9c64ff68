"""Grid convergence of the EHL point-contact solver's central film (flexrv.ehl.solver).

Scheme: second-order upwind wedge term ("second-order upstream", Venner & Lubrecht 2000,
sec. 9.3) and Richardson extrapolation of order 2, h = (4 h_N - h_(N+1)/2)/3, reported at
grids >= 129^2. The order is justified by the observed order of the raw second-order films
p = log2[(h_65 - h_129)/(h_129 - h_257)] (Roache 1998, "Verification and Validation in
Computational Science", ch. 5): measured 1.9-2.0 (circular M = 31, 260; ellipse lambda = 0.25;
rv221 ball), 1.7 for lambda = 0.1 at M = 1300.

Cases span Moes M = 31-1300, L = 6.7-13.6, ry/rx = 1-28 (rv221 main-bearing ball, a/b ~ 9).
Not met: circular M = 640, L = 8.5 (R129 vs R257: 3.9 %; the 65^2 grid closes the film) —
such heavily loaded circular contacts need grid=257.
"""

from functools import lru_cache

import numpy as np
import pytest

from flexrv.ehl.film import hamrock_dowson
from flexrv.ehl.solver import LubricantProperties, solve_point_contact

E = 2.2e11
LUB = LubricantProperties(0.05, 2e-8, 0.67, 1.96e8, 870.0)
LUB_RV = LubricantProperties(0.13, 2e-8, 0.68, 1.96e8, 870.0, 0.6e-9, 1.7e-9)
CASES = {  # load [N], speed [m/s], rx, ry [m], E' [Pa], lubricant
    "circ31": (20.0, 2.0, 0.01, 0.01, E, LUB),
    "circ260": (100.0, 1.0, 0.01, 0.01, E, LUB),
    "ell4": (100.0, 1.0, 0.01, 0.04, E, LUB),
    "ell10": (500.0, 1.0, 0.01, 0.1, E, LUB),
    "rv221": (97.7, 0.0548, 0.01389, 0.39, 2.2857e11, LUB_RV),
}


@lru_cache(maxsize=None)
def solve(case, grid):
    q, u, rx, ry, e, lub = CASES[case]
    return solve_point_contact(q, u, rx, ry, e, lub, grid=grid, wedge_order=2, extrapolate=True)


@pytest.mark.parametrize("case", ["circ31", "ell4", "rv221"])
def test_default_grid_vs_next_coarser(case):
    """Default grid 129^2 against 65^2 (both second order + Richardson): h_c changes < 2 %
    (measured +0.19 %, +1.2 %, +0.66 %); load balance < 1e-3 on both; the extrapolated value
    stays within 8 % of Hamrock-Dowson (1977) (measured +0.7 %, -2.0 %, +6.9 %)."""
    q, u, rx, ry, e, lub = CASES[case]
    coarse, fine = solve(case, 65), solve(case, 129)
    assert abs(fine.h_central / coarse.h_central - 1.0) < 0.02
    assert fine.load_error < 1e-3 and coarse.load_error < 1e-3
    hd, _ = hamrock_dowson(q, u, rx, ry, e, lub.viscosity, lub.pressure_viscosity)
    assert abs(fine.h_central / hd - 1.0) < 0.08


@pytest.mark.slow
@pytest.mark.parametrize("case", ["circ31", "circ260", "ell4", "ell10", "rv221"])
def test_default_grid_vs_next_finer_and_observed_order(case):
    """129^2 against 257^2 (both extrapolated): < 2 % (measured 0.02-1.2 %); the raw
    second-order films converge with observed order p >= 1.6 (measured 1.7-2.0), which is
    what justifies the order-2 Richardson step."""
    mid, fine = solve(case, 129), solve(case, 257)
    assert abs(fine.h_central / mid.h_central - 1.0) < 0.02
    h65, h129, h257 = mid.h_central_coarse, mid.h_central_grid, fine.h_central_grid
    order = np.log2((h129 - h65) / (h257 - h129))
    assert order > 1.6, order
