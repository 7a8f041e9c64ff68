"""Tolerance analysis (flexrv.design.tolerances, flexrv.studies.tolerance, ``flexrv tolerance``).

Checks: validation of the [tolerances] table and the CLI's bad inputs (exit 2
naming the problem, within seconds); reproducible sampling (same seed ->
identical samples), the distributions' marginals and correlations; Sobol'
indices of an additive function against their analytic values (SALib path);
first-order propagation of small errors to the loaded mean TE; resume after
SIGKILL with no finished sample recomputed and an identical table; a study on a
real ``dask scheduler`` + two ``dask worker`` processes equal to the local run.
"""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from flexrv.cache import finished_files
from flexrv.design import load
from flexrv.design.tolerances import load_tolerances, parse_tolerances
from flexrv.errors import ConfigError, InputError
from flexrv.studies.tolerance import OUTPUTS, TolerancePlan, parse_spec, sobol_indices, te_task, yield_estimate

ROOT = Path(__file__).resolve().parents[1]
#: smoke resolution of the CLI studies: 0.1 crank revolution at 2 points per pin mesh
SMOKE = ["--crank-revolutions", "0.1", "--points-per-mesh", "2"]
#: the tiny study of the LocalCluster run and of the runs compared with it (4 samples, seed 3, no what-if)
STUDY = ["rv40e", "--tolerances", "rv40e", "--samples", "4", "--seed", "3", "--what-if-samples", "0", *SMOKE]
#: that study on a LocalCluster of one worker
LOCAL_STUDY = [*STUDY, "--workers", "1"]


@pytest.fixture(scope="module")
def rv40e():
    return load("rv40e")


def _env():
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    return env


def _cli(*args, timeout=600, **kw):
    return subprocess.run(
        [sys.executable, "-m", "flexrv", "tolerance", *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,
    )


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# --------------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "table, words",
    [
        ({"pins.pin_size_um": {"distribution": "normal", "sigma_um": 1.0}}, ["pins.pin_size_um", "no such"]),
        ({"pins.pin_radius_um": {"distribution": "normal", "sigma_um": -1.0}}, ["sigma_um", "-1.0"]),
        ({"pins.pin_radius_um": {"distribution": "normal", "sigma_um": 1.0, "scope": "lot"}}, ["scope", "lot"]),
        ({"pins.pin_radius_um": {"distribution": "normal", "sigma_arcmin": 1.0}}, ["sigma_arcmin", "sigma_um"]),
        ({"pins.pin_radius_um": {"distribution": "band"}}, ["band_um"]),
        ({"pins.pin_radius_um": {"distribution": "triangular", "band_um": 1.0}}, ["distribution", "triangular"]),
        (
            {"clearances.support_clearance_um": {"distribution": "uniform", "band_um": 2.0, "mean_um": 1.0}},
            ["support_clearance_um", "lower bound"],
        ),
        ({"first_stage.sun_runout_phase_deg": {"distribution": "normal", "sigma_deg": 1.0}}, ["sun_runout_phase_deg"]),
        (
            {
                "pins.pin_radius_um": {"distribution": "normal", "sigma_um": 1.0},
                "correlations": [{"fields": ["pins.pin_radius_um", "cranks.bore_radial_um"], "coefficient": 0.5}],
            },
            ["correlations[0]", "cranks.bore_radial_um"],
        ),
    ],
)
def test_bad_tolerance_tables(rv40e, table, words):
    """Each bad entry raises one ConfigError naming the entry/key and value."""
    with pytest.raises(ConfigError) as info:
        parse_tolerances(table, rv40e)
    for w in words:
        assert w in str(info.value)


@pytest.mark.parametrize(
    "text, word",
    [("te_pp<=60", "unknown output"), ("te_pp_arcsec=60", "bad syntax"), ("lost_motion_arcmin<=inf", "finite")],
)
def test_bad_specs(text, word):
    with pytest.raises(InputError, match=word):
        parse_spec(text)


def test_cli_bad_inputs_exit_2_quickly(tmp_path):
    """--samples 0, an unknown spec output, bad spec syntax, a negative sigma, an unknown field and an
    unreachable scheduler: exit 2 with the culprit named, each within a few seconds (interpreter
    start-up included)."""
    bad_tol = tmp_path / "bad.toml"
    bad_tol.write_text('[tolerances."pins.pin_radius_um"]\ndistribution = "normal"\nsigma_um = -2.0\n')
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('[tolerances."pins.pin_colour_um"]\ndistribution = "normal"\nsigma_um = 2.0\n')
    port = _free_port()
    cases = [
        (["--samples", "0"], "--samples"),
        (["--samples", "4", "--spec", "te_pp<=60"], "te_pp"),
        (["--samples", "4", "--spec", "te_pp_arcsec=60"], "bad syntax"),
        (["--samples", "4", "--tolerances", str(bad_tol)], "sigma_um"),
        (["--samples", "4", "--tolerances", str(unknown)], "pins.pin_colour_um"),
        (["--samples", "4", "--scheduler", f"tcp://127.0.0.1:{port}"], "scheduler"),
    ]
    for args, word in cases:
        args = [a if a != "--tolerances" else a for a in args]
        if "--tolerances" not in args:
            args = [*args, "--tolerances", "rv40e"]
        t0 = time.perf_counter()
        res = _cli("rv40e", *args, "--out", str(tmp_path / "o"), timeout=60)
        wall = time.perf_counter() - t0
        assert res.returncode == 2, (args, res.stdout, res.stderr)
        assert word in res.stderr, (args, res.stderr)
        assert "Traceback" not in res.stderr
        assert wall < 20.0, (args, wall)


def test_tolerances_inside_design_toml(tmp_path):
    """A [tolerances] table inside the design TOML is read; the design itself validates as before;
    --tolerances FILE takes precedence; a design without either is a ConfigError naming the fix."""
    from flexrv.design import preset_path
    from flexrv.studies.tolerance import load_design_and_tolerances

    text = preset_path("rv40e").read_text()
    path = tmp_path / "d.toml"
    path.write_text(text + '\n[tolerances."cranks.bore_radial_um"]\ndistribution = "uniform"\nband_um = 2.0\n')
    reducer, tol, data = load_design_and_tolerances(str(path), None)
    assert list(tol.entries) == ["cranks.bore_radial_um"] and tol.entries["cranks.bore_radial_um"].band == 2.0
    assert reducer.model_dump() == load("rv40e").model_dump() and "tolerances" not in data
    _, tol2, _ = load_design_and_tolerances(str(path), "rv40e")
    assert "pins.pin_radius_um" in tol2.entries
    with pytest.raises(ConfigError, match="--tolerances"):
        load_design_and_tolerances("rv40e", None)


# --------------------------------------------------------------------------- sampling
@pytest.mark.parametrize("sampler", ["random", "sobol", "lhs"])
def test_same_seed_identical_samples(rv40e, sampler):
    """Same seed -> bit-identical unit samples, values and [errors] tables; another seed differs.
    Every drawn error set passes the design's [errors] validation; band draws stay in the band."""
    from flexrv.design import with_errors

    tol = load_tolerances("rv40e", rv40e)
    a, b, c = (TolerancePlan.build(rv40e, tol, s) for s in (7, 7, 8))
    ua, ub, uc = (p.unit_samples(16, sampler) for p in (a, b, c))
    assert np.array_equal(ua, ub) and not np.allclose(ua, uc)
    xa, xb = a.values(ua), b.values(ub)
    assert np.array_equal(xa, xb)
    assert a.errors_for(xa[3]) == b.errors_for(xb[3])
    sl = a.slices["pins.pin_radius_um"]
    assert np.all(np.abs(xa[:, sl]) <= 1.25 + 1e-12)
    with_errors(rv40e, a.errors_for(xa[0]))  # validates (bounds, list lengths, assembly)


def test_marginals_and_correlation(rv40e):
    """Random sampler, 20,000 draws: normal sigma, band-3-sigma truncated sigma, uniform half width,
    and a correlation group's coefficient, within 4 standard errors."""
    table = {
        "cranks.bore_radial_um": {"distribution": "normal", "sigma_um": 2.0, "mean_um": 1.0},
        "cranks.bore_tangential_um": {"distribution": "band", "band_um": 3.0},
        "pins.pin_radius_um": {"distribution": "uniform", "band_um": 1.5, "scope": "per_reducer"},
        "discs.hole_radial_um": {"distribution": "normal", "sigma_um": 1.0},
        "discs.hole_tangential_um": {"distribution": "normal", "sigma_um": 1.0},
        "correlations": [{"fields": ["discs.hole_radial_um", "discs.hole_tangential_um"], "coefficient": 0.6}],
    }
    tol = parse_tolerances(table, rv40e)
    plan = TolerancePlan.build(rv40e, tol, 3)
    n = 20000
    x = plan.values(plan.unit_samples(n, "random"))
    se = 1.0 / math.sqrt(2 * n)  # relative standard error of a standard deviation
    br = x[:, plan.slices["cranks.bore_radial_um"]]
    assert abs(br.mean() - 1.0) < 4 * 2.0 / math.sqrt(n * 3)
    assert abs(br.std() / 2.0 - 1) < 4 * se
    # truncated normal, c = 3: sigma_t = sigma sqrt(1 - 2 c phi(c) / (2 Phi(c) - 1)) = 0.98658 sigma
    assert abs(x[:, plan.slices["cranks.bore_tangential_um"]].std() / (0.98658 * 1.0) - 1) < 4 * se * 1.3
    assert abs(tol.sigma_of("cranks.bore_tangential_um") - 0.98658) < 1e-4
    pr = x[:, plan.slices["pins.pin_radius_um"]]
    assert pr.shape[1] == 1 and abs(pr.std() / (1.5 / math.sqrt(3)) - 1) < 4 * se * 1.2
    r = np.corrcoef(
        x[:, plan.slices["discs.hole_radial_um"]].ravel(), x[:, plan.slices["discs.hole_tangential_um"]].ravel()
    )[0, 1]
    assert abs(r - 0.6) < 4 * (1 - 0.36) / math.sqrt(n)
    errs = plan.errors_for(x[0])
    assert len(errs["pins"]["pin_radius_um"]) == 40 and len(set(errs["pins"]["pin_radius_um"])) == 1


def test_yield_clopper_pearson():
    """Yield 45/50 and its exact interval against the Clopper-Pearson closed form in beta
    quantiles (lower = B^-1(0.025; k, n-k+1), upper = B^-1(0.975; k+1, n-k)), computed here
    independently of scipy's binomtest root finding; 1e-7."""
    from scipy.stats import beta

    y = {
        "te_pp_arcsec": np.r_[np.full(45, 10.0), np.full(5, 100.0), np.nan],
        "lost_motion_arcmin": np.r_[1.5, np.full(50, 0.5)],
    }
    res = yield_estimate(y, [parse_spec("te_pp_arcsec<=60")])
    assert res["passed"] == 45 and res["n"] == 50 and res["yield"] == 0.9  # the NaN sample is not counted
    assert res["ci_low"] == pytest.approx(beta.ppf(0.025, 45, 6), abs=1e-7)
    assert res["ci_high"] == pytest.approx(beta.ppf(0.975, 46, 5), abs=1e-7)
    both = yield_estimate(y, [parse_spec("te_pp_arcsec<=60"), parse_spec("lost_motion_arcmin<1")])
    assert both["passed"] == 44  # sample 0 fails the lost-motion spec only


def test_sobol_indices_additive(rv40e):
    """SALib path on the study's own grouped Saltelli design: f = sum_g a_g sum_i u_gi with u
    uniform on [0, 1] is additive, so S1_g = ST_g = a_g^2 n_g / sum_h a_h^2 n_h (n_g variables in
    group g): 3 bores (a=1), 2 sun-runout components (a=2), 1 per-reducer pin radius (a=3) ->
    3/20, 8/20, 9/20. Tolerance 0.03 (N = 2048 base samples; SALib's bootstrap half widths ~0.01)."""
    table = {
        "cranks.bore_radial_um": {"distribution": "normal", "sigma_um": 1.0},
        "first_stage.sun_runout_um": {"distribution": "normal", "sigma_um": 1.0},
        "pins.pin_radius_um": {"distribution": "normal", "sigma_um": 1.0, "scope": "per_reducer"},
    }
    plan = TolerancePlan.build(rv40e, parse_tolerances(table, rv40e), 11)
    u = plan.saltelli(2048)
    assert u.shape == (2048 * (3 + 2), 6)
    a = {"cranks.bore_radial_um": 1.0, "first_stage.sun_runout_um": 2.0, "pins.pin_radius_um": 3.0}
    y = sum(a[k] * u[:, sl].sum(axis=1) for k, sl in plan.slices.items())
    res = sobol_indices(plan.salib_problem(), y, seed=1)
    expect = {"cranks.bore_radial_um": 3 / 20, "first_stage.sun_runout_um": 8 / 20, "pins.pin_radius_um": 9 / 20}
    for k, v in expect.items():
        assert res[k]["S1"] == pytest.approx(v, abs=0.03), (k, res[k])
        assert res[k]["ST"] == pytest.approx(v, abs=0.03), (k, res[k])


# --------------------------------------------------------------------------- propagation
@pytest.mark.slow
def test_first_order_propagation_mean_te(rv40e):
    """Small errors: the loaded mean TE is linear in them, so its Monte Carlo variance equals the
    first-order propagation sum_i (dy/dx_i)^2 sigma_i^2 from central finite differences
    (step = sigma) of the 7 variables (crank-hole tangential positions of 2 discs x 3 holes, a
    common tangential pin-ring offset). Checked two ways on N = 20 samples at 0.1 crank revolution,
    2 points per mesh:
    (1) the predicted variance lies inside the 99.9 % chi-square interval of the sample variance
    (sampling error); (2) sample by sample the linear prediction y0 + J (x - mean) matches the
    computed mean TE within 5 % of its standard deviation (fails for a wrong sensitivity)."""
    from scipy.stats import chi2

    from flexrv.design import with_errors

    table = {
        "discs.hole_tangential_um": {"distribution": "normal", "sigma_um": 0.3},
        "pins.pin_tangential_position_um": {"distribution": "normal", "sigma_um": 0.5, "scope": "per_reducer"},
    }
    tol = parse_tolerances(table, rv40e)
    plan = TolerancePlan.build(rv40e, tol, 5)
    res = {"crank_revolutions": 0.1, "points_per_mesh": 2}

    def mean_te(xrow):
        return te_task(with_errors(rv40e, plan.errors_for(xrow)), **res)["te_mean_arcsec"]

    d = plan.dim
    sig = np.array([tol.sigma_of(c.entry) for c in plan.columns])
    y0 = mean_te(np.zeros(d))
    jac = np.empty(d)
    for i in range(d):
        e = np.zeros(d)
        e[i] = sig[i]
        jac[i] = (mean_te(e) - mean_te(-e)) / (2 * sig[i])
    var_pred = float(np.sum(jac**2 * sig**2))
    n = 20
    x = plan.values(plan.unit_samples(n, "random"))
    y = np.array([mean_te(row) for row in x])
    s2 = float(np.var(y, ddof=1))
    lo, hi = s2 * (n - 1) / chi2.ppf(0.9995, n - 1), s2 * (n - 1) / chi2.ppf(0.0005, n - 1)
    assert lo <= var_pred <= hi, (var_pred, s2, lo, hi)
    y_lin = y0 + x @ jac
    assert s2 > 0.1  # arcsec^2: the errors do move the mean TE
    assert np.max(np.abs(y - y_lin)) < 0.05 * math.sqrt(s2), (y, y_lin)


# --------------------------------------------------------------------------- studies (dask)
def _table(out: Path) -> dict:
    import xarray as xr

    with xr.open_dataset(out / "samples.nc", engine="h5netcdf") as ds:
        return {k: ds[k].values.copy() for k in ("u", "x", "status", *OUTPUTS)}


def _assert_same(a: dict, b: dict) -> None:
    for k in a:
        if a[k].dtype.kind in "fc":
            assert np.array_equal(a[k], b[k], equal_nan=True), k
        else:
            assert np.array_equal(a[k], b[k]), k


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    """A tiny study on a LocalCluster (1 worker): 4 samples, no what-if."""
    out = tmp_path_factory.mktemp("tol") / "local"
    res = _cli(
        *LOCAL_STUDY,
        "--out",
        str(out),
        "--json",
    )
    assert res.returncode == 0, res.stderr
    return out, json.loads(res.stdout)


@pytest.mark.slow
def test_study_outputs_and_rerun_identical(local_run, tmp_path):
    """(slow: three tiny studies.) The study writes samples.nc / summary / PNGs with finite outputs; a second
    identical command
    recomputes nothing; a fresh run in another directory gives the identical table."""
    out, data = local_run
    assert data["samples"] == 4 and data["evaluations"] == 4
    for f in ("samples.nc", "summary.json", "summary.md", "histograms.png", "tornado.png"):
        assert (out / f).is_file()
    t = _table(out)
    ok = t["status"] == "ok"
    assert ok.sum() >= 3
    assert np.all(t["torsional_rigidity_Nm_per_arcmin"][ok] > 100.0)
    again = _cli(
        *LOCAL_STUDY,
        "--out",
        str(out),
        "--json",
    )
    assert again.returncode == 0 and json.loads(again.stdout)["computed_now"] == 0
    fresh = tmp_path / "fresh"
    res = _cli(
        *LOCAL_STUDY,
        "--out",
        str(fresh),
        "--json",
    )
    assert res.returncode == 0, res.stderr
    _assert_same(t, _table(fresh))


def test_sigkill_resume_identical(local_run, tmp_path):
    """SIGKILL the whole study (client and LocalCluster) once a sample is stored; rerunning the
    same command computes only the missing samples (finished ones are skipped, their files
    untouched) and the table equals the uninterrupted run's."""
    out = tmp_path / "killed"
    args = [
        sys.executable,
        "-m",
        "flexrv",
        "tolerance",
        *LOCAL_STUDY,
        "--out",
        str(out),
        "--json",
    ]
    proc = subprocess.Popen(
        args, cwd=ROOT, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    cases = out / "runs" / "cases"
    t0 = time.time()
    try:
        while time.time() - t0 < 300:
            if finished_files(cases):
                break
            if proc.poll() is not None:
                break
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    done = {p.name: p.stat().st_mtime_ns for p in finished_files(cases)}
    assert 1 <= len(done) < 4, done
    res = _cli(*args[4:])
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["skipped_existing"] == len(done) and data["computed_now"] == 4 - len(done)
    assert all((cases / name).stat().st_mtime_ns == m for name, m in done.items())
    _assert_same(_table(local_run[0]), _table(out))


def test_real_dask_scheduler_and_workers(local_run, tmp_path):
    """A real `dask scheduler` and two `dask worker` processes on 127.0.0.1 (free ports, bounded
    waits, killed at the end): the study through --scheduler equals the LocalCluster run."""
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    dask_bin = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    worker_bin = [sys.executable, "-m", "distributed.cli.dask_worker"]
    procs = [
        subprocess.Popen(
            [*dask_bin, "--host", "127.0.0.1", "--port", str(port), "--dashboard-address", ":0", "--no-show"],
            cwd=ROOT,
            env=_env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
    ]
    try:
        t0 = time.time()
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.time() - t0 < 60, "scheduler did not start"
                time.sleep(0.3)
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [*worker_bin, addr, "--nthreads", "1", "--nworkers", "1", "--no-dashboard", "--host", "127.0.0.1"],
                    cwd=ROOT,
                    env=_env(),
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                    start_new_session=True,
                )
            )
        from dask.distributed import Client

        with Client(addr, timeout=30) as client:
            client.wait_for_workers(2, timeout=120)
        out = tmp_path / "remote"
        res = _cli(
            *STUDY,
            "--scheduler",
            addr,
            "--out",
            str(out),
            "--json",
            timeout=600,
        )
        assert res.returncode == 0, res.stderr
        _assert_same(_table(local_run[0]), _table(out))
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait(timeout=30)


def test_src_linear_function(rv40e):
    """SRC^2 on the 'variables' basis of a linear function of the sampled errors equals the
    analytic variance shares a_i^2 sigma_i^2 / sum (R^2 = 1): bores 3 x (a=1, sigma 1), sun
    runout 2 x (a=2, sigma 0.5), pin radius per reducer (a=0.5, sigma 2) -> 3/6, 2/6, 1/6; 0.02."""
    from flexrv.studies.tolerance import src_indices

    table = {
        "cranks.bore_radial_um": {"distribution": "normal", "sigma_um": 1.0},
        "first_stage.sun_runout_um": {"distribution": "normal", "sigma_um": 0.5},
        "pins.pin_radius_um": {"distribution": "normal", "sigma_um": 2.0, "scope": "per_reducer"},
    }
    plan = TolerancePlan.build(rv40e, parse_tolerances(table, rv40e), 2)
    x = plan.values(plan.unit_samples(4000, "random"))
    a = np.r_[1.0, 1.0, 1.0, 2.0, 2.0, 0.5]
    res = src_indices(x, x @ a, plan)
    assert res["best"] == "variables" and res["variables"]["r2"] == pytest.approx(1.0, abs=1e-9)
    got = res["variables"]["indices"]
    assert got["cranks.bore_radial_um"] == pytest.approx(3 / 6, abs=0.02)
    assert got["first_stage.sun_runout_um"] == pytest.approx(2 / 6, abs=0.02)
    assert got["pins.pin_radius_um"] == pytest.approx(1 / 6, abs=0.02)


@pytest.mark.slow
def test_study_sobol_and_what_if(tmp_path):
    """--sobol (Saltelli, N = 2 base samples, 2 tolerances -> 8 evaluations, its A and B rows the 4
    plain samples) and a what-if table on 1 sample (2 tolerances x 2 factors): every evaluation is
    run once, Sobol' indices and the what-if rows are reported; the halved tolerance's stored
    error values are exactly half the plain sample's."""
    tol = tmp_path / "tol.toml"
    tol.write_text(
        '[tolerances."cranks.bore_tangential_um"]\ndistribution = "band"\nband_um = 3.0\n'
        '[tolerances."pins.pin_radius_um"]\ndistribution = "normal"\nsigma_um = 0.4\n'
    )
    out = tmp_path / "s"
    res = _cli(
        "rv40e",
        "--tolerances",
        str(tol),
        "--samples",
        "2",
        "--sobol",
        "--what-if-samples",
        "1",
        "--workers",
        "1",
        "--spec",
        "lost_motion_arcmin<=1.5",
        *SMOKE,
        "--out",
        str(out),
        "--json",
    )
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["samples"] == 4 and data["evaluations"] == 8 + 4
    assert data["yield"]["n"] >= 3
    summary = json.loads((out / "summary.json").read_text())
    sob = summary["sensitivity_sobol"]["te_mean_arcsec"]
    assert set(sob) == {"cranks.bore_tangential_um", "pins.pin_radius_um"}
    assert all(math.isfinite(v["ST"]) for v in sob.values())
    assert {r["tolerance"] for r in data["what_if"]["rows"]} == set(sob)
    records = [json.loads(p.read_text()) for p in (out / "runs" / "cases").glob("*.json")]
    bores = [r["overrides"]["errors"]["cranks"]["bore_tangential_um"] for r in records]
    x0 = np.asarray(_table(out)["x"][0][:3])
    assert any(np.allclose(b, 0.5 * x0, rtol=0, atol=1e-12) for b in bores if isinstance(b, list))


def test_a_study_stopped_before_its_first_stored_case_leaves_no_folder(tmp_path, monkeypatch):
    """A study that stops before any case is stored removes the folder it created, also when a
    case was being written at that moment: the atomic write's temporary file
    (``.<name>.<pid>.<random>.tmp.json``, which a ``*.json`` glob matches) is not a stored case.
    A folder with a stored case is kept (the study resumes from it)."""
    import flexrv.studies.tolerance as study

    def stopped(out, *args, written="", **kw):
        cases = out / "runs" / "cases"
        cases.mkdir(parents=True)
        (cases / f".case_0.json.{os.getpid()}.k2x9_q.tmp.json").write_text("{")
        if written:
            (cases / written).write_text("{}")
        raise KeyboardInterrupt

    for name, kept in (("", False), ("case_1.json", True)):
        out = tmp_path / f"study{int(kept)}"
        monkeypatch.setattr(study, "_run_in", lambda o, *a, **k: stopped(o, *a, written=name, **k))
        cfg = study.StudyConfig(design="rv40e", samples=2, tolerances="rv40e", out=str(out))
        with pytest.raises(KeyboardInterrupt):
            study.run_study(cfg, progress=False)
        assert out.exists() is kept, name


def test_a_stalled_static_solve_is_retried_with_the_ladder(rv40e, monkeypatch):
    """A ConvergenceError of the static solve is retried with the next settings of
    SOLVER_LADDER (tolerance x0.1, then max_iter x5); the attempt that succeeded is
    returned, and the last error is raised when every attempt stalls."""
    import flexrv.model.quasi_static as qs
    from flexrv.errors import ConvergenceError
    from flexrv.studies.tolerance import SOLVER_LADDER, loaded_te_with_retries

    seen = []

    def stalls(times):
        def fake(reducer, options, **kw):
            seen.append((options, kw))
            if len(seen) <= times:
                raise ConvergenceError(f"stalled {len(seen)}")
            return "result"

        return fake

    monkeypatch.setattr(qs, "loaded_te", stalls(2))
    assert loaded_te_with_retries(rv40e, 1e-6, 200, points_per_mesh=3) == ("result", 2)
    assert [o for o, _ in seen] == [{"force_tol": 1e-6 * f, "max_iter": int(200 * i)} for f, i in SOLVER_LADDER]
    assert all(kw == {"points_per_mesh": 3} for _, kw in seen)
    seen.clear()
    monkeypatch.setattr(qs, "loaded_te", stalls(len(SOLVER_LADDER)))
    with pytest.raises(ConvergenceError, match=f"stalled {len(SOLVER_LADDER)}"):
        loaded_te_with_retries(rv40e, 1e-6, 200)
