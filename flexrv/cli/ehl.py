"""CLI: ``flexrv ehl`` — numerical EHL solution of a ball–raceway contact."""

from __future__ import annotations

import math
import time
import warnings
from pathlib import Path
from typing import Any, Optional

import typer

from flexrv.cli._common import JSON_HELP, check_output_file, console, emit, kv_table
from flexrv.errors import ConvergenceError, InputError

PRESET_HELP = (
    "Preset name or design TOML. Without explicit --load-n/--speed-m-s/--rx-m/--ry-m: the main "
    "bearing's most-loaded ball (inner-race contact) at the preset's operating point. With them: "
    "the preset (default rv221) supplies only the materials (balls, rings) and the lubricant."
)


#: largest contact semi-axis / radius of curvature (same direction) for which the
#: Hertz half-space assumption is accepted without a warning (Johnson, Contact
#: Mechanics, sec. 4.1: a << R)
HERTZ_SIZE_LIMIT = 0.1


def operating_contact(reducer) -> dict[str, Any]:
    """Inner-race contact of the main bearing's most-loaded ball at the design's operating point.

    Ball loads: :func:`flexrv.analysis.bearing_load.ball_load_distribution` (rigid rings,
    preload + external forces/moment of ``reducer.operating``); radii at the loaded
    contact angle; entrainment speed for pure rolling with the carrier (inner ring)
    turning at input speed / ratio (:func:`flexrv.geometry.kinematics.member_speeds`)
    and the housing (outer ring) fixed.
    """
    from flexrv.analysis.bearing_load import ball_load_distribution, max_ball_contact
    from flexrv.contact.hertz import effective_modulus
    from flexrv.geometry.bearing import BallBearingGeometry
    from flexrv.geometry.kinematics import member_speeds

    geom = BallBearingGeometry.from_design(reducer.main_bearing)
    e_eff = _reduced_modulus(reducer, effective_modulus)
    op = reducer.operating
    loads = ball_load_distribution(
        geom,
        e_eff,
        force=(op.external_radial_force_N, 0.0, op.external_axial_force_N),
        moment=(op.tilting_moment_Nm, 0.0),
    )
    _, _, (rx_i, ry_i, _, _) = max_ball_contact(geom, e_eff, loads)
    fs, ss = reducer.first_stage, reducer.second_stage
    speeds = member_speeds(op.input_speed, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    alpha = float(loads.contact_angle[loads.max_index])
    u = float(geom.entrainment_speed(abs(float(speeds.carrier)), 0.0, alpha))
    return {
        "load": float(loads.max_load),
        "speed": u,
        "rx": float(rx_i),
        "ry": float(ry_i),
        "e_eff": e_eff,
        "contact_angle_rad": alpha,
        "carrier_speed_rad_s": float(speeds.carrier),
        "ratio": float(speeds.ratio),
    }


def check_half_space(case: dict[str, Any]) -> None:
    """InputError naming the options when the Hertz contact of an explicit case is larger
    than the radii of curvature that carry it (a semi-axis beyond min(rx, ry)): the
    half-space theory of Hertz and of the film solver does not describe such a contact
    (Johnson, Contact Mechanics, sec. 4.1: a << R), so no film is computed."""
    from flexrv.contact.hertz import point_contact

    pc = point_contact(case["load"], case["rx"], case["ry"], case["e_eff"])
    a, b = float(pc.a), float(pc.b)
    overall = max(a, b) / min(case["rx"], case["ry"])
    if not math.isfinite(overall) or overall > 1.0:
        raise InputError(
            f"--load-n {case['load']:g} --rx-m {case['rx']:g} --ry-m {case['ry']:g}: the Hertz contact "
            f"(semi-axes {a:.3g} m along y, {b:.3g} m along x) is {overall:.3g} times the smaller radius of "
            "curvature; the half-space theory needs semi-axes <= min(rx, ry) (and <= "
            f"{HERTZ_SIZE_LIMIT:g} x the radius for physical results): reduce the load or the radius ratio"
        )


def _reduced_modulus(reducer, effective_modulus) -> float:
    ball = reducer.material("rolling_elements")
    ring = reducer.material("bearing_rings")
    return float(effective_modulus(ball.youngs_modulus, ball.poisson_ratio, ring.youngs_modulus, ring.poisson_ratio))


def ehl_case(
    preset: str = "rv221",
    load_n: Optional[float] = None,
    speed_m_s: Optional[float] = None,
    rx_m: Optional[float] = None,
    ry_m: Optional[float] = None,
    grid: int = 129,
    grid_tol: Optional[float] = 0.02,
    max_grid: Optional[int] = None,
):
    """Solve one case; returns (report dict, EHLResult)."""
    from flexrv.contact.hertz import effective_modulus
    from flexrv.design import load as load_design
    from flexrv.ehl.film import hamrock_dowson, moes_central
    from flexrv.ehl.solver import LubricantProperties, solve_point_contact

    reducer = load_design(preset)
    explicit = {"--load-n": load_n, "--speed-m-s": speed_m_s, "--rx-m": rx_m, "--ry-m": ry_m}
    given = [k for k, v in explicit.items() if v is not None]
    if given and len(given) != 4:
        missing = [k for k, v in explicit.items() if v is None]
        raise InputError(f"explicit case needs all of --load-n --speed-m-s --rx-m --ry-m; missing {', '.join(missing)}")
    if given:
        for opt, value in explicit.items():
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{opt} {value!r}: must be a finite number > 0")
        case = {
            "load": load_n,
            "speed": speed_m_s,
            "rx": rx_m,
            "ry": ry_m,
            "e_eff": _reduced_modulus(reducer, effective_modulus),
        }
        source = f"explicit; materials and lubricant from preset {preset}"
        check_half_space(case)
    else:
        case = operating_contact(reducer)
        source = (
            f"preset {preset}: most-loaded main-bearing ball, inner race, at the operating point "
            f"(carrier {case['carrier_speed_rad_s']:.4g} rad/s, ratio {case['ratio']:.4g})"
        )
    lub = LubricantProperties.from_design(reducer.lubricant)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:  # grid not converged: reported, not printed twice
        warnings.simplefilter("always", RuntimeWarning)
        import numpy as np

        try:
            res = solve_point_contact(
                case["load"],
                case["speed"],
                case["rx"],
                case["ry"],
                case["e_eff"],
                lub,
                grid=grid,
                grid_tol=grid_tol,
                max_grid=max_grid,
            )
        except (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError, OverflowError, ConvergenceError) as exc:
            raise InputError(
                f"EHL solve failed for load {case['load']:g} N, speed {case['speed']:g} m/s, "
                f"rx {case['rx']:g} m, ry {case['ry']:g} m ({type(exc).__name__}: {exc}); the case is "
                "outside the solver's range (check --load-n/--speed-m-s/--rx-m/--ry-m)"
            ) from None
    elapsed = time.perf_counter() - t0
    args = (case["load"], case["speed"], case["rx"], case["ry"], case["e_eff"], lub.viscosity, lub.pressure_viscosity)
    hd_c, hd_min = hamrock_dowson(*args)
    report = {
        "case": source,
        "inputs": {
            "load_N": case["load"],
            "entrainment_speed_m_s": case["speed"],
            "rx_m": case["rx"],
            "ry_m": case["ry"],
            "reduced_modulus_Pa": case["e_eff"],
            "viscosity_Pa_s": lub.viscosity,
            "pressure_viscosity_1_Pa": lub.pressure_viscosity,
            "roelands_pressure_viscosity_1_Pa": lub.roelands_alpha,
            "roelands_z": lub.roelands_z,
            "roelands_p0_Pa": lub.roelands_p0,
            "density_kg_m3": lub.density,
            "dowson_higginson_a_1_Pa": lub.dh_a,
            "dowson_higginson_b_1_Pa": lub.dh_b,
            "grid": grid,
            "grid_tol": grid_tol,
            "max_grid": max_grid,
            "wedge_order": res.wedge_order,
        },
        "outputs": {
            "h_central_m": res.h_central,
            "h_central_grid_m": res.h_central_grid,
            "h_central_coarse_grid_m": res.h_central_coarse,
            "extrapolated": res.extrapolated,
            "grid_used": res.grid,
            "grid_change": res.grid_change,
            "grid_converged": res.grid_converged,
            "h_min_m": res.h_min,
            "p_max_Pa": res.p_max,
            "hertz_pressure_Pa": res.hertz_pressure,
            "hertz_a_m": res.hertz_a,
            "hertz_b_m": res.hertz_b,
            "hamrock_dowson_h_central_m": float(hd_c),
            "hamrock_dowson_h_min_m": float(hd_min),
            "moes_h_central_m": float(moes_central(*args)),
            "iterations": res.iterations,
            "total_iterations": res.total_iterations,
            "residual": res.residual,
            "load_error": res.load_error,
            "solve_time_s": elapsed,
        },
    }
    warn = [str(w.message) for w in caught if "EHL" in str(w.message)]
    # Hertz (and the half-space of the film solver) assume contact semi-axes small
    # against the radii of curvature: flag a/Ry or b/Rx above HERTZ_SIZE_LIMIT (a is
    # the semi-axis along y, b along x), and any semi-axis beyond the smaller radius
    # (a contact larger than the curvature of the bodies that carry it)
    a, b = res.hertz_a, res.hertz_b
    paired = max(a / case["ry"], b / case["rx"])
    overall = max(a, b) / min(case["rx"], case["ry"])
    if paired > HERTZ_SIZE_LIMIT or overall > 1.0:
        warn.append(
            f"contact semi-axes a = {a:.3g} m (along y), b = {b:.3g} m (along x) with rx = {case['rx']:.3g} m, "
            f"ry = {case['ry']:.3g} m: semi-axis/radius = {max(paired, overall):.3g}, outside the "
            f"Hertz/half-space assumptions (a/ry, b/rx <= {HERTZ_SIZE_LIMIT:g}, semi-axes <= min(rx, ry)); "
            "results are not physical"
        )
    if warn:
        report["warnings"] = warn
    return report, res


def ehl(
    preset: str = typer.Option("rv221", "--preset", help=PRESET_HELP),
    load_n: Optional[float] = typer.Option(None, "--load-n", help="Normal load Q (N)."),
    speed_m_s: Optional[float] = typer.Option(None, "--speed-m-s", help="Mean entrainment speed (u1+u2)/2 (m/s)."),
    rx_m: Optional[float] = typer.Option(None, "--rx-m", help="Effective radius along the entrainment (m)."),
    ry_m: Optional[float] = typer.Option(None, "--ry-m", help="Effective radius across the entrainment (m)."),
    grid: int = typer.Option(
        129,
        "--grid",
        help="Nodes per direction, 2^k+1 (65, 129, 257); the first grid of the adaptive refinement at >= 129.",
    ),
    grid_tol: float = typer.Option(
        0.02,
        "--grid-tol",
        help="Refine the grid until h_c changes by less than this fraction from the next-coarser grid (0.02 = 2 %).",
    ),
    max_grid: Optional[int] = typer.Option(
        None,
        "--max-grid",
        help="Finest grid of the refinement (default 513 at grid >= 129; = --grid below, i.e. no refinement).",
    ),
    png: Optional[str] = typer.Option(None, "--png", help="Write pressure/film centre lines and 2-D maps to this PNG."),
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
) -> None:
    """Numerical EHL solution (Reynolds + Roelands + Dowson-Higginson + Boussinesq) of a
    ball-raceway contact, compared with Hamrock-Dowson and Moes."""
    if png:
        check_output_file(Path(png), "--png", (".png",))
    report, res = ehl_case(preset, load_n, speed_m_s, rx_m, ry_m, grid, grid_tol, max_grid)
    if png:
        from flexrv.viz.ehl_plots import plot_ehl_solution

        report["png"] = str(plot_ehl_solution(res, png))

    def render(data: dict[str, Any]) -> None:
        console.print(f"EHL point contact — {data['case']}", style="bold")
        units = {
            "_N": "N",
            "_m_s": "m/s",
            "_m": "m",
            "_Pa": "Pa",
            "_Pa_s": "Pa s",
            "_1_Pa": "1/Pa",
            "_kg_m3": "kg/m^3",
            "_s": "s",
        }

        def unit(key: str) -> str:
            for suffix, u in sorted(units.items(), key=lambda kv: -len(kv[0])):
                if key.endswith(suffix):
                    return u
            return ""

        for section in ("inputs", "outputs"):
            console.print(kv_table(section, [(k, v, unit(k)) for k, v in data[section].items()]))
        for message in data.get("warnings", []):
            console.print(f"warning: {message}", style="yellow")
        if "png" in data:
            console.print(f"plot: {data['png']}")

    emit(report, json, render)


def register(app: typer.Typer) -> None:
    """Add the ``ehl`` command to the app."""
    app.command("ehl")(ehl)
