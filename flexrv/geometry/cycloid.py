"""Cycloid-disc geometry: pin-centre epitrochoid and the modified tooth profile.

Conventions (disc frame, origin at the disc centre, SI units): with the curve
parameter phi in [0, 2 pi) and R = R_p + dR_p (shift-modified pin circle),

    C(phi) = R (sin phi, cos phi) - a (sin(z_rp phi), cos(z_rp phi))

is the path of a pin centre relative to the disc (an epitrochoid with
z_c = z_rp - 1 lobes, |C| between R - a and R + a). The tooth profile is its inward
offset by r = r_rp + dr_rp (equidistant-modified pin radius), rotated by the
rotation modification d_delta. Sources: Litvin & Fuentes, *Gear Geometry and
Applied Theory* (2004), ch. 19; Li et al. :cite:`seed004` for the curvature formula.
"""

from __future__ import annotations

import numpy as np

try:  # optional accelerator for the closest-point iteration of pin_gap
    from numba import njit as _njit
except ImportError:  # pragma: no cover - numba absent: plain numpy
    _njit = None


def _jit(fn):
    """numba-compiled ``fn`` (cached on disk) if numba is installed, else ``fn``:
    the same kernel runs either way (one formula, two executors)."""
    return _njit(cache=True)(fn) if _njit is not None else fn


def center_curve(phi, z_rp: int, radius: float, eccentricity: float):
    """Pin-centre epitrochoid C(phi) and its first two derivatives.

    Returns
    -------
    c, dc, ddc : ndarray, shape (..., 2)
        Position [m] and derivatives w.r.t. phi.
    """
    phi = np.asarray(phi, dtype=float)
    out = _CURVE(np.ascontiguousarray(phi).ravel(), int(z_rp), float(radius), float(eccentricity))
    out = out.reshape((3,) + phi.shape + (2,))
    return out[0], out[1], out[2]


def _center_curve_point(phi, z_rp, radius, eccentricity):
    """C(phi), C'(phi), C''(phi) at one curve parameter as six floats
    (cx, cy, d1x, d1y, d2x, d2y): the single implementation of the curve."""
    s, c = np.sin(phi), np.cos(phi)
    zphi = z_rp * phi
    sz, cz = np.sin(zphi), np.cos(zphi)
    rs, rc = radius * s, radius * c
    ez, ez2 = eccentricity * z_rp, eccentricity * z_rp * z_rp
    return (rs - eccentricity * sz, rc - eccentricity * cz, rc - ez * cz, -rs + ez * sz, -rs + ez2 * sz, -rc + ez2 * cz)


_POINT = _jit(_center_curve_point)


def _center_curve_kernel(phi, z_rp, radius, eccentricity):
    """:func:`_center_curve_point` over a flat array ``phi`` (M,): (3, M, 2)."""
    out = np.empty((3, phi.shape[0], 2))
    for i in range(phi.shape[0]):
        out[0, i, 0], out[0, i, 1], out[1, i, 0], out[1, i, 1], out[2, i, 0], out[2, i, 1] = _POINT(
            phi[i], z_rp, radius, eccentricity
        )
    return out


_CURVE = _jit(_center_curve_kernel)


def center_curve_curvature(phi, z_rp: int, radius: float, eccentricity: float):
    """Signed curvature kappa [1/m] of the pin-centre curve; kappa > 0 where the
    curve bends towards the disc centre (convex lobes)."""
    _, d1, d2 = center_curve(phi, z_rp, radius, eccentricity)
    cross = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
    speed = np.hypot(d1[..., 0], d1[..., 1])
    return -cross / speed**3


def min_convex_curvature_radius(z_rp: int, radius: float, eccentricity: float, samples: int = 4001) -> float:
    """Smallest radius of curvature [m] over the convex part of the pin-centre
    curve. The profile (inward offset by r_rp + dr_rp) is free of undercut only if
    that offset is smaller than this radius."""
    phi = np.linspace(0.0, 2.0 * np.pi / (z_rp - 1), samples)
    kappa = center_curve_curvature(phi, z_rp, radius, eccentricity)
    convex = kappa > 0
    if not np.any(convex):
        return float("inf")
    return float(1.0 / kappa[convex].max())


def profile_points(
    phi,
    z_rp: int,
    pin_circle_radius: float,
    pin_radius: float,
    eccentricity: float,
    d_radius: float = 0.0,
    d_pin_radius: float = 0.0,
    d_rotation: float = 0.0,
):
    """Points [m] of the modified disc profile, shape (..., 2).

    The profile is the inward offset of the pin-centre curve (pin circle
    R_p + dR_p) by r_rp + dr_rp, rotated by d_rotation about the disc centre.
    """
    pos, d1, _ = center_curve(phi, z_rp, pin_circle_radius + d_radius, eccentricity)
    tangent = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
    # clockwise traversal: inward normal is the tangent rotated by -90 deg
    inward = np.stack([tangent[..., 1], -tangent[..., 0]], axis=-1)
    pts = pos + (pin_radius + d_pin_radius) * inward
    if d_rotation:
        cr, sr = np.cos(d_rotation), np.sin(d_rotation)
        pts = np.stack([cr * pts[..., 0] - sr * pts[..., 1], sr * pts[..., 0] + cr * pts[..., 1]], axis=-1)
    return pts


# =========================================================================== pose of the pins
def pin_positions(z_rp: int, pin_circle_radius: float):
    """Pin centres [m] in the housing frame, shape (z_rp, 2).

    Pin j sits at curve angle psi_j = 2 pi j / z_rp on the pin circle, in the same
    clockwise-from-+y convention as :func:`center_curve`: R (sin psi_j, cos psi_j).
    """
    psi = 2.0 * np.pi * np.arange(z_rp) / z_rp
    return pin_circle_radius * np.stack([np.sin(psi), np.cos(psi)], axis=-1)


def nominal_disc_pose(z_rp: int, eccentricity: float, crank_angle):
    """Conjugate (ideal) pose of the disc for a crank angle.

    The crank angle chi [rad] is measured like the curve parameter (clockwise from
    +y): the disc centre is at a (sin chi, cos chi) in the housing frame and the
    disc is turned by chi / z_c counter-clockwise (``rotation = chi / z_c``): a
    crank turning clockwise (increasing chi) turns the disc counter-clockwise at
    1/z_c of its speed. With this pose every pin of the ideal pin circle lies on the
    pin-centre curve :func:`center_curve` (derivation: R e(phi + t) - a e(z_rp phi + t)
    + O = R e(psi_j) for all j requires phi = psi_j - t and O = a e(-z_c t), with
    e(x) = (sin x, cos x) and t the clockwise disc angle, so t = -chi/z_c;
    Litvin & Fuentes 2004, ch. 19).

    Returns
    -------
    center : ndarray (..., 2)
        Disc centre [m] in the housing frame.
    rotation : ndarray (...)
        Counter-clockwise disc rotation [rad] (housing <- disc).
    """
    chi = np.asarray(crank_angle, dtype=float)
    center = eccentricity * np.stack([np.sin(chi), np.cos(chi)], axis=-1)
    return center, chi / (z_rp - 1)


def to_disc_frame(points, disc_center, disc_rotation):
    """Express housing-frame points (..., 2) in the disc frame [m]:
    x_disc = Rot(-rotation) (x - centre), rotation counter-clockwise [rad].
    ``disc_center`` (..., 2) and ``disc_rotation`` (...) broadcast against the
    points' leading dimensions."""
    p = np.asarray(points, dtype=float) - np.asarray(disc_center, dtype=float)
    c, s = np.cos(disc_rotation), np.sin(disc_rotation)
    return np.stack([c * p[..., 0] + s * p[..., 1], -s * p[..., 0] + c * p[..., 1]], axis=-1)


def _rotate(v, angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


# =========================================================================== signed pin gap
def _closest_point_newton(px, py, phi, z_rp, radius, eccentricity, max_step, tol, max_iter):
    """Newton iteration of :func:`pin_gap` on g(phi) = |P - C(phi)|^2 / 2 for one
    point P = (px, py) from the start ``phi``; steps clipped to ``max_step``, a
    descent step where g'' <= 0. The single implementation (numba-compiled): the
    pin-contact kernel and :func:`pin_gap` call it.

    Returns (phi, converged, residual, s, nx, ny, dist2, cx, cy, d1x, d1y, d2x, d2y)
    at the LAST EVALUATED parameter phi (the next Newton step from it is below
    ``tol`` [rad] when converged, so phi is the foot point to O(tol)): the
    first-order residual |(P - C).C'|/|C'| [m], the signed distance s(P) = (P -
    C).n_out (> 0 outside, away from the disc centre) with the unit outward normal
    n_out = C'/|C'| turned by +90 deg (clockwise traversal), |P - C|^2, and C, C',
    C'' at phi (:func:`_center_curve_point`; the callers' curvature terms reuse them
    instead of evaluating the curve again)."""
    for _ in range(max_iter):
        cx, cy, d1x, d1y, d2x, d2y = _POINT(phi, z_rp, radius, eccentricity)
        rx, ry = px - cx, py - cy
        g1 = -(rx * d1x + ry * d1y)
        g2 = d1x * d1x + d1y * d1y - (rx * d2x + ry * d2y)
        if g2 > 0.0:
            step = -g1 / g2
        else:
            step = -np.sign(g1) * max_step
        step = min(max(step, -max_step), max_step)
        if abs(step) < tol:
            break
        phi = phi + step
    else:
        cx, cy, d1x, d1y, d2x, d2y = _POINT(phi, z_rp, radius, eccentricity)
        rx, ry = px - cx, py - cy
        step = np.inf
    inv = 1.0 / np.sqrt(d1x * d1x + d1y * d1y)
    nx, ny = -d1y * inv, d1x * inv
    residual = abs(rx * d1x + ry * d1y) * inv
    return phi, abs(step) < tol, residual, rx * nx + ry * ny, nx, ny, rx * rx + ry * ry, cx, cy, d1x, d1y, d2x, d2y


_NEWTON = _jit(_closest_point_newton)

#: relative positions of the cold starts within one lobe (fraction of the lobe angle)
_COLD_STARTS = np.linspace(-0.375, 0.375, 7)


def _foot_point(px, py, phi0, z_rp, radius, eccentricity, max_step, tol, max_iter, cos_half):
    """Foot point of P = (px, py) on C: Newton from the warm start ``phi0`` if it is
    finite, else (or if that fails or lands more than half a lobe from P's polar
    angle theta: a warm start from a far-away state, e.g. a diverging Newton trial,
    can reach another lobe's local minimum) from seven starts across the lobe
    around theta, keeping the nearest converged foot point. A start counts as
    converged when the step fell below ``tol`` or the first-order residual is below
    1e-12 m. Returns (phi, ok, s, nx, ny, d1x, d1y, d2x, d2y) (see
    :func:`_closest_point_newton`; C' and C'' at phi, NaN when not ok).

    The warm start's half-lobe test needs no arctangent: with theta = atan2(px,
    py), |phi - theta| (mod 2 pi) <= lobe/2 is cos(phi - theta) |P| = px sin(phi)
    + py cos(phi) >= cos(lobe/2) |P|, and sin(phi), cos(phi) follow from C and C'
    at phi: R (z - 1) sin(phi) = z cx + d1y, R (z - 1) cos(phi) = z cy - d1x (an
    arctangent per call would cost about 1.5 % of a rigid run); ``cos_half`` = cos(lobe/2)
    (:func:`closest_point_settings`)."""
    lobe = 2.0 * np.pi / (z_rp - 1)
    if np.isfinite(phi0):
        phi, conv, res, sd, nx, ny, _, cx, cy, d1x, d1y, d2x, d2y = _NEWTON(
            px, py, phi0, z_rp, radius, eccentricity, max_step, tol, max_iter
        )
        if conv or res <= 1e-12:
            along = px * (z_rp * cx + d1y) + py * (z_rp * cy - d1x)  # R (z - 1) |P| cos(phi - theta)
            if along >= cos_half * radius * (z_rp - 1) * np.sqrt(px * px + py * py):
                return phi, True, sd, nx, ny, d1x, d1y, d2x, d2y
    theta = np.arctan2(px, py)
    best = (theta, False, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan)
    best_d2 = np.inf
    for k in range(_COLD_STARTS.shape[0]):
        phi, conv, res, sd, nx, ny, d2, _, _, d1x, d1y, d2x, d2y = _NEWTON(
            px, py, theta + lobe * _COLD_STARTS[k], z_rp, radius, eccentricity, max_step, tol, max_iter
        )
        if (conv or res <= 1e-12) and d2 < best_d2:
            best, best_d2 = (phi, True, sd, nx, ny, d1x, d1y, d2x, d2y), d2
    return best


_FOOT = _jit(_foot_point)


def _pin_gap_kernel(px, py, phi0, z_rp, radius, eccentricity, max_step, tol, max_iter, cos_half, out):
    """Foot point, signed distance and outward normal of every point (flat
    arrays); out[0..3] = (s, nx, ny, phi). Returns the number of failures."""
    failed = 0
    for i in range(px.shape[0]):
        phi, ok, out[0, i], out[1, i], out[2, i], _, _, _, _ = _FOOT(
            px[i], py[i], phi0[i], z_rp, radius, eccentricity, max_step, tol, max_iter, cos_half
        )
        failed += not ok
        out[3, i] = phi
    return failed


_PIN_GAP = _jit(_pin_gap_kernel)


def pin_gap(
    points,
    z_rp: int,
    pin_circle_radius: float,
    pin_radius: float,
    eccentricity: float,
    d_radius: float = 0.0,
    d_pin_radius: float = 0.0,
    d_rotation: float = 0.0,
    phi0=None,
    tol: float = 1e-14,
    max_iter: int = 40,
):
    """Exact signed gap between pins and the modified cycloid-disc profile.

    The disc profile is the inward offset, by r_rp + dr_rp, of the pin-centre
    epitrochoid C(phi) on the shift-modified pin circle R_p + dR_p, turned by the
    rotation modification d_rotation (see module docstring). For a pin centre P the
    closest profile point lies on the common normal of the profile and of C (offset
    curves share normals), so with the foot point C(phi*) of P on C,

        gap = s(P) + (r_rp + dr_rp) - r_rp = s(P) + dr_rp,

    where s(P) = (P - C(phi*)) . n_out(phi*) is the signed distance of P from C
    (> 0 outside, away from the disc centre). Valid while the profile has no
    undercut (r_rp + dr_rp below the minimum convex curvature radius of C, which
    the design model checks). Sources: Litvin & Fuentes 2004, ch. 19 (envelope /
    offset of the pin-centre curve); closest point by Newton's method on
    g(phi) = |P - C(phi)|^2 / 2 (g' = -(P - C).C', g'' = |C'|^2 - (P - C).C'').

    Parameters
    ----------
    points : array_like (..., 2)
        Pin centres [m] in the disc frame.
    z_rp : int
        Number of pins.
    pin_circle_radius, pin_radius, eccentricity : float
        R_p, r_rp (actual pin radius) and a [m].
    d_radius, d_pin_radius, d_rotation : float
        Shift dR_p [m], equidistant dr_rp [m] and rotation [rad, counter-clockwise]
        modifications of the profile.
    phi0 : array_like (...), optional
        Warm start for the curve parameter (e.g. the ``phi`` of the previous call);
        without it several starts around the pin's polar angle are used.

    Returns
    -------
    gap : ndarray (...)
        Signed gap [m]: > 0 open, < 0 penetration.
    normal : ndarray (..., 2)
        Unit vector (disc frame) from the profile towards the pin centre: the
        direction of the contact force on the pin.
    phi : ndarray (...)
        Curve parameter of the closest point [rad].

    Raises
    ------
    ConvergenceError
        If the closest-point iteration does not converge.
    """
    from flexrv.errors import ConvergenceError, InputError

    p = np.asarray(points, dtype=float)
    if p.shape[-1] != 2:
        raise InputError(f"points must have shape (..., 2), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise InputError("points must be finite")
    if d_rotation:
        p = _rotate(p, -d_rotation)
    shape = p.shape[:-1]
    flat = np.ascontiguousarray(p.reshape(-1, 2))
    phi0 = (
        np.full(flat.shape[0], np.nan)
        if phi0 is None
        else np.ascontiguousarray(np.broadcast_to(np.asarray(phi0, dtype=float), shape)).ravel()
    )
    out = np.empty((4, flat.shape[0]))
    failed = _PIN_GAP(
        flat[:, 0].copy(),
        flat[:, 1].copy(),
        phi0,
        int(z_rp),
        float(pin_circle_radius + d_radius),
        float(eccentricity),
        *closest_point_settings(z_rp, pin_circle_radius, tol, max_iter),
        out,
    )
    if failed:
        raise ConvergenceError(
            f"pin_gap: closest-point iteration did not converge in {max_iter} iterations for {failed} point(s)"
        )
    gap = out[0].reshape(shape) + d_pin_radius
    n_out = np.stack([out[1], out[2]], axis=-1).reshape(shape + (2,))
    if d_rotation:
        n_out = _rotate(n_out, d_rotation)
    return gap, n_out, out[3].reshape(shape)


def closest_point_settings(z_rp: int, pin_circle_radius: float, tol: float = 1e-14, max_iter: int = 40):
    """(max_step [rad], tolerance [rad], max_iter, cos(lobe / 2)) of the closest-point Newton
    iteration: steps clipped to an eighth of a lobe, tolerance ``tol`` scaled by
    hypot(R_p, 1); the half lobe's cosine for the warm start's test (:func:`_foot_point`)."""
    lobe = 2.0 * np.pi / (z_rp - 1)
    return float(lobe / 8.0), float(tol * np.hypot(pin_circle_radius, 1.0)), int(max_iter), float(np.cos(0.5 * lobe))


# =========================================================================== curvature, arms, stiffness
def profile_curvature_radius(
    phi,
    z_rp: int,
    pin_circle_radius: float,
    pin_radius: float,
    eccentricity: float,
    d_radius: float = 0.0,
    d_pin_radius: float = 0.0,
):
    """Signed radius of curvature [m] of the actual (modified) disc profile at
    curve parameter phi: > 0 convex (tooth flank/tip bending towards the disc
    centre), < 0 concave (tooth space).

    rho_profile = 1/kappa_C - (r_rp + dr_rp), kappa_C the signed curvature of the
    pin-centre curve (:func:`center_curve_curvature`); offset curves share centres
    of curvature (Litvin & Fuentes 2004, ch. 6). Equal to the negative of :cite:`seed004`'s
    rho_i (:func:`seed004_curvature_radius`) at theta = z_c phi for an unmodified profile.
    """
    kappa = center_curve_curvature(phi, z_rp, pin_circle_radius + d_radius, eccentricity)
    with np.errstate(divide="ignore"):
        return 1.0 / kappa - (pin_radius + d_pin_radius)


def seed004_curvature_radius(theta, z_rp: int, pin_circle_radius: float, pin_radius: float, eccentricity: float):
    """:cite:`seed004`'s curvature radius of the cycloid profile [m] (negative = convex):

    rho = r_p (1 + K^2 - 2 K cos th)^(3/2) / (K (z_p + 1) cos th - (1 + z_p K^2)) + r_rp,
    K = a z_p / r_p, th the meshing phase angle (= z_c phi in this module's
    parametrisation; verified in tests/test_cycloid.py).
    """
    k = eccentricity * z_rp / pin_circle_radius
    th = np.asarray(theta, dtype=float)
    s3 = (1.0 + k * k - 2.0 * k * np.cos(th)) ** 1.5
    return pin_circle_radius * s3 / (k * (z_rp + 1) * np.cos(th) - (1.0 + z_rp * k * k)) + pin_radius


def moment_arm(phi_i, z_rp: int, pin_circle_radius: float, eccentricity: float):
    """Moment arm l_i [m] of pin i's ideal contact normal about the disc centre
    (:cite:`seed000`; Chen et al., standard cycloid-drive force analysis):

        l_i = r'_c sin(phi_i) / sqrt(1 + K^2 - 2 K cos(phi_i)),  r'_c = a z_c,
        K = a z_rp / R_p,

    phi_i [rad] being the angle of pin i from the eccentric (crank) direction,
    measured about the pin-wheel centre. The ideal normal passes through the pitch
    point, which lies at a z_c from the disc centre on the eccentric line.
    l_i peaks at r'_c for cos(phi_i) = K.
    """
    k = eccentricity * z_rp / pin_circle_radius
    phi_i = np.asarray(phi_i, dtype=float)
    return eccentricity * (z_rp - 1) * np.sin(phi_i) / np.sqrt(1.0 + k * k - 2.0 * k * np.cos(phi_i))


def pin_stiffness_seed000(width, e_eff):
    """:cite:`seed000`'s per-pin Hertz line-contact stiffness [N/m]:

    k_n = pi b E rho_r rho_c / (4 (1 - mu^2)(rho_r + rho_c) rho_i), rho_i = rho_r rho_c/(rho_r + rho_c),

    which SIMPLIFIES to pi b E / (4 (1 - mu^2)): the curvatures cancel. Written
    with Hamrock's effective modulus E' (= E/(1 - mu^2) for equal materials) it is
    pi b E' / 4, which also covers disc and pin of different steels. It is a
    load- and curvature-independent linear surrogate; the physical 2-D Hertz
    approach is nonlinear in the load (Palmgren: delta ~ Q^0.9, see
    :func:`flexrv.contact.hertz.line_contact_stiffness`).

    Parameters
    ----------
    width : disc width b [m]; e_eff : effective modulus E' [Pa].
    """
    return np.pi * np.asarray(width, dtype=float) * np.asarray(e_eff, dtype=float) / 4.0


def pin_stiffness_seed004(rho, pin_radius: float, width, e_eff):
    """:cite:`seed004`'s per-pin stiffness K_cj [N/m] with rho from
    :func:`seed004_curvature_radius` (rho < 0 convex):

    K_cj = pi b E |rho| (rho - r_rp) / (4 rho (1 - mu^2)(r_rp + |rho|)), E/(1-mu^2) -> E'.

    On the convex (working) flank this equals pi b E'/4 (:cite:`seed000`); on the
    concave part it is reduced by (rho - r_rp)/(rho + r_rp), and it vanishes
    where the pin-centre curve has an inflection (rho = r_rp).
    """
    rho = np.asarray(rho, dtype=float)
    return (
        np.pi
        * np.asarray(width)
        * np.asarray(e_eff)
        * np.abs(rho)
        * (rho - pin_radius)
        / (4.0 * rho * (pin_radius + np.abs(rho)))
    )


def k34(pin_stiffness, arms, engaged=None):
    """Torsional mesh stiffness of one disc about its centre [N m/rad] (:cite:`seed000`):
    k34 = sum over engaged pins of k_n,i l_i^2."""
    k = np.asarray(pin_stiffness, dtype=float) * np.asarray(arms, dtype=float) ** 2
    if engaged is not None:
        k = np.where(engaged, k, 0.0)
    return np.sum(k, axis=-1)
