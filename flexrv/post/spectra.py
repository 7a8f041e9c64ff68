"""Spectra of steady-state signals (TE) with the reducer's characteristic frequencies."""

from __future__ import annotations

import numpy as np


def amplitude_spectrum(signal, time, detrend: bool = True):
    """One-sided amplitude spectrum of a uniformly sampled signal (Hann window,
    amplitude-corrected: a sine of amplitude A shows a peak of ~A).

    Returns (frequency [Hz], amplitude [signal units])."""
    x = np.asarray(signal, dtype=float)
    t = np.asarray(time, dtype=float)
    if len(x) < 8:
        return np.zeros(0), np.zeros(0)
    dt = float(np.median(np.diff(t)))
    if detrend:
        x = x - np.polyval(np.polyfit(t, x, 1), t)
    w = np.hanning(len(x))
    spec = np.fft.rfft(x * w)
    amp = 2.0 * np.abs(spec) / w.sum()
    freq = np.fft.rfftfreq(len(x), dt)
    return freq, amp


def te_spectrum(res):
    """TE amplitude spectrum [arcsec] over the steady window and the
    characteristic frequencies [Hz] at the simulated mean input speed."""
    from flexrv.geometry.kinematics import characteristic_frequencies
    from flexrv.post.stats import mean_speed

    sel = res.steady("te")
    t = sel["time"].values
    freq, amp = amplitude_spectrum(sel.values, t)
    red = res.reducer
    th = res.steady("theta_in").values
    w_in = mean_speed(th, t)
    cf = characteristic_frequencies(
        w_in,
        red.first_stage.sun_teeth,
        red.first_stage.planet_teeth,
        red.second_stage.disc_teeth,
        red.second_stage.pin_count,
    )
    marks = {k: float(getattr(cf, k)) for k in ("crank_rotation", "first_stage_mesh", "cycloid_mesh", "input")}
    return freq, amp, marks
