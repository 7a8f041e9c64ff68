"""Validation: each measured file beside the matching prediction, the same figures from both
by the same functions (``flexrv validate``).

Predictions
-----------
* stiffness loop: the virtual stiffness test (:func:`flexrv.simulation.stiffness_test`,
  the bench's program: input locked, 0 -> +T -> -T -> 0 at the file's peak torque and, if the
  file states it, its ``quarter_time_s``), which has the friction hysteresis; or, with
  ``loop_model = "quasi-static"``, the quasi-static loop
  (:func:`flexrv.studies.calibrate.quasi_static_loop`, no friction: hysteresis 0, about
  0.3 s instead of a minute);
* TE record: the quasi-static loaded TE (:func:`flexrv.model.quasi_static.loaded_te`) at the
  file's torque over the file's range of output revolutions, at the file's density of
  points per pin-mesh period (the speed is not a variable of the quasi-static solver);
* lost-motion points: the quasi-static loop at the file's rated torque.

Figures (:mod:`flexrv.measured.figures`, i.e. :mod:`flexrv.post.definitions`): every figure
``<name>_<unit>`` of the file appears as ``<name>_measured_<unit>``,
``<name>_predicted_<unit>`` and ``<name>_difference_<unit>`` (predicted - measured).
"""

from __future__ import annotations

import math

import numpy as np

from flexrv.units import RAD_PER_ARCMIN, TWO_PI

LOOP_MODELS = ("stiffness-test", "quasi-static")
#: numbers of a record that describe its sampling, not the reducer (not compared)
_NOT_FIGURES = ("output_revolutions", "spectral_resolution_orders")
#: unit suffixes of the figures' names (longest first)
_UNITS = ("_Nm_per_arcmin", "_arcmin", "_arcsec", "_Nm", "_J")


def split_name(key: str) -> tuple[str, str]:
    """("rigidity_tangent", "Nm_per_arcmin") from "rigidity_tangent_Nm_per_arcmin"; ("x", "") without a unit."""
    for u in _UNITS:
        if key.endswith(u):
            return key[: -len(u)], u[1:]
    return key, ""


def _named(base: str, which: str, unit: str) -> str:
    return f"{base}_{which}_{unit}" if unit else f"{base}_{which}"


def predict_loop(reducer, m, loop_model: str = "stiffness-test", model: str = "rigid"):
    """Predicted (torque [N m], angle [rad]) of a loop or lost-motion file (module docstring)."""
    from flexrv.errors import InputError
    from flexrv.measured.figures import program_torque

    if loop_model not in LOOP_MODELS:
        raise InputError(f"--loop-model {loop_model!r}: allowed {', '.join(LOOP_MODELS)}")
    peak = program_torque(m)
    if loop_model == "quasi-static" or m.kind == "lost_motion":
        from flexrv.studies.calibrate import quasi_static_loop

        return quasi_static_loop(reducer, peak)
    from flexrv.simulation import DEFAULT_QUARTER_TIME, stiffness_test

    quarter = float(m.meta.get("quarter_time_s", DEFAULT_QUARTER_TIME))
    _, res = stiffness_test(reducer, model=model, quarter_time=quarter, torque=peak)
    return res.ds["loop_torque"].values, res.ds["loop_angle"].values * RAD_PER_ARCMIN


def predict_te(reducer, m):
    """Predicted (output angle [rad], TE [rad]) of a TE record: the loaded TE at its torque
    (the no-load curve at 1 % rated for a record at zero torque) over its output revolutions."""
    from flexrv.measured.format import te_output_angle
    from flexrv.model.quasi_static import characteristic_orders, loaded_te

    x = te_output_angle(m)
    n = len(x)
    revs = abs(x[-1] - x[0]) * n / max(n - 1, 1) / TWO_PI
    revs = min(max(revs, 1e-3), 100.0)
    mesh = characteristic_orders(reducer)["cycloid mesh"]
    ppm = int(min(max(round(n / (revs * mesh)), 2), 64))
    if abs(n / (mesh * ppm) - revs) < 1e-3 * revs:  # the record's n points are a whole number per mesh period
        revs = n / (mesh * ppm)
    torque = float(m.meta["torque_Nm"])
    res = loaded_te(reducer, torque=torque if torque > 0 else None, output_revolutions=revs, points_per_mesh=ppm)
    te = res.te if torque > 0 else res.te_no_load
    out = res.output_angle - res.output_angle[0] + x[0] if m.meta["direction"] == "forward" else res.output_angle
    return out, te


def compare(measured: dict, predicted: dict) -> dict:
    """``{<name>_measured_<unit>, <name>_predicted_<unit>, <name>_difference_<unit>}`` of every
    scalar figure the measurement has."""
    out = {}
    for key, mv in measured.items():
        if not isinstance(mv, (int, float)) or key not in predicted or key in _NOT_FIGURES:
            continue
        base, unit = split_name(key)
        pv = float(predicted[key])
        out[_named(base, "measured", unit)] = float(mv)
        out[_named(base, "predicted", unit)] = pv
        out[_named(base, "difference", unit)] = pv - float(mv) if math.isfinite(pv) and math.isfinite(mv) else None
    return out


def validate(reducer, measurements, loop_model: str = "stiffness-test", model: str = "rigid") -> list[dict]:
    """Each file beside its prediction: ``{"path", "kind", "comparison", "measured", "predicted"}``
    (``measured`` / ``predicted``: the arrays for the overlay plots, SI)."""
    from flexrv.measured.figures import (
        LOST_MOTION_FIGURES,
        loop_figures_of,
        measurement_figures,
        rated_torque,
        reducer_orders,
        te_record_figures,
    )
    from flexrv.measured.format import te_output_angle

    orders = reducer_orders(reducer)
    rows = []
    for m in measurements:
        figs = measurement_figures(m, orders)
        if m.kind == "te_record":
            x, y = predict_te(reducer, m)
            pred = te_record_figures(x, y, orders)
            arrays = {"measured": (te_output_angle(m), m.columns["te"]), "predicted": (x, y)}
            spectra = {
                "measured": (figs["spectrum_order"], figs["spectrum_amplitude_arcsec"]),
                "predicted": (pred["spectrum_order"], pred["spectrum_amplitude_arcsec"]),
            }
        else:
            t, a = predict_loop(reducer, m, loop_model, model)
            if m.kind == "lost_motion":
                pred = loop_figures_of(t, a, rated_torque(m))
                pred = {k: pred[k] for k in LOST_MOTION_FIGURES}
            else:  # each loop read at its own tips, as the stiffness test reads its loop
                pred = loop_figures_of(t, a, float(min(np.max(t), -np.min(t))))
            arrays = {"measured": (m.columns["torque"], m.columns["angle"]), "predicted": (t, a)}
            spectra = None
        rows.append(
            {
                "path": m.path,
                "kind": m.kind,
                "simulated": m.simulated,
                "prediction": _prediction_name(m.kind, loop_model, model),
                "comparison": compare(figs, pred),
                "spectrum_lines": {"measured": figs.get("spectrum_lines"), "predicted": pred.get("spectrum_lines")},
                "arrays": arrays,
                "spectra": spectra,
            }
        )
    return rows


def _prediction_name(kind: str, loop_model: str, model: str) -> str:
    if kind == "te_record":
        return "quasi-static loaded TE (flexrv te)"
    if kind == "lost_motion" or loop_model == "quasi-static":
        return "quasi-static loop (input locked)"
    return f"virtual stiffness test ({model} model)"


def max_abs_difference(rows: list[dict]) -> float:
    """The largest |difference| over every figure of every file (NaN-free)."""
    diffs = [abs(v) for r in rows for k, v in r["comparison"].items() if "_difference" in k and v is not None]
    return float(np.max(diffs)) if diffs else 0.0
