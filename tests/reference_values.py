"""Pinned reference values of short runs of every model (Exudyn's
``runTestSuiteRefSol.py`` pattern): a drift fails ``tests/test_regression.py``.

Each entry: the case function in ``tests/regression_cases.py``, the values, the
relative tolerance per quantity, and the source of the values with the reason for the
tolerances. An intended change of a value is made here and recorded, with the old and
the new value and its cause, in CHANGELOG.md; an unintended one is a bug.
"""

REFERENCE = {
    "rigid_rv40e": {
        "values": {"te_mean_arcsec": -202.461576, "te_pp_arcsec": 0.620994539, "max_pin_force_N": 647.554787},
        "rtol": {"te_mean_arcsec": 1e-05, "te_pp_arcsec": 0.001, "max_pin_force_N": 0.0001},
        "source": (
            "Rigid model, rv40e: pinned from its own converged run (Newton tolerance "
            "tests/regression_cases.NEWTON_TOLERANCE). A regression guard, not an independent reference: the "
            "physics is verified in tests/test_simulation.py and tests/test_kernel.py. Tolerances: the TE "
            "mean to 1e-5 (round-off of a converged run), the p-p (a difference of two close numbers) to "
            "1e-3."
            " Values after the path compliances entered the models (crank torsion, planet spline, support-"
            "bearing rings, carrier joints) and with the needle clearance at the ISO 5753-1 C2 midpoint (12.5 um) "
            "and the 27 mm carrier bore."
        ),
    },
    "balls_rv40e": {
        "values": {
            "te_mean_arcsec": -202.471653,
            "te_pp_arcsec": 0.785629042,
            "max_pin_force_N": 642.933065,
            "max_ball_load_N": 22.9059261,
        },
        "rtol": {"te_mean_arcsec": 1e-05, "te_pp_arcsec": 0.001, "max_pin_force_N": 0.0001, "max_ball_load_N": 0.0001},
        "source": (
            "Ball-resolved main bearing (rigid rings, quasi-static balls), rv40e: pinned from its own "
            "converged run. Physics verified in tests/test_model_flexible_bearing.py (ball equilibrium vs the"
            " independent ball solver). Tolerances as rigid_rv40e; the ball load to 1e-4."
            " Values after the path compliances entered the models (crank torsion, planet spline, support-"
            "bearing rings, carrier joints) and with the needle clearance at the ISO 5753-1 C2 midpoint (12.5 um) "
            "and the 27 mm carrier bore."
        ),
    },
    "quasi_static_rv40e": {
        "values": {
            "te_pp_arcsec": 0.356927601,
            "te_mean_arcsec": -201.695742,
            "no_load_te_pp_arcsec": 0.297217811,
            "lost_motion_arcmin": 2.03966897,
            "torsional_rigidity_Nm_per_arcmin": 177.456201,
        },
        "rtol": {
            "te_pp_arcsec": 0.001,
            "te_mean_arcsec": 1e-06,
            "no_load_te_pp_arcsec": 0.01,
            "lost_motion_arcmin": 0.0001,
            "torsional_rigidity_Nm_per_arcmin": 0.0001,
        },
        "source": (
            "`flexrv te` on rv40e: pinned from its own run; the solver is verified in "
            "tests/test_quasi_static.py (torque balance, analytic pin loads, wind-up = integral of dT/k_t). "
            "The mean and the rigidity are converged equilibria (1e-6 / 1e-4); the no-load p-p at 1 % of "
            "rated torque is path-sensitive near contact onset (1e-2)."
            " Values after the path compliances entered the models (crank torsion, planet spline, support-"
            "bearing rings, carrier joints) and with the needle clearance at the ISO 5753-1 C2 midpoint (12.5 um) "
            "and the 27 mm carrier bore."
        ),
    },
    "quasi_static_rv40e_grade5": {
        "values": {"te_pp_arcsec": 55.6805618, "te_mean_arcsec": -195.360062, "lost_motion_arcmin": 0.933229499},
        "rtol": {"te_pp_arcsec": 0.001, "te_mean_arcsec": 1e-05, "lost_motion_arcmin": 0.001},
        "source": (
            "`flexrv te` on rv40e with the ISO grade-5 example error set "
            "(flexrv/design/presets/errors/iso_grade5_rv40e.toml): pinned from its own run; the as-built "
            "geometry is verified in tests/test_errors_geometry.py."
            " Values after the path compliances entered the models (crank torsion, planet spline, support-"
            "bearing rings, carrier joints) and with the needle clearance at the ISO 5753-1 C2 midpoint (12.5 um) "
            "and the 27 mm carrier bore."
        ),
    },
    "flexible_rv221": {
        "values": {
            "te_mean_arcsec": -28.5780825,
            "te_pp_arcsec": 8.05024222,
            "max_pin_force_N": 81.3836744,
            "max_ball_load_N": 111.930825,
        },
        "rtol": {"te_mean_arcsec": 0.003, "te_pp_arcsec": 0.1, "max_pin_force_N": 0.001, "max_ball_load_N": 0.001},
        "source": (
            "Flexible main-bearing rings, rv221, inside the load ramps: pinned from its own run (slow: cold-"
            "cache meshing and CMS). rv221's TE p-p in this start-up window amplifies round-off (+-0.4 arcsec"
            " between equivalent Newton paths), hence 10 %; its TE mean varies by 1.9e-3 between equivalent "
            "summation orders, hence 3e-3."
            " Values after the path compliances entered the models (crank torsion, planet spline, support-"
            "bearing rings, carrier joints) and with the needle clearance at the ISO 5753-1 C2 midpoint (17.5 um)."
        ),
    },
}

#: cases run only with ``-m slow`` (cold-cache meshing and CMS)
SLOW = {"flexible_rv221"}
