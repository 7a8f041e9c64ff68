"""Content-addressed caching and atomic file writes.

Every cached artefact (mesh, reduced body, EHL map) is stored under a key that
hashes *everything it depends on* (parameters, mesh size, library versions), and
every file is written to a temporary name in the same directory and renamed, so a
crash never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import hmac
import json
import math
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Any, Iterator

import numpy as np

#: environment variable overriding the cache location (``FLEXRV_CACHE`` is the
#: older name, still honoured)
CACHE_ENV = "FLEXRV_CACHE_DIR"


def cache_dir() -> Path:
    """Directory of cached meshes, reduced bodies and EHL maps (created on demand):
    ``$FLEXRV_CACHE_DIR`` (or ``$FLEXRV_CACHE``) if set, else the user cache
    directory of the platform (``~/.cache/flexrv`` on Linux, via platformdirs)."""
    root = os.environ.get(CACHE_ENV) or os.environ.get("FLEXRV_CACHE")
    if root:
        path = Path(root)
    else:
        try:
            from platformdirs import user_cache_dir

            path = Path(user_cache_dir("flexrv", appauthor=False))
        except ImportError:  # platformdirs missing: the XDG default
            path = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "flexrv"
    path.mkdir(parents=True, exist_ok=True)
    return path


def _canonical(obj: Any) -> Any:
    """Convert ``obj`` to a JSON-serialisable canonical form for hashing."""
    if isinstance(obj, dict):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {
            "__ndarray__": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest(),
            "shape": list(obj.shape),
            "dtype": str(obj.dtype),
        }
    if isinstance(obj, (np.floating, float)):
        return repr(float(obj))
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if hasattr(obj, "model_dump"):
        return _canonical(obj.model_dump())
    return obj


def flexrv_version() -> str:
    """flexrv's own version (part of every cache key and sweep case id)."""
    from flexrv._version import __version__

    return __version__


def library_versions(*names: str) -> dict[str, str]:
    """Installed versions of the named distributions, and always flexrv's own
    version (part of every cache key: a new flexrv never serves an old entry)."""
    return {"flexrv": flexrv_version(), **dict(_distribution_versions(tuple(n for n in names if n != "flexrv")))}


@functools.lru_cache(maxsize=None)
def _distribution_versions(names: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    """(name, version) of installed distributions, read once per process (package
    metadata does not change under a running process; reading it costs milliseconds)."""
    from importlib.metadata import PackageNotFoundError, version

    out = []
    for name in names:
        try:
            out.append((name, version(name)))
        except PackageNotFoundError:
            out.append((name, "absent"))
    return tuple(out)


def content_hash(*parts: Any, length: int = 16) -> str:
    """Stable hex hash of arbitrary nested data (dicts, lists, arrays, models)."""
    payload = json.dumps(_canonical(list(parts)), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(payload.encode()).hexdigest()[:length]


_TMP_RE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[A-Za-z0-9_]+\.tmp")


def _umask() -> int:
    """The process umask (read by setting and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, another user's
        return True
    return True


def temp_file_writer(name: str) -> int | None:
    """The process id of the atomic write (:func:`atomic_path`) whose temporary file is called
    ``name`` (``.<target>.<pid>.<random>.tmp<suffix>``), or None if ``name`` is not one.

    >>> temp_file_writer(".case_3.json.4242.k2x9_q.tmp.json"), temp_file_writer("case_3.json")
    (4242, None)
    """
    match = _TMP_RE.match(name)
    return None if match is None else int(match["pid"])


def finished_files(directory: str | os.PathLike, pattern: str = "*.json") -> list[Path]:
    """The files of ``directory`` matching ``pattern`` whose write has finished, sorted: not an
    atomic write's temporary file (:func:`temp_file_writer`), which a glob also matches
    (``.<name>.<pid>.<random>.tmp.json`` ends in ``.json``); [] if ``directory`` does not exist.
    What counts as a stored case of a study, or a stored file of a run that is being killed."""
    d = Path(directory)
    if not d.is_dir():
        return []
    return sorted(p for p in d.glob(pattern) if temp_file_writer(p.name) is None)


def remove_stale_temp_files(directory: str | os.PathLike) -> list[Path]:
    """Delete the temporary files of atomic writes that were killed before their
    rename (``.<name>.<pid>.<random>.tmp<suffix>``) in ``directory``: those of
    processes that no longer exist. Returns the removed paths."""
    removed = []
    d = Path(directory)
    if not d.is_dir():
        return removed
    for path in d.glob(".*.tmp*"):
        pid = temp_file_writer(path.name)
        if pid is None or pid == os.getpid() or _pid_alive(pid):
            continue
        with contextlib.suppress(OSError):
            path.unlink()
            removed.append(path)
    return removed


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``target``; rename it onto ``target`` on
    success, delete it on failure.

    The file gets the mode of an ordinary new file (0666 minus the umask, not
    the 0600 of a temporary file). The temporary name carries the writer's pid,
    so the leftovers of a writer that was killed mid-save are deleted by the next
    save into the same directory (:func:`remove_stale_temp_files`).

    Examples
    --------
    >>> target = Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("complete")
    >>> target.read_text(), tmp.exists()
    ('complete', False)
    """
    target = Path(target)
    with _naming(target):
        target.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temp_files(target.parent)
        fd, tmp = tempfile.mkstemp(
            prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp" + target.suffix, dir=target.parent
        )
        os.close(fd)
    tmp_path = Path(tmp)
    try:
        with _naming(target):
            yield tmp_path
            os.chmod(tmp_path, 0o666 & ~_umask())
            os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def _naming(target: Path) -> Iterator[None]:
    """Re-raise an OSError that names no file (a full disk, a read-only file system seen
    by a library writing through a temporary name) as one naming ``target``. HDF5's
    errors (netCDF files) carry no errno: their reason is read from the message."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None and Path(exc.filename) == target:
            raise
        errno_ = exc.errno
        if errno_ is None:
            import errno as errnos

            text = str(exc).lower()
            errno_ = next(
                (
                    code
                    for code, word in (
                        (errnos.ENOSPC, "no space"),
                        (errnos.EROFS, "read-only"),
                        (errnos.EACCES, "permission"),
                    )
                    if word in text
                ),
                errnos.EIO,
            )
        reason = os.strerror(errno_) if errno_ else (exc.strerror or str(exc))
        raise OSError(errno_, f"cannot write {target.name}: {reason}", str(target)) from exc


def atomic_write_text(target: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``target`` atomically; return the final path."""
    with atomic_path(target) as tmp:
        tmp.write_text(text)
    return Path(target)


def atomic_write_bytes(target: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``target`` atomically; return the final path."""
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)
    return Path(target)


def to_jsonable(obj: Any) -> Any:
    """Recursively convert numpy scalars/arrays and dataclasses to JSON types.

    Non-finite floats become ``None`` so the output is strict JSON.
    """
    if hasattr(obj, "model_dump"):
        return to_jsonable(obj.model_dump())
    if hasattr(obj, "__dataclass_fields__"):
        return {k: to_jsonable(getattr(obj, k)) for k in obj.__dataclass_fields__}
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


# ------------------------------------------------------------------ verified cache entries
#: suffix of the stamp written next to every cached file: its key, size and sha256
STAMP_SUFFIX = ".stamp.json"


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _stamp_path(path: Path) -> Path:
    return path.with_name(path.name + STAMP_SUFFIX)


#: name of the cache's signing key (random, per cache folder): stamps carry an HMAC made with it
SIGNING_KEY_NAME = "signing.key"
_KEY_BYTES = 32


def _signing_key() -> bytes:
    """The cache folder's secret signing key, created on first use (O_EXCL, mode 0600).
    A damaged key is replaced: every entry signed with the old one is then rebuilt."""
    path = cache_dir() / SIGNING_KEY_NAME
    for _ in range(3):
        try:
            data = path.read_bytes()
            if len(data) == _KEY_BYTES:
                return data
            path.unlink(missing_ok=True)  # damaged: a new key, the entries it signed are rebuilt
        except FileNotFoundError:
            pass
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except FileExistsError:
            continue  # another process is writing it: read it on the next pass
        try:
            os.write(fd, os.urandom(_KEY_BYTES))
        finally:
            os.close(fd)
    data = path.read_bytes()
    if len(data) != _KEY_BYTES:
        raise OSError(f"cache signing key {path} could not be created")
    return data


def _signature(key: str, size: int, sha256: str, version: str) -> str:
    """HMAC-SHA256 of an entry's key, size, content hash and flexrv version under the
    cache's signing key: a file whose stamp was rewritten to match altered content
    (or copied from another cache) does not carry it."""
    message = "\0".join((key, str(size), sha256, version)).encode()
    return hmac.new(_signing_key(), message, hashlib.sha256).hexdigest()


def stamp_entry(paths, key: str) -> None:
    """Record, next to each file of a freshly written cache entry, the entry's key,
    the file's size and sha256, and their signature (read back by :func:`entry_problem`)."""
    for path in map(Path, paths):
        size, sha, version = path.stat().st_size, _sha256(path), flexrv_version()
        stamp = {
            "key": key,
            "size": size,
            "sha256": sha,
            "flexrv": version,
            "signature": _signature(key, size, sha, version),
        }
        atomic_write_text(_stamp_path(path), json.dumps(stamp))


def entry_problem(paths, key: str) -> str | None:
    """None if every file of a cache entry exists and matches its stamp (same key,
    size and sha256, signed with this cache's key); otherwise why not ("missing" if
    no file exists at all)."""
    paths = [Path(p) for p in paths]
    if not any(p.exists() for p in paths):
        return "missing"
    for path in paths:
        if not path.exists():
            return f"{path.name} is missing"
        stamp_file = _stamp_path(path)
        try:
            stamp = json.loads(stamp_file.read_text())
        except (OSError, ValueError):
            return f"{path.name} has no valid stamp (written by an older flexrv or interrupted)"
        if not isinstance(stamp, dict) or stamp.get("key") != key:
            return f"{path.name} belongs to another key ({stamp.get('key') if isinstance(stamp, dict) else None!r})"
        size = path.stat().st_size
        if size != stamp.get("size"):
            return f"{path.name} is truncated or altered ({size} bytes, {stamp.get('size')} expected)"
        sha = _sha256(path)
        if sha != stamp.get("sha256"):
            return f"{path.name} content does not match its hash"
        expected = _signature(key, size, sha, str(stamp.get("flexrv")))
        if not hmac.compare_digest(str(stamp.get("signature", "")), expected):
            return f"{path.name} was not written by this cache (its stamp's signature does not match)"
    return None


def cache_notice(path, reason: str) -> None:
    """The one-line notice of a cache entry that is rebuilt."""
    import sys

    print(f"flexrv: cache entry {Path(path).name}: {reason}; rebuilding it", file=sys.stderr)


@contextlib.contextmanager
def build_lock(path, enabled: bool = True) -> Iterator[None]:
    """Exclusive lock of one cache entry while it is built (``<path>.lock``, fcntl),
    so concurrent builders of the same entry do the work once: the second waits,
    then finds the entry valid. No-op where fcntl is unavailable or ``enabled`` is False."""
    if not enabled:
        yield
        return
    try:
        import fcntl
    except ImportError:  # not POSIX
        yield
        return
    lock_path = Path(path).with_name(Path(path).name + ".lock")
    lock_path.parent.mkdir(parents=True, exist_ok=True)
    with open(lock_path, "a+") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


def cached_entry(paths, key: str, load, build, enabled: bool = True):
    """Load a verified cache entry, or build it once under its lock.

    ``paths``: the entry's files; ``load()`` reads them (called only when every
    file matches its stamp); ``build()`` computes the value and writes the files
    (atomically) and returns the value; the files are then stamped. A corrupt,
    truncated, foreign or unreadable entry is rebuilt with a one-line notice on
    stderr. Returns (value, cached: bool)."""
    paths = [Path(p) for p in paths]
    if not enabled:  # no reuse; what is written is still stamped for later runs
        value = build()
        if all(p.exists() for p in paths):
            stamp_entry(paths, key)
        return value, False

    def try_load():
        problem = entry_problem(paths, key)
        if problem is None:
            try:
                return load(), None
            except Exception as exc:  # unreadable although stamped (foreign writer): rebuild
                problem = f"unreadable ({type(exc).__name__}: {exc})"
        return None, problem

    value, problem = try_load()
    if problem is None:
        return value, True
    with build_lock(paths[0]):
        value, problem2 = try_load()  # built by another process while we waited
        if problem2 is None:
            return value, True
        if problem != "missing":
            cache_notice(paths[0], problem)
        elif _entry_kind(paths[0])[1]:  # a known kind of slow build (an FE body, a mesh)
            build_notice(paths[0])
        t0 = time.perf_counter()
        value = build()
        stamp_entry(paths, key)
        if _entry_kind(paths[0])[1]:
            record_build_time(paths[0], time.perf_counter() - t0)
    return value, False


#: what a cache entry's build does, by the suffix of its first file (the notice of a first build)
_BUILD_KINDS = {
    ".compliance.json": "condensing the {part} FE body (stiffness matrix and static condensation)",
    ".patches.json": "condensing the {part} FE body at its pin contacts (one load case per contact patch)",
    ".sweep.json": "condensing the {part} FE body for a sweep of load positions",
    ".cms.npz": "reducing the {part} FE body to its modes (Craig-Bampton)",
    ".msh": "meshing the {part} (gmsh, second-order tetrahedra)",
}
#: typical first-build time [s] of an entry, by kind, on one core of a quiet 2-core machine (benchmarks/
#: bench_bodies.py: a preset's carrier 12-13 s, disc 11-26 s with their meshes); the notice quotes the
#: time this cache's own earlier builds of the kind took when it has them
TYPICAL_BUILD_S = {".compliance.json": 5.0, ".patches.json": 6.0, ".sweep.json": 6.0, ".cms.npz": 15.0, ".msh": 4.0}
#: file in the cache folder with the measured build time of each kind of entry
BUILD_TIMES = "build_times.json"


def _entry_kind(path) -> tuple[str, str]:
    """(part, kind) of a cache entry's file name ``<part>-<hash><kind>``: ``carrier-3f..e1.msh``
    -> (``"carrier"``, ``".msh"``); the kind is "" for an unknown suffix."""
    name = Path(path).name
    part, _, rest = name.partition("-")
    for kind in _BUILD_KINDS:
        if rest.endswith(kind):
            return part.replace("_", " "), kind
    return part.replace("_", " "), ""


def _build_times() -> dict:
    try:
        data = json.loads((cache_dir() / BUILD_TIMES).read_text())
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def build_notice(path, stream=None) -> str:
    """Print (on stderr) and return the one line announcing the first build of a cache entry:
    what it does and how long it usually takes (this cache's last build of that kind of
    entry, else :data:`TYPICAL_BUILD_S`), e.g. ``flexrv: meshing the carrier (gmsh, ...);
    once, usually ~10 s; cached for later runs``."""
    import sys

    part, kind = _entry_kind(path)
    what = _BUILD_KINDS.get(kind, "building the {part}").format(part=part)
    seconds = _build_times().get(f"{part}{kind}", TYPICAL_BUILD_S.get(kind))
    usual = f", usually ~{seconds:.0f} s" if seconds else ""
    line = f"flexrv: {what}; once{usual}; cached for later runs"
    print(line, file=sys.stderr if stream is None else stream, flush=True)
    return line


def record_build_time(path, seconds: float) -> None:
    """Remember how long the build of this kind of entry took (the next notice quotes it);
    a failure to write is ignored (the figure is only a hint)."""
    part, kind = _entry_kind(path)
    times = _build_times()
    times[f"{part}{kind}"] = round(float(seconds), 1)
    try:
        atomic_write_text(cache_dir() / BUILD_TIMES, json.dumps(times, indent=1, sort_keys=True))
    except OSError:
        pass


def cached_dataclass(path, key: str, cls, compute, enabled: bool = True):
    """A dataclass of JSON-able fields (a condensed FE result, say) cached as one JSON
    file ``path`` under ``key`` (:func:`cached_entry`: verified on read, rebuilt when
    corrupt or foreign, built once under a lock). ``compute()`` returns the instance;
    ``enabled=False`` computes without reading or writing the cache."""
    from dataclasses import asdict

    path = Path(path)

    def build():
        out = compute()
        if enabled:
            atomic_write_text(path, json.dumps(asdict(out)))
        return out

    value, _ = cached_entry([path], key, lambda: cls(**json.loads(path.read_text())), build, enabled=enabled)
    return value


# ------------------------------------------------------------------ numba's compiled kernels
#: environment variable of numba's on-disk cache folder (read by numba when it is imported)
NUMBA_CACHE_ENV = "NUMBA_CACHE_DIR"


def numba_cache_dir() -> Path:
    """Folder of numba's compiled kernels: ``$NUMBA_CACHE_DIR`` if set, else
    ``<cache_dir()>/numba/<flexrv version>`` beside the meshes and reduced bodies (a new
    flexrv starts an empty folder; numba's index also checks each source file's stamp)."""
    env = os.environ.get(NUMBA_CACHE_ENV)
    if env:
        return Path(env)
    root = os.environ.get(CACHE_ENV) or os.environ.get("FLEXRV_CACHE")
    if not root:
        root = str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "flexrv")
        try:
            from platformdirs import user_cache_dir

            root = user_cache_dir("flexrv", appauthor=False)
        except ImportError:
            pass
    return Path(root) / "numba" / flexrv_version()


def configure_numba_cache() -> None:
    """Point numba's cache at :func:`numba_cache_dir` (before numba is imported) and guard
    its loading (:func:`guard_numba_cache`, now if numba is imported, else when it is)."""
    os.environ.setdefault(NUMBA_CACHE_ENV, str(numba_cache_dir()))
    import sys

    if "numba.core.caching" in sys.modules:
        guard_numba_cache()
    elif not any(isinstance(f, _NumbaCachingHook) for f in sys.meta_path):
        sys.meta_path.insert(0, _NumbaCachingHook())


class _NumbaCachingHook:
    """Import hook: runs :func:`guard_numba_cache` right after ``numba.core.caching`` is
    imported (by the first kernel module), so flexrv never imports numba itself."""

    def find_spec(self, name, path=None, target=None):
        if name != "numba.core.caching":
            return None
        from importlib.machinery import PathFinder

        spec = PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        exec_module = loader.exec_module

        def exec_and_guard(module):
            exec_module(module)
            guard_numba_cache(module)

        loader.exec_module = exec_and_guard
        return spec


#: damaged numba cache entries discarded by this process (one warning for all of them)
_DISCARDED: list[str] = []

#: callables ``waiter(cache) -> bool`` asked when a kernel is not in numba's cache, before numba compiles
#: it: a waiter that returns True has waited for another process that compiles the kernel into the same
#: cache (:mod:`flexrv.model.kernel_cache`), and the cache is read again
COMPILE_WAITERS: list = []
#: callables ``handler(signum)`` called for a SIGINT or SIGTERM that arrives while numba compiles or loads a
#: kernel in the main thread (:func:`numba_signals`); the command line registers one that ends the process at
#: once (:func:`flexrv.model.kernel_cache.stop_now`). A handler that returns leaves the signal to the handler
#: installed before
NUMBA_SIGNAL_HANDLERS: list = []
#: name of the lock file in numba's cache folder (:func:`numba_index_lock`)
NUMBA_LOCK_NAME = "index.lock"
_SIGNAL_DEPTH = [0]


@contextlib.contextmanager
def numba_signals() -> Iterator[None]:
    """While numba compiles or loads a kernel: SIGINT and SIGTERM go to the
    :data:`NUMBA_SIGNAL_HANDLERS` first. Numba's code generation calls back into Python
    from C (llvmlite's object-cache hooks, through ctypes), where an exception a signal
    handler raises (KeyboardInterrupt) is printed and dropped: the signal would be lost
    and the command would run on. Reentrant; only in the main thread (elsewhere, and
    without handlers, nothing changes)."""
    import signal
    import threading

    if _SIGNAL_DEPTH[0] or not NUMBA_SIGNAL_HANDLERS or threading.current_thread() is not threading.main_thread():
        _SIGNAL_DEPTH[0] += 1
        try:
            yield
        finally:
            _SIGNAL_DEPTH[0] -= 1
        return
    old = {}

    def on_signal(signum, frame):
        for handler in list(NUMBA_SIGNAL_HANDLERS):
            handler(signum)
        previous = old.get(signum)
        if callable(previous):
            previous(signum, frame)

    _SIGNAL_DEPTH[0] = 1
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            old[sig] = signal.signal(sig, on_signal)
        yield
    finally:
        _SIGNAL_DEPTH[0] = 0
        for sig, handler in old.items():
            signal.signal(sig, handler)


def _compile_signals_listener():
    """A listener of numba's ``numba:compile`` events: :func:`numba_signals` around each
    compilation (the compilations of its callees nested inside)."""
    from numba.core import event

    class CompileSignals(event.Listener):
        def __init__(self):
            self._scopes = []

        def on_start(self, event) -> None:
            scope = numba_signals()
            scope.__enter__()
            self._scopes.append(scope)

        def on_end(self, event) -> None:
            if self._scopes:
                self._scopes.pop().__exit__(None, None, None)

    return CompileSignals()


_LOCK_DEPTH = [0]


@contextlib.contextmanager
def numba_index_lock() -> Iterator[None]:
    """Exclusive lock (fcntl, ``<numba cache>/index.lock``) around every read and write of numba's
    cache by flexrv's processes. Numba writes an entry as its index (signature -> data file
    number) and then the data file, choosing the number from the index it read: two processes
    compiling different signatures of one kernel at once could both write data file 1, leaving an
    index that names one signature's machine code for the other's. Under the lock each save reads
    the index that the last one wrote, and a read never sees an index whose data file is not
    written yet. Reentrant within a process; a no-op without fcntl or a writable cache folder."""
    if _LOCK_DEPTH[0]:
        _LOCK_DEPTH[0] += 1
        try:
            yield
        finally:
            _LOCK_DEPTH[0] -= 1
        return
    try:
        import fcntl

        folder = numba_cache_dir()
        folder.mkdir(parents=True, exist_ok=True)
        handle = open(folder / NUMBA_LOCK_NAME, "a+")
    except (ImportError, OSError):
        handle = None
    _LOCK_DEPTH[0] = 1
    try:
        if handle is not None:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        yield
    finally:
        _LOCK_DEPTH[0] = 0
        if handle is not None:
            handle.close()  # (releases the lock)


def guard_numba_cache(caching=None) -> None:
    """Make a damaged numba cache entry heal itself: an entry whose index (``.nbi``) or
    data (``.nbc``) cannot be read back (truncated, corrupted: any exception while
    numba loads or rebuilds it) is deleted and the kernel compiled again, with one
    warning per process. Numba itself only tolerates a missing file. Every read and
    write holds :func:`numba_index_lock` (processes sharing the cache), a kernel
    not found asks the :data:`COMPILE_WAITERS` before numba compiles it, and a signal
    during a compilation, load or save goes to the :data:`NUMBA_SIGNAL_HANDLERS`
    (:func:`numba_signals`)."""
    if caching is None:
        import numba.core.caching as caching
    cls = caching.Cache
    if getattr(cls.load_overload, "_flexrv_guard", False):
        return
    load, save = cls.load_overload, cls.save_overload
    from numba.core import event

    event.register("numba:compile", _compile_signals_listener())

    def guarded_load(self, sig, target_context):
        with numba_index_lock(), numba_signals():
            try:
                return load(self, sig, target_context)
            except Exception as exc:
                _discard_numba_entry(self, exc)
                return None

    def load_overload(self, sig, target_context):
        value = guarded_load(self, sig, target_context)
        if value is None and any(waiter(self) for waiter in list(COMPILE_WAITERS)):
            value = guarded_load(self, sig, target_context)  # compiled meanwhile by another process
        return value

    def save_overload(self, sig, data):
        with numba_index_lock(), numba_signals():
            try:
                return save(self, sig, data)
            except Exception as exc:  # e.g. an unreadable index: discard it, save again
                _discard_numba_entry(self, exc)
                with contextlib.suppress(Exception):
                    save(self, sig, data)

    load_overload._flexrv_guard = True
    cls.load_overload, cls.save_overload = load_overload, save_overload


def _discard_numba_entry(cache, exc: Exception) -> None:
    """Delete the index and data files of one numba cache entry; warn once per process."""
    import sys

    cache_file = getattr(cache, "_cache_file", None)
    index = Path(getattr(cache_file, "_index_path", "") or "")
    if index.name:
        pattern = getattr(cache_file, "_data_name_pattern", "").replace("{number:d}", "*")
        for path in [index, *(index.parent.glob(pattern) if pattern else [])]:
            with contextlib.suppress(OSError):
                path.unlink()
    _DISCARDED.append(str(index))
    if len(_DISCARDED) == 1:
        print(
            f"flexrv: warning: discarded a damaged numba cache entry ({index.name}: {type(exc).__name__}); "
            "its kernel is compiled again",
            file=sys.stderr,
            flush=True,
        )
