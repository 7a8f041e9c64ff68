"""Batched sweeps: several cases per dask task give the same records as one case per
task, a sweep stopped part-way resumes with the stored cases, and the CPU account
adds what it is given."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import flexrv.sweep as sw
from flexrv.sweep import CpuAccount, batch_size, load_spec, run_sweep

ROOT = Path(__file__).resolve().parent.parent

SPEC = """
name = "batching"
preset = "rv40e"
task = "tests.sweep_tasks:slow_ratio"
outputs = ["kinematics.ratio", "k1"]

[options]
fail_above = 1.25

[grid]
"second_stage.eccentricity_mm" = [1.0, 1.1, 1.2, 1.3]
"first_stage.sun_teeth" = [16, 15]
"""


def test_batch_size():
    """n cases over 4 batches per worker, rounded up, within [1, MAX_BATCH]."""
    assert batch_size(1000, 2) == sw.MAX_BATCH == 32
    assert batch_size(40, 2) == 5  # ceil(40 / 8)
    assert batch_size(8, 2) == 1
    assert batch_size(9, 2) == 2
    assert batch_size(0, 2) == 1
    assert batch_size(100, 0) == 25  # no worker known: treated as one, ceil(100 / 4)


def test_cpu_account_adds_what_it_is_given(monkeypatch):
    """client_s is the process-CPU difference between start and stop, workers_s the sum of
    the batches' worker times; process_cpu_s is getrusage(SELF) user + system."""

    class Usage:
        ru_utime, ru_stime = 3.25, 0.5

    monkeypatch.setattr("resource.getrusage", lambda who: Usage())
    assert sw.process_cpu_s() == 3.75
    readings = iter([10.0, 10.5])
    monkeypatch.setattr(sw, "process_cpu_s", lambda: next(readings))
    acc = CpuAccount()
    acc.start()
    acc.add_batch(2.0, 3)
    acc.add_batch(3.0, 2)
    acc.stop()
    assert acc.client_s == pytest.approx(0.5) and acc.workers_s == 5.0
    assert acc.client_over_workers == pytest.approx(0.1)
    d = acc.as_dict()
    assert d["batches"] == 2 and d["cases"] == 5 and d["client_cpu_s"] == pytest.approx(0.5)
    assert CpuAccount().client_over_workers != CpuAccount().client_over_workers  # NaN without worker time


def test_run_batch_equals_run_case_on_tolerance_draws():
    """Three draws of the rv40e tolerance preset (the tolerance study's cases, its task at a
    coarse resolution): one batch on this process gives exactly the records of the cases
    run one by one from the designs the sweep validated (same numbers, bit for bit)."""
    from flexrv.studies.tolerance import StudyConfig, load_design_and_tolerances, plan_cases
    from flexrv.sweep import SweepSpec, base_design, build_cases, run_batch, run_case

    reducer, tol, _ = load_design_and_tolerances("rv40e", "rv40e")
    cfg = StudyConfig(design="rv40e", tolerances="rv40e", samples=3, seed=5, what_if_samples=0)
    _, parts = plan_cases(cfg, reducer, tol)
    options = {"crank_revolutions": 0.1, "points_per_mesh": 2}
    spec = SweepSpec(
        name="t",
        preset="rv40e",
        task="flexrv.studies.tolerance:te_task",
        outputs=["te_pp_arcsec"],
        options=options,
        cases=[{"errors": c[4]} for c in parts["cases"]],
    )
    cases = build_cases(spec)
    records, cpu = run_batch(base_design(spec), [c.overrides for c in cases], spec.task, options)
    single = [run_case(c.design, spec.task, options) for c in cases]
    assert cpu > 0.0 and len(records) == 3
    for a, b in zip(records, single):
        assert a["status"] == b["status"] == "ok"
        timing = ("solve_time_s",)
        assert {k: v for k, v in a["result"].items() if k not in timing} == {
            k: v for k, v in b["result"].items() if k not in timing
        }
    assert len({r["result"]["te_pp_arcsec"] for r in records}) == 3  # three different builds


def test_batched_sweep_stopped_resumes_same_as_unbatched(tmp_path, monkeypatch):
    """A sweep of 8 cases in batches of 3 is stopped while its second batch is being stored
    (after 4 case files); the rerun computes only the 4 missing cases, leaves the stored
    files untouched, and every record equals that of a sweep run one case per task. The
    CPU account counts every computed case, and the workers' batch times cover the cases'
    own CPU times."""
    sys.path.insert(0, str(ROOT))
    monkeypatch.setenv("PYTHONPATH", f"{ROOT}:{__import__('os').environ.get('PYTHONPATH', '')}")
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(SPEC)
    spec = load_spec(spec_path)

    reference = run_sweep(spec, out_dir=tmp_path / "single", n_workers=1, progress=False, batch=1, plots=False)
    assert reference.cpu.batches == 8 and reference.cpu.cases == 8

    write = sw._write_case
    stored = []

    def stop_after_four(out, case, record):
        if len(stored) == 4:
            raise KeyboardInterrupt
        write(out, case, record)
        stored.append(case.case_id)

    monkeypatch.setattr(sw, "_write_case", stop_after_four)
    out = tmp_path / "batched"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, out_dir=out, n_workers=1, progress=False, batch=3, plots=False)
    monkeypatch.setattr(sw, "_write_case", write)
    cases_dir = out / "cases"
    before = {p.name: (p.stat().st_mtime_ns, p.read_text()) for p in cases_dir.glob("*.json")}
    assert len(before) == 4

    again = run_sweep(spec, out_dir=out, n_workers=1, progress=False, batch=3, plots=False)
    assert again.skipped == 4 and again.computed == 4 and again.failed == reference.failed == 2
    assert again.cpu.cases == 4 and again.cpu.batches == 2
    for name, (mtime, text) in before.items():
        assert (cases_dir / name).stat().st_mtime_ns == mtime and (cases_dir / name).read_text() == text
    records = {p.name: json.loads(p.read_text()) for p in cases_dir.glob("*.json")}
    ref = {p.name: json.loads(p.read_text()) for p in (tmp_path / "single" / "cases").glob("*.json")}
    assert set(records) == set(ref)
    for name, r in records.items():
        assert r["status"] == ref[name]["status"] and r.get("result") == ref[name].get("result")
        assert r.get("error") == ref[name].get("error")
    computed = [records[n] for n in records if n not in before]
    assert again.cpu.workers_s >= sum(r["cpu_time_s"] for r in computed) > 0.0


@pytest.mark.parametrize("bad", [0, -1, 2.5, True])
def test_bad_batch_refused_before_anything(tmp_path, bad):
    """--batch must be an integer >= 1: one ConfigError naming it, nothing written."""
    from flexrv.errors import ConfigError

    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(SPEC)
    with pytest.raises(ConfigError, match=r"--batch .*integer >= 1"):
        run_sweep(load_spec(spec_path), out_dir=tmp_path / "o", n_workers=1, progress=False, batch=bad)
    assert not (tmp_path / "o").exists()
