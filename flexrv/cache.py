"""Content-addressed caching and atomic file writes.

Every cached artefact (mesh, reduced body, EHL map) is stored under a key that
hashes *everything it depends on* (parameters, mesh size, library versions), and
every file is written to a temporary name in the same directory and renamed, so a
crash never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Iterator

import math

import numpy as np

#: Root of the mesh / reduced-body / EHL-map cache (``meshes/`` at the repo top
#: level, overridable with the environment variable ``FLEXRV_CACHE``).
def cache_dir() -> Path:
    """Directory of cached meshes and reduced bodies (created on demand)."""
    root = os.environ.get("FLEXRV_CACHE")
    if root:
        path = Path(root)
    else:
        path = Path(__file__).resolve().parent.parent / "meshes"
    path.mkdir(parents=True, exist_ok=True)
    return path


def _canonical(obj: Any) -> Any:
    """Convert ``obj`` to a JSON-serialisable canonical form for hashing."""
    if isinstance(obj, dict):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {"__ndarray__": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest(),
                "shape": list(obj.shape), "dtype": str(obj.dtype)}
    if isinstance(obj, (np.floating, float)):
        return repr(float(obj))
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if hasattr(obj, "model_dump"):
        return _canonical(obj.model_dump())
    return obj


def library_versions(*names: str) -> dict[str, str]:
    """Installed versions of the named distributions (part of every cache key)."""
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for name in names:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "absent"
    return out


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


def remove_stale_temp_files(directory: str | os.PathLike) -> list[Path]:
    """Delete the temporary files of atomic writes that were killed before their
    rename (``.<name>.<pid>.<random>.tmp<suffix>``) in ``directory``: those of
    processes that no longer exist. Returns the removed paths."""
    removed = []
    d = Path(directory)
    if not d.is_dir():
        return removed
    for path in d.glob(".*.tmp*"):
        match = _TMP_RE.match(path.name)
        if match is None:
            continue
        pid = int(match["pid"])
        if pid == os.getpid() or _pid_alive(pid):
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
    >>> with atomic_path("out.nc") as tmp:          # doctest: +SKIP
    ...     dataset.to_netcdf(tmp)
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temp_files(target.parent)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp" + target.suffix,
                               dir=target.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~_umask())
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


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
