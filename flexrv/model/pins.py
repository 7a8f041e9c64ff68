"""Second stage: every pin–disc contact of every disc in one element.

For disc k with centre c_k and rotation psi_k, the housing-fixed pin centres P_i
are expressed in the disc frame and their exact signed gap g to the modified
profile is found by :func:`flexrv.geometry.cycloid.pin_gap` (closest point on the
pin-centre epitrochoid; warm-started from the previous evaluation). With the
housing-frame normal n (from the profile to the pin), the gap's derivatives are
(envelope theorem, the closest point being stationary)

    dg/dc_k = -n,   dg/dpsi_k = -(r x n)_z,   r = P_i - c_k,

so the gap rate is dg/dt = -n . (dc/dt + dpsi/dt z x r). The normal force is
the seeds' contact law on the signed gap (:func:`flexrv.contact.laws.impact_force`):
Hertz line contact Q = K delta^(10/9) (Palmgren, ``contact.pin_law =
"hertz_line"``, K from :func:`flexrv.contact.hertz.line_contact_stiffness` over
the disc width) or the impact law K delta^e, plus the damping ramp c_max
step(delta, 0, 0, d, 1). The generalized force on the disc is Q = F dg/dq (the
force -F n acts on the disc along the line through the pin centre), so
modification clearance, separation and the number of pins in mesh emerge from
the contact physics. The pins are rigidly fixed in the housing (their own
bending and the pin-housing contact are not modelled).
"""

from __future__ import annotations

import numpy as np

from flexrv.contact.laws import impact_force
from flexrv.errors import ConvergenceError
from flexrv.geometry.cycloid import pin_gap
from flexrv.model.base import ForceGroup, Output


class PinContacts(ForceGroup):
    """Pin–disc contacts (members: disc0..n_discs-1)."""

    name = "pins"
    analytic_jacobian = True

    def __init__(self, params, penetration_limit: float = 100e-6, restart_every: int = 500):
        p = params
        self.nd = p.n_discs
        self.members = tuple(f"disc{k}" for k in range(self.nd))
        self.pins = p.pins  # (z, 2)
        self.geo = dict(z_rp=p.z_rp, pin_circle_radius=p.pin_circle_radius, pin_radius=p.pin_radius,
                        eccentricity=p.eccentricity, d_radius=p.d_radius, d_pin_radius=p.d_pin_radius,
                        d_rotation=p.d_rotation)
        self.k, self.e = p.pin_k, p.pin_exponent
        self.c_max, self.depth = p.pin_c_max, p.contact_depth
        self.limit = penetration_limit
        self.restart_every = restart_every
        self.phi = None
        self.calls = 0
        self.exact_calls = 0
        self.min_gap = np.inf
        self._cache = None
        #: max coordinate change [m, rad] before the gap is re-evaluated exactly within a step
        self.relinearise = 1e-6

    def _exact(self, q, phi0=None):
        """Exact gaps, housing normals and arms r = P - c at the discs' pose q;
        returns (gap, grad, n, r, phi)."""
        lead = q.shape[:-1]
        qd = q.reshape(lead + (self.nd, 1, 3))
        psi = qd[..., 2]
        r = self.pins - qd[..., :2]  # (..., nd, z, 2) housing frame, from disc centre to pin
        c, s = np.cos(psi), np.sin(psi)
        local = np.stack([c * r[..., 0] + s * r[..., 1], -s * r[..., 0] + c * r[..., 1]], axis=-1)
        try:
            gap, n_loc, phi = pin_gap(local, phi0=phi0, **self.geo)
        except ConvergenceError:
            if phi0 is None:
                raise
            gap, n_loc, phi = pin_gap(local, phi0=None, **self.geo)  # multi-start from the polar angle
        n = np.stack([c * n_loc[..., 0] - s * n_loc[..., 1], s * n_loc[..., 0] + c * n_loc[..., 1]], axis=-1)
        rxn = r[..., 0] * n[..., 1] - r[..., 1] * n[..., 0]
        grad = np.stack([-n[..., 0], -n[..., 1], -rxn], axis=-1)  # (..., nd, z, 3)
        return gap, grad, n, r, phi

    def _history(self, q):
        """Exact evaluation over a time history (T, n), sample by sample with the
        closest-point parameter warm-started from the previous sample."""
        out = [np.empty(q.shape[:-1] + (self.nd, len(self.pins))), np.empty(q.shape[:-1] + (self.nd, len(self.pins), 3)),
               np.empty(q.shape[:-1] + (self.nd, len(self.pins), 2)), np.empty(q.shape[:-1] + (self.nd, len(self.pins), 2))]
        phi = None
        for i in range(q.shape[0]):
            gap, grad, n, r, phi = self._exact(q[i], phi0=phi)
            out[0][i], out[1][i], out[2][i], out[3][i] = gap, grad, n, r
        return tuple(out)

    def _contacts(self, q, v):
        if q.ndim == 1:
            # Within one time step Newton moves the discs by far less than the contact
            # curvature radii: the gap is taken to first order about the first
            # (exact) evaluation of the step, g = g0 + grad0 . (q - q0), error
            # O(|q - q0|^2 / rho) (< 2e-10 m within the 1e-6 re-evaluation threshold, rho > 3 mm).
            c = self._cache
            dqmax = np.inf if c is None else np.max(np.abs(q - c[0]))
            if c is None or dqmax > self.relinearise:
                self.calls += 1
                warm = self.phi if (self.phi is not None and self.calls % self.restart_every) else None
                gap, grad, n, r, self.phi = self._exact(q, warm)
                self._cache = (q.copy(), gap, grad, n, r)
                self.exact_calls += 1
            else:
                q0, gap0, grad, n, r = c
                gap = gap0 + np.einsum("dzk,dk->dz", grad, (q - q0).reshape(self.nd, 3))
            self.min_gap = float(gap.min())
        elif q.ndim == 2:
            gap, grad, n, r = self._history(q)
        else:
            gap, grad, n, r, _ = self._exact(q)
        vd = v.reshape(v.shape[:-1] + (self.nd, 1, 3))
        rate = np.einsum("...k,...k->...", grad, vd)
        f, dfg, dfr = impact_force(gap, rate, self.k, self.e, self.c_max, self.depth)
        return gap, f, dfg, dfr, grad, n, r

    def new_step(self):
        """Force an exact evaluation at the next call (called at each step start)."""
        self._cache = None

    def reset(self):
        """Drop the linearisation cache and the closest-point warm start."""
        self._cache = None
        self.phi = None
        self.min_gap = np.inf

    def evaluate(self, t, q, v, want_outputs: bool = False):
        gap, f, _, _, grad, n, r = self._contacts(q, v)
        gen = (f[..., None] * grad).sum(axis=-2).reshape(q.shape)
        out = None
        if want_outputs:
            dims = ("time", "disc", "pin")
            torque = -(f * (r[..., 0] * n[..., 1] - r[..., 1] * n[..., 0])).sum(axis=-1)
            out = {"pin_force": Output(f, dims, "N", "pin-disc contact force"),
                   "pin_gap": Output(gap, dims, "m", "signed pin-profile gap (negative = penetration)"),
                   "pins_in_contact": Output((f > 0).sum(axis=-1), ("time", "disc"), "1", "pins in contact per disc"),
                   "disc_pin_torque": Output(torque, ("time", "disc"), "N m",
                                             "torque of the pin forces on each disc about its centre"),
                   "housing_pin_torque": Output((f * (self.pins[:, 0] * n[..., 1] - self.pins[:, 1] * n[..., 0])).sum(axis=-1),
                                                ("time", "disc"), "N m",
                                                "torque of each disc's pin forces on the housing about the axis")}
        return gen, out

    def jacobian(self, t, q, v):
        gap, f, dfg, dfr, grad, _, _ = self._contacts(q, v)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        for k in range(self.nd):
            s = slice(3 * k, 3 * k + 3)
            g = grad[k]
            dq[s, s] = (g.T * dfg[k]) @ g
            dv[s, s] = (g.T * dfr[k]) @ g
        return dq, dv

    def check(self) -> str | None:
        if self.min_gap < -self.limit:
            return (f"pin-disc penetration {-self.min_gap * 1e6:.3g} um exceeds the physical limit "
                    f"{self.limit * 1e6:.3g} um")
        return None
