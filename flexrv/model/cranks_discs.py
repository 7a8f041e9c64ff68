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


def _rot(v, angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def _cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


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
        n = self.n
        cc, th = q[..., None, 0:2], q[..., 2:3]
        vc, om = v[..., None, 0:2], v[..., 2:3]
        qc = q[..., 6:].reshape(q.shape[:-1] + (n, 3))
        vk = v[..., 6:].reshape(v.shape[:-1] + (n, 3))
        r = _rot(self.local, th)  # (..., n, 2)
        h = cc + r
        hv = vc + om[..., None] * np.stack([-r[..., 1], r[..., 0]], axis=-1)
        d = qc[..., :2] - h
        dv = vk[..., :2] - hv
        return r, d, dv

    def evaluate(self, t, q, v, want_outputs: bool = False):
        r, d, dv = self._kin(q, v)
        f = -self.k * d - self.c * dv  # on the cranks
        gen = np.zeros(q.shape)
        gen[..., 0:2] = -f.sum(axis=-2)
        gen[..., 2] = -_cross2(r, f).sum(axis=-1)
        fk = np.zeros(q.shape[:-1] + (self.n, 3))
        fk[..., :2] = f
        gen[..., 6:] = fk.reshape(q.shape[:-1] + (3 * self.n,))
        out = None
        if want_outputs:
            out = {"crank_support_force": Output(np.hypot(f[..., 0], f[..., 1]), ("time", "crank"), "N",
                                                 "radial force of the carrier on each crank (both support bearings)")}
        return gen, out

    def jacobian(self, t, q, v):
        r, _, _ = self._kin(q, v)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        for j in range(self.n):
            b = np.zeros((2, n))  # d(d_j)/dq
            b[:, 6 + 3 * j:8 + 3 * j] = np.eye(2)
            b[:, 0:2] = -np.eye(2)
            b[:, 2] = [r[j, 1], -r[j, 0]]
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
        self.holes = p.holes  # (nd, nc, 2)
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
        self.min_gap = np.inf

    def _kin(self, q, v):
        nc, nd = self.nc, self.nd
        lead = q.shape[:-1]
        qc = q[..., :3 * nc].reshape(lead + (nc, 1, 3))
        vc = v[..., :3 * nc].reshape(lead + (nc, 1, 3))
        qd = q[..., 3 * nc:].reshape(lead + (1, nd, 3))
        vd = v[..., 3 * nc:].reshape(lead + (1, nd, 3))
        chi = self.chi0 - qc[..., 2]  # (..., nc, nd)
        ecc = self.e * np.stack([np.sin(chi), np.cos(chi)], axis=-1)
        e_phi = self.e * np.stack([-np.cos(chi), np.sin(chi)], axis=-1)  # dE/dphi
        rh = _rot(np.swapaxes(self.holes, 0, 1), qd[..., 2])  # (..., nc, nd, 2)
        h_psi = np.stack([-rh[..., 1], rh[..., 0]], axis=-1)
        d = qc[..., :2] + ecc - qd[..., :2] - rh
        dv = (vc[..., :2] + e_phi * vc[..., 2:3]) - (vd[..., :2] + h_psi * vd[..., 2:3])
        return d, dv, e_phi, h_psi, rh, qc, qd

    def _gen(self, q, grad_c, grad_d, f):
        """Assemble Q = -sum f grad (grad_c: (..., nc, nd, 3), grad_d likewise)."""
        lead = q.shape[:-1]
        gc = -(f[..., None] * grad_c).sum(axis=-2)  # (..., nc, 3)
        gd = -(f[..., None] * grad_d).sum(axis=-3)  # (..., nd, 3)
        return np.concatenate([gc.reshape(lead + (3 * self.nc,)), gd.reshape(lead + (3 * self.nd,))], axis=-1)

    def _contacts(self, q, v):
        d, dv, e_phi, h_psi, rh, qc, qd = self._kin(q, v)
        if self.model == "empirical":
            r = np.sqrt(np.einsum("...k,...k->...", d, d) + 1e-30)
            u = d / r[..., None]  # (..., nc, nd, 2)
            delta = r - self.clear
            rate = np.einsum("...k,...k->...", u, dv)
        else:
            gam_c = 0.5 * ((1.0 - self.g) * qc[..., 2] + (1.0 + self.g) * qd[..., 2])  # (..., nc, nd)
            gam = gam_c[..., None] + 2.0 * np.pi * np.arange(self.z) / self.z
            u = np.stack([np.cos(gam), np.sin(gam)], axis=-1)  # (..., nc, nd, z, 2)
            delta = np.einsum("...k,...zk->...z", d, u) - self.clear
            rate = np.einsum("...k,...zk->...z", dv, u)
            e_phi, h_psi = e_phi[..., None, :], h_psi[..., None, :]
        f, df, dfr = impact_force(-delta, -rate, self.k, self.exponent, self.c_max, self.depth)
        gc = np.concatenate([u, np.einsum("...k,...k->...", u, e_phi)[..., None]], axis=-1)
        gd = -np.concatenate([u, np.einsum("...k,...k->...", u, h_psi)[..., None]], axis=-1)
        return delta, f, -df, -dfr, gc, gd, u

    def evaluate(self, t, q, v, want_outputs: bool = False):
        delta, f, kq, kv, gc, gd, u = self._contacts(q, v)
        if self.model == "empirical":
            gen = self._gen(q, gc, gd, f)
            vec = f[..., None] * u
        else:
            gen = self._gen(q, (f[..., None] * gc).sum(axis=-2), (f[..., None] * gd).sum(axis=-2), np.ones(f.shape[:-1]))
            vec = (f[..., None] * u).sum(axis=-2)
        self.min_gap = float(np.min(-delta)) if q.ndim == 1 else self.min_gap
        out = None
        if want_outputs:
            dims = ("time", "crank", "disc")
            out = {"needle_force": Output(np.hypot(vec[..., 0], vec[..., 1]), dims, "N",
                                          "needle-bearing force (journal on disc hole)"),
                   "needle_force_x": Output(vec[..., 0], dims, "N", "needle-bearing force on the disc, x"),
                   "needle_force_y": Output(vec[..., 1], dims, "N", "needle-bearing force on the disc, y")}
            if self.model == "rollers":
                out["roller_force"] = Output(f, dims + ("roller",), "N", "needle roller contact force")
        return gen, out

    def jacobian(self, t, q, v):
        d, _, e_phi, h_psi, _, _, _ = self._kin(q, v)
        delta, f, kq, kv, gc, gd, u = self._contacts(q, v)
        n = q.shape[-1]
        dq = np.zeros((n, n))
        dv = np.zeros((n, n))
        nc = self.nc
        eye = np.eye(2)
        for j in range(nc):
            for k in range(self.nd):
                idx = np.r_[3 * j:3 * j + 3, 3 * nc + 3 * k:3 * nc + 3 * k + 3]
                b = np.zeros((2, 6))  # d(d)/d(local coordinates of crank j, disc k)
                b[:, 0:2], b[:, 2] = eye, e_phi[j, k]
                b[:, 3:5], b[:, 5] = -eye, -h_psi[j, k]
                if self.model == "empirical":
                    if f[j, k] <= 0 and kq[j, k] <= 0:
                        continue
                    uu = np.outer(u[j, k], u[j, k])
                    r = delta[j, k] + self.clear
                    stiff = kq[j, k] * uu + (f[j, k] / r) * (eye - uu)
                    damp = kv[j, k] * uu
                else:
                    act = kq[j, k] != 0
                    if not np.any(act):
                        continue
                    uj = u[j, k][act]  # (m, 2)
                    stiff = (uj.T * kq[j, k][act]) @ uj
                    damp = (uj.T * kv[j, k][act]) @ uj
                dq[np.ix_(idx, idx)] -= b.T @ stiff @ b
                dv[np.ix_(idx, idx)] -= b.T @ damp @ b
        return dq, dv

    def check(self) -> str | None:
        if self.min_gap < -max(20.0 * self.depth, 50e-6):
            return f"needle-bearing penetration {-self.min_gap * 1e6:.3g} um exceeds the physical limit"
        return None
