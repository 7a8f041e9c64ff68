"""Crankshafts in the carrier and the needle bearings between the cranks'
eccentrics and the cycloid discs.

Crank supports (group ``crank_supports``, members carrier + cranks): each crank
centre is tied to its bore in the carrier, h_j = c_c + Rot(theta_c) a_w
(cos beta_j0, sin beta_j0), by an isotropic linear spring-damper of the two
support bearings (k = 2 k_sb, c = 2 c_sb); the crank turns freely.

Needle bearings (group ``needle_bearings``, members cranks + discs): the journal
centre of crank j under disc k is E = p_j + e (sin chi, cos chi), chi = chi0_k -
phi_j (clockwise eccentric angle, :mod:`flexrv.geometry.cycloid` convention); the
hole centre is H = c_k + Rot(psi_k) h_kj. With d = E - H:

* ``empirical`` (seed 004): a radial power law on the eccentricity of the journal
  in its hole, delta = |d| - c_r, F = K delta^(10/9) along d/|d|. The constant
  follows from seed 004's empirical radial stiffness
  K_Hc = dF/d(delta) = C F^0.1 (see :func:`flexrv.analysis.torsional`); its
  integral is exactly a 10/9 power law, F = (0.9 C delta)^(10/9).
* ``rollers`` (seed 003): each of the Z rollers is a Hertz line contact pair
  (journal–roller and roller–hole in series, Palmgren Q = K delta^(10/9),
  :func:`flexrv.contact.hertz.line_contact_stiffness`) with the radial clearance:
  delta_i = d . e_i - c_r, e_i the roller direction at gamma_c + 2 pi i / Z. The
  cage angle follows epicyclic rolling, gamma_c = ((1 - g) phi_j + (1 + g) psi_k)/2,
  g = D/d_m (Harris & Kotzalas 2007, ch. 8). Rollers are massless (their
  inertia is negligible against the disc's).

Both use the impact-law damping ramp of :func:`flexrv.contact.laws.impact_force`.
Generalized forces are Q = -F d(delta)/dq (exact); analytic Jacobians keep the
contact-stiffness terms and drop the geometric (direction-rotation) ones.
"""

from __future__ import annotations

import numpy as np

from flexrv.contact.hertz import LINE_EXPONENT
from flexrv.contact.laws import impact_force
from flexrv.model.base import ForceGroup, Output


class CrankSupports(ForceGroup):
    """Crank centres in their carrier bores (members: carrier, crank0..N-1)."""

    name = "crank_supports"
    analytic_jacobian = True

    def __init__(self, params):
        p = params
        self.n = p.n_cranks
        self.members = ("carrier",) + tuple(f"crank{j}" for j in range(self.n))
        self.local = p.center_distance * np.stack([np.cos(p.crank_angles), np.sin(p.crank_angles)], axis=-1)
        self.k = p.support_stiffness
        self.c = p.support_damping

    def _kin(self, q, v):
        th, om = q[..., 2:3], v[..., 2:3]
        c, s = np.cos(th), np.sin(th)
        lx, ly = self.local[:, 0], self.local[:, 1]
        rx, ry = c * lx - s * ly, s * lx + c * ly  # (..., n) bore offsets in the housing frame
        dx = q[..., 6::3] - q[..., 0:1] - rx
        dy = q[..., 7::3] - q[..., 1:2] - ry
        dvx = v[..., 6::3] - v[..., 0:1] + om * ry
        dvy = v[..., 7::3] - v[..., 1:2] - om * rx
        return rx, ry, dx, dy, dvx, dvy

    def evaluate(self, t, q, v, want_outputs: bool = False):
        rx, ry, dx, dy, dvx, dvy = self._kin(q, v)
        fx = -self.k * dx - self.c * dvx  # on the cranks
        fy = -self.k * dy - self.c * dvy
        gen = np.zeros(q.shape)
        gen[..., 0] = -fx.sum(axis=-1)
        gen[..., 1] = -fy.sum(axis=-1)
        gen[..., 2] = -(rx * fy - ry * fx).sum(axis=-1)
        gen[..., 6::3] = fx
        gen[..., 7::3] = fy
        out = None
        if want_outputs:
            out = {"crank_support_force": Output(np.hypot(fx, fy), ("time", "crank"), "N",
                                                 "radial force of the carrier on each crank (both support bearings)")}
        return gen, out

    def jacobian(self, t, q, v):
        rx, ry, _, _, _, _ = self._kin(q, v)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        for j in range(self.n):
            b = np.zeros((2, n))  # d(d_j)/dq
            b[:, 6 + 3 * j:8 + 3 * j] = np.eye(2)
            b[:, 0:2] = -np.eye(2)
            b[:, 2] = [ry[j], -rx[j]]
            bb = b.T @ b
            dq -= self.k * bb
            dv -= self.c * bb
        return dq, dv


class NeedleBearings(ForceGroup):
    """All crank–disc needle bearings in one element (members: cranks, discs)."""

    name = "needle_bearings"
    analytic_jacobian = True

    def __init__(self, params, model: str, k_empirical: float | None = None):
        p = params
        self.nc, self.nd = p.n_cranks, p.n_discs
        self.members = tuple(f"crank{j}" for j in range(self.nc)) + tuple(f"disc{k}" for k in range(self.nd))
        self.model = model
        self.e = p.eccentricity
        self.chi0 = p.chi0  # (nd,)
        self.hx = p.holes[..., 0].T  # (nc, nd) hole centres in the disc frames
        self.hy = p.holes[..., 1].T
        self.clear = p.needle_clearance
        self.c_max = p.needle_c_max
        self.depth = p.contact_depth
        self.exponent = LINE_EXPONENT
        if model == "empirical":
            if k_empirical is None:
                raise ValueError("k_empirical required for the empirical needle model")
            self.k = float(k_empirical)
        else:
            self.k = p.needle_roller_k
            self.z = p.needle_roller_count
            self.g = p.needle_pitch_ratio
            self.roller_angles = 2.0 * np.pi * np.arange(self.z) / self.z
        self.min_gap = np.inf

    def _kin(self, q, v):
        """Journal offsets d = E - H and their rates, in components (..., nc, nd)."""
        nc = self.nc
        xc, yc, phc = q[..., 0:3 * nc:3, None], q[..., 1:3 * nc:3, None], q[..., 2:3 * nc:3, None]
        vxc, vyc, vphc = v[..., 0:3 * nc:3, None], v[..., 1:3 * nc:3, None], v[..., 2:3 * nc:3, None]
        xd, yd, psd = q[..., None, 3 * nc::3], q[..., None, 3 * nc + 1::3], q[..., None, 3 * nc + 2::3]
        vxd, vyd, vpsd = v[..., None, 3 * nc::3], v[..., None, 3 * nc + 1::3], v[..., None, 3 * nc + 2::3]
        chi = self.chi0 - phc
        sc, cc = np.sin(chi), np.cos(chi)
        epx, epy = -self.e * cc, self.e * sc  # dE/dphi
        c, s = np.cos(psd), np.sin(psd)
        rhx, rhy = c * self.hx - s * self.hy, s * self.hx + c * self.hy
        hpx, hpy = -rhy, rhx  # dH/dpsi
        dx = xc + self.e * sc - xd - rhx
        dy = yc + self.e * cc - yd - rhy
        dvx = vxc + epx * vphc - vxd - hpx * vpsd
        dvy = vyc + epy * vphc - vyd - hpy * vpsd
        return dx, dy, dvx, dvy, epx, epy, hpx, hpy, phc, psd

    def _contacts(self, q, v):
        dx, dy, dvx, dvy, epx, epy, hpx, hpy, phc, psd = self._kin(q, v)
        if self.model == "empirical":
            r = np.sqrt(dx * dx + dy * dy + 1e-30)
            ux, uy = dx / r, dy / r
            delta = r - self.clear
            rate = ux * dvx + uy * dvy
        else:
            gam = (0.5 * ((1.0 - self.g) * phc + (1.0 + self.g) * psd))[..., None] + self.roller_angles
            ux, uy = np.cos(gam), np.sin(gam)  # (..., nc, nd, z)
            dx, dy, dvx, dvy = dx[..., None], dy[..., None], dvx[..., None], dvy[..., None]
            epx, epy, hpx, hpy = epx[..., None], epy[..., None], hpx[..., None], hpy[..., None]
            delta = dx * ux + dy * uy - self.clear
            rate = dvx * ux + dvy * uy
        f, df, dfr = impact_force(-delta, -rate, self.k, self.exponent, self.c_max, self.depth)
        return dict(delta=delta, f=f, kq=-df, kv=-dfr, ux=ux, uy=uy,
                    gc=(ux * epx + uy * epy), gd=(ux * hpx + uy * hpy), ep=(epx, epy), hp=(hpx, hpy))

    def evaluate(self, t, q, v, want_outputs: bool = False):
        c = self._contacts(q, v)
        f, ux, uy = c["f"], c["ux"], c["uy"]
        fx, fy, mc, md = f * ux, f * uy, f * c["gc"], f * c["gd"]
        if self.model == "rollers":  # sum over the rollers of each bearing
            fx, fy, mc, md = fx.sum(axis=-1), fy.sum(axis=-1), mc.sum(axis=-1), md.sum(axis=-1)
        nc = self.nc
        gen = np.empty(q.shape)
        gen[..., 0:3 * nc:3] = -fx.sum(axis=-1)
        gen[..., 1:3 * nc:3] = -fy.sum(axis=-1)
        gen[..., 2:3 * nc:3] = -mc.sum(axis=-1)
        gen[..., 3 * nc::3] = fx.sum(axis=-2)
        gen[..., 3 * nc + 1::3] = fy.sum(axis=-2)
        gen[..., 3 * nc + 2::3] = md.sum(axis=-2)
        if q.ndim == 1:
            self.min_gap = float(np.min(-c["delta"]))
        out = None
        if want_outputs:
            dims = ("time", "crank", "disc")
            out = {"needle_force": Output(np.hypot(fx, fy), dims, "N", "needle-bearing force (journal on disc hole)"),
                   "needle_force_x": Output(fx, dims, "N", "needle-bearing force on the disc, x"),
                   "needle_force_y": Output(fy, dims, "N", "needle-bearing force on the disc, y")}
            if self.model == "rollers":
                out["roller_force"] = Output(f, dims + ("roller",), "N", "needle roller contact force")
                out["roller_angle"] = Output(np.arctan2(uy, ux), dims + ("roller",), "rad",
                                             "direction of each roller's contact force on the disc (housing frame)")
        return gen, out

    def jacobian(self, t, q, v):
        c = self._contacts(q, v)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        nc = self.nc
        eye = np.eye(2)
        epx, epy = c["ep"]
        hpx, hpy = c["hp"]
        for j in range(nc):
            for k in range(self.nd):
                idx = np.r_[3 * j:3 * j + 3, 3 * nc + 3 * k:3 * nc + 3 * k + 3]
                b = np.zeros((2, 6))  # d(d)/d(local coordinates of crank j, disc k)
                b[:, 0:2], b[:, 3:5] = eye, -eye
                b[:, 2] = [np.ravel(epx[j, k])[0], np.ravel(epy[j, k])[0]]
                b[:, 5] = [-np.ravel(hpx[j, k])[0], -np.ravel(hpy[j, k])[0]]
                kq, kv, f = c["kq"][j, k], c["kv"][j, k], c["f"][j, k]
                if self.model == "empirical":
                    if f <= 0 and kq <= 0:
                        continue
                    u = np.array([c["ux"][j, k], c["uy"][j, k]])
                    uu = np.outer(u, u)
                    r = c["delta"][j, k] + self.clear
                    stiff = kq * uu + (f / r) * (eye - uu)
                    damp = kv * uu
                else:
                    act = kq != 0
                    if not np.any(act):
                        continue
                    u = np.stack([c["ux"][j, k][act], c["uy"][j, k][act]], axis=-1)
                    stiff = (u.T * kq[act]) @ u
                    damp = (u.T * kv[act]) @ u
                dq[np.ix_(idx, idx)] -= b.T @ stiff @ b
                dv[np.ix_(idx, idx)] -= b.T @ damp @ b
        return dq, dv

    def reset(self) -> None:
        self.min_gap = np.inf

    def check(self) -> str | None:
        if self.min_gap < -max(20.0 * self.depth, 50e-6):
            return f"needle-bearing penetration {-self.min_gap * 1e6:.3g} um exceeds the physical limit"
        return None
