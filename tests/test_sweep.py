"""Resumable dask sweeps: a sweep killed part-way finishes only the missing cases,
keeps finished ones untouched, and records failing cases without stopping."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flexrv.cache import finished_files
from flexrv.errors import ConfigError
from flexrv.sweep import load_spec, run_sweep

ROOT = Path(__file__).resolve().parent.parent

SPEC = """
name = "test_sweep"
preset = "rv40e"
task = "tests.sweep_tasks:slow_ratio"
outputs = ["kinematics.ratio", "k1"]

[options]
delay = {delay}
fail_above = 1.25

[grid]
"second_stage.eccentricity_mm" = [1.0, 1.1, 1.2, 1.3]
"first_stage.sun_teeth" = [16, 15]
"""


def _spec(tmp_path: Path, delay: float) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(SPEC.format(delay=delay))
    return path


def test_spec_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name="x"\npreset="rv40e"\ntask="design"\noutputs=[]\nbogus=1\n[grid]\n"a"=[1]\n')
    with pytest.raises(ConfigError, match="bogus"):
        load_spec(bad)
    bad.write_text('name="x"\npreset="rv40e"\ntask="design"\noutputs=[]\n[grid]\n"second_stage.nope"=[1]\n')
    with pytest.raises(ConfigError, match="second_stage.nope"):
        run_sweep(load_spec(bad), out_dir=tmp_path / "o", progress=False)


def test_sweep_killed_and_resumed(tmp_path):
    spec_path = _spec(tmp_path, delay=1.5)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", "sweep", str(spec_path), "--out", str(out), "--workers", "2", "--json"],
        env=env,
        cwd=tmp_path,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    cases_dir = out / "cases"
    deadline = time.time() + 120
    while time.time() < deadline:
        if len(finished_files(cases_dir)) >= 2:
            break
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done_before = {p.name: (p.stat().st_mtime_ns, p.read_text()) for p in finished_files(cases_dir)}
    total = 8
    assert 2 <= len(done_before) < total, "the kill must land part-way through the sweep"

    sys.path.insert(0, str(ROOT))
    os.environ["PYTHONPATH"] = env["PYTHONPATH"]
    summary = run_sweep(load_spec(spec_path), out_dir=out, n_workers=2, progress=False)
    assert summary.total == total
    assert summary.skipped == len(done_before)
    assert summary.computed == total - len(done_before)
    for name, (mtime, text) in done_before.items():  # nothing finished was recomputed
        path = cases_dir / name
        assert path.stat().st_mtime_ns == mtime and path.read_text() == text
    records = [json.loads(p.read_text()) for p in finished_files(cases_dir)]
    assert len(records) == total
    failed = [r for r in records if r["status"] != "ok"]
    # e = 1.3 (x2 sun variants) raise in the task
    assert len(failed) == 2 and summary.failed == 2
    ok = [r for r in records if r["status"] == "ok"]
    for r in ok:  # numbers: ratio 1 + 32*40/(z_s*1)
        zs = r["overrides"]["first_stage.sun_teeth"]
        assert r["result"]["kinematics"]["ratio"] == pytest.approx(1 + 32 * 40 / zs)
    table = (out / "table.csv").read_text().splitlines()
    assert len(table) == total + 1 and "kinematics.ratio" in table[0]
    assert (out / "table.nc").exists() and summary.plots and all(p.exists() for p in summary.plots)

    # a second run computes nothing
    again = run_sweep(load_spec(spec_path), out_dir=out, n_workers=2, progress=False)
    assert again.computed == 0 and again.skipped == total


def test_invalid_case_refuses_the_sweep_before_running(tmp_path):
    """A case whose design is invalid (e = 5 mm: the disc profile undercuts) is found
    before any case runs: ConfigError naming the case, its override and the field,
    nothing written."""
    spec_path = tmp_path / "s.toml"
    spec_path.write_text(SPEC.format(delay=0.0) + '[[cases]]\n"second_stage.eccentricity_mm" = 5.0\n')
    out = tmp_path / "out"
    with pytest.raises(ConfigError, match=r"(?s)case 8 \(second_stage.eccentricity_mm = 5.0\).*eccentricity_mm"):
        run_sweep(load_spec(spec_path), out_dir=out, n_workers=1, progress=False)
    assert not out.exists()


def test_table_follows_a_changed_spec(tmp_path, monkeypatch):
    """A rerun with a grown spec that is killed before its first case finishes
    leaves a table.csv of the new spec (new cases marked missing), never the old one."""
    import flexrv.sweep as sw

    sys.path.insert(0, str(ROOT))
    spec_path = tmp_path / "s.toml"
    body = (
        'name = "grow"\npreset = "rv40e"\ntask = "tests.sweep_tasks:slow_ratio"\noutputs = ["kinematics.ratio"]\n'
        '[grid]\n"second_stage.eccentricity_mm" = {values}\n'
    )
    spec_path.write_text(body.format(values="[1.0]"))
    out = tmp_path / "out"
    summary = run_sweep(load_spec(spec_path), out_dir=out, n_workers=1, progress=False)
    assert summary.failed == 0
    assert (out / "table.csv").read_text().count("\n") == 2

    spec_path.write_text(body.format(values="[1.0, 1.1, 1.2]"))

    def killed(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sw, "pending_cases", killed)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(load_spec(spec_path), out_dir=out, n_workers=1, progress=False)
    rows = (out / "table.csv").read_text().strip().splitlines()[1:]
    assert len(rows) == 3
    assert sum('"ok"' in r for r in rows) == 1 and sum('"missing"' in r for r in rows) == 2


def test_spec_validated_before_running(tmp_path):
    head = 'name = "v"\npreset = "rv40e"\ntask = "design"\noutputs = ["kinematics.ratio"]\n'
    grid = '[grid]\n"second_stage.eccentricity_mm" = [1.0]\n'
    bad = tmp_path / "bad.toml"
    for body, key in (
        (head + "grid = 5\n", "grid"),
        (head + "cases = 5\n", "cases"),
        (head + 'options = "x"\n' + grid, "options"),
        (head.replace('"v"', '"../v"') + grid, "name"),
        (head.replace('"v"', '"a/b"') + grid, "name"),
    ):
        bad.write_text(body)
        with pytest.raises(ConfigError, match=key):
            load_spec(bad)
    bad.write_text(head.replace("kinematics.ratio", "kinematics.ratioo") + grid)
    with pytest.raises(ConfigError, match="kinematics.ratioo"):
        run_sweep(load_spec(bad), out_dir=tmp_path / "o", progress=False)
    assert not (tmp_path / "o").exists()
    with pytest.raises(ConfigError, match="--workers"):
        run_sweep(load_spec(spec_path_ok(tmp_path, head + grid)), out_dir=tmp_path / "o", n_workers=0, progress=False)


def spec_path_ok(tmp_path, body):
    path = tmp_path / "ok.toml"
    path.write_text(body)
    return path
