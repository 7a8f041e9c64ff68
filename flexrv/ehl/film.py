"""Closed-form film-thickness formulas of isothermal, fully flooded EHL point contacts.

All functions are vectorised over numpy arrays and use SI units. Conventions
(:cite:`hamrock1994`, ch. 22; :cite:`hamrock1981`):

* x is the entrainment (rolling) direction, ``rx`` the effective radius in x and
  ``ry`` in y; the formulas are fitted for ry >= rx (entrainment along the minor
  axis of the contact ellipse, the ball-bearing case);
* ``speed`` is the *mean* entrainment speed u = (u1 + u2)/2 [m/s];
* E' = 2 / ((1-nu1^2)/E1 + (1-nu2^2)/E2) (Hamrock's effective modulus,
  :func:`flexrv.contact.hertz.effective_modulus`).

Orders of magnitude: EHL films of rolling bearings are 0.01-1 um. The
"film thickness 0.01-0.18 mm" quoted in :cite:`seed000,seed001` is not an EHL film (it is
three orders of magnitude too large for a loaded ball-raceway contact); it is not
used anywhere in flexrv.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.errors import InputError


def _positive(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"{name} must be finite and > 0, got {value!r}")
    return arr


@dataclass(frozen=True)
class DimensionlessGroups:
    """Dimensionless EHL groups of a point contact (arrays).

    Attributes
    ----------
    speed_u : U = eta0 u / (E' rx) (Hamrock; u = mean entrainment speed).
    material_g : G = alpha E'.
    load_w : W = Q / (E' rx^2).
    moes_m : M = W (2U)^(-3/4) (Moes; 2U uses the sum speed u1 + u2).
    moes_l : L = G (2U)^(1/4).
    ellipticity : k = a/b, exact (elliptic integrals, :func:`ellipticity`); 1 for ry = rx.
    """

    speed_u: np.ndarray
    material_g: np.ndarray
    load_w: np.ndarray
    moes_m: np.ndarray
    moes_l: np.ndarray
    ellipticity: np.ndarray


def ellipticity(rx, ry):
    """Exact Hertz ellipticity k = a/b [-] of the contact of principal radii rx (along the
    entrainment) and ry (across), from the complete elliptic integrals (one executor:
    :func:`flexrv.contact.hertz.point_contact`, whose ellipticity does not depend on load or
    modulus). k = 1 for a circular contact (ry = rx); k < 1 for rx > ry.

    This is the k of the Hamrock–Dowson formulas: their own curve fit k ~ 1.0339 (ry/rx)^0.636
    (:func:`ellipticity_approx`) gives 1.0339 for a circular contact, +1.0 % on h_c and +2.3 %
    on h_min there.
    """
    from flexrv.contact.hertz import point_contact

    rx = np.asarray(rx, dtype=float)
    ry = np.asarray(ry, dtype=float)
    return np.asarray(point_contact(np.ones(np.broadcast(rx, ry).shape), rx, ry, 1.0).ellipticity, dtype=float)


def ellipticity_approx(rx, ry):
    """Ellipticity k = a/b ~ 1.0339 (ry/rx)^0.636 (:cite:`hamrock1983`; :cite:`hamrock1994`, eq. 17.17).

    Within 3.4 % of the exact value for 1 <= ry/rx <= 30 (6 % at 100), but 1.0339 instead of 1 for
    a circular contact; flexrv uses the exact :func:`ellipticity` (kept for comparison only).
    """
    return 1.0339 * (np.asarray(ry, dtype=float) / np.asarray(rx, dtype=float)) ** 0.636


def dimensionless_groups(load, speed, rx, ry, e_eff, viscosity, pressure_viscosity) -> DimensionlessGroups:
    """Hamrock's U, G, W and Moes' M, L of a point contact.

    Parameters
    ----------
    load : normal load Q [N] (> 0).
    speed : mean entrainment speed u [m/s] (> 0).
    rx, ry : effective radii [m] in and across the entrainment direction.
    e_eff : effective modulus E' [Pa].
    viscosity : ambient viscosity eta0 [Pa s].
    pressure_viscosity : Barus pressure-viscosity coefficient alpha [1/Pa].
    """
    load = _positive("load", load)
    speed = _positive("speed", speed)
    rx = _positive("rx", rx)
    ry = _positive("ry", ry)
    e_eff = _positive("e_eff", e_eff)
    viscosity = _positive("viscosity", viscosity)
    alpha = _positive("pressure_viscosity", pressure_viscosity)
    u = viscosity * speed / (e_eff * rx)
    g = alpha * e_eff
    w = load / (e_eff * rx**2)
    return DimensionlessGroups(
        speed_u=u,
        material_g=g,
        load_w=w,
        moes_m=w * (2.0 * u) ** -0.75,
        moes_l=g * (2.0 * u) ** 0.25,
        ellipticity=ellipticity(rx, ry),
    )


def hamrock_dowson(load, speed, rx, ry, e_eff, viscosity, pressure_viscosity, ellipticity=None):
    """Hamrock–Dowson central and minimum film thickness [m] :cite:`hamrock1977`.

    h_c / rx   = 2.69 U^0.67 G^0.53 W^-0.067 (1 - 0.61 exp(-0.73 k)),
    h_min / rx = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k))

    (:cite:`hamrock1977`; :cite:`hamrock1994`, eqs.
    22.18-22.19). Fitted for 1 <= k <= 8, 0.3e-11 < U < 1e-10 (roughly), G ~ 2500-5000
    and W up to ~1e-4, i.e. the piezoviscous-elastic regime; outside it the formula
    is an extrapolation.

    Parameters
    ----------
    load, speed, rx, ry, e_eff, viscosity, pressure_viscosity :
        as in :func:`dimensionless_groups`.
    ellipticity : array_like, optional
        k = a/b; default the exact Hertz ellipticity (:func:`ellipticity`; k = 1 for ry = rx).
        Hamrock & Dowson evaluate k from a curve fit, 1.03 (ry/rx)^0.64, which is 1.03 instead
        of 1 for a circular contact; with the exact k the circular films are
        h_c = 2.69 U^0.67 G^0.53 W^-0.067 (1 - 0.61 e^-0.73) rx and
        h_min = 3.63 U^0.68 G^0.49 W^-0.073 (1 - e^-0.68) rx (tests/test_ehl_film.py).

    Returns
    -------
    h_central, h_min : ndarray [m]
    """
    grp = dimensionless_groups(load, speed, rx, ry, e_eff, viscosity, pressure_viscosity)
    k = grp.ellipticity if ellipticity is None else np.asarray(ellipticity, dtype=float)
    u, g, w = grp.speed_u, grp.material_g, grp.load_w
    rx = np.asarray(rx, dtype=float)
    h_c = 2.69 * u**0.67 * g**0.53 * w**-0.067 * (1.0 - 0.61 * np.exp(-0.73 * k)) * rx
    h_m = 3.63 * u**0.68 * g**0.49 * w**-0.073 * (1.0 - np.exp(-0.68 * k)) * rx
    return h_c, h_m


def moes_asymptotes(moes_m, moes_l, curvature_ratio):
    """The four asymptotic central films of Nijenbanning, Venner & Moes :cite:`nijenbanning1994` (dimensionless).

    With lambda = rx/ry (<= 1 for entrainment along the minor axis of the contact ellipse),
    H = h_c/rx (2U)^-1/2, M = W (2U)^-3/4, L = G (2U)^1/4 (U, W, G of Hamrock, 2U uses the
    sum speed u1 + u2), :cite:`nijenbanning1994`, eqs. (5)-(8):

    * rigid-isoviscous     H_RI = 145 (1 + 0.796 lambda^(14/15))^(-15/7) lambda^-1 M^-2,
    * elastic-isoviscous   H_EI = 3.18 (1 + 0.006 ln lambda + 0.63 lambda^(4/7))^(-14/25) lambda^(-1/15) M^(-2/15),
    * rigid-piezoviscous   H_RP = 1.29 (1 + 0.691 lambda)^(-2/3) L^(2/3),
    * elastic-piezoviscous H_EP = 1.48 (1 + 0.006 ln lambda + 0.63 lambda^(4/7))^(-7/20) lambda^(-1/24)
      M^(-1/12) L^(3/4).

    Parameters
    ----------
    moes_m, moes_l : Moes load and material parameters M, L [-] (> 0, L >= 0).
    curvature_ratio : lambda = rx/ry [-] (> 0).

    Returns
    -------
    h_ri, h_ei, h_rp, h_ep : ndarray (dimensionless, Moes scaling)
    """
    m = np.asarray(moes_m, dtype=float)
    el = np.asarray(moes_l, dtype=float)
    lam = np.asarray(curvature_ratio, dtype=float)
    shape = 1.0 + 0.006 * np.log(lam) + 0.63 * lam ** (4.0 / 7.0)
    h_ri = 145.0 * (1.0 + 0.796 * lam ** (14.0 / 15.0)) ** (-15.0 / 7.0) / lam * m**-2.0
    h_ei = 3.18 * shape ** (-14.0 / 25.0) * lam ** (-1.0 / 15.0) * m ** (-2.0 / 15.0)
    h_rp = 1.29 * (1.0 + 0.691 * lam) ** (-2.0 / 3.0) * el ** (2.0 / 3.0)
    h_ep = 1.48 * shape ** (-7.0 / 20.0) * lam ** (-1.0 / 24.0) * m ** (-1.0 / 12.0) * el**0.75
    return h_ri, h_ei, h_rp, h_ep


def moes_dimensionless(moes_m, moes_l, curvature_ratio):
    """Dimensionless central film H = h_c/rx (2U)^-1/2 of Nijenbanning, Venner & Moes :cite:`nijenbanning1994`.

    Blend of the asymptotes of :func:`moes_asymptotes` (:cite:`nijenbanning1994`,
    eqs. (9)-(10)):

        H = { [H_RI^(3/2) + (H_EI^-4 + H_00^-4)^(-3/8)]^(2s/3) + (H_RP^-8 + H_EP^-8)^(-s/8) }^(1/s),
        s = 1.5 (1 + exp(-1.2 H_EI/H_RI)),   H_00 = 1.8 lambda^-1.

    Limits (tests/test_ehl_film.py): L -> 0 gives (H_RI^(3/2) + H_EI^(3/2))^(2/3) (H_RI at light
    load, H_EI at heavy load); large L gives min(H_RP, H_EP) (H_RP at light, H_EP at heavy load).
    H_00 = 1.8/lambda only caps H_EI at extremely light loads (a constant cap such as 0.1
    would make the elastic-isoviscous asymptote unreachable).
    """
    h_ri, h_ei, h_rp, h_ep = moes_asymptotes(moes_m, moes_l, curvature_ratio)
    lam = np.asarray(curvature_ratio, dtype=float)
    h_00 = 1.8 / lam
    with np.errstate(divide="ignore", over="ignore"):
        s = 1.5 * (1.0 + np.exp(-1.2 * h_ei / h_ri))
        iso = (h_ri**1.5 + (h_ei**-4.0 + h_00**-4.0) ** -0.375) ** (2.0 * s / 3.0)
        piezo = (h_rp**-8.0 + h_ep**-8.0) ** (-s / 8.0)
    return (iso + piezo) ** (1.0 / s)


def moes_central(load, speed, rx, ry, e_eff, viscosity, pressure_viscosity):
    """Central film thickness [m] from the Nijenbanning–Venner–Moes formula :cite:`nijenbanning1994`.

    h_c = H(M, L, lambda) rx (2U)^(1/2) with H of :func:`moes_dimensionless`,
    lambda = rx/ry (:cite:`nijenbanning1994`; the circular case lambda = 1 is the point-contact
    formula quoted in :cite:`venner2000`).

    Unlike Hamrock–Dowson it bridges all four regimes (rigid/elastic x
    isoviscous/piezoviscous). Verification status (tests/test_ehl_film.py,
    tests/test_ehl_solver.py): asymptotic limits exact; in the piezoviscous-elastic
    regime (M >= 30, L ~ 6-14, lambda = 0.036-1) within ~15 % of Hamrock–Dowson. Against
    the numerical solver run like the formula's basis (incompressible, with
    ``pressure_viscosity`` = the Roelands alpha z (ln eta0 + 9.67)/p0 in L): -5.3 %..+0.1 %;
    the solver's Dowson–Higginson compressibility lowers h_c by a further 14-18 %
    (tests/test_ehl_convergence.py). For very elongated contacts (lambda < 0.1) the fit is
    an extrapolation (the paper's data cover lambda >= ~0.1); prefer the numerical
    solver (:func:`flexrv.ehl.solver.solve_point_contact`) there.
    """
    grp = dimensionless_groups(load, speed, rx, ry, e_eff, viscosity, pressure_viscosity)
    lam = np.asarray(rx, dtype=float) / np.asarray(ry, dtype=float)
    h = moes_dimensionless(grp.moes_m, grp.moes_l, lam)
    return h * np.asarray(rx, dtype=float) * np.sqrt(2.0 * grp.speed_u)


def pan_hamrock_line(load, length, speed, r_eff, e_eff, viscosity, pressure_viscosity):
    """Pan & Hamrock central and minimum film of an EHL line contact [m] :cite:`pan1989`.

    h_c / R   = 2.922 W'^-0.166 U^0.692 G^0.470,
    h_min / R = 1.714 W'^-0.128 U^0.694 G^0.568,
    W' = w / (E' R L) (load per unit length), U = eta0 u / (E' R), G = alpha E'
    (:cite:`pan1989`; :cite:`hamrock1994`, eqs. 21.60-21.61).

    Parameters
    ----------
    load : normal load w [N] (> 0); length : contact length L [m];
    speed : mean entrainment speed u [m/s]; r_eff : reduced radius R [m];
    e_eff : E' [Pa]; viscosity : eta0 [Pa s]; pressure_viscosity : alpha [1/Pa].

    Returns
    -------
    h_central, h_min : ndarray [m]
    """
    load = _positive("load", load)
    length = _positive("length", length)
    speed = _positive("speed", speed)
    r_eff = _positive("r_eff", r_eff)
    e_eff = _positive("e_eff", e_eff)
    viscosity = _positive("viscosity", viscosity)
    alpha = _positive("pressure_viscosity", pressure_viscosity)
    w = load / (e_eff * r_eff * length)
    u = viscosity * speed / (e_eff * r_eff)
    g = alpha * e_eff
    return (2.922 * w**-0.166 * u**0.692 * g**0.470 * r_eff, 1.714 * w**-0.128 * u**0.694 * g**0.568 * r_eff)


#: d ln h_c / d ln w of :func:`pan_hamrock_line`.
PAN_HAMROCK_LOAD_EXPONENT = -0.166
#: d ln h_c / d ln Q of :func:`hamrock_dowson`.
HAMROCK_DOWSON_LOAD_EXPONENT = -0.067
