"""`flexrv ehl` command (flexrv.cli.ehl)."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.cli import app
from flexrv.errors import InputError


def test_ehl_preset_json(tmp_path):
    """--preset rv221 --json: inputs are the most-loaded ball of the main bearing (checked
    against ball_load_distribution) at the carrier speed 1500 r/min / 221 with
    u = (d_m/4)(1 - g^2) w_c (Harris ch. 8); outputs within 35 % of Hamrock-Dowson on 33^2,
    p_max near p_H, and a PNG is written."""
    from flexrv.analysis.bearing_load import ball_load_distribution
    from flexrv.contact.hertz import effective_modulus
    from flexrv.design import load
    from flexrv.geometry.bearing import BallBearingGeometry

    png = tmp_path / "ehl.png"
    res = CliRunner().invoke(app, ["ehl", "--preset", "rv221", "--grid", "33", "--json", "--png", str(png)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    inp, out = data["inputs"], data["outputs"]
    red = load("rv221")
    geom = BallBearingGeometry.from_design(red.main_bearing)
    e_eff = effective_modulus(208e9, 0.3, 208e9, 0.3)  # GCr15 balls and rings (rv221.toml)
    np.testing.assert_allclose(inp["reduced_modulus_Pa"], e_eff, rtol=1e-12)
    q = ball_load_distribution(geom, float(e_eff)).max_load
    np.testing.assert_allclose(inp["load_N"], q, rtol=1e-9)
    w_c = 1500.0 * 2 * math.pi / 60.0 / 221.0
    gam = geom.ball_diameter * math.cos(geom.contact_angle) / geom.pitch_diameter
    np.testing.assert_allclose(
        inp["entrainment_speed_m_s"], 0.25 * geom.pitch_diameter * (1 - gam**2) * w_c, rtol=2e-3
    )  # loaded vs nominal contact angle
    assert inp["grid"] == 33 and inp["viscosity_Pa_s"] == red.lubricant.viscosity_Pa_s
    np.testing.assert_allclose(
        inp["roelands_pressure_viscosity_1_Pa"], 0.68 * (math.log(0.13) + 9.67) / 1.96e8, rtol=1e-12
    )  # Roelands 1966 slope at p -> 0
    assert abs(out["h_central_m"] / out["hamrock_dowson_h_central_m"] - 1) < 0.35
    assert 1e-8 < out["h_min_m"] < out["h_central_m"] < 1e-6  # EHL films: 0.01-1 um
    assert abs(out["p_max_Pa"] / out["hertz_pressure_Pa"] - 1) < 0.1
    assert out["load_error"] < 1e-3 and out["residual"] < 1e-6
    assert png.exists() and png.stat().st_size > 10000


def test_ehl_explicit_case_table():
    res = CliRunner().invoke(
        app, ["ehl", "--load-n", "100", "--speed-m-s", "1", "--rx-m", "0.01", "--ry-m", "0.04", "--grid", "33"]
    )
    assert res.exit_code == 0, res.output
    assert "h_central_m" in res.output and "explicit" in res.output


def test_ehl_incomplete_explicit_case():
    res = CliRunner().invoke(app, ["ehl", "--load-n", "100", "--json"])
    assert isinstance(res.exception, InputError)
    assert "--speed-m-s" in str(res.exception)


def test_ehl_grid_refinement_reported():
    """The JSON reports the grid actually used, the change of h_c from the next-coarser grid and
    whether it met --grid-tol; a tolerance the capped refinement cannot meet is reported as a
    warning, not an error."""
    args = ["ehl", "--load-n", "100", "--speed-m-s", "1", "--rx-m", "0.01", "--ry-m", "0.04", "--json"]
    res = CliRunner().invoke(app, args + ["--grid-tol", "0.001", "--max-grid", "129"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    out = data["outputs"]
    assert out["grid_used"] == 129 and not out["grid_converged"] and out["grid_change"] > 0.001
    assert data["inputs"]["grid_tol"] == 0.001 and "not grid-converged" in data["warnings"][0]
    res = CliRunner().invoke(app, args)
    out = json.loads(res.stdout)["outputs"]
    assert out["grid_converged"] and out["grid_change"] < 0.02 and out["grid_used"] >= 129


def test_explicit_case_outside_the_model_is_flagged():
    """A contact whose Hertz semi-axis exceeds the radius of curvature (ry -> 1e30 m:
    a = 34.7 m on rx = 5 mm) is refused before solving, naming the options and the
    half-space assumption (between HERTZ_SIZE_LIMIT x the radius and the radius a result
    carries a warning); a contact well inside it carries none; a speed the solver cannot
    handle is one InputError naming the inputs, not a LinAlgError."""
    from flexrv.cli.ehl import HERTZ_SIZE_LIMIT, ehl_case
    from flexrv.errors import InputError

    with pytest.raises(InputError, match=r"--ry-m 1e\+30.*half-space"):
        ehl_case("rv221", load_n=1000.0, speed_m_s=1.0, rx_m=0.005, ry_m=1e30, grid=65, grid_tol=None)
    assert HERTZ_SIZE_LIMIT < 1
    report, _ = ehl_case("rv221", load_n=1000.0, speed_m_s=1.0, rx_m=0.005, ry_m=0.05, grid=65, grid_tol=None)
    assert not any("Hertz" in w for w in report.get("warnings", []))
    with pytest.raises(InputError, match="--speed-m-s"):
        ehl_case("rv221", load_n=1000.0, speed_m_s=1e-30, rx_m=0.005, ry_m=0.05, grid=65, grid_tol=None)
    with pytest.raises(InputError, match="--load-n"):
        ehl_case("rv221", load_n=-1.0, speed_m_s=1.0, rx_m=0.005, ry_m=0.05, grid=65, grid_tol=None)
