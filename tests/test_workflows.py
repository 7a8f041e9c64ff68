"""Smoke runs of the seed-study workflows (flexrv/workflows/*.py) checked against closed
forms and the seeds' numbers; and the ``flexrv workflow`` / ``flexrv report`` CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.cli import app


@pytest.fixture(scope="module")
def results_root(tmp_path_factory):
    return tmp_path_factory.mktemp("results")


@pytest.fixture(scope="module")
def kinematic(results_root):
    from flexrv.workflows.kinematic_validation import run

    return run(results_root / "kinematic_validation", smoke=True)


@pytest.fixture(scope="module")
def torsional(results_root):
    from flexrv.workflows.torsional_stiffness import run

    return run(results_root / "torsional_stiffness", smoke=True)


@pytest.fixture(scope="module")
def gallery(results_root):
    from flexrv.workflows.mode_gallery import run

    return run(results_root / "mode_gallery", smoke=True)


def _has_table(path):
    text = path.read_text()
    return "| quantity | unit | seed | flexrv | note |" in text


def test_kinematic_validation(kinematic):
    """Rigid rv40e run: steady-window ratio within 0.05 % of 1 + z_p z_rp/(z_s (z_rp - z_c)) = 81;
    :cite:`seed002` Table 4 frequencies at 1215 r/min exact (closed form, 1e-9 relative); RV-221 planet
    speed with the carrier held = 9000 z_s/z_p deg/s within 0.1 % of :cite:`seed001`'s 2452.3;
    RV-221 ratio exactly 221 (:cite:`seed000`'s 221.02 = 9000/40.72, rounded simulated speed)."""
    n = kinematic.numbers
    assert n["rv40e"]["ratio_theory"] == pytest.approx(81.0, rel=1e-12)
    assert abs(n["rv40e"]["ratio_simulated"] / n["rv40e"]["ratio_theory"] - 1) < 5e-4
    seed = {
        "input": 20.25,
        "crank_rotation": 10.0,
        "carrier": 0.25,
        "first_stage_mesh": 320.0,
        "cycloid_mesh": 390.0,
        "pins_x_crank_rotation": 400.0,
    }
    for key, val in seed.items():
        assert n["rv40e_frequencies_hz"][key] == pytest.approx(val, rel=1e-9), key
    planet = n["rv221_planet_deg_s"]
    assert abs(planet["carrier_held"] / 2452.3 - 1) < 1e-3
    assert abs(planet["relative"] / 2452.3 - 1) > 1e-3  # flexrv's relative speed differs from the seed
    assert n["rv221_ratio_theory"] == pytest.approx(221.0, rel=1e-12)  # seed's 221.02 = 9000/40.72 (rounded)
    out = kinematic.out_dir
    assert _has_table(out / "summary.md")
    assert (out / "speeds.png").stat().st_size > 1000 and (out / "speeds_rv40e.nc").exists()


def test_torsional_stiffness(torsional):
    """:cite:`seed004` table with a four-pin zone and C_c = 6.24e8 N mm/rad -> pins 6-9 (sum 6.32e8,
    +1.3 %); analytic and simulated contact both find more than four pins; the stiffness test
    lies between the measured 89 N m/arcmin and the series model (the bench lacks compliances
    of the real reducer but includes the contact). Under seed004's definition, the loop secant
    (lost motion included) lies below the 50-100 % slope; the four path compliances (in the
    model) each have a share between 0 and 100 % of the budget."""
    n = torsional.numbers
    assert n["zone_seed_4"] == [6, 9]
    assert n["c_w_measured_Nm_per_arcmin"] == pytest.approx(3.06e5 / (180 * 60 / math.pi), rel=1e-9)
    assert n["pins_in_contact_analytic"] >= 4 and n["pins_in_contact_sim"] >= 4
    assert n["c_w_measured_Nm_per_arcmin"] < n["rigidity_test_Nm_per_arcmin"] < n["c_w_series_Nm_per_arcmin"]
    assert n["rigidity_loop_secant_Nm_per_arcmin"] < n["rigidity_test_Nm_per_arcmin"]
    shares = n["path_shares_percent"]
    assert set(shares) == {"crank_torsion", "planet_spline", "support_bearing_rings", "carrier_joints"}
    assert all(0.0 < v < 100.0 for v in shares.values())
    assert _has_table(torsional.out_dir / "summary.md")
    assert (torsional.out_dir / "stiffness.png").exists()


def test_mode_gallery(gallery):
    """Crankshaft rv40e: positive, ascending free-free frequencies; PNG renderings not blank
    (more than one distinct colour) and embedded in summary.md."""
    f = gallery.numbers["frequencies_hz"]["rv40e/crankshaft"]
    assert len(f) == 2 and f[0] > 0 and f[1] >= f[0]
    import matplotlib.image as mpimg

    text = (gallery.out_dir / "summary.md").read_text()
    for name in gallery.numbers["pngs"]:
        img = mpimg.imread(gallery.out_dir / name)
        assert np.unique(img.reshape(-1, img.shape[-1]), axis=0).shape[0] > 10
        assert f"({name})" in text


def test_cli_report(kinematic, torsional, gallery, results_root):
    """``flexrv report --json`` collects the three summaries into the generated REPORT.md
    (never README.md); the smoke runs' banner is carried into the report."""
    r = CliRunner().invoke(app, ["report", "--results", str(results_root), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["sections"] == ["kinematic_validation", "mode_gallery", "torsional_stiffness"]
    assert data["path"].endswith("REPORT.md") and not (results_root / "README.md").exists()
    report = (results_root / "REPORT.md").read_text()
    assert "(mode_gallery/rv40e_crankshaft_mode01.png)" in report and "| 6-9 |" in report
    assert "SMOKE RUN" in report and "## References" in report


def test_cli_workflow(tmp_path):
    """``flexrv workflow mode_gallery --smoke --json`` writes summary.md and reports the folder."""
    r = CliRunner().invoke(app, ["workflow", "mode_gallery", "--smoke", "--out", str(tmp_path), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["out_dir"] == str(tmp_path) and (tmp_path / "summary.md").exists()
    assert data["numbers"]["frequencies_hz"]["rv40e/crankshaft"][0] > 0


def test_ring_deformation_smoke(tmp_path):
    """Workflow 3 (:cite:`seed001`) smoke: one load case, 10 ms, coarse rings. The
    flexible rings deflect (> 0) under the preload and the start of the load
    ramp, the rigid-ring run has no ring deflection column to compare but the
    same TE to < 0.1 arcsec this early; the seed's numbers are listed beside."""
    from flexrv.workflows.ring_deformation import SEED_DEFORMATION_UM, run

    r = run(tmp_path / "ring_deformation", smoke=True)
    row = r.numbers["cases"][0]
    assert row["seed deformation [um]"] == SEED_DEFORMATION_UM[0]
    assert 0 < row["outer ring deflection [um]"] < 5.0
    assert abs(row["TE max, flexible [arcsec]"] - row["TE max, rigid rings [arcsec]"]) < 0.1
    assert (tmp_path / "ring_deformation" / "summary.md").exists()
    assert (tmp_path / "ring_deformation" / "ring_deformation.png").exists()


def test_lubrication_smoke(tmp_path):
    """Workflow 4 smoke: the central film grows with viscosity as Hamrock–Dowson's
    eta0^0.67 (Hamrock 1994, eq. 22.18: same load and speed -> ratio
    (1.5/0.05)^0.67 within 10 %, loads differ slightly), the dry case has no film,
    and the seed's table is listed beside flexrv's numbers."""
    from flexrv.workflows.lubrication import run

    r = run(tmp_path / "lubrication", smoke=True)
    dry, low, high = r.numbers["film"]
    assert dry["film at max load [um]"] == 0.0
    ratio = high["film at max load [um]"] / low["film at max load [um]"]
    assert ratio == pytest.approx((1.5 / 0.05) ** 0.67, rel=0.1)
    assert len([c for c in r.comparisons if c.quantity.startswith("film")]) == 3
    assert (tmp_path / "lubrication" / "lubrication.png").exists()


def test_rigid_vs_flexible_smoke(tmp_path):
    """Workflow 2 (:cite:`seed000,seed001`) smoke: both models run on identical inputs; the
    seeds' TE ranges and periods stand beside flexrv's; the TE difference flexible -
    rigid is the difference of the two runs' statistics."""
    from flexrv.workflows.rigid_vs_flexible import run

    r = run(tmp_path / "rigid_vs_flexible", smoke=True)
    rows = {c.quantity: c for c in r.comparisons}
    assert rows["TE range, rigid model"].seed == "-25.2 .. 21.6"
    assert rows["TE range, flexible model"].seed == "-43.2 .. 45.0"
    d = r.numbers["difference"]["te_pp_arcsec"]
    assert d == pytest.approx(r.numbers["flexible"]["te_pp_arcsec"] - r.numbers["rigid"]["te_pp_arcsec"])
    assert r.numbers["te_rms_difference_arcsec"] >= 0
    text = (tmp_path / "rigid_vs_flexible" / "summary.md").read_text()
    assert "te_overlay.png" in text and (tmp_path / "rigid_vs_flexible" / "te_overlay.png").exists()


def test_crankshaft_flexibility_smoke(tmp_path):
    """Workflow 5 (:cite:`seed002`) smoke: Table 4 frequencies from the kinematics equal the
    seed's at 1215 r/min (20.25 / 10 / 0.25 / 320 / 390 Hz, 1e-3); the spectral table
    lists the crank harmonics and mesh lines for both models."""
    from flexrv.workflows.crankshaft_flexibility import SEED_TABLE4, run

    r = run(tmp_path / "crankshaft_flexibility", smoke=True)
    for c in r.comparisons:
        if c.quantity.endswith("frequency"):
            assert c.flexrv == pytest.approx(SEED_TABLE4[c.quantity[: -len(" frequency")]], rel=1e-3)
    labels = [row["line"] for row in r.numbers["lines"]]
    assert "3 x crank rotation" in labels and "cycloid mesh" in labels
    assert (tmp_path / "crankshaft_flexibility" / "te_spectra_table4.png").exists()


def test_crank_bearing_forces_smoke(tmp_path):
    """Workflow 6 (:cite:`seed003`) smoke: the FE load resultant equals the sum of the
    roller forces of crank 0 (both bearings, equilibrium of the spread loads); the
    Hertz pressure equals sqrt(F E' / (2 pi R L)) (Johnson 1985, eq. 4.45, an
    independent form of p0 = 2F/(pi b L)); invalid eccentricities of the seed's
    sweep are reported, not simulated; the roller-load period is one crank
    revolution relative to the carrier."""
    from flexrv.contact.hertz import effective_modulus
    from flexrv.design import load
    from flexrv.workflows.crank_bearing_forces import run

    r = run(tmp_path / "crank_bearing_forces", smoke=True)
    rows = next(iter(r.tables.values()))
    fmax = max(row["resultant [N]"] for row in rows)
    red = load("rv40e")
    nb, cs = red.needle_bearing, red.crankshaft
    reff = 1.0 / (2.0 / (nb.roller_diameter_mm * 1e-3) + 2.0 / (cs.eccentric_journal_diameter_mm * 1e-3))
    mat = red.material("crankshaft")
    e_eff = float(effective_modulus(mat.youngs_modulus, mat.poisson_ratio, mat.youngs_modulus, mat.poisson_ratio))
    p0 = np.sqrt(fmax * e_eff / (2 * np.pi * reff * nb.roller_length_mm * 1e-3))
    assert r.numbers["hertz_life"]["hertz_p_max_Pa"] == pytest.approx(p0, rel=1e-9)
    assert r.numbers["stress"]["von_mises_max_Pa"] > 0
    assert r.numbers["sweep"][0]["valid"]
    period = next(c for c in r.comparisons if c.quantity == "roller-load period")
    # crank relative to the carrier: (omega_in - omega_out) z_s / z_p, i = 81 (Willis)
    assert period.flexrv == pytest.approx(1 / (2000 / 60 * (1 - 1 / 81) * 16 / 32), rel=1e-9)
    assert (tmp_path / "crank_bearing_forces" / "roller_forces.png").exists()


def test_crank_bearing_sweep_reports_invalid_eccentricities():
    """The seed's 2.0 mm on the RV-40E (R_p = 64 mm, 40 pins) makes K1 = 1.25 > 1:
    the workflow's design step rejects it with the physics reason."""
    from flexrv.design import load
    from flexrv.errors import ConfigError
    from flexrv.workflows.crank_bearing_forces import _design

    with pytest.raises(ConfigError, match="K1"):
        _design(load("rv40e"), 2.0)


def test_report_answer_is_computed_from_saved_outputs(tmp_path):
    """The report's Answer section quotes the numbers of the saved comparison
    (rigid_vs_flexible/compare.json), not fixed text: changing the file changes it."""
    from flexrv.workflows._common import answer_section

    (tmp_path / "rigid_vs_flexible").mkdir()
    stats = {"te_min_arcsec": -1.5, "te_max_arcsec": 2.25, "te_mean_arcsec": 0.5, "te_pp_arcsec": 3.75}
    flex = dict(stats, te_mean_arcsec=0.75, te_pp_arcsec=4.0)
    (tmp_path / "rigid_vs_flexible" / "compare.json").write_text(json.dumps({"rigid": stats, "flexible": flex}))
    text = "\n".join(answer_section(tmp_path))
    assert "-1.50 .. 2.25" in text and "+0.25 arcsec in the mean" in text and "+0.25 arcsec in the ripple" in text
    assert answer_section(tmp_path / "missing") == []


def test_te_errors_smoke(tmp_path):
    """te_errors smoke (one crank revolution, 2 points per mesh period): the ideal
    rows reproduce the ideal reducers' loaded TE p-p at this sampling (0.263 / 4.16
    arcsec with the path compliances in the models and the needle clearance at the ISO
    5753-1 C2 midpoint, 12.5 / 17.5 um), the errors multiply it (> 5x; measured 212x rv40e,
    6.9x rv221, whose ideal ripple grows with its clearance), the first stage contributes
    least (its errors reach the output divided by the second stage's ratio), and the rv40e
    all-errors p-p is pinned: 55.68 arcsec (1 %)."""
    from flexrv.workflows.te_errors import run

    r = run(tmp_path / "te_errors", smoke=True)
    for preset, ideal_pp in (("rv40e", 0.263), ("rv221", 4.16)):
        rows = {row["case"]: row for row in r.numbers[preset]["rows"]}
        assert rows["ideal geometry"]["TE p-p [arcsec]"] == pytest.approx(ideal_pp, rel=0.02)
        assert rows["all errors"]["TE p-p [arcsec]"] > 5 * ideal_pp
        singles = [v for k, v in rows.items() if k.endswith(" only")]
        assert min(singles, key=lambda x: x["TE p-p [arcsec]"]) is rows["first stage only"]
    rows = {row["case"]: row for row in r.numbers["rv40e"]["rows"]}
    assert rows["all errors"]["TE p-p [arcsec]"] == pytest.approx(55.68, rel=0.01)
    assert (tmp_path / "te_errors" / "summary.md").read_text().startswith("# Transmission error")
