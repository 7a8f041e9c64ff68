"""A first run that speaks: the command's first-run notice, the one-line notice of each cache
entry built for the first time (with the time it usually takes), `te`'s announcement of its
positions, and Ctrl-C while the FE bodies are built."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests._procs import sigint_default

ROOT = Path(__file__).resolve().parent.parent


def test_build_notice_says_what_and_how_long(tmp_path, monkeypatch, capsys):
    """A condensed FE body's first build announces itself in one line on stderr with the typical
    time (flexrv.cache.TYPICAL_BUILD_S); once this cache has built that kind of entry, the notice
    quotes the measured time instead."""
    from flexrv import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    path = tmp_path / "cycloid_disc-0123456789abcdef.compliance.json"
    line = cache.build_notice(path)
    assert line == capsys.readouterr().err.strip()
    assert "condensing the cycloid disc FE body" in line
    assert f"usually ~{cache.TYPICAL_BUILD_S['.compliance.json']:.0f} s" in line
    cache.record_build_time(path, 12.34)
    assert "usually ~12 s" in cache.build_notice(tmp_path / "cycloid_disc-fedcba9876543210.compliance.json")
    assert "meshing the carrier" in cache.build_notice(tmp_path / "carrier-0123456789abcdef.msh")


def test_cached_entry_announces_a_first_build_once(tmp_path, monkeypatch, capsys):
    """cached_entry: a missing entry prints its notice once while it is built (and its build time
    is recorded); the second call loads it silently."""
    import json

    from flexrv import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    path = tmp_path / "carrier-0123456789abcdef.compliance.json"

    def build():
        cache.atomic_write_text(path, json.dumps({"x": 1.0}))
        return {"x": 1.0}

    value, cached = cache.cached_entry([path], "k1", lambda: json.loads(path.read_text()), build)
    err = capsys.readouterr().err
    assert (value, cached) == ({"x": 1.0}, False)
    assert err.count("\n") == 1 and "condensing the carrier FE body" in err
    assert "carrier.compliance.json" in json.loads((tmp_path / cache.BUILD_TIMES).read_text())
    value, cached = cache.cached_entry([path], "k1", lambda: json.loads(path.read_text()), build)
    assert (value, cached) == ({"x": 1.0}, True)
    assert capsys.readouterr().err == ""


def test_first_run_notice_only_with_an_empty_kernel_cache(tmp_path, monkeypatch, capsys):
    """The command's first-run notice: printed for a model-building command while numba's cache
    holds no index file; not for a warm cache, `--help` or a command that builds nothing."""
    from flexrv.cli import first_run_notice

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    line = first_run_notice(["simulate", "rv221", "--model", "rigid"])
    assert line and "first run" in line and "compiling numba kernels" in line and len(line) < 200
    assert capsys.readouterr().err.strip() == line
    assert first_run_notice(["--cache-dir", str(tmp_path), "te", "rv40e"]).startswith("flexrv te:")
    assert first_run_notice(["presets"]) is None
    assert first_run_notice(["te", "--help"]) is None
    index = tmp_path / "numba" / "flexrv_model" / "kernels.fused-1.py311.nbi"
    index.parent.mkdir(parents=True)
    index.write_bytes(b"")
    assert first_run_notice(["simulate", "rv221"]) is None


def test_te_announces_its_positions(capsys):
    """`flexrv te` announces the number of positions it solves (that of positions_for) and an
    estimate of its time before solving."""
    from flexrv.cli.te import SECONDS_FIXED, SECONDS_PER_POSITION, announce_positions
    from flexrv.design import load
    from flexrv.model.quasi_static import positions_for

    red = load("rv40e")
    n = len(positions_for(red, None, 0.5, 8))
    line = announce_positions(red, None, 0.5, 8)
    assert f"at {n} positions" in line and line == capsys.readouterr().err.strip()
    assert f"usually ~{SECONDS_FIXED + SECONDS_PER_POSITION * n:.0f} s" in line


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_first_line_within_seconds_and_signal_while_building_bodies(tmp_path, sig, code):
    """Empty caches (FE and numba): the first line comes within seconds of the start (goal 2 s on
    a quiet machine, benchmarks/bench_first_run.py; 8 s here for a loaded test machine), and a
    signal a few seconds later, while the design is checked and its FE bodies are built (and its
    kernels compile in a background process), ends the run within 5 s with 128 + signum, no
    traceback and no run folder, and no process of the run is left."""
    out = tmp_path / "run"
    env = {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
        "FLEXRV_CACHE_DIR": str(tmp_path / "cache"),
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "MPLBACKEND": "Agg",
    }
    env.pop("NUMBA_CACHE_DIR", None)
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexrv", "simulate", "rv221", "--model", "rigid", "--t-end", "0.01", "--out", str(out)],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=sigint_default,
    )
    try:
        first = proc.stderr.readline()
        latency = time.monotonic() - t0
        assert "first run" in first, first
        time.sleep(4.0)
        assert proc.poll() is None, "the run ended before the signal"
        if len(os.sched_getaffinity(0)) > 1:  # the command and its background compilation
            assert len(_processes_with_cache(tmp_path / "cache")) >= 2
        t1 = time.monotonic()
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=60)
        elapsed = time.monotonic() - t1
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert latency < 8.0, latency
    assert proc.returncode == code, stderr[-2000:]
    assert elapsed < 5.0, elapsed
    assert "Traceback" not in stderr
    assert not out.exists()
    t2 = time.monotonic()  # the background compilation (flexrv.model.kernel_cache) ended with the command
    while _processes_with_cache(tmp_path / "cache") and time.monotonic() - t2 < 5.0:
        time.sleep(0.1)
    assert not _processes_with_cache(tmp_path / "cache")


def _processes_with_cache(cache: Path) -> list[int]:
    """Live processes (not zombies) whose environment names ``cache`` as FLEXRV_CACHE_DIR."""
    needle = f"FLEXRV_CACHE_DIR={cache}".encode() + b"\0"
    found = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            if needle in (proc / "environ").read_bytes() + b"\0":
                if (proc / "stat").read_text().split(")")[-1].split()[0] != "Z":
                    found.append(int(proc.name))
        except OSError:
            continue
    return found


def test_sigterm_inside_a_gmsh_session_reaches_python():
    """gmsh's initialisation installs its own C handler of SIGTERM (the process then dies with
    -15, no cleanup); inside flexrv's gmsh session Python's handler runs (exit 143 here)."""
    code = (
        "import os, signal, sys\n"
        "signal.signal(signal.SIGTERM, lambda s, f: sys.exit(143))\n"
        "from flexrv.meshing.session import gmsh_session\n"
        "with gmsh_session():\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "    signal.pause() if hasattr(signal, 'pause') else None\n"
    )
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 143, r.stderr[-2000:]


def test_te_reports_progress_of_both_curves():
    """loaded_te's ``progress(stage, done, total)``: both curves report, counts rise to the number
    of positions (every 256 positions and at the end), and the CLI's bar accepts them."""
    from flexrv.cli.te import progress_bar
    from flexrv.design import load
    from flexrv.model.quasi_static import loaded_te

    calls = []
    r = loaded_te(
        load("rv40e"),
        crank_revolutions=1.0,
        points_per_mesh=8,
        catalog_positions=1,
        progress=lambda stage, done, total: calls.append((stage, done, total)),
    )
    n = len(r.input_angle)
    assert n == 312
    assert calls == [(stage, done, n) for stage in ("loaded curve", "no-load curve") for done in (256, n)]
    bar = progress_bar(True)
    for call in calls:
        bar(*call)
    bar.stop()
    assert progress_bar(False) is None
