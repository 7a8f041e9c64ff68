"""Drive and loads as in the seeds.

* Input: speed-driven sun, omega_in(t) = omega_r step(t, 0, 0, t_r, 1) with the
  cubic Adams STEP (:cite:`seed002`: 0 -> 1215 r/min over 0.1 s). The angle is its exact
  integral: with s = t/t_r, theta = omega_r t_r (s^3 - s^4/2) for t <= t_r and
  omega_r (t - t_r/2) afterwards.
* Output: load torque T_max step(t, t1, 0, t2, 1) on the carrier against the
  rotation (:cite:`seed000,seed002`), plus optional external radial force (along +x),
  axial force (+z) and tilting moment (about x) on the output flange, ramped in
  with the same STEP window as the torque (a sudden 30 kN at t = 0 would only add
  a start-up transient of the bearing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.contact.laws import _step_and_slope, adams_step
from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, pack_type


@dataclass(frozen=True)
class LoadParameters:
    """The external loads on the output flange besides the torque (design ``[operating]``).
    Built by :func:`load_parameters`."""

    radial: float  #: external radial force along +x [N]
    axial: float  #: external axial force along +z [N]
    tilt: float  #: tilting moment about x [N m]


def load_parameters(reducer, drive) -> LoadParameters:
    """The design's external forces and tilting moment (the load torque and its ramp are
    the drive's, :class:`flexrv.model.drive.DriveParameters`: ``drive`` is not read)."""
    op = reducer.operating
    return LoadParameters(radial=op.external_radial_force_N, axial=op.external_axial_force_N, tilt=op.tilting_moment_Nm)


#: :func:`loads_kernel`'s pack: the carrier's 6 indices and the generalized load vector at t
LoadsPack = pack_type("LoadsPack", ("idx", (np.int64, 1)), ("load", (np.float64, 1)))


def ramp_drive(speed: float, ramp_time: float):
    """(theta(t), omega(t)) of the Adams-STEP speed ramp; vectorised in t."""

    def omega(t):
        if isinstance(t, float):  # the solver's scalar path: no array round trip
            return speed * _step_and_slope(t, 0.0, 0.0, ramp_time, 1.0)[0] if ramp_time > 0 else speed
        t = np.asarray(t, dtype=float)
        if ramp_time <= 0:
            return np.full_like(t, speed)
        return speed * adams_step(t, 0.0, 0.0, ramp_time, 1.0)

    def theta(t):
        if isinstance(t, float):
            if ramp_time <= 0:
                return speed * t
            if t > ramp_time:
                return speed * (t - 0.5 * ramp_time)
            s = min(max(t / ramp_time, 0.0), 1.0)
            return speed * ramp_time * (s**3 - 0.5 * s**4)
        t = np.asarray(t, dtype=float)
        if ramp_time <= 0:
            return speed * t
        s = np.clip(t / ramp_time, 0.0, 1.0)
        inside = speed * ramp_time * (s**3 - 0.5 * s**4)
        return np.where(t <= ramp_time, inside, speed * (t - 0.5 * ramp_time))

    return theta, omega


def locked_drive():
    """Input locked (stiffness test): theta = omega = 0."""

    def zero(t):
        return np.zeros_like(np.asarray(t, dtype=float))

    return zero, zero


def position_drive():
    """Quasi-static drive: the model's 'time' argument is the input angle [rad]
    (theta(t) = t) and every speed is zero."""

    def theta(t):
        return np.asarray(t, dtype=float)

    def omega(t):
        return np.zeros_like(np.asarray(t, dtype=float))

    return theta, omega


def step_torque(t_max: float, t1: float, t2: float):
    """T(t) = T_max step(t, t1, 0, t2, 1) (jump at t1 if t2 == t1)."""

    def torque(t):
        if isinstance(t, float):  # scalar path of the solver
            if t2 <= t1:
                return t_max if t >= t1 else 0.0
            return t_max * _step_and_slope(t, t1, 0.0, t2, 1.0)[0]
        t = np.asarray(t, dtype=float)
        if t2 <= t1:
            return np.where(t >= t1, t_max, 0.0)
        return t_max * adams_step(t, t1, 0.0, t2, 1.0)

    return torque


def piecewise_torque(times, values):
    """Piecewise-linear torque program T(t) through (times, values) (stiffness test)."""
    times = np.asarray(times, dtype=float)
    values = np.asarray(values, dtype=float)

    def torque(t):
        return np.interp(np.asarray(t, dtype=float), times, values)

    return torque


@njit(cache=True)
def loads_kernel(q, v, f, jq, jv, jac, pack):
    """f[idx] += load (no state dependence: no Jacobian)."""
    idx, load = pack.idx, pack.load
    for i in range(idx.shape[0]):
        f[idx[i]] += load[i]


class OutputLoads(KernelGroup):
    """Load torque and external forces on the carrier (member ``carrier``:
    x, y, theta, z, rx, ry). The loads depend on time only: :meth:`time_inputs`
    evaluates them (cached per time), the fused kernel adds them."""

    name = "loads"
    kind = "loads"
    summary_rows = (SummaryRow("mean_load_torque_Nm", "N m", "mean load torque on the output", "load_torque", "mean"),)
    kernel = staticmethod(loads_kernel)
    time_field = "load"
    members = ("carrier",)
    parameters = staticmethod(load_parameters)

    def __init__(self, params: LoadParameters, torque, ramp: tuple[float, float] | None = None):
        self.params = params
        self.torque = torque
        self.const = np.array([params.radial, 0.0, 0.0, params.axial, params.tilt, 0.0])
        #: the external forces/moment ramp in with step(t, t1, 0, t2, 1) (None: from t = 0)
        self.ramp = ramp
        self._cache = None
        self.load = np.zeros(6)

    def _forces(self, t, shape):
        f = np.broadcast_to(self.const, shape).copy()
        if self.ramp is not None and self.ramp[1] > 0:
            t1, t2 = self.ramp
            f = f * np.asarray(adams_step(t, t1, 0.0, max(t2, t1 + 1e-12), 1.0))[..., None]
        f[..., 2] = -self.torque(t)
        return f

    def time_inputs(self, t):
        """Generalized load vector (6,) at t (cached: same t in all Newton iterations)."""
        if self._cache is None or self._cache[0] != t:
            if isinstance(t, float) and not self.const.any():  # torque only: the solver's scalar path
                f = np.zeros(6)
                f[2] = -float(self.torque(t))
            else:
                f = self._forces(np.asarray(t, dtype=float), (6,))
            self._cache = (t, f)
        return self._cache[1]

    def pack(self, idx, history=False):
        return LoadsPack(idx, self.load)

    @staticmethod
    def empty_pack():
        return empty_pack(LoadsPack)

    def time_inputs_many(self, ts):
        return self._forces(ts, ts.shape + (6,))

    def record_sources(self):
        return {"load": self.load}

    def outputs(self, t, rec):
        return {"load_torque": Output(-rec["load"][..., 2], ("time",), "N m", "load torque on the output")}

    def reset(self) -> None:
        self._cache = None
        super().reset()
