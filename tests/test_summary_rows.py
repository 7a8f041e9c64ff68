"""The run summary's keys live in one table (flexrv.post.stats.SUMMARY_KEYS): summary.json
and summary.md are rendered from it and from the declared outputs of the results file,
so an output declared with a summary row shows up in both without any code naming it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from flexrv.post.stats import _REDUCE, SUMMARY_KEYS

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A results file of rv40e's rigid model from a few loaded states (no time integration)."""
    from flexrv.design import load
    from flexrv.model.factory import build_model
    from flexrv.post.io import save
    from flexrv.post.results import results_from_states

    model = build_model(load("rv40e"), exudyn=False)
    n = 6
    q = np.tile(model.q0, (n, 1))
    for k in range(model.params.n_discs):
        q[:, model.slice(f"disc{k}").start + 2] += 1.5e-4
    v = np.zeros_like(q)
    t = np.linspace(0.0, 5e-4, n)
    res = results_from_states(model, t, q, v, dt=1e-4)
    res.attrs.update(steady_start_s=0.0, steady_end_s=float(t[-1]))
    return save(res, tmp_path_factory.mktemp("run") / "run")


def test_an_extra_declared_output_reaches_summary_json_and_md(run_dir, tmp_path):
    """Read the results file back, add one declared output with a summary row (attributes
    only: units, long name, summary_rows) and save: summary.json lists the row under
    "elements" with the reduced value (max |x| of the window, closed form) and its units,
    summary.md has it in the force-element table."""
    from flexrv.post.io import save
    from flexrv.post.results import Results

    res = Results.load(run_dir)
    n = res.ds.sizes["time"]
    x = np.linspace(-3.0, 2.0, n)
    res.ds["extra_moment"] = ("time", x)
    res.ds["extra_moment"].attrs.update(
        units="N m",
        long_name="an extra declared output",
        summary_rows=json.dumps([["max_extra_moment_Nm", "N m", "largest |extra moment|", "max_abs"]]),
    )
    d = save(res, tmp_path / "again")
    summ = json.loads((d / "summary.json").read_text())
    row = summ["elements"]["max_extra_moment_Nm"]
    assert row == {"value": 3.0, "units": "N m", "description": "largest |extra moment|", "source": "extra_moment"}
    md = (d / "summary.md").read_text()
    assert re.search(r"\| max_extra_moment_Nm \| 3(\.0*)? \| N m \| largest \|extra moment\| \|", md)


def test_summary_keys_render_from_the_table(run_dir):
    """Every listed key of SUMMARY_KEYS the run has is in summary.json and in summary.md's
    table with the units of its declared source output; a key's reduction is a known one."""
    summ = json.loads((run_dir / "summary.json").read_text())
    md = (run_dir / "summary.md").read_text()
    for row in SUMMARY_KEYS:
        assert row.reduce == "" or row.reduce in _REDUCE, row
        if row.listed and row.key in summ and row.group != "derived":
            unit = summ["units"][row.key]
            assert f"| {row.key} | " in md and md.split(f"| {row.key} | ")[1].split("\n")[0].endswith(f" | {unit} |")
    assert summ["units"]["te_pp_arcsec"] == "arcsec" and summ["units"]["efficiency"] == "-"
    assert summ["te_pp_arcsec"] == pytest.approx(summ["te_max_arcsec"] - summ["te_min_arcsec"], rel=1e-12)


def test_summary_keys_are_spelled_in_one_place():
    """The run summary's writers (flexrv/post/io.py: summary.json and summary.md; results.py)
    spell none of the table's keys: they render the table (the quasi-static TE summary of
    post/te.py and the measured figures of post/definitions.py are other summaries)."""
    post = ROOT / "flexrv" / "post"
    hits = []
    for name in ("io.py", "results.py"):
        text = (post / name).read_text()
        hits += [f"{name}: {row.key}" for row in SUMMARY_KEYS if f'"{row.key}"' in text]
    assert not hits, hits


def test_every_summary_number_is_in_the_table(run_dir):
    """No number of summary.json escapes the table: each numeric top-level key is a
    SUMMARY_KEYS row, a declared friction output's mean (friction_keys) or run metadata
    (the steady window and the ratios)."""
    summ = json.loads((run_dir / "summary.json").read_text())
    meta = {"steady_revolutions", "ratio_theoretical", "ratio_simulated", "ratio_simulated_over_theoretical"}
    known = {row.key for row in SUMMARY_KEYS} | meta | set(summ.get("friction_keys", ()))
    numbers = [k for k, v in summ.items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    assert "te_pp_arcsec" in numbers and "mean_dissipation_W" in numbers
    assert [k for k in numbers if k not in known] == []
