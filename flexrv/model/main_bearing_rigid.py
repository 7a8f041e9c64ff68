"""Rigid-model main bearing: the carrier on a linear spring-damper in five DOF
(radial x, y; axial z; tilting rx, ry), the carrier's rotation free.

Diagonal stiffness and damping, f = -K q - C v: evaluated by
:func:`main_bearing_kernel` (numba) inside the model's fused element. The
flexible-bearing model replaces this group by the ball-resolved bearing of
:mod:`flexrv.model.flexible_bearing` under the same output names.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, pack_type
from flexrv.model.drive import DriveParameters

#: :func:`main_bearing_kernel`'s pack: the carrier's 6 indices, diagonal stiffness and damping, reaction
MainBearingPack = pack_type(
    "MainBearingPack",
    ("idx", (np.int64, 1)),
    ("k", (np.float64, 1)),
    ("c", (np.float64, 1)),
    ("force", (np.float64, 1)),
)

#: carrier coordinate order (see :mod:`flexrv.model.drive`)
CARRIER_COORDS = ("x", "y", "theta", "z", "rx", "ry")


@dataclass(frozen=True)
class RigidMainBearingParameters:
    """The rigid main bearing's diagonal stiffness and damping in x, y, z, rx, ry
    [N/m, N m/rad; N s/m, N m s/rad]. Built by :func:`rigid_main_bearing_parameters`."""

    stiffness: np.ndarray  #: (5,)
    damping: np.ndarray  #: (5,)


def rigid_main_bearing_parameters(reducer, drive: DriveParameters) -> RigidMainBearingParameters:
    """The design's radial and axial stiffness (``main_bearing.rigid_*``, estimates with
    provenance in the presets), tilting k_r (s/2)^2 with the row spacing s, and
    carrier-mode damping 2 zeta sqrt(k m) (m: the carrier's mass, or half its polar
    inertia for the tilts; the ball-resolved and flexible main-bearing models replace it)."""
    mb = reducer.main_bearing
    k_r = mb.rigid_radial_stiffness_N_per_m
    s = mb.row_spacing_mm * 1e-3
    k = np.array([k_r, k_r, mb.rigid_axial_stiffness_N_per_m, k_r * (s / 2) ** 2, k_r * (s / 2) ** 2])
    m = np.array([drive.carrier_mass] * 3 + [drive.carrier_inertia / 2] * 2)
    return RigidMainBearingParameters(stiffness=k, damping=2.0 * mb.rigid_damping_ratio * np.sqrt(k * m))


@njit(cache=True)
def main_bearing_kernel(q, v, f, jq, jv, jac, pack):
    """f[idx] -= K q + C v (diagonal K, C), force into out; Jacobians -K, -C."""
    idx, k, c, out = pack.idx, pack.k, pack.c, pack.force
    for i in range(idx.shape[0]):
        ii = idx[i]
        out[i] = -k[i] * q[ii] - c[i] * v[ii]
        f[ii] += out[i]
        if jac:
            jq[ii, ii] -= k[i]
            jv[ii, ii] -= c[i]


class RigidMainBearing(KernelGroup):
    """Linear 5-DOF main-bearing element on the carrier."""

    name = "main_bearing"
    kind = "main_bearing"
    summary_rows = (
        SummaryRow(
            "max_main_bearing_radial_force_N",
            "N",
            "largest radial main-bearing reaction",
            "main_bearing_radial_force",
            "max",
        ),
    )
    kernel = staticmethod(main_bearing_kernel)
    members = ("carrier",)
    parameters = staticmethod(rigid_main_bearing_parameters)

    def __init__(self, params: RigidMainBearingParameters):
        self.params = params
        k5, c5 = params.stiffness, params.damping
        self.kd = np.array([k5[0], k5[1], 0.0, k5[2], k5[3], k5[4]], dtype=float)
        self.cd = np.array([c5[0], c5[1], 0.0, c5[2], c5[3], c5[4]], dtype=float)
        self.k, self.c = np.diag(self.kd), np.diag(self.cd)
        self.force = np.zeros(6)

    def pack(self, idx, history=False):
        return MainBearingPack(idx, self.kd, self.cd, self.force)

    @staticmethod
    def empty_pack():
        return empty_pack(MainBearingPack)

    def record_sources(self):
        return {"f": self.force}

    def outputs(self, t, rec):
        f = rec["f"]
        return {
            "main_bearing_radial_force": Output(
                np.hypot(f[..., 0], f[..., 1]), ("time",), "N", "radial reaction of the main bearing on the carrier"
            ),
            "main_bearing_axial_force": Output(f[..., 3], ("time",), "N", "axial reaction on the carrier"),
            "main_bearing_tilting_moment": Output(
                np.hypot(f[..., 4], f[..., 5]), ("time",), "N m", "tilting reaction moment on the carrier"
            ),
        }
