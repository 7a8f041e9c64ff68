"""Speed paths of the rigid and ball models (issue 15) give the answers of the paths
they replace: the compiled history pass of the declared outputs, the tapered-roller
support law's cheaper inner solve, and the Newton settings."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load


def _fast(name, t_ramp=0.005):
    """Rated speed and load reached at ``t_ramp`` (as benchmarks/bench_rigid.py)."""
    r = load(name)
    op = r.operating.model_copy(update={"speed_ramp_time_s": t_ramp, "load_ramp_start_s": 0.0,
                                        "load_ramp_end_s": t_ramp})
    return r.model_copy(update={"operating": op})


@pytest.fixture(scope="module", params=["rv40e", "rv221"])
def history(request):
    """A short loaded rigid run's recorded states (t, q, v) and its model."""
    from flexrv.post import results as post_results
    from flexrv.simulation import Simulation

    cap = {}
    orig = post_results.results_from_states

    def spy(model, t, q, v, **kw):
        cap.update(t=np.array(t), q=np.array(q), v=np.array(v))
        return orig(model, t, q, v, **kw)

    sim = Simulation(_fast(request.param))
    post_results.results_from_states = spy
    try:
        sim.run(t_end=0.012, dt=1e-4)
    finally:
        post_results.results_from_states = orig
    return sim.model, cap["t"], cap["q"], cap["v"]


def test_compiled_history_equals_per_group_evaluate(history):
    """The fused element's compiled history pass (FusedForces.history, one compiled
    loop over the samples) gives every group output BIT FOR BIT as the groups' own
    evaluate of the history (the per-sample Python path it replaces), also across
    chunk boundaries (chunk 50 of 121 samples)."""
    from flexrv.model.outputs import group_outputs

    model, t, q, v = history
    assert model.fused is not None and len(t) > 100
    fast = group_outputs(model, t, q, v, chunk=50)
    fused, model.fused = model.fused, None  # no fused element: every group by its own evaluate
    try:
        slow = group_outputs(model, t, q, v, chunk=50)
    finally:
        model.fused = fused
    assert list(fast) == list(slow)
    for name in slow:
        assert fast[name].dims == slow[name].dims and fast[name].units == slow[name].units
        assert np.array_equal(fast[name].values, slow[name].values), name
    assert np.max(fast["pin_force"].values) > 0.0  # loaded: the comparison covers contact forces
