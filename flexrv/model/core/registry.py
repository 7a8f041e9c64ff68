"""The registry of compiled force elements and the fused kernel generated from it.

A compiled force element is a :class:`~flexrv.model.base.KernelGroup` subclass with a
``kind``, a ``kernel`` (a numba function ``kernel(q, v, f, jq, jv, jac, pack)`` that adds
the element's generalized forces into f and, if ``jac``, its Jacobians into jq, jv over
the coordinates ``pack.idx``), a typed ``pack`` (:mod:`flexrv.model.core.params`), its
declared outputs (``outputs``), friction outputs (``friction_outputs``) and summary rows
(``summary_rows``) and optionally a compiled per-step check (``step_check``, a static numba
function ``step_check(pack) -> int``, nonzero: the state is unphysical, the group's ``check``
then names why; the compiled integrator runs it after every accepted step). ONE line registers
it: ``register(MyElement)``. The order of
registration is the order of the calls in the fused kernel (the order in which the
elements' forces are summed).

The fused kernel of a model's elements (:func:`fused_functions`) is generated source:
a module with ``fused_kernel(q, v, f, jq, jv, jac, p0, p1, ...)`` calling each present
element's kernel once by name (static solvers, Exudyn's integrator), ``fused_history``
looping it over a time history (the outputs of a run on Exudyn's integrator) and
``fused_integrate``, the compiled generalized-alpha integrator
(:mod:`flexrv.model.numerics.gen_alpha`) with the elements' kernels called at one site,
which also evaluates the elements at given states for a run on it (the outputs' history
pass, the initial accelerations: :meth:`flexrv.model.kernels.FusedForces.drive_with`), so
that each kind of run compiles its own entry points only: numba generates the machine
code of every kernel an entry point calls again for that entry point (each compiled
function is linked with copies of its callees), so each entry point costs the whole
kernels' code generation once more (rv221's rigid model: ~4-5 s CPU each). The module is
written to ``flexrv/model/core/_generated/`` and imported, so numba compiles and caches
it like any other function (``cache=True``: the cache index sits beside the file).

Why generated source and not ``numba.literal_unroll`` over a tuple of (kernel, pack):
numba lowers a compiled function passed as a VALUE (an element of a tuple, an
argument) as the address of a Python object in this process and then refuses to cache
the caller ("Cannot cache compiled function ... as it uses dynamic globals", measured
on the crank supports' kernel when its Newton took the residual function as an
argument); an uncached fused kernel recompiles in every process (tens of seconds). A
generated module calls every kernel as a global (a direct call, cacheable), passes only
the present elements (no empty packs to unbox), and has ONE call site per kernel (several
call sites of the large kernels made LLVM's code generation take minutes).

Staleness: numba keys a cached function on its own file only. The generated file's
name and text carry a hash of the sources its kernels can call (the elements' kernel
modules, flexrv/model/numerics, flexrv/model/core/params.py, flexrv/contact,
flexrv/geometry, flexrv/ehl), so an edit of any of them gives a new file that compiles
afresh instead of reusing old machine code. Compile time of a fresh fused kernel: see ``benchmarks/bench_rigid.py``
(measured in the module docstring of :mod:`flexrv.model.kernels`).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import sys
from dataclasses import dataclass
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parents[2]
#: where the generated fused kernels are written (beside their numba cache)
GENERATED = Path(__file__).resolve().parent / "_generated"
#: the sources a kernel can call into besides its own module (hashed into the generated file's name):
#: the model's shared numerics and parameter types, the contact laws, geometry and EHL kernels
_CALLEE_SOURCES = ("model/numerics", "model/core/params.py", "contact", "geometry", "ehl")


@dataclass(frozen=True)
class ElementSpec:
    """A registered compiled force element: its kind, group class and kernel."""

    kind: str
    group: type
    kernel: object


#: kind -> spec, in registration (= call) order
ELEMENTS: dict[str, ElementSpec] = {}


def register(group: type) -> type:
    """Register a compiled force element (a KernelGroup subclass with ``kind`` and a
    static ``kernel``); usable as a class decorator. Re-registering a kind replaces it
    in place (module reloads); two classes of one kind are refused."""
    kind = getattr(group, "kind", "")
    kernel = inspect.getattr_static(group, "kernel", None)
    kernel = getattr(kernel, "__func__", kernel)
    if not kind or kernel is None or not hasattr(kernel, "py_func"):
        raise TypeError(f"{group.__name__}: a registered element needs a kind and a compiled static kernel")
    old = ELEMENTS.get(kind)
    if old is not None and old.group.__qualname__ != group.__qualname__:
        raise ValueError(f"element kind {kind!r} is registered twice ({old.group.__name__}, {group.__name__})")
    ELEMENTS[kind] = ElementSpec(kind, group, kernel)
    return group


def spec_of(group_obj) -> ElementSpec | None:
    """The registered spec of a group object (None: not a registered element)."""
    spec = ELEMENTS.get(getattr(group_obj, "kind", ""))
    return spec if spec is not None and isinstance(group_obj, spec.group) else None


def dense_blocks(model) -> list[tuple[int, int]]:
    """The dense diagonal blocks (start, size) of the Newton matrix of ``model`` that the
    elements declare (``dense_blocks()``: groups of member names, contiguous in the model's
    order, e.g. a bearing row's balls coupled through its condensed rings), each coupled
    to the rest through other members only: the block elimination of the compiled
    integrator (:mod:`flexrv.model.numerics.block_lu`). Empty: one dense LU."""
    out = []
    for g in model.groups:
        declared = getattr(g, "dense_blocks", None)
        if declared is None:
            continue
        for names in declared():
            members = [model.members[m] for m in names]
            start = members[0].offset
            if any(m.offset != start + sum(x.n for x in members[:i]) for i, m in enumerate(members)):
                raise ValueError(f"{g.name}: the members {names} of a dense block are not contiguous")
            out.append((start, sum(m.n for m in members)))
    return out


_HASHES: dict[tuple, str] = {}


def _source_hash(specs) -> str:
    """Hash of the sources the kernels of ``specs`` can call (read once per process)."""
    key = tuple((s.kind, id(s.kernel)) for s in specs)
    if key not in _HASHES:
        _HASHES[key] = _hash_files(specs)
    return _HASHES[key]


def _hash_files(specs) -> str:
    h = hashlib.sha256()
    files = set()
    for name in _CALLEE_SOURCES:
        path = _PACKAGE / name
        files |= set(path.rglob("*.py")) if path.is_dir() else {path}
    files |= {Path(inspect.getsourcefile(s.kernel.py_func)).resolve() for s in specs}
    for p in sorted(files):
        h.update(str(p).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


#: modes of the generated ``fused_integrate``: integrate time steps, or evaluate the elements at given
#: states (rows of ``qs``, ``vs``) without or with their Jacobians (:func:`_integrate_source`)
INTEGRATE, ROWS, ROWS_JAC = 0, 1, 2


def _copy_lines(indent: int, dst: str, src: str, n: str) -> list[str]:
    """Lines copying ``src[c]`` into ``dst[c]`` for c < ``n``: a loop, not a slice assignment, whose
    shape check compiles numba's string formatting of its error message into every caller."""
    pad = " " * indent
    return [f"{pad}for c in range({n}):", f"{pad}    {dst} = {src}"]


def _fused_source(specs, callee_hash: str) -> str:
    """Text of the generated module for the elements ``specs`` (in call order)."""
    n = len(specs)
    packs = ", ".join(f"p{i}" for i in range(n))
    timed = [(i, s.group.time_field) for i, s in enumerate(specs) if s.group.time_field]
    lines = [
        '"""Generated by flexrv.model.core.registry (do not edit): the fused kernel of the elements',
        f'{", ".join(s.kind for s in specs)}; callee sources {callee_hash}."""',
        "",
        "from numba import njit",
        "",
        "from flexrv.model.numerics.gen_alpha import CONVERGED, EVALUATE, FAILED, I_JAC, JAC_FULL, after_eval, "
        "begin_step, finish_step, zero_outer",
    ]
    for i, s in enumerate(specs):
        lines.append(f"from {s.kernel.py_func.__module__} import {s.kernel.py_func.__name__} as k{i}")
    checks = [(i, _step_check(s)) for i, s in enumerate(specs)]
    checks = [(i, c) for i, c in checks if c is not None]
    for i, c in checks:
        lines.append(f"from {c.py_func.__module__} import {c.py_func.__name__} as c{i}")
    lines += ["", "", "@njit(cache=True)", f"def fused_kernel(q, v, f, jq, jv, jac, {packs}):"]
    lines += _evaluate_lines(4, n, "q", "v", "jac")
    tin = "".join(f"tin{i}, " for i, _ in timed)
    lines += [
        "",
        "",
        "@njit(cache=True)",
        f"def fused_history(qs, vs, {tin}f, jq, jv, {packs}, src, dst):",
        "    no_jac = qs.shape[0] < 0  # False, typed bool: the literal False would compile fused_kernel again",
        "    for i in range(qs.shape[0]):",
    ]
    for i, field in timed:
        lines += _copy_lines(8, f"p{i}.{field}[c]", f"tin{i}[i, c]", f"tin{i}.shape[1]")
    lines += [
        f"        fused_kernel(qs[i], vs[i], f, jq, jv, no_jac, {packs})",
        "        for r in range(len(src)):",
        "            s, d = src[r], dst[r]",
    ]
    lines += _copy_lines(12, "d[i, c]", "s[c]", "s.shape[0]")
    costly = [i for i, s in enumerate(specs) if getattr(s.group, "costly_jacobian", False)]
    lines += _integrate_source(n, timed, packs, tin, [i for i, _ in checks], costly)
    return "\n".join(lines)


def _step_check(spec):
    """The element's compiled per-step check (module docstring), or None."""
    check = inspect.getattr_static(spec.group, "step_check", None)
    check = getattr(check, "__func__", check)
    if check is not None and not hasattr(check, "py_func"):
        raise TypeError(f"{spec.group.__name__}.step_check must be a compiled (numba) static function")
    return check


def _evaluate_lines(indent: int, n: int, q: str, v: str, jac: str, costly=()) -> list[str]:
    """Lines of one evaluation of the elements at (``q``, ``v``): f (and, if ``jac``, the
    Jacobians) zeroed, then every element's kernel once, in registration order; the elements
    ``costly`` add their Jacobians (if ``jck``) into ``jqc``, ``jvc`` (set by the caller's lines:
    with ``kept``, the state's kept arrays, and the others' Jacobians live outside the blocks only)."""
    pad = " " * indent
    lines = [f"{pad}f[:] = 0.0", f"{pad}if {jac}:", f"{pad}    jq[:, :] = 0.0", f"{pad}    jv[:, :] = 0.0"]
    if costly:
        lines[1:] = [
            f"{pad}if {jac} and kept:",
            f"{pad}    zero_outer(st, jq, jv)",
            f"{pad}elif {jac}:",
            f"{pad}    jq[:, :] = 0.0",
            f"{pad}    jv[:, :] = 0.0",
        ]
    args = {i: "jqc, jvc, jck" if i in costly else f"jq, jv, {jac}" for i in range(n)}
    return lines + [f"{pad}k{i}({q}, {v}, f, {args[i]}, p{i})" for i in range(n)]


def _integrate_source(n: int, timed: list, packs: str, tin: str, checks=(), costly=()) -> list[str]:
    """Lines of the generated ``fused_integrate``: with ``mode`` :data:`INTEGRATE`, the compiled
    generalized-alpha (:mod:`flexrv.model.numerics.gen_alpha`, reverse communication) over the
    steps ending at ``times``; returns (steps done, status: 0 done, 1 Newton failed, 2 an
    element's inner solve failed, 3 non-finite state, 4 an element's per-step check failed at
    the accepted state of the last step done; ``checks``: the elements with a ``step_check``).
    Step i writes the elements' time inputs of row i of their tables; an accepted step is
    recorded (state into ``ts``, ``qs``, ``vs`` row ``rec[0]``, the elements' records into
    ``dst``) if its end time is at least ``rec_t[1]`` after the last record ``rec_t[0]`` (or no
    row is recorded yet), while rows remain (``rec[1]``), except the last step of the call when
    ``rec[2]`` (a segment's end, recorded as the next one's start). ``blocks``: the state's
    dense diagonal blocks (``st.blocks``), or None for a state without (the block elimination is
    then not compiled in). The elements ``costly`` (``costly_jacobian``) put their Jacobians into
    the state's kept arrays ``st.jqk``, ``st.jvk`` when it has them (partial Jacobians), and only
    when the state asks for every element's (``ip[I_JAC]`` = JAC_FULL).

    With ``mode`` :data:`ROWS` (:data:`ROWS_JAC`: with the Jacobians), the elements evaluated
    at every row i of ``qs``, ``vs`` with the time inputs of row i, their records copied into
    row i of ``dst`` (the outputs' history pass and single evaluations of a run on this
    integrator: :meth:`flexrv.model.kernels.FusedForces.history`), ``st`` left alone; returns
    (rows done, status 0 or 2). ONE call site of every element's kernel serves both modes, so
    that a run compiles one entry point (each entry point generates the machine code of all
    the kernels it calls again)."""
    lines = [
        "",
        "",
        "@njit(cache=True)",
        f"def fused_integrate(mode, st, blocks, times, t_prev, {tin}f, jq, jv, {packs}, ctrs, src, dst, rec, "
        "rec_t, ts, qs, vs, valid):",
        f"    rows = mode != {INTEGRATE}",
        "    n = qs.shape[0] if rows else times.shape[0]",
        "    for i in range(n):",
    ]
    for i, field in timed:
        lines += _copy_lines(8, f"p{i}.{field}[c]", f"tin{i}[i, c]", f"tin{i}.shape[1]")
    lines += [
        "        if not rows:",
        "            begin_step(st, times[i] - (t_prev if i == 0 else times[i - 1]))",
        "        status = EVALUATE",
        "        while status == EVALUATE:",
        "            q = qs[i] if rows else st.q",
        "            v = vs[i] if rows else st.v",
        f"            jac = mode == {ROWS_JAC} if rows else st.ip[I_JAC] != 0",
        "            before = 0",
        "            for c in ctrs:",
        "                before += c[0]",
    ]
    if costly:
        lines += [
            "            kept = not rows and st.jqk.shape[0] > 0",
            f"            jck = mode == {ROWS_JAC} if rows else st.ip[I_JAC] == JAC_FULL",
            "            jqc = st.jqk if kept else jq",
            "            jvc = st.jvk if kept else jv",
            "            if kept and jck:",
            "                jqc[:, :] = 0.0",
            "                jvc[:, :] = 0.0",
        ]
    lines += _evaluate_lines(12, n, "q", "v", "jac", costly)
    lines += [
        "            after = 0",
        "            for c in ctrs:",
        "                after += c[0]",
        "            if after != before:",
        "                return i, 2",
        "            status = CONVERGED if rows else after_eval(st, f, jq, jv, blocks)",
        "        if rows:",
        "            k = i",
        "        else:",
        "            if status == FAILED:",
        "                return i, 1",
        "            if not finish_step(st):",
        "                return i, 3",
    ]
    if checks:
        lines += [
            "            if " + " or ".join(f"c{i}(p{i}) != 0" for i in checks) + ":",
            "                return i + 1, 4",
        ]
    lines += [
        "            k = rec[0]",
        "            due = k == 0 or times[i] >= rec_t[0] + rec_t[1]",
        "            if not ((i < n - 1 or rec[2] == 0) and k < rec[1] and due):",
        "                continue",
        "            ts[k] = times[i]",
        "            for c in range(st.q.shape[0]):",
        "                qs[k, c] = st.q[c]",
        "                vs[k, c] = st.v[c]",
        "            valid[k] = True",
        "            rec[0] = k + 1",
        "            rec_t[0] = times[i]",
        "        for r in range(len(src)):",
        "            s, d = src[r], dst[r]",
    ]
    lines += _copy_lines(12, "d[k, c]", "s[c]", "s.shape[0]")
    lines += ["    return n, 0", ""]
    return lines


_LOADED: dict[str, object] = {}


def _write_generated(name: str, source: str, write) -> Path:
    """The generated file ``name`` with ``source`` (written if missing or different): in
    :data:`GENERATED`, or where the package is read-only in flexrv's cache folder (keyed by
    the package's path, so two installations never share a file)."""
    from flexrv.cache import cache_dir

    for folder in (GENERATED, cache_dir() / "fused" / hashlib.sha256(str(_PACKAGE).encode()).hexdigest()[:12]):
        path = folder / name
        try:
            if not path.exists() or path.read_text() != source:
                folder.mkdir(parents=True, exist_ok=True)
                write(path, source)
            return path
        except OSError:
            continue
    raise OSError(f"cannot write the generated fused kernel {name}")


def fused_functions(specs) -> tuple:
    """(fused_kernel, fused_history, fused_integrate) of the elements ``specs`` (call
    order), generated and imported once per process (module docstring)."""
    specs = tuple(specs)
    callee_hash = _source_hash(specs)
    source = _fused_source(specs, callee_hash)
    key = hashlib.sha256(source.encode()).hexdigest()[:16]
    mod = _LOADED.get(key)
    if mod is None:
        from flexrv.cache import atomic_write_text

        path = _write_generated(f"fused_{key}.py", source, atomic_write_text)
        name = f"flexrv.model.core._generated.fused_{key}"
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
        _LOADED[key] = mod
    return mod.fused_kernel, mod.fused_history, mod.fused_integrate
