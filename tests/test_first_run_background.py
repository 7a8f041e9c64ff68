"""Background compilation of a first run (:mod:`flexrv.model.kernel_cache`): a second process
fills numba's cache with the kernels the command will call, the command waits for it and loads
them instead of compiling; a failed job leaves the command to compile (one notice); the process
dies with the command (exit, SIGTERM, SIGKILL); numba's cache index is read and written under
one lock by all processes.

The fast cases use a one-line kernel module in a fresh interpreter with its own empty
``NUMBA_CACHE_DIR`` (compiles in about a second); the slow case runs ``flexrv simulate`` cold.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

KERNEL = """
import time

from numba import njit


@njit(cache=True)
def triple_plus_one(x):
    return 3.0 * x + 1.0


def job(delay):
    time.sleep(delay)  # the parent reaches the kernel while this job still runs
    return triple_plus_one(2.0)


def failing_job():
    raise RuntimeError("no compiler today")


def sleeping_job():
    time.sleep(300)
"""

#: the parent: starts the job, then calls the kernel and reports numba's cache statistics
PARENT = """
import sys
import flexrv
import tinykernel
from flexrv.model.kernel_cache import start_background

job = start_background(getattr(tinykernel, sys.argv[1]), tuple(float(a) for a in sys.argv[2:]),
                       entries=("triple_plus_one",), modules=("tinykernel",), what="test kernels")
assert job is not None, "not started"
print("child", job.proc.pid, flush=True)
value = tinykernel.triple_plus_one(2.0)
stats = tinykernel.triple_plus_one.stats
print("result", value, "hits", sum(stats.cache_hits.values()), "misses", sum(stats.cache_misses.values()))
"""

pytestmark = pytest.mark.skipif(
    not hasattr(os, "sched_getaffinity") or len(os.sched_getaffinity(0)) < 2,
    reason="background compilation needs two cores",
)


def _env(tmp_path: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "FLEXRV_BACKGROUND_COMPILE"}
    env.update(PYTHONPATH=f"{ROOT}{os.pathsep}{tmp_path / 'src'}", NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    return env


@pytest.fixture
def src(tmp_path):
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "tinykernel.py").write_text(KERNEL)
    (tmp_path / "src" / "parent.py").write_text(PARENT)
    return tmp_path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (ended, not reaped by its new parent yet) counts as gone
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except OSError:
        return True


def _gone_within(pid: int, seconds: float) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        if not _alive(pid):
            return True
        time.sleep(0.05)
    return False


def test_parent_waits_and_loads_what_the_child_compiled(src):
    """The child compiles the kernel (after a 2 s delay, so the parent reaches the kernel first);
    the parent waits for it (one notice) and loads the kernel from the cache: numba counts one
    cache hit and no miss in the parent (it compiled nothing), and the result is 3 * 2 + 1."""
    r = subprocess.run(
        [sys.executable, str(src / "src" / "parent.py"), "job", "2.0"],
        env=_env(src),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "result 7.0 hits 1 misses 0" in r.stdout, r.stdout + r.stderr
    assert r.stderr.count("waiting for the test kernels compiling in a background process") == 1, r.stderr
    assert "failed" not in r.stderr


def test_failed_child_leaves_the_parent_to_compile_with_one_notice(src):
    """A job that raises: the parent says so once, with the job's error, and compiles the kernel
    itself (one cache miss, the right result)."""
    r = subprocess.run(
        [sys.executable, str(src / "src" / "parent.py"), "failing_job"],
        env=_env(src),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "result 7.0 hits 0 misses 1" in r.stdout, r.stdout + r.stderr
    assert r.stderr.count("background compilation failed (RuntimeError: no compiler today)") == 1, r.stderr


def test_no_child_when_the_cache_holds_the_kernel_or_when_turned_off(src):
    """A warm cache (the kernel's index exists) or FLEXRV_BACKGROUND_COMPILE=0: no process is started."""
    env = _env(src)
    index = src / "numba" / "tinykernel.triple_plus_one-7.py311.nbi"
    index.parent.mkdir(parents=True)
    index.write_bytes(b"")
    r = subprocess.run(
        [sys.executable, str(src / "src" / "parent.py"), "job", "0"], env=env, capture_output=True, text=True
    )
    assert "not started" in r.stderr
    index.unlink()
    env["FLEXRV_BACKGROUND_COMPILE"] = "0"
    r = subprocess.run(
        [sys.executable, str(src / "src" / "parent.py"), "job", "0"], env=env, capture_output=True, text=True
    )
    assert "not started" in r.stderr


@pytest.mark.parametrize("how", ["SIGKILL", "SIGTERM", "stop_now"])
def test_child_dies_with_the_parent(src, how):
    """The parent killed (SIGKILL: the kernel's parent-death signal), ended by SIGTERM (exit 143,
    the exit handler) or by flexrv's stop_now (os._exit inside a compilation): the child is gone
    within 5 s."""
    waiter = {
        "SIGKILL": "time.sleep(300)",
        "SIGTERM": "signal.signal(signal.SIGTERM, lambda s, f: sys.exit(143)); time.sleep(300)",
        "stop_now": "time.sleep(4.0); stop_now(15)",  # after the check that the child runs
    }[how]
    code = (
        "import signal, sys, time, flexrv, tinykernel\n"
        "from flexrv.model.kernel_cache import start_background, stop_now\n"
        "job = start_background(tinykernel.sleeping_job, entries=('x',), modules=('tinykernel',))\n"
        "print(job.proc.pid, flush=True)\n" + waiter + "\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", code], env=_env(src), stdout=subprocess.PIPE, text=True)
    try:
        child = int(parent.stdout.readline())
        time.sleep(1.0)
        assert _alive(child)
        if how != "stop_now":
            parent.send_signal(getattr(signal, how))
        code = parent.wait(timeout=30)
        assert code == {"SIGKILL": -9, "SIGTERM": 143, "stop_now": 143}[how]
        assert _gone_within(child, 5.0), f"background process {child} outlived its parent ({how})"
    finally:
        if parent.poll() is None:
            parent.kill()


def test_index_lock_holds_off_other_processes(src, monkeypatch):
    """While this process holds numba_index_lock, another process cannot read or write numba's
    cache (it waits at its first cache lookup); it finishes, correct, once the lock is released."""
    from flexrv import cache

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(src / "numba"))
    code = "import flexrv, tinykernel; print('result', tinykernel.triple_plus_one(2.0))"
    with cache.numba_index_lock():
        proc = subprocess.Popen(
            [sys.executable, "-c", code], env=_env(src), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        time.sleep(6.0)  # import and compile take ~1-2 s: the process is now waiting for the lock
        assert proc.poll() is None, proc.communicate()
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert "result 7.0" in out
    assert list((src / "numba").rglob("tinykernel.triple_plus_one-*.nbi"))


def _model_compiles_script(args: list[str]) -> str:
    """A flexrv run that reports on stderr the numba compilations of model-layer kernels in ITS process."""
    return (
        "import atexit, sys, flexrv\n"
        "from numba.core import event\n"
        "seen = []\n"
        "class L(event.Listener):\n"
        "    def on_start(self, ev):\n"
        "        f = getattr(ev.data.get('dispatcher'), 'py_func', None)\n"
        "        if f is not None and f.__module__.startswith('flexrv.model.'):\n"
        "            seen.append(f.__module__ + '.' + f.__name__)\n"
        "    def on_end(self, ev):\n"
        "        pass\n"
        "event.register('numba:compile', L())\n"
        "atexit.register(lambda: print('model compiles in the command:', len(seen), sorted(set(seen))[:5], "
        "file=sys.stderr))\n"
        f"from flexrv.cli import main\nmain({args!r})\n"
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    "args",
    [["simulate", "rv221", "--model", "rigid", "--t-end", "0.01"], ["te", "rv40e", "--crank-revolutions", "0.2"]],
    ids=["simulate", "te"],
)
def test_cold_command_loads_every_model_kernel_from_the_background_process(tmp_path, args):
    """Empty caches, ``flexrv simulate rv221 --model rigid`` (short) or ``flexrv te rv40e`` (short):
    the background process compiles the kernels (simulate: the compiled integrator, which also serves
    the outputs' pass; te: the fused kernel and its outputs pass) with the real model's argument types
    (its bodies rigid), so the command itself compiles no model-layer kernel; the command completes
    (a few minutes each on a loaded 2-core machine)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "FLEXRV_BACKGROUND_COMPILE")}
    env.update(PYTHONPATH=str(ROOT), FLEXRV_CACHE_DIR=str(tmp_path / "cache"), OMP_NUM_THREADS="1")
    args = [*args, "--out", str(tmp_path / "run"), "--json"]
    r = subprocess.run(
        [sys.executable, "-c", _model_compiles_script(args)], env=env, capture_output=True, text=True, timeout=1800
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert "model compiles in the command: 0 []" in r.stderr, r.stderr[-3000:]
    assert r.stderr.count("background compilation failed") == 0


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_signal_inside_numbas_native_callbacks_is_not_lost(monkeypatch):
    """Numba's code generation calls Python back from C (llvmlite's object-cache hooks, ctypes),
    where the KeyboardInterrupt a signal raises is printed and dropped: a Ctrl-C there was lost
    and a compiling command ran on. Inside ``numba_signals`` (every numba compilation, load and
    save) a SIGINT goes to ``NUMBA_SIGNAL_HANDLERS`` first (the command line's ends the process
    with 130 at once: kernel_cache.stop_now); the handlers are restored afterwards."""
    import ctypes

    from flexrv import cache

    got = []
    monkeypatch.setattr(cache, "NUMBA_SIGNAL_HANDLERS", [got.append])

    def callback():
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10000):  # the Python handler runs between these bytecodes, inside the callback
            pass

    native = ctypes.CFUNCTYPE(None)(callback)
    native()  # the KeyboardInterrupt raised inside the callback is dropped by ctypes
    assert got == []
    before = signal.getsignal(signal.SIGINT)
    with cache.numba_signals():
        native()
    assert got == [signal.SIGINT]
    assert signal.getsignal(signal.SIGINT) is before
