"""Prediction intervals (:mod:`flexrv.studies.uncertainty`) on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.studies.uncertainty import interval, propagate


def test_series_spring_with_a_uniform_compliance():
    """k = 1 / (1/k1 + c), c uniform on [a, b]: k is monotone in c, so its median and 5 / 95 %
    quantiles are k at c's: c = a + (0.5, 0.95, 0.05)(b - a) (closed form). 256 scrambled Sobol'
    points reproduce them within 1e-2 (the quantiles of 256 points of a well-spread sequence);
    a second input that the output ignores gets SRC^2 < 1e-3, the compliance ~0.98 (the
    regression is linear in c, k is not: R^2 > 0.95)."""
    k1, a, b = 200.0, 0.002, 0.006

    def k_of(c):
        return 1.0 / (1.0 / k1 + c)

    out = propagate(lambda v: {"k": k_of(v["c"])}, {"c": (a, b), "ignored": (0.0, 1.0)}, 256, seed=3)
    r = out["outputs"]["k"]
    assert r["median"] == pytest.approx(k_of(a + 0.5 * (b - a)), rel=1e-2)
    assert r["p05"] == pytest.approx(k_of(a + 0.95 * (b - a)), rel=1e-2)
    assert r["p95"] == pytest.approx(k_of(a + 0.05 * (b - a)), rel=1e-2)
    src = r["contributors"]
    assert src["r2"] > 0.95
    assert src["src2"]["c"] > 0.9 and src["src2"].get("ignored", 0.0) < 1e-3
    assert out["failed"] == []


def test_contributors_with_more_inputs_than_samples():
    """40 inputs, 32 samples (no joint fit): y = x0 + 0.1 x1 with independent uniform inputs
    has corr(x0, y)^2 = 1 / 1.01 = 0.990 and corr(x1, y)^2 = 0.0099 (closed form); the marginal
    SRC^2 ranks x0 first within 0.05 of 0.990, and the 38 ignored inputs score on average about
    the noise floor 1/(N - 1): N r^2 of an ignored input is about chi^2(1), above its mean 1 with
    probability 0.32, so fewer than half of them pass it."""
    ranges = {f"x{i}": (0.0, 1.0) for i in range(40)}
    out = propagate(lambda v: {"y": v["x0"] + 0.1 * v["x1"]}, ranges, 32, seed=2)
    c = out["outputs"]["y"]["contributors"]
    assert c["basis"] == "marginal" and c["noise_floor"] == pytest.approx(1.0 / 31)
    assert next(iter(c["src2"])) == "x0" and c["src2"]["x0"] == pytest.approx(1.0 / 1.01, abs=0.05)
    assert len(set(c["src2"]) - {"x0", "x1"}) < 38 / 2


def test_screen_drops_only_the_inputs_an_evaluation_ignores():
    """y = a + b^2 ignores c: moving each input alone to its range end farther from the nominal
    leaves y unchanged for c only; b's nominal sits at its upper end, so b is moved to the lower
    end and kept."""
    from flexrv.studies.uncertainty import screen

    nominal = {"a": 0.5, "b": 1.0, "c": 0.5}

    def ev(v):
        x = {**nominal, **v}
        return {"y": x["a"] + x["b"] ** 2}

    ranges = {"a": (0.0, 1.0), "b": (0.0, 1.0), "c": (0.0, 1.0)}
    assert screen(ev, ranges, nominal) == ["c"]


def test_failed_samples_are_reported_not_fatal():
    """An evaluation that raises is listed in ``failed`` and leaves NaN; the interval is
    taken over the others."""

    def ev(v):
        if v["x"] > 0.9:
            raise ValueError("outside")
        return {"y": v["x"]}

    out = propagate(ev, {"x": (0.0, 1.0)}, 64, seed=1)
    assert len(out["failed"]) > 0 and all("outside" in f for f in out["failed"])
    assert out["outputs"]["y"]["n"] == 64 - len(out["failed"])
    assert interval(np.array([np.nan]))["n"] == 0


def test_te_cli_uncertainty(tmp_path):
    """``flexrv te rv40e --uncertainty 4 --json``: every output of
    :data:`flexrv.studies.uncertainty.OUTPUTS` with median inside its 5-95 % interval,
    contributors named from the preset's [ranges], uncertainty.json written; no rigidity with
    elements added after the fact (every element is in the model)."""
    import json

    from typer.testing import CliRunner

    from flexrv.cli import app
    from flexrv.design import load
    from flexrv.studies.uncertainty import OUTPUTS

    out = tmp_path / "te"
    args = ["te", "rv40e", "--crank-revolutions", "0.05", "--points-per-mesh", "4", "--out", str(out)]
    res = CliRunner().invoke(app, [*args, "--uncertainty", "4", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    u = d["uncertainty"]
    assert set(OUTPUTS) <= set(u["outputs"]) and u["failed"] == []
    for name in OUTPUTS:
        r = u["outputs"][name]
        assert r["p05"] <= r["median"] <= r["p95"]
    assert set(u["inputs"]) == set(load("rv40e").ranges) == set(u["sampled"]) | set(u["no_effect"])
    assert "main_bearing.cage_damping_Ns_per_m" in u["no_effect"]
    assert "needle_bearing.radial_clearance_um" in u["sampled"]
    assert (out / "uncertainty.json").stat().st_size > 1000
    assert not [k for k in d if "with_added" in k]


def test_preset_ranges_cover_their_estimates():
    """Every numeric field whose provenance says "estimate" has a [ranges] entry, and every
    [ranges] entry names an estimated field, contains the preset's value and gives a reason;
    both ends make a valid design. Text fields (a lubricant's name, a model choice) have no range."""
    from flexrv.design import load, override
    from flexrv.design.model import field_value

    for name in ("rv40e", "rv221"):
        r = load(name)
        for path, note in r.provenance.items():
            value = field_value(r, path) if "estimate" in note.lower() else None
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                assert path in r.ranges, f"{name}: estimated {path} has no [ranges] entry"
        for path, rg in r.ranges.items():
            assert "estimate" in r.provenance[path].lower(), (name, path)
            value = field_value(r, path)
            assert rg.low <= value <= rg.high and len(rg.reason) > 10, (name, path)
            for v in (rg.low, rg.high):
                override(r, {path: int(round(v)) if isinstance(value, int) else float(v)})


def test_preset_ranges_are_jointly_valid():
    """The ranges are sampled together: 128 scrambled Sobol' samples of every preset's ranges
    are all valid designs (the coupled geometry checks: ring sections, cage fills, pillars on
    the plates, needles within the disc)."""
    from flexrv.design import load
    from flexrv.studies.uncertainty import _with_values

    for name in ("rv40e", "rv221"):
        r = load(name)
        ranges = {k: (g.low, g.high) for k, g in r.ranges.items()}
        out = propagate(lambda v: (_with_values(r, v), {"valid": 1.0})[1], ranges, 128, seed=5)
        assert out["failed"] == [], (name, out["failed"][:1])


def test_stiffness_test_cli_names_and_uncertainty(tmp_path):
    """``flexrv stiffness-test rv40e --json --uncertainty 4`` (short loop): the loop's figures
    under their definition names, the budget with the path compliances' shares, and the prediction
    intervals of the same outputs as ``te``."""
    import json

    from typer.testing import CliRunner

    from flexrv.cli import app
    from flexrv.post.definitions import DEFINITIONS
    from flexrv.studies.uncertainty import OUTPUTS

    args = ["stiffness-test", "rv40e", "--quarter-time", "0.01", "--out", str(tmp_path / "st")]
    res = CliRunner().invoke(app, [*args, "--json", "--uncertainty", "4"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert set(DEFINITIONS) <= set(d)
    b = d["stiffness_budget"]
    assert {"carrier_joints", "crank_torsion", "planet_spline", "support_bearing_rings"} <= set(b["elements"])
    assert all(0.0 < e["share_percent"] < 100.0 for e in b["elements"].values())
    assert set(OUTPUTS) <= set(d["uncertainty"]["outputs"])
