"""Steady isothermal EHL of an elliptical point contact (numerical solution).

Model (:cite:`hamrock1994`, ch. 22; :cite:`venner2000`, ch. 9; :cite:`seed000,seed001`):

* Reynolds:  d/dx(rho h^3/(12 eta) dp/dx) + d/dy(rho h^3/(12 eta) dp/dy) = u d(rho h)/dx,
  u = mean entrainment speed (u1 + u2)/2, cavitation by p >= 0 (Reynolds
  condition, written as the complementarity problem p >= 0, R(p) <= 0, p R = 0);
* Roelands viscosity :cite:`roelands1966` eta = eta0 exp{(ln eta0 + 9.67)[(1 + p/p0)^z - 1]};
* Dowson–Higginson density :cite:`dowson1966` rho = rho0 (1 + a p / (1 + b p));
* film h = h0 + x^2/(2 rx) + y^2/(2 ry) + (2/(pi E')) iint p / r  (Boussinesq);
* load balance iint p dx dy = Q, closed by the rigid approach h0.

Dimensionless form (Hertzian scaling of the ellipse): X = x/b, Y = y/a (b the
Hertz semi-axis along x, a along y), P = p/p_H, H = h rx/b^2,
rho_ = rho/rho0, eta_ = eta/eta0:

    d/dX(eps dP/dX) + (b/a)^2 d/dY(eps dP/dY) - d(rho_ H)/dX = 0,
    eps = rho_ H^3 / (eta_ lambda),  lambda = 12 eta0 u rx^2 / (b^3 p_H),
    iint P dX dY = 2 pi / 3.

Discretisation: node-centred finite differences on a uniform grid, second-order
central Poiseuille terms; wedge term d(rho H)/dX by second-order upwind
("second-order upstream", 1.5 f_i - 2 f_(i-1) + 0.5 f_(i-2); :cite:`venner2000`,
sec. 9.3) on grids >= 129^2, first-order upwind below (``wedge_order``); the elastic
deformation uses exact influence coefficients of piecewise-constant pressure on
each (dx x dy) cell (Love's rectangle solution, :cite:`love1929`) and is evaluated by a zero-padded
(linear, non-periodic) FFT convolution, O(N log N).

Reported central film (grids >= 129^2): Richardson extrapolation of order 2 from the
finest grid and the next-coarser one of the grid continuation,
h_c = (4 h_N - h_(N+1)/2) / 3, justified by the observed order 1.7-2.0 of the raw
second-order films on 65/129/257 (tests/test_ehl_convergence.py). Why not the
first-order scheme: its h_c drifts by ~2.2 % per grid doubling all the way to 513^2
(circular M = 260: 296.6, 303.9, 297.2, 290.8 nm at 65..513^2 against the limit
~282 nm), so small grid-to-grid changes did not mean a converged film.

Reported minimum film: h_min is treated like h_c. On each grid level the smallest node film
is refined below the grid spacing (vertex of the parabola through the minimum node and its
neighbours, :func:`_subgrid_min`), and the reported h_min is the same order-2 Richardson
extrapolation of the two finest levels. Measured against the solver's own 513^2 extrapolation
(tests/test_ehl_convergence.py): the reported h_min is within 0.25 % (circ31 +0.13 %, ell4
-0.25 %, rv221 ball +0.05 %, circ260 -0.08 %); the earlier default (the raw node minimum of the
finest grid) read 0.9-3.7 % low (-0.94, -3.71, -2.30, -2.82 %). Limit: in heavily loaded
circular contacts the minimum sits in narrow side lobes; at M = 1000, L = 10 the reported h_min
still changes by 6.5 % from 257^2 to 513^2 (h_c by 0.9 %), and the result is returned with
``grid_converged = False`` and a warning (before, only h_c was checked and it passed).

Adaptive grid (default): the solve starts at 129^2 and adds grid levels (257^2, 513^2 =
``max_grid``) until the reported h_c *and* h_min change by less than ``grid_tol`` = 2 % from the
values the next-coarser grid reports (its own extrapolation from the two grids below). Where
65^2 is too coarse for its extrapolation (heavily loaded circular contacts, M >= ~260, and
ellipticity 10 at M = 1300: 7-9 % change 65 -> 129), the solver goes on to 257^2 (0.7 %) or
513^2 (circular M = 640: 3.9 % at 257^2, 0.3 % at 513^2). A film still outside the tolerance
at ``max_grid`` is returned with ``grid_converged = False`` and a RuntimeWarning. Why not
a shorter inlet for a finer grid at the same cost: the film is starved by 0.5-0.7 % at
x_inlet = -3.5 b and by 2-4 % at -2.5 b (257^2, M = 31-1300), as large as the grid error.

Solver (the choice and why): an inexact *semismooth Newton–Krylov* method on the
coupled unknowns (P, H0):

* the cavitation condition is the semismooth equation min(P, -c R(P)) = 0 with the
  local scaling c_i = 1/|dR_i/dP_i| (primal-dual active set), so the free boundary
  is found by the Newton active set, not by clipping (the iterate is projected on
  P >= 0 in a backtracking line search);
* the Jacobian–vector products are exact up to a forward difference of the full
  residual (one FFT each), so the dense elastic coupling is fully Newton;
* GMRES is preconditioned with a sparse LU of an approximate Jacobian in which the
  elastic kernel is truncated to a small neighbourhood (+-s cells in y, more in x
  for elongated contacts whose cells are long in y; the wedge term
  differentiates the kernel along x, which is what makes the truncation a good
  approximation in the high-pressure zone where the Poiseuille term vanishes);
  the H0 column and the load row are added by a Schur complement (two LU solves);
  the LU is reused while GMRES needs few iterations and the active set is unchanged;
  it is factorised in single precision in a geometric nested-dissection order
  (:cite:`george1973`) with separators as wide as the stencil (2.4x faster than COLAMD);
* symmetry: rolling along x with no spin makes the problem symmetric about Y = 0; the
  unknowns are the half Y >= 0 (the residual is evaluated on the full grid from the
  mirror image, the preconditioner's columns of mirrored nodes are folded), which halves
  the LU and Krylov work; the full-grid solve agrees to the Newton tolerance (tested);
* the solution is computed on a sequence of grids 17^2 -> 33^2 -> ... -> N^2 (grid
  continuation): the coarse grids do the many nonlinear steps cheaply, the fine grid
  typically needs 3-5 Newton steps.

This replaces the classic Jacobi/Gauss–Seidel line relaxation (thousands of
sweeps at high loads without multigrid) with a handful of vectorised steps; no
Python loop runs over grid nodes.

Measured (tests/test_ehl_convergence.py, benchmarks/bench_ehl.py, one core): the default
solve's h_c changes by 0.2-1.3 % from the next-coarser grid for M = 31-1300, L = 6.7-13.6,
ry/rx = 1-28 (stopping at 129^2 for the rv221 ball and moderately loaded contacts, at
257^2/513^2 for the heavily loaded circular ones), and a sweep over M = 10-1000,
L = 5-20, ry/rx = 1-20 converges everywhere within the 2 % grid tolerance in h_c (and in
h_min except at M = 1000, L = 10, circular, see above); h_c within -5.4 %..+6.9 % of
Hamrock–Dowson (with the Barus alpha in G). Nijenbanning–Venner–Moes define L with the
Roelands alpha (``LubricantProperties.roelands_alpha``), and their fit behaves as one to
incompressible solutions: the solver run incompressible (dh_a = 0) against NVM with that
alpha gives -5.3 %..+0.1 % (M = 31-720, tests/test_ehl_solver.py); Dowson–Higginson
compressibility lowers h_c by 14-18 %, which is why the compressible default reads
-15 %..-1 % against NVM with the Barus alpha. Load balance to ~1e-11.
CPU, converged 129^2: 0.5 s circular M = 260, 0.6 s rv221 ball (a/b ~ 9); 257^2: 2.1-2.3 s;
the default adaptive solve 0.6 s (rv221 ball) to 12 s (circular M = 640, 513^2).

Limits: isothermal, Newtonian, smooth surfaces, steady rolling, fully flooded
inlet at X = x_inlet. At high loads (M above ~1000 on 65^2 and a few thousand on
129^2) the grid no longer resolves the thin film against the
elastic deflection and the discrete solution closes the film (h < 0 at the edge
of the contact): this is reported as ConvergenceError, use a finer grid or the
closed-form films there. Very light loads (isoviscous-rigid regime) converge but
the pressure extends beyond the Hertz ellipse and a longer inlet (``x_inlet``)
may be needed. EHL films are 0.01-1 um; they are unrelated to the seeds'
"film thickness 0.01-0.18 mm".
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import scipy.fft as sfft
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexrv.contact.hertz import point_contact
from flexrv.ehl.film import hamrock_dowson
from flexrv.errors import ConvergenceError, InputError


# ----------------------------------------------------------------- lubricant
@dataclass(frozen=True)
class LubricantProperties:
    """Isothermal lubricant in SI units.

    Attributes
    ----------
    viscosity : eta0 [Pa s]; pressure_viscosity : Barus alpha [1/Pa] (Hamrock–Dowson);
    roelands_z : [-]; roelands_p0 : [Pa] (1.96e8 Pa classically);
    density : rho0 [kg/m^3]; dh_a, dh_b : Dowson–Higginson a, b [1/Pa].
    """

    viscosity: float
    pressure_viscosity: float
    roelands_z: float
    roelands_p0: float
    density: float
    dh_a: float = 0.6e-9
    dh_b: float = 1.7e-9

    @classmethod
    def from_design(cls, lub) -> "LubricantProperties":
        """From a :class:`flexrv.design.model.Lubricant`."""
        return cls(
            viscosity=lub.viscosity_Pa_s,
            pressure_viscosity=lub.pressure_viscosity_1_per_GPa * 1e-9,
            roelands_z=lub.roelands_z,
            roelands_p0=lub.roelands_p0_Pa,
            density=lub.density_kg_m3,
            dh_a=lub.dowson_higginson_a_1_per_GPa * 1e-9,
            dh_b=lub.dowson_higginson_b_1_per_GPa * 1e-9,
        )

    def check(self) -> None:
        """Raise InputError for missing/invalid data."""
        for name in ("viscosity", "pressure_viscosity", "roelands_z", "roelands_p0", "density"):
            value = getattr(self, name)
            if value is None or not np.isfinite(value) or value <= 0:
                raise InputError(
                    f"lubricant.{name} must be finite and > 0 (pressure-viscosity data is required "
                    f"for EHL), got {value!r}"
                )
        for name in ("dh_a", "dh_b"):
            value = getattr(self, name)
            if value is None or not np.isfinite(value) or value < 0:
                raise InputError(f"lubricant.{name} must be finite and >= 0 1/Pa, got {value!r}")

    @property
    def roelands_alpha(self) -> float:
        """Pressure-viscosity coefficient of the Roelands law at p -> 0 [1/Pa]:
        d ln(eta)/dp = z (ln eta0 + 9.67)/p0 (:cite:`roelands1966`; the alpha with which
        :cite:`venner2000` and :cite:`nijenbanning1994` define L). It differs from the Barus
        ``pressure_viscosity`` when the two are estimated separately (rv221/rv40e oil:
        26.5/GPa against 20/GPa)."""
        return self.roelands_z * (math.log(self.viscosity) + 9.67) / self.roelands_p0

    def roelands_viscosity_ratio(self, p):
        """eta/eta0 = exp{(ln eta0 + 9.67)[(1 + p/p0)^z - 1]} (:cite:`roelands1966`), p [Pa] >= 0.

        Overflows to inf at extreme pressures, which the solver reads as eps = 0 (no
        pressure flow), the correct limit."""
        with np.errstate(over="ignore"):
            return np.exp((math.log(self.viscosity) + 9.67) * ((1.0 + p / self.roelands_p0) ** self.roelands_z - 1.0))

    def density_ratio(self, p):
        """rho/rho0 = 1 + a p/(1 + b p) (:cite:`dowson1966`)."""
        return 1.0 + self.dh_a * p / (1.0 + self.dh_b * p)

    def density_ratio_derivative(self, p):
        """d(rho/rho0)/dp [1/Pa]."""
        return self.dh_a / (1.0 + self.dh_b * p) ** 2


# ----------------------------------------------------------------- results
@dataclass(frozen=True)
class EHLResult:
    """Solution of :func:`solve_point_contact` (SI units).

    Attributes
    ----------
    x, y : node coordinates [m] (x along entrainment, y transverse), 1-D.
    pressure : p[i, j] at (x[i], y[j]) [Pa].
    film : h[i, j] [m].
    h_central : film at the Hertz centre (x = y = 0) [m].
    h_min : minimum film [m], at the accuracy of ``h_central``: the sub-grid minimum of each
        level, Richardson-extrapolated like h_c when ``extrapolated`` (module docstring).
    h_min_grid : smallest node film of the finest grid [m] (the value reported as h_min before
        h_min was extrapolated; 0.9-3.7 % low at the default grids).
    p_max : maximum pressure [Pa].
    hertz_pressure : p_H [Pa]; hertz_a, hertz_b : semi-axes [m] along y and x.
    rigid_approach : h0 [m] (negative when the bodies overlap elastically).
    iterations : Newton steps on the finest grid; total_iterations : on all grids.
    residual : final scaled RMS residual of the Reynolds/complementarity equations.
    residual_history : residual after each Newton step on the finest grid.
    load_error : |iint p - Q| / Q.
    grid : nodes per direction of the grid used (may exceed the requested one, see ``grid_tol``).
    h_central_grid : central film of the finest-grid solution itself [m].
    h_central_coarse : central film of the next-coarser level (N+1)/2 of the continuation [m]
        (nan when there is none).
    extrapolated : True when ``h_central`` is the Richardson extrapolation
        (4 h_N - h_(N+1)/2)/3 of the second-order scheme (see :func:`solve_point_contact`).
    wedge_order : order of the wedge-term discretisation used (1 or 2).
    grid_requested : the ``grid`` argument (the first grid of the adaptive refinement).
    grid_change : max of ``grid_change_central`` and ``grid_change_min`` (nan when the
        continuation has no coarser level to compare with).
    grid_change_central, grid_change_min : |h(grid) / h(next-coarser grid) - 1| of h_c and of
        h_min, both as reported.
    grid_converged : ``grid_change`` <= ``grid_tol`` (True when no tolerance was set).
    """

    x: np.ndarray
    y: np.ndarray
    pressure: np.ndarray
    film: np.ndarray
    h_central: float
    h_min: float
    p_max: float
    hertz_pressure: float
    hertz_a: float
    hertz_b: float
    rigid_approach: float
    iterations: int
    total_iterations: int
    residual: float
    residual_history: list = field(default_factory=list)
    load_error: float = 0.0
    grid: int = 0
    h_central_grid: float = float("nan")
    h_central_coarse: float = float("nan")
    extrapolated: bool = False
    wedge_order: int = 1
    grid_requested: int = 0
    grid_change: float = float("nan")
    grid_converged: bool = True
    h_min_grid: float = float("nan")
    grid_change_central: float = float("nan")
    grid_change_min: float = float("nan")


# ----------------------------------------------------------------- elasticity
def _rect_integral(u, v):
    """Antiderivative F(u, v) of 1/sqrt(u^2+v^2) over u and v (u, v != 0), up to
    terms in u alone or v alone (they cancel in the four-corner sum):
    u ln(v + r) + v ln(u + r) = u asinh(v/|u|) + v asinh(u/|v|) + u ln|u| + v ln|v|."""
    return u * np.arcsinh(v / np.abs(u)) + v * np.arcsinh(u / np.abs(v))


def influence_kernel(nx: int, ny: int, dx: float, dy: float):
    """Boussinesq influence coefficients D[k, l] [m/Pa]: surface deflection (sum of
    both bodies, E' = 1 Pa) at offset (k dx, l dy) from a cell of uniform unit pressure
    of size dx x dy, k in [-(nx-1), nx-1], l in [-(ny-1), ny-1].

    w = (2/(pi E')) iint p/r ds dt (:cite:`johnson1985`, eq. 3.96 with E' = 2E*),
    rectangle integral of Love :cite:`love1929`: sum over the four corners of
    u asinh(v/|u|) + v asinh(u/|v|).
    """
    k = np.arange(-(nx - 1), nx)[:, None] * dx
    l = np.arange(-(ny - 1), ny)[None, :] * dy
    hx, hy = 0.5 * dx, 0.5 * dy
    val = (
        _rect_integral(k + hx, l + hy)
        - _rect_integral(k + hx, l - hy)
        - _rect_integral(k - hx, l + hy)
        + _rect_integral(k - hx, l - hy)
    )
    return 2.0 / np.pi * val


class _Elastic:
    """Linear (zero-padded) FFT convolution with a precomputed kernel."""

    def __init__(self, kernel: np.ndarray, nx: int, ny: int):
        self.nx, self.ny = nx, ny
        self.sx = sfft.next_fast_len(2 * nx - 1, real=True)
        self.sy = sfft.next_fast_len(2 * ny - 1, real=True)
        circ = np.zeros((self.sx, self.sy))
        # kernel offset (k, l) stored at index (k mod sx, l mod sy): circulant embedding
        ks = np.arange(-(nx - 1), nx) % self.sx
        ls = np.arange(-(ny - 1), ny) % self.sy
        circ[np.ix_(ks, ls)] = kernel
        self.khat = sfft.rfft2(circ)

    def __call__(self, p: np.ndarray) -> np.ndarray:
        out = sfft.irfft2(sfft.rfft2(p, s=(self.sx, self.sy)) * self.khat, s=(self.sx, self.sy))
        return out[: self.nx, : self.ny]


# ----------------------------------------------------------------- one grid
class _GridProblem:
    """Dimensionless discrete problem on one grid (see module docstring)."""

    def __init__(
        self,
        n,
        x_in,
        x_out,
        y_half,
        aspect,
        ky,
        lam,
        kernel_scale,
        pscale,
        lub: LubricantProperties,
        stencil: int,
        wedge_order: int = 2,
        symmetric: bool = True,
    ):
        self.wedge_order = wedge_order
        self.n = n
        self.X = np.linspace(x_in, x_out, n)
        self.Y = np.linspace(-y_half, y_half, n)
        self.dX = self.X[1] - self.X[0]
        self.dY = self.Y[1] - self.Y[0]
        self.ry2 = aspect**2  # (b/a)^2 factor of the Y Poiseuille term
        self.lam = lam
        self.pscale = pscale  # p_H [Pa]
        self.lub = lub
        # rigid gap X^2/2 + (a^2 rx/(b^2 ry)) Y^2/2
        self.gap = 0.5 * self.X[:, None] ** 2 + 0.5 * ky * self.Y[None, :] ** 2
        self.kernel = kernel_scale(n, self.dX, self.dY)  # dimensionless K[k, l], H = ... + K * P
        self.elastic = _Elastic(self.kernel, n, n)
        self.stencil = stencil
        # cells are (b dX) x (a dY): for elongated contacts (a/b > 1) the kernel couples
        # more cells along x, so the preconditioner keeps more of them in x; on grids
        # above 129^2 the extra LU fill costs more than the saved Krylov steps (measured:
        # rv221 ball 129^2 1.5 s vs 1.9 s, 257^2 10.8 s vs 5.4 s), so only up to 129^2
        widen = int(np.clip(np.rint(np.sqrt(self.dY / (aspect * self.dX))), 1, 3)) if n <= 129 else 1
        self.stencil_x = stencil * widen
        self.load_target = 2.0 * np.pi / 3.0
        self.interior = np.zeros((n, n), dtype=bool)
        self.interior[1:-1, 1:-1] = True
        self.refactor_after = 15
        self.refactor_changes = max(4, n // 8)
        self.krylov_rtol = 3e-3
        self.krylov_max = 60
        # single-precision LU of the preconditioner (GMRES works on the true float64 residual, so
        # only the preconditioner quality is affected): -10-25 % CPU at 129^2
        self.lu_dtype = np.float32
        self.trace = False
        # symmetry about Y = 0 (module docstring): unknowns P[i, j] for j >= jc only
        self.symmetric = symmetric
        self.jc = n // 2
        self.mirror = np.abs(np.arange(n) - self.jc) if symmetric else np.arange(n)
        self.m = n - self.jc if symmetric else n
        self.j0 = self.jc if symmetric else 0
        # multiplicity of each unknown in the full grid (load balance): 2 off the centre line
        self.mult = np.ones((n, self.m))
        if symmetric:
            self.mult[:, 1:] = 2.0
        # fill-reducing order of the unknowns for the preconditioner's LU: geometric nested
        # dissection with separators as wide as the stencil's reach (x: kernel +-stencil_x and
        # the upwind wedge's 1-2 nodes back; y: +-stencil); measured rv221 ball 129^2:
        # factorisation 0.045 s vs 0.108 s with COLAMD, 22 % less fill
        self.perm = _nested_dissection(n, self.m, self.stencil_x + 2, stencil + 1)
        self.pos = np.empty_like(self.perm)
        self.pos[self.perm] = np.arange(self.perm.size)

    # -- physics ----------------------------------------------------------
    def film(self, P, H0):
        return H0 + self.gap + self.elastic(P)

    def fields(self, P, H0):
        H = self.film(P, H0)
        p = np.maximum(P, 0.0) * self.pscale
        rho = self.lub.density_ratio(p)
        eta = self.lub.roelands_viscosity_ratio(p)
        Hp = np.maximum(H, 1e-12)  # the film can never close in a converged state; guard transients
        eps = rho * Hp**3 / (eta * self.lam)
        return H, rho, eps

    def reynolds(self, P, H0):
        """Scaled Reynolds residual dX^2 R on the full grid (boundary rows = 0)."""
        H, rho, eps = self.fields(P, H0)
        R = np.zeros_like(P)
        ex = 0.5 * (eps[1:, :] + eps[:-1, :])
        ey = 0.5 * (eps[:, 1:] + eps[:, :-1])
        fx = ex * (P[1:, :] - P[:-1, :])  # flux at i+1/2
        fy = ey * (P[:, 1:] - P[:, :-1])
        rh = rho * H
        wedge = np.empty((self.n - 2, self.n - 2))
        wedge[0] = rh[1, 1:-1] - rh[0, 1:-1]
        if self.wedge_order == 2:  # second-order upwind 1.5 f_i - 2 f_{i-1} + 0.5 f_{i-2}
            wedge[1:] = 1.5 * rh[2:-1, 1:-1] - 2.0 * rh[1:-2, 1:-1] + 0.5 * rh[:-3, 1:-1]
        else:
            wedge[1:] = rh[2:-1, 1:-1] - rh[1:-2, 1:-1]
        r = (
            (fx[1:, 1:-1] - fx[:-1, 1:-1])
            + self.ry2 * (self.dX / self.dY) ** 2 * (fy[1:-1, 1:] - fy[1:-1, :-1])
            - self.dX * wedge
        )
        R[1:-1, 1:-1] = r
        # |dR_i/dP_i| (Poiseuille + wedge) for the scaling of the active-set test
        diag = np.ones_like(P)
        diag[1:-1, 1:-1] = (
            ex[1:, 1:-1]
            + ex[:-1, 1:-1]
            + self.ry2 * (self.dX / self.dY) ** 2 * (ey[1:-1, 1:] + ey[1:-1, :-1])
            + self.dX * rho[1:-1, 1:-1] * self.kernel[self.n - 1, self.n - 1] * (1.5 if self.wedge_order == 2 else 1.0)
        )
        self._diag = diag
        return R, H, rho, eps

    def free_mask(self, P, R):
        """Nodes where the Reynolds equation holds: the semismooth active set of
        min(P, -c R) = 0 with the local scaling c_i = 1/|dR_i/dP_i| (primal-dual
        active-set rule: free where the Jacobi-predicted pressure P - R/(dR/dP) > 0).
        Must follow a call of :meth:`reynolds` at the same state."""
        return self.interior & (P + R / self._diag > 0.0)

    def expand(self, Pu):
        """Full-grid field from the unknowns (n x m): mirror image about Y = 0."""
        return Pu[:, self.mirror] if self.symmetric else Pu

    def restrict(self, F):
        """Unknowns' part (n x m) of a full-grid field."""
        return F[:, self.j0 :]

    def equations(self, z, free, R=None):
        """Semismooth system on the unknowns z = (P[:, j0:], H0): Reynolds rows on free
        nodes, P = 0 elsewhere, plus the load balance (relative); ``R`` (full grid) may be
        passed if already evaluated at ``z``."""
        Pu = z[:-1].reshape(self.n, self.m)
        P = self.expand(Pu)
        if R is None:
            R = self.reynolds(P, z[-1])[0]
        F = self.restrict(np.where(free, R, P))
        g = (self.dX * self.dY * P.sum() - self.load_target) / self.load_target
        return np.concatenate([F.ravel(), [g]])

    def load_error(self, P):
        return abs(self.dX * self.dY * P.sum() - self.load_target) / self.load_target

    # -- preconditioner ---------------------------------------------------
    def precond_matrix(self, P, H0, free):
        """Sparse approximate Jacobian (truncated elastic kernel) with respect to the
        unknowns: rows of free nodes, identity rows elsewhere; plus the approximate H0
        column. ``P``, ``free``: full grid. With symmetry, rows are those of the unknowns
        (j >= jc) and the column of a mirrored node (i, j < jc) is added to (i, 2 jc - j)."""
        n, s, sx = self.n, self.stencil, self.stencil_x
        H, rho, eps = self.fields(P, H0)
        drho = self.lub.density_ratio_derivative(np.maximum(P, 0.0) * self.pscale) * self.pscale
        idx = np.arange(n)[:, None] * self.m + self.mirror[None, :]  # full node -> unknown
        free = free.copy()
        free[:, : self.j0] = False
        fi, fj = np.nonzero(free)
        rows_list, cols_list, vals_list = [], [], []
        kc = n - 1  # centre index of the kernel array
        dx = self.dX
        # wedge term, first-order upwind whatever the residual's order (sparser LU, same Newton
        # steps; measured rv221 ball 129^2: 2.4 s vs 2.85 s with the second-order stencil):
        # -dX (rho_i H_i - rho_(i-1) H_(i-1)); dH_i/dP_(i+k) = K[k]
        coef = (1.0, -1.0)
        back = (fi, fi - 1)  # free nodes are interior: fi >= 1
        for di in range(-sx - 1, sx + 1):
            for dj in range(-s, s + 1):
                val = np.zeros(fi.shape)
                for m in range(2):
                    if abs(di + m) <= sx:
                        val = val - dx * coef[m] * rho[back[m], fj] * self.kernel[kc + di + m, kc + dj]
                ti, tj = fi + di, fj + dj
                ok = (ti >= 0) & (ti < n) & (tj >= 0) & (tj < n) & (val != 0.0)
                rows_list.append(idx[fi[ok], fj[ok]])
                cols_list.append(idx[ti[ok], tj[ok]])
                vals_list.append(val[ok])
        # density derivative part of the wedge term
        for m in range(2):
            rows_list.append(idx[fi, fj])
            cols_list.append(idx[back[m], fj])
            vals_list.append(-dx * coef[m] * H[back[m], fj] * drho[back[m], fj])
        # Poiseuille 5-point stencil with frozen eps
        ex_p = 0.5 * (eps[fi, fj] + eps[fi + 1, fj])
        ex_m = 0.5 * (eps[fi, fj] + eps[fi - 1, fj])
        cy = self.ry2 * (self.dX / self.dY) ** 2
        ey_p = cy * 0.5 * (eps[fi, fj] + eps[fi, fj + 1])
        ey_m = cy * 0.5 * (eps[fi, fj] + eps[fi, fj - 1])
        rows_list += [idx[fi, fj]] * 5
        cols_list += [idx[fi, fj], idx[fi + 1, fj], idx[fi - 1, fj], idx[fi, fj + 1], idx[fi, fj - 1]]
        vals_list += [-(ex_p + ex_m + ey_p + ey_m), ex_p, ex_m, ey_p, ey_m]
        # identity rows for cavitated / boundary nodes
        ci, cj = np.nonzero(~free[:, self.j0 :])
        cj = cj + self.j0
        rows_list.append(idx[ci, cj])
        cols_list.append(idx[ci, cj])
        vals_list.append(np.ones(ci.shape))
        nu = n * self.m
        rows, cols = self.pos[np.concatenate(rows_list)], self.pos[np.concatenate(cols_list)]  # dissection order
        A = sp.csc_matrix((np.concatenate(vals_list), (rows, cols)), shape=(nu, nu))
        # H0 column: wedge term (vanishes for an incompressible film, where d(rho H)/dX does not
        # see a uniform shift) plus the Poiseuille term through d eps/dH = 3 eps/H
        col = np.zeros((n, n))
        col[fi, fj] = -dx * (rho[fi, fj] - rho[fi - 1, fj])
        deps = 3.0 * eps / np.maximum(H, 1e-12)
        dex_p = 0.5 * (deps[fi, fj] + deps[fi + 1, fj])
        dex_m = 0.5 * (deps[fi, fj] + deps[fi - 1, fj])
        dey_p = cy * 0.5 * (deps[fi, fj] + deps[fi, fj + 1])
        dey_m = cy * 0.5 * (deps[fi, fj] + deps[fi, fj - 1])
        col[fi, fj] += (
            dex_p * (P[fi + 1, fj] - P[fi, fj])
            - dex_m * (P[fi, fj] - P[fi - 1, fj])
            + dey_p * (P[fi, fj + 1] - P[fi, fj])
            - dey_m * (P[fi, fj] - P[fi, fj - 1])
        )
        return A, self.restrict(col).ravel()

    # -- Newton -----------------------------------------------------------
    def newton(self, P, H0, tol, max_iter, history):
        """Semismooth Newton–Krylov iteration (module docstring); returns (P, H0, steps, residual)."""
        n = self.n
        z = np.concatenate([self.restrict(P).ravel(), [H0]])
        weight = self.dX * self.dY / self.load_target * self.mult.ravel()
        steps = 0
        R = self.reynolds(P, H0)[0]
        free = self.free_mask(P, R)
        F = self.equations(z, free, R)
        res = _norm(F)
        history.append(res)
        lu = None
        free_lu = free
        last_krylov = 10**9
        while steps < max_iter:
            if res < tol:
                return self.expand(z[:-1].reshape(n, self.m)), z[-1], steps, res
            stale = lu is None or last_krylov > self.refactor_after
            if stale or np.count_nonzero(free != free_lu) > self.refactor_changes:
                free_lu = free
                A, col = self.precond_matrix(self.expand(z[:-1].reshape(n, self.m)), z[-1], free)
                try:
                    lu = _PermutedLU(A.astype(self.lu_dtype), self.perm)
                except RuntimeError as exc:  # singular preconditioner
                    raise ConvergenceError(
                        f"EHL Newton step {steps}: singular preconditioner ({exc}); residual reached {res:.3e}"
                    ) from exc
                y = lu.solve(col)
                ry = float(weight @ y)

            def prec(r, lu=lu, y=y, ry=ry):
                x1 = lu.solve(r[:-1])
                t = (float(weight @ x1) - r[-1]) / ry if ry != 0 else 0.0
                return np.concatenate([x1 - y * t, [t]])

            znorm = _vnorm(z)

            def jv(v, z=z, F=F, free=free, znorm=znorm):
                nv = _vnorm(v)
                if nv == 0:
                    return np.zeros_like(v)
                sig = 1e-7 * (1.0 + znorm) / nv
                return (self.equations(z + sig * v, free) - F) / sig

            dz, last_krylov = _gmres_right(jv, prec, -F, self.krylov_rtol, self.krylov_max)
            # backtracking line search on the projected step
            t = 1.0
            for _ in range(8):
                zt = z + t * dz
                zt[:-1] = np.maximum(zt[:-1], 0.0)
                Pt = self.expand(zt[:-1].reshape(n, self.m))
                Rt = self.reynolds(Pt, zt[-1])[0]
                free_t = self.free_mask(Pt, Rt)
                Ft = self.equations(zt, free_t, Rt)
                rt = _norm(Ft)
                if rt < res * (1.0 - 1e-4 * t) or t < 0.02:
                    break
                t *= 0.5
            if self.trace:
                print(
                    f"  n={n} step {steps}: krylov {last_krylov} t {t:.3g} res {rt:.3e} "
                    f"free {int(free_t.sum())} H0 {zt[-1]:.5f}"
                )
            z, F, free, res = zt, Ft, free_t, rt
            steps += 1
            history.append(res)
        return self.expand(z[:-1].reshape(n, self.m)), z[-1], steps, res


class _PermutedLU:
    """Sparse LU (SuperLU, no further column ordering) of a matrix assembled in the order
    ``perm`` (new -> old index); ``solve`` takes and returns float64 vectors in the original
    order."""

    def __init__(self, A, perm):
        self.perm = perm
        self.dtype = A.dtype
        self.lu = spla.splu(A, permc_spec="NATURAL")

    def solve(self, r):
        out = np.empty(r.shape)
        out[self.perm] = self.lu.solve(r[self.perm].astype(self.dtype))
        return out


@lru_cache(maxsize=32)
def _nested_dissection(ni, nj, wx, wy, leaf=64):
    """Geometric nested-dissection order of an ni x nj node grid (row-major index i*nj + j):
    split the longer side (in units of its separator width) by a separator of wx rows
    (or wy columns), order both halves recursively, the separator last (:cite:`george1973`).
    Returns the permutation new -> old index (int64)."""
    out = []

    def block(i0, i1, j0, j1):
        return (np.arange(i0, i1)[:, None] * nj + np.arange(j0, j1)[None, :]).ravel()

    def rec(i0, i1, j0, j1):
        di, dj = i1 - i0, j1 - j0
        if di * dj <= leaf or (di <= 2 * wx + 1 and dj <= 2 * wy + 1):
            out.append(block(i0, i1, j0, j1))
            return
        if (di * wy >= dj * wx and di > 2 * wx + 1) or dj <= 2 * wy + 1:
            a = (i0 + i1) // 2 - wx // 2
            rec(i0, a, j0, j1)
            rec(a + wx, i1, j0, j1)
            out.append(block(a, a + wx, j0, j1))
        else:
            a = (j0 + j1) // 2 - wy // 2
            rec(i0, i1, j0, a)
            rec(i0, i1, a + wy, j1)
            out.append(block(i0, i1, a, a + wy))

    rec(0, ni, 0, nj)
    perm = np.concatenate(out)
    perm.setflags(write=False)
    return perm


def _gmres_right(matvec, prec, b, rtol, max_iter):
    """Right-preconditioned GMRES without restart (:cite:`saad2003`, alg. 9.5), classical
    Gram–Schmidt with one re-orthogonalisation done as matrix–vector products.

    Solves A x = b to ||b - A x|| <= rtol ||b|| (true residual, because the
    preconditioner acts on the right). Returns (x, iterations).
    """
    beta = _vnorm(b)
    n = b.size
    if beta == 0:
        return np.zeros(n), 0
    V = np.empty((max_iter + 1, n))
    Z = np.empty((max_iter, n))
    Hm = np.zeros((max_iter + 1, max_iter))
    V[0] = b / beta
    e1 = np.zeros(max_iter + 1)
    e1[0] = beta
    k = 0
    y = np.zeros(0)
    for k in range(max_iter):
        Z[k] = prec(V[k])
        w = matvec(Z[k])
        h = np.einsum("ij,j->i", V[: k + 1], w)
        w = w - np.einsum("i,ij->j", h, V[: k + 1])
        h2 = np.einsum("ij,j->i", V[: k + 1], w)
        w = w - np.einsum("i,ij->j", h2, V[: k + 1])
        Hm[: k + 1, k] = h + h2
        Hm[k + 1, k] = _vnorm(w)
        y, *_ = np.linalg.lstsq(Hm[: k + 2, : k + 1], e1[: k + 2], rcond=None)
        res = np.linalg.norm(e1[: k + 2] - Hm[: k + 2, : k + 1] @ y)
        if res <= rtol * beta or Hm[k + 1, k] <= 1e-300:
            break
        V[k + 1] = w / Hm[k + 1, k]
    return np.einsum("i,ij->j", y, Z[: k + 1]), k + 1


def _vnorm(v):
    """Euclidean norm without BLAS (see :func:`_gmres_right`)."""
    return math.sqrt(float(np.einsum("i,i->", v, v)))


def _subgrid_min(H):
    """Minimum of a film sampled on a uniform grid, refined below the grid spacing [same units].

    The smallest interior node value is corrected by the vertex of the parabola through it and
    its two neighbours, separately along each grid direction (f(-1), f(0), f(1) ->
    f(0) - (f(1) - f(-1))^2 / (8 (f(1) - 2 f(0) + f(-1))) where the curvature is positive).
    The discrete node minimum is off the true minimum by O(dX^2) with a sign that depends on
    where the minimum falls between nodes, which makes its grid sequence erratic; the vertex
    removes that sampling error so that the remaining O(dX^2) discretisation error can be
    extrapolated like the central film's.
    """
    inner = H[1:-1, 1:-1]
    i, j = np.unravel_index(int(np.argmin(inner)), inner.shape)
    i += 1
    j += 1
    value = float(H[i, j])
    for lo, hi in ((H[i - 1, j], H[i + 1, j]), (H[i, j - 1], H[i, j + 1])):
        curv = float(lo) - 2.0 * value + float(hi)
        if curv > 0.0:
            value -= (float(hi) - float(lo)) ** 2 / (8.0 * curv)
    return value


def _norm(F):
    """Scaled residual: RMS of the node equations plus the relative load error."""
    return float(np.sqrt(np.mean(F[:-1] ** 2)) + abs(F[-1]))


def _interpolate(P, X0, Y0, X1, Y1):
    """Bilinear interpolation of P from grid (X0, Y0) to (X1, Y1) (separable, vectorised)."""
    ix = np.clip(np.searchsorted(X0, X1) - 1, 0, X0.size - 2)
    wx = (X1 - X0[ix]) / (X0[ix + 1] - X0[ix])
    tmp = P[ix, :] * (1 - wx)[:, None] + P[ix + 1, :] * wx[:, None]
    iy = np.clip(np.searchsorted(Y0, Y1) - 1, 0, Y0.size - 2)
    wy = (Y1 - Y0[iy]) / (Y0[iy + 1] - Y0[iy])
    return tmp[:, iy] * (1 - wy)[None, :] + tmp[:, iy + 1] * wy[None, :]


_TRACE = False


def _check_solver_inputs(
    load,
    speed,
    rx,
    ry,
    e_eff,
    lubricant,
    grid,
    x_inlet,
    x_outlet,
    y_half,
    stencil,
    wedge_order,
    extrapolate,
    grid_tol,
    max_grid,
):
    """Validate :func:`solve_point_contact`'s inputs (InputError naming the bad one) and resolve
    its defaults; returns (wedge_order, extrapolate, refine_asked, max_grid)."""
    for name, value in (("load", load), ("speed", speed), ("rx", rx), ("ry", ry), ("e_eff", e_eff)):
        if value is None or not np.isfinite(value) or value <= 0:
            raise InputError(f"{name} must be finite and > 0, got {value!r}")
    lubricant.check()
    if grid < 9 or ((grid - 1) & (grid - 2)) != 0:
        raise InputError(f"grid must be 2^k + 1 >= 9 nodes (e.g. 65, 129, 257), got {grid}")
    if wedge_order is None:
        wedge_order = 2 if grid >= 129 else 1
    if extrapolate is None:
        extrapolate = wedge_order == 2 and grid >= 129
    refine_asked = max_grid is not None or extrapolate  # warn if the grid change then misses grid_tol
    if max_grid is None:
        max_grid = 513 if extrapolate else grid
    if max_grid < grid or ((max_grid - 1) & (max_grid - 2)) != 0:
        raise InputError(f"max_grid must be 2^k + 1 >= grid = {grid}, got {max_grid}")
    if grid_tol is not None and not (0 < grid_tol < 1):
        raise InputError(f"grid_tol must be in (0, 1) or None, got {grid_tol!r}")
    if wedge_order not in (1, 2):
        raise InputError(f"wedge_order must be 1 or 2, got {wedge_order!r}")
    if stencil not in (0, 1, 2, 3):
        raise InputError(f"stencil must be 0..3, got {stencil!r}")
    if not (x_inlet < 0 < x_outlet) or y_half <= 0:
        raise InputError(
            f"domain must contain the contact centre: x_inlet={x_inlet} < 0 < x_outlet={x_outlet}, y_half={y_half} > 0"
        )
    return wedge_order, extrapolate, refine_asked, max_grid


def _continuation_levels(grid, coarsest, extrapolate, grid_tol):
    """The grid continuation's levels (coarsest to ``grid``) and the first level solved to the
    full tolerance (:func:`solve_point_contact`)."""
    levels = []
    n = grid
    while n >= coarsest:
        levels.append(n)
        n = (n - 1) // 2 + 1
    levels = levels[::-1] or [grid]
    if extrapolate and len(levels) < 2:
        raise InputError(
            f"extrapolate=True needs a coarser level: grid={grid} must be >= 2 * coarsest - 1 = {2 * coarsest - 1}"
        )
    # levels whose central film enters the reported value or the grid-change estimate are solved to
    # ``tol``; the others only to ``coarse_tol``
    exact_from = grid
    for _ in range(int(extrapolate) + int(grid_tol is not None)):  # the reported value and the one below
        exact_from = (exact_from - 1) // 2 + 1

    return levels, exact_from


def _reported_film(values, k, extrapolate):
    """Reported film of level k [m] from a level's films ``values`` (central or minimum):
    extrapolated from levels k-1, k when enabled."""
    if extrapolate:
        return (4.0 * values[k] - values[k - 1]) / 3.0 if k >= 1 else float("nan")
    return values[k]


def _film_change(values, k, extrapolate):
    """|reported(k) / reported(k - 1) - 1| (nan without a coarser reported value)."""
    if k < (2 if extrapolate else 1):
        return float("nan")
    return abs(_reported_film(values, k, extrapolate) / _reported_film(values, k - 1, extrapolate) - 1.0)


# ----------------------------------------------------------------- public API
def _reported_films(h_levels, hmin_levels, k, n, extrapolate):
    """(h_c of level k, h_c of the level below, reported h_c, reported h_min) [m]; a
    non-positive or non-finite reported film (a failed extrapolation) raises ConvergenceError."""
    h_grid = h_levels[k]
    h_coarse = h_levels[k - 1] if k >= 1 else float("nan")
    h_central = _reported_film(h_levels, k, extrapolate)
    if not np.isfinite(h_central) or h_central <= 0:
        raise ConvergenceError(
            f"Richardson extrapolation of h_c failed: h_c({n}) = {h_grid:.4e} m, "
            f"h_c({(n - 1) // 2 + 1}) = {h_coarse:.4e} m"
        )
    h_min = _reported_film(hmin_levels, k, extrapolate)
    if not np.isfinite(h_min) or h_min <= 0:
        raise ConvergenceError(
            f"Richardson extrapolation of h_min failed: h_min({n}) = {hmin_levels[k]:.4e} m, "
            f"h_min({(n - 1) // 2 + 1}) = "
            f"{hmin_levels[k - 1] if k >= 1 else float('nan'):.4e} m"
        )
    return h_grid, h_coarse, h_central, h_min


def _grid_converged(grid_tol, change, change_c, change_min, refine_asked, n, where):
    """Whether the reported films met ``grid_tol``; a RuntimeWarning (naming the load case
    ``where``) when refinement was asked for and did not reach it."""
    grid_converged = bool(grid_tol is None or (np.isfinite(change) and change <= grid_tol))
    if not grid_converged and refine_asked:  # refinement was asked for and did not reach grid_tol
        warnings.warn(
            f"EHL film not grid-converged at the {n}x{n} grid (max_grid): h_c changed by "
            f"{100 * change_c:.2f} % and h_min by {100 * change_min:.2f} % from the next-coarser grid "
            f"(grid_tol {100 * grid_tol:.1f} %); "
            f"{where}",
            RuntimeWarning,
            stacklevel=3,
        )
    return grid_converged


def _hertz_start(prob, n, load, speed, rx, ry, e_eff, lubricant, hscale):
    """A level's start: the Hertz pressure scaled to the load, the rigid approach from the
    Hamrock-Dowson central film."""
    r2 = prob.X[:, None] ** 2 + prob.Y[None, :] ** 2
    P = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    P *= prob.load_target / (prob.dX * prob.dY * P.sum())
    hc_hd, _ = hamrock_dowson(load, speed, rx, ry, e_eff, lubricant.viscosity, lubricant.pressure_viscosity)
    ic, jc = np.argmin(np.abs(prob.X)), n // 2
    return P, float(hc_hd) / hscale - float(prob.gap[ic, jc] + prob.elastic(P)[ic, jc])


def _run_continuation(
    make,
    hertz_start,
    levels,
    grid,
    exact_from,
    max_grid,
    grid_tol,
    extrapolate,
    tol,
    coarse_tol,
    max_iter,
    hscale,
    where,
):
    """The grid continuation of :func:`solve_point_contact`: each level's Newton from the
    previous level's pressure (the first, or after an unusable coarse level, from
    ``hertz_start``), refined beyond ``grid`` up to ``max_grid`` until the reported films
    change by less than ``grid_tol``. Returns (problem, P, H0, H, n, k, steps, residual,
    total steps, residual history, central and minimum films of every level, closed film,
    grid change, of h_c, of h_min)."""
    P = H0 = None
    prev = None
    history: list = []
    h_levels: list = []
    hmin_levels: list = []  # sub-grid minimum film of each level [m] (:func:`_subgrid_min`)
    total = 0
    k = 0
    change = float("nan")
    while True:
        n = levels[k]
        prob = make(n)
        if P is None:
            P, H0 = hertz_start(prob, n)
        else:
            P = np.maximum(_interpolate(P, prev.X, prev.Y, prob.X, prob.Y), 0.0)
        history = []
        final = n >= grid
        # a coarse level that only provides the starting point may stop short of its tolerance
        level_tol = tol if n >= exact_from else max(tol, coarse_tol)
        prob.trace = _TRACE
        P, H0, steps, res = prob.newton(P, H0, level_tol, max_iter if final else 2 * max_iter, history)
        total += steps
        if (not np.isfinite(res) or res >= level_tol) and n >= exact_from:
            raise ConvergenceError(
                f"EHL solver did not converge on the {n}x{n} grid: residual reached {res:.3e} "
                f"(target {level_tol:.1e}) after {steps} Newton steps {where}"
            )
        if not (np.all(np.isfinite(P)) and np.isfinite(H0)):  # only possible below exact_from
            P = H0 = None  # unusable coarse start: the next level starts again from the Hertz pressure
            h_levels.append(float("nan"))
            hmin_levels.append(float("nan"))
            k += 1
            continue
        ic = int(np.argmin(np.abs(prob.X)))
        H = prob.film(P, H0)
        h_levels.append(float(H[ic, n // 2] * hscale))
        hmin_levels.append(_subgrid_min(H) * hscale)
        prev = prob
        if not final:
            k += 1
            continue
        closed = bool(np.any(H[1:-1, 1:-1] <= 0))
        change_c, change_min = _film_change(h_levels, k, extrapolate), _film_change(hmin_levels, k, extrapolate)
        change = max(change_c, change_min)  # nan if either is nan
        converged = True if grid_tol is None else bool((not closed) and np.isfinite(change) and change <= grid_tol)
        if converged or n >= max_grid:
            break
        levels.append(2 * n - 1)  # refine: one more level of the continuation
        k += 1
    return prob, P, H0, H, n, k, steps, res, total, history, h_levels, hmin_levels, closed, change, change_c, change_min


def solve_point_contact(
    load,
    speed,
    rx,
    ry,
    e_eff,
    lubricant: LubricantProperties,
    *,
    grid: int = 129,
    x_inlet: float = -4.5,
    x_outlet: float = 1.5,
    y_half: float = 3.0,
    tol: float = 1e-6,
    max_iter: int = 40,
    stencil: int = 1,
    coarsest: int = 17,
    coarse_tol: float = 1e-4,
    wedge_order: int | None = None,
    extrapolate: bool | None = None,
    grid_tol: float | None = 0.02,
    max_grid: int | None = None,
    symmetric: bool = True,
) -> EHLResult:
    """Solve the steady isothermal EHL point-contact problem.

    Parameters
    ----------
    load : normal load Q [N] (> 0).
    speed : mean entrainment speed u = (u1+u2)/2 [m/s] (> 0).
    rx, ry : effective radii of curvature [m] along and across the entrainment.
    e_eff : effective modulus E' [Pa] (:func:`flexrv.contact.hertz.effective_modulus`).
    lubricant : :class:`LubricantProperties` (Roelands and Dowson–Higginson data).
    grid : nodes per direction, 2^k + 1 (default 129).
    x_inlet, x_outlet, y_half : domain in Hertz semi-axes (x/b, y/a).
    tol : target of the scaled residual (RMS node residual + relative load error).
    max_iter : Newton steps per grid level.
    stencil : half-width of the truncated kernel in the preconditioner.
    coarsest : first grid of the continuation.
    coarse_tol : residual target on the coarser grids of the continuation.
    wedge_order : 1 (first-order upwind) or 2 (second-order upwind, "second-order upstream" of
        :cite:`venner2000`, sec. 9.3) for d(rho H)/dX; default (None): 2 for grid >= 129,
        1 below (the second-order scheme closes the film on grids coarser than ~65^2 at M > ~200).
    grid_tol : adaptive grid: refine (one more level of the continuation, up to ``max_grid``)
        until the reported h_c and h_min both change by less than this fraction from the values
        reported by the next-coarser grid (default 0.02); None: no refinement.
    max_grid : finest grid of the refinement; default 513 when extrapolating (grid >= 129),
        else ``grid`` (the coarse first-order path is not refined).
    symmetric : solve for the half Y >= 0 only (exact by symmetry; False solves the full
        grid, for verification).
    extrapolate : report as ``h_central`` (and likewise ``h_min``) the Richardson extrapolation (4 h_N - h_(N+1)/2)/3 of
        the second-order scheme from the finest grid N and the next-coarser one (both converged to
        ``tol``; the coarser grid is already part of the grid continuation, so this costs only a few
        extra Newton steps there). Default (None): True when ``wedge_order`` is 2 and grid >= 129.
        Justification (tests/test_ehl_convergence.py): the second-order scheme converges as
        O(dX^2) in h_c from 129^2 up (observed order 1.9-2.0 from 129/257/513 at M = 260), while
        the first-order scheme is far from its asymptotic range (+7.8 % at 129^2, +3 % at 513^2
        against the extrapolated limit at M = 260) — its small grid-to-grid changes were
        misleading.

    Returns
    -------
    EHLResult
        ``grid`` is the grid actually used, ``grid_change`` the change of h_c from the
        next-coarser grid, ``grid_converged`` whether it met ``grid_tol``. When refinement
        was asked for (the default at grid >= 129, or ``max_grid`` given) and ``grid_tol`` is
        missed at ``max_grid``, a RuntimeWarning says so.

    Raises
    ------
    InputError
        Non-positive load, speed, radii or modulus; invalid lubricant data; bad grid.
    ConvergenceError
        Newton did not reach ``tol`` (message: residual reached and iterations).
    """
    wedge_order, extrapolate, refine_asked, max_grid = _check_solver_inputs(
        load, speed, rx, ry, e_eff, lubricant, grid, x_inlet, x_outlet, y_half, stencil, wedge_order, extrapolate,
        grid_tol, max_grid,
    )  # fmt: skip
    load, speed, rx, ry, e_eff = map(float, (load, speed, rx, ry, e_eff))
    hz = point_contact(load, rx, ry, e_eff)
    a, b, p_h = float(hz.a), float(hz.b), float(hz.p_max)
    lam = 12.0 * lubricant.viscosity * speed * rx**2 / (b**3 * p_h)
    ky = a**2 * rx / (b**2 * ry)
    hscale = b**2 / rx  # H -> h [m]
    u_dim = lubricant.viscosity * speed / (e_eff * rx)
    moes_m = load / (e_eff * rx**2) * (2.0 * u_dim) ** -0.75

    def kernel_scale(n, dX, dY):
        return influence_kernel(n, n, dX * b, dY * a) / e_eff * p_h / hscale

    levels, exact_from = _continuation_levels(grid, coarsest, extrapolate, grid_tol)

    def make(n):
        return _GridProblem(
            n, x_inlet, x_outlet, y_half, b / a, ky, lam, kernel_scale, p_h, lubricant, stencil, wedge_order, symmetric
        )

    where = f"(load {load:g} N, speed {speed:g} m/s)"

    def start(prob, n):
        return _hertz_start(prob, n, load, speed, rx, ry, e_eff, lubricant, hscale)

    run = _run_continuation(
        make, start, levels, grid, exact_from, max_grid, grid_tol, extrapolate, tol, coarse_tol, max_iter, hscale,
        where,
    )  # fmt: skip
    prob, P, H0, H, n, k, steps, res, total, history, h_levels, hmin_levels, closed, change, change_c, change_min = run
    if closed:
        raise ConvergenceError(
            f"EHL solution on the {n}x{n} grid has a closed film (min h = {H[1:-1, 1:-1].min() * hscale:.3e} m < 0) "
            f"after {steps} Newton steps, residual {res:.3e}: the grid does not resolve the film at this load "
            f"(Moes M = {moes_m:.3g}); use a finer grid (max_grid) or the Hamrock-Dowson formula"
        )
    h_grid, h_coarse, h_central, h_min = _reported_films(h_levels, hmin_levels, k, n, extrapolate)
    grid_converged = _grid_converged(
        grid_tol, change, change_c, change_min, refine_asked, n, f"{where[1:-1]}, Moes M = {moes_m:.3g}"
    )
    return EHLResult(
        x=prob.X * b,
        y=prob.Y * a,
        pressure=P * p_h,
        film=H * hscale,
        h_central=h_central,
        h_min=h_min,
        h_min_grid=float(H[1:-1, 1:-1].min() * hscale),
        p_max=float(P.max() * p_h),
        hertz_pressure=p_h,
        hertz_a=a,
        hertz_b=b,
        rigid_approach=float(H0 * hscale),
        iterations=steps,
        total_iterations=total,
        residual=float(res),
        residual_history=history,
        load_error=float(prob.load_error(P)),
        grid=n,
        h_central_grid=h_grid,
        h_central_coarse=h_coarse,
        extrapolated=bool(extrapolate),
        wedge_order=int(wedge_order),
        grid_requested=int(grid),
        grid_change=float(change),
        grid_change_central=float(change_c),
        grid_change_min=float(change_min),
        grid_converged=grid_converged,
    )
