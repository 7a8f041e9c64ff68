"""Compliances of the torque path between the planet gears and the output that the element
laws of the models do not contain by themselves, each a closed form referred to the output
[rad/(N m)]. One formula, one executor: the analytic budget lists them as elements
(:func:`output_compliances`) and the models carry them at their physical places
(:func:`model_compliances`, called by :func:`flexrv.model.cranks_discs.crank_support_parameters`):

* the crank torsion and the planet spline, a torsional compliance c_t per crank between the
  planet gear and the crank's eccentrics, sit in series with each planet's mesh
  (:mod:`flexrv.model.gear_stage`): the spline and the crank turn the planet by c_t F r_bp
  relative to the eccentrics under the mesh force F on the base radius r_bp, which moves the
  mesh point by c_t r_bp^2 F along the line of action, so the mesh stiffness k becomes
  k_eff = 1 / (1/k + c_t r_bp^2);
* the support-bearing rings, a radial compliance c_r / 2 per crank (two bearings in
  parallel), and the carrier joints, an output torsion c_T, enter the (2N, 2N) compliance of
  the cranks' support points in the carrier (:mod:`flexrv.model.cranks_discs`, "Carrier"): the
  rings on its diagonal (a linear series spring; the condensed equilibrium of the supports
  solves it exactly), the joints as the rank-one term c_T g g^T with g_j = (-y_j, x_j) the map
  from the support forces to the torque about the axis (T = g . f). Under any support forces
  the rank-one term moves the support points by c_T T g, a rigid turn of c_T T: a pure output
  torque sees exactly c_T. With a rigid carrier the same matrix is the support points'
  compliance.

Referred to the output, a compliance c of each crank's rotation relative to its planet is
c / (N i_c^2) with i_c = z_rp + z_s / z_p the crank's turn relative to its planet per output
turn (input held: the planet turns by (1 + z_s / z_p) and the crank by -z_c per output turn,
:mod:`flexrv.geometry.kinematics`). A mesh compliance s along the line of action carries the
mesh force F = T / (N i r_bs) (i = 1 + z_p z_rp / z_s the reducer's ratio, i r_bs = i_c r_bp)
and gives s / (N i_c^2 r_bp^2) at the output: s = c_t r_bp^2 gives c_t / (N i_c^2), the same.

* ``crank_torsion``: St. Venant torsion of each crank between its planet spline and its
  eccentrics. The crank torque is M_c = T / (N i_c) (virtual work: with the input held, an
  eccentric turned by Delta relative to its planet turns the output by Delta / i_c, above;
  i_c is z_rp, the second stage's ratio of crank rotation relative to the carrier to carrier
  rotation, plus the first stage's z_s / z_p). Energy-equivalent length of the
  stepped shaft, torque profile m(x) = M(x)/M_c: the spline feeds it in uniformly over the
  gear seat (int (x/L)^2 = L/3), the support journal carries it whole, the two eccentrics
  take half each, uniformly (7 L_e / 12 and L_e / 12):
  c_crank = (1/G) [L_s / (3 J_s) + L_a / J_a + 2 L_e / (3 J_e)], J = pi d^4 / 32
  :cite:`timoshenko1970`; each eccentric journal twists about its own centroid (the offset
  adds bending, not twist). At the output: c = c_crank / (N i_c^2).
* ``planet_spline``: the N splines with z_sp teeth, a fraction f engaged, each engaged tooth
  pair of stiffness c' per unit face width (ISO 6336's single-pair stiffness used as the
  spline tooth's, an estimate) on the mean radius r_m = seat diameter / 2 over the seat length
  b: k = f z_sp c' b r_m^2 per crank :cite:`iso6336`; at the output 1 / (k N i_c^2).
* ``support_bearing_rings``: the cup and the cone of each support bearing bend as rings on
  the elastic foundation of their seats (carrier bore, crank journal). A roller load Q on a
  ring of bending stiffness E I (I = b h^3 / 12, b the roller length, h the wall) on a Winkler
  foundation of modulus k deflects it by Q beta / (2 k), beta = (k / (4 E I))^(1/4)
  :cite:`hetenyi1946` (the infinite beam: the ring's circumference is many 1/beta); the seat's
  modulus is k = phi E b / R (phi, preset ``support_ring_seat_factor``, an order-of-magnitude
  estimate). The most loaded roller carries Q_max = 4.08 F / (Z cos alpha) of a bearing's
  radial load F (Stribeck's line-contact factor without clearance :cite:`harris2007`), so a
  bearing's rings give c_r = 4.08 / (Z cos alpha) sum_rings beta / (2 k); the two bearings of
  a crank in parallel, the N cranks on the crank circle a_w: c = c_r / (2 N a_w^2). Ring
  walls from the bearing's geometry: the cup from the outer raceway d_m/2 + D/2 to the crank
  bore, the cone from the support journal to the inner raceway d_m/2 - D/2.
* ``carrier_joints``: each pillar is bolted to a plate; the joint turns under the pillar's
  end moment with the compliance c_phi = kappa l_K / (E I_j) of VDI 2230's bending
  resilience of the clamped parts :cite:`vdi2230`, with the substitute body the pillar's
  section (I_j = pi d_p^4 / 64), l_K the clamp length and kappa >= 1 the joint's excess
  over the solid body (contact, dowel fits; an estimate). A pillar of length L (the plate
  gap), clamped at its other end, sheared by V between plates that do not turn: slope-
  deflection gives delta / V = L^3 / (12 E I) (1 + 4 kc) / (1 + kc) with k = E I / L, so the
  joint adds Delta = L^3 / (12 E I) * 3 kc / (1 + kc). A fraction f_T of the output torque
  passes the joints (the rest goes from the cranks' supports straight into the output plate;
  an estimate): V = f_T T / (N_p R_p) per pillar, and the joints' strain energy
  N_p Delta V^2 / 2 = c T^2 / 2 gives c = f_T^2 Delta / (N_p R_p^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexrv.units import M_PER_MM

#: Stribeck's factor: the most loaded roller of a line-contact bearing without clearance carries 4.08 F / (Z cos alpha)
STRIBECK_LINE = 4.08


def shear_modulus(material) -> float:
    """G = E / (2 (1 + nu)) [Pa] of an isotropic material."""
    return material.youngs_modulus / (2.0 * (1.0 + material.poisson_ratio))


def polar_moment(d: float) -> float:
    """J = pi d^4 / 32 [m^4] of a solid circle of diameter d [m]."""
    return math.pi * d**4 / 32.0


def crank_torsion_compliance(reducer) -> float:
    """c_crank [rad/(N m)] of one crank between its spline and its eccentrics (module docstring)."""
    cs = reducer.crankshaft
    g = shear_modulus(reducer.material("crankshaft"))
    ls, ds = cs.gear_seat_length_mm * M_PER_MM, cs.gear_seat_diameter_mm * M_PER_MM
    la, da = cs.support_journal_length_mm * M_PER_MM, cs.support_journal_diameter_mm * M_PER_MM
    le, de = cs.eccentric_journal_length_mm * M_PER_MM, cs.eccentric_journal_diameter_mm * M_PER_MM
    return (ls / (3.0 * polar_moment(ds)) + la / polar_moment(da) + 2.0 * le / (3.0 * polar_moment(de))) / g


def crank_ratio(reducer) -> float:
    """i_c = z_rp + z_s / z_p: the crank's turn relative to its planet per output turn, input held
    (module docstring)."""
    fs = reducer.first_stage
    return reducer.second_stage.pin_count + fs.sun_teeth / fs.planet_teeth


def _at_output(c_crank: float, reducer) -> float:
    """A compliance in each crank's rotation relative to its planet referred to the output:
    c / (N i_c^2)."""
    return c_crank / (reducer.first_stage.n_planets * crank_ratio(reducer) ** 2)


def crank_torsion(reducer) -> float:
    """The cranks' torsion at the output [rad/(N m)]."""
    return _at_output(crank_torsion_compliance(reducer), reducer)


def planet_spline(reducer) -> float:
    """The planet splines at the output [rad/(N m)]."""
    return _at_output(planet_spline_compliance(reducer), reducer)


def planet_spline_compliance(reducer) -> float:
    """1 / k [rad/(N m)] of one planet spline (module docstring)."""
    pe, cs = reducer.path_estimates, reducer.crankshaft
    c_prime = pe.spline_tooth_stiffness_N_per_mm_um * 1e9  # N/(mm um) -> N/m^2
    r_m = 0.5 * cs.gear_seat_diameter_mm * M_PER_MM
    k = (
        pe.planet_spline_engaged_fraction
        * pe.planet_spline_teeth
        * c_prime
        * cs.gear_seat_length_mm
        * M_PER_MM
        * r_m**2
    )
    return 1.0 / k


def ring_on_foundation(r_in: float, r_out: float, width: float, youngs: float, seat_factor: float) -> float:
    """Deflection per roller load [m/N] of a ring between radii r_in and r_out [m] of width
    ``width`` [m] on its seat's Winkler foundation k = seat_factor E b / R: beta / (2 k),
    beta = (k / (4 E I))^(1/4) (module docstring)."""
    h = r_out - r_in
    if h <= 0.0:
        raise ValueError(f"ring wall {h * 1e3:.3g} mm must be > 0 (radii {r_in * 1e3:.4g}, {r_out * 1e3:.4g} mm)")
    k = seat_factor * youngs * width / (0.5 * (r_in + r_out))
    beta = (k / (4.0 * youngs * width * h**3 / 12.0)) ** 0.25
    return beta / (2.0 * k)


def support_ring_radial_compliance(reducer) -> float:
    """c_r [m/N] of one support bearing's cup and cone on their seats (module docstring)."""
    cs, c = reducer.crankshaft, reducer.carrier
    e = reducer.material("bearing_rings").youngs_modulus
    phi = reducer.path_estimates.support_ring_seat_factor
    dm, dw = cs.support_bearing_pitch_diameter_mm * M_PER_MM, cs.support_bearing_roller_diameter_mm * M_PER_MM
    b = cs.support_bearing_roller_length_mm * M_PER_MM
    cup = ring_on_foundation(0.5 * (dm + dw), 0.5 * c.crank_bore_diameter_mm * M_PER_MM, b, e, phi)
    cone = ring_on_foundation(0.5 * cs.support_journal_diameter_mm * M_PER_MM, 0.5 * (dm - dw), b, e, phi)
    cos_a = math.cos(math.radians(cs.support_bearing_contact_angle_deg))
    return STRIBECK_LINE / (cs.support_bearing_roller_count * cos_a) * (cup + cone)


def support_bearing_rings(reducer) -> float:
    """The support rings at the output [rad/(N m)]: c_r / (2 N a_w^2)."""
    n, a_w = reducer.first_stage.n_planets, reducer.first_stage.center_distance
    return support_ring_radial_compliance(reducer) / (2.0 * n * a_w**2)


def joint_shear_compliance(length: float, ei: float, c_phi: float) -> float:
    """Shear compliance [m/N] a rotational joint spring c_phi [rad/(N m)] adds to a beam of
    length ``length`` and bending stiffness ``ei`` clamped at its other end, between
    supports that do not turn: L^3/(12 EI) * 3 kc / (1 + kc), k = EI / L."""
    kc = ei / length * c_phi
    return length**3 / (12.0 * ei) * 3.0 * kc / (1.0 + kc)


def carrier_joints(reducer) -> float:
    """The pillar-to-plate joints at the output [rad/(N m)]: f_T^2 Delta / (N_p R_p^2) with
    Delta the joint's shear compliance (:func:`joint_shear_compliance`) and f_T the
    fraction of the torque through the joints (module docstring)."""
    c, pe = reducer.carrier, reducer.path_estimates
    e = reducer.material("carrier").youngs_modulus
    i = math.pi * (c.pillar_diameter_mm * M_PER_MM) ** 4 / 64.0
    c_phi = pe.carrier_joint_compliance_factor * pe.carrier_joint_clamp_length_mm * M_PER_MM / (e * i)
    delta = joint_shear_compliance(c.plate_gap_mm * M_PER_MM, e * i, c_phi)
    r_p = c.pillar_circle_radius_mm * M_PER_MM
    return pe.carrier_joint_torque_fraction**2 * delta / (c.pillar_count * r_p**2)


def _has(reducer) -> dict[str, bool]:
    """Which of the four elements the design has the data and the switch for: the crank torsion
    with ``crankshaft.torsion_model = "st_venant"``; the others with a ``[path_estimates]``
    table (and the carrier and the tapered-roller supports they need)."""
    pe, c, cs = reducer.path_estimates is not None, reducer.carrier is not None, reducer.crankshaft
    return {
        "crank_torsion": cs.torsion_model == "st_venant",
        "planet_spline": pe,
        "support_bearing_rings": pe and c and cs.support_bearing_model == "tapered_rollers",
        "carrier_joints": pe and c,
    }


def output_compliances(reducer) -> dict[str, float]:
    """The four elements at the output [rad/(N m)] the design has (:func:`_has`): the analytic
    budget's elements and the closed forms the models reproduce."""
    laws = {
        "crank_torsion": crank_torsion,
        "planet_spline": planet_spline,
        "support_bearing_rings": support_bearing_rings,
        "carrier_joints": carrier_joints,
    }
    return {k: laws[k](reducer) for k, on in _has(reducer).items() if on}


def torque_map(bores: np.ndarray) -> np.ndarray:
    """g (2N,) with T = g . f the torque about the axis of the support forces f (2N,) at the
    support points ``bores`` (N, 2) [m]: g_j = (-y_j, x_j)."""
    b = np.asarray(bores, dtype=float)
    return np.column_stack([-b[:, 1], b[:, 0]]).ravel()


@dataclass(frozen=True)
class ModelCompliances:
    """The four elements as the models carry them (module docstring): ``crank_torsion`` and
    ``planet_spline`` per crank [rad/(N m)], their sum c_t in series with each planet's mesh;
    ``support_parts`` element -> (2N, 2N) support-point compliance [m/N]
    (``support_bearing_rings``, ``carrier_joints``), added to the carrier's."""

    crank_torsion: float
    planet_spline: float
    support_parts: dict

    def support_compliance(self, carrier_c: np.ndarray) -> np.ndarray:
        """The carrier's support-point compliance ``carrier_c`` ((0, 0): rigid) with the parts
        added; (0, 0) if both are empty."""
        if not self.support_parts:
            return carrier_c
        total = sum(self.support_parts.values())
        return total if carrier_c.size == 0 else carrier_c + total


def planet_torsion_compliances(reducer) -> tuple[float, float]:
    """Per-crank torsional compliances [rad/(N m)] between planet gear and eccentrics that the
    gear stage puts in series with each mesh: (crank torsion, planet spline), 0 where the design
    leaves an element out."""
    has = _has(reducer)
    c_crank = crank_torsion_compliance(reducer) if has["crank_torsion"] else 0.0
    c_spline = planet_spline_compliance(reducer) if has["planet_spline"] else 0.0
    return c_crank, c_spline


def model_compliances(reducer, bores: np.ndarray) -> ModelCompliances:
    """The four elements of ``reducer`` at their places in the models (module docstring),
    ``bores`` (N, 2) the support points in the carrier frame [m]."""
    has = _has(reducer)
    c_crank, c_spline = planet_torsion_compliances(reducer)
    n2 = 2 * len(bores)
    parts = {}
    if has["support_bearing_rings"]:
        parts["support_bearing_rings"] = 0.5 * support_ring_radial_compliance(reducer) * np.eye(n2)
    if has["carrier_joints"]:
        g = torque_map(bores)
        parts["carrier_joints"] = carrier_joints(reducer) * np.outer(g, g)
    return ModelCompliances(c_crank, c_spline, parts)
