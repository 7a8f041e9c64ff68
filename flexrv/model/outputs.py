"""Declared outputs of an assembled model: every result variable that comes from the state
of the members, the drive or the force groups, with its name, dimensions, unit and long name.

Post-processing (:func:`flexrv.post.results.results_from_states`) reads these outputs by name
and never sees the state layout or the member names (PyBaMM's ``model.variables``
pattern). Three kinds:

* **member-state outputs** (:data:`STATE_OUTPUTS`): one coordinate of the position ``q`` or the
  speed ``v`` of a member role -- the ``carrier``, each ``crank`` j (dimension ``crank``) or
  each ``disc`` k (dimension ``disc``);
* **derived outputs** (:data:`DERIVED_OUTPUTS`): functions of the member states and the drive
  (output angle and speed, relative crank speed, carrier tilt, input and load torque,
  kinetic energy, angular momentum);
* **friction output** ``friction_power``: the sum of the outputs the groups declare as
  friction (``friction_outputs``) [W] (present when friction is on);
* **group outputs**: the named :class:`flexrv.model.base.Output` s of every force group
  (contact forces, film thickness, ...), evaluated over the time history in chunks
  (the compiled groups' taken from what the integrator computed where the run recorded
  it, else in one compiled loop over the samples; see :func:`group_outputs`).

:func:`model_outputs` evaluates all of them on a recorded history; :func:`declared_outputs`
lists the names, units and long names of the member-state and derived outputs without a run.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from flexrv.model.base import Output
from flexrv.units import ARCSEC_PER_RAD

#: member roles: role -> (member-name prefix, dimension of the result axis or None, count attribute
#: of the model parameters). ``carrier`` is one member; ``crank`` j and ``disc`` k are numbered.
ROLES: dict[str, tuple[str, str | None, str | None]] = {
    "carrier": ("carrier", None, None),
    "crank": ("crank", "crank", "n_cranks"),
    "disc": ("disc", "disc", "n_discs"),
}


@dataclass(frozen=True)
class StateOutput:
    """One coordinate of a member role's position (``state="q"``) or speed (``"v"``)."""

    name: str
    role: str  #: key of :data:`ROLES`
    state: str  #: "q" or "v"
    coordinate: int  #: index in the member's own coordinates (see its ``labels``)
    units: str
    long_name: str


#: member-state outputs, in result order. Coordinates: carrier (x, y, theta, z, rx, ry),
#: crank (x, y, phi), disc (x, y, psi) (:func:`flexrv.model.factory.build_rigid`).
STATE_OUTPUTS: tuple[StateOutput, ...] = (
    StateOutput("crank_speed", "crank", "v", 2, "rad/s", "crank (planet) speed, absolute"),
    StateOutput("crank_angle", "crank", "q", 2, "rad", "crank (planet) angle, absolute"),
    StateOutput("crank_x", "crank", "q", 0, "m", "crank centre x"),
    StateOutput("crank_y", "crank", "q", 1, "m", "crank centre y"),
    StateOutput("disc_x", "disc", "q", 0, "m", "disc centre x"),
    StateOutput("disc_y", "disc", "q", 1, "m", "disc centre y"),
    StateOutput("disc_speed", "disc", "v", 2, "rad/s", "disc rotation speed"),
    StateOutput("carrier_x", "carrier", "q", 0, "m", "carrier centre x"),
    StateOutput("carrier_y", "carrier", "q", 1, "m", "carrier centre y"),
    StateOutput("carrier_z", "carrier", "q", 3, "m", "carrier axial displacement"),
)


@dataclass(frozen=True)
class DerivedOutput:
    """An output computed from the history by ``fn(model, t, q, v) -> values`` (leading axis time)."""

    name: str
    dims: tuple[str, ...]
    units: str
    long_name: str
    fn: Callable


def _member_names(model, role: str) -> list[str]:
    prefix, dim, count = ROLES[role]
    if dim is None:
        return [prefix]
    return [f"{prefix}{i}" for i in range(int(getattr(model.params, count)))]


def _coordinate(model, q, role: str, coordinate: int) -> np.ndarray:
    """(T,) for a single member, (T, n_members) for a numbered role."""
    cols = [q[:, model.slice(name)][:, coordinate] for name in _member_names(model, role)]
    return cols[0] if ROLES[role][1] is None else np.stack(cols, axis=1)


def _theta_out(model, t, q, v):
    return _coordinate(model, q, "carrier", 2)


def _omega_out(model, t, q, v):
    return _coordinate(model, v, "carrier", 2)


def _te(model, t, q, v):
    """Transmission error theta_out - theta_in / i [arcsec]."""
    th_in = np.asarray(model.input_angle(t), dtype=float)
    return (_theta_out(model, t, q, v) - th_in / model.params.ratio) * ARCSEC_PER_RAD


def _crank_speed_relative(model, t, q, v):
    return _coordinate(model, v, "crank", 2) - _omega_out(model, t, q, v)[:, None]


def _carrier_tilt(model, t, q, v):
    return np.hypot(_coordinate(model, q, "carrier", 4), _coordinate(model, q, "carrier", 5))


def _input_speed(model, t):
    return np.asarray(model.input_speed(t), dtype=float)


def _kinetic_energy(model, t, q, v):
    """Sum of 1/2 v^T M v over the members plus the input shaft's 1/2 J_in omega_in^2
    (quasi-static balls, the ball model's default, carry none: they are no members)."""
    ke = np.zeros_like(t)
    for m in model.members.values():
        vm = v[:, model.slice(m.name)]
        if m.kind == "points":  # point masses: a diagonal mass matrix (the einsum over (3Z)^2 cost ~0.5 s/s)
            ke += 0.5 * (vm * vm) @ np.diag(m.mass_matrix)
        else:
            ke += 0.5 * np.einsum("ti,ij,tj->t", vm, m.mass_matrix, vm)
    return ke + 0.5 * model.params.input_inertia * _input_speed(model, t) ** 2


def _angular_momentum(model, t, q, v):
    """Angular momentum about the axis of the planar members (spin + orbit) and the point
    masses; modal members' elastic vibration about their frames carries no net angular
    momentum about the axis to first order."""
    lz = np.zeros_like(t)
    for m in model.members.values():
        qm, vm = q[:, model.slice(m.name)], v[:, model.slice(m.name)]
        if m.kind == "planar":  # x, y, rotation first
            lz += m.mass_matrix[2, 2] * vm[:, 2] + m.mass_matrix[0, 0] * (qm[:, 0] * vm[:, 1] - qm[:, 1] * vm[:, 0])
        elif m.kind == "points":  # (x, y, z) per point, diagonal mass
            mass = np.diag(m.mass_matrix)[0::3]
            lz += ((qm[:, 0::3] * vm[:, 1::3] - qm[:, 1::3] * vm[:, 0::3]) * mass).sum(axis=-1)
    return lz


#: outputs derived from the member states and the drive, in result order; ``position`` says
#: where each goes among the other outputs (see :func:`model_outputs`)
DERIVED_OUTPUTS: tuple[DerivedOutput, ...] = (
    DerivedOutput(
        "theta_in",
        ("time",),
        "rad",
        "input angle",
        lambda model, t, q, v: np.asarray(model.input_angle(t), dtype=float),
    ),
    DerivedOutput("theta_out", ("time",), "rad", "output angle", _theta_out),
    DerivedOutput("omega_in", ("time",), "rad/s", "input speed", lambda model, t, q, v: _input_speed(model, t)),
    DerivedOutput("omega_out", ("time",), "rad/s", "output speed", _omega_out),
    DerivedOutput("te", ("time",), "arcsec", "TE", _te),
    DerivedOutput(
        "crank_speed_relative", ("time", "crank"), "rad/s", "crank speed relative to the carrier", _crank_speed_relative
    ),
    DerivedOutput(
        "carrier_tilt", ("time",), "rad", "carrier tilt (magnitude of the rotations about x and y)", _carrier_tilt
    ),
    DerivedOutput(
        "output_torque",
        ("time",),
        "N m",
        "output (load) torque",
        lambda model, t, q, v: np.asarray(model.load_torque(t), dtype=float),
    ),
    DerivedOutput("kinetic_energy", ("time",), "J", "kinetic energy", _kinetic_energy),
    DerivedOutput(
        "angular_momentum",
        ("time",),
        "N m s",
        "angular momentum of the rigid members and massive balls about the axis",
        _angular_momentum,
    ),
)

#: result order of the member and drive outputs (group outputs follow ``carrier_tilt``)
_ORDER = (
    "theta_in",
    "theta_out",
    "omega_in",
    "omega_out",
    "te",
    "crank_speed",
    "crank_speed_relative",
    "crank_angle",
    "crank_x",
    "crank_y",
    "disc_x",
    "disc_y",
    "disc_speed",
    "carrier_x",
    "carrier_y",
    "carrier_z",
    "carrier_tilt",
)


def declare_element_outputs(model, outputs: dict) -> None:
    """Mark the group outputs the model's elements declare: their friction outputs (``role``
    "friction", :attr:`flexrv.model.base.KernelGroup.friction_outputs`) and the summary rows
    that read them (``summary``, :attr:`~flexrv.model.base.KernelGroup.summary_rows`)."""
    from dataclasses import replace

    for g in model.groups:
        for name in getattr(g, "friction_outputs", ()):
            if name in outputs:
                outputs[name] = replace(outputs[name], role="friction")
        for row in getattr(g, "summary_rows", ()):
            if row.source in outputs:
                o = outputs[row.source]
                outputs[row.source] = replace(o, summary=o.summary + (row,))


def declared_outputs() -> dict[str, tuple[tuple[str, ...], str, str]]:
    """name -> (dims, units, long_name) of the member-state and derived outputs (the group
    outputs are declared by the groups and known after a run), plus ``input_torque``."""
    out = {}
    for s in STATE_OUTPUTS:
        dim = ROLES[s.role][1]
        out[s.name] = (("time",) if dim is None else ("time", dim), s.units, s.long_name)
    for d in DERIVED_OUTPUTS:
        out[d.name] = (d.dims, d.units, d.long_name)
    out["input_torque"] = (("time",), "N m", "input torque")
    out["power_in"] = (("time",), "W", "input power")
    out["power_out"] = (("time",), "W", "output power")
    return out


def group_outputs(model, t, q, v, chunk: int = 1000, records: dict | None = None) -> dict[str, Output]:
    """The named outputs of every force group over the history (T,), (T, n), (T, n),
    evaluated in chunks of ``chunk`` samples. The groups of the model's fused compiled
    element (:class:`flexrv.model.kernels.FusedForces`) are evaluated together, one
    compiled loop over the samples of a chunk (:meth:`~flexrv.model.kernels.FusedForces.history`:
    the same kernels on the same inputs as their own evaluate, bit for bit); the
    others by their own evaluate. ``records`` (:meth:`flexrv.model.kernels.HistoryRecorder.records`
    of the run): the groups' records the integrator computed at the samples, used
    where their ``valid`` mask is set (the history pass fills the other samples; see
    the recorder for what differs) -- the fused groups' and those of groups with
    recording elements (``recorded_outputs``); the arrays are filled in place at the
    rows not valid and may be referenced by the outputs."""
    outs: dict[str, list] = {}
    meta: dict[str, tuple] = {}
    fused = getattr(model, "fused", None)
    fused_groups = list(fused.recorded) if fused is not None else []
    fused_recs: dict = {}
    rec_data = records["data"] if records is not None else {}
    rec_valid = records["valid"] if records is not None else {}
    if fused_groups:
        nt = len(t)
        have = all(g in rec_data for g in fused_groups)
        todo = np.flatnonzero(~np.asarray(rec_valid[fused_groups[0]], dtype=bool)) if have else np.arange(nt)
        if have:  # used in place (the history pass below fills the rows not valid)
            fused_recs = {g: dict(rec_data[g]) for g in fused_groups}
        if len(todo):
            ix = fused.index
            for a in range(0, len(todo), chunk):
                rows = todo[a : a + chunk]
                part = fused.history(t[rows], q[rows][:, ix], v[rows][:, ix])
                for g in fused_groups:
                    dst = fused_recs.setdefault(g, {})
                    for key, val in part[g].items():
                        if key not in dst:
                            dst[key] = np.empty((nt,) + val.shape[1:])
                        dst[key][rows] = val

    def put(out):
        for name, o in (out or {}).items():
            outs.setdefault(name, []).append(np.asarray(o.values))
            meta[name] = (o.dims, o.units, o.long_name)

    tf = np.asarray(t, dtype=float)
    for g in model.groups:
        if g in fused_recs:
            put(g.outputs(tf, fused_recs[g]))
            continue
        qg_all = model.group_state(g, q)
        vg_all = model.group_state(g, v)
        if g in rec_data:  # a group recorded from its own elements
            put(g.recorded_outputs(tf, qg_all, vg_all, dict(rec_data[g]), rec_valid[g]))
            continue
        for a in range(0, len(t), chunk):
            b = min(a + chunk, len(t))
            _, out = g.evaluate(t[a:b], qg_all[a:b], vg_all[a:b], want_outputs=True)
            put(out)
    result = {}
    for name, parts in outs.items():
        dims, units, long_name = meta[name]
        values = np.concatenate(parts, axis=0) if len(t) else np.zeros((0,) + parts[0].shape[1:])
        result[name] = Output(values, dims, units, long_name)
    return result


def model_outputs(model, t, q, v, chunk: int = 1000, records: dict | None = None) -> dict[str, Output]:
    """Every declared output of ``model`` on the recorded history t (T,), q, v (T, n), by name,
    in result order: drive and member outputs (with ``te``), group outputs, ``input_torque``
    (the sun's torque from the gear-stage group plus J_in d(omega_in)/dt), ``output_torque``,
    ``power_in`` (input torque times input speed), ``power_out`` (output torque times output
    speed), ``kinetic_energy``, ``angular_momentum``. ``records``: see :func:`group_outputs`."""
    t = np.asarray(t, dtype=float)
    declared = declared_outputs()
    computed: dict[str, np.ndarray] = {}
    for s in STATE_OUTPUTS:
        computed[s.name] = _coordinate(model, q if s.state == "q" else v, s.role, s.coordinate)
    derived = {d.name: d for d in DERIVED_OUTPUTS}
    out: dict[str, Output] = {}

    def put(name):
        values = derived[name].fn(model, t, q, v) if name in derived else computed[name]
        dims, units, long_name = declared[name]
        out[name] = Output(np.asarray(values), dims, units, long_name)

    for name in _ORDER:
        put(name)
    groups = group_outputs(model, t, q, v, chunk, records)
    declare_element_outputs(model, groups)
    out.update(groups)
    fric = {name: o.values.reshape(len(t), -1).sum(axis=1) for name, o in groups.items() if o.role == "friction"}
    if fric:
        out["friction_power"] = Output(
            np.sum(list(fric.values()), axis=0),
            ("time",),
            "W",
            f"power dissipated by friction, all groups ({', '.join(fric)})",
        )
    w_in = out["omega_in"].values
    acc_in = np.gradient(w_in, t) if len(t) > 1 else np.zeros_like(t)
    sun = groups["sun_torque"].values if "sun_torque" in groups else 0.0
    dims, units, long_name = declared["input_torque"]
    out["input_torque"] = Output(sun + model.params.input_inertia * acc_in, dims, units, long_name)
    put("output_torque")
    out["power_in"] = Output(out["input_torque"].values * out["omega_in"].values, *declared["power_in"])
    out["power_out"] = Output(out["output_torque"].values * out["omega_out"].values, *declared["power_out"])
    for name in ("kinetic_energy", "angular_momentum"):
        put(name)
    return out
