"""EHL-corrected normal contact laws (ball–raceway point contact, roller/pin line contact).

Model
-----
A lubricated rolling contact carries load through an oil film of central
thickness h_c(Q, u) in series with the Hertzian elastic approach s of the two
bodies. With the geometric approach delta (> 0: the dry bodies would overlap,
measured exactly as for the dry law) the bodies' elastic approach is
s = delta + h_c(Q, u), and

    Q = K s^n,   s = delta + h_c(Q, u),    (n = 3/2 point contact, 10/9 line contact)

so load starts at delta = -h_c, *before* dry contact, and the law tends to dry
Hertz when u -> 0 or h_c << delta. The implicit relation is solved per contact by
Newton's method on phi(s) = s - delta - h_c(K s^n) = 0 (vectorised, fixed number of
steps from s0 = max(delta + h_c(Q_floor), 0)); because h_c decreases with load
phi' = 1 - (n h_c/s) d ln h_c/d ln Q >= 1, so the root is unique, the force is
continuous and monotone in delta, and dQ/ddelta = n K s^(n-1) / phi'(s).

Film h_c(Q, u) by ``mode``:

* ``"dry"`` — h_c = 0 (plain Hertz, :cite:`harris2007` eq. 6.42);
* ``"hamrock_dowson"`` — Hamrock & Dowson :cite:`hamrock1977` central film for point contacts,
  Pan & Hamrock :cite:`pan1989` for line contacts (:mod:`flexrv.ehl.film`);
* ``"map"`` — the numerical solver's h_c(Q, u) table (:mod:`flexrv.ehl.maps`),
  interpolated in log space by the map's one compiled function
  (:func:`flexrv.ehl.maps.packed_log_correction`, also called by the bearing row
  kernel; point contacts only).

Below the load floor ``load_floor`` the film is frozen at h_c(load_floor): the
steady EHL formulas diverge as Q^-0.067 for Q -> 0, which would make the law reach
out to infinite separation. With the floor, Q = 0 exactly for
delta <= -h_c(load_floor) and the law stays C0 there.

Damping: the seeds' impact-law damper (flexrv.contact.laws) acting on the elastic
approach, F_d = c_max step(s, 0, 0, d, 1) d(delta)/dt, i.e. it ramps in from the
film onset. It stands for the film-squeeze and material damping of the contact
lumped into one coefficient; it is *not* derived from the transient Reynolds
equation.

Limits: quasi-static film (the steady EHL h_c at the instantaneous load and speed,
no squeeze-film history), isothermal, fully flooded, smooth surfaces. Real EHL
films are 0.01-1 um; the "oil film 0.01-0.18 mm" of :cite:`seed000,seed001` is not an EHL
film and is not used. The film offset matters for the bearing's stiffness and
clearance at the 0.1 um level, not for its load capacity.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from flexrv.contact.hertz import line_contact_stiffness, point_contact_stiffness
from flexrv.contact.laws import adams_step, adams_step_derivative
from flexrv.ehl.film import HAMROCK_DOWSON_LOAD_EXPONENT, PAN_HAMROCK_LOAD_EXPONENT, hamrock_dowson, pan_hamrock_line
from flexrv.errors import InputError
from flexrv.units import M_PER_MM

MODES = ("dry", "hamrock_dowson", "map")


@dataclass(frozen=True)
class EHLForce:
    """Result of an EHL law evaluation (arrays of the broadcast input shape).

    Attributes
    ----------
    force : compressive normal force [N] (>= 0).
    dforce_ddelta : dF/d delta [N/m].
    dforce_ddelta_rate : dF/d(d delta/dt) [N s/m].
    film : central film h_c [m] used (0 where out of contact or dry).
    elastic_approach : s = delta + h_c [m].
    """

    force: np.ndarray
    dforce_ddelta: np.ndarray
    dforce_ddelta_rate: np.ndarray
    film: np.ndarray
    elastic_approach: np.ndarray


FilmFunction = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def _solve(delta, delta_rate, k, n, film: Optional[FilmFunction], load_floor, c_max, depth, iterations):
    """Newton solve of Q = K (delta + h(Q))^n and the force derivatives (see module docstring).

    ``film(Q)`` returns (h [m], d ln h / d ln Q) for Q >= load_floor at the current
    speeds (bound by the caller).
    """
    delta = np.asarray(delta, dtype=float)
    delta_rate = np.asarray(delta_rate, dtype=float)
    if film is None:
        s = np.maximum(delta, 0.0)
        h = np.zeros(delta.shape)
        dphi = 1.0
    else:
        h_floor, _ = film(np.float64(load_floor))
        s = np.maximum(delta + h_floor, 0.0)
        tiny = 1e-300
        for it in range(iterations + 1):
            q = k * s**n
            above = q > load_floor
            h, slope = film(np.maximum(q, load_floor))
            # dphi/ds = 1 - dh/ds, dh/ds = n (d ln h/d ln Q) h / s  (>= 1 for slope <= 0)
            dphi = np.maximum(1.0 - np.where(above, n * slope * h / np.maximum(s, tiny), 0.0), 1e-3)
            if it == iterations:
                break
            s = np.maximum(s - (s - delta - h) / dphi, 0.0)
    contact = s > 0
    sn1 = s ** (n - 1.0)
    spring = k * sn1 * s
    dspring = n * k * sn1 / dphi
    if c_max > 0:
        c = c_max * adams_step(s, 0.0, 0.0, depth, 1.0)
        dc = c_max * adams_step_derivative(s, 0.0, 0.0, depth, 1.0) / dphi
        force = spring + c * delta_rate
        dforce = dspring + dc * delta_rate
    else:
        c = np.zeros(s.shape)
        force, dforce = spring, dspring
    active = contact & (force > 0)
    return EHLForce(
        force=np.where(active, force, 0.0),
        dforce_ddelta=np.where(active, dforce, 0.0),
        dforce_ddelta_rate=np.where(active, c, 0.0),
        film=np.where(contact, h, 0.0),
        elastic_approach=s,
    )


def _check_mode(mode, lubricant, film_map):
    if mode not in MODES:
        raise InputError(f"EHL mode must be one of {MODES}, got {mode!r}")
    if mode != "dry" and lubricant is None:
        raise InputError(f"EHL mode {mode!r} needs a lubricant with pressure-viscosity data")
    if mode == "map" and film_map is None:
        raise InputError("EHL mode 'map' needs a film_map (flexrv.ehl.maps.film_map)")
    if lubricant is not None:
        lubricant.check()


@dataclass(frozen=True)
class EHLPointLaw:
    """EHL-corrected ball–raceway law Q(delta, delta_rate, u), vectorised over contacts.

    Parameters
    ----------
    rx, ry : effective radii [m] (scalars or one per contact).
    e_eff : effective modulus E' [Pa].
    lubricant : :class:`flexrv.ehl.solver.LubricantProperties` (not needed for ``"dry"``).
    mode : ``"dry"``, ``"hamrock_dowson"`` or ``"map"``.
    film_map : :class:`flexrv.ehl.maps.FilmMap` of the same geometry (``"map"`` only).
    c_max : damping coefficient [N s/m]; damping_depth : ramp depth d [m].
    load_floor : load [N] below which the film is frozen (see module docstring).
    iterations : Newton steps (4 reach machine precision from the start value in the tests).

    Examples
    --------
    Dry, the law is Hertz's Q = K delta^1.5; lubricated, the film carries load before the dry
    bodies touch (delta = 0):

    >>> from flexrv.ehl.solver import LubricantProperties
    >>> dry = EHLPointLaw(5e-3, 50e-3, 2.3e11, mode="dry")       # rx, ry [m], E' [Pa]
    >>> bool(np.isclose(dry(1e-6, 0.0, 1.0).force, dry.stiffness * 1e-6**1.5))
    True
    >>> oil = LubricantProperties(viscosity=0.1, pressure_viscosity=2e-8, roelands_z=0.6,
    ...                           roelands_p0=1.96e8, density=870.0)
    >>> wet = EHLPointLaw(5e-3, 50e-3, 2.3e11, oil, mode="hamrock_dowson")
    >>> out = wet(0.0, 0.0, 1.0)                                 # delta, its rate, entrainment speed
    >>> round(float(out.film) * 1e6, 2), bool(out.force > 0)     # central film [um], load carried
    (0.52, True)
    """

    rx: object
    ry: object
    e_eff: object
    lubricant: object = None
    mode: str = "hamrock_dowson"
    film_map: object = None
    c_max: float = 0.0
    damping_depth: float = 1e-6
    load_floor: float = 1.0
    iterations: int = 5

    def __post_init__(self):
        _check_mode(self.mode, self.lubricant, self.film_map)
        if not (self.load_floor > 0 and self.damping_depth > 0 and self.c_max >= 0):
            raise InputError(
                f"load_floor ({self.load_floor}) and damping_depth ({self.damping_depth}) must be > 0, "
                f"c_max ({self.c_max}) >= 0"
            )
        object.__setattr__(self, "_k", point_contact_stiffness(self.rx, self.ry, self.e_eff))
        if self.mode != "dry":
            lub = self.lubricant
            h1, _ = hamrock_dowson(1.0, 1.0, self.rx, self.ry, self.e_eff, lub.viscosity, lub.pressure_viscosity)
            object.__setattr__(self, "_h_unit", np.asarray(h1))  # h_HD at Q = 1 N, u = 1 m/s

    @classmethod
    def from_design(
        cls,
        reducer,
        rx,
        ry,
        *,
        mode: Optional[str] = None,
        load_range=(5.0, 2000.0),
        speed_range=(0.005, 0.5),
        map_grid: int = 129,
    ) -> "EHLPointLaw":
        """Law for the main-bearing ball contacts of a :class:`flexrv.design.model.Reducer`.

        E' from the ``rolling_elements`` and ``bearing_rings`` materials, lubricant from
        ``reducer.lubricant``, c_max = ``main_bearing.ball_damping_Ns_per_m``, damping depth
        ``contact.impact_damping_depth_mm``, mode ``contact.ehl`` unless given. For
        ``"map"`` (scalar rx, ry only) the solver map over ``load_range`` [N] x
        ``speed_range`` [m/s] is built once and cached (:func:`flexrv.ehl.maps.film_map`).
        """
        from flexrv.contact.hertz import effective_modulus
        from flexrv.ehl.solver import LubricantProperties

        ball, ring = reducer.material("rolling_elements"), reducer.material("bearing_rings")
        e_eff = float(
            effective_modulus(ball.youngs_modulus, ball.poisson_ratio, ring.youngs_modulus, ring.poisson_ratio)
        )
        lub = LubricantProperties.from_design(reducer.lubricant)
        mode = reducer.contact.ehl if mode is None else mode
        fmap = None
        if mode == "map":
            if np.size(rx) != 1 or np.size(ry) != 1:
                raise InputError(
                    "EHL mode 'map' needs one contact geometry (scalar rx, ry); "
                    f"got shapes {np.shape(rx)}, {np.shape(ry)}"
                )
            from flexrv.ehl.maps import film_map

            fmap = film_map(float(rx), float(ry), e_eff, lub, load_range, speed_range, grid=map_grid)
        return cls(
            rx,
            ry,
            e_eff,
            lub,
            mode=mode,
            film_map=fmap,
            c_max=reducer.main_bearing.ball_damping_Ns_per_m,
            damping_depth=reducer.contact.impact_damping_depth_mm * M_PER_MM,
        )

    @property
    def stiffness(self):
        """Hertz constant K [N/m^1.5] of each contact."""
        return self._k

    def film(self, load, speed):
        """Central film h_c [m] and d ln h_c / d ln Q at load [N] (>= load_floor), speed [m/s]."""
        load = np.asarray(load, dtype=float)
        speed = np.asarray(speed, dtype=float)
        if self.mode == "dry":
            return np.zeros(np.broadcast(load, speed).shape), np.zeros(np.broadcast(load, speed).shape)
        # Hamrock-Dowson is a pure power law: h = h(1 N, 1 m/s) Q^-0.067 u^0.67
        h = self._h_unit * load**HAMROCK_DOWSON_LOAD_EXPONENT * speed**0.67
        slope = np.full(h.shape, HAMROCK_DOWSON_LOAD_EXPONENT)
        if self.mode == "map":
            c, dc = self.film_map.log_correction(load, np.maximum(speed, 1e-300))
            h = h * np.exp(c)
            slope = slope + dc
        return h, slope

    def __call__(self, delta, delta_rate, speed) -> EHLForce:
        """Normal force and derivatives for approach delta [m] (> 0 dry overlap), its rate
        [m/s] and the mean entrainment speed [m/s]."""
        speed = np.abs(np.asarray(speed, dtype=float))
        film = None
        if self.mode == "hamrock_dowson":
            hu = self._h_unit * speed**0.67

            def film(q, hu=hu):
                return hu * q**HAMROCK_DOWSON_LOAD_EXPONENT, HAMROCK_DOWSON_LOAD_EXPONENT
        elif self.mode == "map":
            hu = self._h_unit * speed**0.67
            speed_c = np.maximum(speed, 1e-300)

            def film(q, hu=hu):
                c, dc = self.film_map.log_correction(q, speed_c)
                return hu * q**HAMROCK_DOWSON_LOAD_EXPONENT * np.exp(c), HAMROCK_DOWSON_LOAD_EXPONENT + dc

        return _solve(
            delta, delta_rate, self._k, 1.5, film, self.load_floor, self.c_max, self.damping_depth, self.iterations
        )

    def normal_law(self, speed):
        """Adapter to the ``NormalLaw`` signature of :mod:`flexrv.contact.ball_raceway`:
        (delta, delta_rate) -> (Q, dQ/ddelta, dQ/ddelta_rate) at a fixed entrainment speed."""

        def law(delta, delta_rate):
            out = self(delta, delta_rate, speed)
            return out.force, out.dforce_ddelta, out.dforce_ddelta_rate

        return law


@dataclass(frozen=True)
class EHLLineLaw:
    """EHL-corrected line-contact law (rollers, pins): Q = K s^(10/9), s = delta + h_c.

    K from Palmgren's line-contact law (:func:`flexrv.contact.hertz.line_contact_stiffness`),
    h_c from Pan & Hamrock :cite:`pan1989`. Modes ``"dry"`` and ``"hamrock_dowson"`` (the latter
    meaning the Pan–Hamrock line-contact formula here); no solver map for line contacts.

    Parameters
    ----------
    length : contact length [m]; r_eff : reduced radius R [m] in the rolling direction;
    e_eff : E' [Pa]; lubricant, mode, c_max, damping_depth, load_floor, iterations as in
    :class:`EHLPointLaw`.
    """

    length: object
    r_eff: object
    e_eff: object
    lubricant: object = None
    mode: str = "hamrock_dowson"
    c_max: float = 0.0
    damping_depth: float = 1e-6
    load_floor: float = 1.0
    iterations: int = 5

    def __post_init__(self):
        if self.mode == "map":
            raise InputError("EHL mode 'map' is available for point contacts only; use 'hamrock_dowson' for lines")
        _check_mode(self.mode, self.lubricant, None)
        if not (self.load_floor > 0 and self.damping_depth > 0 and self.c_max >= 0):
            raise InputError(
                f"load_floor ({self.load_floor}) and damping_depth ({self.damping_depth}) must be > 0, "
                f"c_max ({self.c_max}) >= 0"
            )
        object.__setattr__(self, "_k", line_contact_stiffness(self.length, self.e_eff))
        if self.mode != "dry":
            lub = self.lubricant
            h1, _ = pan_hamrock_line(
                1.0, self.length, 1.0, self.r_eff, self.e_eff, lub.viscosity, lub.pressure_viscosity
            )
            object.__setattr__(self, "_h_unit", np.asarray(h1))

    @property
    def stiffness(self):
        """Palmgren constant K [N/m^(10/9)]."""
        return self._k

    def film(self, load, speed):
        """Pan–Hamrock h_c [m] and d ln h_c / d ln Q (pure power law in Q and u)."""
        load = np.asarray(load, dtype=float)
        h = self._h_unit * load**PAN_HAMROCK_LOAD_EXPONENT * np.asarray(speed, dtype=float) ** 0.692
        return h, np.full(h.shape, PAN_HAMROCK_LOAD_EXPONENT)

    def __call__(self, delta, delta_rate, speed) -> EHLForce:
        speed = np.abs(np.asarray(speed, dtype=float))
        film = None
        if self.mode != "dry":
            hu = self._h_unit * speed**0.692

            def film(q, hu=hu):
                return hu * q**PAN_HAMROCK_LOAD_EXPONENT, PAN_HAMROCK_LOAD_EXPONENT

        return _solve(
            delta,
            delta_rate,
            self._k,
            10.0 / 9.0,
            film,
            self.load_floor,
            self.c_max,
            self.damping_depth,
            self.iterations,
        )
