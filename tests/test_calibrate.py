"""Calibration (flexrv.studies.calibrate, `flexrv calibrate`): synthetic round trips on rv40e.

The measurements are made by flexrv itself from a design with known "true" values plus
normal angle noise of 0.005 arcmin (:func:`flexrv.studies.calibrate.synthetic_loop`), so the
truth is known exactly: the 95 % intervals must cover it, a pair that one loop cannot
separate must be reported as not identifiable, and the calibrated design must carry its
provenance. Evaluations in this process (``workers=0``); the dask path is the benchmark's
(benchmarks/bench_calibrate.py) and the CLI test's."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexrv.design import load, override
from flexrv.measured import read_measured
from flexrv.measured.writer import write_loop
from flexrv.studies.calibrate import calibrate, screen, synthetic_loop
from flexrv.workflows.calibration import EXAMPLE_TRUTH as TRUTH
from flexrv.workflows.calibration import FREE

SIGMA = 0.005  # arcmin


def _measured(tmp_path, truth: dict, seed: int, name: str = "loop.csv"):
    t, a = synthetic_loop(override("rv40e", truth), 412.0, SIGMA, seed)
    return read_measured(write_loop(tmp_path / name, t, a, angle_uncertainty_arcmin=SIGMA))


def test_round_trip_three_fields_covered(tmp_path):
    """Three estimated inputs (pin-disc clearance, crank support preload, needle roller length)
    calibrated back from one noisy loop: every field is identifiable and within 3 standard
    errors of its truth (the 99.7 % interval: one draw; the 95 % coverage is counted over 20
    draws in the workflow's slow test), the weighted residual RMS is that of the stated noise
    (0.4 .. 1.6 for 6 observations and 3 fields), and the interval of the clearance is narrow
    (< 10 % of its range: the lost motion fixes it)."""
    cal = calibrate(load("rv40e"), [_measured(tmp_path, TRUTH, seed=1)], free=FREE, workers=0)
    for k, v in cal.identified.items():
        assert v["identifiable"], k
        se = (v["ci95_high"] - v["ci95_low"]) / (2 * 1.959964)
        assert abs(v["value"] - TRUTH[k]) <= 3 * se, (k, v)
    c = cal.identified["second_stage.modification_equidistant_mm"]
    assert c["ci95_high"] - c["ci95_low"] < 0.1 * (FREE["second_stage.modification_equidistant_mm"][1] - 0.0025)
    assert 0.4 < cal.residual_rms < 1.6
    assert cal.sigma_source == "stated"
    corr = np.array(cal.correlation)
    assert np.allclose(np.diag(corr), 1.0) and np.all(np.abs(corr) <= 1.0 + 1e-9)


def test_two_compliances_in_series_not_identifiable(tmp_path):
    """Crank bending (eccentric journal length) and the housing ring (its outer diameter) are two
    linear compliances in series: one loop sees only their sum (their sensitivity columns are
    parallel to 1e-6). Both freed: the fit reports one non-identifiable combination holding
    both, neither field identifiable, and their intervals are the whole plausible ranges,
    never a tight interval."""
    free = {"crankshaft.eccentric_journal_length_mm": (9.0, 15.0), "housing.ring_outer_diameter_mm": (170.0, 220.0)}
    truth = {"crankshaft.eccentric_journal_length_mm": 12.6, "housing.ring_outer_diameter_mm": 185.0}
    cal = calibrate(load("rv40e"), [_measured(tmp_path, truth, seed=2)], free=free, workers=0)
    assert len(cal.non_identifiable) == 1
    assert set(cal.non_identifiable[0]["weights"]) == set(free)
    for k, (lo, hi) in free.items():
        v = cal.identified[k]
        assert not v["identifiable"], k
        assert (v["ci95_low"], v["ci95_high"]) == (lo, hi)


def test_screening_drops_collinear_and_insensitive_fields():
    """The sensitivity screen on four candidates: the eccentric journal length (crank bending)
    is chosen; the support journal length (the same bending compliance: a parallel column) is
    not separable from it; the needle-bearing damping does not act on a static loop
    (insensitive); the pin-disc clearance adds a direction (lost motion) and is chosen."""
    from flexrv.studies.calibrate import Evaluator, Target, observe, quasi_static_loop

    rv = load("rv40e")
    t, a = quasi_static_loop(rv, 412.0)
    target = Target("synthetic", "stiffness_loop", 412.0, (), observe("stiffness_loop", t, a, 412.0), SIGMA)
    cands = {
        "crankshaft.eccentric_journal_length_mm": (9.0, 15.0),
        "crankshaft.support_journal_length_mm": (7.0, 13.0),
        "crankshaft.support_bearing_damping_Ns_per_m": (100.0, 300.0),
        "second_stage.modification_equidistant_mm": (0.0025, 0.0075),
    }
    chosen, report = screen(Evaluator(workers=0), rv.model_dump(mode="python"), cands, [target], max_free=3)
    assert set(chosen) == {"crankshaft.eccentric_journal_length_mm", "second_stage.modification_equidistant_mm"}
    why = {r["field"]: r["decision"] for r in report}
    assert "not separable" in why["crankshaft.support_journal_length_mm"]
    assert "insensitive" in why["crankshaft.support_bearing_damping_Ns_per_m"]


def test_calibrate_cli_json_and_calibrated_design(tmp_path, capsys):
    """`flexrv calibrate rv40e --measured loop.csv --free ... --json` (dask, one worker): the
    JSON holds identified {value, ci95_low, ci95_high, identifiable}, correlation,
    residual_rms and predicted_not_fitted; calibrated.toml loads, carries the fitted value and
    a provenance naming the measured file and the fit; the rv40e preset is unchanged."""
    from flexrv.cli import main
    from flexrv.design import preset_path

    before = preset_path("rv40e").read_bytes()
    truth = {"second_stage.modification_equidistant_mm": 0.0062}
    m = _measured(tmp_path, truth, seed=3)
    out = tmp_path / "cal"
    main(
        [
            "calibrate",
            "rv40e",
            "--measured",
            m.path,
            "--free",
            "second_stage.modification_equidistant_mm=0.0025:0.0075",
            "--workers",
            "1",
            "--out",
            str(out),
            "--json",
        ]
    )
    d = json.loads(capsys.readouterr().out)
    v = d["identified"]["second_stage.modification_equidistant_mm"]
    assert set(v) >= {"value", "ci95_low", "ci95_high", "identifiable"}
    assert v["identifiable"] and v["ci95_low"] <= 0.0062 <= v["ci95_high"]
    assert d["correlation"]["matrix"] == [[1.0]] and d["residual_rms"] > 0
    assert d["predicted_not_fitted"][0]["comparison"]["lost_motion_predicted_arcmin"] > 0
    cal = load(out / "calibrated.toml")
    assert cal.second_stage.modification_equidistant_mm == pytest.approx(v["value"], rel=1e-12)
    prov = cal.provenance["second_stage.modification_equidistant_mm"]
    assert "loop.csv" in prov and "calibrated by flexrv calibrate" in prov
    assert preset_path("rv40e").read_bytes() == before


def test_calibrate_bad_free_option(tmp_path, capsys):
    """A bad --free: exit 2, one message naming the option and what is allowed."""
    from flexrv.cli import main

    m = _measured(tmp_path, {}, seed=4)
    for bad, text in (
        ("second_stage.modification_equidistant_mm", "FIELD=LO:HI"),
        ("nope.field=0:1", "no field"),
        ("second_stage.modification_equidistant_mm=0.006:0.007", "outside the range"),
        ("contact.pin_law=0:1", "not a numeric"),
    ):
        with pytest.raises(SystemExit) as exc:
            main(["calibrate", "rv40e", "--measured", m.path, "--free", bad, "--out", str(tmp_path / "x")])
        assert exc.value.code == 2
        err = " ".join(capsys.readouterr().err.split())
        assert "--free" in err and text in err, err


@pytest.mark.slow
def test_calibration_workflow_coverage_twenty_draws(tmp_path):
    """The workflow's full study (a): over 20 draws (truths inside the middle 60 % of the
    plausible ranges, independent noise seeds) each field's 95 % interval covers its truth in
    at least 17; the series pair is not identifiable; (b) the rv40e estimates give a loop
    secant far above seed004's 89 N m/arcmin (> 120) and the table holds one row per field."""
    from flexrv.workflows.calibration import DRAWS, FREE, SEED004_FIELDS, run

    r = run(tmp_path / "calibration")
    rt = r.numbers["round_trip"]
    assert rt["draws"] == DRAWS
    for k in FREE:
        assert rt["covered"][k] >= 17, (k, rt["covered"])
    assert not any(v["identifiable"] for v in r.numbers["series_pair"]["identified"].values())
    s = r.numbers["seed004"]
    assert s["target_Nm_per_arcmin"] == pytest.approx(89.0, abs=0.05)
    assert len(s["fields"]) == len(SEED004_FIELDS) and s["fields"][0]["secant_at_estimate"] > 120


@pytest.mark.slow
def test_calibration_workflow_smoke(tmp_path):
    """`flexrv workflow calibration --smoke`: two draws, both covered; summary written."""
    from flexrv.workflows.calibration import FREE, run

    r = run(tmp_path / "cal", smoke=True)
    assert all(r.numbers["round_trip"]["covered"][k] == 2 for k in FREE)
    assert (tmp_path / "cal" / "summary.md").read_text().startswith("# Calibration")
