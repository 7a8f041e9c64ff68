"""Crank support: a preloaded pair of tapered-roller bearings, roller-resolved, in
series with the crank's bending between its support journals and its eccentrics.

One law, one executor: :func:`crank_support_force` (numba) is called by the
compiled crank-support kernel (:mod:`flexrv.model.cranks_discs`: dynamic and
quasi-static models) and, through :func:`support_deflection`, by the analytic
stiffness budget (:mod:`flexrv.analysis.torsional`, ``flexrv design``).

Bearing (Harris & Kotzalas, *Rolling Bearing Analysis*, 5th ed. 2007, ch. 7 and
11): each crank runs in two identical tapered-roller bearings (cup half-angle
alpha, Z rollers, effective roller length l), face to face, axially preloaded.
A radial displacement b = (b_x, b_y) of the inner ring (the crank journal)
relative to the outer ring (the carrier bore) in the transverse plane, the same
for both bearings (planar model: the crank does not tilt; with a radial load the
two opposed bearings keep their axial preload by symmetry), gives roller i at
azimuth psi_i the normal approach

    delta_i = delta_0 + cos(alpha) (b . u_i - c_r),   u_i = (cos psi_i, sin psi_i),

delta_0 = s_a sin(alpha) the normal approach of the axial preload s_a per bearing
(negative s_a: axial end play), c_r the as-built radial clearance. Each roller is
two Palmgren line contacts (cone and cup raceways) in series, Q = K delta^(10/9)
(:func:`flexrv.contact.hertz.line_contact_stiffness`,
:func:`flexrv.contact.hertz.series_stiffness`; rib contacts neglected). The
rollers' normal forces act at alpha to the radial plane, so the force on the crank
(both bearings) is

    F(b) = -2 cos(alpha) sum_i Q_i u_i,

with the tangent K_b = -dF/db = 2 cos^2(alpha) sum_i Q'_i u_i u_i^T. The cage turns
at the epicyclic rate (Harris & Kotzalas 2007, ch. 8) psi_i = gamma + 2 pi i / Z,
gamma = (1 - g) phi_crank / 2 + (1 + g) theta_carrier / 2, g = D cos(alpha) / d_m.

Linear option (``support_bearing_model = "linear"``): F = -k max(|b| - c_r, 0) b/|b|.

Crank bending in series (``crankshaft.bending_model``): the crank centre in the
planar model is displaced by d = b + e relative to its bore, e the shaft's elastic
deflection between the support journals and the eccentrics under the transmitted
force, e = -F / k_bend (k_bend from :func:`flexrv.analysis.torsional.crank_bending`; the
constants of a design from :func:`flexrv.analysis.torsional.support_constants`;
Timoshenko stepped shaft, verified against the FE condensation of
:func:`flexrv.fem.crankshaft.crank_bending_compliance`). For a given d the inner
equation R(b) = F(b) + k_bend (d - b) = 0 is solved by Newton's method (R is the
gradient of a strictly convex energy, so Newton with step halving converges); the
tangent is exact by the implicit-function theorem (the roller directions u_i are
computed once per call, the inner solve keeping gamma fixed; its tolerance is
relative to the summed roller load, see :func:`crank_support_force`):

    -df/dd = K_s = K_b (K_b + k_bend I)^-1 k_bend,
    df/dgamma = k_bend (K_b + k_bend I)^-1 dF/dgamma.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class SupportConstants(NamedTuple):
    """The constants ``sc`` of :func:`crank_support_force`, read by name (numba types a
    NamedTuple of floats defined at module level, and its cache finds it again by name in
    the next process). Build it with :meth:`of` (every field converted to float, so that
    every instance has the same numba type)."""

    linear: float  #: radial stiffness k of the linear law (both bearings) [N/m]; 0: roller law
    k_roller: float  #: roller constant K of Q = K delta^n (two line contacts in series) [N/m^n]
    cos_a: float  #: cos(alpha) of the cup half-angle [-]
    delta0: float  #: normal approach of the axial preload s_a sin(alpha) [m]
    k_bend: float  #: crank bending stiffness in series [N/m]; 0: rigid crank
    exponent: float  #: load-deflection exponent n of a roller [-]
    g: float  #: D cos(alpha) / d_m of the cage's epicyclic rate [-]

    @classmethod
    def of(cls, **values) -> SupportConstants:
        """Every field given by name (missing or unknown ones rejected), as float."""
        missing, extra = set(cls._fields) - set(values), set(values) - set(cls._fields)
        if missing or extra:
            raise TypeError(f"SupportConstants: missing {sorted(missing)}, unknown {sorted(extra)}")
        return cls(**{k: float(values[k]) for k in cls._fields})

    @classmethod
    def zero(cls) -> SupportConstants:
        return cls(*([0.0] * len(cls._fields)))


@njit(cache=True)
def _roller_directions(gam, angles):
    """Unit vectors u_i = (cos psi_i, sin psi_i), psi_i = gamma + angles[i], of the
    rollers at cage angle gamma: computed once per support evaluation (the inner
    Newton keeps gamma fixed), not once per bearing evaluation."""
    z = angles.shape[0]
    ux, uy = np.empty(z), np.empty(z)
    roller_directions_into(gam, np.cos(angles), np.sin(angles), ux, uy)
    return ux, uy


@njit(cache=True)
def roller_directions_into(gam, cos_angles, sin_angles, ux, uy):
    """:func:`_roller_directions` into given arrays (no allocation), from the cosines and
    sines of the roller spacing ``angles`` (a caller that evaluates at many cage angles
    computes them once): u_i = Rot(gamma) (cos angle_i, sin angle_i), two trigonometric
    calls per cage angle instead of two per roller."""
    cg, sg = np.cos(gam), np.sin(gam)
    for i in range(cos_angles.shape[0]):
        ca, sa = cos_angles[i], sin_angles[i]
        ux[i], uy[i] = cg * ca - sg * sa, sg * ca + cg * sa


@njit(cache=True)
def _bearing(bx, by, clear, sc, ux, uy, is_linear):
    """Bearing force F (on the crank) at inner-ring displacement b, its tangent
    K_b = -dF/db (kxx, kxy, kyy), dF/dgamma (gx, gy) and the summed roller load;
    (ux, uy): the roller directions (:func:`_roller_directions`)."""
    if is_linear:
        k = sc.linear
        dist = np.sqrt(bx * bx + by * by)
        if clear <= 0.0:
            return -k * bx, -k * by, k, 0.0, k, 0.0, 0.0, k * dist
        if dist <= clear:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        sk = k * (1.0 - clear / dist)
        ux, uy = bx / dist, by / dist
        w = k * clear / dist
        return -sk * bx, -sk * by, sk + w * ux * ux, w * ux * uy, sk + w * uy * uy, 0.0, 0.0, sk * dist
    kr, ca, d0, n = sc.k_roller, sc.cos_a, sc.delta0, sc.exponent
    fx = fy = kxx = kxy = kyy = gx = gy = qsum = 0.0
    for i in range(ux.shape[0]):
        cx, cy = ux[i], uy[i]
        delta = d0 + ca * (bx * cx + by * cy - clear)
        if delta <= 0.0:
            continue
        q = kr * delta**n
        dq = n * q / delta
        qsum += q
        fx -= 2.0 * ca * q * cx
        fy -= 2.0 * ca * q * cy
        kxx += 2.0 * ca * ca * dq * cx * cx
        kxy += 2.0 * ca * ca * dq * cx * cy
        kyy += 2.0 * ca * ca * dq * cy * cy
        # d/dgamma: u' = (-uy, ux); d(delta)/dgamma = ca b . u'
        dd = ca * (-bx * cy + by * cx)
        gx -= 2.0 * ca * (dq * dd * cx - q * cy)
        gy -= 2.0 * ca * (dq * dd * cy + q * cx)
    return fx, fy, kxx, kxy, kyy, gx, gy, 2.0 * qsum


@njit(cache=True)
def crank_support_force(dx, dy, gam, clear, sc, angles, is_linear, b0x, b0y):
    """Force (fx, fy) of one crank support (two bearings + crank bending in series)
    on the crank at the crank-centre displacement d relative to its bore (module
    docstring), its tangent K_s = -df/dd (kxx, kxy, kyy), df/dgamma (gx, gy), the
    bearing displacement (bx, by) and the summed roller load. (b0x, b0y): Newton
    start for b (the previous solution; any value converges). The inner equation is
    solved to |R|_1 <= 1e-13 (k_bend |d|_1 + |F|_1 + summed roller load), or to its
    round-off floor (a Newton step that no longer lowers |R|), i.e. b to ~1e-19 m.
    The roller directions at the cage angle gamma, then :func:`crank_support_force_at`."""
    if is_linear:
        ux = uy = angles[:0]
    else:
        ux, uy = _roller_directions(gam, angles)
    return crank_support_force_at(dx, dy, ux, uy, clear, sc, is_linear, b0x, b0y)


@njit(cache=True)
def crank_support_force_at(dx, dy, ux, uy, clear, sc, is_linear, b0x, b0y):
    """:func:`crank_support_force` with the roller directions (ux, uy) of its cage angle
    given (:func:`_roller_directions`; empty for the linear law): a caller that evaluates
    one support at several d and the same cage angle (the elastic carrier's Newton)
    computes them once."""
    kb = sc.k_bend
    if kb <= 0.0:  # rigid crank: b = d
        fx, fy, kxx, kxy, kyy, gx, gy, qs = _bearing(dx, dy, clear, sc, ux, uy, is_linear)
        return fx, fy, kxx, kxy, kyy, gx, gy, dx, dy, qs
    bx, by = b0x, b0y
    fx, fy, kxx, kxy, kyy, gx, gy, qs = _bearing(bx, by, clear, sc, ux, uy, is_linear)
    rx, ry = fx + kb * (dx - bx), fy + kb * (dy - by)
    # tolerance relative to the largest terms of R: the shaft force, the net bearing force and the
    # summed roller loads qs (with preload the roller forces cancel in F, whose round-off is ~eps qs;
    # without qs the scale of a nearly unloaded support, ~0.01-0.1 N, lay below that floor and the
    # loop ran to its limit: 100 iterations of 20 halvings in ~6 % of the quasi-static solver's calls)
    scale = abs(kb) * (abs(dx) + abs(dy)) + abs(fx) + abs(fy) + qs + 1e-300
    for _ in range(100):
        if abs(rx) + abs(ry) <= 1e-13 * scale:
            break
        axx, axy, ayy = kxx + kb, kxy, kyy + kb
        det = axx * ayy - axy * axy
        sx = (ayy * rx - axy * ry) / det
        sy = (axx * ry - axy * rx) / det
        r0 = abs(rx) + abs(ry)
        lam = 1.0
        for _h in range(40):  # step halving on |R|_1 (R is the gradient of a convex energy)
            nbx, nby = bx + lam * sx, by + lam * sy
            f2 = _bearing(nbx, nby, clear, sc, ux, uy, is_linear)
            nrx, nry = f2[0] + kb * (dx - nbx), f2[1] + kb * (dy - nby)
            if abs(nrx) + abs(nry) < r0 or lam < 1e-6:
                break
            lam *= 0.5
        if not abs(nrx) + abs(nry) < r0:  # no decrease along the Newton direction: R is at its round-off floor
            break
        bx, by = nbx, nby
        fx, fy, kxx, kxy, kyy, gx, gy, qs = f2
        rx, ry = nrx, nry
    # K_s = K_b (K_b + k I)^-1 k ; df/dgamma = k (K_b + k I)^-1 dF/dgamma
    axx, axy, ayy = kxx + kb, kxy, kyy + kb
    det = axx * ayy - axy * axy
    ixx, ixy, iyy = ayy / det, -axy / det, axx / det
    sxx = kb * (kxx * ixx + kxy * ixy)
    sxy = kb * (kxx * ixy + kxy * iyy)
    syy = kb * (kxy * ixy + kyy * iyy)
    hx = kb * (ixx * gx + ixy * gy)
    hy = kb * (ixy * gx + iyy * gy)
    return fx, fy, sxx, sxy, syy, hx, hy, bx, by, qs


def support_deflection(force, sc, angles, is_linear, clear: float = 0.0, gamma: float = 0.0):
    """Crank-centre displacement d [m] (2,) relative to its bore under which the
    support carries the force ``force`` [N] (2,) applied to the crank (the support
    pushes back with -force), and the tangent K_s [N/m] (2, 2) and bearing
    displacement b there: the inverse of :func:`crank_support_force` by Newton's
    method (monotone law; with a clearance the start lies along the force)."""
    f = np.asarray(force, dtype=float)
    fn = float(np.hypot(*f))
    d = np.zeros(2) if fn == 0.0 else f / fn * (clear + 1e-9)
    b = d.copy()
    for _ in range(200):
        fx, fy, kxx, kxy, kyy, _, _, bx, by, _ = crank_support_force(
            d[0], d[1], gamma, clear, sc, angles, is_linear, b[0], b[1]
        )
        b = np.array([bx, by])
        r = np.array([fx, fy]) + f
        if np.hypot(*r) <= 1e-10 * max(fn, 1.0):
            break
        k = np.array([[kxx, kxy], [kxy, kyy]])
        try:
            step = np.linalg.solve(k, r)
        except np.linalg.LinAlgError:
            step = f / fn * 1e-7
        if not np.all(np.isfinite(step)) or np.hypot(*step) > 1e-4:
            step = step / max(np.hypot(*step), 1e-30) * 1e-6
        d = d + step
    else:  # pragma: no cover - monotone law: always converges
        raise RuntimeError("crank support deflection did not converge")
    return d, np.array([[kxx, kxy], [kxy, kyy]]), b
