"""Batched evaluation of ``flexrv optimize`` candidates: draws split into chunks give the
record of one task, and the builds of one design share its error-free model constants
with the same answers."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

import flexrv.design.manufacturing as mf
import flexrv.model.bodies as prm
from flexrv.studies._opt_runner import Runner, Store, chunk_draws, join_chunks


def test_chunk_draws():
    """One chunk per candidate when the candidates fill 4 tasks per slot; otherwise enough
    consecutive, covering ranges (at most one per draw)."""
    assert chunk_draws(32, 20, 2) == [(0, 32)]
    assert chunk_draws(32, 8, 2) == [(0, 32)]
    assert chunk_draws(32, 1, 2) == [(0, 4), (4, 8), (8, 12), (12, 16), (16, 20), (20, 24), (24, 28), (28, 32)]
    assert chunk_draws(32, 3, 2) == [(0, 11), (11, 21), (21, 32)]
    assert chunk_draws(2, 1, 2) == [(0, 1), (1, 2)]
    assert chunk_draws(5, 1, 0) == [(0, 5)]  # inline: no split
    for n, c, s in ((33, 5, 2), (7, 2, 3), (1, 1, 4)):
        ch = chunk_draws(n, c, s)
        assert ch[0][0] == 0 and ch[-1][1] == n and all(a[1] == b[0] for a, b in zip(ch, ch[1:]))
        assert all(b > a for a, b in ch)


def test_join_chunks():
    """Nominal of the first chunk, draws concatenated in order, times summed; a failed chunk
    fails the candidate with its error."""
    a = {"status": "ok", "result": {"nominal": {"q": 1.0}, "draws": {"q": [1, 2]}}, "wall_time_s": 1, "cpu_time_s": 2}
    b = {"status": "ok", "result": {"nominal": {}, "draws": {"q": [3]}}, "wall_time_s": 3, "cpu_time_s": 4}
    j = join_chunks([a, b])
    assert j["result"] == {"nominal": {"q": 1.0}, "draws": {"q": [1, 2, 3]}}
    assert j["wall_time_s"] == 4 and j["cpu_time_s"] == 6 and j["status"] == "ok"
    bad = {"status": "failed", "error": "E: x", "wall_time_s": 1}
    f = join_chunks([a, bad])
    assert f["status"] == "failed" and f["error"] == "E: x" and f["wall_time_s"] == 2
    assert join_chunks([a]) is a


def test_chunked_store_record_equals_one_task(tmp_path, monkeypatch):
    """The analytic ZDT1 task with 5 common draws: a store whose runner offers 2 slots splits
    the single candidate into 5 chunks (one draw each) and stores the same record result as
    one task over all draws; the chunks after the first are asked without the nominal."""
    from tests.test_optimize import _analytic_problem

    p = _analytic_problem(draws=5)
    seen = []
    import tests.test_optimize as me

    orig = me.analytic_task

    def spy(design, draws, options):
        seen.append((len(draws), options.get("nominal", True)))
        return orig(design, draws, options)

    monkeypatch.setattr(me, "analytic_task", spy)
    one = Store(tmp_path / "one", p.task, p.draws, Runner(mode="inline"))
    (r1,) = one.evaluate([p.base], p.options)
    assert seen == [(5, True)]
    seen.clear()
    runner = Runner(mode="inline")
    monkeypatch.setattr(runner, "slots", lambda: 2)
    split = Store(tmp_path / "split", p.task, p.draws, runner)
    (r2,) = split.evaluate([p.base], p.options)
    assert seen == [(1, True)] + [(1, False)] * 4
    assert r2["result"] == r1["result"] and r2["id"] == r1["id"] and split.computed == 1
    (r3,) = split.evaluate([p.base], p.options)  # stored: read, not computed
    assert r3 == r2 and split.reused == 1 and len(seen) == 5


@pytest.fixture(scope="module")
def rv40e_draws():
    from flexrv.studies.optimize import OptimizeConfig, build_problem

    cfg = OptimizeConfig(
        "rv40e",
        vary=["second_stage.modification_equidistant_mm=0:0.015"],
        objectives=["lost_motion_p95_arcmin"],
        tolerances="rv40e",
        samples_per_design=2,
    )
    problem, _, _ = build_problem(cfg)
    return problem


def test_shared_nominal_constants_same_answers(rv40e_draws, monkeypatch):
    """rv40e, the nominal build and 2 grade-5 draws at a coarse resolution: the builds with
    the shared error-free constants give exactly (bit for bit) the figures of builds that
    compute them each; the body compliances are computed once instead of three times."""
    import flexrv.studies._modification_eval as me

    problem = rv40e_draws
    res = {"crank_revolutions": 0.1, "points_per_mesh": 2, "catalog_positions": 1, "force_tol": 1e-6, "max_iter": 200}
    calls = {"n": 0}
    body = prm._body_compliance_matrix

    def counted(reducer, name):
        calls["n"] += name == "carrier"  # (the discs' likewise)
        return body(reducer, name)

    monkeypatch.setattr(prm, "_body_compliance_matrix", counted)
    me._NOMINAL_MEMO.clear()
    shared = me.modification_task(problem.base, problem.draws, {"resolution": res})
    assert calls["n"] == 1
    orig = mf.shared_nominal_constants

    @contextlib.contextmanager
    def off(memo=None):
        yield

    monkeypatch.setattr(mf, "shared_nominal_constants", off)
    calls["n"] = 0
    each = me.modification_task(problem.base, problem.draws, {"resolution": res})
    assert calls["n"] == 3
    monkeypatch.setattr(mf, "shared_nominal_constants", orig)
    assert shared == each
    assert np.all(np.isfinite(shared["draws"]["lost_motion"]))
    assert shared["draws"]["lost_motion"][0] != shared["draws"]["lost_motion"][1]  # different builds


def test_nominal_constants_are_those_of_the_error_free_design(rv40e_draws):
    """Inside the sharing block a design with errors gets the constants of its error-free
    design, equal to the ones computed without sharing for the design with errors (the
    constants do not read the errors), and each call returns its own arrays."""
    from flexrv.analysis.pin_load import pin_contact_constant
    from flexrv.analysis.torsional import housing_model_compliance
    from flexrv.design import from_dict
    from flexrv.design.manufacturing import nominal_design

    red = from_dict({**rv40e_draws.base, "errors": rv40e_draws.draws[0]})

    def bodies(r):
        return tuple(prm.body_compliance_matrix(r, b) for b in prm.BODY_PARTS)

    plain = bodies(red), pin_contact_constant(red).k, housing_model_compliance(red)
    with mf.shared_nominal_constants():
        first = bodies(nominal_design(red))
        again = bodies(red), pin_contact_constant(red).k, housing_model_compliance(red)
    assert plain[1] == again[1] > 0.0 and plain[2] == again[2] > 0.0
    for i in (0, 1):
        assert np.array_equal(plain[0][i], first[i]) and np.array_equal(plain[0][i], again[0][i])
        assert again[0][i] is not first[i] and again[0][i].size


def test_chunked_candidate_interrupted_is_recomputed(tmp_path, monkeypatch):
    """A candidate split into 5 chunks, interrupted at its third chunk, leaves no record (a
    record is stored only whole); the rerun computes it and stores the record of one task."""
    import tests.test_optimize as me
    from tests.test_optimize import _analytic_problem

    p = _analytic_problem(draws=5)
    (ref,) = Store(tmp_path / "ref", p.task, p.draws, Runner(mode="inline")).evaluate([p.base], p.options)
    orig = me.analytic_task
    calls = {"n": 0}

    def stop_third(design, draws, options):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return orig(design, draws, options)

    runner = Runner(mode="inline")
    monkeypatch.setattr(runner, "slots", lambda: 2)
    monkeypatch.setattr(me, "analytic_task", stop_third)
    store = Store(tmp_path / "run", p.task, p.draws, runner)
    with pytest.raises(KeyboardInterrupt):
        store.evaluate([p.base], p.options)
    assert not list((tmp_path / "run" / "evaluations").glob("*.json"))
    monkeypatch.setattr(me, "analytic_task", orig)
    again = Store(tmp_path / "run", p.task, p.draws, runner)
    (rec,) = again.evaluate([p.base], p.options)
    assert again.computed == 1 and rec["result"] == ref["result"]
