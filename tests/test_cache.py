"""Caches that heal: every entry is stamped with its key, size and sha256 (signed with the
cache's own key) and verified on read; a truncated, emptied, altered or foreign entry is rebuilt with a
one-line notice; keys include flexrv's version; concurrent builders of one entry
build it once. Atomic writes respect the umask and clean stale temp files."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

import flexrv
from flexrv import cache
from flexrv.cache import (
    atomic_write_text,
    cache_dir,
    cached_entry,
    finished_files,
    library_versions,
    remove_stale_temp_files,
)


@pytest.fixture()
def cache_root(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXRV_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("FLEXRV_CACHE", raising=False)
    return tmp_path / "cache"


def test_cache_dir_env_and_default(cache_root, monkeypatch):
    assert cache_dir() == cache_root and cache_root.is_dir()
    monkeypatch.delenv("FLEXRV_CACHE_DIR")
    from platformdirs import user_cache_dir

    monkeypatch.setenv("XDG_CACHE_HOME", str(cache_root.parent / "xdg"))
    assert cache_dir() == Path(user_cache_dir("flexrv", appauthor=False))


def test_keys_include_flexrv_version(monkeypatch):
    from flexrv.design import load
    from flexrv.meshing import parts as P
    from flexrv.meshing.mesh import mesh_key

    assert library_versions("numpy")["flexrv"] == flexrv.__version__
    spec = P.spec_for(load("rv40e"), "crankshaft")
    k1 = mesh_key(spec, 3e-3, 3e-3)
    from flexrv import _version

    monkeypatch.setattr(_version, "__version__", flexrv.__version__ + ".post1")
    assert mesh_key(spec, 3e-3, 3e-3) != k1


def _counting_build(path: Path, counter: Path, value: float, delay: float = 0.0):
    def build():
        with open(counter, "a") as fh:
            fh.write("x")
        time.sleep(delay)
        atomic_write_text(path, json.dumps({"value": value}))
        return value

    return build


def test_corrupt_entries_are_rebuilt_with_a_notice(cache_root, capsys):
    path = cache_dir() / "entry.json"
    counter = cache_root / "count"
    load = lambda: json.loads(path.read_text())["value"]  # noqa: E731
    build = _counting_build(path, counter, 1.5)
    assert cached_entry([path], "k1", load, build) == (1.5, False)
    assert cached_entry([path], "k1", load, build) == (1.5, True)
    assert capsys.readouterr().err == ""
    for corrupt in (
        lambda: path.write_text(path.read_text()[:5]),  # truncated
        lambda: path.write_bytes(b""),  # 0 bytes
        lambda: path.write_text(path.read_text().replace("1.5", "2.5")),
    ):  # same size, other content
        corrupt()
        assert cached_entry([path], "k1", load, build) == (1.5, False)
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "entry.json" in err and "rebuilding" in err
    # a foreign entry (another key's file and stamp) under this name is not served
    assert cached_entry([path], "k2", load, _counting_build(path, counter, 7.0)) == (7.0, False)
    assert "another key" in capsys.readouterr().err
    assert counter.read_text() == "x" * 5


def test_altered_entry_with_a_matching_stamp_is_rebuilt(cache_root, capsys):
    """Provenance, not only integrity: an entry whose file was altered AND whose stamp
    was rewritten with the altered file's size and sha256 (a forger without the cache's
    signing key, or an entry copied from another cache) is refused and rebuilt; the
    signing key is private to its folder (mode 0600) and a damaged key only forces
    rebuilds."""
    import hashlib

    path = cache_dir() / "entry.json"
    counter = cache_root / "count"
    load = lambda: json.loads(path.read_text())["value"]  # noqa: E731
    build = _counting_build(path, counter, 1.5)
    assert cached_entry([path], "k1", load, build) == (1.5, False)
    key_file = cache_dir() / cache.SIGNING_KEY_NAME
    assert key_file.stat().st_mode & 0o777 == 0o600 and len(key_file.read_bytes()) == 32
    path.write_text(json.dumps({"value": 9.5}))
    stamp_file = path.with_name(path.name + cache.STAMP_SUFFIX)
    stamp = json.loads(stamp_file.read_text())
    data = path.read_bytes()
    stamp.update(size=len(data), sha256=hashlib.sha256(data).hexdigest())
    stamp_file.write_text(json.dumps(stamp))
    assert cache.entry_problem([path], "k1") is not None and "signature" in cache.entry_problem([path], "k1")
    assert cached_entry([path], "k1", load, build) == (1.5, False)
    assert "signature" in capsys.readouterr().err
    assert cached_entry([path], "k1", load, build) == (1.5, True)
    key_file.write_bytes(b"short")  # damaged key: replaced, the entry it signed is rebuilt once
    assert cached_entry([path], "k1", load, build) == (1.5, False)
    assert cached_entry([path], "k1", load, build) == (1.5, True)
    assert counter.read_text() == "x" * 3


def test_library_versions_read_once(monkeypatch):
    """Package metadata is read once per process: the second call reads nothing."""
    import importlib.metadata as md

    library_versions("numpy", "scipy")
    calls = []
    monkeypatch.setattr(md, "version", lambda name: calls.append(name) or "0")
    v = library_versions("numpy", "scipy")
    assert calls == [] and v["numpy"] == np.__version__ and v["flexrv"] == flexrv.__version__


def test_truncated_mesh_files_rebuilt(cache_root, capsys):
    from flexrv.design import load
    from flexrv.meshing import build_mesh

    rv = load("rv40e")
    first = build_mesh(rv, "crankshaft")
    assert not first.cached
    nodes = first.data.nodes.copy()
    again = build_mesh(rv, "crankshaft")
    assert again.cached
    for path, cut in ((first.npz_path, 1000), (first.npz_path, 0), (first.msh_path, 5000), (first.vtu_path, 100)):
        with open(path, "r+b") as fh:
            fh.truncate(cut)
        res = build_mesh(rv, "crankshaft")
        assert not res.cached, path
        assert "rebuilding" in capsys.readouterr().err
        np.testing.assert_array_equal(res.data.nodes.shape, nodes.shape)
        assert build_mesh(rv, "crankshaft").cached


def _builder_process(root: str, counter: str, barrier) -> None:
    os.environ["FLEXRV_CACHE_DIR"] = root
    path = Path(root) / "shared.json"
    barrier.wait()
    cached_entry(
        [path], "k", lambda: json.loads(path.read_text())["value"], _counting_build(path, Path(counter), 3.0, delay=1.0)
    )


def test_concurrent_builders_build_once(cache_root):
    cache_root.mkdir(parents=True, exist_ok=True)
    counter = cache_root / "count"
    ctx = mp.get_context("fork")
    barrier = ctx.Barrier(3)
    procs = [ctx.Process(target=_builder_process, args=(str(cache_root), str(counter), barrier)) for _ in range(3)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    assert counter.read_text() == "x"  # one build, the others waited and loaded it


def test_atomic_write_mode_and_stale_temp_files(tmp_path):
    old = os.umask(0o027)
    try:
        atomic_write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o640
    dead_pid = 2**22 + 12345  # above the default pid_max: no such process
    stale = tmp_path / f".results.nc.{dead_pid}.ab_cd.tmp.nc"
    stale.write_text("half")
    mine = tmp_path / f".te.png.{os.getpid()}.zz.tmp.png"  # a save in progress in this process
    mine.write_text("busy")
    atomic_write_text(tmp_path / "b.txt", "y")
    assert not stale.exists() and mine.exists()
    assert remove_stale_temp_files(tmp_path) == []
    shutil.rmtree(tmp_path)
    assert remove_stale_temp_files(tmp_path) == []
    assert cache.STAMP_SUFFIX.endswith(".json")


def test_finished_files_leave_out_writes_in_progress(tmp_path):
    """A glob for ``*.json`` also matches an atomic write's temporary file
    (``.<name>.<pid>.<random>.tmp.json``); :func:`flexrv.cache.finished_files` counts only the
    files whose write finished (what a study counts as its stored cases)."""
    assert finished_files(tmp_path / "missing") == []
    (tmp_path / f".case_1.json.{os.getpid()}.k2x9_q.tmp.json").write_text("{")
    assert len(list(tmp_path.glob("*.json"))) == 1 and finished_files(tmp_path) == []
    atomic_write_text(tmp_path / "case_0.json", "{}")
    (tmp_path / "notes.txt").write_text("x")
    assert finished_files(tmp_path) == [tmp_path / "case_0.json"]
    assert finished_files(tmp_path, "*.txt") == [tmp_path / "notes.txt"]


def test_cli_cache_dir_option(tmp_path):
    """`flexrv --cache-dir DIR ...` puts the cache entries in DIR (overriding the
    environment and the user cache directory)."""
    import subprocess
    import sys

    d = tmp_path / "cache"
    cp = subprocess.run(
        [sys.executable, "-m", "flexrv", "--cache-dir", str(d), "mesh", "rv40e", "--part", "outer_ring", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert cp.returncode == 0, cp.stderr
    assert any(p.name.startswith("outer_ring-") and p.suffix == ".msh" for p in d.iterdir())
