"""Design data model: presets load, round-trip, and every kind of bad input gives one
clear ConfigError naming the field (property-based with hypothesis)."""

from __future__ import annotations

import copy
import math
import re
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from flexrv.cli import app
from flexrv.design import from_dict, list_presets, load, loads, preset_path, to_toml
from flexrv.design.model import Reducer
from flexrv.errors import ConfigError

PRESETS = list_presets()
RAW = {name: tomllib.loads(preset_path(name).read_text()) for name in PRESETS}


def _numeric_fields(data, prefix=()):
    """(path, value) of every numeric leaf of a preset dict (excluding provenance)."""
    for key, value in data.items():
        if key == "provenance":
            continue
        path = prefix + (key,)
        if isinstance(value, dict):
            yield from _numeric_fields(value, path)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            yield path, value


FIELDS = {name: list(_numeric_fields(RAW[name])) for name in PRESETS}


def _set(data, path, value):
    data = copy.deepcopy(data)
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return data


def _delete(data, path):
    data = copy.deepcopy(data)
    node = data
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]
    return data


def test_presets_listed():
    assert {"rv221", "rv40e"} <= set(PRESETS)


@pytest.mark.parametrize("name", PRESETS)
def test_preset_roundtrip_toml(name):
    """`flexrv show --toml` output loads back to an identical design."""
    reducer = load(name)
    assert loads(to_toml(reducer)) == reducer


@pytest.mark.parametrize("name", PRESETS)
def test_every_estimate_has_provenance(name):
    """Every provenance key names an existing field and is non-empty."""
    reducer = load(name)
    dumped = reducer.model_dump()
    for key, note in reducer.provenance.items():
        section, _, field = key.partition(".")
        assert section in dumped and note.strip(), key
        if field and isinstance(dumped[section], dict):
            assert field in dumped[section], key


def test_seed_values_present():
    """The presets carry the seeds' key numbers (ratio-relevant teeth, module, a)."""
    rv221, rv40e = load("rv221"), load("rv40e")
    assert (rv221.first_stage.sun_teeth, rv221.first_stage.planet_teeth) == (12, 44)
    assert (rv221.second_stage.disc_teeth, rv221.second_stage.pin_count) == (59, 60)
    assert rv221.first_stage.module_mm == 3.0 and rv221.second_stage.eccentricity_mm == 2.4
    assert rv221.main_bearing.ball_count == 26 and rv221.main_bearing.contact_angle_deg == 40.0
    assert math.isclose(rv221.operating.input_speed_rpm * 6.0, 9000.0)  # 9000 deg/s
    assert (rv40e.first_stage.sun_teeth, rv40e.first_stage.planet_teeth) == (16, 32)
    assert (rv40e.second_stage.disc_teeth, rv40e.second_stage.pin_count) == (39, 40)
    assert math.isclose(rv40e.second_stage.shortening_coefficient, 0.8125)  # :cite:`seed002` Table 1
    assert rv40e.needle_bearing.roller_count == 15


def test_physics_override_of_rv221_pin_circle_is_documented():
    """R_p = 82.5 mm (:cite:`seed000`) is rejected by validation; the preset uses 165 mm and says why."""
    data = _set(RAW["rv221"], ("second_stage", "pin_circle_radius_mm"), 82.5)
    with pytest.raises(ConfigError, match="second_stage.pin_radius_mm"):
        from_dict(data)
    assert "PHYSICS OVERRIDES SEED" in load("rv221").provenance["second_stage.pin_circle_radius_mm"]


@pytest.mark.parametrize("name", PRESETS)
def test_inconsistent_teeth(name):
    data = _set(RAW[name], ("second_stage", "pin_count"), RAW[name]["second_stage"]["disc_teeth"] + 2)
    with pytest.raises(ConfigError, match=r"second_stage.pin_count.*disc_teeth \+ 1"):
        from_dict(data)


@pytest.mark.parametrize("name", PRESETS)
def test_eccentricity_undercut(name):
    ss = RAW[name]["second_stage"]
    limit = ss["pin_circle_radius_mm"] / ss["pin_count"]
    data = _set(RAW[name], ("second_stage", "eccentricity_mm"), limit * 1.05)
    with pytest.raises(ConfigError, match="second_stage.eccentricity_mm.*undercut"):
        from_dict(data)


@pytest.mark.parametrize("name", PRESETS)
def test_ball_larger_than_ring(name):
    mb = RAW[name]["main_bearing"]
    big = (mb["outer_ring_outer_diameter_mm"] - mb["inner_ring_bore_diameter_mm"]) / 2.0
    data = _set(RAW[name], ("main_bearing", "ball_diameter_mm"), min(big, 199.0))
    with pytest.raises(ConfigError, match="main_bearing.ball_diameter_mm"):
        from_dict(data)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(PRESETS),
    data=st.data(),
    bad=st.sampled_from([-1.0, 0.0, float("nan"), float("inf"), -1e9, 1e12, "text"]),
)
def test_bad_numeric_value_names_field(name, data, bad):
    """Negative, zero, NaN, inf, huge or non-numeric values either are valid for that
    field or raise ConfigError naming exactly that field."""
    path, _ = data.draw(st.sampled_from(FIELDS[name]))
    mutated = _set(RAW[name], path, bad)
    try:
        from_dict(mutated)
    except ConfigError as exc:
        assert ".".join(path) in str(exc) or path[-1] in str(exc)
    else:
        # accepted: must be a legal value for this field (e.g. 0 for a damping ratio)
        assert isinstance(bad, float) and math.isfinite(bad)


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(PRESETS), data=st.data())
def test_missing_field_named(name, data):
    path, _ = data.draw(st.sampled_from(FIELDS[name]))
    with pytest.raises(ConfigError, match="missing required field") as info:
        from_dict(_delete(RAW[name], path))
    assert ".".join(path) in str(info.value)


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(PRESETS),
    data=st.data(),
    key=st.text(alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=3, max_size=12),
)
def test_unknown_field_named(name, data, key):
    section = data.draw(
        st.sampled_from(
            [k for k, v in RAW[name].items() if isinstance(v, dict) and k not in ("provenance", "materials", "ranges")]
        )
    )
    if key in RAW[name][section]:
        return
    mutated = _set(RAW[name], (section, key), 1.0)
    with pytest.raises(ConfigError, match=f"{section}.{key}: unknown field"):
        from_dict(mutated)


def test_range_in_message():
    data = _set(RAW["rv40e"], ("first_stage", "module_mm"), -1.5)
    with pytest.raises(ConfigError) as info:
        from_dict(data)
    msg = str(info.value)
    assert "first_stage.module_mm = -1.5" in msg and "0.2 < value <= 20" in msg


def test_cli_bad_file_exit_2_no_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(to_toml(load("rv40e")).replace("ball_count = 38", "ball_count = -3"))
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-c", "from flexrv.cli import main; main()", "show", str(bad)], capture_output=True, text=True
    )
    assert proc.returncode == 2
    assert "main_bearing.ball_count" in proc.stderr and "Traceback" not in proc.stderr


def test_cli_show_toml_roundtrip():
    result = CliRunner().invoke(app, ["show", "rv221", "--toml"])
    assert result.exit_code == 0
    assert loads(result.stdout) == load("rv221")


def test_reducer_is_frozen():
    r = load("rv40e")
    with pytest.raises(Exception):
        r.name = "x"  # type: ignore[misc]
    assert isinstance(r, Reducer)


def _dump(name):
    return copy.deepcopy(load(name).model_dump(mode="python"))


@pytest.mark.parametrize("name", list_presets())
def test_strict_types(name):
    """No string or boolean is coerced into a number, no float into an integer;
    an integer (TOML ``12``) still loads into a float field, numpy scalars too."""
    import numpy as np

    data = _dump(name)
    data["second_stage"]["disc_width_mm"] = int(data["second_stage"]["disc_width_mm"])
    assert isinstance(from_dict(data).second_stage.disc_width_mm, float)
    for section, field, bad in (
        ("second_stage", "disc_width_mm", "12.0"),
        ("inertia", "input_shaft_inertia_kg_m2", True),
        ("second_stage", "disc_teeth", float(data["second_stage"]["disc_teeth"])),
        ("first_stage", "sun_teeth", "[/x]"),
    ):
        d = _dump(name)
        d[section][field] = bad
        with pytest.raises(ConfigError, match=rf"{section}\.{field} = {re.escape(repr(bad))}"):
            from_dict(d)
    d = _dump(name)
    d["second_stage"]["n_discs"] = np.int64(d["second_stage"]["n_discs"])
    d["second_stage"]["disc_width_mm"] = np.float64(d["second_stage"]["disc_width_mm"])
    assert from_dict(d) == load(name)


@pytest.mark.parametrize("name", list_presets())
def test_first_stage_contact_ratio(name):
    """eps_alpha of the design model is the involute helper's value, and designs
    outside 1 < eps_alpha < 2.5 are refused naming the profile shift. For the
    unshifted rv40e pair (z 16/32, m 1.5, 20 deg, standard addendum) the textbook
    formula eps = [sqrt(ra1^2-rb1^2) + sqrt(ra2^2-rb2^2) - a sin(alpha)] / (pi m cos(alpha))
    gives 1.583 (computed independently below)."""
    from flexrv.geometry.involute import contact_ratio

    r = load(name)
    fs = r.first_stage
    assert fs.contact_ratio == pytest.approx(
        float(
            contact_ratio(
                fs.sun_teeth,
                fs.planet_teeth,
                fs.module,
                fs.pressure_angle,
                fs.sun_profile_shift,
                fs.planet_profile_shift,
            )
        ),
        rel=1e-12,
    )
    if name == "rv40e":
        m, al = 1.5, math.radians(20.0)
        ra1, ra2 = m * (16 + 2) / 2, m * (32 + 2) / 2
        rb1, rb2 = m * 16 / 2 * math.cos(al), m * 32 / 2 * math.cos(al)
        eps = (math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - m * 24 * math.sin(al)) / (
            math.pi * m * math.cos(al)
        )
        assert fs.contact_ratio == pytest.approx(eps, rel=1e-9)
        assert eps == pytest.approx(1.583, abs=1e-3)
    for shifts in ((1.5, 1.5), (-1.0, -1.0)):
        d = _dump(name)
        d["first_stage"]["sun_profile_shift"], d["first_stage"]["planet_profile_shift"] = shifts
        with pytest.raises(ConfigError, match="first_stage.sun_profile_shift.*eps_alpha"):
            from_dict(d)


@pytest.mark.parametrize("name", list_presets())
def test_geometric_feasibility(name):
    """Needles that do not fit on their pitch circle, needles longer than the disc,
    a main bearing inside the crank-hole circle: refused naming the field."""
    base = load(name)
    nb, cs = base.needle_bearing, base.crankshaft
    n_max = int(math.pi * (cs.eccentric_journal_diameter_mm + nb.roller_diameter_mm) / nb.roller_diameter_mm)
    d = _dump(name)
    d["needle_bearing"]["roller_count"] = n_max
    from_dict(d)  # the limit itself fits
    d["needle_bearing"]["roller_count"] = n_max + 1
    with pytest.raises(ConfigError, match=rf"needle_bearing.roller_count = {n_max + 1} .*<= {n_max}"):
        from_dict(d)
    d = _dump(name)
    d["needle_bearing"]["roller_length_mm"] = base.second_stage.disc_width_mm + 0.5
    with pytest.raises(ConfigError, match="needle_bearing.roller_length_mm"):
        from_dict(d)
    r_out = (base.first_stage.center_distance + base.crank_hole_radius) * 1e3
    d = _dump(name)
    mb = d["main_bearing"]
    dm = 2 * r_out - 4.0
    mb.update(
        pitch_diameter_mm=dm,
        inner_ring_bore_diameter_mm=dm - 20.0,
        outer_ring_outer_diameter_mm=dm + 20.0,
        ball_diameter_mm=6.0,
        ball_count=20,
        ring_width_mm=8.0,
        row_spacing_mm=max(mb["row_spacing_mm"], 8.0),
    )
    with pytest.raises(ConfigError, match="main_bearing.pitch_diameter_mm.*crank-hole circle"):
        from_dict(d)


def test_design_report_load_sanity_warnings():
    """Contact pressures above the ISO 76 static limits (4.2 GPa ball, 4.0 GPa line)
    are flagged by name; the presets at their operating points are not."""
    from flexrv.analysis.report import design_report
    from flexrv.cli.design import load_sanity_warnings

    fake = {
        "main_bearing": {"external": {"hertz_max_ball": {"inner_p_max_Pa": 4.3e9, "outer_p_max_Pa": 4.1e9}}},
        "pin_loads": {"rated_torque": {"max_hertz_pressure_Pa": 4.05e9}},
    }
    warnings = load_sanity_warnings(fake)
    assert len(warnings) == 2
    assert warnings[0].startswith("main_bearing.external.hertz_max_ball.inner_p_max_Pa = 4.3 GPa")
    assert warnings[1].startswith("pin_loads.rated_torque.max_hertz_pressure_Pa = 4.05 GPa")
    assert load_sanity_warnings(design_report(load("rv40e"))) == []


def test_toml_template_comments_round_trip_and_optional_provenance(tmp_path):
    """`show --toml` writes a comment with the description and allowed range above every
    described field; the commented text loads back to the same design. A design without a
    [provenance] table loads (own designs), and `show` warns about it on stderr."""
    import subprocess
    import sys

    from flexrv.design import load, loads, to_toml

    red = load("rv40e")
    text = to_toml(red, comments=True)
    assert "# Sun gear teeth z_s [-]; allowed: 8 <= value <= 200\nsun_teeth = 16" in text
    assert loads(text) == red
    bare = "\n".join(line for line in to_toml(red).splitlines())
    bare = bare[: bare.index("[provenance]")]
    path = tmp_path / "own.toml"
    path.write_text(bare)
    assert load(path).provenance == {}
    cp = subprocess.run(
        [sys.executable, "-m", "flexrv", "show", str(path)], capture_output=True, text=True, timeout=120
    )
    assert cp.returncode == 0 and "no [provenance] table" in cp.stderr


def test_involute_undercut_is_refused():
    """Practical undercut limit x >= 5/6 - z sin^2(alpha)/2 (DIN 3960 / Niemann: 14 teeth at
    20 deg without shift): a 12-tooth sun without profile shift (limit 0.131) is refused
    naming the field; the presets (rv221: 12 teeth with x = 0.5, rv40e: 16 teeth, x = 0)
    pass."""
    from flexrv.design import load, override
    from flexrv.errors import ConfigError

    load("rv40e"), load("rv221")
    with pytest.raises(ConfigError, match=r"first_stage.sun_profile_shift = 0.0 .*>= 0.131"):
        override("rv221", {"first_stage.sun_profile_shift": 0.0})
