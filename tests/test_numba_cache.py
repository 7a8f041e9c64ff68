"""numba's compiled-kernel cache: it lives in the user cache directory beside flexrv's
other caches (``<cache>/numba/<flexrv version>``), and a damaged entry heals itself: a
truncated data file (``.nbc``) or a corrupted index (``.nbi``) is discarded and the
kernel compiled again, with one warning, and the result is correct.

Each case runs in a fresh interpreter with its own empty ``NUMBA_CACHE_DIR`` and a
one-line kernel module (compiles in about a second), so the test is fast and never
touches the real cache.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

KERNEL = """
from numba import njit


@njit(cache=True)
def triple_plus_one(x):
    return 3.0 * x + 1.0
"""

#: the child imports flexrv first (which guards numba's cache), then the kernel module
CHILD = "import flexrv, tinykernel; print('result', tinykernel.triple_plus_one(2.0))"


def _run(tmp_path: Path) -> subprocess.CompletedProcess:
    env = {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{tmp_path / 'src'}",
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
    }
    return subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, timeout=300)


@pytest.fixture
def filled(tmp_path):
    """A kernel module whose cache entry has been written by a first run."""
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "tinykernel.py").write_text(KERNEL)
    first = _run(tmp_path)
    assert first.returncode == 0, first.stderr
    assert "result 7.0" in first.stdout
    assert "damaged" not in first.stderr
    return tmp_path


def _files(tmp_path: Path, suffix: str) -> list[Path]:
    return sorted((tmp_path / "numba").rglob(f"tinykernel.*{suffix}"))


def _damage_nbc(tmp_path: Path) -> None:
    (nbc,) = _files(tmp_path, ".nbc")
    data = nbc.read_bytes()
    nbc.write_bytes(data[: len(data) // 3])  # truncated (disk full, killed writer)


def _damage_nbi(tmp_path: Path) -> None:
    import io
    import pickle

    (nbi,) = _files(tmp_path, ".nbi")
    data = bytearray(nbi.read_bytes())
    # keep numba's version header (a pickled string), corrupt the pickled index after it
    stream = io.BytesIO(bytes(data))
    pickle.load(stream)
    start = stream.tell() + 8
    data[start : start + 16] = b"\xfe" * 16
    nbi.write_bytes(bytes(data))


@pytest.mark.parametrize("damage", [_damage_nbc, _damage_nbi], ids=["truncated_nbc", "corrupted_nbi"])
def test_damaged_entry_is_recompiled_with_one_warning(filled, damage):
    damage(filled)
    healed = _run(filled)
    assert healed.returncode == 0, healed.stderr
    assert "Traceback" not in healed.stderr
    assert "result 7.0" in healed.stdout  # 3 * 2 + 1, computed by the recompiled kernel
    assert healed.stderr.count("discarded a damaged numba cache entry") == 1, healed.stderr
    again = _run(filled)  # the entry was written anew: no warning any more
    assert again.returncode == 0 and "result 7.0" in again.stdout
    assert "damaged" not in again.stderr, again.stderr
    assert _files(filled, ".nbi") and _files(filled, ".nbc")


def test_cache_sits_beside_flexrv_caches(tmp_path):
    """Without NUMBA_CACHE_DIR, flexrv points numba at <FLEXRV_CACHE_DIR>/numba/<version>
    before numba is imported (numba reads the variable once, at its import)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update({"PYTHONPATH": str(ROOT), "FLEXRV_CACHE_DIR": str(tmp_path)})
    code = (
        "import sys, flexrv; assert 'numba' not in sys.modules; "
        "from numba.core import config; print(config.CACHE_DIR); print(flexrv.__version__)"
    )
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    cache, version = proc.stdout.split()
    assert Path(cache) == tmp_path / "numba" / version
