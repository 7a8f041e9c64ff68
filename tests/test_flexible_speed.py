"""The compiled integrator's own Newton settings of the ball-resolved bearing models
(flexrv.simulation.COMPILED_MODEL_NEWTON); that the flexible rings give the same TE with them on
both integrators: tests/test_integrator.py::test_cross_check_flexible_rings_against_exudyn."""

from __future__ import annotations


def test_compiled_newton_settings_of_the_flexible_rings_are_compiled_options():
    """The compiled integrator's per-model Newton settings are options it honours
    (integrator.compiled_newton_options maps them to gen_alpha's keywords, an unknown one is an
    InputError): the flexible rings' contractivity 0.25, stricter than Exudyn's default 0.5 (a new
    Jacobian when the residual contracts worse than that per iteration); the ball model, whose
    setting MODEL_NEWTON holds for both integrators, has none of its own."""
    from flexrv.model.integrator import compiled_newton_options
    from flexrv.simulation import COMPILED_MODEL_NEWTON, MODEL_NEWTON

    opts = compiled_newton_options(COMPILED_MODEL_NEWTON["flexible"])
    assert opts["contractivity"] == 0.25
    assert set(COMPILED_MODEL_NEWTON) == {"flexible"} and "flexible" not in MODEL_NEWTON


def test_compiled_segments_pass_the_flexible_rings_setting_under_the_users(monkeypatch):
    """The compiled path's option route (simulation._CompiledSegments): a flexible-rings model
    (249 coordinates, balls with inertia) gets the Jacobian kept across steps (above SPARSE_ABOVE)
    and contractivity 0.25; the user's newton_options win over it; the rigid model (< 100
    coordinates) gets neither (a Jacobian every step, gen_alpha's default contractivity)."""
    import types

    import flexrv.model.integrator as integrator
    from flexrv import simulation

    seen = []

    class Recorder:
        def __init__(self, model, spectral_radius, tolerance, newton):
            seen.append(newton)

    monkeypatch.setattr(integrator, "CompiledIntegrator", Recorder)
    plan = types.SimpleNamespace(t_start=0.0)

    def newton_of(name, n, user):
        model = types.SimpleNamespace(n=n, name=name, info={"ball_inertia": True}, groups=[])
        simulation._CompiledSegments(model, 0.5, (1e-3, 0.1), user, plan)
        return seen[-1]

    flexible = newton_of("flexible", 249, None)
    assert flexible["contractivity"] == 0.25 and flexible["jacobian_each_step"] is False
    assert newton_of("flexible", 249, {"modifiedNewtonContractivity": 0.5})["contractivity"] == 0.5
    rigid = newton_of("rigid", 54, None)
    assert "contractivity" not in rigid and rigid["jacobian_each_step"] is True
