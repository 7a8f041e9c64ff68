"""Grid convergence of the EHL point-contact solver's central film (flexrv.ehl.solver).

Scheme: second-order upwind wedge term ("second-order upstream", Venner & Lubrecht 2000,
sec. 9.3) and Richardson extrapolation of order 2, h = (4 h_N - h_(N+1)/2)/3, reported at
grids >= 129^2. The order is justified by the observed order of the raw second-order films
p = log2[(h_65 - h_129)/(h_129 - h_257)] (Roache 1998, "Verification and Validation in
Computational Science", ch. 5): measured 1.9-2.0 (circular M = 31, 260; ellipse lambda = 0.25;
rv221 ball), 1.7 for lambda = 0.1 at M = 1300.

Default grid: 129^2, refined by the solver (257^2, 513^2) until the reported h_c changes by
less than ``grid_tol`` = 2 % from the next-coarser grid. Measured (one core):

====================  ======  =====  ===========  ===========  =========
case                  Moes M  grid   change [%]   vs HD [%]    CPU [s]
====================  ======  =====  ===========  ===========  =========
circ31                31      129    0.19         +1.7         0.6
ell4 (ry/rx = 4)      260     129    1.23         -2.0         0.6
rv221 ball (a/b 9)    720     129    0.66         +6.9         0.8
circ260               260     257    0.75         +3.2         2.7
ell10 (ry/rx = 10)    1300    257    0.68         -5.4         6.6
circ640               640     513    0.31         +2.3         12.5
====================  ======  =====  ===========  ===========  =========

Cases span Moes M = 31-1300, L = 6.7-13.6, ry/rx = 1-28. "vs HD" uses the exact Hertz
ellipticity (k = 1 for the circular cases, +1.0 % on the ratio against the earlier fitted
k = 1.0339). "change" is that of h_c; the grid refinement now also requires h_min's change
< 2 % (measured circ31 0.20 %, ell4 1.30 %, rv221 0.37 %, circ260 0.17 %), which did not
change any grid chosen here.
"""

import warnings
from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest
import scipy.sparse as sp

from flexrv.ehl.film import hamrock_dowson, moes_central
from flexrv.ehl.solver import LubricantProperties, _nested_dissection, _PermutedLU, solve_point_contact

E = 2.2e11
LUB = LubricantProperties(0.05, 2e-8, 0.67, 1.96e8, 870.0)
LUB_RV = LubricantProperties(0.13, 2e-8, 0.68, 1.96e8, 870.0, 0.6e-9, 1.7e-9)
CASES = {  # load [N], speed [m/s], rx, ry [m], E' [Pa], lubricant
    "circ31": (20.0, 2.0, 0.01, 0.01, E, LUB),
    "circ260": (100.0, 1.0, 0.01, 0.01, E, LUB),
    "circ640": (246.0, 1.0, 0.01, 0.01, E, LUB),
    "ell4": (100.0, 1.0, 0.01, 0.04, E, LUB),
    "ell10": (500.0, 1.0, 0.01, 0.1, E, LUB),
    "rv221": (97.7, 0.0548, 0.01389, 0.39, 2.2857e11, LUB_RV),
}


@lru_cache(maxsize=None)
def solve(case, grid=129, refine=True):
    q, u, rx, ry, e, lub = CASES[case]
    kw = {} if refine else dict(grid_tol=None)
    return solve_point_contact(q, u, rx, ry, e, lub, grid=grid, wedge_order=2, extrapolate=True, **kw)


@pytest.mark.parametrize(
    "case",
    [
        "circ31",
        "ell4",
        "rv221",
        "circ260",
        pytest.param("ell10", marks=pytest.mark.slow),
        pytest.param("circ640", marks=pytest.mark.slow),
    ],
)
def test_default_solve_is_grid_converged(case):
    """The default solve reports h_c that changes by < 2 % from the next-coarser grid: checked
    against an independent solve on that coarser grid (no refinement), which must also give the
    solver's own grid-change estimate; load balance < 1e-3; h_c within 8 % of Hamrock-Dowson
    (1977) (measured -5.4..+6.9 %, table in the module docstring)."""
    q, u, rx, ry, e, lub = CASES[case]
    fine = solve(case)
    assert fine.grid_converged and fine.grid_change < 0.02
    coarse = solve(case, (fine.grid - 1) // 2 + 1, refine=False)
    change = abs(fine.h_central / coarse.h_central - 1.0)
    assert change < 0.02
    assert change == pytest.approx(fine.grid_change_central, abs=2e-3)
    assert fine.grid_change == max(fine.grid_change_central, fine.grid_change_min)
    assert fine.load_error < 1e-3 and coarse.load_error < 1e-3
    hd, _ = hamrock_dowson(q, u, rx, ry, e, lub.viscosity, lub.pressure_viscosity)
    assert abs(fine.h_central / hd - 1.0) < 0.08


def test_refinement_where_129_is_too_coarse():
    """Circular M = 260: the 65^2 grid is too coarse for its extrapolation (8.6 % change from
    65^2 to 129^2), so the solver refines to 257^2; capped at max_grid = 129 it returns the
    129^2 film, flags it as not grid-converged and warns."""
    assert solve("circ260").grid == 257
    q, u, rx, ry, e, lub = CASES["circ260"]
    with pytest.warns(RuntimeWarning, match="not grid-converged"):
        capped = solve_point_contact(q, u, rx, ry, e, lub, max_grid=129)
    assert capped.grid == 129 and not capped.grid_converged and capped.grid_change > 0.02
    assert capped.h_central == pytest.approx(solve("circ260", 129, refine=False).h_central, rel=1e-3)


def test_symmetric_half_domain_is_exact():
    """The solver keeps only the half Y >= 0 (the problem is symmetric about the entrainment
    axis); solving the full grid instead gives the same solution to the Newton tolerance."""
    q, u, rx, ry, e, lub = CASES["ell4"]
    half = solve_point_contact(q, u, rx, ry, e, lub, grid=65, grid_tol=None)
    full = solve_point_contact(q, u, rx, ry, e, lub, grid=65, grid_tol=None, symmetric=False)
    np.testing.assert_allclose(half.pressure, full.pressure, atol=1e-4 * half.hertz_pressure)
    assert half.h_central == pytest.approx(full.h_central, rel=1e-5)
    np.testing.assert_array_equal(half.pressure, half.pressure[:, ::-1])


@pytest.mark.parametrize("shape", [(129, 65, 5, 2), (33, 17, 3, 2), (9, 5, 5, 2)])
def test_nested_dissection_lu(shape):
    """The nested-dissection order is a permutation of all nodes, and the LU assembled in that
    order solves the original system (a random non-symmetric matrix with the grid stencil
    +-(wx - 1) x +-(wy - 1); vs scipy's spsolve, 1e-10)."""
    ni, nj, wx, wy = shape
    perm = _nested_dissection(ni, nj, wx, wy)
    np.testing.assert_array_equal(np.sort(perm), np.arange(ni * nj))
    rng = np.random.default_rng(0)
    n = ni * nj
    ii, jj = np.meshgrid(np.arange(ni), np.arange(nj), indexing="ij")
    rows, cols = [], []
    for di in range(-wx + 1, wx):
        for dj in range(-wy + 1, wy):
            ok = (ii + di >= 0) & (ii + di < ni) & (jj + dj >= 0) & (jj + dj < nj)
            rows.append((ii * nj + jj)[ok])
            cols.append(((ii + di) * nj + jj + dj)[ok])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    A = (
        sp.csc_matrix((rng.standard_normal(rows.size), (rows, cols)), shape=(n, n)) + sp.eye(n) * 4.0 * wx * wy
    ).tocsc()
    pos = np.empty_like(perm)
    pos[perm] = np.arange(n)
    coo = A.tocoo()
    Ap = sp.csc_matrix((coo.data, (pos[coo.row], pos[coo.col])), shape=A.shape)
    b = rng.standard_normal(n)
    x = _PermutedLU(Ap, perm).solve(b)
    np.testing.assert_allclose(x, sp.linalg.spsolve(A, b), rtol=1e-10, atol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["circ31", "circ260", "ell4", "ell10", "rv221"])
def test_observed_order_of_the_raw_films(case):
    """The raw second-order films on 65/129/257 converge with observed order p >= 1.6
    (measured 1.7-2.0), which is what justifies the order-2 Richardson step; 129^2 against
    257^2 (both extrapolated, no refinement) differ by < 2 % (measured 0.02-1.2 %)."""
    mid, fine = solve(case, 129, refine=False), solve(case, 257, refine=False)
    assert abs(fine.h_central / mid.h_central - 1.0) < 0.02
    h65, h129, h257 = mid.h_central_coarse, mid.h_central_grid, fine.h_central_grid
    order = np.log2((h129 - h65) / (h257 - h129))
    assert order > 1.6, order


def test_no_warning_without_refinement():
    """An explicit coarse grid (first order, no refinement asked for) reports its grid change
    but does not warn."""
    q, u, rx, ry, e, lub = CASES["circ31"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = solve_point_contact(q, u, rx, ry, e, lub, grid=33)
    assert res.grid == 33 and np.isfinite(res.grid_change)


@pytest.mark.parametrize("case,measured", [("circ31", 0.001), ("ell4", -0.043), ("rv221", -0.053)])
def test_incompressible_film_vs_nvm_with_roelands_alpha(case, measured):
    """Nijenbanning, Venner & Moes (1994) define L with the Roelands alpha
    z (ln eta0 + 9.67)/p0 and fit (as this check shows) incompressible solutions: the solver
    run incompressible (Dowson-Higginson a = 0) is within 8 % of NVM evaluated with that alpha
    (measured +0.1 %, -4.3 %, -5.3 %; circular M = 260: -0.6 %), and compressibility lowers h_c
    by 10-20 % (measured 14-18 %)."""
    q, u, rx, ry, e, lub = CASES[case]
    incompressible = solve_point_contact(q, u, rx, ry, e, replace(lub, dh_a=0.0))
    nvm = moes_central(q, u, rx, ry, e, lub.viscosity, lub.roelands_alpha)
    assert incompressible.h_central / nvm - 1.0 == pytest.approx(measured, abs=0.01)
    assert abs(incompressible.h_central / nvm - 1.0) < 0.08
    drop = 1.0 - solve(case).h_central / incompressible.h_central
    assert 0.10 < drop < 0.20


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [1.0, 4.0, 20.0])
@pytest.mark.parametrize("moes_l", [5.0, 10.0, 20.0])
@pytest.mark.parametrize("moes_m", [10.0, 50.0, 200.0, 1000.0])
def test_robust_over_the_ehl_map(moes_m, moes_l, ratio):
    """Robustness sweep, M = 10-1000, L = 5-20, ry/rx = 1-20 (36 cases; speed and load chosen
    from L = G (2U)^(1/4), M = W (2U)^(-3/4)): the default solve converges and h_c meets the 2 %
    grid tolerance everywhere (measured 0.0-1.7 %, stopping at 129^2 to 513^2, 0.2-19 s); h_min
    meets it everywhere except at M = 1000, L = 10, circular (6.5 % at 513^2, flagged);
    h_c within 12 % of Hamrock-Dowson for M >= 50 (measured 0.90-1.10; at M = 10 it
    reads 0.76-0.98, outside the formula's piezoviscous-elastic range)."""
    lub, e, rx = LUB, E, 0.01
    two_u = (moes_l / (lub.pressure_viscosity * e)) ** 4
    u = two_u / 2.0 * e * rx / lub.viscosity
    q = moes_m * two_u**0.75 * e * rx**2
    if (moes_m, moes_l, ratio) == (1000.0, 10.0, 1.0):
        # the one case where h_min is not grid-converged at 513^2: it changes by 6.5 % from the
        # 257^2 value (narrow side lobes of a heavily loaded circular contact), h_c by 0.9 %;
        # reported as not converged, with a warning naming both changes
        with pytest.warns(RuntimeWarning, match="h_min by 6"):
            res = solve_point_contact(q, u, rx, ratio * rx, e, lub)
        assert not res.grid_converged and res.grid == 513
        assert res.grid_change_central < 0.02 and 0.04 < res.grid_change_min < 0.09
    else:
        res = solve_point_contact(q, u, rx, ratio * rx, e, lub)
        assert res.grid_converged and res.grid_change < 0.02
    assert res.load_error < 1e-3
    if moes_m >= 50:
        hd, _ = hamrock_dowson(q, u, rx, ratio * rx, e, lub.viscosity, lub.pressure_viscosity)
        assert abs(res.h_central / hd - 1.0) < 0.12


@pytest.mark.parametrize("case", ["circ31", "rv221"])
def test_h_min_at_the_accuracy_of_h_c(case):
    """Issue 17 (1): the default solve's h_min is extrapolated like h_c (sub-grid minimum of
    each level, order-2 Richardson) and takes part in the grid refinement. Checked against the
    solver's own finer-grid value (257^2, extrapolated, no refinement): within 0.5 % (measured
    circ31 +0.13 %, rv221 ball +0.05 % against 513^2). The previous default (the finest grid's
    raw node minimum, kept as ``h_min_grid``) is 0.9-3.7 % low against 513^2; it must stay
    further from the reference than 0.8 % here, so this test fails if h_min reverts to it."""
    fine = solve(case, 257, refine=False)
    default = solve(case)
    assert default.grid == 129  # both cases stop at 129^2
    assert abs(default.h_min / fine.h_min - 1.0) < 0.005
    assert default.h_min_grid / fine.h_min - 1.0 < -0.008
    # the reported value is the extrapolation of the two finest levels, and it is what converged
    assert default.grid_change == max(default.grid_change_central, default.grid_change_min)
    assert default.grid_change_min < 0.02
    assert default.h_min < default.h_central


@pytest.mark.slow
@pytest.mark.parametrize(
    "case,measured", [("circ31", 0.0013), ("ell4", -0.0025), ("rv221", 0.0005), ("circ260", -0.0008)]
)
def test_h_min_vs_513(case, measured):
    """The default h_min against the solver's 513^2 extrapolation: within 0.5 % (measured
    +0.13, -0.25, +0.05, -0.08 %); the old raw node minimum read -0.94, -3.71, -2.30, -2.82 %."""
    ref = solve(case, 513, refine=False)
    default = solve(case)
    assert default.h_min / ref.h_min - 1.0 == pytest.approx(measured, abs=0.002)
    assert default.h_min_grid / ref.h_min - 1.0 < -0.008
