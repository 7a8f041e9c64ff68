"""One compiled residual and Jacobian for the rigid reducer's force groups.

:class:`FusedForces` evaluates every registered compiled force element
(:mod:`flexrv.model.core.registry`; here: gear stage, crank supports, needle bearings,
pins, rigid main bearing or the ball bearing's rows, loads) of a model in ONE call of the fused kernel generated
for the elements present, a numba function that calls the elements' own compiled
kernels (the physics stays in the elements' modules: one formula, one executor) on
the model's coordinate vector. It backs both the single
Exudyn ``ObjectGenericODE2`` of these groups (force and Jacobian user functions,
:meth:`FusedForces.add_to`) and :meth:`flexrv.model.assembled.AssembledModel.generalized_forces`.
Groups of other kinds (flexible crank) keep their own elements. The
generated ``fused_integrate`` (:mod:`flexrv.model.core.registry`) runs the compiled
generalized-alpha around the same kernel (:mod:`flexrv.model.integrator`).

Python work per call: Exudyn's argument lists to arrays (``np.asarray``), the
drive angle and load vector at t (cached per time), one call of the compiled entry
point (1.8 us of unboxing the 51 pack arrays, measured against an empty kernel of
the same arguments; the compiled work is 7 us at a fixed loaded state and ~15 us
in a run, where the closest points and the supports' inner solves move). Measured
in benchmarks/bench_rigid.py.

Outputs: :meth:`FusedForces.history` evaluates the same kernels over a recorded
time history in ONE compiled loop (the generated ``fused_history``, or on a run of the
compiled integrator that integrator's ``fused_integrate``: :meth:`FusedForces.drive_with`), copying each group's
per-contact arrays (:meth:`~flexrv.model.base.KernelGroup.record_sources`) per
sample: bit for bit the groups' own per-sample evaluate, without its ~50 us of
Python per sample. What remains (~22-28 us per sample) is the kernels' own work,
mostly the exact gap of every pin (the solver skips provably open pins; this pass
does not, so its ``pin_gap`` is exact for every pin). A simulation records the
same arrays from the integrator's own calls instead (:class:`HistoryRecorder`, ~2
us per sample; ``pin_gap`` of a pin the solver proved open is then a positive
lower bound) and uses this pass only where that record is missing or with
``Simulation.run(record_outputs=False)``.

Numba's on-disk cache (``cache=True``) keys each function on its OWN source file
only: after editing a kernel that other modules' compiled functions call (e.g.
:func:`flexrv.geometry.cycloid._foot_point` from the pins kernel), delete the
``__pycache__/*.nbi``/``*.nbc`` files, or the callers keep the old machine code. The
generated fused kernel is exempt: its file name carries a hash of its callees' sources.
"""

from __future__ import annotations

import contextlib
import os

import numpy as np
from numba import njit

from flexrv.model.base import exudyn_vector
from flexrv.model.core.registry import ELEMENTS, ROWS, ROWS_JAC, fused_functions, register, spec_of
from flexrv.model.cranks_discs import CrankSupports, NeedleBearings
from flexrv.model.flexible_bearing import BallBearingGroup
from flexrv.model.gear_stage import GearMeshes
from flexrv.model.loads import OutputLoads
from flexrv.model.main_bearing_rigid import RigidMainBearing
from flexrv.model.pins import PinContacts

#: the compiled force elements, in the fused kernel's call order (one registry line each)
for _element in (
    GearMeshes,
    CrankSupports,
    NeedleBearings,
    PinContacts,
    RigidMainBearing,
    BallBearingGroup,
    OutputLoads,
):
    register(_element)


@njit(cache=True)
def copy_records_if_same(q0, q, v0, v, index, src, dst, k):
    """If q0 == q[index] and v0 == v[index] exactly (``index`` empty: q0 == q, v0 == v):
    row k of every history buffer ``dst`` (T, size) from the flat live arrays ``src``;
    returns whether it copied."""
    full = index.shape[0] == 0
    n = q0.shape[0]
    if (q.shape[0] if full else index.shape[0]) != n or v0.shape[0] != n or v.shape[0] != q.shape[0]:
        return False
    for i in range(n):
        j = i if full else index[i]
        if q0[i] != q[j] or v0[i] != v[j]:
            return False
    for r in range(len(src)):
        dst[r][k, :] = src[r]
    return True


_F8 = np.dtype(np.float64)


def _f8c(a) -> bool:
    """float64 and C-contiguous: the types the compiled entry points were found for."""
    return a.dtype is _F8 and a.flags.c_contiguous


def _entry_point(fn, args):
    """The compiled function of the numba dispatcher ``fn`` (the fused kernel,
    :func:`copy_records_if_same`) for the types of ``args``, to be called directly
    (None if not found). Skips numba's dispatch, i.e. typing the ~50 arguments on
    every call (~1.7 us of a ~9 us call, measured); valid while the arguments keep
    their types, which the callers check for the only ones that change (q, v:
    float64, C-contiguous; the packs and record buffers are fixed at construction,
    jac / ts / ws are bool / float)."""
    from numba import typeof

    cres = fn.overloads.get(tuple(typeof(a) for a in args))
    return None if cres is None else cres.entry_point


def blas_threads() -> int | None:
    """BLAS threads inside simulations: FLEXRV_BLAS_THREADS if set (``0`` or empty:
    leave the library default), else 1. OpenBLAS's default threads spin on a
    loaded machine (1.9-2.4x wall on 2 cores)."""
    env = os.environ.get("FLEXRV_BLAS_THREADS")
    if env is None:
        return 1
    env = env.strip()
    return int(env) if env and int(env) > 0 else None


#: threadpoolctl's controller and the number of imported modules when it was built: its scan of the
#: process's shared libraries costs 2-4 ms CPU in a simulation process, paid once and again only after
#: new imports (which may load another BLAS); entering the limit with it 0.04-0.07 ms
_BLAS_CONTROLLER: list = [None, -1]


def _blas_controller():
    """The process's threadpoolctl controller, rebuilt when modules were imported since."""
    import sys

    if _BLAS_CONTROLLER[1] != len(sys.modules):
        from threadpoolctl import ThreadpoolController

        _BLAS_CONTROLLER[0] = ThreadpoolController()
        _BLAS_CONTROLLER[1] = len(sys.modules)
    return _BLAS_CONTROLLER[0]


@contextlib.contextmanager
def single_thread_blas():
    """Context manager limiting BLAS to :func:`blas_threads` threads (threadpoolctl)."""
    n = blas_threads()
    if n is None:
        yield
        return
    with _blas_controller().limit(limits=n, user_api="blas"):
        yield


class FusedForces:
    """The kernel groups of a model as one compiled residual (see module docstring).

    The element's coordinates are those of the members the kernel groups touch, in
    the model's member order; :attr:`index` maps them into the model's vector."""

    def __init__(self, model, groups=None):
        if groups is None:
            groups = [g for g in model.groups if spec_of(g) is not None]
        by_kind = {}
        for g in groups:
            if g.kind in by_kind:
                raise ValueError(f"two kernel groups of kind {g.kind!r} in one fused element")
            by_kind[g.kind] = g
        self.groups = list(groups)
        from flexrv.model.base import KernelGroup

        #: the groups whose records are their record_sources (live arrays the kernel fills); a group
        #: that overrides record() itself is left to its own evaluate for the outputs
        self.recorded = [g for g in self.groups if type(g).record is KernelGroup.record]
        #: the model's groups outside this element (own elements; added by generalized_forces)
        self.others = [g for g in model.groups if g not in self.groups]
        names = [name for name in model.members if any(name in g.members for g in groups)]
        self.member_names = names
        local, pos = {}, 0
        for name in names:
            local[name] = pos
            pos += model.members[name].n
        self.n = pos
        self.index = (
            np.concatenate(
                [np.arange(model.members[m].offset, model.members[m].offset + model.members[m].n) for m in names]
            ).astype(np.int64)
            if names
            else np.zeros(0, np.int64)
        )
        self.is_full = self.n == model.n and np.array_equal(self.index, np.arange(model.n))
        unknown = [g.name for g in groups if spec_of(g) is None]
        if unknown:
            raise ValueError(f"groups {unknown} are not registered compiled elements (flexrv.model.core.registry)")
        #: the present elements in the registry's (= call) order: (group, positions of its local
        #: coordinates in the element's vector)
        self.slots = [
            (
                g,
                np.concatenate([np.arange(local[m], local[m] + model.members[m].n) for m in g.members]).astype(
                    np.int64
                ),
            )
            for g in (by_kind[k] for k in ELEMENTS if k in by_kind)
        ]
        #: the generated compiled functions of these elements (flexrv.model.core.registry)
        self.kernel, self.history_kernel, self.integrate_kernel = fused_functions([spec_of(g) for g, _ in self.slots])
        self.packs = self._packs(history=False)
        #: (group, its pack's live time-input array) of the elements with time inputs
        self.timed = [(g, getattr(p, g.time_field)) for (g, _), p in zip(self.slots, self.packs) if g.time_field]
        #: the live failure counters of the elements' inner solves: (group, counter)
        self.counters = [(g, c) for (g, _), p in zip(self.slots, self.packs) if (c := g.failure_counter(p)) is not None]
        self.f = np.zeros(self.n)
        self.jq, self.jv = np.zeros((self.n, self.n)), np.zeros((self.n, self.n))
        self.stats = [0, 0]
        #: compiled entry point of fused_kernel for this element's argument types (set on the first call)
        self._entry = None
        #: (t, q, v) of the last solver call (residual / jacobian), the state the groups' live records
        #: belong to (HistoryRecorder), or None. References, not copies: Exudyn passes every call fresh
        #: arrays it never reuses (checked: 127 calls, none changed afterwards)
        self.memo = None
        #: jq, jv hold the Jacobians of the call that ``memo`` describes
        self._jac_ready = False
        #: time of the last residual call
        self._t_last = None
        #: the solver updates its Jacobian at the start of every step (set by the simulation from its
        #: Newton settings): the first residual call of a step fills the Jacobians too (:meth:`residual`)
        self.jacobian_each_step = False
        #: (integrator state, its blocks or None) of the compiled integrator that drives this element
        #: (:meth:`drive_with`), or None
        self._driver = None
        #: the record buffers of a single evaluation through the driver (:meth:`_call_rows`)
        self._eval_records = None

    def drive_with(self, state, blocks) -> None:
        """A compiled integrator with the generalized-alpha state ``state`` (``blocks``: as it
        passes them to ``fused_integrate``) drives this element: the evaluations from Python
        (:meth:`full`, :meth:`history`: the run's initial accelerations, the outputs' history
        pass) then go through that same compiled function (its ``ROWS`` mode, the same
        argument types), so that the run compiles one entry point instead of three (each
        entry point generates the machine code of every element's kernel again)."""
        self._driver = (state, blocks)

    def _packs(self, history: bool) -> list:
        """The kernel arguments of every slot (the solver's, or fresh ones for a time history)."""
        return [g.pack(idx, history=history) for g, idx in self.slots]

    def history(self, t, q, v) -> dict:
        """Per-sample records of every group of this element over a time history t (T,),
        q, v (T, n) on the element's coordinates: {group: {key: (T, *shape)}}, as the
        groups' own evaluate of the history would stack them (the same kernels on the
        same inputs, bit for bit: fresh history packs, the vectorised time inputs), in
        one compiled loop (the generated ``fused_history``)."""
        t = np.ascontiguousarray(t, dtype=float)
        nt = len(t)
        packs = self._packs(history=True)
        tables = self.time_tables(t)  # the time inputs at every sample, per element with time inputs
        srcs, dsts, keys = [], [], []
        for g, key, a in self.record_entries():
            srcs.append(a.reshape(-1))
            dsts.append(np.empty((nt, a.size)))
            keys.append((g, key, a.shape))
        f = np.zeros(self.n)
        counters = [(g, g.failure_counter(p)) for (g, _), p in zip(self.slots, packs)]
        before = [None if c is None else int(c[0]) for _, c in counters]
        if nt and srcs:
            q, v = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float)
            if self._driver is not None:
                ctrs = tuple(c for _, c in counters if c is not None)
                self._rows(ROWS, t, q, v, tables, f, packs, ctrs, tuple(srcs), tuple(dsts))
            else:
                self.history_kernel(q, v, *tables, f, self.jq, self.jv, *packs, tuple(srcs), tuple(dsts))
        for g, _ in self.timed:
            g._time_last = None  # the history pass overwrote the live time inputs
        for (g, c), b in zip(counters, before):
            if c is not None and int(c[0]) != b:
                from flexrv.errors import ConvergenceError

                raise ConvergenceError(g.failure_message)
        out = {g: {} for g in self.recorded}
        for (g, key, shape), d in zip(keys, dsts):
            out[g][key] = d.reshape((nt,) + shape)
        return out

    def time_tables(self, times: np.ndarray) -> list:
        """The time inputs of the elements with time inputs at ``times`` (T,): per element a
        (T, size) table, row i at times[i]; writable, C-contiguous float64 (one argument type of
        the compiled functions: a read-only view would be another type, compiled again)."""
        out = []
        for g, array in self.timed:
            rows = np.broadcast_to(g.time_inputs_many(times), (len(times), array.size))
            out.append(np.require(rows, dtype=np.float64, requirements=("C", "W")))
        return out

    def _rows(self, mode, t, qs, vs, tables, f, packs, ctrs, src, dst) -> None:
        """The generated ``fused_integrate`` in ``mode`` ROWS / ROWS_JAC over the states ``qs``,
        ``vs`` (T, n) at times ``t`` with the time-input ``tables`` (the argument types of the
        driving integrator's calls: :meth:`drive_with`)."""
        state, blocks = self._driver
        nt = len(qs)
        self.integrate_kernel(
            mode,
            state,
            blocks,
            t,
            0.0,
            *tables,
            f,
            self.jq,
            self.jv,
            *packs,
            ctrs or (np.zeros(1, np.int64),),
            src,
            dst,
            np.zeros(3, np.int64),
            np.zeros(2),
            np.zeros(nt),
            qs,
            vs,
            np.zeros(nt, dtype=bool),
        )

    def _call_rows(self, t, q, v, jac) -> None:
        """One evaluation at (t, q, v) through the driving integrator's compiled function
        (:meth:`drive_with`), on the live packs; f, jq, jv and the live records as :meth:`_call`."""
        for g, array in self.timed:
            g.set_time(t, array)
        tables = [array.reshape(1, -1) for _, array in self.timed]  # (row 0: the live time inputs themselves)
        if self._eval_records is None:
            srcs = tuple(a.reshape(-1) for _, _, a in self.record_entries()) or (np.zeros(0),)
            self._eval_records = (srcs, tuple(np.empty((1, a.size)) for a in srcs))
        before = [c[0] for _, c in self.counters]
        self._rows(
            ROWS_JAC if jac else ROWS,
            np.array([float(t)]),
            np.ascontiguousarray(q, dtype=float).reshape(1, -1),
            np.ascontiguousarray(v, dtype=float).reshape(1, -1),
            tables,
            self.f,
            self.packs,
            tuple(c for _, c in self.counters),
            *self._eval_records,
        )
        for (g, c), b in zip(self.counters, before):
            if c[0] != b:
                self._failed(g)

    def _call(self, t, q, v, jac):
        for g, array in self.timed:  # (the groups cache their time inputs per time)
            g.set_time(t, array)
        counters = self.counters
        if len(counters) == 1:  # (the usual case, the pins: no list per call)
            ctr = counters[0][1]
            before = ctr[0]
        else:
            ctr, before = None, [c[0] for _, c in counters]
        entry = self._entry
        if entry is not None and _f8c(q) and _f8c(v):
            entry(q, v, self.f, self.jq, self.jv, jac, *self.packs)
        else:
            args = (q, v, self.f, self.jq, self.jv, bool(jac), *self.packs)
            self.kernel(*args)
            if entry is None:
                self._entry = _entry_point(self.kernel, args)
        if ctr is not None:
            if ctr[0] != before:
                self._failed(counters[0][0])
        elif counters:
            for (g, c), b in zip(counters, before):
                if c[0] != b:
                    self._failed(g)

    @staticmethod
    def _failed(group):
        from flexrv.errors import ConvergenceError

        raise ConvergenceError(group.failure_message)

    def record_entries(self) -> list:
        """(group, key, live array) of every per-contact record of this element's groups, in order."""
        out = []
        for g in self.recorded:
            for key, a in g.record_sources().items():
                if a.dtype != np.float64 or not a.flags.c_contiguous:
                    raise TypeError(f"{g.name}.record_sources()[{key!r}] must be float64 and C-contiguous")
                out.append((g, key, a))
        return out

    def residual(self, t, q, v) -> np.ndarray:
        """Generalized force on the element's coordinates (a view, overwritten by the next call).

        With :attr:`jacobian_each_step` the first call at a new time (the solver's predictor
        of a new step) also fills the Jacobians: a solver that updates its
        Jacobian every step asks for them next, at that same state (the rigid model's calls per
        step are R J R [R ...]; every Jacobian call of a 0.1 s rv40e / rv221 run, 1266 / 1119,
        came at the previous call's state), and :meth:`jacobian` then returns them without a
        second kernel call (bench_rigid: rv40e kernel 100-103 -> 90 us per step)."""
        self.stats[0] += 1
        self.memo = None  # until the call has filled the records
        first = self.jacobian_each_step and t != self._t_last
        self._t_last = t
        self._jac_ready = False
        self._call(t, q, v, first)
        self.memo = (t, q, v)
        self._jac_ready = first
        return self.f

    def jacobian(self, t, q, v):
        """(dF/dq, dF/dv) on the element's coordinates (views, overwritten by the next call):
        those the last residual call computed if it was at exactly (t, q, v), else a kernel call."""
        self.stats[1] += 1
        m = self.memo
        if (
            self._jac_ready
            and m is not None
            and m[0] == t
            and m[1].tobytes() == q.tobytes()
            and m[2].tobytes() == v.tobytes()
        ):
            return self.jq, self.jv
        self.memo = None  # until the call has filled the records
        self._call(t, q, v, True)
        self.memo = (t, q, v)
        self._jac_ready = True
        return self.jq, self.jv

    def full(self, t, q, v, jacobian: bool = True, velocity: bool = True):
        """Force and Jacobians on the MODEL's full vector (copies), for static solvers; dF/dv is
        None unless ``jacobian`` and ``velocity`` (a static solver never reads it)."""
        n_model = len(q)
        self.memo, self._jac_ready = None, False  # the caller may change its arrays afterwards
        call = self._call if self._driver is None else self._call_rows
        if self.is_full:
            call(float(t), q, v, bool(jacobian))
            jv = self.jv.copy() if jacobian and velocity else None
            return self.f.copy(), (self.jq.copy() if jacobian else None), jv
        ix = self.index
        call(float(t), np.ascontiguousarray(q[ix]), np.ascontiguousarray(v[ix]), bool(jacobian))
        f = np.zeros(n_model)
        f[ix] = self.f
        dq = dv = None
        if jacobian:
            dq, dv = np.zeros((n_model, n_model)), np.zeros((n_model, n_model))
            dq[np.ix_(ix, ix)] = self.jq
            dv[np.ix_(ix, ix)] = self.jv
        return f, dq, dv

    def add_to(self, mbs, nodes: list[int]) -> int:
        """Add the ONE ObjectGenericODE2 over ``nodes`` (the members' nodes in
        :attr:`member_names` order) with force and Jacobian user functions."""
        from exudyn.itemInterface import ObjectGenericODE2

        def force_fn(mbs_, t, item, q, q_t):
            return self.residual(t, exudyn_vector(q), exudyn_vector(q_t))

        out, tmp = np.empty((self.n, self.n)), np.empty((self.n, self.n))

        def jac_fn(mbs_, t, item, q, q_t, f_q, f_v):
            dq, dv = self.jacobian(t, exudyn_vector(q), exudyn_vector(q_t))
            np.multiply(dq, -f_q, out=out)  # -(f_q dq + f_v dv) without temporaries (Exudyn copies it)
            np.multiply(dv, f_v, out=tmp)
            return np.subtract(out, tmp, out=out)

        return mbs.AddObject(
            ObjectGenericODE2(nodeNumbers=nodes, forceUserFunction=force_fn, jacobianUserFunction=jac_fn)
        )


class HistoryRecorder:
    """The per-contact records at every recorded sample of a run, taken from what the
    integrator computed, for every recording element of a model: the fused
    element (:class:`FusedForces`) and the groups' own (``recorded_elements()``, e.g.
    the bearing rows of :class:`flexrv.model.flexible_bearing.BallBearingGroup`). At
    each recorded state an element's last call (its ``memo`` = (t, q, v) on its own
    coordinates) is, in Exudyn's Newton iteration, the residual at the accepted
    state; if (t, q, v) are exactly those of the record, the element's live arrays
    are copied into row k (one compiled call) and the row is ``valid`` for that
    element, else it is left to the outputs' history pass
    (:meth:`FusedForces.history`, the groups' ``recorded_outputs``). Measured
    (rv40e / rv221, 0.2 s, fused element): 1999 of 2001 and 1997 of 2001 records
    matched (the others: segment starts and repeated steps).

    Same numbers as the history pass to the solvers' own tolerances (the crank supports'
    inner solve, the closest points', the condensed rings' and the films' warm starts), with one
    difference: a pin the solver
    proved open (:func:`flexrv.model.pins.pin_kernel`'s bound > 0: no force, no Jacobian)
    keeps that positive lower bound of its gap in ``pin_gap`` instead of the exact gap;
    every pin within reach of contact, every force and every other record is the exact
    evaluation at the recorded state."""

    def __init__(self, model, n_out: int):
        #: per element: (element, index of its coordinates in the model's vector (empty: all),
        #: [(group, key, shape)], flat live arrays, history buffers (n_out, size))
        self.sources = []
        elements = (
            [] if model.fused is None else [(model.fused, model.fused.member_names, model.fused.record_entries())]
        )
        for g in model.groups:
            elements += g.recorded_elements()
        for element, members, entries in elements:
            if not entries:
                continue
            for g, key, a in entries:
                if a.dtype != np.float64 or not a.flags.c_contiguous:
                    raise TypeError(f"{g.name} record {key!r} must be float64 and C-contiguous")
            index = np.concatenate(
                [np.arange(model.members[m].offset, model.members[m].offset + model.members[m].n) for m in members]
            ).astype(np.int64)
            if np.array_equal(index, np.arange(model.n)):
                index = np.zeros(0, np.int64)  # all of the model's coordinates, in order
            src = tuple(a.reshape(-1) for _, _, a in entries)
            self.sources.append(
                (
                    element,
                    index,
                    [(g, key, a.shape) for g, key, a in entries],
                    src,
                    tuple(np.empty((n_out, a.size)) for a in src),
                )
            )
        self.valid = np.zeros((len(self.sources), n_out), dtype=bool)
        #: compiled entry point of copy_records_if_same per element (set on the first call)
        self._entry = [None] * len(self.sources)

    def store(self, k: int, t: float, q: np.ndarray, v: np.ndarray) -> None:
        """Record row k from each element's last call if it was at (t, q, v) (full model vectors)."""
        for i, (element, index, _, src, dst) in enumerate(self.sources):
            memo = element.memo
            ok = memo is not None and memo[0] == t
            if ok:  # one compiled call: compare (q, v) exactly, copy the records
                args = (memo[1], q, memo[2], v, index, src, dst, k)
                entry = self._entry[i]
                if entry is None:
                    ok = copy_records_if_same(*args)
                    self._entry[i] = _entry_point(copy_records_if_same, args)
                elif _f8c(args[0]) and _f8c(q) and _f8c(args[2]) and _f8c(v):
                    ok = entry(*args)  # the compiled function directly: no typing of the record arrays
                else:
                    ok = copy_records_if_same(*args)
            self.valid[i, k] = ok

    def forget(self) -> None:
        """The elements' last calls no longer match their records (the groups were reset)."""
        for element, *_ in self.sources:
            element.memo = None

    def fill(self, k0: int, arrays: list, valid: np.ndarray) -> None:
        """Rows 0..k0-1 from a checkpoint (:meth:`arrays` of the interrupted run)."""
        dst = [d for *_, ds in self.sources for d in ds]
        valid = np.asarray(valid)
        if (
            len(arrays) != len(dst)
            or any(a.shape[1:] != d.shape[1:] for a, d in zip(arrays, dst))
            or valid.ndim != 2
            or valid.shape[0] != len(self.sources)
        ):
            return  # another model's records: those rows are left to the history pass
        for a, d in zip(arrays, dst):
            d[:k0] = a[:k0]
        self.valid[:, :k0] = valid[:, :k0]

    def arrays(self, k: int) -> tuple[list, np.ndarray]:
        """(buffers, valid (elements, k)) of rows 0..k-1, for a checkpoint."""
        return [d[:k] for *_, ds in self.sources for d in ds], self.valid[:, :k]

    def records(self, k: int) -> dict:
        """Rows 0..k-1: {"valid": {group: (k,)}, "data": {group: {key: (k, *shape)}}} for
        :func:`flexrv.model.outputs.group_outputs` (a group's mask: its element's)."""
        data: dict = {}
        valid: dict = {}
        for i, (_, _, entries, _, dst) in enumerate(self.sources):
            for (g, key, shape), d in zip(entries, dst):
                data.setdefault(g, {})[key] = d[:k].reshape((k,) + shape)
                valid[g] = self.valid[i, :k]
        return {"valid": valid, "data": data}
