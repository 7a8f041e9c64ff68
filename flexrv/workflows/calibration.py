"""Calibration workflow: (a) synthetic round trips on rv40e with known truths, (b) the
estimated inputs of rv40e against :cite:`seed004`'s measured RV-40E rigidity.

(a) Round trips. Each draw takes "true" values of three estimated inputs of rv40e (the
    pin-disc clearance through the equidistant modification, the crank support preload, the
    needle roller length) uniformly inside the middle 60 % of their plausible ranges, makes a
    loop with flexrv (:func:`flexrv.studies.calibrate.synthetic_loop`: the quasi-static loop at
    40 torques per quarter, 0.005 arcmin normal angle noise, its own noise seed), writes and
    reads it through the measured-data format and calibrates the three fields back from the
    preset's estimates (:func:`flexrv.studies.calibrate.calibrate`). Counted: in how many
    draws each field's 95 % interval covers its truth (goal: >= 17 of 20), and all three at
    once. One more case frees two compliances in series (crank bending through the eccentric
    journal length, the housing ring through its outer diameter) and must report them not
    identifiable.
(b) seed004 measured 3.06e8 N mm/rad = 89.0 N m/arcmin on an RV-40E loop at +-412 N m, read
    as the loop secant (:mod:`flexrv.post.definitions`, ``rigidity_loop_secant``). One number
    identifies at most one parameter: for each estimated input alone, the value that makes the
    quasi-static loop's secant 89.0 N m/arcmin (Brent's method on the field, the others at
    their estimates), beside its estimate and its plausible range. A value far outside the
    range says that field alone cannot explain the gap; several fields inside their ranges
    can each explain it, and this one number cannot tell which.

Run: ``python -m flexrv.workflows.calibration`` or ``flexrv workflow calibration``.
"""

from __future__ import annotations

import numpy as np

from flexrv.workflows._common import WorkflowResult, new_figure

NAME = "calibration"
PRESET = "rv40e"
SIGMA_ARCMIN = 0.005
DRAWS = 20
SMOKE_DRAWS = 2
FREE = {
    "second_stage.modification_equidistant_mm": (0.0025, 0.0075),
    "crankshaft.support_bearing_axial_preload_um": (0.0, 6.0),
    "needle_bearing.roller_length_mm": (7.0, 12.0),
}
#: one fixed "true" design inside FREE (the benchmark's and the default test's round trip)
EXAMPLE_TRUTH = {
    "second_stage.modification_equidistant_mm": 0.0062,
    "crankshaft.support_bearing_axial_preload_um": 2.8,
    "needle_bearing.roller_length_mm": 9.2,
}
SERIES_PAIR = {"crankshaft.eccentric_journal_length_mm": (9.0, 15.0), "housing.ring_outer_diameter_mm": (170.0, 220.0)}
#: seed004's loop rigidity [N mm/rad] at +-412 N m
SEED004_RIGIDITY_NMM_PER_RAD = 3.06e8
#: estimated inputs of (b), each with the range searched (factors of the estimate; preload from 0)
SEED004_FIELDS = (
    "crankshaft.eccentric_journal_length_mm",
    "crankshaft.support_journal_length_mm",
    "housing.ring_outer_diameter_mm",
    "crankshaft.support_bearing_axial_preload_um",
    "second_stage.modification_equidistant_mm",
    "first_stage.backlash_um",
)
SEARCH = (0.1, 10.0)


def round_trip(draw: int, workers: int = 0) -> dict:
    """One synthetic draw (module docstring): truths, fitted values and intervals."""
    import tempfile
    from pathlib import Path

    from flexrv.design import load, override
    from flexrv.measured import read_measured
    from flexrv.measured.writer import write_loop
    from flexrv.studies.calibrate import calibrate, synthetic_loop

    rng = np.random.default_rng(1000 + draw)
    truth = {k: float(lo + (0.2 + 0.6 * rng.random()) * (hi - lo)) for k, (lo, hi) in FREE.items()}
    t, a = synthetic_loop(override(PRESET, truth), 412.0, SIGMA_ARCMIN, seed=draw)
    path = write_loop(
        Path(tempfile.mkdtemp()) / f"draw{draw}.csv",
        t,
        a,
        origin="simulated by flexrv: calibration workflow round trip (not a measurement)",
        angle_uncertainty_arcmin=SIGMA_ARCMIN,
    )
    cal = calibrate(load(PRESET), [read_measured(path)], free=FREE, workers=workers)
    out = {"draw": draw, "residual_rms": cal.residual_rms}
    for k, v in cal.identified.items():
        out[k] = {**v, "truth": truth[k], "covered": bool(v["ci95_low"] <= truth[k] <= v["ci95_high"])}
    return out


def series_pair() -> dict:
    """The two compliances in series freed together (module docstring)."""
    import tempfile
    from pathlib import Path

    from flexrv.design import load, override
    from flexrv.measured import read_measured
    from flexrv.measured.writer import write_loop
    from flexrv.studies.calibrate import calibrate, synthetic_loop

    truth = {"crankshaft.eccentric_journal_length_mm": 12.6, "housing.ring_outer_diameter_mm": 185.0}
    t, a = synthetic_loop(override(PRESET, truth), 412.0, SIGMA_ARCMIN, seed=7)
    path = write_loop(Path(tempfile.mkdtemp()) / "pair.csv", t, a, angle_uncertainty_arcmin=SIGMA_ARCMIN)
    cal = calibrate(load(PRESET), [read_measured(path)], free=SERIES_PAIR, workers=0)
    return {"identified": cal.identified, "non_identifiable": cal.non_identifiable}


def loop_secant(reducer) -> float:
    """The quasi-static loop's secant rigidity at +-412 N m [N m/arcmin] (seed004's reading)."""
    from flexrv.measured.figures import loop_figures_of
    from flexrv.studies.calibrate import quasi_static_loop

    t, a = quasi_static_loop(reducer, 412.0)
    return loop_figures_of(t, a, 412.0)["rigidity_loop_secant_Nm_per_arcmin"]


def seed004_single_field(field: str, target: float) -> dict:
    """The value of ``field`` alone that gives the target secant rigidity (others at their
    estimates), searched over SEARCH x its estimate (from 0 for a preload or a clearance)."""
    from scipy.optimize import brentq

    from flexrv.design import load, override
    from flexrv.errors import FlexrvError
    from flexrv.studies.calibrate import DEFAULT_RANGE, field_value

    rv = load(PRESET)
    est = float(field_value(rv, field))
    lo = 0.0 if field.endswith(("_um", "equidistant_mm")) else SEARCH[0] * est
    hi = SEARCH[1] * est
    rng = rv.ranges.get(field)
    plausible = (rng.low, rng.high) if rng is not None else (DEFAULT_RANGE[0] * est, DEFAULT_RANGE[1] * est)

    def f(x):
        try:
            return loop_secant(override(rv, {field: float(x)})) - target
        except FlexrvError:
            return float("nan")

    f_lo, f_hi = f(lo), f(hi)
    row = {
        "field": field,
        "estimate": est,
        "plausible_low": float(plausible[0]),
        "plausible_high": float(plausible[1]),
        "plausible_source": rng.reason if rng is not None else f"default {DEFAULT_RANGE} x the estimate",
        "searched": [lo, hi],
        "secant_at_estimate": f(est) + target,
    }
    if np.isfinite(f_lo) and np.isfinite(f_hi) and f_lo * f_hi < 0:
        x = brentq(f, lo, hi, xtol=1e-6 * max(abs(est), 1e-9), maxiter=40)
        row["value_for_target"] = float(x)
        row["inside_plausible_range"] = bool(row["plausible_low"] <= x <= row["plausible_high"])
    else:
        row["value_for_target"] = None
        row["inside_plausible_range"] = False
    return row


def run(out_dir=None, smoke: bool = False, draws: int | None = None) -> WorkflowResult:
    """(a) round trips and the series pair, (b) seed004's number against single fields."""
    from flexrv.units import RAD_PER_ARCMIN

    n = draws if draws is not None else (SMOKE_DRAWS if smoke else DRAWS)
    r = WorkflowResult(NAME, "Calibration: synthetic round trips and seed004's RV-40E rigidity", ["004"], smoke=smoke)
    rows = [round_trip(i) for i in range(n)]
    cover = {k: sum(row[k]["covered"] for row in rows) for k in FREE}
    joint = sum(all(row[k]["covered"] for k in FREE) for row in rows)
    r.numbers["round_trip"] = {"draws": n, "covered": cover, "all_covered": joint, "rows": rows}
    for k in FREE:
        r.compare(f"(a) 95 % interval covers the truth: {k}", "draws", f">= {int(np.ceil(0.85 * n))} of {n}", cover[k])
    r.compare("(a) all three intervals cover their truths", "draws", f"~{0.95**3 * n:.1f} of {n} expected", joint)
    pair = series_pair()
    r.numbers["series_pair"] = pair
    r.compare(
        "(a) crank bending + housing ring in series: identifiable",
        "-",
        "no (one loop sees their sum)",
        "no" if not any(v["identifiable"] for v in pair["identified"].values()) else "YES (wrong)",
    )
    r.tables["(a) round trips: truth, fitted value and 95 % interval"] = [
        {
            "draw": row["draw"],
            "field": k.split(".")[-1],
            "truth": row[k]["truth"],
            "fitted": row[k]["value"],
            "ci95 low": row[k]["ci95_low"],
            "ci95 high": row[k]["ci95_high"],
            "covered": row[k]["covered"],
        }
        for row in rows
        for k in FREE
    ]
    target = SEED004_RIGIDITY_NMM_PER_RAD * 1e-3 * RAD_PER_ARCMIN
    fields = SEED004_FIELDS[:2] if smoke else SEED004_FIELDS
    single = [seed004_single_field(f, target) for f in fields]
    r.numbers["seed004"] = {"target_Nm_per_arcmin": target, "fields": single}
    r.compare(
        "(b) seed004 loop rigidity (3.06e8 N mm/rad)",
        "N m/arcmin",
        target,
        single[0]["secant_at_estimate"],
        "flexrv: quasi-static loop secant of the rv40e estimates",
    )
    r.tables["(b) each estimated input alone fitted to seed004's 89 N m/arcmin"] = [
        {
            "field": s["field"],
            "estimate": s["estimate"],
            "plausible range": f"{s['plausible_low']:.4g} .. {s['plausible_high']:.4g}",
            "value for 89 N m/arcmin": s["value_for_target"],
            "inside plausible range": s["inside_plausible_range"],
        }
        for s in single
    ]
    inside = [x["field"] for x in single if x["inside_plausible_range"]]
    r.text.append(
        f"(b) seed004's {target:.1f} N m/arcmin against the rv40e estimates' {single[0]['secant_at_estimate']:.1f}: "
        + (
            f"within their plausible ranges, {', '.join(inside)} alone could explain it."
            if inside
            else "no single estimated input explains it inside its plausible range (the values needed alone are "
            "in table (b); '-' where none in the searched range does): the gap lies in several inputs together "
            "or in compliances the quasi-static model does not contain."
        )
    )
    r.numbers["seed004"]["fields_inside_plausible_range"] = inside
    r.text += [
        "One measured number identifies at most one parameter: each row of table (b) is the value that field "
        "would need ALONE, with every other input at its estimate. Several rows inside their plausible ranges "
        "mean several explanations that this number cannot tell apart; a calibration that frees more than one "
        "of them from this number alone would report them not identifiable (table (a)'s series pair). A full "
        "loop (spans at several torques), lost-motion points and TE records separate more.",
        f"Round trips: {n} draws, 0.005 arcmin angle noise, 6 mid-curve spans per loop, 3 free fields; "
        "intervals from the Jacobian (stated sigma: normal quantile 1.96).",
    ]
    r.figures["round_trip_intervals"] = _interval_figure(rows)
    r.figures["seed004_single_fields"] = _seed004_figure(single)
    r.save(out_dir)
    return r


def _interval_figure(rows):
    fig, axes = new_figure(1, len(FREE), figsize=(4 * len(FREE), 3.6))
    for ax, k in zip(np.atleast_1d(axes), FREE):
        for row in rows:
            v = row[k]
            c = "C0" if v["covered"] else "C3"
            ax.plot([row["draw"]] * 2, [v["ci95_low"], v["ci95_high"]], color=c, lw=2)
            ax.plot(row["draw"], v["truth"], "k_", ms=10)
        ax.set_title(k.split(".")[-1], fontsize=9)
        ax.set_xlabel("draw")
    fig.suptitle("95 % intervals (blue: cover the truth, red: miss) and truths (black)", fontsize=10)
    fig.tight_layout()
    return fig


def _seed004_figure(single):
    fig, ax = new_figure(figsize=(7, 3.6))
    for i, s in enumerate(single):
        ax.plot([s["plausible_low"] / s["estimate"], s["plausible_high"] / s["estimate"]], [i, i], color="0.7", lw=6)
        if s["value_for_target"] is not None:
            ax.plot(s["value_for_target"] / s["estimate"], i, "C3o")
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(range(len(single)), [s["field"].split(".")[-1] for s in single], fontsize=8)
    ax.set_xscale("symlog", linthresh=0.1)
    ax.set_xlabel("value / estimate (grey: plausible range; red: value alone for 89 N m/arcmin)")
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    print(run().out_dir)
