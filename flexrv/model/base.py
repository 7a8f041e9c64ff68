"""Building blocks of the multibody models: members (nodes), force-element
groups and the assembled model.

A *member* is a body with its own Exudyn ``NodeGenericODE2`` (coordinates are
absolute: reference 0, initial = nominal pose) and a constant mass matrix. A
*force group* couples several members. The rigid reducer's groups (gear stage,
crank supports, needle bearings, pins, rigid main bearing, loads) and the
ball-resolved bearing's rows are :class:`KernelGroup` s: their physics is one
numba-compiled kernel each, and the model evaluates all of them in ONE compiled call
from ONE ``ObjectGenericODE2`` (:class:`flexrv.model.kernels.FusedForces`; with one
numpy element per group, 95 % of a step was Python overhead). The flexible crank
(Exudyn-native FFRF body) keeps its own element with a Python force function.
The assembled model (:class:`flexrv.model.assembled.AssembledModel`) lives in its
own module, above the kernels it calls.

A group's ``evaluate(t, q, v)`` accepts one state (q of shape (n,), the solver
path) or a whole time history (shape (T, n)), from which the declared outputs
(:mod:`flexrv.model.outputs`) recover every contact force as a named output. Replacing a member group by a
flexible one (flexible-bearing issue) means registering another group under the
same output names.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Member:
    """A body of the model: ``n`` coordinates, constant mass matrix, initial state.

    ``kind`` says what the coordinates are (used by the declared outputs,
    :mod:`flexrv.model.outputs`, for the kinetic energy and the angular momentum): ``"planar"``
    (x, y, rotation about the axis first, as carrier, cranks and discs), ``"points"`` (x, y, z of point masses,
    e.g. the balls) or ``"modal"`` (elastic modal coordinates of a reduced body, with
    constant ``stiffness_matrix`` and ``damping_matrix`` added to the member's own
    Exudyn element).
    """

    name: str
    mass_matrix: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    labels: tuple[str, ...]
    node: int = -1  #: Exudyn node number (set on assembly)
    offset: int = -1  #: first index in the model's state vector
    kind: str = "planar"
    stiffness_matrix: np.ndarray | None = None  #: constant K [N/m] (modal members)
    damping_matrix: np.ndarray | None = None  #: constant D [N s/m] (modal members)

    @property
    def n(self) -> int:
        return len(self.q0)


@dataclass
class Output:
    """A named output of a group, evaluated on a time history.

    ``values`` has shape (T, *shape of dims[1:]); ``dims`` names every axis, the
    first being ``time``. ``role``: "friction" for dissipated friction power [W] (summed
    into ``friction_power``), else ""; ``summary``: the run-summary rows read from this
    output (:class:`SummaryRow`, declared by the element's ``summary_rows``)."""

    values: np.ndarray
    dims: tuple[str, ...]
    units: str
    long_name: str
    role: str = ""
    summary: tuple = ()


def exudyn_vector(values) -> np.ndarray:
    """An Exudyn user function's coordinate list (Exudyn passes Python lists) as a new
    float64 array: ``np.fromiter``, the fastest conversion of a list of floats
    (per conversion: 84 floats 1.3 us instead of 1.6 us with np.array, 120
    floats 1.8 instead of 2.5-3.2 us; two per element call, ~12 row calls per step).

    >>> exudyn_vector([1.0, 2.5])
    array([1. , 2.5])
    """
    return np.fromiter(values, np.float64, len(values))


class ForceGroup:
    """Base class of a vectorised force-element group.

    Subclasses set ``name`` and ``members`` (names of the members whose
    coordinates form the group's local vector, in order) and implement
    :meth:`evaluate`.
    """

    name: str = "group"
    members: tuple[str, ...] = ()
    #: True: analytic Jacobian via :meth:`jacobian`; False: Exudyn differentiates numerically
    analytic_jacobian: bool = False

    def evaluate(self, t, q, v, want_outputs: bool = False):
        """Return (generalized force (..., n), outputs dict or None)."""
        raise NotImplementedError

    def jacobian(self, t, q, v):
        """(dF/dq, dF/dv), each (n, n), of the generalized force."""
        raise NotImplementedError

    def check(self) -> str | None:
        """Return a failure message if the last evaluated state is unphysical."""
        return None

    def recorded_elements(self) -> list:
        """The group's own Exudyn elements that keep their per-contact results of the last
        call (:class:`flexrv.model.kernels.HistoryRecorder`): (element with ``memo`` =
        (t, q, v) of that call, the member names of its coordinates, [(group, key, live
        float64 array)]). None by default (the fused kernel groups record through
        :class:`flexrv.model.kernels.FusedForces`)."""
        return []

    def recorded_outputs(self, t, q, v, rec: dict, valid) -> dict:
        """Named outputs over a history (local coordinates) from the run's records of
        :meth:`recorded_elements` (``rec``: key -> (T, ...); samples not ``valid`` to be
        evaluated here); groups that record must implement it."""
        raise NotImplementedError

    def new_step(self) -> None:
        """Hook called at the start of every time step (e.g. to drop caches)."""

    def reset(self) -> None:
        """Hook called before a run: forget all state of previous evaluations."""
        self.new_step()

    # -------------------------------------------------------------- exudyn glue
    def add_to(self, mbs, nodes: list[int], sizes: list[int]) -> int:
        """Add the group's ObjectGenericODE2 to ``mbs``; return its object number."""
        from exudyn.itemInterface import ObjectGenericODE2

        stats = self.stats

        def force_fn(mbs_, t, item, q, q_t):
            stats[0] += 1
            f, _ = self.evaluate(t, exudyn_vector(q), exudyn_vector(q_t))
            return f

        kwargs = {}
        if self.analytic_jacobian:

            def jac_fn(mbs_, t, item, q, q_t, f_q, f_v):
                stats[1] += 1
                dq, dv = self.jacobian(t, exudyn_vector(q), exudyn_vector(q_t))
                return -(f_q * dq + f_v * dv)

            kwargs["jacobianUserFunction"] = jac_fn
        return mbs.AddObject(ObjectGenericODE2(nodeNumbers=nodes, forceUserFunction=force_fn, **kwargs))

    @property
    def stats(self) -> list[int]:
        """[force calls, jacobian calls] (mutable counters)."""
        if not hasattr(self, "_stats"):
            self._stats = [0, 0]
        return self._stats


_NO_JACOBIAN = np.zeros((0, 0))


@dataclass(frozen=True)
class SummaryRow:
    """One number of the run summary: ``key`` (with its unit in the name where it has one),
    ``units``, ``description``, the declared output it reads (``source``) and the reduction
    over the steady window (``reduce``: "max", "min", "mean", "max_abs" or "p2p" over all
    samples and axes, or "mean_sum": the window mean of the sum over the non-time axes)."""

    key: str
    units: str
    description: str
    source: str
    reduce: str = "max"


class KernelGroup(ForceGroup):
    """A force group whose physics is ONE numba-compiled kernel.

    The kernel (a module-level function of the group's module, written with
    explicit loops) adds the group's generalized forces, and optionally its
    Jacobians, into preallocated arrays over ANY coordinate vector: ``pack(idx)``
    returns the kernel's argument tuple, ``idx`` giving the position of each of the
    group's local coordinates in that vector. The group's own :meth:`evaluate` /
    :meth:`jacobian` call the kernel on the local vector (idx = 0..n-1); the
    fused element (:class:`flexrv.model.kernels.FusedForces`) calls the same
    kernels, inside one compiled function, on the model's vector. Per-contact
    results of the last call stay in the group's arrays (``record``), from which
    :meth:`outputs` builds the named outputs; a time history (T, n) loops the
    kernel over the samples.

    Subclasses set ``kind`` (their name in the element registry,
    :mod:`flexrv.model.core.registry`) and ``kernel`` (``staticmethod`` of the compiled
    kernel(q, v, f, jq, jv, jac, pack)), implement :meth:`pack`, :meth:`record_sources`
    and :meth:`outputs`, and may declare ``time_field`` (the pack's array of time inputs,
    written by :meth:`set_time`), ``friction_outputs`` and ``summary_rows``.
    """

    analytic_jacobian = True
    kind: str = ""
    #: the compiled kernel, ``staticmethod(kernel)``
    kernel = None
    #: field of the pack that holds the time inputs at t (:meth:`time_inputs`), "" if none
    time_field: str = ""
    #: the element's Jacobian costs several force calls (the bearing rows' condensed rings): the
    #: compiled integrator keeps it between full Jacobians while it refreshes the other elements'
    #: every step (partial Jacobians, :mod:`flexrv.model.numerics.gen_alpha`). On the class: it can
    #: be (the generated integrator routes its Jacobian); on an instance: it is (an element may set
    #: it per instance, :func:`flexrv.model.integrator.partial_jacobian_allowed` reads the instance)
    costly_jacobian: bool = False
    #: names of the outputs that are dissipated friction power [W] (>= 0), summed into ``friction_power``
    friction_outputs: tuple[str, ...] = ()
    #: rows of the run summary computed from this element's outputs (:class:`SummaryRow`)
    summary_rows: tuple = ()
    #: message of the ConvergenceError raised when :meth:`failure_counter` grows in a call
    failure_message: str = "an inner solve of a force element did not converge"
    #: the element's typed parameters from the design, ``staticmethod(builder)``: builder(reducer,
    #: drive) -> a frozen dataclass (``drive``: the shared :class:`flexrv.model.drive.DriveParameters`),
    #: the first argument of the constructor (:meth:`from_design`)
    parameters = None

    @classmethod
    def from_design(cls, reducer, drive, *args, **kwargs):
        """The element of a design: ``cls(cls.parameters(reducer, drive), *args, **kwargs)``
        (only this element's parameters are built)."""
        return cls(cls.parameters(reducer, drive), *args, **kwargs)

    def reset(self) -> None:
        """Forget the state of earlier evaluations; the time inputs are written again."""
        self._time_last = None
        super().reset()

    def set_time(self, t, array) -> None:
        """Write the time inputs at t into the pack's live ``array`` (skipped while
        :meth:`time_inputs` returns the same cached object: the array still holds it unless
        a group's own evaluate or a history pass wrote it, which clear ``_time_last``)."""
        x = self.time_inputs(t)
        if x is not getattr(self, "_time_last", None):
            array[:] = x
            self._time_last = x

    def failure_counter(self, pack):
        """A live int64 array (1,) of ``pack`` that the kernel increments on a failed inner
        solve (a :class:`flexrv.errors.ConvergenceError` is raised when it grows), or None."""
        return None

    def pack(self, idx: np.ndarray, history: bool = False) -> tuple:
        """Kernel arguments for coordinates at ``idx`` (int64); ``history``: fresh
        warm-start state (post-processing of a time history)."""
        raise NotImplementedError

    def time_inputs(self, t) -> tuple:
        """Time-dependent kernel inputs at scalar t (drive angle, loads)."""
        return ()

    def time_inputs_many(self, ts: np.ndarray):
        """Time-dependent inputs for every sample of a history (vectorised; row i is
        passed to :meth:`run` as ``inputs``), or None."""
        return None

    def run(self, t, q, v, f, jq, jv, jac: bool, pack: tuple, inputs=None) -> None:
        """Call the compiled kernel: add forces into f (and Jacobians into jq, jv);
        ``inputs``: precomputed time inputs at t (else :meth:`time_inputs`), written into
        the pack's ``time_field``; raises ConvergenceError if the kernel's failure counter grew."""
        if self.time_field:
            getattr(pack, self.time_field)[:] = self.time_inputs(t) if inputs is None else inputs
            self._time_last = None  # the live array no longer holds what set_time wrote
        ctr = self.failure_counter(pack)
        before = ctr[0] if ctr is not None else 0
        type(self).kernel(q, v, f, jq, jv, jac, pack)
        if ctr is not None and ctr[0] != before:
            from flexrv.errors import ConvergenceError

            raise ConvergenceError(self.failure_message)

    def record_sources(self) -> dict:
        """The per-contact result arrays the kernel fills through the pack (live, not
        copies), by record key: float64, C-contiguous, fixed shapes. :meth:`record`
        copies them after one call; the compiled history pass of the fused element
        (:meth:`flexrv.model.kernels.FusedForces.history`) copies them per sample."""
        return {}

    def record(self) -> dict:
        """Copies of the per-contact results of the last kernel call."""
        return {k: a.copy() for k, a in self.record_sources().items()}

    def outputs(self, t, rec: dict) -> dict:
        """Named outputs from stacked records (leading axis time)."""
        return {}

    def evaluate(self, t, q, v, want_outputs: bool = False):
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)
        n = q.shape[-1]
        idx = np.arange(n, dtype=np.int64)
        if q.ndim == 1:
            f = np.zeros(n)
            self.run(float(t), q, v, f, _NO_JACOBIAN, _NO_JACOBIAN, False, self.pack(idx))
            out = None
            if want_outputs:
                rec = {k: a[None] for k, a in self.record().items()}
                out = {
                    k: Output(o.values[0], o.dims, o.units, o.long_name)
                    for k, o in self.outputs(np.asarray(t, dtype=float)[None], rec).items()
                }
            return f, out
        lead = q.shape[:-1]
        # writable and C-contiguous like the fused kernel's arguments: a read-only (broadcast) or
        # strided array would be another type signature of the kernel, compiled a second time
        qf = np.require(q.reshape(-1, n), requirements=("C", "W"))
        vf = np.require(np.broadcast_to(v, q.shape).reshape(-1, n), requirements=("C", "W"))
        ts = np.broadcast_to(np.asarray(t, dtype=float), lead).ravel()
        pack = self.pack(idx, history=True)
        f = np.zeros(qf.shape)
        recs = []
        inputs = self.time_inputs_many(ts)
        for i in range(qf.shape[0]):
            self.run(
                float(ts[i]),
                qf[i],
                vf[i],
                f[i],
                _NO_JACOBIAN,
                _NO_JACOBIAN,
                False,
                pack,
                None if inputs is None else inputs[i],
            )
            if want_outputs:
                recs.append(self.record())
        out = None
        if want_outputs:
            rec = {k: np.stack([r[k] for r in recs]).reshape(lead + recs[0][k].shape) for k in recs[0]} if recs else {}
            out = self.outputs(ts.reshape(lead), rec) if recs else {}
        return f.reshape(q.shape), out

    def jacobian(self, t, q, v):
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)
        n = q.shape[-1]
        f = np.zeros(n)
        dq, dv = np.zeros((n, n)), np.zeros((n, n))
        self.run(float(t), q, v, f, dq, dv, True, self.pack(np.arange(n, dtype=np.int64)))
        return dq, dv
