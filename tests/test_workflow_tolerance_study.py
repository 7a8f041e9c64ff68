"""Workflow ``tolerance_study`` (issue 13): the what-if restriction to chosen
tolerances, and the smoke run's bookkeeping checked against its own samples."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexrv.errors import InputError


def test_what_if_entries_restrict_the_cases():
    """what_if_entries = [a, b] with M = 3: N plain cases, then 2 x 2 x 3 what-if
    cases of exactly a and b (factors 0.5 and 2), the plain samples unchanged; an
    entry that is not in the tolerance set is an InputError naming it."""
    from flexrv.studies.tolerance import StudyConfig, load_design_and_tolerances, plan_cases

    red, tol, _ = load_design_and_tolerances("rv40e", "rv40e")
    keys = list(tol.entries)[:2]
    cfg = StudyConfig(design="rv40e", tolerances="rv40e", samples=5, what_if_samples=3, what_if_entries=keys)
    plan, parts = plan_cases(cfg, red, tol)
    cases = parts["cases"]
    assert [c[0] for c in cases[:5]] == ["sample"] * 5
    what_if = [c for c in cases if c[0] == "what_if"]
    assert len(cases) == 5 + 12 and len(what_if) == 12
    assert sorted({(c[2], c[3]) for c in what_if}) == sorted((k, f) for k in keys for f in (0.5, 2.0))
    _, full = plan_cases(StudyConfig(design="rv40e", tolerances="rv40e", samples=5, what_if_samples=3), red, tol)
    assert [c[4] for c in full["cases"][:5]] == [c[4] for c in cases[:5]]
    with pytest.raises(InputError, match="pins.no_such_um"):
        plan_cases(
            StudyConfig(design="rv40e", tolerances="rv40e", samples=5, what_if_entries=["pins.no_such_um"]), red, tol
        )


@pytest.mark.slow
def test_tolerance_study_smoke(tmp_path):
    """(slow: two small studies on a LocalCluster, about 1 min.) The smoke run (20
    samples, M = 4) writes the summary with the published values beside the batch's
    percentiles; its numbers agree with its own samples.nc: P50 / P95 of TE p-p and
    lost motion (numpy percentiles), the yield (fraction with TE p-p <= 60 arcsec
    and lost motion <= 1 arcmin), the unscaled what-if column (P95 of the first M
    samples); the three top tolerances are entries of the set and have what-if rows;
    the second study reused the 20 plain samples and computed only the 2 x 3 x 4
    what-if cases."""
    import xarray as xr

    from flexrv.workflows.tolerance_study import run

    r = run(tmp_path / "ts", smoke=True, workers=1)
    n = r.numbers
    ds = xr.load_dataset(tmp_path / "ts" / "study" / "samples.nc", engine="h5netcdf")
    te, lm = ds["te_pp_arcsec"].values, ds["lost_motion_arcmin"].values
    assert n["samples"] == 20 and np.all(np.isfinite(te)) and np.all(np.isfinite(lm))
    assert n["percentiles"]["te_pp_arcsec"]["P50"] == pytest.approx(np.percentile(te, 50), rel=1e-12)
    assert n["percentiles"]["lost_motion_arcmin"]["P95"] == pytest.approx(np.percentile(lm, 95), rel=1e-12)
    assert n["yield"]["yield"] == pytest.approx(np.mean((te <= 60.0) & (lm <= 1.0)), abs=1e-12)
    tol = json.loads(ds.attrs["tolerances"])
    assert len(n["top_tolerances"]) == 3 and set(n["top_tolerances"]) <= set(tol)
    assert sorted(w["tolerance"] for w in n["what_if"]) == sorted(n["top_tolerances"])
    for w in n["what_if"]:
        assert w["samples_used"] == 4
        assert w["p95_te_pp_arcsec"] == pytest.approx(np.percentile(te[:4], 95), rel=1e-12)
    study = json.loads((tmp_path / "ts" / "study" / "summary.json").read_text())
    assert study["skipped_existing"] == 20 and study["computed_now"] == 24
    text = (tmp_path / "ts" / "summary.md").read_text()
    assert text.startswith("# Tolerance study") and "SMOKE RUN" in text
    assert "about 60 (RV-80E, measured)" in text and "<= 1 (catalog)" in text
    assert (tmp_path / "ts" / "tolerance_study.png").stat().st_size > 10_000
