"""No run ever lost: Ctrl-C / SIGTERM keep the partial results with exit code
130 / 143 (128 + the signal number); a SIGKILL leaves the last checkpoint readable
(``results.nc`` with status "running" and ``checkpoint.npz``), and ``flexrv
simulate --resume DIR`` completes the run.

Resume is bit-identical to the uninterrupted run, by construction: every run is
integrated in segments of SEGMENT_STEPS steps, restarting the integrator at each
boundary from the reached coordinates, velocities and accelerations with every
group's history (pin closest-point warm starts, time caches) reset, and checkpoints
are written only at boundaries (flexrv.simulation.Simulation.run). The SIGKILL test
compares every variable of the two results.nc with np.array_equal.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parent.parent


def _env() -> dict:
    return {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MPLBACKEND": "Agg",
    }


def _start(out: Path, t_end: float, checkpoint_s: float = 0.5) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flexrv",
            "simulate",
            "rv40e",
            "--t-end",
            str(t_end),
            "--out",
            str(out),
            "--checkpoint-s",
            str(checkpoint_s),
            "--json",
        ],
        cwd=out.parent,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_checkpoint(proc: subprocess.Popen, out: Path, timeout: float = 400.0) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline:
        if (out / "checkpoint.npz").exists() and (out / "results.nc").exists():
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    proc.kill()
    pytest.fail("no checkpoint written")


@pytest.mark.slow
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_keeps_partial_results(tmp_path, sig, code):
    out = tmp_path / "run"
    proc = _start(out, t_end=3.0)
    _wait_for_checkpoint(proc, out)
    time.sleep(0.5)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == code, stderr[-2000:]
    assert "Traceback" not in stderr
    ds = xr.load_dataset(out / "results.nc", engine="h5netcdf")
    assert ds.attrs["status"] == "interrupted"
    assert ds.attrs["signal"] == signal.Signals(sig).name
    t = ds["time"].values
    assert 0.0 < t[-1] < 3.0 and np.all(np.diff(t) > 0)
    assert np.all(np.isfinite(ds["te"].values))
    assert (out / "summary.json").exists() and (out / "te.png").exists()
    assert '"status": "interrupted"' in stdout


@pytest.mark.slow
def test_sigkill_checkpoint_and_resume(tmp_path):
    from flexrv.post.results import load_results

    t_end = 0.5  # 5 segments: the kill comes after a checkpoint at a boundary, long before the end
    killed = tmp_path / "killed"
    proc = _start(killed, t_end=t_end, checkpoint_s=0.3)
    _wait_for_checkpoint(proc, killed)
    proc.kill()
    proc.communicate()
    part = xr.load_dataset(killed / "results.nc", engine="h5netcdf")
    assert part.attrs["status"] == "running"
    t_part = part["time"].values
    assert 0.0 < t_part[-1] < t_end and np.all(np.isfinite(part["te"].values))

    resumed = subprocess.run(
        [sys.executable, "-m", "flexrv", "simulate", "--resume", str(killed), "--json"],
        cwd=tmp_path,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert not list(killed.glob(".*.tmp*"))  # stale temp files removed by the resumed saves
    full = subprocess.run(
        [
            sys.executable,
            "-m",
            "flexrv",
            "simulate",
            "rv40e",
            "--t-end",
            str(t_end),
            "--out",
            str(tmp_path / "full"),
            "--json",
        ],
        cwd=tmp_path,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert full.returncode == 0, full.stderr[-2000:]
    a, b = load_results(killed), load_results(tmp_path / "full")
    assert a.attrs["status"] == b.attrs["status"] == "completed"
    assert np.array_equal(a.time, b.time)
    assert set(a.ds.data_vars) == set(b.ds.data_vars) and len(a.ds.data_vars) > 20
    differ = [n for n in a.ds.data_vars if not np.array_equal(a.ds[n].values, b.ds[n].values, equal_nan=True)]
    assert differ == []  # bit-identical, start-up transient included
    np.testing.assert_array_equal(a["te"].values[: len(t_part)], part["te"].values)
    assert a.summary()["te_pp_arcsec"] == b.summary()["te_pp_arcsec"]


def test_resume_refuses_what_it_cannot_continue(tmp_path):
    from flexrv.errors import InputError
    from flexrv.post.io import load_checkpoint

    with pytest.raises(InputError, match="no checkpoint.npz"):
        load_checkpoint(tmp_path)
    (tmp_path / "checkpoint.npz").write_bytes(b"PK\x03\x04 truncated")
    with pytest.raises(InputError, match="unreadable"):
        load_checkpoint(tmp_path)


def test_step_bound_before_build():
    from flexrv.errors import InputError
    from flexrv.simulation import MAX_STEPS, Simulation, check_step_count

    assert check_step_count(0.4, 1e-4) == 4000
    with pytest.raises(InputError, match="time steps"):
        Simulation("rv40e").run(t_end=1e9, dt=1e-4)
    with pytest.raises(InputError, match="GiB"):
        check_step_count(MAX_STEPS * 1e-4, 1e-4, n_coordinates=10_000)
