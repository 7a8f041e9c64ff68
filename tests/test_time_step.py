"""Time-step and Newton-tolerance study of the rigid model (issue 15): is the
default step (flexrv.simulation.DEFAULT_DT) and Newton tolerance
(DEFAULT_NEWTON_TOLERANCE) fine enough?

Criterion (issue 15): the TE mean over the steady window within 0.05 arcsec, and
the TE lines up to the cycloid mesh frequency within 2 % of a fine reference.
Lines: the local maxima of the reference's amplitude spectrum (Hann window,
flexrv.post.spectra.amplitude_spectrum) at 0 < f <= 1.01 x cycloid mesh with at
least 5 % of the largest; every run's TE is sampled on the same 2e-4 s grid over
the same steady window (the records coincide with it), so the bins are the same.

Measured (default ramps, t_end 0.4 s, integrator segments of 1000 steps;
reference dt 2.5e-5 s, Newton tolerance 1e-5 / 1e-3 N):

========  ===========  =============  ==================  ====================
preset    dt [s]       tolerance      TE mean - ref ["]   lines, max rel. dev.
========  ===========  =============  ==================  ====================
rv40e     1e-4         1e-3 / 0.1     +0.0000             0.09 % (60, 339, 389 Hz)
rv40e     2e-4         1e-3 / 0.1     +0.0001             0.41 %
rv40e     1e-4         1e-5 / 1e-3    +0.0000             0.10 %
rv40e     5e-5         1e-4 / 1e-2    -0.0001             0.16 %
rv221     1e-4         1e-3 / 0.1     -0.040              0.7 % at 13.6 Hz; 23-34 % at 217-285 Hz
rv221     1e-4         1e-4 / 1e-2    -0.076              1.1 % at 13.6 Hz; 81-90 % at 217-285 Hz
rv221     1e-4         1e-5 / 1e-3    -0.045              0.8 % at 13.6 Hz; 28-39 % at 217-285 Hz
rv221     2e-4         1e-3 / 0.1     -0.067              0.9 % at 13.6 Hz; 68-88 % at 217-285 Hz
rv221     5e-5         1e-4 / 1e-2    -0.057              1.1 % at 13.6 Hz; 39-47 % at 217-285 Hz
========  ===========  =============  ==================  ====================

Re-measured on the model with every issue-14 compliance and friction (2026-11-24, t_end 0.4 s,
reference 2.5e-5 s, 1e-5 / 1e-3 N), rv40e: dt 1e-4 s mean +0.0000, lines 1.59 % (10, 60, 339, 389
Hz; the 10 Hz start-up remnant is the largest deviation); 2e-4 s +0.0000, 1.04 % -- but there the
rigid model's Newton needs ~3 iterations per step and rejects steps, for ~20 % less CPU.

Ball model (``--model balls``, rigid rings; its Newton setting
flexrv.simulation.MODEL_NEWTON, contractivity 0.25), same criterion and reference:

========  ===========  ===========  ==================  ====================
preset    load [N m]   dt [s]       TE mean - ref ["]   lines, max rel. dev.
========  ===========  ===========  ==================  ====================
rv40e     preset       1e-4         +0.0001             1.14 % (10, 60, 339, 389 Hz)
rv40e     preset       2e-4         +0.0001             1.30 %
rv221     3000         1e-4         0.0002              0.03 % (13.6 Hz)
rv221     3000         2e-4         0.0002              0.02 %
rv221     20 (preset)  1e-4         0.0039              0.07 % (13.6 Hz)
rv221     20 (preset)  2e-4         0.0016              0.21 %
========  ===========  ===========  ==================  ====================

With the quasi-static balls of the ball model's default (issue 15, 2026-11-24; Exudyn's
Newton defaults, MODEL_NEWTON being for balls with inertia): rv40e at 1e-4 s mean +0.0000,
lines 1.11 %; rv221 at 3000 N m +0.0001, 0.03 % -- the same as with ball inertia.

2e-4 s met the criterion in this study (CPU per simulated s -30 to -45 %), but it is not robust:
after the disc's mesh change (issue 15, branch fecold: a 2.4 % softer disc) the same rv40e run at
2e-4 s failed in the speed ramp (disc 1 skipped a pin at t = 0.074 s), as the flexible rings at 2e-4
s do (t = 0.07 s). Every model therefore keeps DEFAULT_DT = 1e-4 s; the ball model's case at 1e-4 s
is asserted below.

So the default (1e-4 s, 1e-3 / 0.1 N) meets the criterion on rv40e with a wide
margin (2e-4 s would too; TE p-p, 0.29-0.51 arcsec, is not converged in dt, as
issue 15 says). On rv221 no step or tolerance meets it for the lines between
200 and 300 Hz: the rigid rv221 has (at least) two steady responses, TE mean
~ -20.36 / p-p ~ 3.5 arcsec (the reference) and ~ -20.43 / ~ 2.75 arcsec, and
runs land on one, the other or in between depending on Newton-tolerance-level
differences of the start-up, not monotonically in dt (both persist to t_end =
0.8 s, window 0.36-0.8 s, measured with 200-step segments). What does converge on
rv221 is the dominant line at twice the crank rotation (13.6 Hz, within 1.1 % for
every setting) and the mean within 0.08 arcsec: those are what the rv221 case
asserts.

Why: the rv221 preset runs at a light load (load_torque_Nm = 20 of 3000 rated),
where the first-stage mesh carries 2.7 N on average with 10 um backlash: the two
responses differ in its force fluctuation (std 1.6 N in the reference's, 0.34 N in
the other; crank-support force std 11.5 / 3.2 N) -- a nearly unloaded mesh with
backlash, whose periodic responses need not be unique. Loaded, the response is
unique and converged: at 300 N m the TE mean is within 4e-4 arcsec of the
reference for dt 1e-4 and 2e-4 s and either tolerance, at 3000 N m within 2e-4
arcsec, the lines (13.6 and 298 Hz, >= 5 % of the largest) within 0.1 %; the
next, 386 Hz at 0.6 % of the largest, is 1.6 % off at 1e-4 s and 2.6 % at 2e-4 s
-- one reason to keep 1e-4 s as the default.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load
from flexrv.geometry.kinematics import characteristic_frequencies
from flexrv.post.spectra import amplitude_spectrum
from flexrv.simulation import DEFAULT_DT, DEFAULT_NEWTON_TOLERANCE, MODEL_NEWTON, Simulation
from flexrv.units import RAD_S_PER_RPM

GRID = 2e-4  #: common sampling of the compared TE signals [s]


def fast(name):
    """Shortened ramps: rated speed at 0.01 s, load 0.01-0.03 s."""
    r = load(name)
    op = r.operating.model_copy(update={"speed_ramp_time_s": 0.01, "load_ramp_start_s": 0.01, "load_ramp_end_s": 0.03})
    return r.model_copy(update={"operating": op})


def te_signal(reducer, t_end, dt, tol, model="rigid"):
    """(mean, frequencies, amplitudes) of the TE over the steady window on the GRID."""
    res = Simulation(reducer, model=model).run(t_end=t_end, dt=dt, newton_tolerance=tol)
    assert res.attrs["status"] == "completed"
    t0, t1 = res.steady_window()
    tg = np.arange(int(round(t0 / GRID)), int(round(t1 / GRID)) + 1) * GRID
    te = np.interp(tg, res.time, res["te"].values)
    f, a = amplitude_spectrum(te, tg)
    return float(te.mean()), f, a


def lines(reducer, f, a):
    """Indices of the spectral lines of ``a`` up to the cycloid mesh frequency."""
    cf = characteristic_frequencies(
        reducer.operating.input_speed_rpm * RAD_S_PER_RPM,
        reducer.first_stage.sun_teeth,
        reducer.first_stage.planet_teeth,
        reducer.second_stage.disc_teeth,
        reducer.second_stage.pin_count,
    )
    sel = np.where((f > 0) & (f <= 1.01 * float(cf.cycloid_mesh)))[0]
    top = a[sel].max()
    return [i for i in sel if a[i] >= a[i - 1] and a[i] >= a[min(i + 1, len(a) - 1)] and a[i] > 0.05 * top]


def deviations(reducer, run, ref):
    """(|mean - ref mean| [arcsec], max relative line deviation, the lines' frequencies)."""
    m, f, a = run
    m0, f0, a0 = ref
    assert np.array_equal(f, f0)
    pk = lines(reducer, f0, a0)
    assert pk
    return abs(m - m0), float(np.max(np.abs(a[pk] - a0[pk]) / a0[pk])), f0[pk]


def test_default_step_and_tolerance_rv40e_fast():
    """Default dt and Newton tolerance against half the step with a 100x tighter
    tolerance (rv40e, shortened ramps, t_end 0.3 s: two crank revolutions in the
    window; with one, t_end 0.2 s, a 0.004 arcsec remnant of the start-up at 10 Hz
    counts as a line and differs by 2.5 %). Measured: mean 0.0001 arcsec, lines
    (60, 340, 390 Hz) 0.09 % apart. ~6 s."""
    r = fast("rv40e")
    run = te_signal(r, 0.3, DEFAULT_DT, DEFAULT_NEWTON_TOLERANCE)
    ref = te_signal(r, 0.3, DEFAULT_DT / 2, (1e-5, 1e-3))
    d_mean, d_lines, freqs = deviations(r, run, ref)
    assert len(freqs) >= 2 and freqs.max() > 300  # the cycloid-mesh line (390 Hz) is among them
    assert d_mean < 0.05
    assert d_lines < 0.02


@pytest.mark.slow
@pytest.mark.parametrize("name, torque", [("rv40e", None), ("rv221", None), ("rv221", 3000.0)])
def test_default_step_and_tolerance_against_fine_reference(name, torque):
    """Default settings against the fine reference (dt 2.5e-5 s, tolerance
    1e-5 / 1e-3 N), default ramps and t_end (module table). rv40e and rv221 at its
    rated 3000 N m: the full criterion. rv221 at its preset load (20 N m): mean
    within 0.1 arcsec and the dominant line (13.6 Hz) within 2 %; its 200-300 Hz
    lines are not unique (module docstring). ~7-15 s each."""
    r = load(name)
    if torque is not None:
        r = r.model_copy(update={"operating": r.operating.model_copy(update={"load_torque_Nm": torque})})
    run = te_signal(r, 0.4, DEFAULT_DT, DEFAULT_NEWTON_TOLERANCE)
    ref = te_signal(r, 0.4, 2.5e-5, (1e-5, 1e-3))
    d_mean, d_lines, freqs = deviations(r, run, ref)
    if name == "rv40e" or torque is not None:
        assert d_mean < 0.05
        assert d_lines < 0.02
    else:
        assert d_mean < 0.1
        _, f, a = run
        _, f0, a0 = ref
        i = int(np.argmax(a0 * (f0 > 0)))
        assert f0[i] == pytest.approx(13.6, abs=0.5)
        assert abs(a[i] - a0[i]) < 0.02 * a0[i]


def test_ball_model_newton_setting():
    """The ball model with ball inertia runs with its own Newton setting
    (flexrv.simulation.MODEL_NEWTON), the user's newton_options on top; the others, and
    the ball model's default quasi-static balls, with Exudyn's defaults."""
    assert MODEL_NEWTON == {"balls": {"modifiedNewtonContractivity": 0.25}}
    for options, inertia in (({}, False), ({"ball_inertia": True}, True)):
        sim = Simulation("rv40e", model="balls", model_options=options)
        res = sim.run(t_end=0.004)
        assert sim.model.info["ball_inertia"] is inertia
        assert sim.timing["steps"] == 40 and res.attrs["status"] == "completed"


@pytest.mark.slow
@pytest.mark.parametrize("name, torque", [("rv40e", None), ("rv221", 3000.0)])
def test_ball_model_default_step_against_fine_reference(name, torque):
    """Ball model at the default step with its Newton setting against the fine reference
    (dt 2.5e-5 s, tolerance 1e-5 / 1e-3 N), default ramps, t_end 0.4 s: the full
    criterion (module table: rv40e mean 1e-4 arcsec, lines 1.1 %; rv221 at 3000 N m
    2e-4 arcsec, 0.03 %). ~40 s each."""
    r = load(name)
    if torque is not None:
        r = r.model_copy(update={"operating": r.operating.model_copy(update={"load_torque_Nm": torque})})
    run = te_signal(r, 0.4, DEFAULT_DT, DEFAULT_NEWTON_TOLERANCE, model="balls")
    ref = te_signal(r, 0.4, 2.5e-5, (1e-5, 1e-3), model="balls")
    d_mean, d_lines, freqs = deviations(r, run, ref)
    assert d_mean < 0.05
    assert d_lines < 0.02
