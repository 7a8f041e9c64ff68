"""Verification of the quasi-static loaded-TE solver (flexrv.model.quasi_static).

Each test states its reference and tolerance. Short ranges (a fraction of a
crank revolution) keep the default suite fast.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from flexrv.design import load, override
from flexrv.errors import InputError
from flexrv.model.quasi_static import StaticModel, loaded_te, positions_for, ramp_to
from flexrv.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD


def ideal(name: str):
    """The preset with ideal geometry: no profile modification, no needle
    clearance, no first-stage backlash."""
    return override(
        name,
        {
            "second_stage.modification_equidistant_mm": 0.0,
            "second_stage.modification_shift_mm": 0.0,
            "second_stage.modification_rotation_deg": 0.0,
            "needle_bearing.radial_clearance_um": 0.0,
            "first_stage.backlash_um": 0.0,
        },
    )


@pytest.fixture(scope="module")
def rv40e_quarter():
    return loaded_te(load("rv40e"), crank_revolutions=0.25, points_per_mesh=8)


def test_positions_resolve_the_pin_mesh():
    """K points per cycloid-mesh period: one output revolution of rv40e holds
    z_c * (crank revolutions per output revolution) = 39 * 40 = 1560 mesh
    periods (:cite:`seed002` Table 4: 390 Hz mesh / 0.25 Hz output), so 12,480 positions
    at K = 8, spanning i = 81 input revolutions (exact)."""
    red = load("rv40e")
    th = positions_for(red, output_revolutions=1.0, points_per_mesh=8)
    assert len(th) == 12480
    assert th[-1] + (th[1] - th[0]) == pytest.approx(81 * 2 * np.pi, rel=1e-12)
    assert len(positions_for(red, crank_revolutions=1.0, points_per_mesh=8)) == 39 * 8


def test_equilibrium_residual_and_kinematic_pose():
    """The kinematic pose is an exact equilibrium at zero load (every force
    vanishes, |R| < 1e-6 N); the loaded solve meets the force tolerance."""
    red = load("rv40e")
    sm = StaticModel(red)
    for th in (0.0, 0.37, 5.0):
        f, _ = sm.residual(th, sm.kinematic_pose(th))
        assert np.max(np.abs(f)) < 1e-6
    sm.torque = red.operating.rated_torque_Nm
    q, _ = sm.solve(0.37, sm.kinematic_pose(0.37))
    f, _ = sm.residual(0.37, q)
    assert np.max(np.abs(f / sm.arm)) < sm.options.force_tol * sm.f_ref


def test_pin_loads_vs_analytic_distribution():
    """Rated torque, crank angle 0 (input angle 0): pin forces of disc 0 vs the
    analytic initial-clearance distribution (flexrv.analysis.pin_load, rigid
    crank bearings, equal torque share per disc) driven by the disc's own pin
    torque from the solve. Tolerance: same pins in contact within +-1 and max
    pin force within 5 % (the solver lets the disc centre move on its compliant
    needle bearings, which the analytic method does not)."""
    from flexrv.analysis.pin_load import disc_effective_modulus, pin_contact_constant, pin_load_distribution

    red = load("rv40e")
    r = loaded_te(red, crank_revolutions=0.01, points_per_mesh=8, catalog_positions=1)
    f = r.outputs["pin_force"].values[0, 0]
    t_disc = r.outputs["disc_pin_torque"].values[0, 0]
    ss = red.second_stage
    ref = pin_load_distribution(
        t_disc,
        ss.pin_count,
        ss.pin_circle_radius,
        ss.pin_radius,
        ss.eccentricity,
        ss.disc_width,
        disc_effective_modulus(red),
        ss.modification_shift,
        ss.modification_equidistant,
        ss.modification_rotation,
        0.0,
        "palmgren",
        stiffness_constant=pin_contact_constant(red).k,
    )  # pin path with the seats (issue 14)
    assert abs(int((f > 0).sum()) - ref.n_contact) <= 1
    assert f.max() == pytest.approx(ref.max_force, rel=0.05)
    # static torque balance about the axis (exact at equilibrium): the pins' reaction on the
    # housing and the sun's reaction carry the load torque
    t_r = red.operating.rated_torque_Nm
    o = r.outputs
    balance = o["housing_pin_torque"].values[0].sum() - o["sun_torque"].values[0] + o["load_torque"].values[0]
    assert abs(balance) < 1e-6 * t_r
    assert o["load_torque"].values[0] == pytest.approx(t_r)


def test_ideal_geometry_no_load_te_vanishes_and_loaded_does_not():
    """Ideal geometry: the no-load TE (1 % of rated torque) is the elastic part
    only, p-p below 2 % of the loaded p-p and below 0.01 arcsec (the kinematics are
    exact: conjugate profile, no clearance); the loaded TE winds up by more than
    10 arcsec."""
    r = loaded_te(ideal("rv40e"), crank_revolutions=0.25, points_per_mesh=8, catalog_positions=1)
    s = r.summary()
    assert s["no_load_te_pp_arcsec"] < 0.01
    assert s["no_load_te_pp_arcsec"] < 0.02 * s["te_pp_arcsec"]
    assert s["te_mean_arcsec"] < -10.0
    # no clearance anywhere: the backlash is the elastic twist between +-1 % of the rated torque, i.e.
    # twice the no-load wind-up (the ideal reducer is symmetric under load reversal), a small figure
    # (measured 0.051 arcmin with the path compliances of flexrv.analysis.path_compliances in the model)
    assert s["backlash_arcmin"] == pytest.approx(2 * abs(r.te_no_load[0]) * ARCMIN_PER_RAD, rel=1e-3)
    assert s["backlash_arcmin"] < 0.06


def test_mean_wind_up_equals_integrated_tangent_compliance():
    """TE(T) - TE(0) = -integral_0^T dT / k_t(T) with the tangent rigidity k_t
    from the condensed Jacobian (Simpson's rule on 9 torque levels); reference:
    the directly solved equilibria. Tolerance 0.5 % (the Hertz law's k_t varies
    like T^0.1, which Simpson integrates to < 0.1 %, plus the pins entering
    contact)."""
    red = ideal("rv40e")
    sm = StaticModel(red)
    t_r = red.operating.rated_torque_Nm
    th = 0.0
    levels = np.linspace(0.05 * t_r, t_r, 9)
    sm.torque = 0.0
    q = ramp_to(sm, th, sm.kinematic_pose(th), levels[0])
    angles, k = [], []
    for t in levels:
        q = ramp_to(sm, th, q, t, steps=1)
        angles.append(q[sm.i_theta])
        k.append(sm.tangent_rigidity(th, q))
    dt = levels[1] - levels[0]
    c = 1.0 / np.asarray(k)
    integral = dt / 3.0 * (c[0] + c[-1] + 4 * c[1:-1:2].sum() + 2 * c[2:-1:2].sum())
    assert angles[0] - angles[-1] == pytest.approx(integral, rel=5e-3)


def test_convergence_in_points_per_mesh_and_newton_tolerance():
    """Over 4 whole cycloid-mesh periods the positions for K points per period are
    nested (K = 8, 16, 32, 64), so the sampled TE p-p rises monotonically towards
    the continuous one. The TE has cusps where the first-stage mesh stiffness
    switches between one and two tooth pairs (order 3840 of rv40e, 2.46 per
    cycloid-mesh period), which coarse sampling can miss: the error against
    K = 64 measured 7.2 %, 3.0 %, 0.01 % at K = 8, 16, 32 (2026-11-24, with the pin
    seats in series, issue 14; 2.8 %, 2.2 %, 0.0 % with the stiffer pin law before);
    required: no doubling raises it, K = 8 within 10 % and K = 32 within 0.5 %.
    Tightening the force tolerance 100x changes no TE sample by more than
    1e-4 arcsec."""
    red = load("rv40e")
    crank = 4.0 / 39.0  # 4 mesh periods of rv40e (z_c = 39 per crank revolution)
    pp = {}
    for k in (8, 16, 32, 64):
        r = loaded_te(red, crank_revolutions=crank, points_per_mesh=k, catalog_positions=1)
        assert len(r.te) == 4 * k
        pp[k] = r.summary()["te_pp_arcsec"]
    assert (
        pp[8] <= pp[16] + 1e-5 and pp[16] <= pp[32] + 1e-5 and pp[32] <= pp[64] + 1e-5
    )  # nested, up to solver tolerance
    err = {k: (pp[64] - pp[k]) / pp[64] for k in (8, 16, 32)}
    assert err[8] >= err[16] >= err[32] - 1e-9
    assert err[8] < 0.10 and err[32] < 0.005
    a = loaded_te(red, crank_revolutions=0.05, points_per_mesh=8, catalog_positions=1)
    b = loaded_te(red, crank_revolutions=0.05, points_per_mesh=8, catalog_positions=1, options={"force_tol": 1e-8})
    assert np.max(np.abs(a.te - b.te)) * ARCSEC_PER_RAD < 1e-4


def test_catalog_numbers_are_consistent(rv40e_quarter):
    """Lost motion (+-3 %) >= backlash (+-1 %) > 0 with the preset's clearances;
    the catalog secant rigidity (50-100 % rated) lies within 5 % of the tangent
    rigidity at the rated torque (the Hertz laws stiffen mildly with load)."""
    s = rv40e_quarter.summary()
    assert s["lost_motion_arcmin"] > s["backlash_arcmin"] > 0.0
    assert s["catalog_rigidity_Nm_per_arcmin"] == pytest.approx(s["torsional_rigidity_Nm_per_arcmin"], rel=0.05)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"torque": -1.0}, "torque"),
        ({"torque": 1e9}, "torque"),
        ({"points_per_mesh": 1}, "points_per_mesh"),
        ({"output_revolutions": 0.0}, "output_revolutions"),
        ({"crank_revolutions": float("nan")}, "crank_revolutions"),
        ({"output_revolutions": 1.0, "crank_revolutions": 1.0}, "crank_revolutions"),
        ({"options": {"bogus": 1}}, "bogus"),
    ],
)
def test_bad_inputs_name_the_field(kwargs, field):
    with pytest.raises(InputError, match=field):
        loaded_te(load("rv40e"), **kwargs)


def test_outputs_are_the_solver_evaluations_at_the_converged_states():
    """The force groups' outputs of a curve are copied from the solver's own residual call at
    each converged position (``_CurveRecords``), not evaluated in a second pass. Reference: a
    fresh evaluation of every group at the converged states (``group_outputs`` without
    records: the fused element's history pass, which solves every closest point and inner
    problem from fresh starts). Every output agrees to 1e-8 of its largest magnitude (the
    solver's warm-started inner solves converge to ~1e-10 relative); ``pin_gap`` agrees to
    1e-12 m except at pins the solver proved open, where it is a positive lower bound of the
    exact gap (as declared). The kernels of the groups keep the one type signature of their
    call from the fused kernel (a read-only or strided state would compile each again)."""
    from flexrv.model.outputs import group_outputs
    from flexrv.model.quasi_static import _CurveRecords, equilibrium_path

    red = load("rv40e")
    angles = positions_for(red, crank_revolutions=0.1, points_per_mesh=8)
    sm = StaticModel(red)
    q = ramp_to(sm, angles[0], sm.kinematic_pose(angles[0]), red.operating.rated_torque_Nm)
    records = _CurveRecords(sm, len(angles))
    qs, its = equilibrium_path(sm, angles, q, record=records)
    got = records.outputs(angles, qs)
    ref = group_outputs(sm.model, angles, qs, np.zeros_like(qs))
    for g in sm.model.groups:  # the group's own Jacobian (catalog budget) and a history: one signature
        qg = sm.model.group_state(g, qs[:3])
        g.jacobian(angles[0], qg[0], np.zeros(qg.shape[1]))
        g.evaluate(angles[:3], qg, np.zeros(qg.shape[1]), want_outputs=True)
        assert len(type(g).kernel.signatures) == 1, g.name
    assert set(got) == set(ref) and got["pin_force"].dims[0] == "position"
    for name, o in ref.items():
        a, b = got[name].values, o.values
        if name == "pin_gap":
            exact = np.abs(a - b) <= 1e-12
            assert np.all(exact | ((a > 0) & (a < b))), name
            assert np.all(exact[got["pin_force"].values > 0])
            continue
        assert np.allclose(a, b, rtol=0.0, atol=1e-8 * np.abs(b).max() + 1e-18), name
    # a position that did not converge (NaN state) is NaN in every output; the others keep their values
    # (every position converged: the record buffers are used unmasked; else masked copies)
    bad = qs.copy()
    bad[3] = np.nan
    part = records.outputs(angles, bad)
    keep = np.arange(len(angles)) != 3
    for name, o in got.items():
        assert np.all(np.isnan(part[name].values[3])), name
        assert np.array_equal(part[name].values[keep], o.values[keep]), name


def test_cli_te_json_matches_saved_results(tmp_path):
    """`flexrv te ... --json`: the required keys, and the TE numbers equal the
    statistics recomputed from the saved NetCDF (1e-9); the process imports neither dask
    arrays nor dask.distributed nor Exudyn (``-X importtime``: what a te run does not use)."""
    import xarray as xr

    out = tmp_path / "te"
    cp = subprocess.run(
        [
            sys.executable,
            "-X",
            "importtime",
            "-m",
            "flexrv",
            "te",
            "rv40e",
            "--crank-revolutions",
            "0.1",
            "--points-per-mesh",
            "8",
            "--json",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert cp.returncode == 0, cp.stderr[-3000:]
    rows = [line.split("|") for line in cp.stderr.splitlines() if line.startswith("import time:")]
    # modules loaded (a hidden module's refused import is listed too, at a few microseconds)
    imported = {r[2].strip() for r in rows[1:] if int(r[1]) > 200}
    # no dask arrays, no dask.distributed, no Exudyn in a te process (flexrv.post.io.xarray_without_dask); the
    # figures are drawn on their own Agg canvases, without pyplot (flexrv.viz.plots._AggFigures)
    assert "xarray" in imported and not imported & {"dask.array", "distributed", "exudyn", "matplotlib.pyplot"}
    d = json.loads(cp.stdout)
    for key in (
        "te_pp_arcsec",
        "te_mean_arcsec",
        "no_load_te_pp_arcsec",
        "lost_motion_arcmin",
        "backlash_arcmin",
        "rigidity_tangent_Nm_per_arcmin",
        "positions",
        "solve_time_s",
        "spectrum_lines",
    ):
        assert key in d
    ds = xr.load_dataset(out / "results.nc")
    te = ds["te"].values
    assert d["te_pp_arcsec"] == pytest.approx(float(np.ptp(te)), rel=1e-9)
    assert d["te_mean_arcsec"] == pytest.approx(float(te.mean()), rel=1e-9)
    assert d["positions"] == ds.sizes["position"] == 31
    assert ds["te"].attrs["units"] == "arcsec" and ds["pin_force"].attrs["units"] == "N"
    for png in ("te.png", "te_spectrum.png", "pin_forces.png"):
        assert (out / png).stat().st_size > 10_000


def test_dynamic_model_follows_the_quasi_static_curve_at_low_speed():
    """rv40e at a tenth of the rated input speed (121.5 r/min), rated torque: the
    dynamic rigid model's TE after the ramps (0.12-0.2 s, 3.6 cycloid-mesh
    periods) against the quasi-static equilibrium at the same input angles.
    Inertia forces scale with speed squared (1 % of rated-speed ones), so the
    curves must coincide: measured mean difference 2e-5 arcsec and largest
    deviation 0.0036 arcsec (1.4 % of the 0.25 arcsec p-p); required 0.005 and
    0.015 arcsec (6 % of p-p)."""
    from flexrv.model.quasi_static import equilibrium_path
    from flexrv.simulation import Simulation

    red = override(
        "rv40e",
        {
            "operating.input_speed_rpm": 121.5,
            "operating.speed_ramp_time_s": 0.05,
            "operating.load_ramp_start_s": 0.0,
            "operating.load_ramp_end_s": 0.05,
            "contact.friction": False,
        },
    )  # the static solver has no friction (zero speed)
    res = Simulation(red).run(t_end=0.2, dt=1e-4)
    sel = res.time > 0.12
    th = res["theta_in"].values[sel][::4]
    te_dyn = res["te"].values[sel][::4]
    sm = StaticModel(red)
    sm.torque = 0.0
    q = ramp_to(sm, th[0], sm.kinematic_pose(th[0]), red.operating.load_torque_Nm)
    qs, _ = equilibrium_path(sm, th, q)
    te_qs = (qs[:, sm.i_theta] - th / sm.p.ratio) * ARCSEC_PER_RAD
    d = te_dyn - te_qs
    assert abs(d.mean()) < 0.005
    assert np.max(np.abs(d - d.mean())) < 0.015
    assert np.ptp(te_qs) > 0.1  # the comparison is about a real ripple


def test_compliance_budget_predicts_a_stiffer_support():
    """The budget's shares sum to 1, and doubling the crank-support stiffness
    lowers the torsional compliance by share/2 of it (exact for an element in
    series; measured 0.12 % of C off, the load sharing between cranks shifting
    slightly); required within 1 % of C."""

    def compliance(red):
        sm = StaticModel(red)
        sm.torque = 0.0
        q = ramp_to(sm, 0.0, sm.kinematic_pose(0.0), red.operating.rated_torque_Nm)
        return 1.0 / sm.tangent_rigidity(0.0, q), sm.compliance_budget(0.0, q)

    from tests.data.make_force_reference import legacy_supports  # the linear support law (issue 14)

    red = legacy_supports(load("rv40e"), "rv40e")
    c0, budget = compliance(red)
    assert sum(budget.values()) == pytest.approx(1.0, abs=1e-9)
    k = red.crankshaft.support_bearing_radial_stiffness_N_per_m
    c1, _ = compliance(override(red, {"crankshaft.support_bearing_radial_stiffness_N_per_m": 2 * k}))
    assert c1 == pytest.approx(c0 * (1 - budget["crank_supports"] / 2), abs=0.01 * c0)


def _pins(red, field, values):
    return override(red, {f"errors.pins.{field}": values})


def test_uniform_tangential_pin_error_is_an_exact_offset():
    """All pins moved tangentially by t = 2 um: the pin ring turned by
    alpha = t / R_p. With the input held, the relative kinematics give
    theta_out - alpha = (theta_in - alpha) / i, so TE rises by alpha (1 - 1/i)
    at every position, loaded and unloaded (closed form; 6.366 arcsec for rv40e).
    Tolerance 1e-3 relative; the TE ripple is unchanged to 1e-3 arcsec."""
    base = override("rv40e", {"needle_bearing.radial_clearance_um": 0.0})
    kw = dict(crank_revolutions=0.2, points_per_mesh=8, catalog_positions=1)
    r0 = loaded_te(base, **kw)
    r1 = loaded_te(_pins(base, "pin_tangential_position_um", 2.0), **kw)
    alpha = 2e-6 / base.second_stage.pin_circle_radius * (1.0 - 1.0 / r0.ratio)
    for d in (r1.te - r0.te, r1.te_no_load - r0.te_no_load):
        assert d.mean() == pytest.approx(alpha, rel=1e-3)
        assert np.ptp(d) * ARCSEC_PER_RAD < 1e-3


def test_single_pin_tangential_error_bump_height():
    """One pin moved tangentially by t = 2 um (towards its loaded flank): its gap
    falls by t l_j / R_p (l_j its moment arm), so while it is the first contact the
    disc turns t / R_p earlier and the kinematic TE rises by t / R_p (1 - 1/i) =
    6.366 arcsec (closed form, independent of l_j). The no-load curve holds the
    elastic part at its torque, which falls like T^0.9: measured 65 % of the
    closed form at 1 % of the rated torque and 96.7 % at 0.1 % (2026-11-24, with the
    pin seats in series, issue 14, the softer pin path holds more elastic part; 76 %
    and 97.5 % before); required >= 60 % and within 4 % respectively. Moved the other way, the pin only opens its
    gap: no bump (< 0.2 arcsec)."""
    base = override("rv40e", {"needle_bearing.radial_clearance_um": 0.0})
    z = base.second_stage.pin_count
    expected = None
    for frac, sign, check in ((1e-2, 1.0, "default"), (1e-3, 1.0, "small"), (1e-2, -1.0, "away")):
        kw = dict(crank_revolutions=1.1, points_per_mesh=8, catalog_positions=1, no_load_fraction=frac)
        r0 = loaded_te(base, **kw)
        expected = 2e-6 / base.second_stage.pin_circle_radius * (1.0 - 1.0 / r0.ratio)
        t = [0.0] * z
        t[5] = 2.0 * sign
        d = loaded_te(_pins(base, "pin_tangential_position_um", t), **kw).te_no_load - r0.te_no_load
        if check == "default":
            assert 0.60 * expected < d.max() < expected
        elif check == "small":
            assert d.max() == pytest.approx(expected, rel=0.04)
        else:
            assert np.max(np.abs(d)) * ARCSEC_PER_RAD < 0.2


def test_uniform_pin_circle_radius_error_is_a_shift_modification():
    """Every pin moved outward by d = 2 um: in the disc's frame this is the
    profile-shift modification dR_p = -d (the pin-centre epitrochoid on R_p + d
    against a profile generated on R_p; first order in d/R_p). So its TE equals
    the shift-modified design's: mean, p-p and lost motion within 1e-3
    (measured 4e-5); it is an offset and a backlash change (lost motion +0.16
    arcmin), and adds no variation over the output revolution beyond the changed
    mesh ripple (TE p-p +0.044 arcsec, required < 0.1). The disc body and the housing
    are rigid here: their compliance constants are design-level, evaluated on the
    design without errors (flexrv.design.manufacturing.nominal_design), so the error
    keeps the base design's constants while the modification gets its own; the
    equivalence is one of the contact geometry."""
    base = override(
        "rv40e",
        {
            "needle_bearing.radial_clearance_um": 0.0,
            "second_stage.disc_body_model": "rigid",
            "housing.body_model": "rigid",
        },
    )
    kw = dict(crank_revolutions=0.25, points_per_mesh=8, catalog_positions=1)
    r0 = loaded_te(base, **kw)
    r1 = loaded_te(_pins(base, "pin_radial_position_um", 2.0), **kw)
    r2 = loaded_te(override(base, {"second_stage.modification_shift_mm": -2e-3}), **kw)
    s0, s1, s2 = r0.summary(), r1.summary(), r2.summary()
    assert (r1.te - r0.te).mean() == pytest.approx((r2.te - r0.te).mean(), rel=1e-3)
    assert s1["te_pp_arcsec"] == pytest.approx(s2["te_pp_arcsec"], rel=1e-3)
    assert s1["lost_motion_arcmin"] == pytest.approx(s2["lost_motion_arcmin"], rel=1e-3)
    assert s1["lost_motion_arcmin"] > s0["lost_motion_arcmin"] + 0.1
    assert abs(s1["te_pp_arcsec"] - s0["te_pp_arcsec"]) < 0.1


def test_single_enlarged_pin_bump_height():
    """One pin enlarged by dr = 2 um, no load (0.1 % of rated torque): its gap
    falls by dr along its normal, so while it is the first contact the disc turns
    dr / l_j earlier; the bump is largest where its moment arm l_j peaks at
    r'_c = a z_c (:func:`flexrv.geometry.cycloid.moment_arm`, the equidistant
    clearance being uniform along the normals), i.e. dr / (a z_c) (1 - 1/i) =
    8.04 arcsec at the output (closed form). Measured 7.69 (95.7 %: the elastic
    part at 0.4 N m and the sampling of the arm's maximum); required within 6 %."""
    base = override("rv40e", {"needle_bearing.radial_clearance_um": 0.0})
    z, ss = base.second_stage.pin_count, base.second_stage
    kw = dict(crank_revolutions=1.1, points_per_mesh=8, catalog_positions=1, no_load_fraction=1e-3)
    r0 = loaded_te(base, **kw)
    radius = [0.0] * z
    radius[5] = 2.0
    d = loaded_te(_pins(base, "pin_radius_um", radius), **kw).te_no_load - r0.te_no_load
    expected = 2e-6 / (ss.eccentricity * ss.disc_teeth) * (1.0 - 1.0 / r0.ratio)
    assert d.max() == pytest.approx(expected, rel=0.06)


@pytest.mark.parametrize("errors", [None, "iso_grade5_rv40e"])
def test_solver_jacobian_equals_finite_differences(errors):
    """The analytic Jacobian the solver uses (one fused call) equals the central
    finite-difference Jacobian of the residual (StaticModel.fd_jacobian, steps
    1e-10 and 5e-11 m on the crank circle, Richardson-extrapolated) within 1e-6 of
    its largest entry at equilibria of rv40e (rated and 1 % torque, ideal and with
    the grade-5 error set): the pins' and gear meshes' Jacobians are complete, so
    the solver needs no finite-difference fallback. The extrapolation removes the
    differences' O(h^2 / delta^2) error at a pin compressed by only delta = 1.9 nm
    (1.3e-6 of the largest entry with h = 1e-10 alone, 2e-3 with h = 1e-9). Rigid
    carrier and discs: the elastic bodies' condensed Jacobians are checked in
    tests/test_bodies.py (their local Newton's round-off, ~5e-8 N, is at this test's
    noise floor with steps of 5e-11 m; with 2e-10 / 4e-10 m they agree to 1e-8)."""
    from flexrv.design import load_error_set, with_errors
    from flexrv.model.bodies import with_bodies

    red = load("rv40e") if errors is None else with_errors("rv40e", load_error_set(errors))
    red = with_bodies(red, [])
    sm = StaticModel(red)
    th = 0.37
    sm.torque = red.operating.rated_torque_Nm
    q = ramp_to(sm, th, sm.kinematic_pose(th), sm.torque, steps=8)
    for frac in (1.0, 0.01):
        q = ramp_to(sm, th, q, frac * red.operating.rated_torque_Nm)
        _, jac = sm.residual(th, q)
        fd = (4.0 * sm.fd_jacobian(th, q, 5e-11) - sm.fd_jacobian(th, q, 1e-10)) / 3.0
        assert np.abs(fd).max() > 1e8
        assert np.abs(jac - fd).max() <= 1e-6 * np.abs(fd).max()


def test_catalog_level_independent_of_warm_start_history():
    """rv40e with the grade-5 error set, one crank revolution: at the last catalog
    position the -3 % level was once reached from a wrong warm-started closest
    point of five pins per disc (gaps of 1-2 mm instead of ~10 um, residual 5.5 kN
    on a cold evaluation), giving lost motion 0.1848 instead of 0.1625 arcmin (linear
    crank supports; with the tapered-roller supports the pinned value is the
    quasi_static_rv40e_grade5 entry of tests/reference_values.py).
    The pins kernel now re-finds a warm-started closest point from cold starts
    wherever it lies beyond the curve's reach: each catalog level equals the one
    from a fresh model (fresh warm starts) started at the loaded path's state,
    within 1e-6 arcmin."""
    from flexrv.design import load_error_set, with_errors
    from flexrv.model import quasi_static as qs

    red = with_errors("rv40e", load_error_set("iso_grade5_rv40e"))
    rated = red.operating.rated_torque_Nm
    seen = {}
    orig = qs._catalog_levels

    def spy(sm, th, q, *args):
        levels = orig(sm, th, q, *args)
        seen[th] = (q.copy(), levels)
        return levels

    qs._catalog_levels = spy
    try:
        res = loaded_te(red, crank_revolutions=1.0, points_per_mesh=2, catalog_positions=2)
    finally:
        qs._catalog_levels = orig
    from tests.reference_values import REFERENCE

    pinned = REFERENCE["quasi_static_rv40e_grade5"]["values"]["lost_motion_arcmin"]
    assert res.catalog["lost_motion_rad"] * ARCMIN_PER_RAD == pytest.approx(pinned, abs=1e-4)
    th = max(seen)
    q, levels = seen[th]
    fresh = StaticModel(red)
    ref = qs._catalog_levels(fresh, th, q, rated, rated, 0.01 * rated)
    for k in ("rated", "half", "plus3", "minus3"):
        assert abs(levels[k] - ref[k]) * ARCMIN_PER_RAD < 1e-6, k


def test_compiled_newton_step_and_norms_equal_numpy():
    """The solver's compiled step (flexrv.model.numerics.static_step) against numpy on a random
    well-conditioned 21 x 21 system: dq = (s diag(m) - J)^-1 R within 1e-12 relative (LU with
    partial pivoting both), its limit to max_step on the scaled size max_i |dq_i| arm_i and its
    halving exact; the norms max |R_i / arm_i| and |R / arm|_2 within 1e-14, max_i |J_ii| / m_i
    exact; a singular matrix is reported (ok False) as numpy raises."""
    from flexrv.model.numerics.static_step import (
        largest_stiffness_per_mass,
        scaled_norms,
        shifted_newton_step,
        work_arrays,
    )

    rng = np.random.default_rng(3)
    n = 21
    jac = -(np.eye(n) * 50.0 + rng.normal(size=(n, n)))
    f = rng.normal(size=n)
    mass = rng.uniform(0.5, 2.0, n)
    arm = np.where(rng.uniform(size=n) < 0.3, 0.05, 1.0)
    a, piv = work_arrays(n)
    dq = np.empty(n)
    ref = np.linalg.solve(0.7 * np.diag(mass) - jac, f)
    size_ref = np.max(np.abs(ref) * arm)
    ok, size, raw = shifted_newton_step(jac, f, 0.7, mass, arm, 1.0, False, a, piv, dq)
    assert ok and np.allclose(dq, ref, rtol=1e-12, atol=0) and size == pytest.approx(size_ref, rel=1e-14)
    assert raw == pytest.approx(np.max(np.abs(ref)), rel=1e-14)
    ok, size, raw = shifted_newton_step(jac, f, 0.7, mass, arm, 0.25 * size_ref, True, a, piv, dq)
    assert ok and np.allclose(dq, ref * 0.125, rtol=1e-12, atol=0)
    assert size == pytest.approx(0.125 * size_ref, rel=1e-14)
    big, l2 = scaled_norms(f, arm)
    assert big == pytest.approx(np.max(np.abs(f / arm)), rel=1e-14)
    assert l2 == pytest.approx(np.linalg.norm(f / arm), rel=1e-14)
    assert largest_stiffness_per_mass(jac, mass) == np.max(np.abs(np.diag(jac)) / mass)
    singular = np.zeros((n, n))
    ok, _, _ = shifted_newton_step(singular, f, 0.0, mass, arm, 1.0, False, a, piv, dq)
    assert not ok


def test_compiled_periodic_image_equals_numpy():
    """The image of a solution one crank revolution later (static_step.turned_deviation) against
    numpy: kin_now + d with the in-plane pairs of d = q - kin_earlier turned by the carrier's
    step, bit for bit (the same operations in the same order; numba contracts no products into
    fused multiply-adds without fastmath); the inputs are left unchanged."""
    from flexrv.model.numerics.static_step import turned_deviation

    rng = np.random.default_rng(5)
    q, kin_a, kin_b = (rng.normal(size=21) for _ in range(3))
    ia, ib = np.array([0, 3, 10], dtype=np.int64), np.array([1, 4, 11], dtype=np.int64)
    c, s = np.cos(0.157), np.sin(0.157)
    d = q - kin_a
    d[ia], d[ib] = c * d[ia] - s * d[ib], s * d[ia] + c * d[ib]
    q0, ka0 = q.copy(), kin_a.copy()
    got = turned_deviation(q, kin_a, kin_b, ia, ib, c, s)
    assert np.array_equal(got, kin_b + d)
    assert np.array_equal(q, q0) and np.array_equal(kin_a, ka0)
