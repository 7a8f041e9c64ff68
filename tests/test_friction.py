"""Friction (issue 14): the regularised Coulomb law, its use in the pin and needle
kernels (exact Jacobians), the switch that removes it exactly, the hysteresis of a
Coulomb element, the loop energy, the efficiency and the energy balance of a driven
run, and the pin-mesh loss against kinematic sliding speeds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexrv.contact.laws import _friction_one, effective_pin_friction, friction_factor
from flexrv.design import load, override
from flexrv.model.assembled import group_index
from flexrv.model.factory import build_model


# ----------------------------------------------------------------------------- the law
def test_friction_factor_closed_form():
    """s(v) = v / sqrt(v^2 + v_reg^2) and ds/dv = v_reg^2 / (v^2 + v_reg^2)^1.5 at
    chosen speeds (1e-15 rel.), odd in v, s(0) = 0, s(10 v_reg) = 10/sqrt(101), ds/dv
    vs central differences (h = 1e-4 v_reg: within 1e-7 of its peak 1/v_reg), and v_reg = 0 switches it off."""
    v_reg = 2e-5
    v = np.array([-1e-2, -3e-5, -1e-6, 0.0, 1e-6, 3e-5, 1e-2])
    s, ds = friction_factor(v, v_reg)
    assert np.allclose(s, v / np.sqrt(v**2 + v_reg**2), rtol=1e-15, atol=0)
    assert np.allclose(ds, v_reg**2 / (v**2 + v_reg**2) ** 1.5, rtol=1e-15, atol=0)
    assert np.array_equal(s, -s[::-1]) and s[3] == 0.0
    assert _friction_one(10 * v_reg, v_reg)[0] == pytest.approx(10 / math.sqrt(101), rel=1e-15)
    h = 1e-4 * v_reg
    for x in v:
        fd = (_friction_one(x + h, v_reg)[0] - _friction_one(x - h, v_reg)[0]) / (2 * h)
        assert fd == pytest.approx(_friction_one(x, v_reg)[1], abs=1e-7 / v_reg)  # 1e-7 of the peak 1/v_reg
    assert _friction_one(1e-3, 0.0) == (0.0, 0.0)


def test_effective_pin_friction():
    """A pin free to turn in its groove slides where friction is lower: min(mu_disc, mu_seat)."""
    assert effective_pin_friction(0.05, 0.08) == 0.05
    assert effective_pin_friction(0.1, 0.03) == 0.03
    assert effective_pin_friction(0.0, 0.08) == 0.0


# ----------------------------------------------------------------------------- kernels
def _loaded_state(m, v_scale, seed=1):
    """Discs turned into the pins, cranks onto their drive flanks, random speeds."""
    rng = np.random.default_rng(seed)
    q = m.q0.copy()
    for k in range(m.params.n_discs):
        q[m.slice(f"disc{k}").start + 2] += 1.5e-4
    for j in range(m.params.n_cranks):
        q[m.slice(f"crank{j}").start + 2] += 5e-5
    q += rng.normal(scale=1e-7, size=q.shape)
    return q, rng.normal(scale=v_scale, size=q.shape)


def _group_fd(m, g, q, v, hq=3e-10, hv=1e-9):
    """(analytic jq, jv; central differences of the group's own force in q and v)."""
    ix = np.arange(m.n)[group_index([m.members[n].offset for n in g.members], [m.members[n].n for n in g.members])]
    g.new_step()
    jq, jv = (a.copy() for a in g.jacobian(0.0, q[ix], v[ix]))

    def force(qq, vv):
        g.new_step()
        return g.evaluate(0.0, qq, vv)[0].copy()

    n = len(ix)
    nq, nv = np.zeros_like(jq), np.zeros_like(jv)
    for i in range(n):
        e = np.zeros(n)
        e[i] = hq
        nq[:, i] = (force(q[ix] + e, v[ix]) - force(q[ix] - e, v[ix])) / (2 * hq)
        e[i] = hv
        nv[:, i] = (force(q[ix], v[ix] + e) - force(q[ix], v[ix] - e)) / (2 * hv)
    return jq, jv, nq, nv


@pytest.mark.parametrize("v_scale", [1e-5, 1e-3])
def test_pin_friction_jacobian_vs_central_differences(v_scale):
    """Pin kernel with friction (rv40e preset: mu_eff 0.05, v_reg 0.01 mm/s), rigid
    disc bodies and housing (second_stage.disc_body_model = housing.body_model = "rigid": the plain pin kernel, the
    friction Jacobian itself): dF/dq and dF/dv equal central differences of its own
    force (h = 3e-10 in q, 1e-9 / 1e-8 in v) within 1e-6 of the largest entry, at
    sliding speeds around v_reg (the stiff part of the regularisation, speeds ~1e-5)
    and far beyond it (~1e-3). Measured 2026-11-24: 6-8e-9 (q), 4e-9 / 4e-8 (v: the
    differences' round-off). The friction must be active: dF/dv is dominated by
    mu F / v_reg (> 1e5 N s/m at 1e-5) and the friction power < 0."""
    m = build_model(
        override(load("rv40e"), {"second_stage.disc_body_model": "rigid", "housing.body_model": "rigid"}), exudyn=False
    )
    g = next(g for g in m.groups if g.name == "pins")
    assert g.mu == 0.05 and g.v_reg == pytest.approx(1e-5) and not g.elastic_discs
    q, v = _loaded_state(m, v_scale)
    jq, jv, nq, nv = _group_fd(m, g, q, v, hv=1e-9 if v_scale < 1e-4 else 1e-8)
    assert np.abs(nq).max() > 5e8  # pins in contact (with the pin seats in series: 1.7e9 N/m here)
    if v_scale < 1e-4:
        assert np.abs(nv).max() > 1e5
    assert g.pw.sum() < 0.0 and np.all(g.pw <= 0.0)
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    assert np.abs(jv - nv).max() <= 1e-6 * np.abs(nv).max()


@pytest.mark.parametrize("v_scale", [1e-5, 1e-3])
def test_pin_friction_jacobian_with_disc_rim_condensation(v_scale):
    """The pins group with friction AND the elastic disc rims (rv40e preset,
    pins.pin_body_kernel: Q_eff(q, v) = Q(q + delta, v), delta = C_d Q_eff) vs central
    differences of its own force. The condensed Jacobians are exact derivatives of
    Q_eff: differentiating delta = C_d Q(q + delta, v) gives d(delta)/dv =
    (I - C_d J)^-1 C_d J_v, so dQ_eff/dv = J_v + J d(delta)/dv = (I - J C_d)^-1 J_v
    (push-through identity), and likewise in q; the rim's own velocity is left out of
    the damping by design, consistently in the force and the Jacobian. dF/dq within
    1e-6 of the largest entry (h = 3e-10; measured 8e-9). dF/dv: the force carries a
    noise eps_F from the rim Newton: the rim pose q_hub + delta is rounded differently
    for different Newton paths (a perturbation of one disc changes the shared
    iteration count of all), eps_F ~ J r_p eps |q| ~ 1e9 * 0.06 * 2.2e-16 ~ 1e-8 N, and
    the rim Newton stops within its tolerance (1e-10 of max|delta|, at least 1e-15 m), which
    the contact stiffness (~1.7e9 N/m) turns into up to ~2e-6 N between two starts: checked
    below as the spread of the force over Newton starts, bound 5e-6 N (measured 2.4e-6 N with
    the closest points' second-order warm start, 6e-8 N without it, where the iterations
    happened to end far inside the tolerance). A central difference then errs by up to eps_F / h: with h_v = 1e-8 /
    1e-7, 10 / 1 N s/m, i.e. 5e-6 / 4e-3 of the largest entry (2.3e6 / 268 N s/m), so
    the bounds are 1e-5 / 4e-3 (measured 4e-7 / 9e-5); the rigid-disc test above
    checks the friction Jacobian itself at 1e-6. The housing is rigid here (its
    coupled rim Newton with friction: tests/test_housing.py)."""
    m = build_model(override(load("rv40e"), {"housing.body_model": "rigid"}), exudyn=False)
    g = next(g for g in m.groups if g.name == "pins")
    assert g.mu == 0.05 and g.elastic_discs
    q, v = _loaded_state(m, v_scale)
    jq, jv, nq, nv = _group_fd(m, g, q, v, hv=1e-8 if v_scale < 1e-4 else 1e-7)
    assert np.abs(nq).max() > 5e8 and g.pw.sum() < 0.0 and np.all(g.pw <= 0.0)
    assert np.abs(g.dstate[:, 2]).max() > 1e-5  # the rims turn relative to their hubs
    assert np.abs(jq - nq).max() <= 1e-6 * np.abs(nq).max()
    assert np.abs(jv - nv).max() <= (1e-5 if v_scale < 1e-4 else 4e-3) * np.abs(nv).max()
    g.new_step()
    f0, d0 = g.evaluate(0.0, q, v)[0].copy(), g.dstate.copy()
    spread = 0.0
    for start in (0.0, 0.5, 2.0):  # the same state from other Newton starts
        g.dstate[:] = start * d0
        g.new_step()
        spread = max(spread, np.abs(g.evaluate(0.0, q, v)[0] - f0).max())
    assert spread <= 5e-6


@pytest.mark.parametrize("needle", ["empirical", "rollers"])
def test_needle_friction_jacobian_vs_central_differences(needle):
    """Needle kernel with the friction moment vs central differences of its own force:
    dF/dv (exact: the regularisation term -mu F (d/2)^2 s' and the load's rate terms)
    within 1e-5 of the largest entry; dF/dq no worse than the frictionless kernel's
    (+ 1e-6 of the largest entry): the force Jacobian drops the rotation of the
    eccentric/hole arms (~F e, documented in flexrv.model.cranks_discs; ~1e-4 of the
    largest entry empirical, 1e-8 rollers), and the friction moment's load derivative
    uses that same force Jacobian. Speeds 1e-5 m/s (~v_reg: the moment's damping
    mu F (d/2)^2 / v_reg enters) and 1e-3."""
    # a 6 um total needle clearance, which the loaded state (_loaded_state) closes
    red = override("rv40e", {"needle_bearing.model": needle, "needle_bearing.radial_clearance_um": 6.0})
    models = [build_model(r, exudyn=False) for r in (red, override(red, {"contact.friction": False}))]
    for v_scale in (1e-5, 1e-3):
        err = []
        for m in models:
            g = next(g for g in m.groups if g.name == "needle_bearings")
            q, v = _loaded_state(m, v_scale)
            jq, jv, nq, nv = _group_fd(m, g, q, v)
            err.append(np.abs(jq - nq).max() / np.abs(nq).max())
            if g.mu > 0.0:
                assert g.mu == 0.0025 and np.all(g.pw <= 0.0) and g.pw.sum() < 0.0
                assert np.abs(jv - nv).max() <= 1e-5 * np.abs(nv).max()
        assert err[0] <= err[1] + 1e-6, err


def test_friction_switch_and_zero_coefficients_are_exact():
    """contact.friction = false and friction = true with every coefficient 0 give the
    same forces and Jacobians bit for bit (1e-12 rel. asked, 0 measured: the friction
    code is skipped), and with friction on at zero speed the forces are those of the
    frictionless model (s(0) = 0; bit for bit from the same warm starts: the groups are
    reset first, since the elastic disc rims' Newton (pins.pin_body_kernel) starts from
    its last call's rim offsets, and other starts differ at round-off). The frictionless
    numbers are also those of before issue 14: tests/test_kernel.py compares the
    frictionless model with the stored reference forces (tests/data/force_reference.npz)."""
    base = load("rv40e")
    off = build_model(override(base, {"contact.friction": False}), exudyn=False)
    zero = build_model(
        override(
            base,
            {
                "contact.pin_friction_coefficient": 0.0,
                "contact.pin_seat_friction_coefficient": 0.0,
                "contact.needle_friction_coefficient": 0.0,
            },
        ),
        exudyn=False,
    )
    on = build_model(base, exudyn=False)
    q, v = _loaded_state(off, 1e-3)
    fo, dqo, dvo = off.generalized_forces(0.002, q, v)
    fz, dqz, dvz = zero.generalized_forces(0.002, q, v)
    for a, b in ((fo, fz), (dqo, dqz), (dvo, dvz)):
        assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max()
    for g in off.groups + on.groups:
        g.reset()
    fo0 = off.generalized_forces(0.002, q, 0 * v, jacobian=False)[0]
    fn0 = on.generalized_forces(0.002, q, 0 * v, jacobian=False)[0]
    assert np.array_equal(fo0, fn0)
    fn = on.generalized_forces(0.002, q, v, jacobian=False)[0]
    assert np.abs(fn - fo).max() > 1.0  # friction on acts at speed


@pytest.mark.parametrize(
    "field,value",
    [
        ("pin_friction_coefficient", 0.7),
        ("needle_friction_coefficient", -0.01),
        ("pin_seat_friction_coefficient", 0.51),
        ("friction_velocity_mm_per_s", 0.0),
    ],
)
def test_friction_field_out_of_range(tmp_path, capsys, field, value):
    """A friction field out of range: one message naming field, value and allowed range, exit 2."""
    from flexrv.cli import main
    from flexrv.design import preset_path

    text = preset_path("rv40e").read_text()
    line = next(ln for ln in text.splitlines() if ln.startswith(f"{field} ="))
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(line, f"{field} = {value}"))
    with pytest.raises(SystemExit) as exc:
        main(["design", str(bad)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"contact.{field} = {value}" in err and "allowed" in err, err
    assert "Traceback" not in err


# ----------------------------------------------------------------------------- hysteresis
def _coulomb_element_loop(k=1e6, f_c=100.0, t_r=1000.0, mass=1e-3, quarter=0.2, dt=1e-4, v_reg=1e-5):
    """A mass on a spring k with friction force f_c s(v) (THE compiled law of the
    kernels) under the stiffness-test program 0 -> +T_r -> -T_r -> 0 (each quarter over
    ``quarter`` s), integrated by backward Euler with Newton on the velocity (exact
    derivative ds/dv). The mass is small (1 g: natural period 0.2 ms, 2 dt) so that the
    loading is quasi-static, as in the reducer's test (its output period ~1 ms, 5 % of a
    quarter): backward Euler damps the element's own vibration. Returns (time, load, x, program times)."""
    times = np.array([0.0, quarter, 3 * quarter, 4 * quarter])
    n = int(round(times[-1] / dt))
    t = np.arange(n + 1) * dt
    load_ = np.interp(t, times, [0.0, t_r, -t_r, 0.0])
    x, v = np.zeros(n + 1), 0.0
    for i in range(n):
        # m (v' - v)/dt = F - k (x + dt v') - f_c s(v'): r(v') increasing, one root; Newton kept
        # inside a shrinking bracket (bisection when it leaves it: s is stiff near 0)
        lo, hi, vn = -1.0, 1.0, v
        for _ in range(200):
            s, ds = _friction_one(vn, v_reg)
            r = mass * (vn - v) / dt - load_[i + 1] + k * (x[i] + dt * vn) + f_c * s
            if abs(r) <= 1e-12 * (f_c + t_r) or hi - lo <= 1e-16:
                break
            if r > 0.0:
                hi = vn
            else:
                lo = vn
            step = vn - r / (mass / dt + k * dt + f_c * ds)
            vn = step if lo < step < hi else 0.5 * (lo + hi)
        v = vn
        x[i + 1] = x[i] + dt * v
    return t, load_, x, times


def test_coulomb_element_hysteresis_width_and_loss():
    """Coulomb element (k = 1e6 N/m, F_c = 100 N, T_r = 1000 N, quarter 0.2 s: sliding
    speed Fdot/k = 5 mm/s = 500 v_reg): the stiffness-test evaluation
    (flexrv.post.stiffness) gives the analytic hysteresis width 2 F_c / k and loop area
    4 F_c (T_r - F_c) / k (the parallelogram of two sliding branches and two stick
    phases). Tolerance of the width: the regularised sliding force is F_c s(v),
    1 - s = v_reg^2 / (2 v^2) = 2e-6 at 500 v_reg, and backward Euler holds the sliding
    branch in equilibrium at every step (linear interpolation at T = 0 exact on a line):
    1e-4 rel. allowed (measured -2.0e-6, the predicted 1 - s). Area: the stick phases creep
    at ~v_reg (F - k x)/F_c, which rounds the parallelogram's corners: 1e-3 rel. allowed
    (measured 1.6e-4)."""
    from flexrv.post.stiffness import evaluate_stiffness_test
    from flexrv.units import ARCMIN_PER_RAD

    k, f_c, t_r = 1e6, 100.0, 1000.0
    t, load_, x, times = _coulomb_element_loop(k, f_c, t_r)
    fig = evaluate_stiffness_test(t, load_, x, times)  # x in "rad" -> arcmin in the figures
    width = fig.hysteresis_arcmin / ARCMIN_PER_RAD
    assert width == pytest.approx(2 * f_c / k, rel=1e-4)
    assert fig.hysteresis_loss_J == pytest.approx(4 * f_c * (t_r - f_c) / k, rel=1e-3)
    assert fig.rigidity_Nm_per_arcmin == pytest.approx(k / ARCMIN_PER_RAD, rel=1e-4)  # slope k on both branches
    # no friction: no loop (width and area 0 up to the inertia's lag)
    t, load_, x, times = _coulomb_element_loop(k, 0.0, t_r)
    fig0 = evaluate_stiffness_test(t, load_, x, times)
    assert abs(fig0.hysteresis_arcmin / ARCMIN_PER_RAD) <= 1e-3 * 2 * f_c / k
    assert abs(fig0.hysteresis_loss_J) <= 1e-3 * 4 * f_c * (t_r - f_c) / k


def test_loop_energy_closed_form():
    """loop_energy of a parallelogram loop (branches theta = (T -+ c)/k, stick phases at
    the reversals) = 4 c (T_r - c) / k to 1e-6 (trapezoid rule on a piecewise-linear loop
    with 2001 samples: exact up to the kinks' cells)."""
    from flexrv.post.stiffness import loop_energy

    k, c, t_r = 2e5, 30.0, 400.0
    td = np.linspace(t_r, -t_r, 801)
    ad = np.minimum((td + c) / k, (t_r - c) / k)  # stick at the top, then the descending line
    tb = np.linspace(-t_r, 0.0, 401)
    ab = np.maximum((tb - c) / k, (-t_r + c) / k)
    assert loop_energy(td, ad, tb, ab, t_r, samples=4001) == pytest.approx(4 * c * (t_r - c) / k, rel=1e-5)


# ----------------------------------------------------------------------------- driven run
@pytest.fixture(scope="module")
def driven():
    """rv40e rigid, speed and load ramped in over 20 ms (tests/regression_cases.py FAST),
    0.06 s at dt 1e-4; the window t >= 0.03 s (loaded, at speed)."""
    from flexrv.simulation import Simulation

    red = override(
        "rv40e",
        {"operating.speed_ramp_time_s": 0.02, "operating.load_ramp_start_s": 0.0, "operating.load_ramp_end_s": 0.02},
    )
    res = Simulation(red).run(t_end=0.06, dt=1e-4)
    return red, res, res.ds.sel(time=slice(0.03, None))


def test_energy_balance_with_friction(driven):
    """Driven run: mean input power = mean output power + mean friction dissipation +
    dE_kin/dt within 1 % of the input power (asked; measured 4e-5: the rest is the contact
    damping and the change of elastic energy over the window). Friction is ~6 % of the
    input (pins ~2/3, needles ~1/3), so the check is not empty."""
    _, _, ds = driven
    t = ds.time.values
    p_in, p_out, p_f = (float(ds[k].mean()) for k in ("power_in", "power_out", "friction_power"))
    ke = ds["kinetic_energy"].values
    dke = (ke[-1] - ke[0]) / (t[-1] - t[0])
    assert 0.03 * p_in < p_f < 0.1 * p_in
    pins = float(ds["pin_friction_power"].sum("disc").mean())
    needles = float(ds["needle_friction_power"].sum(("crank", "disc")).mean())
    assert pins + needles == pytest.approx(p_f, rel=1e-12) and pins > needles > 0.0
    assert abs(p_in - p_out - p_f - dke) <= 0.01 * p_in


def test_friction_loss_vs_kinematic_sliding_speeds(driven):
    """Pin-mesh and needle losses against the textbook estimate from the contact loads and
    the KINEMATIC sliding speeds (rigid conjugate action, flexrv.geometry.kinematics.
    member_speeds): the disc rolls its pitch circle (radius z_c e) in the pins' pitch
    circle (z_rp e), so relative to the housing it turns at omega_d about the pitch point
    I = z_rp c_k (c_k the disc centre), the contact normal passes through I and the
    contact point X slides at omega_d |I X|, |I X| = |I P_i| - r_i:
    P_pins = mu_eff |omega_d| sum F_i (|I P_i| - r_i); each needle bearing slides at
    (d/2) |omega_crank - omega_disc|: P_needles = mu_b (d/2) |omega_crank - omega_disc|
    sum |F_jk|. Efficiency estimate eta = 1 - (P_pins + P_needles)/P_in vs the simulated
    P_out/P_in. Tolerances: 1 % on the losses (the modified profile's normals miss the
    pitch point by O(dR_p / R_p) and the elastic deflections change the arms by ~um of
    ~50 mm; the regularisation matters only within ~0.1 mm of the pitch point where F ~ 0;
    measured 1.8e-5 on the pins, 9e-7 on the needles) and 1e-3 on eta (measured 5.8e-5:
    0.93858 estimated vs 0.93852 simulated, the rest being the contact damping)."""
    from flexrv.geometry.kinematics import member_speeds
    from flexrv.model.cranks_discs import NeedleBearings
    from flexrv.model.drive import drive_parameters
    from flexrv.model.pins import PinContacts
    from flexrv.post.stats import mean_speed

    red, _, ds = driven
    d = drive_parameters(red)
    p, pn = PinContacts.parameters(red, d), NeedleBearings.parameters(red, d)
    fs, ss = red.first_stage, red.second_stage
    t = ds.time.values
    sp = member_speeds(mean_speed(ds["theta_in"].values, t), fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    ix, iy = d.z_rp * ds["disc_x"].values, d.z_rp * ds["disc_y"].values  # pitch points (T, disc)
    arm = np.hypot(p.pins[:, 0] - ix[..., None], p.pins[:, 1] - iy[..., None]) - p.pin_radii
    est_pins = p.pin_friction * abs(sp.disc_rotation) * (ds["pin_force"].values * arm).sum(axis=(1, 2)).mean()
    rel = abs(sp.crank_absolute - sp.disc_rotation)
    est_needles = pn.friction * pn.friction_radius * rel * ds["needle_force"].values.sum(axis=(1, 2)).mean()
    sim_pins = float(ds["pin_friction_power"].sum("disc").mean())
    sim_needles = float(ds["needle_friction_power"].sum(("crank", "disc")).mean())
    assert est_pins == pytest.approx(sim_pins, rel=0.01)
    assert est_needles == pytest.approx(sim_needles, rel=0.01)
    p_in, p_out = float(ds["power_in"].mean()), float(ds["power_out"].mean())
    assert 1.0 - (est_pins + est_needles) / p_in == pytest.approx(p_out / p_in, abs=1e-3)


# ----------------------------------------------------------------------------- stiffness test
#: quarter time [s] of the loops below (their pinned figures were measured with it; the default is longer)
QUARTER = 0.02
#: the frictionless rv40e loop at QUARTER on the current physics, re-measured at every intended change
#: of the torque path (the CHANGELOG records the old and new values); the path compliances of
#: flexrv.analysis.path_compliances in the models, the needle clearance at the ISO 5753-1 C2 midpoint
TODAY_RV40E = {
    "rigidity_Nm_per_arcmin": 173.52593522630346,
    "lost_motion_arcmin": 1.025844651379018,
    "hysteresis_arcmin": 1.8536673779065174,
}
#: relative tolerance of TODAY_RV40E: the loop's figures at the default Newton tolerance move by ~1e-3 with
#: equivalent residuals (rigidity 196.79, 196.84, 196.69 N m/arcmin for the same model with the row-kernel and
#: condensation speed-ups of issue 15, 2026-11-24; a cold FE rebuild alone: 1e-5)
TODAY_RTOL = 2e-3


def test_stiffness_loop_closes_as_mu_goes_to_zero():
    """rv40e rigid stiffness test: (1) friction off gives today's figures (clearance-only
    hysteresis 1.8537 arcmin, rigidity, lost motion) to TODAY_RTOL (2e-3: the default-tolerance Newton path moves
    them by ~1e-3 between equivalent residuals; a cold rebuild of the FE carrier and disc bodies reproduces the
    rigidity to 1e-5) and zero friction energy;
    (2) with friction the energy dissipated by friction over the program, E(mu) (the
    integral of friction_power), is > 0, grows with mu and vanishes with it: E(s mu) / s for
    s = 1/4, 1/2 of the preset's coefficients lies between E(mu) and 2 E(mu) (Coulomb work
    mu F x slip; the slip shrinks as friction holds the contacts, so E is sublinear:
    measured 3.48, 5.48, 8.11 mJ). The loop width at T = 0 stays the clearance's
    within 0.01 arcmin (measured <= 0.001): with the input locked the contacts slide only by
    their elastic deflections (um), so friction adds ~8 mJ per cycle to a loop whose area is
    dominated by crossing the clearance (hysteresis_loss 0.0182 J frictionless, 0.0213 J with friction;
    the loop area is not a clean friction measure: the crossing's dynamics scatter it by
    ~1 mJ)."""
    from flexrv.simulation import stiffness_test

    fig, _ = stiffness_test(override("rv40e", {"contact.friction": False}), quarter_time=QUARTER)
    for key, value in TODAY_RV40E.items():
        assert getattr(fig, key) == pytest.approx(value, rel=TODAY_RTOL), key
    assert fig.friction_energy_J == 0.0
    energy = {}
    for s in (0.25, 0.5, 1.0):
        red = override(
            "rv40e", {"contact.pin_friction_coefficient": 0.05 * s, "contact.needle_friction_coefficient": 0.0025 * s}
        )
        f, _ = stiffness_test(red, quarter_time=QUARTER)
        energy[s] = f.friction_energy_J
        assert abs(f.hysteresis_arcmin - TODAY_RV40E["hysteresis_arcmin"]) < 0.01
    assert 0.0 < energy[0.25] < energy[0.5] < energy[1.0]
    for s in (0.25, 0.5):
        assert energy[1.0] < energy[s] / s < 2.0 * energy[1.0]
