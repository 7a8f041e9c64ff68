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
