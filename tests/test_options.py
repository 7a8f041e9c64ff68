"""Options dicts are validated before any work (issue 16: typed, validated options;
an unknown option is a clear error naming it, like scipy's ``_check_unknown_options``)."""

import pytest

from flexrv.errors import InputError, check_options, signature_options
from flexrv.simulation import Simulation


@pytest.mark.parametrize(
    "model, options, message",
    [
        ("rigid", {"bogus": 1}, "model options of 'rigid': unknown option 'bogus'"),
        (
            "flexible",
            {"crankshaft": "flexible"},
            "unknown option 'crankshaft'; allowed: ball_inertia, crank_options, drive, exudyn, parts",
        ),
        ("flexible", {"ring_options": {"harmonic": 8}}, "ring_options: unknown option 'harmonic'"),
        (
            "flexible",
            {"parts": ("crankshaft",), "crank_options": {"damping_ratio": True}},
            "crank_options.damping_ratio = True is not allowed: expected a value of type float",
        ),
    ],
)
def test_model_options_checked(model, options, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Simulation("rv40e", model=model, model_options=options).build()


@pytest.mark.parametrize(
    "options, message",
    [
        ({"maxIteration": 10}, "newton_options: unknown option 'maxIteration'; allowed: absoluteTolerance"),
        ({"maxIterations": "10"}, r"newton_options.maxIterations = '10' is not allowed: expected a value of type int"),
        ({"maxIterations": 2.5}, r"newton_options.maxIterations = 2.5 is not allowed"),
        ({"relativeTolerance": False}, r"newton_options.relativeTolerance = False is not allowed"),
    ],
)
def test_newton_options_checked_before_work(options, message):
    sim = Simulation("rv40e")
    with pytest.raises(InputError, match=message):
        sim.run(t_end=0.01, newton_options=options)
    assert sim.model is None  # refused before the model was built


def test_check_options_accepts_ints_for_floats_and_any_for_none():
    def fn(reducer, size=None, scale=1.0, n=3, flag=True, zeta: "float | None" = None):
        pass

    allowed = signature_options(fn, skip=1)
    assert allowed == {"size": None, "scale": 1.0, "n": 3, "flag": True, "zeta": 0.0}
    with pytest.raises(InputError, match=r"x.zeta = 'a' is not allowed"):
        check_options("x", {"zeta": "a"}, allowed)
    assert check_options("x", {"size": "anything", "scale": 2, "n": 4, "flag": False}, allowed) == {
        "size": "anything",
        "scale": 2,
        "n": 4,
        "flag": False,
    }
    with pytest.raises(InputError, match=r"x.flag = 1 is not allowed"):
        check_options("x", {"flag": 1}, allowed)
