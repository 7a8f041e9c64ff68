"""Hostile inputs through the real command line (``python -m flexrv ...`` in a
subprocess with a timeout): every one must end with exit code 2, one clear
message naming the option/field (and, where there is one, the value), and no
traceback. Covers usage errors, undecodable files, markup-like text, strict types,
infeasible designs, step bounds, output paths checked before work, sweep specs, and
one case per cause of the third hardening round: TOML nested too deep or with a key
given twice, empty option values, duplicate or empty ``--parts``, a missing report
folder, EHL contacts larger than their radii, provenance keys naming no field, a
name with a newline, physical lower bounds (face width, masses, rated torque, the
``te`` torque), and sweep / tolerance limits found before any cluster starts (case
count, workers beyond the cores, every case's values and the task's options).

The cases run six at a time (each is a fresh interpreter, ~1 s on an idle machine);
only the unreachable-scheduler case waits for its 5 s timeout.
"""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import tomli_w

from flexrv.design import load

ROOT = Path(__file__).resolve().parent.parent
TIMEOUT_S = 120


def _design(path: Path, preset: str = "rv40e", **changes) -> str:
    """Write a preset with changed fields (``section__field=value``) to ``path``."""
    data = load(preset).model_dump(mode="python")
    for key, value in changes.items():
        if "__" not in key:  # a top-level field (name, description)
            data[key] = value
            continue
        section, field = key.split("__")
        data[section][field] = value
    path.write_text(tomli_w.dumps(data))
    return str(path)


def _spec(path: Path, body: str) -> str:
    path.write_text(body)
    return str(path)


_GRID = '[grid]\n"second_stage.eccentricity_mm" = [1.0]\n'
_HEAD = 'name = "fz"\npreset = "rv40e"\ntask = "design"\noutputs = ["kinematics.ratio"]\n'
_SIM = 'name = "fzs"\npreset = "rv40e"\ntask = "simulate"\noutputs = ["te_pp_arcsec"]\n'
#: six design fields: a grid of ten values each is a 10^6-case sweep
_SIX_FIELDS = (
    "second_stage.eccentricity_mm",
    "second_stage.disc_width_mm",
    "first_stage.face_width_mm",
    "operating.load_torque_Nm",
    "operating.input_speed_rpm",
    "contact.pin_friction_coefficient",
)
#: what a refused worker count must say: the option, the bound and the way past it
_CORES = ["--workers 1000", f"{os.cpu_count()} cores", "--force"]


def _cases(d: Path) -> list[tuple[str, list[str], list[str]]]:
    """(id, argv, substrings the stderr must contain)."""
    d.mkdir(exist_ok=True)
    (d / "afile").write_text("x")
    full = d / "full"
    full.mkdir(exist_ok=True)
    (full / "old.txt").write_text("x")
    bogus_run = d / "bogus_run"
    bogus_run.mkdir(exist_ok=True)
    (bogus_run / "results.nc").write_text("not netcdf")
    empty = d / "empty"
    empty.mkdir(exist_ok=True)
    (d / "u16.toml").write_bytes("name = 'x'\n".encode("utf-16"))
    (d / "latin1.toml").write_bytes('name = "caf\xe9"\n'.encode("latin-1"))
    (d / "binary.toml").write_bytes(bytes(range(256)))
    (d / "sweep_u16.toml").write_bytes(_HEAD.encode("utf-16"))
    out = str(d / "new_out")
    base_text = Path(_design(d / "base.toml")).read_text()
    (d / "deep_arrays.toml").write_text(base_text + "\nx = " + "[" * 5000 + "]" * 5000 + "\n")
    (d / "deep_dotted.toml").write_text(base_text + "\n[" + ".".join(["t"] * 2000) + "]\nx = 1\n")
    (d / "dup.toml").write_text(
        base_text.replace("face_width_mm = 10.0\n", "face_width_mm = 10.0\nface_width_mm = 11.0\n")
    )
    flood = load("rv40e").model_dump(mode="python")
    flood["provenance"] = {f"u{i}": "x" for i in range(100_000)}  # ~1 MB: under the size limit
    (d / "flood.toml").write_text(tomli_w.dumps(flood))
    big_grid = "[grid]\n" + "".join(f'"{k}" = [{", ".join(["1.0"] * 10)}]\n' for k in _SIX_FIELDS)
    tol = ["tolerance", "rv40e", "--tolerances", "rv40e", "--samples", "2"]
    return [
        # --- hardening round 3: one case per cause
        ("toml_deep_arrays", ["show", str(d / "deep_arrays.toml")], ["deep_arrays.toml", "nested 5000 levels"]),
        ("toml_deep_dotted", ["design", str(d / "deep_dotted.toml")], ["deep_dotted.toml", "levels", "at most 32"]),
        ("toml_duplicate_key", ["show", str(d / "dup.toml")], ["dup.toml", "'face_width_mm'", "twice"]),
        ("design_empty_name", ["design", ""], ["flexrv design", "empty argument"]),
        ("out_empty", ["simulate", "rv40e", "--out", ""], ["--out", "empty value"]),
        ("out_empty_equals", ["te", "rv40e", "--out="], ["--out", "empty value"]),
        (
            "parts_duplicate",
            ["simulate", "rv40e", "--model", "flexible", "--parts", "carrier,carrier", "--out", out],
            ["carrier given twice"],
        ),
        ("parts_empty_item", ["simulate", "rv40e", "--parts", "carrier,", "--out", out], ["empty part name"]),
        ("report_missing_folder", ["report", "--results", str(d / "MISSING")], ["--results", "does not exist"]),
        (
            "ehl_radius_huge",
            ["ehl", "--load-n", "100", "--speed-m-s", "1", "--rx-m", "0.005", "--ry-m", "1e30"],
            ["--ry-m 1e+30", "half-space"],
        ),
        ("provenance_flood", ["show", str(d / "flood.toml")], ["provenance", "100000 of 100000"]),
        ("name_newline", ["show", _design(d / "nl.toml", name="a\nb")], ["name", "printable"]),
        (
            "rated_torque_tiny",
            ["design", _design(d / "rt.toml", operating__rated_torque_Nm=1e-300)],
            ["operating.rated_torque_Nm", "1e-300", "smallest cycloidal drives"],
        ),
        (
            "face_width_subnormal",
            ["show", _design(d / "fw.toml", first_stage__face_width_mm=5e-324)],
            ["first_stage.face_width_mm", "5e-324", "narrower than 1 mm"],
        ),
        (
            "carrier_mass_tiny",
            ["design", _design(d / "cm.toml", inertia__carrier_mass_kg=1e-9)],
            ["inertia.carrier_mass_kg", "1e-09", "lighter than"],
        ),
        ("te_torque_tiny", ["te", "rv40e", "--torque-nm", "1e-300", "--out", out], ["torque", "1e-300", "no-load"]),
        (
            "sweep_grid_huge",
            ["sweep", _spec(d / "gh.toml", _HEAD + big_grid)],
            ["1000000 cases", "at most 20000"],
        ),
        ("sweep_workers_beyond_cores", ["sweep", _spec(d / "wc.toml", _HEAD + _GRID), "--workers", "1000"], _CORES),
        ("tolerance_workers_beyond_cores", [*tol, "--workers", "1000", "--out", out], _CORES),
        ("tolerance_samples_huge", [*tol[:-1], "10000000", "--out", out], ["--samples", "20000"]),
        (
            "sweep_value_nan",
            ["sweep", _spec(d / "vn.toml", _HEAD + '[grid]\n"second_stage.eccentricity_mm" = [1.0, nan]\n')],
            ["case 1", "second_stage.eccentricity_mm", "nan"],
        ),
        (
            "sweep_value_string",
            ["sweep", _spec(d / "vs.toml", _HEAD + '[[cases]]\n"first_stage.face_width_mm" = "wide"\n')],
            ["case 0", "first_stage.face_width_mm", "wide"],
        ),
        (
            "sweep_simulate_t_end_huge",
            ["sweep", _spec(d / "st.toml", _SIM + "[options]\nt_end = 1e9\n" + _GRID)],
            ["case 0", "t_end", "time steps"],
        ),
        (
            "sweep_simulate_dt_nan",
            ["sweep", _spec(d / "sd.toml", _SIM + "[options]\ndt = nan\n" + _GRID)],
            ["options.dt", "nan"],
        ),
        (
            "sweep_simulate_option_type",
            ["sweep", _spec(d / "so.toml", _SIM + '[options]\nt_end = "long"\n' + _GRID)],
            ["options.t_end", "'long'"],
        ),
        (
            "sweep_task_takes_no_design",
            ["sweep", _spec(d / "tn.toml", _HEAD.replace('"design"', '"os:getcwd"') + _GRID)],
            ["os:getcwd", "takes no design"],
        ),
        # --- usage errors (typer's vendored click exceptions)
        ("bare", [], ["Usage"]),
        ("dt_not_number", ["simulate", "rv40e", "--dt", "abc"], ["--dt", "abc"]),
        ("unknown_option_n", ["simulate", "rv40e", "--n", "1.5"], ["--n"]),
        ("n_not_int", ["modes", "rv40e", "--part", "crankshaft", "--n", "1.5"], ["--n", "1.5"]),
        ("part_bogus", ["mesh", "rv40e", "--part", "bogus"], ["--part", "bogus", "crankshaft"]),
        ("part_missing", ["mesh", "rv221"], ["--part"]),
        ("design_unknown_option", ["design", "rv40e", "--bogus"], ["--bogus"]),
        ("unknown_command", ["bogus"], ["bogus"]),
        ("missing_preset", ["simulate"], ["PRESET"]),
        ("workers_negative", ["sweep", _spec(d / "w.toml", _HEAD + _GRID), "--workers", "-1"], ["--workers"]),
        ("workers_zero", ["sweep", _spec(d / "w0.toml", _HEAD + _GRID), "--workers", "0"], ["--workers"]),
        # --- undecodable files, markup-like text
        ("utf16_design", ["design", str(d / "u16.toml")], ["u16.toml", "UTF-16"]),
        ("latin1_design", ["show", str(d / "latin1.toml")], ["latin1.toml", "UTF-8"]),
        ("binary_design", ["show", str(d / "binary.toml")], ["binary.toml", "binary"]),
        ("utf16_sweep", ["sweep", str(d / "sweep_u16.toml")], ["sweep_u16.toml", "UTF-16"]),
        ("markup_path", ["design", str(d / "[/x].toml")], ["[/x].toml"]),
        ("markup_bold_path", ["show", str(d / "[bold]x.toml")], ["[bold]x.toml"]),
        (
            "markup_value",
            ["show", _design(d / "m.toml", first_stage__sun_teeth="[/x]")],
            ["first_stage.sun_teeth", "[/x]"],
        ),
        # --- strict types
        (
            "string_number",
            ["show", _design(d / "s.toml", second_stage__disc_width_mm="12.0")],
            ["second_stage.disc_width_mm", "12.0"],
        ),
        (
            "bool_number",
            ["show", _design(d / "b.toml", inertia__input_shaft_inertia_kg_m2=True)],
            ["inertia.input_shaft_inertia_kg_m2", "True"],
        ),
        ("float_int", ["show", _design(d / "f.toml", second_stage__disc_teeth=39.0)], ["second_stage.disc_teeth"]),
        # --- infeasible designs
        (
            "needles_overlap",
            ["show", _design(d / "n.toml", needle_bearing__roller_count=80)],
            ["needle_bearing.roller_count", "80"],
        ),
        (
            "roller_too_long",
            ["show", _design(d / "r.toml", needle_bearing__roller_length_mm=100.0)],
            ["needle_bearing.roller_length_mm"],
        ),
        (
            "main_bearing_in_crank_circle",
            [
                "show",
                _design(
                    d / "mb.toml",
                    main_bearing__pitch_diameter_mm=90.0,
                    main_bearing__inner_ring_bore_diameter_mm=70.0,
                    main_bearing__outer_ring_outer_diameter_mm=110.0,
                    main_bearing__ball_count=20,
                ),
            ],
            ["main_bearing.pitch_diameter_mm", "crank"],
        ),
        (
            "contact_ratio_low",
            ["show", _design(d / "c1.toml", first_stage__sun_profile_shift=1.5, first_stage__planet_profile_shift=1.5)],
            ["first_stage.sun_profile_shift", "eps_alpha = 0.792"],
        ),
        (
            "contact_ratio_high",
            [
                "show",
                _design(d / "c2.toml", first_stage__sun_profile_shift=-1.0, first_stage__planet_profile_shift=-1.0),
            ],
            ["first_stage.sun_profile_shift", "eps_alpha"],
        ),
        (
            "contact_angle_design",
            ["design", _design(d / "ca.toml", main_bearing__contact_angle_deg=10.0)],
            ["main_bearing.contact_angle_deg", "10"],
        ),
        (
            "clearance_design",
            ["design", _design(d / "pre.toml", "rv221", main_bearing__axial_preload_um=-100.0)],
            ["main_bearing.axial_preload_um", "-100"],
        ),
        # --- bounds and output paths, before any work
        ("dt_tiny", ["simulate", "rv40e", "--dt", "1e-12", "--out", out], ["dt", "1e-12", "time steps"]),
        ("t_end_huge", ["simulate", "rv40e", "--t-end", "1e9", "--out", out], ["t_end", "1e+09", "time steps"]),
        ("out_is_file", ["simulate", "rv40e", "--out", str(d / "afile")], ["--out", "afile"]),
        ("out_in_proc", ["simulate", "rv40e", "--out", "/proc/x"], ["--out", "/proc/x"]),
        ("out_not_empty", ["simulate", "rv40e", "--out", str(full)], ["--out", "--overwrite"]),
        ("stiffness_out_not_empty", ["stiffness-test", "rv40e", "--out", str(full)], ["--out", "--overwrite"]),
        ("resume_no_checkpoint", ["simulate", "--resume", str(empty)], ["--resume", "checkpoint"]),
        ("ehl_png_proc", ["ehl", "--png", "/proc/x/a.png"], ["--png"]),
        (
            "ehl_negative_load",
            ["ehl", "--load-n", "-1", "--speed-m-s", "1", "--rx-m", "0.005", "--ry-m", "0.05"],
            ["--load-n", "-1"],
        ),
        ("view_not_netcdf", ["view", str(bogus_run)], ["results.nc"]),
        # --- sweep specs
        ("sweep_grid_scalar", ["sweep", _spec(d / "g.toml", _HEAD + "grid = 5\n")], ["grid", "5"]),
        ("sweep_cases_scalar", ["sweep", _spec(d / "cs.toml", _HEAD + "cases = 5\n")], ["cases", "5"]),
        ("sweep_options_string", ["sweep", _spec(d / "o.toml", _HEAD + 'options = "x"\n' + _GRID)], ["options", "'x'"]),
        (
            "sweep_name_parent",
            ["sweep", _spec(d / "n1.toml", _HEAD.replace('"fz"', '"../y"') + _GRID)],
            ["name", "../y"],
        ),
        (
            "sweep_name_absolute",
            ["sweep", _spec(d / "n2.toml", _HEAD.replace('"fz"', '"/tmp/x"') + _GRID)],
            ["name", "/tmp/x"],
        ),
        (
            "sweep_task_missing",
            ["sweep", _spec(d / "t.toml", _HEAD.replace('"design"', '"no.such.module:fn"') + _GRID)],
            ["no.such.module"],
        ),
        (
            "sweep_output_misspelled",
            ["sweep", _spec(d / "k.toml", _HEAD.replace("kinematics.ratio", "kinematics.ratioo") + _GRID)],
            ["outputs", "kinematics.ratioo"],
        ),
        (
            "sweep_task_option",
            ["sweep", _spec(d / "to.toml", _HEAD + "[options]\nbogus = 1\n" + _GRID)],
            ["options.bogus"],
        ),
        (
            "sweep_scheduler_unreachable",
            ["sweep", _spec(d / "sc.toml", _HEAD + _GRID), "--scheduler", "tcp://127.0.0.1:1"],
            ["--scheduler"],
        ),
    ]


def _run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MPLBACKEND": "Agg",
        "COLUMNS": "200",
    }
    return subprocess.run(
        [sys.executable, "-m", "flexrv", *argv], cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT_S
    )


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    cases = _cases(d / "inputs")
    with ThreadPoolExecutor(max_workers=6) as pool:
        futures = {cid: pool.submit(_run, argv, d) for cid, argv, _ in cases}
        return {cid: (argv, must, futures[cid].result()) for cid, argv, must in cases}, d


def _case_ids() -> list[str]:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        return [c[0] for c in _cases(Path(tmp) / "inputs")]


CASE_IDS = _case_ids()


@pytest.mark.parametrize("cid", CASE_IDS)
def test_bad_input_is_one_clear_error(outcomes, cid):
    table, _ = outcomes
    argv, must, proc = table[cid]
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert proc.returncode == 2, (argv, proc.returncode, proc.stderr[-1000:])
    text = " ".join(proc.stderr.split())
    for s in must:
        assert s in text, (cid, s, text[-600:])


def test_nothing_written_before_refusal(outcomes):
    """Refused runs leave no output behind (the paths are probed, not created)."""
    _, d = outcomes
    assert not (d / "inputs" / "new_out").exists()
    assert not (d / "results").exists()  # sweeps with bad specs wrote nothing under results/
    assert list((d / "inputs" / "full").iterdir()) == [d / "inputs" / "full" / "old.txt"]


def test_help_keeps_units_in_brackets():
    proc = _run(["simulate", "--help"], ROOT)
    assert proc.returncode == 0
    assert "End time [s]" in " ".join(proc.stdout.split())
