"""Simulation results on xarray: named, unit-tagged time series.

Transmission error (:cite:`seed000,seed001,seed002,seed003`): TE(t) = theta_out(t) - theta_in(t) / i,
reported in arcsec. Mechanism in the rigid-member model: the members are rigid,
so TE comes only from the compliant elements and the clearances along the
torque path sun -> planet meshes -> cranks -> needle bearings -> discs -> pins
(and back through the crank supports to the carrier):

* a *mean* wind-up under load, (load torque) / (torsional stiffness), mostly from
  the pin–disc Hertz contacts and the needle bearings (:cite:`seed004`'s series model);
* *fluctuations* at the first-stage mesh frequency (single/double tooth-pair
  alternation of the involute mesh stiffness, divided by the second-stage ratio
  z_rp as seen at the output) and at the cycloid mesh frequency z_c f_crank (the
  number of loaded pins and their moment arms change as pins pass through the
  meshing zone, so the second-stage stiffness varies with the crank angle), plus
  crank-rotation harmonics from the needle bearing load cycle;
* the *lost motion* of clearances (equidistant modification, needle clearance,
  backlash) that must close before torque is transmitted.

With ideal geometry (no modification, no clearance, no backlash) and no load,
every element stays unloaded and the conjugate kinematics give TE = 0 up to the
integration error; with load TE is the (varying) elastic wind-up.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from flexrv.cache import to_jsonable


class Results:
    """Time series of one run (an :class:`xarray.Dataset` plus metadata).

    ``res["te"]`` or ``res["TE [arcsec]"]`` return a DataArray with the ``time``
    coordinate [s] and a ``units`` attribute; ``list(res)`` lists the labels.
    """

    def __init__(self, ds: xr.Dataset, reducer=None):
        self.ds = ds
        self.reducer = reducer

    # ------------------------------------------------------------------ access
    @property
    def attrs(self) -> dict:
        return self.ds.attrs

    def labels(self) -> dict[str, str]:
        """label "long name [units]" -> variable name."""
        return {f"{v.attrs.get('long_name', k)} [{v.attrs.get('units', '')}]": k for k, v in self.ds.data_vars.items()}

    def __iter__(self):
        return iter(self.labels())

    def __contains__(self, key) -> bool:
        return key in self.ds.data_vars or key in self.labels()

    def __getitem__(self, key: str) -> xr.DataArray:
        if key in self.ds.data_vars:
            return self.ds[key]
        labels = self.labels()
        if key in labels:
            return self.ds[labels[key]]
        raise KeyError(f"{key!r} is not a result; available: {sorted(labels)}")

    @property
    def time(self) -> np.ndarray:
        return self.ds["time"].values

    def steady_window(self) -> tuple[float, float]:
        """(t0, t1) [s] of the steady-state window stored with the run."""
        return float(self.attrs["steady_start_s"]), float(self.attrs["steady_end_s"])

    @property
    def is_steady(self) -> bool:
        """True if the window holds >= 1 whole crank revolution after the ramps
        (:func:`steady_window_rule`); runs saved before the rule count as steady."""
        return bool(int(self.attrs.get("steady", 1)))

    def steady(self, key: str) -> xr.DataArray:
        t0, t1 = self.steady_window()
        return self[key].sel(time=slice(t0, t1))

    # ------------------------------------------------------------------ summary
    def summary(self) -> dict:
        """Summary numbers over the steady window (ratio, TE statistics, forces)."""
        from flexrv.post.stats import summary

        return summary(self)

    def save(self, directory: str | Path) -> Path:
        """Write the run directory (:func:`flexrv.post.io.save`): results.nc, config.toml,
        summary.json, summary.md and the figures of :meth:`write_figures`."""
        from flexrv.post.io import save

        return save(self, directory, figures=self.write_figures)

    def write_figures(self, directory: Path) -> list[Path]:
        """Figures written with the data by :meth:`save`: none at this layer. A subclass above
        the plotting layer adds its plots (:class:`flexrv.viz.plots.PlottedResults`, the
        results of :class:`flexrv.simulation.Simulation`)."""
        return []

    @classmethod
    def load(cls, directory: str | Path) -> "Results":
        """Read a run directory written by :meth:`save` (:func:`flexrv.post.io.read_run`)."""
        from flexrv.post.io import read_run

        ds, reducer = read_run(directory)
        return cls(ds, reducer=reducer)

    def __repr__(self) -> str:
        return (
            f"Results({self.attrs.get('preset')}, model={self.attrs.get('model')}, {len(self.time)} samples, "
            f"status={self.attrs.get('status')})"
        )


def _var(values, dims, units, long_name, role="", summary=()):
    """A result variable with its declared metadata: units, long name and, if the element
    declared them, its ``role`` ("friction") and its summary rows (JSON list of [key, units,
    description, reduce], read by :func:`flexrv.post.stats.element_summary`)."""
    attrs = {"units": units, "long_name": long_name}
    if role:
        attrs["role"] = role
    if summary:
        attrs["summary_rows"] = json.dumps([[r.key, r.units, r.description, r.reduce] for r in summary])
    return xr.Variable(dims, np.asarray(values), attrs=attrs)


#: settle time [s] after the end of the speed and load ramps before the steady window may
#: start (a numerical choice of the evaluation, not a physical estimate: several periods of
#: the slowest structural mode, ~1 ms, and of the contact transients after the ramps)
STEADY_SETTLE_S = 0.05


@dataclass(frozen=True)
class SteadyWindow:
    """The steady-state window of a run (see :func:`steady_window_rule`)."""

    start_s: float
    end_s: float
    steady: bool  #: True: a whole number (>= 1) of crank revolutions after the ramps and settle time
    revolutions: int  #: whole crank revolutions (relative to the carrier) in the window
    crank_period_s: float  #: one crank revolution relative to the carrier [s] (inf: no input rotation)
    note: str  #: why the window is (not) steady, in words


def steady_window_rule(
    ramps_end_s: float, t_end: float, crank_period_s: float, settle_s: float = STEADY_SETTLE_S
) -> SteadyWindow:
    """The steady window chosen from the drive program.

    Rule: the window may start at ``ramps_end_s + settle_s`` (the later of the speed and the
    load ramp's end, plus the settle time); it is the last whole number n >= 1 of crank
    revolutions relative to the carrier (period ``crank_period_s``) before ``t_end``, i.e.
    [t_end - n T, t_end] with n = floor((t_end - ramps_end_s - settle_s) / T). A whole number
    of revolutions makes the mean and the spectrum free of a partial load cycle (the needle
    and pin loads repeat once per crank revolution relative to the carrier).

    If not even one revolution fits (or the input does not rotate), the run has no steady
    state: the window returned is what remains after the ramps and settle time (or the last
    half of the run if nothing remains) and is flagged ``steady=False`` with the reason and
    the ``t_end`` needed.

    Example: rv40e at 1215 r/min, crank period 0.1 s, ramps end 0.2 s: t_end = 0.6 s gives
    n = floor(0.35 / 0.1) = 3, window [0.3, 0.6] s; t_end = 0.2 s gives no steady state.
    """
    t_ready = ramps_end_s + settle_s
    if not (math.isfinite(crank_period_s) and crank_period_s > 0):
        t0 = t_ready if t_end - t_ready > 0 else 0.5 * t_end
        return SteadyWindow(
            t0,
            t_end,
            False,
            0,
            float("inf"),
            "no input rotation (locked or zero-speed drive): no crank revolution to average over",
        )
    n = int(math.floor((t_end - t_ready) / crank_period_s + 1e-9)) if t_end > t_ready else 0
    if n >= 1:
        return SteadyWindow(
            t_end - n * crank_period_s,
            t_end,
            True,
            n,
            crank_period_s,
            f"{n} whole crank revolution{'s' if n > 1 else ''} (relative to the carrier, "
            f"{crank_period_s:.4g} s each) after the ramps (end {ramps_end_s:.4g} s) and "
            f"{settle_s:.3g} s settle time",
        )
    t0 = t_ready if t_end - t_ready > 0 else 0.5 * t_end
    where = "inside the speed/load ramps" if t0 < ramps_end_s else "shorter than one crank revolution"
    return SteadyWindow(
        t0,
        t_end,
        False,
        0,
        crank_period_s,
        f"NOT STEADY: the run ends at {t_end:.4g} s; the window {t0:.4g} - {t_end:.4g} s is {where}. "
        f"A steady state needs t_end >= {t_ready + crank_period_s:.4g} s (ramps end "
        f"{ramps_end_s:.4g} s + settle {settle_s:.3g} s + one crank revolution "
        f"{crank_period_s:.4g} s); the statistics below are NOT steady-state values",
    )


def steady_window_for(
    reducer, t_end: float, input_speed: float | None = None, settle: float = STEADY_SETTLE_S
) -> SteadyWindow:
    """:func:`steady_window_rule` for a reducer's drive program: ramps from
    ``reducer.operating``, crank period from the input speed at the end of the run
    (``input_speed`` [rad/s], default the operating point's) and the tooth counts
    (:func:`flexrv.geometry.kinematics.member_speeds`)."""
    from flexrv.geometry.kinematics import member_speeds

    op = reducer.operating
    w = op.input_speed if input_speed is None else float(input_speed)
    fs, ss = reducer.first_stage, reducer.second_stage
    w_rel = abs(float(member_speeds(w, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count).crank_relative))
    period = 2.0 * math.pi / w_rel if w_rel > 0 else float("inf")
    return steady_window_rule(max(op.speed_ramp_time_s, op.load_ramp_end_s), t_end, period, settle)


def results_from_states(
    model,
    t,
    q,
    v,
    dt: float,
    status: str = "completed",
    timing: dict | None = None,
    chunk: int = 1000,
    cls: type[Results] = Results,
    records: dict | None = None,
) -> Results:
    """Build :class:`Results` (or the subclass ``cls``) from recorded states (T,), (T, n), (T, n).

    The variables are the model's declared outputs (:func:`flexrv.model.outputs.model_outputs`,
    read by name: this module never sees the state layout or the member names; TE and the
    input and output power are among them). ``records``:
    the groups' records the integrator computed at the T samples
    (:meth:`flexrv.model.kernels.HistoryRecorder.records`), used where valid."""
    from flexrv.geometry.kinematics import member_speeds
    from flexrv.model.outputs import model_outputs

    p = model.params
    t = np.asarray(t, dtype=float)
    if len(t) > 1:  # keep the last record of any repeated time (adaptive step reduction)
        keep = np.r_[np.diff(t) > 0, True]
        if not keep.all():  # else (the usual case) no copies of the states and records
            t, q, v = t[keep], q[keep], v[keep]
            if records is not None:
                records = {
                    "valid": {g: np.asarray(m)[keep] for g, m in records["valid"].items()},
                    "data": {g: {k: a[keep] for k, a in d.items()} for g, d in records["data"].items()},
                }
    data: dict[str, xr.Variable] = {}
    for name, o in model_outputs(model, t, q, v, chunk=chunk, records=records).items():
        data[name] = _var(o.values, o.dims, o.units, o.long_name, o.role, o.summary)
    ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
    red = model.reducer
    t_end = float(t[-1]) if len(t) else 0.0
    w_end = abs(float(np.asarray(model.input_speed(np.array([t_end])), dtype=float).ravel()[0])) if len(t) else 0.0
    win = steady_window_for(red, t_end, input_speed=w_end)
    s0, s1 = win.start_s, win.end_s
    ks = member_speeds(1.0, p.z_s, p.z_p, p.z_c, p.z_rp)
    ds.attrs.update(
        {
            "preset": red.name,
            "model": model.name,
            "status": status,
            "dt_s": dt,
            "ratio": p.ratio,
            "rated_input_speed_rad_s": p.input_speed,
            "steady_start_s": s0,
            "steady_end_s": s1,
            "steady": int(win.steady),
            "steady_revolutions": win.revolutions,
            "steady_note": win.note,
            "crank_period_s": win.crank_period_s,
            "crank_relative_per_input": float(ks.crank_relative),
            "crank_absolute_per_input": float(ks.crank_absolute),
            "needle_model": red.needle_bearing.model,
            "pin_law": red.contact.pin_law,
            "timing": json.dumps(to_jsonable(timing or {})),
        }
    )
    for key, value in model.info.items():  # e.g. flexible_bodies: how to rebuild the reduced bodies
        if isinstance(value, bool):  # (NetCDF has no boolean attributes: 0 / 1)
            value = int(value)
        ds.attrs[key] = value if isinstance(value, (str, int, float)) else json.dumps(to_jsonable(value))
    return cls(ds, reducer=red)


def load_results(directory: str | Path) -> Results:
    """Read a run directory written by :meth:`Results.save`."""
    return Results.load(directory)
