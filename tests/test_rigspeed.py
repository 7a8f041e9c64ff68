"""Speed paths of the rigid and ball models (issue 15) give the answers of the paths
they replace: the compiled history pass of the declared outputs, the tapered-roller
support law's cheaper inner solve, and the Newton settings."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load


def _fast(name, t_ramp=0.005):
    """Rated speed and load reached at ``t_ramp`` (as benchmarks/bench_rigid.py)."""
    r = load(name)
    op = r.operating.model_copy(
        update={"speed_ramp_time_s": t_ramp, "load_ramp_start_s": 0.0, "load_ramp_end_s": t_ramp}
    )
    return r.model_copy(update={"operating": op})


@pytest.fixture(scope="module", params=["rv40e", "rv221"])
def history(request):
    """A short loaded rigid run's recorded states (t, q, v) and its model."""
    from flexrv.post import results as post_results
    from flexrv.simulation import Simulation

    cap = {}
    orig = post_results.results_from_states

    def spy(model, t, q, v, **kw):
        cap.update(t=np.array(t), q=np.array(q), v=np.array(v))
        return orig(model, t, q, v, **kw)

    sim = Simulation(_fast(request.param))
    post_results.results_from_states = spy
    try:
        sim.run(t_end=0.012, dt=1e-4)
    finally:
        post_results.results_from_states = orig
    return sim.model, cap["t"], cap["q"], cap["v"]


def test_compiled_history_equals_per_group_evaluate(history):
    """The fused element's compiled history pass (FusedForces.history, one compiled
    loop over the samples) gives every group output BIT FOR BIT as the groups' own
    evaluate of the history (the per-sample Python path it replaces), also across
    chunk boundaries (chunk 50 of 121 samples), from the same warm starts."""
    from flexrv.model.outputs import group_outputs

    model, t, q, v = history
    assert model.fused is not None and len(t) > 100
    for g in model.groups:  # the same start for both (the supports' inner solves start from the last solution)
        g.reset()
    fast = group_outputs(model, t, q, v, chunk=50)
    fused, model.fused = model.fused, None  # no fused element: every group by its own evaluate
    try:
        for g in model.groups:
            g.reset()
        slow = group_outputs(model, t, q, v, chunk=50)
    finally:
        model.fused = fused
    assert list(fast) == list(slow)
    for name in slow:
        assert fast[name].dims == slow[name].dims and fast[name].units == slow[name].units
        assert np.array_equal(fast[name].values, slow[name].values), name
    assert np.max(fast["pin_force"].values) > 0.0  # loaded: the comparison covers contact forces


@pytest.mark.parametrize("name", ["rv40e", "rv221"])
def test_support_inner_solve_against_independent_root(name):
    """The tapered-roller support's inner solve (crank_support_force: Newton on
    R(b) = F(b) + k_bend (d - b) with the roller directions computed once and a
    tolerance relative to the summed roller load) against an independent root
    finder (scipy.optimize.root, hybr, on the same bearing force F, xtol 1e-15),
    on 300 random crank-centre displacements |d| <= 30 um incl. 60 nearly unloaded
    ones (|d| <= 1 nm, the case whose old tolerance lay below the round-off floor and
    ran the loop to its limit), with and without clearance, from cold and far starts:
    the force agrees within 1e-12 of the summed roller load qs (measured: up to
    6e-13) and the bearing displacement within 1e-12 qs / k_bend (~1e-18 m;
    measured up to 6e-13)."""
    from scipy.optimize import root

    from flexrv.contact.tapered_roller import _bearing, _roller_directions, crank_support_force
    from flexrv.model.factory import build_model

    m = build_model(load(name), exudyn=False)
    g = next(g for g in m.groups if g.name == "crank_supports")
    sc, angles = g.sc, g.angles
    kb = sc.k_bend
    assert kb > 0.0 and not g.linear
    rng = np.random.default_rng(15)
    for i in range(300):
        amp = 1e-9 if i < 60 else 30e-6
        dx, dy = rng.uniform(-amp, amp, 2)
        gam = rng.uniform(0, 2 * np.pi)
        clear = 0.0 if i % 3 else 2e-6
        b0 = rng.uniform(-20e-6, 20e-6, 2) if i % 2 else np.zeros(2)
        fx, fy, kxx, kxy, kyy, hx, hy, bx, by, qs = crank_support_force(
            dx, dy, gam, clear, sc, angles, False, b0[0], b0[1]
        )
        ux, uy = _roller_directions(gam, angles)

        def resid(b):
            f = _bearing(b[0], b[1], clear, sc, ux, uy, False)
            return np.array([f[0] + kb * (dx - b[0]), f[1] + kb * (dy - b[1])]) / kb  # [m]

        sol = root(resid, np.array([bx, by]) * (1 + 1e-6) + 1e-12, method="hybr", options={"xtol": 1e-15})
        ref = _bearing(sol.x[0], sol.x[1], clear, sc, ux, uy, False)
        load_scale = max(qs, abs(fx) + abs(fy), 1.0)
        assert abs(fx - ref[0]) + abs(fy - ref[1]) <= 1e-12 * load_scale, (i, fx - ref[0], fy - ref[1], qs)
        assert np.hypot(bx - sol.x[0], by - sol.x[1]) <= 1e-12 * load_scale / kb, i


@pytest.mark.parametrize(
    "name, model", [("rv40e", "rigid"), ("rv221", "rigid"), ("rv221", "balls"), ("rv221", "flexible")]
)
def test_integrator_records_match_the_history_pass(name, model):
    """The compiled groups' outputs recorded from the integrator's own calls
    (HistoryRecorder, Simulation.run's default) against evaluating them again from
    the recorded states (the history pass, record_outputs=False's path), on the same
    run: nearly every sample is recorded (the rest, segment starts and repeated
    steps, come from the history pass); every output but pin_gap agrees within 2e-9
    of its largest value (before the disc bodies 1.5e-10: the closest points' warm
    starts and the supports' inner solves converge to their tolerances from other
    starts; with the elastic disc rims, measured 2026-11-24: pin forces 6.7e-10,
    pin_friction_power 9.8e-10 on rv221, all else <= 1e-10: the rim Newton of
    pins.pin_body_kernel starts from the solver's last rim offsets in the run and from
    delta = 0 in the history pass and stops at 1e-10 of the largest rim offset,
    ~1e-10 * R_p * 3e-6 rad ~ 3e-17 m on rv221, which the pin contact stiffness
    (~1e9 N/m) turns into ~3e-8 N on pin forces of ~200 N, ~2e-10, with the friction
    outputs more sensitive through the sliding speed; 2e-9 keeps a factor 2 over the
    measured; where the rim Newton stops on its quadratic rule its records are moved to
    the pose of its linearised last correction (pins._shift_records; measured 2026-11-28:
    pin forces 9.7e-11 on rv40e, 3.4e-10 on rv221, all else <= 5.3e-10; 4e-6 without the
    move); the ball model's rows, recorded from their own elements, agree to
    their quasi-static balls' local solve (bearing_kernel.quasi_static_balls, 1e-6
    of the row's largest load, BALL_FORCE_TOL), reached from the run's prediction
    in the one and from the previous sample in the other: measured 2026-11-24 on
    rv221, ball loads 6.2e-7 and the bearing's radial force 2.1e-6 of their largest
    values (with ball inertia, before: 3.5e-16, round-off); bound 1e-5
    relative with a 1e-9 floor [N, N m]; with the
    condensed flexible rings the bearing's outputs agree to the rings' local solve,
    started from other deflections: CONDENSE_TOL = 1e-13 m on the contact deflections
    times a ball's contact stiffness (~1e9 N/m) is ~1e-4 N on ~100 N loads; measured
    ball loads 1.2e-7, carrier forces 6.9e-7 of their largest values (the near-zero
    net axial force 1.2e-9 N), raceway deflections 1.6e-13 m; bounds 2e-6 with a
    1e-8 N floor, and 1e-12 m),
    except disc_rim_offset, which is round-off on both paths (the
    rim compliance C_d of flexrv.fem.disc.rim_compliance is torsional, so the rim
    translation is ~1e-31 m), compared with the rim Newton's absolute floor,
    1e-15 m (pins.pin_body_kernel); pin_gap agrees where the solver evaluated the
    pin, and elsewhere holds a positive lower bound of the exact gap on a pin without
    force."""
    from flexrv.model.outputs import model_outputs
    from flexrv.post import results as post_results
    from flexrv.simulation import Simulation

    cap = {}
    orig = post_results.results_from_states

    def spy(model, t, q, v, **kw):
        cap.update(t=np.array(t), q=np.array(q), v=np.array(v), records=kw.get("records"))
        return orig(model, t, q, v, **kw)

    sim = Simulation(_fast(name), model=model)
    post_results.results_from_states = spy
    try:
        sim.run(t_end=0.03, dt=1e-4)
    finally:
        post_results.results_from_states = orig
    m, t, q, v, rec = sim.model, cap["t"], cap["q"], cap["v"], cap["records"]
    assert rec is not None and all(mask.mean() > 0.99 for mask in rec["valid"].values())
    assert (model != "rigid") == any(g.name == "main_bearing" and "balls0" in d for g, d in rec["data"].items())
    fast = model_outputs(m, t, q, v, records=rec)
    exact = model_outputs(m, t, q, v)
    assert list(fast) == list(exact)
    for key in exact:
        a, b = np.asarray(fast[key].values, dtype=float), np.asarray(exact[key].values, dtype=float)
        if key == "pin_gap":
            continue
        floor = 1e-15 if key == "disc_rim_offset" else 0.0  # [m] the rim Newton's absolute tolerance
        # the flexible rings' run on the compiled integrator (Jacobians kept across steps, ~3.4 Newton
        # corrections per step): the pins' rim Newton ends from other starts, measured 2026-11-28 on rv221
        # pin forces 3.0e-9, the pins' torques 1.1e-9, the disc rims' rotation 1.7e-9 of their largest values
        rel = 6e-9 if model == "flexible" and key.startswith(("pin_", "disc_", "housing_")) else 2e-9
        if model == "flexible" and key.startswith(("ball_", "main_bearing_", "ring_")):
            rel, floor = 2e-6, (1e-12 if key.startswith("ring_deformation") else 1e-8)  # [m], [N] (zero forces)
        elif model == "balls" and key.startswith(("ball_", "main_bearing_")):
            rel, floor = 1e-5, 1e-9  # the balls' local solve; [N], [N m]: net forces that are round-off
        assert np.max(np.abs(a - b), initial=0.0) <= max(rel * max(np.max(np.abs(b), initial=0.0), 1e-300), floor), key
    gap, gap_exact, force = fast["pin_gap"].values, exact["pin_gap"].values, exact["pin_force"].values
    bound = np.abs(gap - gap_exact) > 1e-12
    assert np.all(force[bound] == 0.0) and np.all(gap[bound] > 0.0) and np.all(gap[bound] <= gap_exact[bound])
    assert np.max(force) > 0.0 and (~bound).sum() >= (force > 0).sum()


def test_group_with_its_own_record_keeps_its_own_outputs_path(history):
    """A compiled group that overrides record() (e.g. one written before
    record_sources) is not recorded by the fused element's paths: its outputs come
    from its own evaluate, bit for bit as before, and the others' from the compiled
    pass."""
    from flexrv.model.kernels import FusedForces
    from flexrv.model.outputs import group_outputs

    model, t, q, v = history
    pins = next(g for g in model.groups if g.kind == "pins")
    cls = type(pins)
    legacy = type(
        "LegacyPins", (cls,), {"record": lambda self: {k: a.copy() for k, a in cls.record_sources(self).items()}}
    )
    fused = model.fused
    try:
        pins.__class__ = legacy
        model.fused = FusedForces(model, fused.groups)
        assert pins not in model.fused.recorded and len(model.fused.recorded) == len(fused.groups) - 1
        for g in model.groups:
            g.reset()
        got = group_outputs(model, t, q, v, chunk=50)
    finally:
        pins.__class__ = cls
        model.fused = fused
    for g in model.groups:
        g.reset()
    ref = group_outputs(model, t, q, v, chunk=50)
    assert list(got) == list(ref)
    for name in ref:
        assert np.array_equal(got[name].values, ref[name].values), name


def test_recorder_checkpoint_round_trip_with_bearing_rows():
    """The recorder's buffers of the ball model's recording element (the fused element,
    the bearing rows' records among its entries: per row the per-ball records, the force on
    the frame, the frame and modal coordinates and the frame's velocities; balls with
    inertia) go into a checkpoint (:meth:`HistoryRecorder.arrays`) and come back bit for
    bit (:meth:`HistoryRecorder.fill`, as Simulation.resume does); a checkpoint of another
    layout (a 1-D valid mask, or other buffers) is left to the history pass (nothing
    filled). With quasi-static balls (the default) the same entries."""
    from flexrv.model.kernels import HistoryRecorder
    from flexrv.simulation import Simulation

    keys = ["balls0", "frame0", "x0", "xt0", "balls1", "frame1", "x1", "xt1"]
    sim = Simulation(_fast("rv221"), model="balls", model_options={"ball_inertia": True})
    sim.run(t_end=0.003, dt=1e-4)
    m = sim.model
    group = m.groups[[g.name for g in m.groups].index("main_bearing")]
    rec = HistoryRecorder(m, 8)
    assert len(rec.sources) == 1  # the fused element: every force element of the model
    assert [key for g, key, _ in rec.sources[0][2] if g is group] == keys
    q = np.asarray(m.mbs.systemData.GetODE2Coordinates())
    v = np.asarray(m.mbs.systemData.GetODE2Coordinates_t())
    element = rec.sources[0][0]
    element.memo = (0.0, q.copy(), v.copy())  # its last call at (0, q, v)
    for k in range(4):
        rec.store(k, 0.0, q, v)
    element.memo = None  # its last call was elsewhere
    rec.store(4, 0.0, q, v)
    assert rec.valid[:, :5].tolist() == [[True] * 4 + [False]]
    arrays, valid = rec.arrays(5)
    back = HistoryRecorder(m, 8)
    back.fill(5, arrays, valid)
    assert np.array_equal(back.valid, rec.valid)
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(back.arrays(5)[0], arrays))  # NaN: no contact
    balls = back.records(5)["data"][group]["balls0"]
    assert balls.shape[1:] == group.record_sources()["balls0"].shape
    assert np.max(balls[:4, :, 0]) > 1.0  # inner ball loads [N] of the loaded bearing
    other = HistoryRecorder(m, 8)
    other.fill(5, arrays, valid[0])  # another mask layout
    other.fill(5, arrays[:-1], valid)
    assert not other.valid.any()
    sim = Simulation(_fast("rv221"), model="balls")
    sim.run(t_end=0.002, dt=1e-4)
    rec = HistoryRecorder(sim.model, 8)
    group = sim.model.groups[[g.name for g in sim.model.groups].index("main_bearing")]
    assert len(rec.sources) == 1 and [key for g, key, _ in rec.sources[0][2] if g is group] == keys


def _pack_arrays(x, out):
    """Every array of a (nested) pack, for a snapshot of the kernels' warm-start state."""
    if isinstance(x, np.ndarray):
        out.append(x)
    elif isinstance(x, (tuple, list)):
        for y in x:
            _pack_arrays(y, out)
    return out


def test_first_residual_of_a_step_supplies_the_jacobian(history):
    """With jacobian_each_step (the rigid model's Newton updates its Jacobian every
    step), the first residual call at a new time also fills the Jacobians and the
    solver's Jacobian call at that state returns them without a kernel call: force
    and Jacobians bit for bit those of the kernel called from the same warm-start
    state (what a separate Jacobian call computes differs only by the inner solves
    restarting from their own converged state: 1e-11 relative, measured 2026-11-24);
    a later residual at the same time computes no Jacobian, a Jacobian call at
    another state or after ``full`` calls the kernel."""
    model, t, q, v = history
    fused = model.fused
    runs = []
    call, call_rows = fused._call, fused._call_rows  # (full() of a model run on the compiled integrator: rows)

    def counted(*args):
        runs.append(args[3])
        return call(*args)

    def counted_rows(*args):
        runs.append(args[3])
        return call_rows(*args)

    arrays = _pack_arrays(fused.packs, [])
    fused.jacobian_each_step = True
    fused._call, fused._call_rows = counted, counted_rows
    try:
        fused.residual(float(t[-2]), q[-2].copy(), v[-2].copy())
        snap = [a.copy() for a in arrays]
        t1, q1, v1 = float(t[-1]), q[-1].copy(), v[-1].copy()
        f = fused.residual(t1, q1, v1).copy()
        jq, jv = (a.copy() for a in fused.jacobian(t1, q1.copy(), v1.copy()))
        assert runs == [True, True]  # the second residual's kernel call made the Jacobians; none after it
        for a, s in zip(arrays, snap):
            a[...] = s
        call(t1, q1, v1, True)
        assert np.array_equal(fused.f, f) and np.array_equal(fused.jq, jq) and np.array_equal(fused.jv, jv)
        assert np.abs(jq).max() > 1e8
        for a, s in zip(arrays, snap):
            a[...] = s
        call(t1, q1, v1, False)
        assert np.array_equal(fused.f, f)  # the force does not depend on whether the Jacobians are made
        runs.clear()
        fused.residual(t1, q1 + 1e-9, v1)  # a Newton iterate: same time, no Jacobian
        fused.jacobian(t1, q1, v1)  # another state than the last call's: the kernel
        fused.full(t1, q1, v1, jacobian=False)
        fused.jacobian(t1, q1, v1)  # full() overwrote the arrays: the kernel again
        assert runs == [False, True, False, True]
    finally:
        fused._call, fused._call_rows = call, call_rows
        fused.jacobian_each_step = False


def test_simulation_sets_jacobian_each_step_from_its_newton_settings():
    """On Exudyn's integrator the fused element makes its Jacobians with the step's first
    residual exactly when the solver updates the Jacobian at every step (the rigid model's
    default)."""
    from flexrv.simulation import Simulation

    sim = Simulation(_fast("rv40e"))
    sim.run(t_end=0.002, integrator="exudyn")
    assert sim.model.fused.jacobian_each_step is True
    sim.run(t_end=0.002, integrator="exudyn", newton_options={"modifiedNewtonJacUpdatePerStep": False})
    assert sim.model.fused.jacobian_each_step is False
