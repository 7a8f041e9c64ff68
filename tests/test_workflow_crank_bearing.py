"""Workflow 6 (:cite:`seed003`, crank-bearing forces): numbers of the smoke setting.

One short rigid run of the RV-40E at the seed's operating point (2000 r/min,
600 N m, roller-resolved needle bearings) is shared by the tests (module fixture,
a few seconds); each test checks a number against an independent calculation.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.workflows.crank_bearing_forces import SMOKE, _design, crank_stress, hertz_and_life, max_load_instant


@pytest.fixture(scope="module")
def run_smoke():
    from flexrv.design import load
    from flexrv.simulation import Simulation

    red = _design(load("rv40e"))
    res = Simulation(red, model="rigid").run(t_end=SMOKE["t_end"])
    return red, res


def test_operating_point_and_roller_model(run_smoke):
    """The design step sets the seed's case: 2000 r/min input, 600 N m, one
    force per roller (``roller_force`` has z = roller_count entries)."""
    red, res = run_smoke
    assert red.operating.input_speed_rpm == 2000.0
    assert red.operating.load_torque_Nm == 600.0
    assert res["roller_force"].shape[-1] == red.needle_bearing.roller_count


def test_roller_forces_sum_to_the_needle_bearing_force(run_smoke):
    """Equilibrium of the roller loads: at every record, the vector sum of the
    roller forces f_j (cos g_j, sin g_j) of each bearing equals the recorded
    bearing force (needle_force_x, needle_force_y), to 1e-9 relative (Newton's
    third law, summed independently of the kernel's own sum)."""
    red, res = run_smoke
    f = res["roller_force"].values
    g = res["roller_angle"].values
    fx = (f * np.cos(g)).sum(axis=-1)
    fy = (f * np.sin(g)).sum(axis=-1)
    scale = max(1.0, float(np.abs(res["needle_force"].values).max()))
    np.testing.assert_allclose(fx, res["needle_force_x"].values, atol=1e-9 * scale)
    np.testing.assert_allclose(fy, res["needle_force_y"].values, atol=1e-9 * scale)
    assert np.all(f >= 0.0)  # rollers push, never pull


def test_fe_load_resultant_equals_the_bearing_resultant(run_smoke):
    """The nodal loads spread on the crankshaft mesh carry exactly the vector sum
    of crank 0's roller forces over both bearings (rotation into the mesh frame
    keeps the magnitude), rel. 1e-9; the stress peak is off the clamped nodes and
    finite."""
    red, res = run_smoke
    i, _, _ = max_load_instant(res)
    st = crank_stress(red, res, i, size=SMOKE["mesh_size"])
    fx = res["needle_force_x"].values[i, 0].sum()
    fy = res["needle_force_y"].values[i, 0].sum()
    assert st["resultant_N"] == pytest.approx(np.hypot(fx, fy), rel=1e-9, abs=1e-9)
    assert np.isfinite(st["von_mises_max_Pa"]) and st["von_mises_max_Pa"] > 0
    assert st["location"] in {"eccentric_1", "eccentric_2", "support_a", "support_b", "gear_seat"} or st[
        "location"
    ].startswith("shoulder")


def test_hertz_and_life_against_closed_forms(run_smoke):
    """Line contact of a roller (R = d/2) on the journal (R = D/2), both steel:
    b = sqrt(4 F R' / (pi L E*)) with 1/R' = 2/d + 2/D, E* = E / (2 (1 - nu^2))
    (Johnson 1985, eq. 4.43b) and p0 = 2F / (pi b L) — computed here for a 3 kN
    roller, rel 1e-9; L10 = (C/P)^(10/3) (ISO 281) of the reported C and P."""
    red, res = run_smoke
    F = 3000.0
    hl = hertz_and_life(red, res, F)
    nb, cs = red.needle_bearing, red.crankshaft
    d, L, D = nb.roller_diameter_mm * 1e-3, nb.roller_length_mm * 1e-3, cs.eccentric_journal_diameter_mm * 1e-3
    mat = red.material("crankshaft")
    e_star = mat.youngs_modulus / (2.0 * (1.0 - mat.poisson_ratio**2))
    r_eff = 1.0 / (2.0 / d + 2.0 / D)
    b = np.sqrt(4.0 * F * r_eff / (np.pi * L * e_star))
    assert hl["hertz_half_width_m"] == pytest.approx(b, rel=1e-9)
    assert hl["hertz_p_max_Pa"] == pytest.approx(2.0 * F / (np.pi * b * L), rel=1e-9)
    assert hl["hertz_p_max_Pa"] < 4.0e9  # ISO 76 static limit for roller bearing steel
    assert hl["L10_Mrev"] == pytest.approx((hl["dynamic_rating_N"] / hl["equivalent_load_N"]) ** (10 / 3), rel=1e-9)


def test_seed_eccentricity_2mm_is_rejected_with_the_physics_reason():
    """a = 2.0 mm on R_p = 64 mm with 40 pins gives K1 = a z / R_p = 1.25 >= 1
    (looping pin-centre curve): the design step raises ConfigError naming K1."""
    from flexrv.design import load
    from flexrv.errors import ConfigError

    assert 2.0 * 40 / 64.0 == pytest.approx(1.25)
    with pytest.raises(ConfigError, match="K1"):
        _design(load("rv40e"), 2.0)
    assert _design(load("rv40e"), 1.0).second_stage.eccentricity_mm == 1.0


@pytest.mark.slow
def test_full_run_bearing_load_against_the_carrier_moment_balance(tmp_path):
    """Full setting (rated 600 N m reached, ~1 min): the mean crank-bearing force
    is at least its tangential part T / (N n r_c) (moment balance of the carrier
    about its axis) and at most 30 % above it (the radial pin-resultant part is
    smaller); the most-loaded roller carries less than the whole bearing force and
    more than the Stribeck share 4.08 F / Z (Harris & Kotzalas, line contact,
    zero clearance); the Hertz pressure stays below 4 GPa (ISO 76)."""
    from flexrv.workflows.crank_bearing_forces import run

    r = run(tmp_path / "cbf", sweep=(1.3,))
    chk = r.numbers["bearing_load_check"]
    assert 0.98 <= chk["mean_bearing_force_N"] / chk["tangential_closed_form_N"] <= 1.3
    fmax = max(row["resultant [N]"] for row in r.numbers["rollers"])
    p_eq = r.numbers["hertz_life"]["equivalent_load_N"]
    assert 4.08 * chk["mean_bearing_force_N"] / 15 < fmax < 1.5 * p_eq
    assert r.numbers["hertz_life"]["hertz_p_max_Pa"] < 4.0e9
    assert r.numbers["stress"]["von_mises_max_Pa"] < 1.0e9
