"""The compiled integrator's per-step checks (the elements' ``step_check``, run in the compiled
loop after every accepted step): the same conditions as the groups' Python checks, and a run
stopped at the step where Exudyn's integrator (its pre-step hook checks every step) stops."""

from __future__ import annotations

import re

import numpy as np
import pytest

from flexrv.errors import SimulationError
from flexrv.model.cranks_discs import needle_check
from flexrv.model.pins import pin_penetrated


def test_needle_check_codes():
    """needle_check: 1 (a skipped pin, the cause) before 2 (a penetration, the symptom); a NaN
    departure (not evaluated yet) is never a skip; the limits are strict inequalities."""
    lim = np.pi / 40
    assert needle_check(np.array([0.0, 0.0]), np.array([-1e-6]), lim, 2e-6) == 0
    assert needle_check(np.array([np.nan, np.nan]), np.array([np.inf]), lim, 2e-6) == 0
    assert needle_check(np.array([0.0, -1.01 * lim]), np.array([0.0]), lim, 2e-6) == 1
    assert needle_check(np.array([0.0, 1.01 * lim]), np.array([-3e-6]), lim, 2e-6) == 1
    assert needle_check(np.array([0.0, 0.99 * lim]), np.array([-3e-6]), lim, 2e-6) == 2
    assert needle_check(np.array([0.0, 0.0]), np.array([-2e-6]), lim, 2e-6) == 0


def test_pin_penetrated():
    """pin_penetrated: the smallest gap of every (disc, pin) below -limit; never before a call."""
    gap = np.full((2, 40), 1e-5)
    calls = np.ones(1, np.int64)
    assert not pin_penetrated(gap, calls, 1e-6)
    gap[1, 17] = -1.5e-6
    assert pin_penetrated(gap, calls, 1e-6)
    assert not pin_penetrated(gap, calls, 2e-6)
    assert not pin_penetrated(gap, np.zeros(1, np.int64), 1e-6)


def _failure_time(sim, integrator) -> tuple[float, str]:
    with pytest.raises(SimulationError) as exc:
        sim.run(
            t_end=0.03,
            dt=1e-4,
            integrator=integrator,
            newton_options={"extrapolatedPredictor": False} if integrator == "compiled" else None,
        )
    text = exc.value.results.attrs["failure"]
    return float(re.match(r"t = ([0-9.eE+-]+) s", text).group(1)), text


def test_compiled_check_stops_at_exudyns_step():
    """rv40e, loaded (shortened ramps), the pin penetration limit lowered to 0.05 um (a loaded
    pin contact penetrates by more): both integrators stop with the pins' message at the same
    step (the compiled one with Exudyn's predictor takes the same steps; its check runs after
    every accepted step as Exudyn's pre-step hook does, where the Python check used to see
    every 25th state). Measured: both t = 0.0043 s, penetration 0.0915 um; the Python check every
    25 steps stopped the compiled run at 0.005 s (0.0887 um)."""
    from flexrv.simulation import Simulation
    from tests.test_time_step import fast

    r = fast("rv40e")
    r = r.model_copy(update={"contact": r.contact.model_copy(update={"pin_penetration_limit_um": 0.05})})
    sim = Simulation(r)
    t_c, msg_c = _failure_time(sim, "compiled")
    t_e, msg_e = _failure_time(sim, "exudyn")
    assert "pin-disc penetration" in msg_c and "pin-disc penetration" in msg_e
    assert abs(t_c - t_e) < 0.5e-4, (msg_c, msg_e)
