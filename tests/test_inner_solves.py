"""The force kernel's inner solves: the pins' per-contact records after the rim Newton's
quadratic stop, moved to the pose of the linearised last correction
(flexrv.model.pins._shift_records), equal an exact evaluation of the pin kernel there; the
crank bearings' first-order Newton start (flexrv.model.cranks_discs._bearing_start) is
second order in the change of the crank's displacement; the roller directions by rotation
and the elastic carrier's calls without the Jacobian (no tangent) keep the answers."""

from __future__ import annotations

import dataclasses

import numpy as np

from flexrv.design import load
from flexrv.model.drive import drive_parameters


def _rigid_pins():
    """rv40e's pins with rigid discs and housing (the plain pin kernel), a loaded state with
    sliding velocities (the friction records act)."""
    from flexrv.model.factory import _members
    from flexrv.model.pins import PinContacts

    r = load("rv40e")
    p = PinContacts.parameters(r, drive_parameters(r))
    p = dataclasses.replace(p, disc_compliance=np.zeros((0, 3, 3)), housing_compliance=0.0)
    mem = _members(p.drive)
    q = np.concatenate([mem[f"disc{k}"].q0 for k in range(p.drive.n_discs)])
    q[2::3] -= 3e-4  # the discs turned against their pins: loaded
    v = np.zeros_like(q)
    v[0::3], v[1::3], v[2::3] = 2e-4, -1e-4, 1e-2
    return p, q, v


def _evaluate(g, pack, q, v):
    from flexrv.model.pins import pin_kernel

    n = q.shape[0]
    pin_kernel(q, v, np.zeros(n), np.zeros((n, n)), np.zeros((n, n)), True, pack.pins)
    return {k: getattr(g, k).copy() for k in ("gap", "force", "nx", "ny", "rxn", "ft", "pw")}


def test_shifted_records_equal_an_exact_evaluation_at_the_corrected_pose():
    """After a quadratic stop the rim Newton applies its last correction dq linearised and
    moves the last evaluation's records by dq (_shift_records: first order in dq through
    the gap gradient and the normal's turn of the kernel's Jacobian, the contact and
    friction laws evaluated again). Against an exact evaluation at q + dq (every pin, cold
    closest points) for a correction of |dP| ~ 6e-10 m (the corrections of a run are
    ~1e-12 m): gaps of the evaluated pins within 1e-15 m (the remainder ~h |dP|^2 ~
    4e-17 m; measured 3e-16), forces, friction forces and powers within 1e-9 of their largest
    value (measured 6e-11), the normals and arms within 1e-11 (the remainder (h |dP|)^2 ~
    1e-11 at the tooth tip's curvature h = 4.7e3 /m; measured 5.9e-12, falling as |dq|^2 to
    the closest points' own floor ~1e-13); a pin the kernel proved open keeps a positive lower
    bound of its exact gap. Without the shift the records differ by ~1e-4 of the largest
    force (checked: the comparison sees the correction)."""
    from flexrv.model.pins import PinContacts, _shift_records

    p, q, v = _rigid_pins()
    idx = np.arange(q.shape[0], dtype=np.int64)
    g, ref = PinContacts(p), PinContacts(p)
    pack = g.pack(idx)
    _evaluate(g, pack, q, v)
    before = _evaluate(g, pack, q, v)  # the second call skips the pins its last exact gaps prove open
    skipped = np.isnan(g.curv[..., 0])
    assert skipped.sum() >= 10 and (before["force"] > 0).sum() >= 10
    dq = np.zeros_like(q)
    dq[0::3], dq[1::3], dq[2::3] = 2e-10, -1e-10, 3e-9
    _shift_records(pack.pins, q, v, dq)
    exact = _evaluate(ref, ref.pack(idx, history=True), q + dq, v)
    shifted = {k: getattr(g, k) for k in exact}
    fmax = np.abs(exact["force"]).max()
    assert np.abs(before["force"] - exact["force"]).max() > 1e-5 * fmax  # the correction is seen
    ev = ~skipped
    assert np.abs(shifted["gap"] - exact["gap"])[ev].max() <= 1e-15
    assert np.all(shifted["gap"][skipped] > 0.0) and np.all(shifted["gap"][skipped] <= exact["gap"][skipped])
    assert np.all(exact["force"][skipped] == 0.0)
    for key in ("force", "ft", "pw"):
        scale = np.abs(exact[key]).max()
        assert scale > 0.0 and np.abs(shifted[key] - exact[key]).max() <= 1e-9 * scale, key
    for key in ("nx", "ny", "rxn"):
        assert np.abs(shifted[key] - exact[key])[ev].max() <= 1e-11, key


def test_bearing_start_is_second_order_in_the_displacement_change():
    """The crank support's inner Newton starts from b_prev + (I - K_s / k_bend)(d - d_prev)
    (db/dd = (K_b + k I)^-1 k = I - K_s / k, the series tangent K_s of the last solution).
    Against the converged b at d_prev + e (crank_support_force, tests/test_rigspeed.py checks
    it against an independent root finder) on rv40e's loaded support (|d| = 25 um, with and
    without clearance): the start's error falls as |e|^2 (ratio <= 0.02 for |e| 10x
    smaller; exactly 0.01 for a quadratic remainder) and is below 1e-3 of the previous
    solution's (b_prev: first order, ~|e| k / (K_b + k)) at |e| = 1e-8 m. Measured: 4.9e-14 m
    against 4.0e-9 m at |e| = 1e-8 m, ratio 0.0100 (5.5e-14 m with the clearance). A zero
    state (a reset) starts from b_prev."""
    from flexrv.contact.tapered_roller import crank_support_force
    from flexrv.model.cranks_discs import BEARING_STATE, CrankSupports, _bearing_start

    r = load("rv40e")
    g = CrankSupports(CrankSupports.parameters(r, drive_parameters(r)))
    sc, angles, kb = g.sc, g.angles, g.sc.k_bend
    assert kb > 0.0 and not g.linear
    for clear in (0.0, 2e-6):
        d = np.array([15e-6, -20e-6])
        gam = 0.7
        fx, fy, kxx, kxy, kyy, _, _, bx, by, _ = crank_support_force(d[0], d[1], gam, clear, sc, angles, False, 0, 0)
        state = np.zeros((1, BEARING_STATE))
        state[0, :7] = bx, by, d[0], d[1], kxx, kxy, kyy
        errs, prev = [], []
        for eps in (1e-8, 1e-9):
            e = eps * np.array([0.6, -0.8])
            start = np.array(_bearing_start(state, 0, d[0] + e[0], d[1] + e[1], kb))
            sol = crank_support_force(d[0] + e[0], d[1] + e[1], gam, clear, sc, angles, False, *start)
            exact = np.array(sol[7:9])
            errs.append(np.hypot(*(start - exact)))
            prev.append(np.hypot(bx - exact[0], by - exact[1]))
        assert errs[0] <= 1e-3 * prev[0], (errs, prev)
        assert errs[1] <= 0.02 * errs[0], errs
        zero = np.zeros((1, BEARING_STATE))
        zero[0, :2] = bx, by
        assert _bearing_start(zero, 0, d[0] + 1e-8, d[1], kb) == (bx, by)


def test_foot_point_prediction_is_third_order_in_the_pin_motion():
    """The pins' closest-point warm start (flexrv.model.pins._pin_foot): phi + g . dP +
    dP^T H dP / 2 with the foot point's derivatives g = dphi/dP = C'/D and H = d2phi/dP2 of the
    implicit function (P - C(phi)) . C'(phi) = 0 (pins._foot_derivatives) stored at the last exact
    evaluation. Against the foot points of the moved positions found independently
    (flexrv.geometry.cycloid.pin_gap's Newton to 1e-14 rad) on every pin of rv40e's discs: the
    error is third order in |dP| (a tenth of the motion: at most 3e-3 of the error, where a
    wrong second derivative would leave 1e-2 and a wrong gradient 1e-1), the largest over the
    pins below 5e-8 rad at |dP| = 1 um (measured 6.4e-9 rad at 1 um, 6.2e-6 rad at 10 um: ratio
    1.03e-3)."""
    from flexrv.geometry.cycloid import pin_gap
    from flexrv.model.pins import GRAD, HESS, PinContacts, PinControl

    p, q, v = _rigid_pins()
    g = PinContacts(p)
    pack = g.pack(np.arange(q.shape[0], dtype=np.int64))
    pack = pack._replace(pins=pack.pins._replace(control=PinControl.of(restart_every=0, skip_open=False)))
    _evaluate(g, pack, q, v)
    rng = np.random.default_rng(3)
    errs = {}
    for eps in (1e-5, 1e-6):
        worst = 0.0
        for kd in range(g.nd):
            d_r = g.profile[kd, 0]
            for i in range(len(g.pins)):
                last = g.last[kd, i]
                assert np.all(np.isfinite(last[GRAD : HESS + 3]))
                u = rng.normal(size=2)
                dp = eps * u / np.linalg.norm(u)
                hess = np.array([[last[HESS], last[HESS + 1]], [last[HESS + 1], last[HESS + 2]]])
                pred = g.phi[kd, i] + last[GRAD : GRAD + 2] @ dp + 0.5 * dp @ hess @ dp
                point = last[1:3] + dp
                _, _, exact = pin_gap(
                    point,
                    p.drive.z_rp,
                    p.pin_circle_radius,
                    p.pin_radius,
                    p.drive.eccentricity,
                    d_radius=d_r,
                    phi0=g.phi[kd, i],
                )
                worst = max(worst, abs(pred - float(exact)))
        errs[eps] = worst
    assert errs[1e-6] < 5e-8
    assert errs[1e-6] <= 3e-3 * errs[1e-5], errs


def _skips_only_open_pins(g, p, idx, q, v, got):
    """(skipped mask, exact evaluation) after asserting that ``got`` (an evaluation of
    ``g`` that skipped pins by a bound) has the forces of an exact evaluation of every pin
    (a fresh element, history pack: no skips) to 1e-10 of the largest, skipped >= 10 pins,
    and that every skipped pin is open in the exact evaluation."""
    from flexrv.model.pins import PinContacts

    skipped = np.isnan(g.curv[..., 0])
    ref = PinContacts(p)
    exact = _evaluate(ref, ref.pack(idx, history=True), q, v)
    fmax = np.abs(exact["force"]).max()
    assert fmax > 0.0 and skipped.sum() >= 10
    assert np.abs(got["force"] - exact["force"]).max() <= 1e-10 * fmax
    assert np.all(exact["force"][skipped] == 0.0)
    return skipped, exact


def test_chained_open_pin_bound_skips_only_open_pins_and_keeps_the_forces():
    """The pin kernel's chained bound (flexrv.model.pins.pin_kernel: the last lower bound of
    the gap less the largest motion of any pin relative to the disc since the disc's last
    evaluated pose, |dc| + (max|pin| + |c0|) |dpsi|) after a sequence of small disc motions
    (1e-8 m, 1e-7 rad per call, a solver's Newton corrections): the forces equal an exact
    evaluation of every pin (closest points from the cold starts) to 1e-10 of the largest
    (the gaps' round-off, ~1e-17 m, times the contact stiffness; measured 1.7e-12); every
    pin the kernel skipped is open there and keeps a positive lower bound of its exact gap;
    the chained bound is taken (skipped pins' recorded gaps strictly below the direct bound
    g0 - |P - P0| of their last exact gap, which the chained one is never above)."""
    from flexrv.model.pins import SLACK, PinContacts

    p, q, v = _rigid_pins()
    idx = np.arange(q.shape[0], dtype=np.int64)
    g = PinContacts(p)
    pack = g.pack(idx)
    _evaluate(g, pack, q, v)
    for k in range(1, 6):  # small motions: most open pins skipped by the chained bound
        q[0::3] += 1e-8
        q[2::3] += 1e-7
        got = _evaluate(g, pack, q, v)
    skipped, exact = _skips_only_open_pins(g, p, idx, q, v, got)
    assert np.all(got["gap"][skipped] > 0.0) and np.all(got["gap"][skipped] <= exact["gap"][skipped])
    assert np.array_equal(g.last[..., SLACK][skipped], got["gap"][skipped])
    # the direct bound from the last exact evaluation, recomputed here: the chained ones lie below it
    c, s = np.cos(q[2::3]), np.sin(q[2::3])
    direct = np.empty_like(got["gap"])
    for kd in range(g.nd):
        r = g.pins - q[3 * kd : 3 * kd + 2]
        lx, ly = c[kd] * r[:, 0] + s[kd] * r[:, 1], -s[kd] * r[:, 0] + c[kd] * r[:, 1]
        cr, sr = np.cos(g.profile[kd, 2]), np.sin(g.profile[kd, 2])
        px, py = cr * lx + sr * ly, -sr * lx + cr * ly
        direct[kd] = g.last[kd, :, 0] - np.hypot(px - g.last[kd, :, 1], py - g.last[kd, :, 2])
    assert np.any(got["gap"][skipped] < direct[skipped] - 1e-12)


def test_outer_medial_radius_table_and_the_tangent_ball_bound():
    """The pin-centre curve's outer medial radius over one lobe (flexrv.model.pins._medial_radii,
    _outer_ball_table) on rv40e: at the lobe's valley phi = 0 (the curve's concave side facing
    the pins) the empty tangent ball is the osculating circle, so the sampled radius equals
    1 / |kappa(0)| of the closed-form curvature (flexrv.geometry.cycloid.center_curve_curvature)
    within 1 % (the samples' spacing; measured 2e-4); every bin is at least the global reach
    (pins._curve_reach) and at most its cap (8x the valley bin on the flanks).
    The bound itself (pins._ball_record): for 4,000
    points P0 within +-30 um of the curve at random foot points and moves dP up to 60 um (four
    time steps' motion), the exact signed distance s(P0 + dP) (cycloid.pin_gap, its Newton to
    1e-14 rad from the cold starts) is never below rho - |P - O| (rigour; measured slack >= 0 to
    round-off), and for most of the moves (random directions) strictly above the 1-Lipschitz
    bound s0 - |dP|, which it is never below."""
    from flexrv.geometry.cycloid import center_curve, center_curve_curvature, pin_gap
    from flexrv.model.pins import BALL, GRAD, LAST_SIZE, _ball_record, _curve_reach, _medial_radii, _outer_ball_table

    r = load("rv40e")
    d = drive_parameters(r)
    z, radius, ecc = int(d.z_rp), float(r.second_stage.pin_circle_radius), float(d.eccentricity)
    r_out, _ = _medial_radii(z, radius, ecc)
    kappa = abs(float(center_curve_curvature(0.0, z, radius, ecc)))
    assert abs(r_out[0] * kappa - 1.0) < 1e-2
    table = _outer_ball_table(z, radius, ecc)
    lobe = 2.0 * np.pi / (z - 1)
    assert np.all(table >= _curve_reach(z, radius, ecc)[0] * (1 - 1e-12))
    assert np.all(table <= 0.05 * radius * lobe) and table.max() > 5 * table.min()
    rng = np.random.default_rng(5)
    n = 4000
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    c, d1, _ = center_curve(phi, z, radius, ecc)
    t = d1 / np.linalg.norm(d1, axis=1)[:, None]
    n_out = np.stack([-t[:, 1], t[:, 0]], axis=1)
    s0 = rng.uniform(-30e-6, 30e-6, n)
    p0 = c + s0[:, None] * n_out
    dp = rng.normal(size=(n, 2)) * rng.uniform(0.0, 60e-6, n)[:, None] / np.sqrt(2.0)
    last = np.zeros((1, n, LAST_SIZE))
    last[0, :, GRAD] = 1.0  # a converged foot point
    worst, better = np.inf, 0
    for i in range(n):
        at0 = _ball_record(last, 0, i, p0[i, 0], p0[i, 1], s0[i], n_out[i, 0], n_out[i, 1], table, z, phi[i], 0.0)
        assert at0 == s0[i]
        pt = p0[i] + dp[i]
        bound = last[0, i, BALL + 2] - np.hypot(pt[0] - last[0, i, BALL], pt[1] - last[0, i, BALL + 1])
        exact = float(pin_gap(pt, z, radius, 0.0, ecc)[0])
        worst = min(worst, exact - bound)
        better += bound > s0[i] - np.hypot(*dp[i]) + 1e-9
    assert worst >= -1e-12, worst
    assert better > n // 2


def test_tangent_ball_bound_skips_only_open_pins_over_a_steps_motion():
    """A time step's motion (disc centres 1.5e-5 m, rotations 3e-5 rad per call: a pin moves
    ~15 um relative to its disc, far more than the gaps of its neighbours in mesh) after an
    exact evaluation of every pin: the forces of the skipping kernel (chained and tangent-ball
    bounds, flexrv.model.pins.pin_kernel) equal an exact evaluation of every pin from the cold
    starts to 1e-10 of the largest (round-off; measured 3.9e-13); every skipped pin is open
    there with its recorded gap a positive lower bound; and the tangent-ball bound proves open
    pins the 1-Lipschitz bound g0 - |P - P0| could not (that bound <= 0 for some skipped pin),
    some by the ball at their predicted foot point (pins._ball_predicted: the ball record
    replaced while the pin's exact records stay those of the first evaluation)."""
    from flexrv.model.pins import BALL, PinContacts

    p, q, v = _rigid_pins()
    idx = np.arange(q.shape[0], dtype=np.int64)
    g = PinContacts(p)
    pack = g.pack(idx)
    _evaluate(g, pack, q, v)
    g0, p0, o0 = g.last[..., 0].copy(), g.last[..., 1:3].copy(), g.last[..., BALL].copy()
    for _ in range(3):
        q[0::3] += 1.5e-5
        q[1::3] -= 0.5e-5
        q[2::3] += 3e-5
        got = _evaluate(g, pack, q, v)
        skipped, exact = _skips_only_open_pins(g, p, idx, q, v, got)
        assert np.all(got["gap"][skipped] > 0.0) and np.all(got["gap"][skipped] <= exact["gap"][skipped] + 1e-15)
    # the 1-Lipschitz bound from the first exact evaluation, at the final pose, for the pins skipped since
    never = np.all(g.last[..., 1:3] == p0, axis=-1)
    c, s = np.cos(q[2::3]), np.sin(q[2::3])
    lip = np.empty_like(g0)
    for kd in range(g.nd):
        r = g.pins - q[3 * kd : 3 * kd + 2]
        lx, ly = c[kd] * r[:, 0] + s[kd] * r[:, 1], -s[kd] * r[:, 0] + c[kd] * r[:, 1]
        cr, sr = np.cos(g.profile[kd, 2]), np.sin(g.profile[kd, 2])
        px, py = cr * lx + sr * ly, -sr * lx + cr * ly
        lip[kd] = g0[kd] - np.hypot(px - p0[kd, :, 0], py - p0[kd, :, 1])
    assert np.any(lip[never & skipped] <= 0.0)
    assert np.any(never & skipped & (g.last[..., BALL] != o0))  # proved open by a ball at a predicted foot point


def test_roller_directions_by_rotation_equal_the_angles_cosines():
    """The crank supports' roller directions u_i = Rot(gamma) (cos a_i, sin a_i) (one rotation
    of the stored cosines and sines per cage angle, tapered_roller.roller_directions_into)
    equal (cos(gamma + a_i), sin(gamma + a_i)) to round-off on rv40e's rollers (2e-15 (1 + |gamma|):
    the sum gamma + a_i itself is rounded to ~|gamma| eps; measured 3.5e-15 at gamma = 41.3), and
    the element's stored table holds the cosines and sines of its roller angles."""
    from flexrv.contact.tapered_roller import _roller_directions
    from flexrv.model.cranks_discs import CrankSupports

    r = load("rv40e")
    g = CrankSupports(CrankSupports.parameters(r, drive_parameters(r)))
    assert len(g.angles) > 0
    np.testing.assert_array_equal(g.angle_cs, [np.cos(g.angles), np.sin(g.angles)])
    for gam in (-2.9, 0.0, 0.7, 41.3):
        ux, uy = _roller_directions(gam, g.angles)
        tol = 2e-15 * (1.0 + abs(gam))
        np.testing.assert_allclose(ux, np.cos(gam + g.angles), rtol=0, atol=tol)
        np.testing.assert_allclose(uy, np.sin(gam + g.angles), rtol=0, atol=tol)


def test_carrier_calls_without_jacobian_converge_to_the_fresh_solution():
    """The elastic carrier's calls without the Jacobian compute no tangent: their successors start
    from u_prev + S (q - q_prev) with the S of the last call with the Jacobian. Along a path of
    calls (one with the Jacobian, then four without, each moving every crank by ~5 nm) the forces
    equal a fresh solve from zero (a reset group) at each state to 1e-9 of the largest force (the
    carrier Newton's tolerance: measured 4e-14), with the predictor in use (the solves stop
    after at most 2 evaluations)."""
    from flexrv.model.cranks_discs import CrankSupports, _support_views
    from flexrv.model.numerics.newton import EVALS

    r = load("rv40e")
    p = CrankSupports.parameters(r, drive_parameters(r))
    assert p.carrier_compliance.size
    g, fresh = CrankSupports(p), CrankSupports(p)
    n = p.drive.n_cranks
    rng = np.random.default_rng(3)
    q = np.zeros(6 + 3 * n)
    q[2] = 0.3
    c, s = np.cos(0.3), np.sin(0.3)
    for j in range(n):
        b = p.crank_bores[j]
        q[6 + 3 * j : 8 + 3 * j] = [c * b[0] - s * b[1], s * b[0] + c * b[1]] + rng.normal(0.0, 20e-6, 2)
        q[8 + 3 * j] = rng.normal()
    v = np.zeros_like(q)
    g.jacobian(0.0, q, v)
    views = _support_views(g.work, n)
    for k in range(4):
        q = q + rng.normal(0.0, 5e-9, q.shape)
        f = g.evaluate(0.0, q, v)[0]
        assert views.nw[EVALS] <= 2
        fresh.reset()
        f0 = fresh.evaluate(0.0, q, v)[0]
        np.testing.assert_allclose(f, f0, rtol=0, atol=1e-9 * np.abs(f0).max())


def test_asymmetric_carrier_compliance_is_rejected():
    """The condensed tangent takes M = (I + K C_h)^-1 as the transpose of the carrier Newton's
    (I + C_h K)^-1, exact for a symmetric compliance (Maxwell-Betti); a compliance asymmetric by
    more than 1e-9 of its largest entry is rejected with a message naming it."""
    import pytest

    from flexrv.model.cranks_discs import CrankSupports

    r = load("rv40e")
    p = CrankSupports.parameters(r, drive_parameters(r))
    c = p.carrier_compliance.copy()
    CrankSupports(dataclasses.replace(p, carrier_compliance=c))
    c[0, 1] += 1e-6 * np.abs(c).max()
    with pytest.raises(ValueError, match="carrier_compliance is not symmetric"):
        CrankSupports(dataclasses.replace(p, carrier_compliance=c))
