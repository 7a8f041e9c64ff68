"""The figures of a measurement, by the same functions as a prediction's
(:mod:`flexrv.post.definitions`): rigidity by each named definition, lost motion, backlash
and hysteresis of a loop or of lost-motion points; p-p, mean, forward-backward difference
and the order spectrum (lines labelled with the reducer's orders) of TE records."""

from __future__ import annotations

import numpy as np

from flexrv.measured.format import Measurement, te_output_angle
from flexrv.units import ARCSEC_PER_RAD, TWO_PI

#: the loop figures a lost-motion points file gives (the rest need the loop's large torques)
LOST_MOTION_FIGURES = ("lost_motion_arcmin", "lost_motion_1pct_arcmin", "backlash_arcmin", "hysteresis_arcmin")


def rated_torque(m: Measurement) -> float:
    """The torque [N m] the figures are read at (their T_r): for a loop the smaller of its two
    peak torques (the stiffness test's convention, :func:`flexrv.post.stiffness.evaluate_stiffness_test`:
    both tips lie on the loop); for lost-motion points the file's ``rated_torque_Nm``."""
    if m.kind == "lost_motion":
        return float(m.meta["rated_torque_Nm"])
    t = m.columns["torque"]
    return float(min(np.max(t), -np.min(t)))


def program_torque(m: Measurement) -> float:
    """The peak torque [N m] of the test program that reproduces the file: its
    ``rated_torque_Nm`` if given, else the largest |T| of the record."""
    if "rated_torque_Nm" in m.meta:
        return float(m.meta["rated_torque_Nm"])
    return float(np.max(np.abs(m.columns["torque"])))


def loop_figures_of(torque_Nm, angle_rad, rated_Nm: float) -> dict:
    """The loop figures (:func:`flexrv.post.definitions.loop_figures`), the one route for a
    measured and a predicted loop."""
    from flexrv.post.definitions import loop_figures

    return {k: float(v) for k, v in loop_figures(torque_Nm, angle_rad, rated_Nm).items()}


def te_record_figures(output_angle_rad, te_rad, orders: dict[str, float] | None = None) -> dict:
    """Figures of one TE record over the output angle: p-p and mean
    (:func:`flexrv.post.definitions.te_figures`) and the order spectrum's largest lines
    (:func:`flexrv.post.te.order_spectrum` on the record resampled to uniform output angles,
    labelled by ``orders``: name -> cycles per output revolution)."""
    from flexrv.post.definitions import te_figures
    from flexrv.post.te import order_spectrum, spectrum_lines

    x = np.asarray(output_angle_rad, dtype=float)
    y = np.asarray(te_rad, dtype=float)
    out = {k: float(v) for k, v in te_figures(x, y).items()}
    order = np.argsort(x)
    x, y = x[order], y[order]
    n = len(x)
    span = (x[-1] - x[0]) * n / max(n - 1, 1)  # n samples over [x0, x0 + span)
    revs = span / TWO_PI
    grid = x[0] + np.arange(n) * (span / n)
    o, amp = order_spectrum(np.interp(grid, x, y) * ARCSEC_PER_RAD, revs)
    out["output_revolutions"] = float(revs)
    out["spectral_resolution_orders"] = float(o[1] - o[0]) if len(o) > 1 else float("nan")
    out["spectrum_lines"] = spectrum_lines(o, amp, orders or {"output rotation": 1.0})
    out["spectrum_order"], out["spectrum_amplitude_arcsec"] = o, amp
    return out


def reducer_orders(reducer) -> dict[str, float]:
    """The reducer's lines per output revolution: the output rotation (1), the disc teeth z_c
    and the pins z_p, and the characteristic orders of the cranks, the cycloid mesh and the
    first-stage mesh (:func:`flexrv.model.quasi_static.characteristic_orders`)."""
    from flexrv.model.quasi_static import characteristic_orders

    ss = reducer.second_stage
    out = {"output rotation": 1.0, "disc teeth z_c": float(ss.disc_teeth), "pins z_p": float(ss.pin_count)}
    for name, o in characteristic_orders(reducer).items():
        if all(abs(o - v) > 1e-9 for v in out.values()):
            out[name] = o
    return out


def measurement_figures(m: Measurement, orders: dict[str, float] | None = None) -> dict:
    """The named figures of one measured file (units in the names)."""
    if m.kind == "te_record":
        out = te_record_figures(te_output_angle(m), m.columns["te"], orders)
        out["torque_Nm"] = float(m.meta["torque_Nm"])
        return out
    figs = loop_figures_of(m.columns["torque"], m.columns["angle"], rated_torque(m))
    if m.kind == "lost_motion":
        return {k: figs[k] for k in LOST_MOTION_FIGURES} | {"rated_torque_Nm": rated_torque(m)}
    return figs


def forward_backward(measurements: list[Measurement]) -> list[dict]:
    """For every torque with a forward and a backward TE record: the forward-backward
    difference (:func:`flexrv.post.definitions.te_figures`), sorted by torque."""
    from flexrv.post.definitions import te_figures

    by_torque: dict[float, dict[str, Measurement]] = {}
    for m in measurements:
        if m.kind == "te_record":
            by_torque.setdefault(float(m.meta["torque_Nm"]), {})[m.meta["direction"]] = m
    rows = []
    for torque in sorted(by_torque):
        pair = by_torque[torque]
        if {"forward", "backward"} <= set(pair):
            f, b = pair["forward"], pair["backward"]
            figs = te_figures(te_output_angle(f), f.columns["te"], te_output_angle(b), b.columns["te"])
            rows.append({"torque_Nm": torque, "forward": f.path, "backward": b.path, **figs})
    return rows
