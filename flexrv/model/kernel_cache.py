"""First-run notice of the numba kernels, and their compilation in a background process.

The hot kernels (the fused kernel of the compiled force elements, the ball-bearing rows)
are compiled by numba on their first call and cached on disk (``cache=True``) in
``NUMBA_CACHE_DIR``, which flexrv sets to ``<user cache>/flexrv/numba/<version>``
(:func:`flexrv.cache.numba_cache_dir`; a damaged entry is discarded and compiled
again, :func:`flexrv.cache.guard_numba_cache`). The first run of a fresh install
therefore spends most of its time compiling: :func:`announce_compile` prints one short
line before that happens (and the command line one line at its start,
:func:`flexrv.cli.first_run_notice`). Ctrl-C or SIGTERM during the compilation end the
run at once (:func:`stop_now`).

Background compilation (:class:`BackgroundCompile`): a command that will compile its
kernels (a first run) starts a second process that calls what the command will call, with
the same argument types, on a stand-in of its model whose elastic bodies are rigid (the
kernels' argument types do not depend on the bodies: an absent body is an empty array of
the same dimension), so numba compiles the kernels into the shared cache while the command
builds the FE bodies, on the other core. When the command then reaches a kernel of the
model layer that is not cached yet, it waits for that process
(:data:`flexrv.cache.COMPILE_WAITERS`) and loads the kernel instead of compiling it. The
process dies with the command (killed at exit, by :func:`stop_now`, or by the kernel when
the command is killed), and if it fails, the command compiles the kernels itself (one
notice). The time estimates quoted come from ``benchmarks/bench_first_run.py``
(docs/benchmarks.md).
"""

from __future__ import annotations

import atexit
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: modules whose cached numba dispatchers a run may compile (every dispatcher found in them counts)
KERNEL_MODULES = (
    "flexrv.geometry.cycloid",
    "flexrv.contact.laws",
    "flexrv.analysis.mesh_stiffness",
    "flexrv.model.pins",
    "flexrv.model.gear_stage",
    "flexrv.model.cranks_discs",
    "flexrv.model.loads",
    "flexrv.model.main_bearing_rigid",
    "flexrv.model.kernels",
    "flexrv.model.bearing_kernel",
)
#: prefix of the fused kernels generated from the element registry (:mod:`flexrv.model.core.registry`);
#: their dispatchers are listed as ``fused.<name>``
GENERATED_PREFIX = "flexrv.model.core._generated."
#: the compiled functions a run calls directly, per kind of run or force element (they compile their
#: callees into themselves): the fused element of the kernel groups on Exudyn's integrator or in a static
#: solver (``fused``), the compiled integrator, which also evaluates that element for the run's Python
#: calls (``integrate``: :meth:`flexrv.model.kernels.FusedForces.drive_with`), and the ball-bearing rows'
#: own Exudyn element of the stand-alone bearing model (``rows``; in a reducer model the rows are in the fused kernel).
#: A helper a run may never call (row_kernel, which the tests and the quasi-static path use;
#: copy_records_if_same, which only Exudyn's path calls, a second to compile) stays uncached and must not
#: trigger the notice
RUN_ENTRY_POINTS = {
    "fused": ("fused.fused_kernel", "fused.fused_history"),
    "integrate": ("fused.fused_integrate",),
    "rows": ("bearing_kernel.row_element", "bearing_kernel.row_history"),
}
#: first-compile time [s] of the rigid model's kernels in one process (~40 s CPU for the compiled integrator of
#: rv221, ~30 s for te's fused kernel: benchmarks/bench_compile.py), for the notice
COMPILE_ESTIMATE_S = 45
#: a whole first run [s] on 2 cores (kernels compiled in the background while the FE bodies of a preset
#: are built; benchmarks/bench_first_run.py, docs/benchmarks.md), for the command line's notice
FIRST_RUN_ESTIMATE_S = 45


def uncached_kernels(modules: dict | None = None) -> list[str]:
    """Names of the kernels of the already imported modules (:data:`KERNEL_MODULES` and the
    generated fused kernels) whose on-disk cache index does not exist yet (they will compile
    on first call). Modules not imported are not used by the run and are skipped; without
    numba the list is empty."""
    modules = sys.modules if modules is None else modules
    names = [(m, m.rsplit(".", 1)[-1]) for m in KERNEL_MODULES]
    names += [(m, "fused") for m in sorted(modules) if m.startswith(GENERATED_PREFIX)]
    out = []
    for mod_name, label in names:
        mod = modules.get(mod_name)
        if mod is None:
            continue
        for attr, disp in sorted(vars(mod).items()):
            cache = getattr(disp, "_cache", None)
            index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
            if index is not None and not Path(index).exists():
                out.append(f"{label}.{attr}")
    return out


def cache_dir() -> str:
    """Where numba writes its cache (``NUMBA_CACHE_DIR``, set by flexrv at import)."""
    from flexrv.cache import numba_cache_dir

    return str(numba_cache_dir())


def stop_now(signum: int) -> None:
    """End the process at once with exit code 128 + ``signum`` (130 Ctrl-C, 143 SIGTERM),
    after flushing stdout and stderr: for a signal that arrives before a run has
    integrated its first step (numba compiling its kernels for a minute holds the run
    in that step), when there are no partial results to keep. A background compilation
    (:class:`BackgroundCompile`) is killed first."""
    kill_background()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(128 + int(signum))


def stop_on_signal_while_compiling() -> None:
    """Let a SIGINT or SIGTERM that arrives while numba compiles or loads a kernel end the
    process at once with 130 / 143 (:func:`stop_now`; :func:`flexrv.cache.numba_signals`: numba
    runs Python callbacks from C there, in which the KeyboardInterrupt a signal raises is
    dropped). The command line's policy: a compiling command has nothing to keep."""
    from flexrv.cache import NUMBA_SIGNAL_HANDLERS

    if stop_now not in NUMBA_SIGNAL_HANDLERS:
        NUMBA_SIGNAL_HANDLERS.append(stop_now)


def announce_compile(stream=None, modules: dict | None = None, kinds=None) -> bool:
    """Print one short line, ``flexrv: compiling numba kernels (once, ~45 s or more; ...)``, on
    stderr if a kernel the run calls (:data:`RUN_ENTRY_POINTS` of ``kinds``, default all)
    is not cached yet; returns whether it printed."""
    if any(job.running for job in ACTIVE):  # compiling in the background: the wait announces itself
        return False
    missing = uncached_kernels(modules)
    kinds = RUN_ENTRY_POINTS if kinds is None else kinds
    entries = {name for kind in kinds for name in RUN_ENTRY_POINTS[kind]}
    if not entries.intersection(missing):
        # only helpers the run does not call are uncached: nothing compiles now
        return False
    stream = sys.stderr if stream is None else stream
    print(
        f"flexrv: compiling numba kernels (once, ~{COMPILE_ESTIMATE_S} s or more; cached in {cache_dir()})",
        file=stream,
        flush=True,
    )
    return True


# ------------------------------------------------------------------ background compilation
#: environment variable: ``0`` turns the background compilation off (the command compiles itself)
BACKGROUND_ENV = "FLEXRV_BACKGROUND_COMPILE"
#: the background compilations of this process that have not been waited for or killed
ACTIVE: list["BackgroundCompile"] = []
#: how often a waiting command looks at its background process [s] (signals are handled in between)
POLL_S = 0.2


class BackgroundCompile:
    """A second process running ``job(*args, **kwargs)`` (a module-level function: it is
    pickled by name) to fill numba's cache with the kernels of ``modules`` (module name
    prefixes) that this process will call (module docstring).

    :meth:`start` returns at once; a kernel of ``modules`` that this process then does not
    find in the cache makes it wait for the job (:meth:`wait`, one line on stderr) and load
    the kernel. A job that fails leaves this process to compile (one line naming the
    reason). The process is killed when this one exits (:func:`kill_background`)."""

    def __init__(self, job, args=(), kwargs=None, modules=("flexrv.model.",), what="numba kernels"):
        self.job, self.args, self.kwargs = job, tuple(args), dict(kwargs or {})
        self.modules, self.what = tuple(modules), what
        self.proc: subprocess.Popen | None = None
        self.started = 0.0
        self._log = None
        self.returncode: int | None = None

    def start(self) -> "BackgroundCompile":
        """Start the process (its stdin: the pickled job; its stderr: a temporary file read
        only if it fails) in a session of its own, so a Ctrl-C at the terminal reaches this
        process only, which then ends it."""
        from flexrv.cache import NUMBA_CACHE_ENV

        payload = tempfile.TemporaryFile()
        pickle.dump((self.job, self.args, self.kwargs), payload)
        payload.seek(0)
        self._log = tempfile.TemporaryFile()
        env = dict(os.environ)
        env[NUMBA_CACHE_ENV] = cache_dir()  # the cache this process reads
        root = str(Path(__file__).resolve().parents[2])  # the same flexrv as this process
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "flexrv.model.kernel_cache", str(os.getpid())],
                stdin=payload,
                stdout=subprocess.DEVNULL,
                stderr=self._log,
                env=env,
                start_new_session=True,
            )
        finally:
            payload.close()
        self.started = time.monotonic()
        ACTIVE.append(self)
        return self

    @property
    def running(self) -> bool:
        return self.proc is not None and self.returncode is None and self.proc.poll() is None

    def covers(self, numba_cache) -> bool:
        """Whether the job compiles the kernel of this numba cache (its module is in ``modules``)."""
        module = getattr(getattr(numba_cache, "_py_func", None), "__module__", None) or ""
        return module.startswith(self.modules)

    def wait(self, stream=None) -> bool:
        """Wait for the process (one line on stderr; signals are handled while waiting);
        True if it succeeded, else False after one line with its last error line."""
        stream = sys.stderr if stream is None else stream
        if self.running:
            print(
                f"flexrv: waiting for the {self.what} compiling in a background process "
                f"(started {time.monotonic() - self.started:.0f} s ago; once, cached for later runs)",
                file=stream,
                flush=True,
            )
        while self.proc is not None and self.returncode is None:
            try:
                self.returncode = self.proc.wait(timeout=POLL_S)
            except subprocess.TimeoutExpired:
                continue
        _forget(self)
        if self.returncode == 0:
            return True
        print(
            f"flexrv: the background compilation failed ({self.reason()}); compiling here instead "
            f"(once, ~{COMPILE_ESTIMATE_S} s)",
            file=stream,
            flush=True,
        )
        return False

    def reason(self) -> str:
        """The last line of the process's stderr, or its exit code."""
        text = ""
        if self._log is not None:
            try:
                self._log.seek(0)
                text = self._log.read().decode(errors="replace")
            except (OSError, ValueError):
                pass
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        return lines[-1][:200] if lines else f"exit code {self.returncode}"

    def kill(self) -> None:
        """Kill the process (and its session) if it still runs; reap it."""
        if self.proc is not None and self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError, AttributeError):
                self.proc.kill()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
        if self.proc is not None:
            self.returncode = self.proc.returncode
        _forget(self)


def _forget(job: BackgroundCompile) -> None:
    if job in ACTIVE:
        ACTIVE.remove(job)
    if job._log is not None and job.returncode is not None and job.returncode == 0:
        job._log.close()
        job._log = None


def kill_background() -> None:
    """Kill every background compilation of this process (at exit, on a signal)."""
    for job in list(ACTIVE):
        job.kill()


def _wait_for_background(numba_cache) -> bool:
    """The compile waiter (:data:`flexrv.cache.COMPILE_WAITERS`): wait for the background
    compilations of this kernel not waited for yet (a failed one is announced here, once);
    True if one succeeded (read the cache again)."""
    jobs = [job for job in ACTIVE if job.covers(numba_cache)]
    return any([job.wait() for job in jobs])


def start_background(job, args=(), kwargs=None, entries=(), **options) -> BackgroundCompile | None:
    """Start a :class:`BackgroundCompile` of ``job`` if it can help: numba's cache holds no index
    of the ``entries`` (kernel names such as ``"fused_integrate"``: a first run), this process
    may use two cores, and ``FLEXRV_BACKGROUND_COMPILE`` is not ``0``. Returns it, or None."""
    if os.environ.get(BACKGROUND_ENV, "1").strip() == "0":
        return None
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    if cores < 2:
        return None
    folder = Path(cache_dir())
    try:
        if entries and any(next(folder.rglob(f"*.{name}-*.nbi"), None) for name in entries):
            return None
    except OSError:
        return None
    if _wait_for_background not in _waiters():
        _waiters().append(_wait_for_background)
    return BackgroundCompile(job, args, kwargs, **options).start()


def _waiters() -> list:
    from flexrv.cache import COMPILE_WAITERS

    return COMPILE_WAITERS


atexit.register(kill_background)


# ------------------------------------------------------------------ the background process
def _die_with_parent(parent: int) -> None:
    """End this process when its parent ends: the kernel's parent-death signal (Linux),
    and a thread that watches the parent's pid (elsewhere, or if the parent ended first)."""
    import threading

    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch():
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


def _child_main(argv: list[str]) -> None:
    """Entry of the background process: ``python -m flexrv.model.kernel_cache PARENT_PID``
    with the pickled (job, args, kwargs) on stdin."""
    _die_with_parent(int(argv[0]))
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda signum, frame: os._exit(128 + signum))
    job, args, kwargs = pickle.load(sys.stdin.buffer)
    job(*args, **kwargs)


if __name__ == "__main__":
    _child_main(sys.argv[1:])
