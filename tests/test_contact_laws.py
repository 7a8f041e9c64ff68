"""Impact law of the seeds (Adams IMPACT) on the signed gap."""

import numpy as np

from flexrv.contact.laws import adams_step, adams_step_derivative, impact_force


def test_step_values():
    """Adams STEP: endpoints, midpoint 0.5, C1 at the ends (MSC Adams reference)."""
    x = np.array([-1.0, 0.0, 0.5, 1.0, 2.0])
    np.testing.assert_allclose(adams_step(x, 0, 0, 1, 1), [0, 0, 0.5, 1, 1])
    np.testing.assert_allclose(adams_step_derivative(np.array([0.0, 0.5, 1.0]), 0, 0, 1, 1), [0, 1.5, 0])


def test_impact_force_static_is_power_law():
    """Without velocity the force is k delta^e; open contacts carry nothing."""
    gap = np.array([1e-6, 0.0, -1e-6, -4e-6])
    f, _, _ = impact_force(gap, np.zeros(4), 2e10, 1.5, 1e3, 1e-5)
    np.testing.assert_allclose(f, [0, 0, 2e10 * 1e-9, 2e10 * 8e-9])


def test_impact_force_damping_ramp_and_no_pull():
    """Damping is c_max beyond depth d, 0 at first touch, and the force never pulls."""
    f, _, dv = impact_force(np.array([-2e-5, -1e-9]), np.array([-0.1, -0.1]), 0.0, 1.5, 1e3, 1e-5)
    assert np.isclose(f[0], 100.0) and f[1] < 1e-3
    f, _, _ = impact_force(np.array([-1e-6]), np.array([1.0]), 1e10, 1.5, 1e3, 1e-6)  # fast separation
    assert f[0] == 0.0


def test_impact_force_derivatives_match_finite_differences():
    rng = np.random.default_rng(1)
    gap = -rng.uniform(1e-7, 3e-5, 50)
    rate = rng.uniform(-0.05, 0.05, 50)
    args = (3e10, 1.5, 2e3, 1e-5)
    f, dg, dv = impact_force(gap, rate, *args)
    h = 1e-12
    f_g, _, _ = impact_force(gap + h, rate, *args)
    f_v, _, _ = impact_force(gap, rate + 1e-7, *args)
    active = f > 0
    np.testing.assert_allclose(dg[active], ((f_g - f) / h)[active], rtol=1e-4)
    np.testing.assert_allclose(dv[active], ((f_v - f) / 1e-7)[active], rtol=1e-5)
