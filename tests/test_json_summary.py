"""`--json` carries what summary.md says in words: the steady flag and its reason of a
simulation, the notes, and every figure of a `te` run's summary."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest


def test_simulate_json_says_not_steady_like_summary_md(tmp_path):
    """A run that ends inside the ramps (rv40e, 4 ms): summary.md quotes the window as not steady
    with its reason; `--json` has ``"steady": false`` and the same reason and notes, word for word,
    as summary.json (the rule: flexrv.post.results.steady_window_rule)."""
    from typer.testing import CliRunner

    from flexrv.cli import app

    out = tmp_path / "run"
    r = CliRunner().invoke(
        app, ["simulate", "rv40e", "--model", "rigid", "--t-end", "0.004", "--out", str(out), "--json"]
    )
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    saved = json.loads((out / "summary.json").read_text())
    md = (out / "summary.md").read_text()
    assert data["steady"] is False and saved["steady_state"] is False
    assert data["steady_reason"] == saved["steady_note"] != ""
    assert "ramp" in data["steady_reason"] or "shorter" in data["steady_reason"]
    assert data["steady_reason"] in md
    assert data["notes"] == saved["notes"] and data["notes"]
    for note in data["notes"]:
        assert note in md


@pytest.fixture(scope="module")
def te_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("te") / "run"
    cp = subprocess.run(
        [sys.executable, "-m", "flexrv", "te", "rv40e", "--crank-revolutions", "0.05", "--points-per-mesh", "4"]
        + ["--json", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert cp.returncode == 0, cp.stderr
    return json.loads(cp.stdout), out


def test_te_json_carries_every_summary_figure(te_run):
    """Every key of a `te` run's summary.json (what summary.md is written from) is in `--json` with
    the same value, including the solver's words (unconverged positions, spectrum note)."""
    data, out = te_run
    saved = json.loads((out / "summary.json").read_text())
    missing = sorted(set(saved) - set(data))
    assert not missing
    for key, value in saved.items():
        if key == "stiffness_budget":
            continue
        assert json.loads(json.dumps(data[key])) == value, key
    assert data["unconverged_positions"] == 0
    md = (out / "summary.md").read_text()
    if "spectrum_note" in data:
        assert data["spectrum_note"] in md


def test_te_summary_md_states_unconverged_positions(te_run):
    """summary.md says in words how many positions did not converge, the number `--json` carries
    as ``unconverged_positions`` (absent from the text when all converged)."""
    from flexrv.design import load
    from flexrv.post.te import te_summary_markdown

    data, out = te_run
    saved = json.loads((out / "summary.json").read_text())
    assert "did not converge" not in (out / "summary.md").read_text()
    text = te_summary_markdown({**saved, "unconverged_positions": 3}, load("rv40e"))
    assert "3 positions did not converge" in text


def test_stiffness_test_json_carries_the_reading_summary_md_states():
    """A synthetic linear loop with play (k = 100 N m/arcmin, +-0.5 arcmin of play, T_r = 400 N m):
    the figures summary.md states beside the named ones (rated torque, fit range, lost-motion band
    and its angles, hysteresis angles at T = 0) are in ``reading()``, the dict `flexrv stiffness-test
    --json` prints, with the values summary.md writes (same attributes, 1e-12), and the lost-motion
    angles at +-3 % T_r read -0.5 - 0.12 and 0.5 + 0.12 arcmin (closed form, 1e-9)."""
    import numpy as np

    from flexrv.post.stiffness import evaluate_stiffness_test, stiffness_summary_markdown
    from flexrv.units import RAD_PER_ARCMIN

    rated, k, play = 400.0, 100.0, 0.5
    t = np.linspace(0.0, 4.0, 4001)
    torque = rated * np.interp(t, [0.0, 1.0, 3.0, 4.0], [0.0, 1.0, -1.0, 0.0])
    angle = (torque / k + play * np.sign(torque)) * RAD_PER_ARCMIN
    fig = evaluate_stiffness_test(t, torque, angle, (0.0, 1.0, 3.0, 4.0))
    reading = fig.reading()
    assert not set(reading) & set(fig.named())
    for key in ("rated_torque_Nm", "fit_range_low_Nm", "lost_motion_torque_Nm", "hysteresis_ascending_angle_arcmin"):
        assert key in reading
    assert reading["rated_torque_Nm"] == pytest.approx(rated, rel=1e-12)
    assert reading["lost_motion_torque_Nm"] == pytest.approx(0.03 * rated, rel=1e-12)
    assert reading["lost_motion_negative_angle_arcmin"] == pytest.approx(-(play + 0.03 * rated / k), rel=1e-9)
    assert reading["lost_motion_positive_angle_arcmin"] == pytest.approx(play + 0.03 * rated / k, rel=1e-9)
    md = stiffness_summary_markdown(fig, "synthetic", "rigid", 1.0, 1e-4, plot=None)
    assert f"{reading['fit_range_low_Nm']:.4g}" in md and f"{reading['lost_motion_torque_Nm']:.3g}" in md
