"""A plain (non-editable) install runs the workflows and ``simulate`` from any directory:
the workflows are part of the installed package, outputs go to ./results of the current
directory (issue 18). Slow: builds a wheel (pip's build isolation fetches setuptools/wheel
from the package index) and installs it into a temporary folder with ``pip install
--target`` (dependencies from the running interpreter), then compiles the numba kernels
of that copy once."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_non_editable_install_runs_workflow_and_simulate_from_another_directory(tmp_path):
    import shutil

    src = tmp_path / "src"  # a copy, so that the build leaves nothing in the source tree
    shutil.copytree(
        ROOT,
        src,
        ignore=shutil.ignore_patterns(
            ".git", "meshes", "results", "build", "*.egg-info", ".pytest_cache", "__pycache__", ".benchmarks"
        ),
    )
    target = tmp_path / "site"
    r = subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), str(src)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    if r.returncode != 0 and ("Could not find a version" in r.stderr or "NewConnectionError" in r.stderr):
        pytest.skip("no package index reachable to build the wheel")
    assert r.returncode == 0, r.stderr[-2000:]
    py = sys.executable
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {
        **os.environ,
        "MPLBACKEND": "Agg",
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
        "PYTHONPATH": str(target),
    }
    where = subprocess.run(
        [str(py), "-c", "import flexrv.workflows, flexrv; print(flexrv.__file__)"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert where.startswith(str(target)), where  # the installed copy, not the source tree
    r = subprocess.run(
        [str(py), "-m", "flexrv", "workflow", "kinematic_validation", "--smoke", "--json"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    out = Path(json.loads(r.stdout)["out_dir"])
    assert out == work / "results" / "kinematic_validation-smoke"
    assert (out / "summary.md").read_text().startswith("# Kinematic validation")
    assert "SMOKE RUN" in (out / "summary.md").read_text().splitlines()[0]
    r = subprocess.run(
        [str(py), "-m", "flexrv", "simulate", "rv40e", "--t-end", "0.004", "--json", "--out", "results/sim"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert (work / "results" / "sim" / "results.nc").exists()
    r = subprocess.run(
        [str(py), "-m", "flexrv", "report", "--smoke", "--json"], cwd=work, env=env, capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert Path(json.loads(r.stdout)["path"]) == work / "results" / "REPORT-smoke.md"
