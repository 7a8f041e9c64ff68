"""Flexible crankshafts: crank torsion (and gear-seat bending) in the reducer model.

:cite:`seed002` replaces the rigid crankshafts by Abaqus modal bodies and finds crank
torsion in TE. flexrv splits each crank j of the rigid model into two planar
members with the same (x, y, rotation) layout:

* ``crank<j>`` — support journals and eccentrics (held by the carrier bores through
  :class:`flexrv.model.cranks_discs.CrankSupports` and driving the discs through
  :class:`flexrv.model.cranks_discs.NeedleBearings`, unchanged);
* ``planet<j>`` — the planet gear on the gear seat (the sun–planet mesh of
  :class:`flexrv.model.gear_stage.GearMeshes` is re-targeted to it);

coupled by the FE crankshaft's condensed stiffness (:func:`flexrv.fem.crankshaft.
crank_compliance`): a torsional spring k_t on (phi_planet - phi_crank) and an
isotropic lateral spring k_l on the gear seat's offset from the crank axis, with
stiffness-proportional damping of ratio ``damping_ratio`` on each (default: the design's
crankshaft.structural_damping_ratio, an estimate with provenance in the presets).
Mass split: planet gear + gear seat on ``planet<j>``, the rest of the shaft on
``crank<j>`` (:func:`flexrv.model.drive.drive_parameters`).

Why a two-member Guyan model is enough: the shaft's lowest mode with all its
interfaces clamped is > 20 kHz for both presets (``lowest_clamped_hz``; rv40e:
176 kHz at the default mesh), more than two orders above every excitation of
the drive (:cite:`seed002`'s Table 4 tops at 400 Hz),
so the shaft's own inertia between the interfaces does not act dynamically;
the planet's torsional vibration on the crank (sqrt(k_t / J_red), J_red the
reduced inertia of planet and crank: ~22 kHz for rv40e) is kept. Neglected: the x/y
anisotropy of the lateral stiffness (the eccentrics make the shaft slightly unsymmetric;
measured |k_x - k_y| / k < 4 %), the coupling of the gear seat's lateral motion and twist (off-diagonal terms of the
condensed 6x6 compliance, not carried), and bending between the eccentrics and the support
journals (the needle and support bearings are 10-100x softer).

Planar subtlety: crank and planet turn together through large angles; the
torsional spring acts on the difference of their absolute angles (exact for a
linear spring about the common axis), the lateral spring on the difference of
their centres in the fixed frame — legitimate because it is taken isotropic
(mean of k_x, k_y), so it need not be rotated with the crank angle.

Measured (rv40e, default mesh 3 mm, 3528 nodes): k_t = 2.74e4 N m/rad, 14 %
below the beam-theory G J / L of the free support journal A (3.18e4 N m/rad; the
two shoulders add ~0.23 r of effective length; at 0.6x the mesh size, 12183
nodes: 2.69e4, -1.9 %), k_l = 3.15e9 N/m (fine mesh -7 %); planet-on-crank
torsional mode ~22 kHz. Verified in tests/test_model_flexible_crank.py: Saint-
Venant torsion increment within 1 %, stiff-crank (1000x) static TE = rigid TE
within 1e-4 relative (measured 5e-6), static twist = F_mesh r_bp / k_t within 1 %,
TE shift = mean twist / z_c within 5 % (measured 1.5 %, -0.64 arcsec at 412 N m).
"""

from __future__ import annotations

import numpy as np

from flexrv.model.base import ForceGroup, Member, Output


class CrankElasticity(ForceGroup):
    """Linear springs between each crank and its planet (members crank0, planet0, crank1, ...)."""

    name = "crankshaft_elasticity"
    analytic_jacobian = True

    def __init__(self, n_cranks: int, k_t: float, k_l: float, c_t: float, c_l: float):
        self.n = n_cranks
        self.members = tuple(name for j in range(n_cranks) for name in (f"crank{j}", f"planet{j}"))
        k = np.array([k_l, k_l, k_t])
        c = np.array([c_l, c_l, c_t])
        # one crank-planet pair: f = -K (q_planet - q_crank) on the planet, +K(...) on the crank
        pair_k = np.block([[np.diag(-k), np.diag(k)], [np.diag(k), np.diag(-k)]])  # d f / d [q_crank, q_planet]
        pair_c = np.block([[np.diag(-c), np.diag(c)], [np.diag(c), np.diag(-c)]])
        self._jq = np.kron(np.eye(n_cranks), pair_k)
        self._jv = np.kron(np.eye(n_cranks), pair_c)
        self.k, self.c = k, c

    def evaluate(self, t, q, v, want_outputs: bool = False):
        f = q @ self._jq.T + v @ self._jv.T
        out = None
        if want_outputs:
            qq = q.reshape(q.shape[:-1] + (self.n, 2, 3))
            twist = qq[..., 1, 2] - qq[..., 0, 2]
            out = {
                "crank_twist": Output(
                    twist, ("time", "crank"), "rad", "twist of the gear seat against the eccentrics (planet - crank)"
                ),
                "crank_torque": Output(
                    self.k[2] * twist, ("time", "crank"), "N m", "elastic torque transmitted by each crankshaft"
                ),
            }
        return f, out

    def jacobian(self, t, q, v):
        return self._jq, self._jv


def add_flexible_cranks(
    reducer,
    params,
    members: dict,
    groups: list,
    size: float | None = None,
    stiffness_scale: float = 1.0,
    damping_ratio: float | None = None,
) -> dict:
    """Turn the rigid cranks of a model under construction into flexible ones (see
    module doc): split the members, re-target the gear meshes, add the coupling.
    ``params``: the drive's parameters (:class:`flexrv.model.drive.DriveParameters`).

    Returns facts for the model's ``info`` (stiffness, frequencies)."""
    from flexrv.errors import ConfigError
    from flexrv.fem.crankshaft import crank_compliance

    if not stiffness_scale > 0:
        raise ConfigError(f"stiffness_scale = {stiffness_scale!r} must be > 0")
    p = params
    comp = crank_compliance(reducer, size)
    k_t, k_l = stiffness_scale * comp.torsional, stiffness_scale * comp.lateral
    m_p, j_p = p.planet_mass, p.planet_inertia
    m_c, j_c = p.crank_mass - m_p, p.crank_inertia - j_p
    j_red, m_red = j_p * j_c / (j_p + j_c), m_p * m_c / (m_p + m_c)
    if damping_ratio is None:  # the design's estimate (presets, with provenance)
        damping_ratio = reducer.crankshaft.structural_damping_ratio
    c_t = 2.0 * damping_ratio * np.sqrt(k_t * j_red)
    c_l = 2.0 * damping_ratio * np.sqrt(k_l * m_red)
    for j in range(p.n_cranks):
        crank = members[f"crank{j}"]
        crank.mass_matrix = np.diag([m_c, m_c, j_c])
        members[f"planet{j}"] = Member(
            f"planet{j}", np.diag([m_p, m_p, j_p]), crank.q0.copy(), crank.v0.copy(), ("x", "y", "phi")
        )
    gear = next(g for g in groups if g.name == "gear_stage")
    gear.members = ("carrier",) + tuple(f"planet{j}" for j in range(p.n_cranks))
    gear.set_planet_torsion(gear.params.planet_spline_compliance)  # the crank's torsion is the coupling's k_t
    groups.append(CrankElasticity(p.n_cranks, k_t, k_l, c_t, c_l))
    return {
        "crank_torsional_stiffness_Nm_per_rad": k_t,
        "crank_lateral_stiffness_N_per_m": k_l,
        "crank_lateral_anisotropy": abs(comp.lateral_x - comp.lateral_y) / comp.lateral,
        "crank_lowest_clamped_mode_hz": comp.lowest_clamped_hz,
        "planet_torsional_mode_hz": float(np.sqrt(k_t / j_red) / (2 * np.pi)),
    }
