"""Steady-window statistics and the kinematic validation table of a run."""

from __future__ import annotations

import json
import math
from typing import NamedTuple

import numpy as np


def mean_speed(angle: np.ndarray, time: np.ndarray) -> float:
    """Mean angular speed [rad/s] over a window: slope of the least-squares line
    through angle(t) (insensitive to speed ripple and, unlike the end-point
    increment, to the instantaneous TE at the window's ends)."""
    if len(time) < 2 or time[-1] <= time[0]:
        return float("nan")
    tc = time - time.mean()
    return float(np.dot(tc, angle - angle.mean()) / np.dot(tc, tc))


def kinematic_table(res) -> list[dict]:
    """Theory vs simulation of the mean member speeds over the steady window.

    Theory: :func:`flexrv.geometry.kinematics.member_speeds` at the simulated mean
    input speed. Rows: input, output, crank absolute, crank relative, disc
    rotation, ratio. Errors in percent of the theoretical value."""
    from flexrv.geometry.kinematics import member_speeds

    t0, t1 = res.steady_window()
    sel = res.ds.sel(time=slice(t0, t1))
    t = sel["time"].values
    red = res.reducer
    fs, ss = red.first_stage, red.second_stage
    w_in = mean_speed(sel["theta_in"].values, t)
    w_out = mean_speed(sel["theta_out"].values, t)
    th = member_speeds(w_in, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    crank_abs = float(np.mean(sel["crank_speed"].values)) if len(t) else float("nan")
    crank_rel = float(np.mean(sel["crank_speed_relative"].values)) if len(t) else float("nan")
    disc = float(np.mean(sel["disc_speed"].values)) if len(t) else float("nan")
    rows = [
        ("input speed", "rad/s", float(th.input), w_in),
        ("output speed", "rad/s", float(th.carrier), w_out),
        ("crank speed, absolute", "rad/s", float(th.crank_absolute), crank_abs),
        ("crank speed, relative to carrier", "rad/s", float(th.crank_relative), crank_rel),
        ("disc rotation speed", "rad/s", float(th.disc_rotation), disc),
        ("total ratio", "-", float(th.ratio), w_in / w_out if w_out else float("nan")),
    ]
    out = []
    for name, unit, theory, sim in rows:
        err = 100.0 * (sim - theory) / theory if theory else float("nan")
        out.append({"quantity": name, "unit": unit, "theory": theory, "simulated": sim, "error_percent": err})
    return out


def summary(res) -> dict:
    """Numbers of a run over its steady window (JSON-ready)."""
    t0, t1 = res.steady_window()
    sel = res.ds.sel(time=slice(t0, t1))
    te = sel["te"].values
    table = kinematic_table(res)
    ratio_sim = table[-1]["simulated"]
    window = _window_rows(sel, "window")
    power = _window_rows(sel, "power")
    p_in, p_out = power["mean_input_power_W"], power["mean_output_power_W"]
    ke = sel["kinetic_energy"].values
    tw = sel["time"].values
    dke = float((ke[-1] - ke[0]) / (tw[-1] - tw[0])) if len(te) > 1 and tw[-1] > tw[0] else 0.0
    finite = len(te) > 0
    steady = bool(int(res.attrs.get("steady", 1)))
    fric = float(np.mean(sel["friction_power"].values)) if ("friction_power" in sel and len(te)) else None
    balance = power_balance(p_in, p_out, dke, steady=steady, friction=fric)
    out = {
        "preset": res.attrs.get("preset"),
        "model": res.attrs.get("model"),
        "status": res.attrs.get("status"),
        "steady_window_s": [t0, t1],
        "steady_state": steady,
        "steady_revolutions": int(res.attrs.get("steady_revolutions", 0)),
        "steady_note": str(res.attrs.get("steady_note", "")),
        "ratio_theoretical": float(res.attrs["ratio"]),
        "ratio_simulated": ratio_sim,
        "ratio_simulated_over_theoretical": ratio_sim / float(res.attrs["ratio"]),
        **window,
        **power,
        "mean_kinetic_energy_rate_W": dke,
        "mean_dissipation_W": balance["dissipation_W"],
        **efficiency_summary(sel, p_in, p_out),
        "power_balance_note": balance["note"],
        "notes": ([] if steady else [str(res.attrs.get("steady_note", "NOT STEADY"))]) + [balance["note"]],
        "kinematics": table,
        "failure": res.attrs.get("failure"),
        **_window_rows(sel, "bearing"),
        **_film_summary(sel, finite),
        "elements": element_summary(sel),
    }
    out["units"] = summary_units(res, out)
    return out


class SummaryKey(NamedTuple):
    """One number of the run summary: its ``key`` (with the unit in the name where it has
    one), the declared output it reads and whose ``units`` it carries (``source``; None:
    dimensionless, "-"), the reduction over the steady window (``reduce``, a name of
    :data:`_REDUCE`; "": computed by :func:`summary` from several outputs), a
    ``description``, its ``group`` ("window": None on an empty window; "power": NaN on an
    empty window; "bearing": only when its output exists and the window is not empty;
    "derived": computed in :func:`summary`) and whether the run tables (summary.md, the
    CLI) list it (``listed``)."""

    key: str
    source: str | None
    reduce: str
    description: str
    group: str = "window"
    listed: bool = True


#: ONE table of the run summary's keys: :func:`summary` computes the rows with a reduction
#: from it, :func:`summary_units` takes their units from it, summary.md
#: (:func:`flexrv.post.io.summary_markdown`) and the CLI tables (:func:`summary_table`) list
#: them from it. The force elements' own rows come from their declared ``summary_rows``
#: (:func:`element_summary`, the summary's "elements").
SUMMARY_KEYS = (
    SummaryKey("te_min_arcsec", "te", "min", "smallest transmission error"),
    SummaryKey("te_max_arcsec", "te", "max", "largest transmission error"),
    SummaryKey("te_pp_arcsec", "te", "p2p", "transmission error peak-to-peak"),
    SummaryKey("te_mean_arcsec", "te", "mean", "mean transmission error"),
    SummaryKey("te_rms_fluctuation_arcsec", "te", "std", "RMS of the transmission error about its mean"),
    SummaryKey("max_pin_force_N", "pin_force", "max", "largest pin-disc contact force"),
    SummaryKey("pins_in_contact_mean", "pins_in_contact", "mean", "mean number of pins in contact per disc"),
    SummaryKey("pins_in_contact_max", "pins_in_contact", "max_int", "largest number of pins in contact per disc"),
    SummaryKey("mean_input_power_W", "power_in", "mean", "mean input power", "power"),
    SummaryKey("mean_output_power_W", "power_out", "mean", "mean output power", "power"),
    SummaryKey(
        "mean_kinetic_energy_rate_W", "power_in", "", "mean rate of the kinetic energy", "derived", listed=False
    ),
    SummaryKey("mean_dissipation_W", "power_in", "", "P_in - P_out - dE_kin/dt", "derived"),
    SummaryKey("efficiency", None, "", "mean output power / mean input power", "derived"),
    SummaryKey("mean_friction_power_W", "friction_power", "", "mean dissipated friction power", "derived"),
    SummaryKey("max_ball_load_N", "ball_load_inner", "max", "largest ball load", "bearing", listed=False),
    SummaryKey(
        "max_ring_deformation_m", "ring_deformation_outer", "max", "largest outer-ring deformation", "bearing", False
    ),
    SummaryKey(
        "max_inner_ring_deformation_m",
        "ring_deformation_inner",
        "max",
        "largest inner-ring deformation",
        "bearing",
        False,
    ),
    SummaryKey("max_ball_pressure_Pa", "ball_max_pressure", "max", "largest ball contact pressure", "bearing", False),
    SummaryKey(
        "min_film_thickness_m", "ball_film_thickness", "", "smallest film of the loaded balls", "derived", False
    ),
)


def _window_rows(sel, group: str) -> dict:
    """The values of the table's rows of ``group`` with a reduction over the window ``sel``."""
    n = sel.sizes.get("time", 0)
    out = {}
    for row in SUMMARY_KEYS:
        if row.group != group:
            continue
        if group == "bearing" and not (row.source in sel and n):
            continue
        if not n:
            out[row.key] = float("nan") if group == "power" else None
        elif row.source in sel:
            out[row.key] = _REDUCE[row.reduce](np.asarray(sel[row.source].values))
    return out


def summary_table(summ: dict) -> list[tuple[str, object, str]]:
    """(key, value, units) of the listed rows of :data:`SUMMARY_KEYS` present in a summary,
    then its per-group friction keys: the rows of summary.md's table and the CLI tables."""
    units = summ.get("units", {})
    keys = [row.key for row in SUMMARY_KEYS if row.listed] + list(summ.get("friction_keys", ()))
    return [(key, summ.get(key), units.get(key, "-")) for key in keys if key in summ]


def efficiency_summary(sel, p_in: float, p_out: float) -> dict:
    """Efficiency of a driven run over a window ``sel`` (the steady window): eta =
    mean output power / mean input power (both the window means of ``power_out`` and
    ``power_in``), and the mean friction dissipation [W] per group (keys listed in
    ``friction_keys``) and in total when the run has friction outputs (the variables the
    model declared with ``role`` "friction"). eta is NaN when the input does no work (P_in <= 0,
    e.g. a locked input)."""
    out = {"efficiency": float(p_out / p_in) if (math.isfinite(p_in) and p_in > 0.0) else float("nan")}
    if "friction_power" in sel and sel.sizes.get("time", 0):
        out["mean_friction_power_W"] = float(np.mean(sel["friction_power"].values))
        for name in friction_variables(sel):
            out[f"mean_{name}_W"] = float(np.mean(sel[name].values.reshape(sel.sizes["time"], -1).sum(axis=1)))
        out["friction_keys"] = [f"mean_{name}_W" for name in friction_variables(sel)]
    return out


def friction_variables(ds) -> list[str]:
    """Names of the variables declared as friction power (attribute ``role`` = "friction")."""
    return [name for name, var in ds.data_vars.items() if var.attrs.get("role") == "friction"]


#: the reductions of a declared summary row over the steady window
_REDUCE = {
    "max": lambda a: float(np.max(a)),
    "min": lambda a: float(np.min(a)),
    "mean": lambda a: float(np.mean(a)),
    "max_abs": lambda a: float(np.max(np.abs(a))),
    "p2p": lambda a: float(np.max(a) - np.min(a)),
    "mean_sum": lambda a: float(np.mean(a.reshape(a.shape[0], -1).sum(axis=1))),
    "std": lambda a: float(np.std(a)),
    "max_int": lambda a: int(np.max(a)),
}


def element_summary(sel) -> dict:
    """The summary rows the model's elements declared on their outputs (attribute
    ``summary_rows``: [key, units, description, reduce]) over the steady window ``sel``:
    {key: {"value", "units", "description", "source"}} (value None on an empty window)."""
    out = {}
    n = sel.sizes.get("time", 0)
    for name, var in sel.data_vars.items():
        for key, units, description, reduce in json.loads(var.attrs.get("summary_rows", "[]")):
            if reduce not in _REDUCE:
                raise ValueError(f"summary row {key!r}: reduce = {reduce!r} is not one of {sorted(_REDUCE)}")
            value = _REDUCE[reduce](np.asarray(var.values)) if n else None
            out[key] = {"value": value, "units": units, "description": description, "source": name}
    return out


def summary_units(res, summ: dict) -> dict:
    """Units of the summary's numbers, carried from the result variables' ``units``
    attributes (the model's declared outputs), not parsed from the key names; the steady
    window in the time coordinate's units, ratios dimensionless ("-")."""
    units = {}
    sources = {row.key: row.source for row in SUMMARY_KEYS}
    sources.update({f"mean_{name}_W": name for name in friction_variables(res.ds)})  # the declared friction outputs
    for key, var in sources.items():
        if key in summ and var in res.ds:
            units[key] = str(res.ds[var].attrs.get("units", ""))
    units["steady_window_s"] = str(res.ds["time"].attrs.get("units", "s"))
    for key in ("ratio_theoretical", "ratio_simulated", "ratio_simulated_over_theoretical"):
        units[key] = "-"
    units.update({row.key: "-" for row in SUMMARY_KEYS if row.source is None and row.key in summ})
    return units


def _split(d: float, friction: float | None) -> str:
    """Words for the dissipation D: contact damping only, or friction + the rest."""
    if friction is None:
        return "contact damping"
    return f"friction {friction:.4g} W + contact damping and elastic storage {d - friction:.3g} W"


def power_balance(
    p_in: float, p_out: float, dke_dt: float, tol: float = 0.01, steady: bool = True, friction: float | None = None
) -> dict:
    """Mean power balance over a window: dissipation D = P_in - P_out - dE_kin/dt [W]
    (every term the window mean; dE_kin/dt = (E_kin(t1) - E_kin(t0)) / (t1 - t0) is exactly
    the mean of the rate). ``note`` says in words what the numbers mean: D < 0 beyond
    ``tol`` P_in cannot be dissipation — energy is then released from storage the balance
    does not count (elastic energy of the contacts, e.g. while the load still ramps, or a
    window that is not steady) or the integration error shows. ``friction``: the mean
    friction power of the run [W], if it has friction; the note then splits D
    into friction and the rest (contact damping, elastic storage)."""
    d = p_in - p_out - dke_dt
    scale = max(abs(p_in), abs(p_out), 1e-12)
    if not all(map(math.isfinite, (p_in, p_out, dke_dt))):
        note = "power balance not available"
    elif abs(d) <= tol * scale:
        note = (
            f"power balance closes: P_in {p_in:.4g} W = P_out {p_out:.4g} W + dE_kin/dt {dke_dt:.3g} W "
            f"+ remainder {d:.3g} W; the remainder is within {100 * tol:.0f} % of the power, the accuracy of "
            "the window means (P_in uses the numerically differentiated input speed): the contact damping "
            "dissipates less than that"
        )
    elif d > 0:
        note = (
            f"power balance: P_in {p_in:.4g} W - P_out {p_out:.4g} W - dE_kin/dt {dke_dt:.3g} W = "
            f"{d:.4g} W dissipated ({_split(d, friction)}), efficiency P_out/P_in = {p_out / p_in:.4f}"
            if p_in
            else f"power balance: {d:.4g} W dissipated"
        )
    else:
        note = (
            f"power balance: P_out {p_out:.4g} W + dE_kin/dt {dke_dt:.3g} W exceeds P_in {p_in:.4g} W by "
            f"{-d:.4g} W: not a negative dissipation but energy released from elastic storage (contact "
            "and mesh deflections, not counted in E_kin) — the window is not in steady state (ramps) or "
            "too short"
        )
    if not steady:
        note += (
            "; the window is NOT steady: energy stored elastically in the contacts while the load ramps "
            "is not part of E_kin, so the balance above is not a dissipation measurement"
        )
    return {"dissipation_W": float(d), "note": note}


def _film_summary(sel, finite: bool) -> dict:
    """The smallest film thickness of the loaded balls over the window (ball-resolved bearing)."""
    if "ball_film_thickness" not in sel or not finite:
        return {}
    h = sel["ball_film_thickness"].values
    loaded = sel["ball_load_inner"].values > 0
    return {"min_film_thickness_m": float(h[loaded].min()) if loaded.any() else None}
