"""Analytic design report of a reducer at its operating point (nested dict, SI).

Collects kinematics (:mod:`flexrv.geometry.kinematics`), the involute stage
(:mod:`flexrv.analysis.mesh_stiffness`), the cycloid stage
(:mod:`flexrv.geometry.cycloid`), the pin load distribution
(:mod:`flexrv.analysis.pin_load`), the :cite:`seed004` torsional model and meshing-zone
identification (:mod:`flexrv.analysis.torsional`), the main-bearing ball loads
(:mod:`flexrv.analysis.bearing_load`), Hertz and Hamrock–Dowson film of the
most loaded ball and the L10 life (:mod:`flexrv.analysis.life`). All values are
plain floats/ints/lists/str so :func:`flexrv.cli._common.to_jsonable` passes
them through; keys carry their unit as a suffix where it is not SI-obvious.
"""

from __future__ import annotations

import math

import numpy as np

from flexrv.units import ARCSEC_PER_RAD, M_PER_UM, RAD_PER_ARCMIN, RPM_PER_RAD_S

#: Measured torsional stiffness of the RV-40E (:cite:`seed004`): 3.06e8 N mm/rad.
SEED004_MEASURED_CW = 3.06e5  # N m/rad


def _f(x) -> float:
    return float(x)


def _kinematics(reducer) -> dict:
    from flexrv.geometry.kinematics import FREQUENCY_NAMES, reducer_kinematics

    kin = reducer_kinematics(reducer)
    s, f = kin.speeds, kin.frequencies
    speeds = {
        k: _f(getattr(s, k))
        for k in (
            "input",
            "sun_relative",
            "carrier",
            "crank_absolute",
            "crank_relative",
            "disc_rotation",
            "disc_orbit",
            "disc_orbit_relative",
        )
    }
    return {
        "ratio": s.ratio,
        "speeds_rad_s": speeds,
        "speeds_rpm": {k: v * RPM_PER_RAD_S for k, v in speeds.items()},
        # names and meanings: flexrv.geometry.kinematics.CharacteristicFrequencies
        "frequencies_Hz": {k: _f(getattr(f, k)) for k in FREQUENCY_NAMES},
    }


def _involute(reducer) -> dict:
    from flexrv.analysis.mesh_stiffness import involute_stage

    st = involute_stage(reducer)
    return {
        "contact_ratio": st.eps_alpha,
        "center_distance_m": st.center_distance,
        "base_radius_sun_m": st.rb_sun,
        "base_radius_planet_m": st.rb_planet,
        "q_min_mm_um_per_N": st.q_min,
        "c_th_N_per_m2": st.c_th,
        "c_single_N_per_m2": st.c_single,
        "c_gamma_N_per_m2": st.c_gamma,
        "k_single_pair_N_per_m": st.k_single,
        "k12_mean_N_per_m": st.k12,
        "k12_double_zone_N_per_m": 1.75 * st.k_single,
        "c12_N_s_per_m": st.c12,
        "planet_inertia_estimate_kg_m2": st.planet_inertia,
    }


def _pin_case(reducer, torque: float, law: str = "palmgren", d_pin_radius=None) -> dict:
    from flexrv.analysis.pin_load import reducer_pin_loads

    res = reducer_pin_loads(reducer, torque, law=law, d_pin_radius=d_pin_radius)
    n_discs = reducer.second_stage.n_discs
    return {
        "output_torque_Nm": torque,
        "disc_torque_Nm": res.torque,
        "law": res.law,
        "pins_in_contact": res.n_contact,
        "loaded_pins": [int(i) for i in np.flatnonzero(res.in_contact)],
        "max_pin_force_N": res.max_force,
        "max_hertz_pressure_Pa": res.max_pressure,
        "disc_rotation_rad": res.rotation,
        "pins_share_of_lost_motion_arcsec": res.backlash_rotation * ARCSEC_PER_RAD,
        "torsional_stiffness_per_disc_Nm_per_rad": res.torsional_stiffness,
        "torsional_stiffness_all_discs_Nm_per_rad": n_discs * res.torsional_stiffness,
        "pin_resultant_N": float(np.linalg.norm(res.resultant)),
        "torque_balance_error_Nm": float(np.sum(res.forces * res.arms) - res.torque),
    }


def _cycloid(reducer) -> dict:
    from flexrv.analysis.pin_load import disc_effective_modulus, reducer_pin_loads
    from flexrv.geometry.cycloid import (
        k34,
        min_convex_curvature_radius,
        pin_stiffness_seed000,
        profile_curvature_radius,
    )

    ss = reducer.second_stage
    e_eff = disc_effective_modulus(reducer)
    k_n = float(pin_stiffness_seed000(ss.disc_width, e_eff))
    rated = reducer.operating.rated_torque_Nm
    ideal = reducer_pin_loads(reducer, rated, d_pin_radius=0.0, law="linear")
    loaded = reducer_pin_loads(reducer, reducer.operating.load_torque_Nm or rated, law="linear")
    lobe = np.linspace(0.0, 2.0 * np.pi / ss.disc_teeth, 721)
    rho = profile_curvature_radius(
        lobe,
        ss.pin_count,
        ss.pin_circle_radius,
        ss.pin_radius,
        ss.eccentricity,
        ss.modification_shift,
        ss.modification_equidistant,
    )
    convex = rho[rho > 0]
    return {
        "shortening_coefficient_K1": ss.shortening_coefficient,
        "rolling_circle_radius_m": ss.eccentricity * ss.disc_teeth,
        "min_convex_curvature_radius_pin_centre_curve_m": min_convex_curvature_radius(
            ss.pin_count, ss.pin_circle_radius + ss.modification_shift, ss.eccentricity
        ),
        "profile_convex_curvature_radius_range_m": [float(convex.min()), float(convex.max())],
        "effective_modulus_Pa": e_eff,
        "pin_stiffness_seed000_N_per_m": k_n,
        "k34_ideal_half_pins_Nm_per_rad": float(k34(k_n, ideal.arms, ideal.in_contact)),
        "k34_ideal_pins_engaged": ideal.n_contact,
        "k34_at_load_torque_Nm_per_rad": float(k34(k_n, loaded.arms, loaded.in_contact)),
        "k34_at_load_torque_pins_engaged": loaded.n_contact,
        "note": "k34 = sum k_n l_i^2 over engaged pins, per disc (seed000); k_n = pi b E'/4 is curvature-free",
    }


def _modification_sweep(reducer, torque: float) -> dict:
    from flexrv.analysis.pin_load import reducer_pin_loads

    out = {}
    for dr_um in (0.0, 1.0, 2.0, 5.0, 10.0, 20.0):
        res = reducer_pin_loads(reducer, torque, d_pin_radius=dr_um * M_PER_UM)
        out[f"{dr_um:g}um"] = {
            "pins_in_contact": res.n_contact,
            "max_pin_force_N": res.max_force,
            "pins_share_of_lost_motion_arcsec": res.backlash_rotation * ARCSEC_PER_RAD,
        }
    return out


def _torsional(reducer) -> dict:
    from flexrv.analysis.torsional import second_stage_stiffness

    torque = reducer.operating.rated_torque_Nm
    lobes = np.linspace(0.0, 2.0 * np.pi, 7)[:-1]
    runs = [second_stage_stiffness(reducer, torque, chi) for chi in lobes]
    first = runs[0]
    cw_seed = np.array([r.c_w_seed for r in runs])
    cw_tan = np.array([r.c_w_tangent for r in runs])
    return {
        "output_torque_Nm": torque,
        "crank_bearing_forces_N": first.bearing_forces.tolist(),
        "crank_bearing_loads_N": first.bearing_loads.tolist(),
        "needle_stiffness_N_per_m": first.bearing_stiffness.tolist(),
        "lever_arm_m": first.lever_arm,
        "C_Hc_Nm_per_rad": first.c_bearings,
        "C_c_seed004_Nm_per_rad": first.c_mesh_seed,
        "C_c_palmgren_tangent_Nm_per_rad": first.c_mesh_tangent,
        "C_W_seed004_Nm_per_rad": first.c_w_seed,
        "C_W_palmgren_Nm_per_rad": first.c_w_tangent,
        "C_W_seed004_Nm_per_arcmin": first.c_w_seed * RAD_PER_ARCMIN,
        "C_W_palmgren_Nm_per_arcmin": first.c_w_tangent * RAD_PER_ARCMIN,
        "C_W_palmgren_over_crank_angle_Nm_per_rad": {"min": float(cw_tan.min()), "max": float(cw_tan.max())},
        "C_W_seed004_over_crank_angle_Nm_per_rad": {"min": float(cw_seed.min()), "max": float(cw_seed.max())},
        "pins_in_contact": first.n_contact,
        "model": "the second stage's series models, not the reducer's rigidity (that is the stiffness budget's): "
        "seed004's model (needle bearings, empirical K_Hc, in series with seed004's pin contacts) and the same "
        "with the Palmgren pin-load tangent; both neglect the crank supports, crank bending and torsion, pin "
        "seats, housing, carrier and its joints, discs and the first stage",
    }


def _meshing_zone(reducer, bearing_c: float, measured: float) -> dict:
    from flexrv.analysis.torsional import (
        SEED004_CC_NMM,
        SEED004_KTC_NMM,
        identify_meshing_zone,
        required_mesh_stiffness,
        seed004_pin_contributions,
    )
    from flexrv.errors import InputError

    out: dict = {"measured_C_W_Nm_per_rad": measured, "C_Hc_Nm_per_rad": bearing_c}
    try:
        target = required_mesh_stiffness(measured, bearing_c)
    except InputError as exc:
        out["own_values"] = {"error": str(exc)}
        target = None
    th, ktc = seed004_pin_contributions(reducer)
    if target is not None:
        z = identify_meshing_zone(ktc, target, th)
        z4 = z.best_by_count[4]
        out["own_values"] = {
            "required_C_c_Nm_per_rad": target,
            "best_pins": [z.first, z.last],
            "best_angles_deg": [math.degrees(a) for a in z.angles],
            "best_total_Nm_per_rad": z.total,
            "best_rel_error": z.rel_error,
            "best_four_pins": [z4[0], z4[1]],
            "best_four_total_Nm_per_rad": z4[2],
            "max_single_pin_contribution_Nm_per_rad": float(ktc.max()),
        }
    zs = identify_meshing_zone(SEED004_KTC_NMM * 1e-3, SEED004_CC_NMM * 1e-3, np.radians(np.arange(21) * 9.0))
    s4 = zs.best_by_count[4]
    out["seed_table"] = {
        "required_C_c_Nm_per_rad": SEED004_CC_NMM * 1e-3,
        "best_pins": [zs.first, zs.last],
        "best_angles_deg": [math.degrees(a) for a in zs.angles],
        "best_total_Nm_per_rad": zs.total,
        "best_rel_error": zs.rel_error,
        "best_four_pins": [s4[0], s4[1]],
        "best_four_total_Nm_per_rad": s4[2],
        "note": "seed004 reports pins 6-9 (4 pins, 6.32e8 N mm/rad); over all set sizes pins 9-15 "
        "match its own target 6.24e8 N mm/rad better (6.303e8)",
    }
    return out


def _bearing_case(reducer, geom, e_eff, force, moment) -> dict:
    from flexrv.analysis.bearing_load import ball_load_distribution, max_ball_contact
    from flexrv.analysis.life import ball_dynamic_rating, equivalent_radial_load, l10, life_hours, system_life

    res = ball_load_distribution(geom, e_eff, force=force, moment=moment)
    inner, outer, (rx_i, ry_i, rx_o, ry_o) = max_ball_contact(geom, e_eff, res)
    loaded = res.loads > 0
    alpha = res.contact_angle[loaded] if np.any(loaded) else res.contact_angle.ravel()
    c_row = ball_dynamic_rating(
        geom.ball_diameter,
        geom.pitch_diameter,
        geom.ball_count,
        geom.contact_angle,
        geom.inner_conformity,
        geom.outer_conformity,
    )
    fr = np.hypot(res.row_forces[:, 0], res.row_forces[:, 1])
    fa = np.abs(res.row_forces[:, 2])
    p = equivalent_radial_load(fr, fa, geom.contact_angle)
    lives = l10(c_row, p)
    speed = reducer.operating.input_speed / _ratio(reducer)
    out = {
        "force_N": list(map(float, force)),
        "moment_Nm": list(map(float, moment)),
        "displacement": {
            "dx_m": res.displacement[0],
            "dy_m": res.displacement[1],
            "dz_m": res.displacement[2],
            "tilt_x_rad": res.displacement[3],
            "tilt_y_rad": res.displacement[4],
        },
        "max_ball_load_N": res.max_load,
        "max_ball_row": res.max_index[0],
        "ball_loads_row_N": [{"min": float(r.min()), "max": float(r.max())} for r in res.loads],
        "contact_angle_deg": {
            "min": float(np.degrees(alpha.min())),
            "max": float(np.degrees(alpha.max())),
            "of_max_ball": float(np.degrees(res.contact_angle[res.max_index])),
        },
        "hertz_max_ball": {
            "inner_p_max_Pa": float(inner.p_max),
            "outer_p_max_Pa": float(outer.p_max),
            "inner_semi_axes_m": [float(inner.a), float(inner.b)],
            "outer_semi_axes_m": [float(outer.a), float(outer.b)],
        },
        "dynamic_rating_per_row_N": c_row,
        "equivalent_load_per_row_N": p.tolist(),
        "L10_per_row_Mrev": [float(x) if np.isfinite(x) else None for x in lives],
        "L10_pair_Mrev": system_life(lives),
    }
    lp = out["L10_pair_Mrev"]
    out["L10_pair_h"] = float(life_hours(lp, speed)) if np.isfinite(lp) else None
    try:
        from flexrv.ehl.film import hamrock_dowson

        lub = reducer.lubricant
        u = float(geom.entrainment_speed(speed, 0.0, res.contact_angle[res.max_index]))
        if res.max_load > 0 and u > 0:
            hc, hm = hamrock_dowson(res.max_load, u, rx_i, ry_i, e_eff, lub.viscosity, lub.pressure_viscosity)
            out["film_inner_max_ball"] = {
                "entrainment_speed_m_s": u,
                "h_central_m": float(hc),
                "h_min_m": float(hm),
                "formula": "Hamrock-Dowson 1977 (flexrv.ehl.film)",
            }
    except ImportError:
        out["film_inner_max_ball"] = "skipped: flexrv.ehl.film not available"
    return out


def _ratio(reducer) -> float:
    from flexrv.geometry.kinematics import total_ratio

    fs, ss = reducer.first_stage, reducer.second_stage
    return float(total_ratio(fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count))


def _main_bearing(reducer) -> dict:
    from flexrv.analysis.pin_load import reducer_pin_loads
    from flexrv.contact.hertz import effective_modulus
    from flexrv.geometry.bearing import BallBearingGeometry

    geom = BallBearingGeometry.from_design(reducer.main_bearing)
    ring, ball = reducer.material("bearing_rings"), reducer.material("rolling_elements")
    e_eff = float(effective_modulus(ring.youngs_modulus, ring.poisson_ratio, ball.youngs_modulus, ball.poisson_ratio))
    op = reducer.operating
    ext_f = (op.external_radial_force_N, 0.0, op.external_axial_force_N)
    ext_m = (0.0, op.tilting_moment_Nm)
    out = {
        "effective_modulus_Pa": e_eff,
        "curvature_center_distance_m": geom.curvature_center_distance,
        "external": _bearing_case(reducer, geom, e_eff, ext_f, ext_m),
    }
    ss = reducer.second_stage
    if ss.n_discs == 2 and op.load_torque_Nm != 0:
        res = reducer_pin_loads(reducer, op.load_torque_Nm)
        couple = float(np.linalg.norm(res.resultant)) * ss.disc_width
        out["external_plus_disc_couple"] = _bearing_case(reducer, geom, e_eff, ext_f, (couple, op.tilting_moment_Nm))
        out["external_plus_disc_couple"]["note"] = (
            "each disc's pin resultant returns to the carrier through the cranks; the two discs (180 deg apart) give "
            "opposite forces one disc width apart, i.e. a tilting couple |F| b on the carrier, carried by the main "
            f"bearing ({couple:.4g} N m at the load torque). First-stage and crank support forces are internal to "
            "the carrier and not included; the output torque itself is not reacted by the main bearing."
        )
    return out


def design_report(reducer) -> dict:
    """Analytic design report of a :class:`flexrv.design.model.Reducer` at its
    operating point (nested dict of floats/ints/lists/str, SI; keys with
    non-SI-obvious units carry a suffix). Sections: kinematics, involute_stage,
    cycloid_stage, pin_loads (load and rated torque, ideal profile), modification
    sweep, second_stage_series_models (:cite:`seed004`'s model and the Palmgren series model of
    the second stage alone; the reducer's rigidity is the stiffness budget's), meshing_zone (vs the measured
    3.06e5 N m/rad of :cite:`seed004`), main_bearing (ball loads, contact angles, Hertz,
    Hamrock–Dowson film, L10)."""
    op = reducer.operating
    report: dict = {
        "name": reducer.name,
        "kinematics": _kinematics(reducer),
        "involute_stage": _involute(reducer),
        "cycloid_stage": _cycloid(reducer),
    }
    pins = {}
    if op.load_torque_Nm != 0:
        pins["load_torque"] = _pin_case(reducer, op.load_torque_Nm)
    pins["rated_torque"] = _pin_case(reducer, op.rated_torque_Nm)
    pins["rated_torque_linear_seed000"] = _pin_case(reducer, op.rated_torque_Nm, law="linear")
    pins["rated_torque_ideal_profile"] = _pin_case(reducer, op.rated_torque_Nm, d_pin_radius=0.0)
    report["pin_loads"] = pins
    report["modification_sweep_rated_torque"] = _modification_sweep(reducer, op.rated_torque_Nm)
    tors = _torsional(reducer)
    report["second_stage_series_models"] = tors
    report["meshing_zone"] = _meshing_zone(reducer, tors["C_Hc_Nm_per_rad"], SEED004_MEASURED_CW)
    report["meshing_zone"]["note"] = (
        "seed004 procedure; the measured value is the RV-40E's (seed004) and is meaningful only for rv40e"
    )
    report["main_bearing"] = _main_bearing(reducer)
    return report
