"""Post-processing: Results access, save/load round trip, spectra and the
stiffness-loop evaluation against closed forms; the CLI commands."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexrv.post.spectra import amplitude_spectrum
from flexrv.post.stiffness import evaluate_stiffness_test
from flexrv.units import ARCMIN_PER_RAD


@pytest.fixture(scope="module")
def short_run():
    from flexrv.simulation import Simulation

    return Simulation("rv40e").run(t_end=0.006, dt=1e-4)


def test_results_access_by_label(short_run):
    """res["TE [arcsec]"] and res["te"] are the same DataArray with units and the
    time coordinate; TE = theta_out - theta_in / i in arcsec (:cite:`seed000`)."""
    res = short_run
    te = res["TE [arcsec]"]
    assert te.attrs["units"] == "arcsec" and "time" in te.coords
    expected = (res["theta_out"].values - res["theta_in"].values / res.attrs["ratio"]) * 180 / np.pi * 3600
    assert np.allclose(te.values, expected)
    assert np.allclose(res["te"].values, te.values)
    with pytest.raises(KeyError):
        res["no such thing"]


def test_save_load_roundtrip(short_run, tmp_path):
    """All files are written; NetCDF data and attributes read back unchanged."""
    from flexrv.post.results import Results

    d = short_run.save(tmp_path / "run")
    for name in ("results.nc", "config.toml", "summary.md", "summary.json", "te.png", "speeds.png", "pin_forces.png"):
        assert (d / name).is_file(), name
    back = Results.load(d)
    assert np.array_equal(back["pin_force"].values, short_run["pin_force"].values)
    assert back.attrs["preset"] == "rv40e" and back.reducer == short_run.reducer
    summ = json.loads((d / "summary.json").read_text())
    assert summ["ratio_theoretical"] == pytest.approx(81.0)
    assert "Kinematic validation" in (d / "summary.md").read_text()


def test_amplitude_spectrum_of_a_sine():
    """Hann-windowed one-sided spectrum: a 3 arcsec sine at 320 Hz (:cite:`seed002`'s
    mesh frequency) on a trend shows a 3 +- 0.1 arcsec peak at 320 +- 2 Hz."""
    t = np.arange(0, 0.5, 1e-4)
    f, a = amplitude_spectrum(5.0 * t + 3.0 * np.sin(2 * np.pi * 320 * t), t)
    k = np.argmax(a)
    assert f[k] == pytest.approx(320, abs=2)
    assert a[k] == pytest.approx(3.0, abs=0.1)


def test_stiffness_loop_evaluation_closed_form():
    """A bilinear loop with known stiffness k, lost-motion band +-b and no
    hysteresis: rigidity k [N m/arcmin], lost motion 2 b (within the 3 % band)."""
    k = 100.0  # N m/arcmin
    b = 0.5  # arcmin
    tr = 400.0
    times = (0.0, 1.0, 3.0, 4.0)
    t = np.linspace(0, 4, 4001)
    torque = np.interp(t, [0, 1, 3, 4], [0, tr, -tr, 0])
    angle = (torque / k + np.sign(torque) * b) / ARCMIN_PER_RAD
    fig = evaluate_stiffness_test(t, torque, angle, times)
    assert fig.rigidity_Nm_per_arcmin == pytest.approx(k, rel=1e-6)
    assert fig.lost_motion_arcmin == pytest.approx(2 * b + 2 * 0.03 * tr / k, rel=1e-3)
    assert abs(fig.hysteresis_arcmin) < 1e-6


def test_cli_simulate_json(tmp_path):
    """`flexrv simulate rv40e --t-end 0.004 --json` writes the run directory and
    prints the summary numbers."""
    from typer.testing import CliRunner

    from flexrv.cli import app

    out = tmp_path / "cli_run"
    r = CliRunner().invoke(
        app, ["simulate", "rv40e", "--model", "rigid", "--t-end", "0.004", "--out", str(out), "--json"]
    )
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["ratio_theoretical"] == pytest.approx(81.0)
    assert {"te_min_arcsec", "te_max_arcsec", "te_pp_arcsec", "max_pin_force_N", "pins_in_contact_max"} <= set(data)
    assert (out / "results.nc").is_file()


def test_cli_rejects_bad_step():
    """A step beyond the allowed range is a clear InputError (exit code 2 via main)."""
    from flexrv.errors import InputError
    from flexrv.simulation import Simulation

    with pytest.raises(InputError, match="dt"):
        Simulation("rv40e").run(t_end=0.01, dt=1e-2)
