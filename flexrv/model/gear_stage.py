"""First stage: sun–planet involute meshes along the line of action.

Mesh deflection of planet j (lumped-parameter model along the line of action,
Kahraman 1994; Lin & Parker 1999), with the sun centre fixed on the axis and its
angle prescribed by the drive:

    delta_j = r_bs theta_s + r_bp phi_j - (r_bs + r_bp)(beta_j - beta_j0)
              - sin(alpha_w) (a_j - a_w),

beta_j, a_j the polar angle and radius of the crank (= planet) centre, phi_j the
absolute planet angle, r_b base radii, alpha_w the working pressure angle. It is
zero for the ideal rolling motion (r_bs (theta_s - beta) = -r_bp (phi - beta))
and positive when the drive flanks are compressed. With the normal backlash
b_n = j_t cos(alpha_w) the force is

    F = k(xi) delta + c ddelta/dt              for delta > 0   (drive flank, F >= 0)
    F = k(xi) (delta + b_n) + c ddelta/dt      for delta < -b_n (coast flank, F <= 0)
    F = 0                                      otherwise,

with the time-varying stiffness k(xi) of :func:`flexrv.analysis.mesh_stiffness.
time_varying_mesh_stiffness` at the mesh phase xi_j = z_s (theta_s - beta_j)/2pi
- z_s beta_j0/2pi (carrier-frame kinematics: one base pitch per sun tooth passing
the planet), and the mesh damping c12 of
:func:`flexrv.analysis.mesh_stiffness.involute_stage`. The generalized forces
are Q = -F d(delta)/dq (exact, the deflection being a function of the
coordinates). Analytic Jacobian: -dF/d(delta) g g^T and -c g g^T (g = d delta/dq;
the curvature terms of beta(x, y) are dropped, modified Newton converges on the
exact residual).
"""

from __future__ import annotations

import numpy as np

from flexrv.model.base import ForceGroup, Output
from flexrv.units import TWO_PI



class GearMeshes(ForceGroup):
    """All sun–planet meshes in one element (members: carrier, crank0..N-1)."""

    name = "gear_stage"
    analytic_jacobian = True

    def __init__(self, params, stage, input_angle, input_speed, ramp_fraction: float = 0.2):
        from flexrv.analysis.mesh_stiffness import time_varying_mesh_stiffness

        p = params
        self.n = p.n_cranks
        self.members = ("carrier",) + tuple(f"crank{j}" for j in range(self.n))
        self.rbs, self.rbp = p.base_radius_sun, p.base_radius_planet
        self.sw = np.sin(p.working_pressure_angle)
        self.aw = p.center_distance
        self.beta0 = p.crank_angles
        self.zs = p.z_s
        self.bn = p.normal_backlash
        self.k_single = stage.k_single
        self.eps = stage.eps_alpha
        w1 = self.eps - 1.0
        self.ramp = ramp_fraction * min(w1, 1.0 - w1)
        self.c = stage.c12
        self.theta_s, self.omega_s = input_angle, input_speed
        self._k_of = time_varying_mesh_stiffness
        self._drive_cache = None

    def _drive(self, t):
        """Sun angle and speed (..., 1) at t; cached for a scalar t (all Newton
        iterations of a step evaluate the same time)."""
        if np.ndim(t) == 0:
            c = self._drive_cache
            if c is not None and c[0] == t:
                return c[1], c[2]
        ts = np.asarray(self.theta_s(t), dtype=float)[..., None]
        ws = np.asarray(self.omega_s(t), dtype=float)[..., None]
        if np.ndim(t) == 0:
            self._drive_cache = (float(t), ts, ws)
        return ts, ws

    def reset(self) -> None:
        self._drive_cache = None
        super().reset()

    def _kin(self, t, q, v):
        n = self.n
        x, y, phi = q[..., 6::3], q[..., 7::3], q[..., 8::3]
        vx, vy, vphi = v[..., 6::3], v[..., 7::3], v[..., 8::3]
        th_c = q[..., 2:3]
        a2 = x * x + y * y
        a = np.sqrt(a2)
        rel = np.arctan2(y, x) - th_c - self.beta0
        rel -= TWO_PI * np.rint(rel / TWO_PI)
        beta = th_c + self.beta0 + rel
        ts, ws = self._drive(t)
        r = self.rbs + self.rbp
        delta = self.rbs * ts + self.rbp * phi - r * (beta - self.beta0) - self.sw * (a - self.aw)
        gx = r * y / a2 - self.sw * x / a
        gy = -r * x / a2 - self.sw * y / a
        ddelta = self.rbs * ws + gx * vx + gy * vy + self.rbp * vphi
        phase = (self.zs / TWO_PI) * (ts - beta - self.beta0)
        k = self._k_of(phase, self.k_single, self.eps, self.ramp)
        drive = delta > 0.0
        coast = delta < -self.bn
        f_drive = np.maximum(k * delta + self.c * ddelta, 0.0)
        f_coast = np.minimum(k * (delta + self.bn) + self.c * ddelta, 0.0)
        force = np.where(drive, f_drive, np.where(coast, f_coast, 0.0))
        active = (drive & (f_drive > 0)) | (coast & (f_coast < 0))
        return delta, ddelta, force, (gx, gy), k, active

    def evaluate(self, t, q, v, want_outputs: bool = False):
        delta, ddelta, force, (gx, gy), k, active = self._kin(t, q, v)
        gen = np.zeros(q.shape)
        gen[..., 6::3] = -force * gx
        gen[..., 7::3] = -force * gy
        gen[..., 8::3] = -force * self.rbp
        out = None
        if want_outputs:
            out = {
                "mesh_force": Output(force, ("time", "planet"), "N", "sun-planet mesh force along the line of action"),
                "mesh_deflection": Output(delta, ("time", "planet"), "m", "mesh deflection along the line of action"),
                "mesh_stiffness": Output(k, ("time", "planet"), "N/m", "time-varying mesh stiffness"),
                "sun_torque": Output(self.rbs * force.sum(axis=-1), ("time",), "N m", "torque of the meshes on the sun"),
            }
        return gen, out

    def jacobian(self, t, q, v):
        _, _, _, (gx, gy), k, active = self._kin(t, q, v)
        grad = np.stack([gx, gy, np.full_like(gx, self.rbp)], axis=-1)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        for j in range(self.n):
            if not active[j]:
                continue
            s = slice(6 + 3 * j, 9 + 3 * j)
            gg = np.outer(grad[j], grad[j])
            dq[s, s] = -k[j] * gg
            dv[s, s] = -self.c * gg
        return dq, dv
