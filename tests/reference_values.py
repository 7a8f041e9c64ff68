"""Pinned reference values of short runs of every model (Exudyn's
``runTestSuiteRefSol.py`` pattern): a drift fails ``tests/test_regression.py``.

Each entry: the case function in ``tests/regression_cases.py``, the values, the
relative tolerance per quantity, and dated notes. An intended change of a value
is made here, with a new dated note saying what changed it and by how much; an
unintended one is a bug.
"""

REFERENCE = {
    "rigid_rv40e": {
        "values": {"te_mean_arcsec": -166.366356, "te_pp_arcsec": 0.330184678, "max_pin_force_N": 634.947753},
        "rtol": {"te_mean_arcsec": 1e-5, "te_pp_arcsec": 1e-3, "max_pin_force_N": 1e-4},
        "notes": [
            "2026-11-23: pinned with the compiled fused force kernel (the numpy groups gave the same "
            "TE to 1e-5 arcsec, tests/data/te_reference.json)",
            "2026-11-24: crank supports became roller-resolved preloaded tapered-roller pairs in series with the crank's Timoshenko bending (issue 14, branch stiff) instead of one linear 2e8 N/m spring per bearing; "
            "TE mean -131.470 -> -134.379 arcsec, p-p 0.291 -> 0.283, max pin force 725.65 -> 726.04 N",
            "2026-11-24: the pins seated in the housing grooves (issue 14, branch pinseat): the pin law's constant is the pin-disc and the pin-seat Palmgren contacts in series (K 1.67e9 -> 7.92e8 N/m^(10/9) on rv40e); TE mean -134.379 -> -139.345 arcsec, p-p 0.283 -> 0.340, max pin force 726.04 -> 621.41 N (softer pins share the load over more pins)",
            '2026-11-24: the FE carrier and cycloid-disc bodies enter every model by default (issue 14, branch bodies: carrier.body_model = second_stage.disc_body_model = "condensed_fe"; the carrier in series with the crank supports, the disc rim around the pins); '
            "TE mean -134.379 -> -154.650 arcsec, p-p 0.283 -> 0.291, max pin force 726.04 -> 724.82 N",
            "2026-11-24 (merge of fric, pinseat, bodies, rigspeed, flexspeed): TE mean -139.345 -> -159.748 arcsec, p-p 0.340 -> 0.396, max pin force 621.41 -> 634.98 N: the pin seats in series (pinseat) and the FE carrier and disc bodies (bodies) together, with friction on (the pinned value before had the pin seats but not the bodies)",
            '2026-11-24 (housing branch): the pin housing ring enters the models as an elastic pin-ring rotation (housing.body_model = "ring_estimate", c_h from the thin-ring + tube estimate, 8.16e-8 rad/(N m) on rv40e) and the stiffness-test default quarter time became 0.08 s (not used here): te_mean_arcsec -159.748 -> -166.506, te_pp_arcsec 0.395516 -> 0.340347, max_pin_force_N 634.981 -> 634.913',
            "2026-11-24 (fecold branch, issue 15): cold-cache cost of the FE bodies: the cycloid disc's flank mesh size is now r_rp (was tooth pitch / 8: rv40e 3 mm for 1.29 mm, 16.9k for 66.7k nodes; rv221 5 mm for 2.2 mm, 32.5k for 107k nodes) and its pin patches carry consistent instead of lumped loads, chosen from a convergence study (flexrv.meshing.parts.CycloidDiscSpec.profile_size: the default within 0.8 % / 0.5 % of the converged disc compliance); the rv40e disc compliance moves 1.4982e-7 -> 1.4626e-7 rad/(N m) (-2.4 %, 5 % of the total compliance; rv221 2.2975e-8 -> 2.2799e-8, -0.8 %); the carrier mesh is unchanged. te_mean_arcsec -166.506 -> -166.366, te_pp_arcsec 0.340347 -> 0.330597, max_pin_force_N 634.913 -> 634.948",
            "2026-11-24 (issue 15, merge of rowspeed and fecold): the dynamic cases run at a converged Newton tolerance (tests/regression_cases.NEWTON_TOLERANCE = (1e-5, 1e-3) instead of the default (1e-3, 0.1)), so the pinned numbers are the model's answer and not the path a default-tolerance Newton took (a faster, equivalent residual changed balls_rv40e's TE p-p 0.4026 -> 0.3759 arcsec at the default tolerance; converged 0.3616 both); re-pinned on the merged code (disc mesh r_rp, row kernel rewrite): te_mean_arcsec -166.366 -> -166.366, te_pp_arcsec 0.330597 -> 0.330185, max_pin_force_N 634.948 -> 634.948",
        ],
    },
    "balls_rv40e": {
        "values": {
            "te_mean_arcsec": -166.365559,
            "te_pp_arcsec": 0.36415373,
            "max_pin_force_N": 631.599699,
            "max_ball_load_N": 20.8637169,
        },
        "rtol": {"te_mean_arcsec": 1e-5, "te_pp_arcsec": 1e-3, "max_pin_force_N": 1e-4, "max_ball_load_N": 1e-4},
        "notes": [
            "2026-11-23: pinned (ball-resolved main bearing, rigid rings; ball load = preload only)",
            "2026-11-24: crank supports became roller-resolved preloaded tapered-roller pairs in series with the crank's Timoshenko bending (issue 14, branch stiff) instead of one linear 2e8 N/m spring per bearing; "
            "TE mean -131.474 -> -134.383 arcsec, p-p 0.312 -> 0.314, ball load 20.907 -> 20.966 N",
            "2026-11-24: friction on in the presets (issue 14, branch fric; as rigid_rv40e): TE mean -134.383 -> "
            "-134.907 arcsec, p-p 0.314 -> 0.337, max pin force 722.06 -> 735.64 N, ball load 20.966 -> 21.375 N",
            '2026-11-24: the FE carrier and cycloid-disc bodies enter every model by default (issue 14, branch bodies: carrier.body_model = second_stage.disc_body_model = "condensed_fe"; the carrier in series with the crank supports, the disc rim around the pins); '
            "TE mean -134.383 -> -154.653 arcsec, p-p 0.314 -> 0.358, max pin force 722.06 -> 721.36 N, ball load 20.966 -> 20.739 N",
            "2026-11-24 (merge of fric, pinseat, bodies, rigspeed, flexspeed): TE mean -139.344 -> -159.747 arcsec, p-p 0.335 -> 0.430, max pin force 617.88 -> 631.65 N, ball load 20.719 -> 20.860 N: the pin seats and the FE carrier and disc bodies together (as rigid_rv40e)",
            '2026-11-24 (housing branch): the pin housing ring enters the models as an elastic pin-ring rotation (housing.body_model = "ring_estimate", c_h from the thin-ring + tube estimate, 8.16e-8 rad/(N m) on rv40e) and the stiffness-test default quarter time became 0.08 s (not used here): te_mean_arcsec -159.747 -> -166.505, te_pp_arcsec 0.430168 -> 0.402616, max_pin_force_N 631.649 -> 631.578, max_ball_load_N 20.8595 -> 20.8657',
            "2026-11-24 (rowspeed, issue 15): row kernel and glue rewritten (same physics to round-off), the films' entrainment-speed "
            "term added to the row Jacobian (d f/d q_t was missing it), the member objects no longer numerically differentiated by "
            "Exudyn: a different Newton path at the default tolerance (1e-3): te_mean_arcsec -166.505487 -> -166.505757, "
            "te_pp_arcsec 0.402616 -> 0.375869, max_pin_force_N 631.578 -> 631.768, max_ball_load_N 20.8657 -> 20.8649. Converged "
            "(newton_tolerance (1e-5, 1e-3)) the code before and after give the same answer: TE mean -166.5058067562 / "
            "-166.5058067556, p-p 0.36157285 / 0.36157294, max pin force 631.608165 / 631.608165, ball load 20.8643229 / "
            "20.8643227; the default tolerance leaves p-p 0.4026 (before) and 0.3759 (after) against the converged 0.3616",
            "2026-11-24 (fecold branch, issue 15): cold-cache cost of the FE bodies: the cycloid disc's flank mesh size is now r_rp (was tooth pitch / 8: rv40e 3 mm for 1.29 mm, 16.9k for 66.7k nodes; rv221 5 mm for 2.2 mm, 32.5k for 107k nodes) and its pin patches carry consistent instead of lumped loads, chosen from a convergence study (flexrv.meshing.parts.CycloidDiscSpec.profile_size: the default within 0.8 % / 0.5 % of the converged disc compliance); the rv40e disc compliance moves 1.4982e-7 -> 1.4626e-7 rad/(N m) (-2.4 %, 5 % of the total compliance; rv221 2.2975e-8 -> 2.2799e-8, -0.8 %); the carrier mesh is unchanged. te_mean_arcsec -166.505 -> -166.365, te_pp_arcsec 0.402616 -> 0.378645, max_pin_force_N 631.578 -> 631.692, max_ball_load_N 20.8657 -> 20.8609",
            "2026-11-24 (issue 15, merge of rowspeed and fecold): the dynamic cases run at a converged Newton tolerance (tests/regression_cases.NEWTON_TOLERANCE = (1e-5, 1e-3) instead of the default (1e-3, 0.1)), so the pinned numbers are the model's answer and not the path a default-tolerance Newton took (a faster, equivalent residual changed balls_rv40e's TE p-p 0.4026 -> 0.3759 arcsec at the default tolerance; converged 0.3616 both); re-pinned on the merged code (disc mesh r_rp, row kernel rewrite): te_mean_arcsec -166.365 -> -166.366, te_pp_arcsec 0.378645 -> 0.359635, max_pin_force_N 631.692 -> 631.612, max_ball_load_N 20.8609 -> 20.8644",
            "2026-11-24 (issue 15, branch qs2): the ball model's balls became quasi-static by default (ball_inertia = false: massless, solved inside the row elements; flexrv.model.flexible_bearing): te_mean_arcsec -166.365549 -> -166.365559, te_pp_arcsec 0.359635 -> 0.364154 (this window, 25-50 ms, is the start-up, where the balls' inertia still shows: the steady window of a 0.4 s run moves by 5e-5 / 3e-5 arcsec, tests/test_model_flexible_bearing.py), max_pin_force_N 631.612 -> 631.600, max_ball_load_N 20.8644 -> 20.8637; with ball_inertia = true the old values are unchanged",
        ],
    },
    "quasi_static_rv40e": {
        "values": {
            "te_pp_arcsec": 0.298947976,
            "te_mean_arcsec": -165.671204,
            "no_load_te_pp_arcsec": 0.147442555,
            "lost_motion_arcmin": 1.41528022,
            "torsional_rigidity_Nm_per_arcmin": 202.641686,
        },
        "rtol": {
            "te_pp_arcsec": 1e-3,
            "te_mean_arcsec": 1e-6,
            "no_load_te_pp_arcsec": 1e-2,
            "lost_motion_arcmin": 1e-4,
            "torsional_rigidity_Nm_per_arcmin": 1e-4,
        },
        "notes": [
            "2026-11-23: pinned with the first quasi-static solver (issue 12); no-load TE at 1 % of the rated torque",
            "2026-11-24: crank supports became roller-resolved preloaded tapered-roller pairs in series with the crank's Timoshenko bending (issue 14, branch stiff) instead of one linear 2e8 N/m spring per bearing; "
            "rigidity 279.83 -> 269.17 N m/arcmin, TE mean -131.462 -> -134.372 arcsec, lost motion 1.3802 -> 1.3746 arcmin",
            "2026-11-24: the pins seated in the housing grooves (issue 14, branch pinseat): the pin law's constant is the pin-disc and the pin-seat Palmgren contacts in series (K 1.67e9 -> 7.92e8 N/m^(10/9) on rv40e); rigidity 269.17 -> 258.44 N m/arcmin, TE mean -134.372 -> -139.334 arcsec, p-p 0.239 -> 0.297, lost motion 1.3746 -> 1.3889 arcmin",
            '2026-11-24: the FE carrier and cycloid-disc bodies enter every model by default (issue 14, branch bodies: carrier.body_model = second_stage.disc_body_model = "condensed_fe"; the carrier in series with the crank supports, the disc rim around the pins); '
            "rigidity 269.17 -> 220.51 N m/arcmin (carrier 12 %, disc 6 % of the compliance), TE mean -134.372 -> -154.642 arcsec, lost motion 1.3746 -> 1.3949 arcmin",
            "2026-11-24 (merge of fric, pinseat, bodies, rigspeed, flexspeed): rigidity 258.44 -> 214.28 N m/arcmin, TE mean -139.334 -> -159.048 arcsec, p-p 0.2967 -> 0.2990, no-load p-p 0.1481 -> 0.1474, lost motion 1.3889 -> 1.4087 arcmin: the pin seats in series and the FE carrier and disc bodies together",
            '2026-11-24 (housing branch): the pin housing ring enters the models as an elastic pin-ring rotation (housing.body_model = "ring_estimate", c_h from the thin-ring + tube estimate, 8.16e-8 rad/(N m) on rv40e) and the stiffness-test default quarter time became 0.08 s (not used here): te_pp_arcsec 0.298987 -> 0.298946, te_mean_arcsec -159.048 -> -165.812, no_load_te_pp_arcsec 0.14744 -> 0.147436, lost_motion_arcmin 1.40866 -> 1.41542, torsional_rigidity_Nm_per_arcmin 214.276 -> 202.408',
            "2026-11-24 (fecold branch, issue 15): cold-cache cost of the FE bodies: the cycloid disc's flank mesh size is now r_rp (was tooth pitch / 8: rv40e 3 mm for 1.29 mm, 16.9k for 66.7k nodes; rv221 5 mm for 2.2 mm, 32.5k for 107k nodes) and its pin patches carry consistent instead of lumped loads, chosen from a convergence study (flexrv.meshing.parts.CycloidDiscSpec.profile_size: the default within 0.8 % / 0.5 % of the converged disc compliance); the rv40e disc compliance moves 1.4982e-7 -> 1.4626e-7 rad/(N m) (-2.4 %, 5 % of the total compliance; rv221 2.2975e-8 -> 2.2799e-8, -0.8 %); the carrier mesh is unchanged. te_pp_arcsec 0.298946 -> 0.298948, te_mean_arcsec -165.812 -> -165.671, no_load_te_pp_arcsec 0.147436 -> 0.147443, lost_motion_arcmin 1.41542 -> 1.41528, torsional_rigidity_Nm_per_arcmin 202.408 -> 202.642",
        ],
    },
    "quasi_static_rv40e_grade5": {
        "values": {"te_pp_arcsec": 55.1149691, "te_mean_arcsec": -159.394049, "lost_motion_arcmin": 0.173586591},
        "rtol": {"te_pp_arcsec": 1e-3, "te_mean_arcsec": 1e-5, "lost_motion_arcmin": 1e-3},
        "notes": [
            "2026-11-23: pinned; ISO grade-5 example error set iso_grade5_rv40e (one crank revolution)",
            "2026-11-24: crank supports became roller-resolved preloaded tapered-roller pairs in series with the crank's Timoshenko bending (issue 14, branch stiff) instead of one linear 2e8 N/m spring per bearing; "
            "TE mean -124.247 -> -127.184 arcsec, p-p 53.226 -> 53.195, lost motion 0.1625 -> 0.1514 arcmin",
            "2026-11-24: the pins seated in the housing grooves (issue 14, branch pinseat): the pin law's constant is the pin-disc and the pin-seat Palmgren contacts in series (K 1.67e9 -> 7.92e8 N/m^(10/9) on rv40e); TE mean -127.184 -> -132.722 arcsec, p-p 53.195 -> 55.065, lost motion 0.1514 -> 0.1493 arcmin",
            '2026-11-24: the FE carrier and cycloid-disc bodies enter every model by default (issue 14, branch bodies: carrier.body_model = second_stage.disc_body_model = "condensed_fe"; the carrier in series with the crank supports, the disc rim around the pins); '
            "TE mean -127.184 -> -147.808 arcsec, p-p 53.195 -> 53.249, lost motion 0.1514 -> 0.1772 arcmin",
            "2026-11-24 (merge of fric, pinseat, bodies, rigspeed, flexspeed): TE mean -132.722 -> -152.771 arcsec, p-p 55.065 -> 55.114, lost motion 0.1493 -> 0.1670 arcmin: the pin seats in series and the FE carrier and disc bodies together",
            '2026-11-24 (housing branch): the pin housing ring enters the models as an elastic pin-ring rotation (housing.body_model = "ring_estimate", c_h from the thin-ring + tube estimate, 8.16e-8 rad/(N m) on rv40e) and the stiffness-test default quarter time became 0.08 s (not used here): te_pp_arcsec 55.1141 -> 55.1143, te_mean_arcsec -152.771 -> -162.899, lost_motion_arcmin 0.166965 -> 0.177092',
            "2026-11-24: the disc-body pattern and the housing estimate evaluated on the design without its errors (flexrv.design.manufacturing.nominal_design; the analytic as-built pin loads of some tolerance samples gave unphysical constants): TE mean -162.899 -> -159.536 arcsec, p-p 55.1143 -> 55.1142, lost motion 0.17709 -> 0.17373 arcmin",
            "2026-11-24 (fecold branch, issue 15): cold-cache cost of the FE bodies: the cycloid disc's flank mesh size is now r_rp (was tooth pitch / 8: rv40e 3 mm for 1.29 mm, 16.9k for 66.7k nodes; rv221 5 mm for 2.2 mm, 32.5k for 107k nodes) and its pin patches carry consistent instead of lumped loads, chosen from a convergence study (flexrv.meshing.parts.CycloidDiscSpec.profile_size: the default within 0.8 % / 0.5 % of the converged disc compliance); the rv40e disc compliance moves 1.4982e-7 -> 1.4626e-7 rad/(N m) (-2.4 %, 5 % of the total compliance; rv221 2.2975e-8 -> 2.2799e-8, -0.8 %); the carrier mesh is unchanged. te_pp_arcsec 55.1142 -> 55.115, te_mean_arcsec -159.536 -> -159.394, lost_motion_arcmin 0.173729 -> 0.173587",
        ],
    },
    "flexible_rv221": {
        "values": {
            "te_mean_arcsec": -19.9699277,
            "te_pp_arcsec": 3.8940657,
            "max_pin_force_N": 61.4060892,
            "max_ball_load_N": 114.577587,
        },
        "rtol": {"te_mean_arcsec": 3e-3, "te_pp_arcsec": 0.1, "max_pin_force_N": 1e-3, "max_ball_load_N": 1e-3},
        "notes": [
            "2026-11-23: pinned (flexible main-bearing rings, 0.02-0.04 s, inside the ramps); rv221's TE "
            "p-p amplifies round-off (issue 15: +-0.4 arcsec at the default Newton tolerance), hence 10 %",
            "2026-11-24: crank supports became roller-resolved preloaded tapered-roller pairs in series with the crank's Timoshenko bending (issue 14, branch stiff) instead of one linear 5e8 N/m spring per bearing; inside the load ramp the stiffer, preloaded supports change the transient: TE mean -19.862 -> -19.662 arcsec, p-p 3.19 -> 2.71, max pin force 68.5 -> 83.8 N, max ball load 110.6 -> 112.7 N",
            "2026-11-24: the quasi-static rings condensed into the bearing element (issue 15): the one modelling "
            "difference, the rings' own velocity left out of the contact damping, changes this start-up window "
            "inside the load ramp: TE mean -19.662 -> -19.296 arcsec, p-p 2.71 -> 3.28, max pin force 83.8 -> 104.0 N, "
            "ball load 112.7 -> 113.4 N; with ring_options condense = false the run gives -19.659 arcsec (the old "
            "value to 0.02 %), and in the loaded steady state (0.2-0.3 s) the two formulations agree to 0.03 % on the "
            "TE mean (benchmarks/bench_flexible_model.py)",
            "2026-11-24: friction on in the presets (issue 14, branch fric: pins mu_eff 0.05, needles 0.0025, "
            "v_reg 0.01 mm/s); inside the load ramp of this start-up window the friction changes the transient: "
            "TE mean -19.296 -> -18.982 arcsec, p-p 3.28 -> 4.99, max pin force 104.0 -> 111.5 N, ball load "
            "113.4 -> 115.1 N",
            "2026-11-24: row-kernel speed-ups (issue 15, branch flexspeed): every row call agrees with the previous "
            "kernel within 2e-13 relative, but this window inside the load ramp amplifies round-off in the TE mean "
            "(the disc's position in the first-stage backlash at 20 N m): TE mean -19.2958 -> -19.2590 arcsec, p-p "
            "3.279387 -> 3.279394, max pin force 104.0122 -> 104.0118 N, ball load 113.39841 -> 113.39844 N; the same "
            "code with the condensation's vectorised sums off (another round-off pattern) gives -19.2689 arcsec, so "
            "the TE mean tolerance is 3e-3 (the measured spread 1.9e-3)",
            '2026-11-24: the FE carrier and cycloid-disc bodies enter every model by default (issue 14, branch bodies: carrier.body_model = second_stage.disc_body_model = "condensed_fe"; the carrier in series with the crank supports, the disc rim around the pins); '
            "inside the load ramp: TE mean -19.296 -> -19.221 arcsec, p-p 3.28 -> 5.84 (rv221 p-p amplifies round-off: a 0.08 % change of the disc compliance moved it 5.42 -> 5.84), max pin force 104.0 -> 103.9 N, ball load 113.4 -> 113.5 N",
            "2026-11-24 (merge of fric, pinseat, bodies, rigspeed, flexspeed): inside the load ramp: TE mean -18.901 -> -19.417 arcsec, p-p 5.52 -> 4.72 (rv221's p-p amplifies round-off, tolerance 10 %), max pin force 68.00 -> 88.42 N, ball load 117.06 -> 114.43 N: the old value was pinned on the pin-seat branch; the merge adds the FE carrier and disc bodies and the row-kernel speed-ups, which change this start-up transient",
            '2026-11-24 (housing branch): the pin housing ring enters the models as an elastic pin-ring rotation (housing.body_model = "ring_estimate", c_h from the thin-ring + tube estimate, 8.16e-8 rad/(N m) on rv40e) and the stiffness-test default quarter time became 0.08 s (not used here): te_mean_arcsec -19.4166 -> -20.1296, te_pp_arcsec 4.72292 -> 2.47753, max_pin_force_N 88.4174 -> 56.6409, max_ball_load_N 114.432 -> 120.737',
            "2026-11-24 (rowspeed, issue 15): row kernel and glue rewritten (same physics to round-off), the films' entrainment-speed term added to the row Jacobian, the member objects no longer numerically differentiated by Exudyn: a different Newton path at the default tolerance (1e-3): te_mean_arcsec -20.12964 -> -20.22070, te_pp_arcsec 2.47753 -> 2.48685, max_pin_force_N 56.641 -> 59.174, max_ball_load_N 120.737 -> 121.386. Converged (newton_tolerance (1e-5, 1e-3)) before / after: TE mean -19.9548 / -19.9414, p-p 3.8983 / 3.8978, max pin force 61.807 / 61.795 N, ball load 113.7315 / 113.7320 N; the default tolerance itself is off by 0.9 % (mean), 36 % (p-p) and 6 % (ball load) in this start-up window",
            "2026-11-24 (fecold branch, issue 15): cold-cache cost of the FE bodies: the cycloid disc's flank mesh size is now r_rp (was tooth pitch / 8: rv40e 3 mm for 1.29 mm, 16.9k for 66.7k nodes; rv221 5 mm for 2.2 mm, 32.5k for 107k nodes) and its pin patches carry consistent instead of lumped loads, chosen from a convergence study (flexrv.meshing.parts.CycloidDiscSpec.profile_size: the default within 0.8 % / 0.5 % of the converged disc compliance); the rv40e disc compliance moves 1.4982e-7 -> 1.4626e-7 rad/(N m) (-2.4 %, 5 % of the total compliance; rv221 2.2975e-8 -> 2.2799e-8, -0.8 %); the carrier mesh is unchanged. te_mean_arcsec -20.1296 -> -20.1753, te_pp_arcsec 2.47753 -> 2.47464, max_pin_force_N 56.6409 -> 56.1756, max_ball_load_N 120.737 -> 121.258",
            "2026-11-24 (issue 15, merge of rowspeed and fecold): the dynamic cases run at a converged Newton tolerance (tests/regression_cases.NEWTON_TOLERANCE = (1e-5, 1e-3) instead of the default (1e-3, 0.1)), so the pinned numbers are the model's answer and not the path a default-tolerance Newton took (a faster, equivalent residual changed balls_rv40e's TE p-p 0.4026 -> 0.3759 arcsec at the default tolerance; converged 0.3616 both); re-pinned on the merged code (disc mesh r_rp, row kernel rewrite): te_mean_arcsec -20.1753 -> -19.9699, te_pp_arcsec 2.47464 -> 3.89407, max_pin_force_N 56.1756 -> 61.4061, max_ball_load_N 121.258 -> 114.578",
        ],
    },
}

#: cases run only with ``-m slow`` (cold-cache meshing and CMS)
SLOW = {"flexible_rv221"}
