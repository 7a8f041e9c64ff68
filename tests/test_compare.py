"""``flexrv compare`` and ``flexrv view`` on a short rv40e run (coarse rings).

Checks numbers, not only files: the comparison's JSON equals the statistics
recomputed from the saved NetCDF; the dominant TE frequency is the spectrum's
largest non-DC bin; the view's VTU displacement equals the reduced body's
displacement of the recorded modal coordinates (mirrored for the second row); the
PNG shows the rings.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.cli import app

RING_SIZE = 0.003  #: coarse rv40e rings (default 1.7 mm)


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    from flexrv.studies.compare import run_compare

    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    out = tmp_path_factory.mktemp("compare")
    cmp = run_compare("rv40e", t_end=0.02, out_dir=out, flexible_options={"ring_options": {"size": RING_SIZE}})
    yield cmp
    del os.environ["FLEXRV_CACHE"]


def test_compare_writes_everything_and_numbers_match_netcdf(compared):
    from flexrv.post.results import load_results
    from flexrv.post.spectra import te_spectrum

    out = compared.out_dir
    for name in (
        "te_overlay.png",
        "te_spectrum.png",
        "ball_loads.png",
        "ring_deformation.png",
        "summary.md",
        "compare.json",
        "rigid/results.nc",
        "flexible/results.nc",
    ):
        assert (out / name).exists(), name
    numbers = json.loads((out / "compare.json").read_text())
    for model in ("rigid", "flexible"):
        res = load_results(out / model)
        te = res.steady("te").values
        assert numbers[model]["te_min_arcsec"] == pytest.approx(te.min(), abs=1e-9)
        assert numbers[model]["te_pp_arcsec"] == pytest.approx(np.ptp(te), abs=1e-9)
        freq, amp, marks = te_spectrum(res)
        assert numbers[model]["dominant_frequency_hz"] == pytest.approx(freq[1 + np.argmax(amp[1:])])
        assert numbers[model]["characteristic_frequencies_hz"] == pytest.approx(marks)
    assert numbers["flexible"]["max_ball_load_N"] > 0
    assert numbers["difference"]["te_pp_arcsec"] == pytest.approx(
        numbers["flexible"]["te_pp_arcsec"] - numbers["rigid"]["te_pp_arcsec"]
    )
    text = (out / "summary.md").read_text()
    # rv40e is not the seeds' reducer (rv221): no seed TE values, no prose about them
    assert "-25.2" not in text and "seed000/seed001 TE range" not in text and "No seed reference" in text
    assert numbers["seed"] is None


def test_compare_cli_rejects_unknown_part(tmp_path):
    r = CliRunner().invoke(app, ["compare", "rv40e", "--parts", "main_bearing,housing", "--out", str(tmp_path)])
    assert r.exit_code != 0
    assert "housing" in str(r.exception) and "crankshaft" in str(r.exception)


def test_view_png_and_pvd_match_the_reduced_bodies(compared, tmp_path):
    import meshio

    from flexrv.post.results import load_results
    from flexrv.viz.rings import render_rings_png, ring_bodies, write_pvd

    res = load_results(compared.out_dir / "flexible")
    png = render_rings_png(res, tmp_path / "rings.png")
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    assert (np.abs(img[..., :3] - img[0, 0, :3]).sum(axis=-1) > 0.1).mean() > 0.02  # rings drawn
    every = 7
    seen = []
    pvd = write_pvd(res, tmp_path / "vtu", every=every, notice=lambda frames, size: seen.append((frames, size)))
    n_frames = len(range(0, len(res.time), every))
    # the size estimate (uncompressed first frame x frames) is announced once and bounds the
    # written (compressed) size from above, within a factor 4
    written = sum(f.stat().st_size for f in (tmp_path / "vtu").glob("*.vtu"))
    assert len(seen) == 1 and seen[0][0] == n_frames
    assert written <= seen[0][1] <= 4 * written
    assert pvd.read_text().count("<DataSet") == 4 * n_frames  # 2 rings x 2 rows per frame
    bodies = ring_bodies(res)
    i = (n_frames - 1) * every
    body = bodies["outer"]
    q = res["ring_modal_outer"].values[i, 1]
    expected = body.displacement(q) * np.array([1.0, 1.0, -1.0])  # row 1: mirrored
    mesh = meshio.read(tmp_path / "vtu" / f"outer_row1_{i:06d}.vtu")
    used = np.unique(body.tris[:, :3])
    np.testing.assert_allclose(
        mesh.point_data["displacement"], expected[used], rtol=0, atol=1e-9 * np.abs(expected).max()
    )
    assert np.abs(expected).max() > 1e-10


def test_view_cli_on_rigid_result_says_why(compared):
    r = CliRunner().invoke(app, ["view", str(compared.out_dir / "rigid")])
    assert r.exit_code != 0
    assert "--model flexible" in str(r.exception)


def test_view_time_beyond_the_run_is_an_error(compared):
    """`view --time` outside the recorded interval names the option and the run's span (exit 2
    through the CLI's error handling)."""
    from flexrv.errors import InputError

    r = CliRunner().invoke(app, ["view", str(compared.out_dir / "flexible"), "--time", "5"])
    assert isinstance(r.exception, InputError) and "--time 5" in str(r.exception)


def test_view_loads_the_runs_cached_body_and_never_remeshes(compared, tmp_path, monkeypatch):
    """Issue 16: a saved flexible run records the identity (cache file + content key) of
    each reduced ring; view loads exactly that body, verified, without meshing. Gone
    from the cache, view refuses with how to rebuild it; ``--rebuild`` rebuilds it."""
    import json
    import shutil

    import flexrv.fem.body as fb
    from flexrv.post.results import load_results
    from flexrv.viz.rings import ring_bodies

    res = load_results(compared.out_dir / "flexible")
    ids = {part: o["identity"] for part, o in json.loads(res.attrs["flexible_bodies"]).items()}
    assert set(ids) == {"outer_ring", "inner_ring"}

    def no_meshing(*args, **kwargs):
        raise AssertionError("view re-meshed / re-reduced a ring")

    monkeypatch.setattr(fb, "reduce_part", no_meshing)
    bodies = ring_bodies(res)
    assert bodies["outer"].path.name == ids["outer_ring"]["cache_file"]
    # the body file gone (a cleared cache): a clear refusal naming the way back
    cache = fb.cache_dir()
    moved = tmp_path / "moved"
    moved.mkdir()
    for f in cache.glob(ids["outer_ring"]["cache_file"] + "*"):
        shutil.move(str(f), moved / f.name)
    try:
        with pytest.raises(fb.InputError, match=r"rebuild it by re-running the simulation.*--rebuild"):
            ring_bodies(res)
        monkeypatch.undo()
        assert ring_bodies(res, rebuild=True)["outer"].n_modes == bodies["outer"].n_modes
    finally:
        for f in moved.iterdir():
            shutil.move(str(f), cache / f.name)
