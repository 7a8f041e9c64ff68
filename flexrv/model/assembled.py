"""The assembled model: members, force groups, drive and load, and the summed
generalized forces of all groups at one state (used by the Exudyn element of the
compiled groups and by the quasi-static solver). Above :mod:`flexrv.model.base`
and :mod:`flexrv.model.kernels` (it calls the fused kernel), below the factory."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from flexrv.model.base import ForceGroup, Member


@dataclass
class AssembledModel:
    """A model ready to simulate: Exudyn system, members, groups, drive."""

    name: str
    reducer: object
    params: object
    members: dict[str, Member]
    groups: list[ForceGroup]
    input_angle: Callable  #: theta_in(t) [rad], vectorised
    input_speed: Callable  #: omega_in(t) [rad/s]
    load_torque: Callable  #: T_load(t) [N m] acting against the output rotation
    mbs: object = None
    sc: object = None
    n: int = 0
    info: dict = field(default_factory=dict)
    #: the fused compiled element of the kernel groups (:class:`flexrv.model.kernels.FusedForces`)
    fused: object = None

    def slice(self, member: str) -> slice:
        m = self.members[member]
        return slice(m.offset, m.offset + m.n)

    def group_state(self, group: ForceGroup, q: np.ndarray) -> np.ndarray:
        """Local coordinates of ``group`` from full states (..., n_total)."""
        return np.concatenate([q[..., self.slice(name)] for name in group.members], axis=-1)

    @property
    def q0(self) -> np.ndarray:
        return np.concatenate([m.q0 for m in self.members.values()])

    def generalized_forces(self, t, q: np.ndarray, v: np.ndarray, jacobian: bool = True):
        """Sum of every group's generalized force at one state, and its Jacobians.

        Returns ``(f, dfdq, dfdv)`` with f of shape (n,) and the Jacobians (n, n)
        (``None`` if ``jacobian`` is False). The compiled groups run in ONE call of
        the fused kernel (:class:`flexrv.model.kernels.FusedForces`, the same as the
        Exudyn element); other groups (ball bearing, flexible crank) add their own
        evaluate/jacobian. Every call is an exact evaluation, so a static solver
        can iterate on it. BLAS is pinned to one thread
        (:func:`flexrv.model.kernels.single_thread_blas`) around the numpy work of
        the other groups.
        """
        from flexrv.model.kernels import FusedForces

        n = self.n
        fused = self.fused
        if fused is None:
            fused = self.fused = FusedForces(self)
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)
        f, dq, dv = fused.full(t, q, v, jacobian)
        others = fused.others
        if others:
            from flexrv.model.kernels import single_thread_blas

            with single_thread_blas():
                for g in others:
                    idx = group_index(
                        [self.members[m].offset for m in g.members], [self.members[m].n for m in g.members]
                    )
                    g.new_step()
                    qg, vg = q[idx], v[idx]
                    fg, _ = g.evaluate(t, qg, vg)
                    f[idx] += fg
                    if jacobian:
                        jq, jv = g.jacobian(t, qg, vg)
                        ix = np.ix_(np.arange(n)[idx], np.arange(n)[idx])
                        dq[ix] += jq
                        dv[ix] += jv
        return f, dq, dv


def group_index(offsets: list[int], sizes: list[int]):
    """Indices of a group's local vector in a state vector: a slice if the
    members are contiguous and in order, else an integer array."""
    idx = np.concatenate([np.arange(o, o + n) for o, n in zip(offsets, sizes)])
    if len(idx) and np.all(np.diff(idx) == 1):
        return slice(int(idx[0]), int(idx[-1]) + 1)
    return idx
