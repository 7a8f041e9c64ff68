"""Design report: structure, JSON round trip, key numbers consistent with the models."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.analysis.report import design_report
from flexrv.cli import app
from flexrv.cli._common import to_jsonable
from flexrv.design import load


@pytest.fixture(scope="module")
def rv40e_report():
    return design_report(load("rv40e"))


def test_report_numbers_rv40e(rv40e_report):
    """:cite:`seed002` Table 4 frequencies, ratio 81, torque balance of the pin loads and
    C_W = series(C_Hc, C_c) inside the report."""
    rep = rv40e_report
    f = rep["kinematics"]["frequencies_Hz"]
    assert rep["kinematics"]["ratio"] == 81.0
    assert np.allclose(
        [
            f["input"],
            f["crank_rotation"],
            f["carrier"],
            f["first_stage_mesh"],
            f["cycloid_mesh"],
            f["pins_x_crank_rotation"],
            f["disc_tooth_pin_passing"],
        ],
        [20.25, 10, 0.25, 320, 390, 400, 10],
        rtol=1e-12,
    )
    assert "pin_passing" not in f  # the misnamed key is gone (issue 17 (4))
    for case in rep["pin_loads"].values():
        assert abs(case["torque_balance_error_Nm"]) < 1e-6 * abs(case["disc_torque_Nm"])
    assert rep["pin_loads"]["rated_torque_ideal_profile"]["pins_in_contact"] in (19, 20, 21)
    t = rep["second_stage_series_models"]
    c1, c2 = t["C_Hc_Nm_per_rad"], t["C_c_palmgren_tangent_Nm_per_rad"]
    assert np.isclose(t["C_W_palmgren_Nm_per_rad"], c1 * c2 / (c1 + c2))
    assert rep["meshing_zone"]["seed_table"]["best_four_pins"] == [6, 9]
    mb = rep["main_bearing"]["external"]
    assert mb["max_ball_load_N"] > 0 and 35 < mb["contact_angle_deg"]["min"] <= mb["contact_angle_deg"]["max"] < 45


def test_report_json_roundtrip(rv40e_report):
    """Everything serialises to strict JSON with no None except documented infinities."""
    text = json.dumps(to_jsonable(rv40e_report))
    back = json.loads(text)
    assert back["name"] == "rv40e" and "NaN" not in text


def test_cli_design_json():
    """`flexrv design rv221 --json` prints the same report (CLI owned by the lead)."""
    res = CliRunner().invoke(app, ["design", "rv221", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["kinematics"]["ratio"] == 221.0
    assert data["involute_stage"]["contact_ratio"] == pytest.approx(1.439633, rel=1e-5)
