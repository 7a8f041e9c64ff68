"""Fast convergence-rate tests (default suite, a few seconds each), in the style of
scikit-fem's ``tests/test_convergence.py``: each class states the expected observed order
``rate`` as a class attribute and the band ``tol`` around it, computes the observed order on a
short sequence of grids/meshes, and asserts it is inside the band. The fine-grid versions live
in the slow tests (tests/test_ehl_convergence.py, tests/test_fem_frequencies.py).

Observed order (Roache :cite:`roache1998`, ch. 5), from three solutions with a constant
refinement ratio r: p = log(|f1 - f2| / |f2 - f3|) / log r; with an exact reference value:
the least-squares slope of log|error| against log h.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.ehl.solver import LubricantProperties, solve_point_contact


def observed_order(f1, f2, f3, ratio):
    """Order from three solutions on grids refined by ``ratio`` (coarse to fine)."""
    return float(np.log(abs(f1 - f2) / abs(f2 - f3)) / np.log(ratio))


def error_slope(h, err):
    """Least-squares slope of log|err| against log h."""
    return float(np.polyfit(np.log(h), np.log(np.abs(err)), 1)[0])


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE", str(tmp_path))


# ----------------------------------------------------------------------------- EHL film
E = 2.2e11
LUB = LubricantProperties(0.05, 2e-8, 0.67, 1.96e8, 870.0)
LUB_RV = LubricantProperties(0.13, 2e-8, 0.68, 1.96e8, 870.0, 0.6e-9, 1.7e-9)


class ConvergenceEHLCircular:
    """Raw (unextrapolated) films of the second-order scheme on 33^2/65^2/129^2, light circular
    contact (Moes M = 31, L = 9.9). Expected order 2 (second-order upwind wedge, central
    Poiseuille terms, :cite:`venner2000` sec. 9.3); measured h_c 1.93, h_min 1.94 (h_min is the
    sub-grid minimum, flexrv.ehl.solver._subgrid_min). ~1.2 s."""

    case = (20.0, 2.0, 0.01, 0.01, E, LUB)
    rate = 2.0
    tol = 0.3

    def films(self):
        q, u, rx, ry, e, lub = self.case
        out = [
            solve_point_contact(q, u, rx, ry, e, lub, grid=g, wedge_order=2, extrapolate=False, grid_tol=None)
            for g in (33, 65, 129)
        ]
        return [r.h_central for r in out], [r.h_min for r in out]

    def test_order(self):
        hc, hmin = self.films()
        assert observed_order(*hc, 2.0) == pytest.approx(self.rate, abs=self.tol)
        assert observed_order(*hmin, 2.0) == pytest.approx(self.rate, abs=self.tol)


class TestConvergenceEHLCircular(ConvergenceEHLCircular):
    pass


class TestConvergenceEHLEllipse(ConvergenceEHLCircular):
    """Elliptical contact ry/rx = 4, M = 260: measured h_c 1.85, h_min 2.13. ~1 s."""

    case = (100.0, 1.0, 0.01, 0.04, E, LUB)


class TestConvergenceEHLBall(ConvergenceEHLCircular):
    """rv221 main-bearing ball (a/b ~ 9, M = 720): measured h_c 1.91, h_min 2.05. ~1.5 s."""

    case = (97.7, 0.0548, 0.01389, 0.39, 2.2857e11, LUB_RV)


# ----------------------------------------------------------------------------- FE modes
class TestConvergenceShaftTorsion:
    """Free-free steel shaft r = 10 mm, L = 100 mm, P2 tetrahedra (scikit-fem), mesh sizes
    10/6.7/4.5 mm: the first torsional frequency against the exact sqrt(G/rho)/(2L) (the
    uniform torsion mode of a free circular cylinder is an exact solution of 3-D elasticity,
    :cite:`timoshenko1970`). Expected order 4 for the eigenvalue error of quadratic
    elements (twice the energy-norm order 2); measured errors 3.1e-3, 4.0e-4, 8.6e-5, slope 4.5
    (5.1, 3.9 pairwise: unstructured meshes; 4.0 from 6.7/4.5/3 mm in 9 s). ~2 s."""

    rate = 4.5
    tol = 1.0
    sizes = (0.010, 0.0067, 0.0045)

    def test_order(self):
        from flexrv.fem.assembly import assemble
        from flexrv.fem.modal import eigenmodes
        from flexrv.meshing.mesh import generate_mesh
        from flexrv.meshing.parts import CrankshaftSpec

        e_mod, nu, rho, r, length = 2.1e11, 0.3, 7850.0, 0.01, 0.1
        exact = np.sqrt(e_mod / (2 * (1 + nu)) / rho) / (2 * length)
        errors = []
        for h in self.sizes:
            m = generate_mesh(CrankshaftSpec(segments=(("shaft", r, length, 0.0),)), "shaft", h).data
            fe = assemble(m.nodes, m.tets, e_mod, nu, rho)
            f, v = eigenmodes(fe.K, fe.M, 12)
            u = v.reshape(-1, 3, v.shape[1])
            x = m.nodes
            tang = (-x[:, 1, None] * u[:, 0] + x[:, 0, None] * u[:, 1]) / np.maximum(np.hypot(x[:, 0], x[:, 1]), 1e-12)[
                :, None
            ]
            share = (tang**2).sum(0) / (u**2).sum((0, 1))
            errors.append(f[(f > 1.0) & (share > 0.9)][0] / exact - 1.0)
        errors = np.array(errors)
        assert np.all(errors > 0)  # conforming FE: frequencies converge from above
        assert error_slope(self.sizes, errors) == pytest.approx(self.rate, abs=self.tol)
        assert errors[-1] < 2e-4


# ----------------------------------------------------------------------------- crank k_t
class TestConvergenceCrankTorsion:
    """Torsional stiffness k_t of the rv40e crankshaft (flexrv.fem.crankshaft.crank_compliance,
    gear seat against the eccentrics, both as rigid interfaces) at mesh sizes 6/4/2.67 mm
    (ratio 1.5): 29389, 27890, 27329 N m/rad, observed order 2.42 (~4.5 s). The stiffness
    converges from above but is NOT in its asymptotic range at affordable meshes: the next
    triple 4/2.67/1.78 mm (26864 N m/rad at 1.78 mm, 19 s) gives 0.46, consistent with the
    stress singularities where the rigid interfaces meet the free surface. So k_t at the
    default mesh (3 mm for rv40e: 27419 N m/rad) carries a discretisation error of the order
    of 5-10 %: extrapolating the last two values with an order between 0.46 and 1 gives
    24.6e3-25.9e3 N m/rad. The band pins the coarse-triple behaviour so that a change of the
    FE model or of the interface coupling shows up."""

    rate = 2.4
    tol = 0.6
    sizes = (0.006, 0.004, 0.00267)

    def test_order(self):
        from flexrv.design import load
        from flexrv.fem.crankshaft import crank_compliance

        red = load("rv40e")
        k = [crank_compliance(red, size=s, cache=False).torsional for s in self.sizes]
        assert k[0] > k[1] > k[2]  # displacement FE: stiffness from above
        assert observed_order(*k, 1.5) == pytest.approx(self.rate, abs=self.tol)
        assert k[2] == pytest.approx(27329.0, rel=0.01)


# ----------------------------------------------------------------------------- carrier and disc bodies
class TestConvergenceCarrierTorsion:
    """Torsional compliance g^T C g of a small carrier (3 cranks, 3 pillars of r = 3 mm, 6 mm
    plates; the executors of flexrv.fem.carrier.carrier_compliance: RBE3 bore loads,
    flange held, torque load vector) at global sizes 6/4.24/3 mm, pillar size half the
    global (ratio sqrt 2; 5.1k-17.6k nodes, ~9 s). Measured 2026-11-24: 7.8062, 8.1850,
    8.4236e-6 rad/(N m), observed order 1.33. Expected about 1.1: the strain energy of P2
    elements converges as h^(2 lambda) next to the sharp re-entrant edges where the pillars meet
    the plates (lambda = 0.545 for a 270-degree wedge; Szabo & Babuska, Finite Element Analysis,
    1991, ch. 10), which no part default can outrun with uniform refinement: the rv40e carrier
    gives 1.08 on 8/5.66/4 mm (tests/test_fem_carrier.py::test_mesh_convergence_carrier_slow),
    and its default mesh (6.67 mm, pillars 5.5 mm, 1.6250e-7) lies 6 % below the Richardson value
    1.729e-7 (0.7 % of the rv40e's total torsional compliance, the carrier's share being 11 %).
    Graded refinement at the pillar roots alone (edge size 2/1/0.5 mm) gives 1.6607/1.6840/
    1.6948e-7 at 31k/48k/83k nodes and 52/102/221 s: the same order 1.1 in the edge size."""

    rate = 1.3
    tol = 0.5
    sizes = (0.006, 0.006 / np.sqrt(2), 0.003)

    def test_order(self):
        from flexrv.fem.assembly import assemble
        from flexrv.fem.carrier import bore_groups, clamped_flexibility, rbe3_loads, torque_load_vector
        from flexrv.meshing.mesh import generate_mesh
        from tests._parts import MINI_CARRIER

        spec = MINI_CARRIER
        g = torque_load_vector(3, spec.crank_circle_radius, 0.5)
        c = []
        for h in self.sizes:
            m = generate_mesh(spec, "carrier", h, local_size=0.5 * h, cache=False).data
            fe = assemble(m.nodes, m.tets, 2.1e11, 0.3, 7800.0, mass=False)
            W = rbe3_loads(m.nodes, [m.faces(b) for b in bore_groups(3)])
            C, _ = clamped_flexibility(fe.K, m.node_set("flange"), W)
            c.append(float(g @ C @ g))
        assert c[0] < c[1] < c[2]  # displacement FE: compliance from below
        assert observed_order(*c, np.sqrt(2)) == pytest.approx(self.rate, abs=self.tol)
        assert c[2] == pytest.approx(8.4236e-6, rel=0.01)


class TestConvergenceDiscTorsion:
    """The rv40e disc body compliance as the models and the budget take it (mean over six crank
    angles of flexrv.fem.disc.disc_torsion_sweep, pin patches r_rp / 2 with consistent loads)
    on coarse meshes: global 8 mm, flank sizes 6/4.24/3 mm (ratio sqrt 2; 5.2k-12.7k nodes,
    ~14 s). Measured 2026-11-24: 1.44093, 1.45448, 1.46447e-7 rad/(N m), observed order 0.88
    (pre-asymptotic: at the default global size 5.5 mm the flank triple 4.24/3/2.12 mm gives
    1.86 and a Richardson value 0.8 % above the default flank size r_rp = 3 mm, slow test
    tests/test_fem_disc.py::test_disc_mesh_convergence_slow). The band pins the coarse-triple
    behaviour, so that a change of the patch loads or the hole coupling shows up."""

    rate = 0.9
    tol = 0.5
    flanks = (0.006, 0.006 / np.sqrt(2), 0.003)

    def test_order(self):
        from flexrv.design import load
        from flexrv.fem.disc import disc_torsion_sweep

        red = load("rv40e")
        c = [disc_torsion_sweep(red, size=0.008, local_size=h, cache=False).mean for h in self.flanks]
        assert c[0] < c[1] < c[2]
        assert observed_order(*c, np.sqrt(2)) == pytest.approx(self.rate, abs=self.tol)
        assert c[2] == pytest.approx(1.46447e-7, rel=0.01)
