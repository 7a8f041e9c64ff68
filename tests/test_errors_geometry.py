"""Manufacturing and assembly errors: the [errors] table, the as-built geometry
(flexrv.geometry.as_built) and the analytic pin loads that read it (issue 12, section 1).

Closed forms are stated in each test's docstring with their tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from flexrv.analysis.pin_load import (
    disc_effective_modulus,
    pin_contact_constant,
    pin_load_distribution,
    reducer_pin_loads,
)
from flexrv.cli import app
from flexrv.design import error_set_names, from_dict, load, load_error_set, loads, to_toml, with_errors
from flexrv.design.manufacturing import ASSEMBLY_PENETRATION_LIMIT_UM, ManufacturingErrors
from flexrv.errors import ConfigError
from flexrv.geometry.as_built import (
    as_built,
    as_built_pin_gap,
    assembly_disc_poses,
    assembly_penetration,
    profile_deviation,
)
from flexrv.geometry.cycloid import nominal_disc_pose, pin_gap, to_disc_frame
from flexrv.units import M_PER_UM, RAD_PER_ARCMIN, RAD_PER_DEG

Z, N, ND = 40, 3, 2  # rv40e: pins, cranks, discs


def _with(errors: dict, name: str = "rv40e"):
    data = load(name).model_dump()
    data["errors"] = errors
    return from_dict(data)


def _zeros(n):
    return [0.0] * n


# --------------------------------------------------------------------------- zero errors
@pytest.mark.parametrize("name", ["rv40e", "rv221"])
def test_zero_errors_as_built_is_nominal_exactly(name):
    """No [errors] table: every as-built array equals the nominal geometry written
    out independently here (pins R_p (sin psi, cos psi), psi = 2 pi j / z_rp; crank
    bores a_w (cos beta, sin beta); holes = Rot(-chi0_k / z_c) bores; nominal radii,
    modifications, eccentricity and clearance; no harmonics, runout, phase error),
    bit for bit (the errors enter as exact zeros)."""
    r = load(name)
    ss, fs = r.second_stage, r.first_stage
    z, n, nd = ss.pin_count, fs.n_planets, ss.n_discs
    assert r.errors.is_zero() and r.errors == ManufacturingErrors()
    ab = as_built(r)
    psi = 2.0 * np.pi * np.arange(z) / z
    np.testing.assert_array_equal(ab.pins, ss.pin_circle_radius * np.stack([np.sin(psi), np.cos(psi)], -1))
    np.testing.assert_array_equal(ab.pin_radii, np.full(z, ss.pin_radius))
    np.testing.assert_array_equal(
        ab.disc_profile,
        np.tile([ss.modification_shift, ss.modification_equidistant, ss.modification_rotation], (nd, 1)),
    )
    assert ab.profile_harmonics.shape == (nd, 0, 3)
    beta = 2.0 * np.pi * np.arange(n) / n
    bores = fs.center_distance * np.stack([np.cos(beta), np.sin(beta)], -1)
    np.testing.assert_array_equal(ab.crank_bores, bores)
    for k in range(nd):
        rot = 2.0 * np.pi * k / nd / ss.disc_teeth
        c, s = math.cos(rot), math.sin(rot)
        np.testing.assert_array_equal(
            ab.holes[k], np.stack([c * bores[:, 0] + s * bores[:, 1], -s * bores[:, 0] + c * bores[:, 1]], -1)
        )
    np.testing.assert_array_equal(ab.eccentricities, np.full((n, nd), ss.eccentricity))
    np.testing.assert_array_equal(
        ab.needle_clearances, np.full((n, nd), 0.5 * r.needle_bearing.radial_clearance_um * 1e-6)
    )
    for arr in (
        ab.eccentric_phase_errors,
        ab.support_clearances,
        ab.sun_runout,
        ab.planet_runout,
        ab.planet_phase_errors,
    ):
        assert not np.any(arr)
    # the rigid model's elements read the same arrays, each in its own parameters
    from flexrv.model.cranks_discs import CrankSupports, NeedleBearings
    from flexrv.model.drive import drive_parameters
    from flexrv.model.gear_stage import GearMeshes
    from flexrv.model.pins import PinContacts

    drive = drive_parameters(r)
    own = {cls: cls.parameters(r, drive) for cls in (PinContacts, NeedleBearings, CrankSupports, GearMeshes)}
    for cls, fields in (
        (PinContacts, {"pins": "pins", "pin_radii": "pin_radii", "disc_profile": "disc_profile"}),
        (PinContacts, {"profile_harmonics": "profile_harmonics"}),
        (NeedleBearings, {"holes": "holes", "eccentricities": "eccentricities", "clearances": "needle_clearances"}),
        (NeedleBearings, {"eccentric_phase_errors": "eccentric_phase_errors"}),
        (CrankSupports, {"crank_bores": "crank_bores", "support_clearances": "support_clearances"}),
        (GearMeshes, {"sun_runout": "sun_runout", "planet_runout": "planet_runout"}),
        (GearMeshes, {"planet_phase_errors": "planet_phase_errors"}),
    ):
        for field, key in fields.items():
            np.testing.assert_array_equal(getattr(own[cls], field), getattr(ab, key))
    np.testing.assert_array_equal(drive.chi0, ab.chi0)
    # assembly pose of the ideal design = nominal pose (round-off)
    centres, rots = assembly_disc_poses(r, ab)
    for k in range(nd):
        c0, r0 = nominal_disc_pose(z, ss.eccentricity, 2.0 * np.pi * k / nd)
        np.testing.assert_allclose(centres[k], c0, atol=1e-15)
        assert rots[k] == pytest.approx(float(r0), abs=1e-15)


def test_zero_errors_pin_loads_unchanged():
    """Zero errors: reducer_pin_loads (as-built pins, radii, profile) equals the
    scalar call with the nominal geometry exactly (same arrays in, same numbers out),
    for both discs (disc k at crank angle chi + 2 pi k / n_discs)."""
    r = load("rv40e")
    ss = r.second_stage
    for k in range(ss.n_discs):
        res = reducer_pin_loads(r, 412.0, crank_angle=0.1, disc=k)
        ref = pin_load_distribution(
            412.0 / ss.n_discs,
            ss.pin_count,
            ss.pin_circle_radius,
            ss.pin_radius,
            ss.eccentricity,
            ss.disc_width,
            disc_effective_modulus(r),
            ss.modification_shift,
            ss.modification_equidistant,
            ss.modification_rotation,
            0.1 + 2.0 * np.pi * k / ss.n_discs,
            stiffness_constant=pin_contact_constant(r).k,
        )  # the design's pin path (issue 14)
        np.testing.assert_array_equal(res.forces, ref.forces)
        np.testing.assert_array_equal(res.clearance, ref.clearance)
        assert res.rotation == ref.rotation and res.max_pressure == ref.max_pressure


# --------------------------------------------------------------------------- closed forms
def test_uniform_pin_radius_equals_reduced_equidistant():
    """A pin larger by d everywhere closes every gap by exactly d, like an
    equidistant modification smaller by d (pin_gap: gap = s(P) + dr_rp - (r_i - r_rp)).
    rv40e (dr_rp = +5 um) with pin_radius_um = 3 vs dr_rp = 2 um: same forces,
    clearances and rotation to 1e-9 relative (round-off of 5e-3 mm - 3e-3 mm), for
    both discs, and the assembly clearance shrinks by exactly d (5 -> 2 um, 1e-12 m)."""
    d_um = 3.0
    r_err = _with({"pins": {"pin_radius_um": d_um}})
    r_eq = from_dict(
        {
            **load("rv40e").model_dump(),
            "second_stage": {
                **load("rv40e").second_stage.model_dump(),
                "modification_equidistant_mm": 0.005 - d_um * 1e-3,
            },
        }
    )
    for k in range(ND):
        a = reducer_pin_loads(r_err, 412.0, crank_angle=0.2, disc=k)
        b = reducer_pin_loads(r_eq, 412.0, crank_angle=0.2, disc=k)
        np.testing.assert_allclose(a.forces, b.forces, rtol=1e-9, atol=1e-9 * b.max_force)
        np.testing.assert_allclose(a.clearance, b.clearance, rtol=0, atol=1e-15)
        assert a.rotation == pytest.approx(b.rotation, rel=1e-9)
        assert a.n_contact == b.n_contact
    assert assembly_penetration(r_err)[0] == pytest.approx(-(5.0 - d_um) * M_PER_UM, abs=1e-12)


def test_pin_position_errors_move_the_pin_along_its_radius_and_tangent():
    """Radial error rho on pin 7 moves its centre by exactly rho (sin psi_7, cos psi_7)
    (outward); tangential error t on pin 0 (at (0, R_p)) moves it by t along -x
    (counter-clockwise); every other pin is untouched (1e-18 m)."""
    rad, tan = _zeros(Z), _zeros(Z)
    rad[7], tan[0] = 12.5, -4.0
    r = _with({"pins": {"pin_radial_position_um": rad, "pin_tangential_position_um": tan}})
    ab, nom = as_built(r), as_built(load("rv40e"))
    psi7 = 2.0 * np.pi * 7 / Z
    moved = ab.pins - nom.pins
    np.testing.assert_allclose(moved[7], 12.5e-6 * np.array([np.sin(psi7), np.cos(psi7)]), atol=1e-18)
    np.testing.assert_allclose(moved[0], [4.0e-6, 0.0], atol=1e-18)
    assert np.linalg.norm(ab.pins[7]) - r.second_stage.pin_circle_radius == pytest.approx(12.5e-6, abs=1e-15)
    others = np.ones(Z, bool)
    others[[0, 7]] = False
    assert not np.any(moved[others])


def test_crank_disc_errors_land_at_crank_disc():
    """[crank][disc] fields land at [crank][disc] of the arrays, per-crank fields at
    [crank], unit conversions exact (um -> m, arcmin -> rad, deg -> rad); the
    crank-hole and bore errors move the centres along their radius / CCW tangent."""
    ecc = [[0.0, 0.0], [0.0, 0.0], [0.0, 3.0]]
    phase = [[0.0, 0.0], [0.0, -2.0], [0.0, 0.0]]
    needle = [[1.0, 0.0], [0.0, 0.0], [0.0, -2.0]]
    r = _with(
        {
            "cranks": {
                "eccentricity_um": ecc,
                "eccentric_phase_arcmin": phase,
                "bore_radial_um": [0.0, 2.0, 0.0],
                "bore_tangential_um": [1.5, 0.0, 0.0],
            },
            "clearances": {"needle_extra_clearance_um": needle, "support_clearance_um": [0.0, 4.0, 0.0]},
            "first_stage": {
                "sun_runout_um": 2.0,
                "sun_runout_phase_deg": 30.0,
                "planet_runout_um": [0.0, 1.0, 0.0],
                "planet_runout_phase_deg": 45.0,
                "planet_phase_arcmin": [0.0, 0.0, 0.5],
            },
            "discs": [{"hole_radial_um": [0.0, 0.0, 1.0]}, {}],
        }
    )
    ab, nom = as_built(r), as_built(load("rv40e"))
    a, c0 = r.second_stage.eccentricity, 0.5 * r.needle_bearing.radial_clearance_um * 1e-6
    expected = np.full((N, ND), a)
    expected[2, 1] += 3e-6
    np.testing.assert_array_equal(ab.eccentricities, expected)
    expected = np.zeros((N, ND))
    expected[1, 1] = -2.0 * RAD_PER_ARCMIN
    np.testing.assert_array_equal(ab.eccentric_phase_errors, expected)
    np.testing.assert_allclose(ab.needle_clearances, c0 + np.array(needle) * 1e-6, atol=1e-21)
    np.testing.assert_array_equal(ab.support_clearances, [0.0, 4e-6, 0.0])
    np.testing.assert_allclose(ab.sun_runout, [2e-6, 30.0 * RAD_PER_DEG])
    np.testing.assert_allclose(
        ab.planet_runout, [[0.0, 45 * RAD_PER_DEG], [1e-6, 45 * RAD_PER_DEG], [0.0, 45 * RAD_PER_DEG]]
    )
    np.testing.assert_allclose(ab.planet_phase_errors, [0.0, 0.0, 0.5 * RAD_PER_ARCMIN])
    b = 2.0 * np.pi / 3  # crank 1
    np.testing.assert_allclose(
        ab.crank_bores[1] - nom.crank_bores[1], 2e-6 * np.array([np.cos(b), np.sin(b)]), atol=1e-18
    )
    np.testing.assert_allclose(ab.crank_bores[0] - nom.crank_bores[0], [0.0, 1.5e-6], atol=1e-18)
    u = nom.holes[0, 2] / np.linalg.norm(nom.holes[0, 2])
    np.testing.assert_allclose(ab.holes[0, 2] - nom.holes[0, 2], 1e-6 * u, atol=1e-18)
    np.testing.assert_array_equal(ab.holes[1], nom.holes[1])


def test_profile_harmonic_reduces_the_gap_by_its_value_at_the_foot_point():
    """A disc harmonic (order n, amplitude A, phase p) adds A cos(n phi* + p) of
    material at the pin's foot point phi*: as_built_pin_gap = pin_gap - delta(phi*)
    exactly (foot points from pin_gap), and the as-built table carries (n, A [m], p [rad])."""
    r = _with(
        {
            "discs": [
                {
                    "harmonics": [
                        {"order": 39, "amplitude_um": 2.0, "phase_deg": 40.0},
                        {"order": 1, "amplitude_um": 1.0},
                    ]
                },
                {},
            ]
        }
    )
    ab = as_built(r)
    ss = r.second_stage
    np.testing.assert_allclose(ab.profile_harmonics[0], [[39, 2e-6, 40 * RAD_PER_DEG], [1, 1e-6, 0.0]])
    assert not np.any(ab.profile_harmonics[1, :, 1])
    center, rot = nominal_disc_pose(Z, ss.eccentricity, 0.3)
    p = to_disc_frame(ab.pins, center, rot)
    g0, _, phi = pin_gap(p, Z, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity, *ab.disc_profile[0])
    g, _, phi1 = as_built_pin_gap(
        p,
        ab.pin_radii,
        Z,
        ss.pin_circle_radius,
        ss.pin_radius,
        ss.eccentricity,
        ab.disc_profile[0],
        ab.profile_harmonics[0],
    )
    np.testing.assert_array_equal(phi1, phi)
    closed = 2e-6 * np.cos(39 * phi + 40 * RAD_PER_DEG) + 1e-6 * np.cos(phi)
    np.testing.assert_allclose(g, g0 - closed, rtol=0, atol=1e-18)
    np.testing.assert_allclose(profile_deviation(phi, ab.profile_harmonics[0]), closed, atol=1e-20)
    # the analytic pin loads read the harmonics: disc 0 changes, disc 1 does not
    assert reducer_pin_loads(r, 412.0, disc=0).max_force != reducer_pin_loads(load("rv40e"), 412.0, disc=0).max_force
    np.testing.assert_array_equal(
        reducer_pin_loads(r, 412.0, disc=1).forces, reducer_pin_loads(load("rv40e"), 412.0, disc=1).forces
    )


def test_disc_rotation_error_is_a_rigid_turn_of_that_disc():
    """errors.discs[k].rotation_arcmin adds to the disc's rotation modification: the
    pin forces are unchanged (the exact method is invariant under a rigid turn of
    the profile, 1e-6 relative) and the disc's loaded rotation is smaller by it."""
    d = 3.0
    r = _with({"discs": [{"rotation_arcmin": -d}, {}]})
    a, b = reducer_pin_loads(r, 412.0, disc=0), reducer_pin_loads(load("rv40e"), 412.0, disc=0)
    np.testing.assert_allclose(a.forces, b.forces, rtol=1e-6, atol=1e-6 * b.max_force)
    assert a.rotation == pytest.approx(b.rotation + d * RAD_PER_ARCMIN, abs=1e-12)


def test_assembly_pose_follows_eccentricity_errors():
    """Equal eccentricity errors +e on every crank of disc 0 move its assembly centre
    radially by exactly e (Procrustes fit of the holes onto bore + eccentric), rotation
    unchanged (1e-15)."""
    r = _with({"cranks": {"eccentricity_um": [[2.0, 0.0]] * N}})
    c, rot = assembly_disc_poses(r, as_built(r))
    c0, rot0 = assembly_disc_poses(load("rv40e"), as_built(load("rv40e")))
    np.testing.assert_allclose(c[0] - c0[0], [0.0, 2e-6], atol=1e-15)
    np.testing.assert_allclose(c[1], c0[1], atol=1e-15)
    np.testing.assert_allclose(rot, rot0, atol=1e-15)


# --------------------------------------------------------------------------- bad input
BAD = [
    ({"pins": {"pin_radius_um": [1.0] * 39}}, "errors.pins.pin_radius_um", "exactly 40 values"),
    ({"pins": {"pin_radius_um": float("nan")}}, "errors.pins.pin_radius_um", "NaN"),
    (
        {"pins": {"pin_tangential_position_um": [0.0] * 5 + [float("inf")] + [0.0] * 34}},
        "errors.pins.pin_tangential_position_um[5]",
        "-500..500 um",
    ),
    ({"pins": {"pin_radial_position_um": 600.0}}, "errors.pins.pin_radial_position_um", "-500..500 um"),
    ({"pins": {"pin_radius_um": "2"}}, "errors.pins.pin_radius_um", "number"),
    ({"pins": {"pin_radius_um": True}}, "errors.pins.pin_radius_um", "number"),
    (
        {"cranks": {"eccentricity_um": [[0.0, 0.0], [0.0, 0.0], [0.0, float("nan")]]}},
        "errors.cranks.eccentricity_um[2][1]",
        "NaN",
    ),
    ({"cranks": {"eccentricity_um": [[0.0, 0.0], [0.0, 0.0]]}}, "errors.cranks.eccentricity_um", "N = 3"),
    (
        {"cranks": {"eccentricity_um": [[0.0, 0.0], [0.0], [0.0, 0.0]]}},
        "errors.cranks.eccentricity_um[1]",
        "n_discs = 2",
    ),
    ({"cranks": {"eccentricity_um": [0.0, 0.0, 0.0]}}, "errors.cranks.eccentricity_um[0]", "one value per disc"),
    (
        {"cranks": {"eccentric_phase_arcmin": [[0.0, 0.0], [61.0, 0.0], [0.0, 0.0]]}},
        "errors.cranks.eccentric_phase_arcmin[1][0]",
        "-60..60 arcmin",
    ),
    ({"cranks": {"bore_radial_um": [1.0, 2.0]}}, "errors.cranks.bore_radial_um", "exactly 3 values"),
    ({"discs": [{}]}, "errors.discs", "n_discs = 2"),
    ({"discs": [{}, {"rotation_arcmin": -75.0}]}, "errors.discs[1].rotation_arcmin", "-60..60 arcmin"),
    ({"discs": [{"harmonics": [{"order": 0, "amplitude_um": 1.0}]}, {}]}, "errors.discs[0].harmonics[0].order", ">= 1"),
    (
        {"discs": [{}, {"harmonics": [{"order": 161, "amplitude_um": 1.0}]}]},
        "errors.discs[1].harmonics[0].order",
        "1..4 z_rp = 160",
    ),
    (
        {"discs": [{"harmonics": [{"order": 2, "amplitude_um": -1.0}]}, {}]},
        "errors.discs[0].harmonics[0].amplitude_um",
        "0..500 um",
    ),
    (
        {"discs": [{"harmonics": [{"order": 2, "amplitude_um": 1.0, "phase_deg": float("inf")}]}, {}]},
        "errors.discs[0].harmonics[0].phase_deg",
        "finite",
    ),
    ({"discs": [{"hole_tangential_um": [1.0] * 4}, {}]}, "errors.discs[0].hole_tangential_um", "exactly 3 values"),
    ({"first_stage": {"sun_runout_um": -1.0}}, "errors.first_stage.sun_runout_um", "0..500 um"),
    (
        {"first_stage": {"planet_phase_arcmin": [0.0, 90.0, 0.0]}},
        "errors.first_stage.planet_phase_arcmin[1]",
        "-60..60",
    ),
    (
        {"clearances": {"needle_extra_clearance_um": [[0.0, 0.0], [-7.0, 0.0], [0.0, 0.0]]}},
        "errors.clearances.needle_extra_clearance_um[1][0]",
        "total needle clearance",
    ),
    ({"clearances": {"support_clearance_um": -1.0}}, "errors.clearances.support_clearance_um", "0..500 um"),
    ({"pins": {"pin_size_um": 1.0}}, "errors.pins.pin_size_um", "unknown field"),
    ({"pins": {"pin_radius_um": 30.0}}, "errors.pins:", "penetrates disc"),
    ({"discs": [{"rotation_arcmin": 10.0}, {}]}, "errors.discs:", "penetrates disc"),
]


@pytest.mark.parametrize("errors,field,text", BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_bad_errors_name_the_field(errors, field, text):
    """Every bad input class (wrong list length, NaN/inf, out of bounds, wrong type,
    unknown field, interference at assembly) -> one ConfigError naming the full field
    path and the allowed range."""
    with pytest.raises(ConfigError) as info:
        _with(errors)
    msg = str(info.value)
    assert field in msg and text in msg, msg


def test_interference_message_names_the_group():
    """Uniform pin radius +30 um against the +5 um equidistant clearance: penetration
    25 um > the 20 um limit; the message names errors.pins (alone 25 um) and the
    limit. 24 um (19 um) passes."""
    with pytest.raises(ConfigError) as info:
        _with({"pins": {"pin_radius_um": 30.0}})
    msg = str(info.value)
    assert (
        "errors.pins: the as-built parts interfere" in msg
        and f"{ASSEMBLY_PENETRATION_LIMIT_UM:g} um" in msg
        and "errors.pins alone: 25 um interference" in msg
    )
    assert assembly_penetration(_with({"pins": {"pin_radius_um": 24.0}}))[0] == pytest.approx(19e-6, abs=1e-12)


def test_cli_bad_errors_exit_2(tmp_path):
    """`flexrv show` of a design with a bad [errors] value: exit 2, the field named, no traceback."""
    import subprocess
    import sys

    path = tmp_path / "bad.toml"
    path.write_text(
        to_toml(load("rv40e")) + "\n[errors.cranks]\neccentricity_um = [[0.0, 0.0], [0.0, 0.0], [0.0, 900.0]]\n"
    )
    proc = subprocess.run([sys.executable, "-m", "flexrv", "show", str(path)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "errors.cranks.eccentricity_um[2][1]" in proc.stderr and "Traceback" not in proc.stderr


# --------------------------------------------------------------------------- TOML round trip, show
def _example():
    return _with(
        {
            "pins": {"pin_radius_um": 2.0, "pin_tangential_position_um": [1.0] + _zeros(38) + [-1.5]},
            "cranks": {"eccentricity_um": [[0.0, 1.0], [2.0, 0.0], [0.0, 3.0]]},
            "discs": [
                {"rotation_arcmin": 0.5, "harmonics": [{"order": 1, "amplitude_um": 2.0, "phase_deg": 30.0}]},
                {"hole_radial_um": [1.0, -1.0, 0.5]},
            ],
            "first_stage": {"sun_runout_um": 3.0},
        }
    )


def test_toml_round_trip_with_errors(tmp_path):
    """to_toml writes the non-zero [errors] fields; loads gives the identical design;
    an error-free design has no [errors] table; `flexrv show --toml` round-trips too."""
    r = _example()
    text = to_toml(r)
    assert "[errors.pins]" in text and "[[errors.discs]]" in text
    assert loads(text) == r
    assert "[errors" not in to_toml(load("rv40e"))
    path = tmp_path / "d.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["show", str(path), "--toml"])
    assert result.exit_code == 0
    assert loads(result.stdout) == r


def test_show_prints_nonzero_errors(tmp_path):
    """`flexrv show` lists exactly the non-zero error fields (and says none for an ideal design)."""
    path = tmp_path / "d.toml"
    path.write_text(to_toml(_example()))
    out = CliRunner().invoke(app, ["show", str(path)], terminal_width=200).stdout
    for field in (
        "errors.pins.pin_radius_um",
        "errors.pins.pin_tangential_position_um",
        "errors.cranks.eccentricity_um",
        "errors.discs[0].rotation_arcmin",
        "errors.discs[0].harmonics[0]",
        "errors.discs[1].hole_radial_um",
        "errors.first_stage.sun_runout_um",
    ):
        assert field in out, field
    assert "planet_runout" not in out and "support_clearance" not in out
    assert "errors: none" in CliRunner().invoke(app, ["show", "rv40e"]).stdout


@pytest.mark.parametrize("name", ["rv40e", "rv221"])
def test_example_error_sets_load(name):
    """The example grade-5 error sets validate on their presets: every group that
    the file sets is non-zero, the assembly penetration stays within the limit, the
    file is exactly what `python -m flexrv.workflows._error_sets` writes, and the pin loads
    of both discs read it."""
    from flexrv.design import error_set_path
    from flexrv.workflows._error_sets import iso_grade5_toml

    assert f"iso_grade5_{name}" in error_set_names()
    assert error_set_path(f"iso_grade5_{name}").read_text() == iso_grade5_toml(name)
    r = with_errors(name, load_error_set(f"iso_grade5_{name}"))
    groups = {path.split(".")[1].split("[")[0] for path, _ in r.errors.nonzero_items()}
    assert groups == {"pins", "discs", "cranks", "first_stage"}
    assert assembly_penetration(r)[0] < ASSEMBLY_PENETRATION_LIMIT_UM * M_PER_UM
    nominal = reducer_pin_loads(load(name), r.operating.rated_torque_Nm)
    assert reducer_pin_loads(r, r.operating.rated_torque_Nm, disc=1).max_force != nominal.max_force
    other = "rv221" if name == "rv40e" else "rv40e"
    with pytest.raises(ConfigError):
        with_errors(other, load_error_set(f"iso_grade5_{name}"))  # wrong pin count for the other design


def test_dotted_override_reaches_the_errors():
    """Sweeps and tolerance studies set errors by dotted path like any other field
    (flexrv.design.override), with the same validation."""
    from flexrv.design import override

    r = override("rv40e", {"errors.pins.pin_radius_um": 2.0})
    np.testing.assert_array_equal(as_built(r).pin_radii, np.full(Z, r.second_stage.pin_radius + 2e-6))
    with pytest.raises(ConfigError, match=r"errors\.pins\.pin_radius_um"):
        override("rv40e", {"errors.pins.pin_radius_um": 501.0})
