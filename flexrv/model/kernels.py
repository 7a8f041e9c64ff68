"""One compiled residual and Jacobian for the rigid reducer's force groups (issue 15).

:class:`FusedForces` evaluates every :class:`~flexrv.model.base.KernelGroup` of a
model — gear stage, crank supports, needle bearings, pins, rigid main bearing,
loads — in ONE call of :func:`fused_kernel`, a numba function that calls the
groups' own compiled kernels (the physics stays in the groups' modules: one
formula, one executor) on the model's coordinate vector. It backs both the single
Exudyn ``ObjectGenericODE2`` of these groups (force and Jacobian user functions,
:meth:`FusedForces.add_to`) and :meth:`flexrv.model.assembled.AssembledModel.generalized_forces`.
Groups of other kinds (ball bearing, flexible crank) keep their own elements.

Python work per call: Exudyn's argument lists to arrays (``np.asarray``), the
drive angle and load vector at t (cached per time), one dispatch of the compiled
function (about 8 us of unboxing the ~45 pack arrays; the compiled work is 6-9 us
on rv40e/rv221). Measured in benchmarks/bench_rigid.py.

Numba's on-disk cache (``cache=True``) keys each function on its OWN source file
only: after editing a kernel that other modules' compiled functions call (e.g.
:func:`flexrv.geometry.cycloid._foot_point` from the pins kernel, or any group
kernel from :func:`fused_kernel`), delete the ``__pycache__/*.nbi``/``*.nbc``
files, or the callers keep the old machine code.
"""

from __future__ import annotations

import contextlib
import os

import numpy as np
from numba import njit

from flexrv.model.cranks_discs import CrankSupports, NeedleBearings, crank_support_kernel, needle_kernel
from flexrv.model.gear_stage import GearMeshes, gear_stage_kernel
from flexrv.model.loads import OutputLoads, loads_kernel
from flexrv.model.main_bearing_rigid import RigidMainBearing, main_bearing_kernel
from flexrv.model.pins import PinContacts, pin_body_kernel

#: slots of the fused kernel, in call order, and the group class of each
KINDS = (("gear", GearMeshes), ("supports", CrankSupports), ("needles", NeedleBearings), ("pins", PinContacts),
         ("main_bearing", RigidMainBearing), ("loads", OutputLoads))


@njit(cache=True)
def fused_kernel(q, v, f, jq, jv, jac, ts, ws, gear, supports, needles, pins, main_bearing, loads):
    """All kernel groups at one state: f = sum of their generalized forces and, if
    ``jac``, jq = dF/dq, jv = dF/dv (all zeroed first). ``ts``, ``ws``: sun angle
    and speed; each remaining argument is one group's pack (an absent group has an
    empty pack and adds nothing)."""
    f[:] = 0.0
    if jac:
        jq[:, :] = 0.0
        jv[:, :] = 0.0
    gear_stage_kernel(ts, ws, q, v, f, jq, jv, jac, gear)
    crank_support_kernel(q, v, f, jq, jv, jac, supports)
    needle_kernel(q, v, f, jq, jv, jac, needles)
    pin_body_kernel(q, v, f, jq, jv, jac, pins)
    main_bearing_kernel(q, v, f, jq, jv, jac, main_bearing)
    loads_kernel(q, v, f, jq, jv, jac, loads)


_F8 = np.dtype(np.float64)


def _entry_point(args):
    """The compiled function of :func:`fused_kernel` for the types of ``args``, to
    be called directly (None if not found). Skips numba's dispatch, i.e. typing
    the ~50 arguments on every call (~1.7 us of a ~9 us call, measured); valid
    while the arguments keep their types, which :meth:`FusedForces._call` checks
    for the only ones that change (q, v: float64, C-contiguous; the packs are
    fixed at construction, jac / ts / ws are converted to bool / float)."""
    from numba import typeof

    cres = fused_kernel.overloads.get(tuple(typeof(a) for a in args))
    return None if cres is None else cres.entry_point


def blas_threads() -> int | None:
    """BLAS threads inside simulations: FLEXRV_BLAS_THREADS if set (``0`` or empty:
    leave the library default), else 1. OpenBLAS's default threads spin on a
    loaded machine (issue 15: 1.9-2.4x wall on 2 cores)."""
    env = os.environ.get("FLEXRV_BLAS_THREADS")
    if env is None:
        return 1
    env = env.strip()
    return int(env) if env and int(env) > 0 else None


@contextlib.contextmanager
def single_thread_blas():
    """Context manager limiting BLAS to :func:`blas_threads` threads (threadpoolctl)."""
    n = blas_threads()
    if n is None:
        yield
        return
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=n, user_api="blas"):
        yield


class FusedForces:
    """The kernel groups of a model as one compiled residual (see module docstring).

    The element's coordinates are those of the members the kernel groups touch, in
    the model's member order; :attr:`index` maps them into the model's vector."""

    def __init__(self, model, groups=None):
        if groups is None:
            groups = [g for g in model.groups if type(g) in dict((c, k) for k, c in KINDS)]
        by_kind = {}
        for g in groups:
            if g.kind in by_kind:
                raise ValueError(f"two kernel groups of kind {g.kind!r} in one fused element")
            by_kind[g.kind] = g
        self.groups = list(groups)
        #: the model's groups outside this element (own elements; added by generalized_forces)
        self.others = [g for g in model.groups if g not in self.groups]
        names = [name for name in model.members if any(name in g.members for g in groups)]
        self.member_names = names
        local, pos = {}, 0
        for name in names:
            local[name] = pos
            pos += model.members[name].n
        self.n = pos
        self.index = np.concatenate([np.arange(model.members[m].offset, model.members[m].offset + model.members[m].n)
                                     for m in names]).astype(np.int64) if names else np.zeros(0, np.int64)
        self.is_full = self.n == model.n and np.array_equal(self.index, np.arange(model.n))
        self.packs = []
        for kind, cls in KINDS:
            g = by_kind.get(kind)
            if g is None:
                self.packs.append(cls.empty_pack())
            else:
                idx = np.concatenate([np.arange(local[m], local[m] + model.members[m].n) for m in g.members])
                self.packs.append(g.pack(idx.astype(np.int64)))
        self.gear, self.loads = by_kind.get("gear"), by_kind.get("loads")
        self.pins = by_kind.get("pins")
        self.f = np.zeros(self.n)
        self.jq, self.jv = np.zeros((self.n, self.n)), np.zeros((self.n, self.n))
        self.stats = [0, 0]
        #: compiled entry point of fused_kernel for this element's argument types (set on the first call)
        self._entry = None

    def _call(self, t, q, v, jac):
        ts, ws = self.gear.time_inputs(t) if self.gear is not None else (0.0, 0.0)
        if self.loads is not None:
            self.loads.load[:] = self.loads.time_inputs(t)
        before = self.pins.ctr[2] if self.pins is not None else 0
        args = (q, v, self.f, self.jq, self.jv, bool(jac), float(ts), float(ws), *self.packs)
        entry = self._entry
        if entry is not None and q.dtype is _F8 and v.dtype is _F8 and q.flags.c_contiguous and v.flags.c_contiguous:
            entry(*args)
        else:
            fused_kernel(*args)
            if entry is None:
                self._entry = _entry_point(args)
        if self.pins is not None and self.pins.ctr[2] != before:
            from flexrv.errors import ConvergenceError

            raise ConvergenceError("pin gap: closest-point iteration did not converge")

    def residual(self, t, q, v) -> np.ndarray:
        """Generalized force on the element's coordinates (a view, overwritten by the next call)."""
        self.stats[0] += 1
        self._call(t, q, v, False)
        return self.f

    def jacobian(self, t, q, v):
        """(dF/dq, dF/dv) on the element's coordinates (views, overwritten by the next call)."""
        self.stats[1] += 1
        self._call(t, q, v, True)
        return self.jq, self.jv

    def full(self, t, q, v, jacobian: bool = True):
        """Force and Jacobians on the MODEL's full vector (copies), for static solvers."""
        n_model = len(q)
        if self.is_full:
            self._call(float(t), q, v, jacobian)
            return self.f.copy(), (self.jq.copy() if jacobian else None), (self.jv.copy() if jacobian else None)
        ix = self.index
        self._call(float(t), np.ascontiguousarray(q[ix]), np.ascontiguousarray(v[ix]), jacobian)
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
            return self.residual(t, np.asarray(q), np.asarray(q_t))

        def jac_fn(mbs_, t, item, q, q_t, f_q, f_v):
            dq, dv = self.jacobian(t, np.asarray(q), np.asarray(q_t))
            return -(f_q * dq + f_v * dv)

        return mbs.AddObject(ObjectGenericODE2(nodeNumbers=nodes, forceUserFunction=force_fn,
                                               jacobianUserFunction=jac_fn))
