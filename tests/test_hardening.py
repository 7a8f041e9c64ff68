"""Faults a run must survive with a clear outcome: signals while numba compiles, a
cluster endpoint that is not a dask scheduler, full or read-only disks, spec limits.

Each test names the mechanism it checks; the CLI cases run ``python -m flexrv`` in a
subprocess, as a user would.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from tests._procs import sigint_default

ROOT = Path(__file__).resolve().parent.parent


def _env(**extra) -> dict:
    return {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MPLBACKEND": "Agg",
        **extra,
    }


# ----------------------------------------------------------------- signals while compiling
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_during_first_compile_exits_within_5s(tmp_path, sig, code):
    """With an empty numba cache the first step of a run compiles the kernels (tens of
    seconds to minutes, in this process or in the background process it waits for); a signal
    then ends the run within 5 s with 128 + signum and leaves no run folder (nothing was
    integrated). The compile notice is one short line."""
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", "simulate", "rv221", "--model", "rigid", "--t-end", "0.01", "--out", str(out)],
        cwd=tmp_path,
        env=_env(NUMBA_CACHE_DIR=str(tmp_path / "numba")),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=sigint_default,
    )
    try:
        first = proc.stderr.readline()  # the command's first-run notice, at its start
        assert "first run" in first and len(first) < 200, first
        # printed just before the kernels compile in this process, or (on 2+ cores) before it waits
        # for them to compile in the background process (flexrv.model.kernel_cache.BackgroundCompile)
        starts = ("flexrv: compiling numba kernels", "flexrv: waiting for the numba kernels")
        notice = proc.stderr.readline()
        while notice and not notice.startswith(starts):
            notice = proc.stderr.readline()  # (a notice of an FE body built on the way)
        assert notice.startswith(starts), notice
        assert len(notice) < 200 and "laws." not in notice  # one short line, no list of functions
        time.sleep(2.0)  # well inside the compilation (>= 10 s of it on this model)
        assert proc.poll() is None, "the run ended before the signal: nothing compiled?"
        t0 = time.monotonic()
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=30)
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == code, stderr[-2000:]
    assert elapsed < 5.0, elapsed
    assert "Traceback" not in stderr
    assert not out.exists()


# ----------------------------------------------------------------- pin loads: every pose
def _valid_stage(z_rp, radius, k1, pin_fraction):
    """(eccentricity, pin radius) of a cycloid stage free of undercut and pin overlap,
    or None: shortening coefficient K1 < 1, pins narrower than their spacing, pin
    radius below the epitrochoid's smallest convex curvature radius (the checks of
    :class:`flexrv.design.model.SecondStage`)."""
    from flexrv.geometry.cycloid import min_convex_curvature_radius

    e = k1 * radius / z_rp
    r_pin = pin_fraction * radius * np.sin(np.pi / z_rp)
    if r_pin >= 0.95 * min_convex_curvature_radius(z_rp, radius, e, samples=801):
        return None
    return e, r_pin


@pytest.mark.parametrize("law", ["palmgren", "linear"])
def test_degenerate_no_load_pose_of_a_small_unmodified_drive(law):
    """18 pins, 17 lobes, R_p 60-85 mm, e 0.9-1.6 mm, r_rp 2.5 mm, no modification: at the
    nominal pose every pin touches at once (gaps are round-off of either sign). The
    no-load pose is found at every one of 240 crank angles, and the pin forces balance
    the torque (sum F_i l_i = T to 1e-9, the Brent tolerance)."""
    from flexrv.analysis.pin_load import pin_load_distribution

    for radius, e in ((0.060, 0.0009), (0.070, 0.0012), (0.085, 0.0016)):
        for chi in np.linspace(0.0, 2.0 * np.pi, 240, endpoint=False):
            r = pin_load_distribution(50.0, 18, radius, 0.0025, e, 0.01, 2.2e11, crank_angle=chi, law=law)
            assert r.n_contact >= 1
            assert abs(np.sum(r.forces * r.arms) - 50.0) <= 1e-9 * 50.0


try:
    from hypothesis import given, settings
    from hypothesis import strategies as st
except ImportError:  # pragma: no cover
    given = None


if given is not None:

    @settings(max_examples=12, deadline=None, derandomize=True)
    @given(
        z_rp=st.integers(12, 60),
        radius=st.floats(0.03, 0.2),
        k1=st.floats(0.4, 0.9),
        pin_fraction=st.floats(0.2, 0.7),
        modified=st.booleans(),
        shift_um=st.floats(-20.0, 0.0),
        equidistant_um=st.floats(0.0, 20.0),
        rotation_deg=st.floats(-0.05, 0.05),
        torque=st.floats(1.0, 2000.0),
    )
    def test_pin_loads_at_every_crank_angle(
        z_rp, radius, k1, pin_fraction, modified, shift_um, equidistant_um, rotation_deg, torque
    ):
        """Random valid stages (12-60 pins, with and without modifications that leave the
        disc a clearance: equidistant >= 0, shift <= 0, any rotation): the no-load pose and
        a load distribution that balances the torque exist at every crank angle tried (24
        per stage). The pose stays within a fraction of the pin pitch."""
        from hypothesis import assume

        from flexrv.analysis.pin_load import pin_load_distribution

        stage = _valid_stage(z_rp, radius, k1, pin_fraction)
        assume(stage is not None)
        e, r_pin = stage
        mods = (shift_um * 1e-6, equidistant_um * 1e-6, np.radians(rotation_deg)) if modified else (0.0, 0.0, 0.0)
        for chi in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False):
            r = pin_load_distribution(
                torque, z_rp, radius, r_pin, e, 0.01, 2.2e11, *mods, crank_angle=chi, law="palmgren"
            )
            assert r.n_contact >= 1 and np.all(np.isfinite(r.forces))
            assert abs(np.sum(r.forces * r.arms) - torque) <= 1e-8 * torque
            assert abs(r.rotation) < 2.0 * np.pi / z_rp


def test_interference_fit_is_named():
    """A disc that overlaps every pin (equidistant modification -11 um, no clearance
    anywhere) has no no-load pose: a clear InputError, not a pose radians away."""
    from flexrv.analysis.pin_load import pin_load_distribution
    from flexrv.errors import InputError

    refused = 0
    for chi in np.linspace(0.0, 2.0 * np.pi / 40, 6, endpoint=False):
        try:
            r = pin_load_distribution(
                1.0, 40, 0.125, 0.0049, 0.0015625, 0.01, 2.2e11, 0.0, -11e-6, 0.0, crank_angle=chi
            )
        except InputError as exc:
            assert "interference fit" in str(exc) and "11 um" in str(exc)
            refused += 1
        else:  # a preloaded pose near the nominal one (Brent balances the preload), never radians away
            assert abs(r.rotation) < 1e-4
    assert refused >= 1


# ----------------------------------------------------------------- full and read-only disks
@pytest.fixture
def small_disk(tmp_path):
    """A 64 KiB tmpfs mounted for the test (skipped where the test may not mount one)."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)], capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here (needs root): {proc.stderr.strip() or proc.returncode}")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def test_atomic_write_on_full_and_read_only_disk_names_the_path(small_disk):
    """A write that does not fit fails naming the target file (not a temporary name,
    not a bare 'No space left on device'), keeps the earlier file intact and leaves no
    temporary file; the same on a file system remounted read-only."""
    import errno

    from flexrv.cache import atomic_write_bytes

    target = small_disk / "checkpoint.npz"
    atomic_write_bytes(target, b"old checkpoint" * 100)
    with pytest.raises(OSError) as info:
        atomic_write_bytes(target, os.urandom(200_000))
    assert info.value.errno == errno.ENOSPC
    assert info.value.filename == str(target) and "checkpoint.npz" in info.value.strerror
    assert target.read_bytes() == b"old checkpoint" * 100
    assert list(small_disk.iterdir()) == [target]
    ro = subprocess.run(["mount", "-o", "remount,ro", str(small_disk)], capture_output=True, text=True)
    if ro.returncode != 0:
        pytest.skip(f"cannot remount read-only: {ro.stderr.strip()}")
    with pytest.raises(OSError) as info:
        atomic_write_bytes(target, b"new")
    assert info.value.errno == errno.EROFS and info.value.filename == str(target)
    assert target.read_bytes() == b"old checkpoint" * 100


def test_disk_full_run_names_path_and_leaves_no_folder(small_disk):
    """``flexrv simulate`` onto a full disk: exit 2, one message naming the file it could
    not write, no traceback, and no empty run folder left behind."""
    out = small_disk / "run"
    proc = subprocess.run(
        [sys.executable, "-m", "flexrv", "simulate", "rv40e", "--t-end", "0.05", "--out", str(out)],
        cwd=small_disk.parent,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and "Warning" not in proc.stderr
    assert "No space left on device" in proc.stderr and str(out) + "/" in proc.stderr
    assert not out.exists()


# ----------------------------------------------------------------- cluster endpoints
class _Server:
    """A local TCP server of another protocol, started and stopped by the test: ``http``
    (an HTTP server: waits for a request, says nothing) or ``banner`` (sends a text line
    at once, as SSH does, whose first 8 bytes spell a length of exabytes)."""

    def __init__(self, kind: str):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.kind = kind
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        self.sock.settimeout(0.2)
        conns = []
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            conns.append(conn)
            if self.kind == "banner":
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
        for c in conns:
            c.close()

    def close(self):
        self.stop.set()
        self.thread.join(5)
        self.sock.close()


@pytest.mark.parametrize("kind", ["http", "banner"])
@pytest.mark.parametrize("command", ["sweep", "tolerance"])
def test_scheduler_that_is_not_dask_is_refused_quickly(tmp_path, kind, command):
    """``--scheduler`` at a server that accepts the TCP connection but is no dask
    scheduler: exit 2 within the 5 s handshake timeout (+ start-up), a message naming
    --scheduler and saying it is not a dask scheduler; no hang, no huge allocation."""
    server = _Server(kind)
    try:
        address = f"tcp://127.0.0.1:{server.port}"
        if command == "sweep":
            spec = tmp_path / "s.toml"
            spec.write_text(
                'name = "hs"\npreset = "rv40e"\ntask = "design"\noutputs = ["kinematics.ratio"]\n'
                '[grid]\n"second_stage.eccentricity_mm" = [1.0]\n'
            )
            argv = ["sweep", str(spec), "--scheduler", address, "--out", str(tmp_path / "out")]
        else:
            argv = ["tolerance", "rv40e", "--tolerances", "rv40e", "--samples", "2", "--scheduler", address]
            argv += ["--out", str(tmp_path / "out")]
        t0 = time.monotonic()
        proc = subprocess.run(
            [sys.executable, "-m", "flexrv", *argv],
            cwd=tmp_path,
            env=_env(),
            capture_output=True,
            text=True,
            timeout=120,
        )
        elapsed = time.monotonic() - t0
    finally:
        server.close()
    assert proc.returncode == 2, proc.stderr[-2000:]
    text = " ".join(proc.stderr.split())
    assert "--scheduler" in text and "not a dask scheduler" in text, text
    assert "Traceback" not in proc.stderr
    assert elapsed < 60.0
    assert not (tmp_path / "out").exists()


def test_real_scheduler_handshake_is_accepted():
    """The probe accepts a real dask scheduler (its handshake frame), so the check does
    not refuse what it guards."""
    from dask.distributed import LocalCluster

    from flexrv.sweep import check_scheduler

    with LocalCluster(
        n_workers=0, processes=False, protocol="tcp://", dashboard_address=None, silence_logs=40
    ) as cluster:
        check_scheduler(cluster.scheduler_address)


# ----------------------------------------------------------------- tolerance studies
def test_sigma_fraction_is_accepted():
    """``sigma_fraction``, listed as an allowed key of a band tolerance, is read as the
    band's sigma fraction (sigma = 0.5 x 2 um = 1 um: the truncated normal's standard
    deviation on +-2 sigma is 0.880 x sigma, scipy.stats.truncnorm)."""
    from flexrv.design import load
    from flexrv.design.tolerances import parse_tolerances

    table = {"pins.pin_radius_um": {"distribution": "band", "band_um": 2.0, "sigma_fraction": 0.5}}
    tol = parse_tolerances(table, load("rv40e"))
    assert tol.entries["pins.pin_radius_um"].sigma_fraction == 0.5
    # standard deviation of a normal of sigma 1 um truncated at +-2 sigma: 0.8796 um (closed form:
    # sqrt(1 - 2 c phi(c) / (2 Phi(c) - 1)) with c = 2, phi/Phi the standard normal pdf/cdf)
    assert abs(tol.sigma_of("pins.pin_radius_um") - 0.8796) < 1e-4


def test_failed_evaluations_exit_nonzero_with_the_count(monkeypatch, capsys):
    """``flexrv tolerance``: a study with failed evaluations prints them with the count
    and exits 1 (0 only when every evaluation succeeded)."""
    import flexrv.studies.tolerance as study
    from flexrv.cli import main

    def fake_run_study(cfg, progress=True):
        return {
            "design": "rv40e",
            "output_dir": "/x/out",
            "samples": 4,
            "sampler": "sobol",
            "seed": 0,
            "variables": 1,
            "evaluations": 4,
            "computed_now": 4,
            "skipped_existing": 0,
            "failed": 3,
            "wall_time_s": 0.1,
            "resolution": {},
            "cpu": {},
            "percentiles": {},
            "yield": None,
            "ranked_sensitivities": {},
            "what_if": {},
        }

    monkeypatch.setattr(study, "run_study", fake_run_study)
    with pytest.raises(SystemExit) as info:
        main(["tolerance", "rv40e", "--samples", "4", "--json"])
    assert info.value.code == 1
    assert "3 of 4 evaluations failed" in " ".join(capsys.readouterr().err.split())


def test_all_failed_study_draws_no_histograms(tmp_path):
    """Without one successful sample the study writes its data and summary but no
    histogram or tornado figure (an empty histogram says nothing), and removes those
    of an earlier run of the same folder."""
    from types import SimpleNamespace

    import flexrv.studies.tolerance as study

    (tmp_path / "histograms.png").write_bytes(b"old")
    plan = SimpleNamespace(
        columns=[SimpleNamespace(label="pin r", entry="pins.pin_radius_um")],
        reducer=SimpleNamespace(name="rv40e"),
        tol=SimpleNamespace(to_dict=lambda: {}),
        batch_values={},
    )
    n = 3
    parts = {"u": np.zeros((n, 1)), "x": np.zeros((n, 1))}
    y = np.full((n, len(study.OUTPUTS)), np.nan)
    result = {"sampler": "random", "resolution": {}, "ranked_sensitivities": {}}
    cfg = SimpleNamespace(seed=0)
    orig = study._markdown
    try:
        study._markdown = lambda r: "summary"
        study._write_outputs(tmp_path, cfg, plan, parts, y, ["failed"] * n, ["a", "b", "c"], [], result)
    finally:
        study._markdown = orig
    assert result["plots"] == []
    assert not (tmp_path / "histograms.png").exists() and not (tmp_path / "tornado.png").exists()
    assert (tmp_path / "samples.nc").exists() and (tmp_path / "summary.md").read_text() == "summary"


# ----------------------------------------------------------------- te: a run too short for a spectrum
def test_te_too_short_for_a_spectrum_writes_its_summary(tmp_path):
    """``flexrv te rv40e --crank-revolutions 0.05 --points-per-mesh 2``: 4 positions, fewer
    than the 8 a spectrum needs. The run ends normally with every output except the
    spectrum, and says why there is none."""
    out = tmp_path / "te"
    proc = subprocess.run(
        [sys.executable, "-m", "flexrv", "te", "rv40e", "--crank-revolutions", "0.05", "--points-per-mesh", "2"]
        + ["--out", str(out), "--json"],
        cwd=tmp_path,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert {"results.nc", "summary.json", "summary.md", "te.png", "pin_forces.png"} <= {p.name for p in out.iterdir()}
    assert not (out / "te_spectrum.png").exists()
    md = (out / "summary.md").read_text()
    assert "no TE spectrum: 4 positions, a spectrum needs at least 8" in md
