"""Where workflow outputs go (./results/NAME, ./results/NAME-smoke), the smoke banner,
the References section, table number formatting and the generated report
(REPORT.md, prose computed from the numbers it shows). No simulation: seconds."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from flexrv.workflows import _common as wc


def _result(smoke: bool) -> wc.WorkflowResult:
    r = wc.WorkflowResult("demo", "Demo workflow", ["004 (stiffness)"], smoke=smoke)
    r.compare("stiffness", "N m/rad", 3.06e5, 6214726455202.804, "a big number")
    r.tables["t"] = [{"a [N]": 1234.5678, "b [-]": 3}]
    return r


def test_default_out_is_under_cwd_and_smoke_is_separate(tmp_path, monkeypatch):
    """Like ``flexrv simulate``: ./results of the current directory; smoke -> NAME-smoke."""
    monkeypatch.chdir(tmp_path)
    assert wc.default_out("lubrication") == tmp_path / "results" / "lubrication"
    assert wc.default_out("lubrication", smoke=True) == tmp_path / "results" / "lubrication-smoke"
    out = _result(True).save()
    assert out == tmp_path / "results" / "demo-smoke"
    out = _result(False).save()
    assert out == tmp_path / "results" / "demo"


def test_smoke_summary_says_so_at_the_top_and_nested_summaries_too(tmp_path):
    (tmp_path / "rigid").mkdir()
    (tmp_path / "rigid" / "summary.md").write_text("# Simulation\n")
    _result(True).save(tmp_path)
    head = (tmp_path / "summary.md").read_text().splitlines()[:3]
    assert "SMOKE RUN" in head[0] and head[2].startswith(wc.SMOKE_BANNER[:20])
    assert (tmp_path / "rigid" / "summary.md").read_text().startswith(wc.SMOKE_BANNER)
    full = _result(False).summary_markdown()
    assert "SMOKE" not in full


def test_summary_has_references_and_formatted_numbers():
    text = _result(False).summary_markdown()
    assert "## References" in text and "`seed004`" in text and "docs/references.md" in text
    assert "6214726455202" not in text and "6.215e+12" in text
    assert "| 1235 | 3 |" in text


@pytest.mark.parametrize(
    "value, cell",
    [
        (6214726455202.804, "6.215e+12"),
        (0.0, "0"),
        (1e-5, "1.000e-05"),
        (12.3456, "12.35"),
        (17138.2, "17138"),
        (None, "–"),
        (7, "7"),
        ("1 .. 2", "1 .. 2"),
    ],
)
def test_fmt(value, cell):
    assert wc._fmt(value) == cell


def _compare_json(folder, rigid_pp, flex_pp, d_mean=0.25):
    folder.mkdir(parents=True)
    r = {"te_min_arcsec": -1.5, "te_max_arcsec": -1.5 + rigid_pp, "te_mean_arcsec": 0.5, "te_pp_arcsec": rigid_pp}
    f = dict(r, te_mean_arcsec=0.5 + d_mean, te_pp_arcsec=flex_pp)
    (folder / "compare.json").write_text(json.dumps({"rigid": r, "flexible": f}))


def test_report_prose_follows_the_numbers(tmp_path):
    """Same file layout, different numbers -> different words: a 0.25 arcsec mean change
    against a 3.75 arcsec ripple (6.7 %) is 'significant', against 10 arcsec (2.5 %)
    'negligible'; a ripple ratio equal to the seeds' (88.2/46.8 = 1.885) is 'consistent
    with the seeds', a ratio of 1 'unlike the seeds'."""
    _compare_json(tmp_path / "a" / "rigid_vs_flexible", 3.75, 3.75 * 88.2 / 46.8)
    _compare_json(tmp_path / "b" / "rigid_vs_flexible", 10.0, 10.0)
    a = "\n".join(wc.answer_section(tmp_path / "a"))
    b = "\n".join(wc.answer_section(tmp_path / "b"))
    assert "+0.25 arcsec in the mean (significant" in a and "consistent with the seeds" in a
    assert "+0.25 arcsec in the mean (negligible" in b and "unlike the seeds" in b
    assert "ratio flexible/rigid of 1.88 against the seeds' 1.88" in a


def test_report_is_generated_full_and_smoke_kept_apart(tmp_path):
    """REPORT.md from full runs only, REPORT-smoke.md from the -smoke folders only; the tracked
    README.md is not written."""
    from flexrv.cli import app

    _result(False).save(tmp_path / "demo")
    _result(True).save(tmp_path / "demo-smoke")
    (tmp_path / "rv40e_rigid_sim_20261123").mkdir()  # a `flexrv simulate` run in the same ./results
    (tmp_path / "rv40e_rigid_sim_20261123" / "summary.md").write_text("# Simulation rv40e\n")
    _compare_json(tmp_path / "rigid_vs_flexible-smoke", 3.0, 3.0)
    r = CliRunner().invoke(app, ["report", "--results", str(tmp_path), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["sections"] == ["demo"]
    full = (tmp_path / "REPORT.md").read_text()
    assert "SMOKE" not in full and "## Answer" not in full and "Demo workflow" in full
    assert full.count("## References") == 1 and "Simulation rv40e" not in full
    r = CliRunner().invoke(app, ["report", "--results", str(tmp_path), "--smoke", "--json"])
    assert json.loads(r.stdout)["sections"] == ["demo-smoke"]  # the compare.json folder has no summary
    smoke = (tmp_path / "REPORT-smoke.md").read_text()
    assert smoke.splitlines()[0].endswith("(SMOKE RUNS)") and "## Answer" in smoke
    assert not (tmp_path / "README.md").exists()


def test_workflows_run_by_name_without_path_tricks():
    """The workflows are a subpackage of flexrv (installed with it): no sys.path edit."""
    import importlib
    import sys

    before = list(sys.path)
    mod = importlib.import_module("flexrv.workflows.kinematic_validation")
    assert callable(mod.run) and sys.path == before
    from flexrv.cli.workflows import Workflow

    for name in Workflow:
        assert importlib.util.find_spec(f"flexrv.workflows.{name.value}") is not None
