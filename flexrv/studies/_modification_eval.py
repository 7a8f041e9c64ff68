"""One reducer's figures for the profile-modification search (:mod:`flexrv.studies.optimize`).

:func:`build_quantities` evaluates one build (the design with one tolerance draw in its
``[errors]`` table) with the quasi-static loaded-TE solver
(:func:`flexrv.model.quasi_static.loaded_te`) and the assembly-interference check
(:func:`flexrv.geometry.as_built.assembly_penetration`):

=========================  ==============  ==================================================
quantity                   unit            definition
=========================  ==============  ==================================================
``lost_motion``            arcmin          output rotation between -3 % and +3 % rated torque,
                                           input locked, largest over the catalog positions
``backlash``               arcmin          the same between -/+1 % rated torque
``rigidity``               N m/arcmin      tangent torsional rigidity at rated torque, mean
                                           over the catalog positions
``te_pp``                  arcsec          loaded TE peak to peak over the evaluated range
``pin_force``              N               largest pin-disc contact force over the positions
``pin_contact_pressure``   MPa             largest Hertz line-contact pressure of the pins
                                           over the positions (:func:`pin_contact_pressure`)
``assembly_penetration``   um              largest pin penetration into the discs at assembly
                                           (> 0: the parts interfere, the pins are preloaded)
=========================  ==============  ==================================================

The resolution (range of the loaded path and number of catalog positions) is an argument:
the search runs a cheap one, the recommended designs are re-evaluated with the full one
(:data:`flexrv.studies.optimize.FULL_RESOLUTION`, the evaluation of ``flexrv tolerance``).
"""

from __future__ import annotations

import numpy as np

from flexrv.units import PA_PER_MPA, UM_PER_M

#: quantities of one build and their units (the unit token of the metric names)
QUANTITIES = {
    "lost_motion": "arcmin",
    "backlash": "arcmin",
    "rigidity": "Nm_per_arcmin",
    "te_pp": "arcsec",
    "pin_force": "N",
    "pin_contact_pressure": "MPa",
    "assembly_penetration": "um",
}


def contact_parameters(reducer, input_angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reduced radius r_eff [m] of every pin-disc contact at the nominal (conjugate) pose of
    every input angle, and the nominal gap [m] there: shapes (P, n_discs, z_rp).

    Disc k sits at :func:`flexrv.geometry.cycloid.nominal_disc_pose` of its crank angle
    chi_k = chi0_k - phi(theta_in), phi the absolute crank angle (crank speed per input
    speed, :func:`flexrv.geometry.kinematics.member_speeds`); the pin's foot point phi* on
    the profile gives the profile's radius of curvature rho
    (:func:`flexrv.geometry.cycloid.profile_curvature_radius`, concave < 0) and
    r_eff = 1 / (1 / r_pin + 1 / rho) (Johnson 1985, sec. 4.3). The loaded pose differs
    from the nominal one by micrometres, which moves phi* by ~1e-4 rad."""
    from flexrv.geometry.as_built import as_built, as_built_pin_gap
    from flexrv.geometry.cycloid import nominal_disc_pose, profile_curvature_radius, to_disc_frame
    from flexrv.geometry.kinematics import member_speeds

    fs, ss = reducer.first_stage, reducer.second_stage
    ab = as_built(reducer)
    speeds = member_speeds(1.0, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    phi_crank = np.asarray(input_angles, dtype=float) * float(speeds.crank_absolute)
    nd, z = ss.n_discs, ss.pin_count
    r_eff = np.empty((len(phi_crank), nd, z))
    gap = np.empty_like(r_eff)
    for k in range(nd):
        centre, rot = nominal_disc_pose(z, ss.eccentricity, ab.chi0[k] - phi_crank)
        pts = to_disc_frame(ab.pins[None, :, :], centre[:, None, :], rot[:, None])
        gap[:, k], _, phi = as_built_pin_gap(
            pts,
            ab.pin_radii,
            z,
            ss.pin_circle_radius,
            ss.pin_radius,
            ss.eccentricity,
            ab.disc_profile[k],
            ab.profile_harmonics[k],
        )
        d_radius, d_pin_radius, _ = ab.disc_profile[k]
        rho = profile_curvature_radius(
            phi, z, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity, d_radius, d_pin_radius
        )
        with np.errstate(divide="ignore"):
            r_eff[:, k] = 1.0 / (1.0 / ab.pin_radii + 1.0 / rho)
    return r_eff, gap


def pin_contact_pressure(reducer, input_angles: np.ndarray, pin_force: np.ndarray) -> np.ndarray:
    """Hertz line-contact pressure p_max [Pa] of every pin force (P, n_discs, z_rp) [N] at the
    input angles (P,): :func:`flexrv.contact.hertz.line_contact` over the disc width with
    the reduced radius of :func:`contact_parameters` and the disc-pin E'
    (:func:`flexrv.analysis.pin_load.disc_effective_modulus`); 0 where the force is 0."""
    from flexrv.analysis.pin_load import disc_effective_modulus
    from flexrv.contact.hertz import line_contact

    f = np.nan_to_num(np.asarray(pin_force, dtype=float), nan=0.0)
    r_eff, _ = contact_parameters(reducer, input_angles)
    r_eff = np.where(r_eff > 0, r_eff, np.inf)  # a concave seat wider than the pin: flat limit
    r_eff = np.where(np.isfinite(r_eff), r_eff, 1.0)
    width = reducer.second_stage.disc_width
    return line_contact(np.maximum(f, 0.0), width, r_eff, disc_effective_modulus(reducer)).p_max


def build_quantities(reducer, resolution: dict) -> dict[str, float]:
    """The :data:`QUANTITIES` of one build at ``resolution`` (keys ``crank_revolutions``,
    ``points_per_mesh``, ``catalog_positions``, ``force_tol``, ``max_iter``). A stalled
    static solve is retried with the tolerance ladder of ``flexrv tolerance``
    (:func:`flexrv.studies.tolerance.loaded_te_with_retries`) before it raises."""
    from flexrv.geometry.as_built import assembly_penetration
    from flexrv.studies.tolerance import loaded_te_with_retries

    res, _ = loaded_te_with_retries(
        reducer,
        resolution["force_tol"],
        resolution["max_iter"],
        crank_revolutions=resolution["crank_revolutions"],
        points_per_mesh=int(resolution["points_per_mesh"]),
        catalog_positions=int(resolution["catalog_positions"]),
    )
    s = res.summary()
    force = np.asarray(res.outputs["pin_force"].values, dtype=float)
    pressure = pin_contact_pressure(reducer, res.input_angle, force)
    penetration, _, _ = assembly_penetration(reducer)
    return {
        "lost_motion": float(s["lost_motion_arcmin"]),
        "backlash": float(s["backlash_arcmin"]),
        "rigidity": float(s["torsional_rigidity_Nm_per_arcmin"]),
        "te_pp": float(s["te_pp_arcsec"]),
        "pin_force": float(np.nanmax(force)),
        "pin_contact_pressure": float(np.max(pressure)) / PA_PER_MPA,
        "assembly_penetration": float(penetration) * UM_PER_M,
    }


#: the design-only model constants of the last candidates evaluated in this process
#: (:func:`flexrv.design.manufacturing.shared_nominal_constants`): the chunks of one candidate's
#: draws that run on the same worker build them once
_NOMINAL_MEMO: dict = {}
#: most candidates kept in :data:`_NOMINAL_MEMO`
_MEMO_SIZE = 8


def modification_task(design: dict, draws: list, options: dict) -> dict:
    """One candidate (or a chunk of its draws) on a worker: its nominal build (the design's
    own ``[errors]``; skipped with ``options["nominal"] = False``) and one build per
    tolerance draw (``draws``: ``[errors]`` tables), at ``options["resolution"]``. Returns
    ``{"nominal": {q: v}, "draws": {q: [v per draw]}}`` (``nominal`` empty when skipped);
    a build whose solve fails gives NaN (counted as failed by the statistics). The builds
    share the model constants of the design without its errors, computed once
    (:func:`flexrv.design.manufacturing.shared_nominal_constants`: the same numbers)."""
    from flexrv.design import from_dict
    from flexrv.design.manufacturing import shared_nominal_constants
    from flexrv.errors import FlexrvError

    res = options["resolution"]
    if len(_NOMINAL_MEMO) >= _MEMO_SIZE:
        _NOMINAL_MEMO.clear()
    with shared_nominal_constants(_NOMINAL_MEMO):
        nominal = {}
        if options.get("nominal", True):
            nominal = build_quantities(from_dict(design, source="optimize candidate"), res)
        per = {q: [] for q in QUANTITIES}
        for errors in draws:
            try:
                vals = build_quantities(from_dict({**design, "errors": errors}, source="optimize draw"), res)
            except FlexrvError:
                vals = {q: float("nan") for q in QUANTITIES}
            for q in QUANTITIES:
                per[q].append(vals[q])
    return {"nominal": nominal, "draws": per}


modification_task.quantities = QUANTITIES
