"""Rigid-model main bearing: the carrier on a linear spring-damper in five DOF
(radial x, y; axial z; tilting rx, ry), the carrier's rotation free.

A constant-matrix ``ObjectGenericODE2`` (no Python call per step). The
flexible-bearing model replaces this group by the ball-resolved bearing of
:mod:`flexrv.model.flexible_bearing` under the same output names.
"""

from __future__ import annotations

import numpy as np

from flexrv.model.base import ForceGroup, Output

#: carrier coordinate order (see :mod:`flexrv.model.parameters`)
CARRIER_COORDS = ("x", "y", "theta", "z", "rx", "ry")


class RigidMainBearing(ForceGroup):
    """Linear 5-DOF main-bearing element on the carrier."""

    name = "main_bearing"
    members = ("carrier",)

    def __init__(self, params):
        k5, c5 = params.main_bearing_stiffness, params.main_bearing_damping
        self.k = np.diag([k5[0], k5[1], 0.0, k5[2], k5[3], k5[4]])
        self.c = np.diag([c5[0], c5[1], 0.0, c5[2], c5[3], c5[4]])

    def evaluate(self, t, q, v, want_outputs: bool = False):
        f = -(q @ self.k.T) - (v @ self.c.T)
        out = None
        if want_outputs:
            out = {"main_bearing_radial_force": Output(np.hypot(f[..., 0], f[..., 1]), ("time",), "N",
                                                       "radial reaction of the main bearing on the carrier"),
                   "main_bearing_axial_force": Output(f[..., 3], ("time",), "N", "axial reaction on the carrier"),
                   "main_bearing_tilting_moment": Output(np.hypot(f[..., 4], f[..., 5]), ("time",), "N m",
                                                         "tilting reaction moment on the carrier")}
        return f, out

    def jacobian(self, t, q, v):
        return -self.k, -self.c

    def add_to(self, mbs, nodes, sizes):
        from exudyn.itemInterface import ObjectGenericODE2

        return mbs.AddObject(ObjectGenericODE2(nodeNumbers=nodes, massMatrix=np.zeros((6, 6)),
                                               stiffnessMatrix=self.k, dampingMatrix=self.c))
