"""The shape of the code: no function in flexrv/ is longer than MAX_LINES lines (read from
the AST: from the ``def`` line to the function's last line, decorators excluded, its
docstring included). A long compiled kernel is split into phase functions (each its own
``@njit`` function; numba inlines or calls them at no measurable cost), a long builder
into helpers that each build one part."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "flexrv"
MAX_LINES = 150

#: functions still over the limit, each with the reason it is: a split under way in a module
#: another change owns. An entry that no longer exists or is no longer over the limit fails
#: the test below, so the list can only shrink.
PENDING: dict[str, str] = {}


def function_lengths(root: Path = PACKAGE) -> dict[str, int]:
    """{"path:Qualified.name": lines} of every function and method under ``root``."""
    out: dict[str, int] = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()

        def visit(node, prefix):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    name = f"{prefix}{child.name}"
                    out[f"{rel}:{name}"] = child.end_lineno - child.lineno + 1
                    visit(child, name + ".")
                elif isinstance(child, ast.ClassDef):
                    visit(child, f"{prefix}{child.name}.")

        visit(ast.parse(path.read_text()), "")
    return out


def test_no_function_over_the_limit():
    """Every function in flexrv/ has at most MAX_LINES lines, except the PENDING ones."""
    long = {k: n for k, n in function_lengths().items() if n > MAX_LINES and k not in PENDING}
    assert not long, "functions over %d lines: %s" % (MAX_LINES, long)


def test_pending_list_is_current():
    """Every PENDING entry exists and is still over the limit (a split function leaves the list)."""
    lengths = function_lengths()
    stale = [k for k in PENDING if lengths.get(k, 0) <= MAX_LINES]
    assert not stale, f"no longer over {MAX_LINES} lines (remove from PENDING): {stale}"


def test_lengths_are_counted(tmp_path):
    """The counter sees functions, methods and nested functions with their full extent."""
    pkg = tmp_path / "flexrv"
    pkg.mkdir()
    body = "\n".join(f"        x{i} = {i}" for i in range(160))
    (pkg / "m.py").write_text(f"class A:\n    def f(self):\n{body}\n\n\ndef g():\n    def h():\n        pass\n")
    import tests.test_code_shape as mod

    old = mod.ROOT
    mod.ROOT = tmp_path
    try:
        got = function_lengths(pkg)
    finally:
        mod.ROOT = old
    assert got == {"flexrv/m.py:A.f": 161, "flexrv/m.py:g": 3, "flexrv/m.py:g.h": 2}


#: the bearing rows' shared compiled phases: {name: {argument index: the helper that must pass it}}.
#: numba specializes a compiled callee on literal and boolean argument types, and every
#: specialization compiles the callee's whole call tree again (~10-20 s each, docs/benchmarks.md):
#: a call passes the mode through ``_mode`` (a run-time int64) and row_part's flag through ``_flag``
ROW_PHASES = {
    "_row_pass1": {3: "_mode"},
    "_row_front": {3: "_mode"},
    "_row_back": {3: "_mode"},
    "row_eval": {3: "_mode"},
    "quasi_static_balls": {3: "_mode"},
    "row_part": {2: "_flag", 3: "_mode"},
}
BEARING_KERNEL = PACKAGE / "model" / "bearing_kernel.py"


def constant_mode_calls(source: str) -> tuple[list[str], dict[str, int]]:
    """The calls of a :data:`ROW_PHASES` function in ``source`` whose mode (or flag) is not a run-time
    value -- a call of its helper, or a name assigned from one in the same function -- as
    "callee:line", and the number of calls found per phase."""
    bad, found = [], dict.fromkeys(ROW_PHASES, 0)

    def called(node):  # the name a call calls, else None
        return node.func.id if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) else None

    for fn in ast.walk(ast.parse(source)):
        if not isinstance(fn, ast.FunctionDef):
            continue
        bound = {
            t.id: called(a.value)
            for a in ast.walk(fn)
            if isinstance(a, ast.Assign)
            for t in a.targets
            if isinstance(t, ast.Name)
        }
        for call in ast.walk(fn):
            name = called(call)
            if name not in ROW_PHASES:
                continue
            found[name] += 1
            for index, helper in ROW_PHASES[name].items():
                arg = call.args[index] if index < len(call.args) else None
                ok = called(arg) == helper or (isinstance(arg, ast.Name) and bound.get(arg.id) == helper)
                if not ok:
                    bad.append(f"{name}:{call.lineno}")
    return bad, found


def test_row_phases_get_their_mode_at_run_time():
    """Every call of a bearing-row phase in bearing_kernel.py passes its jacobian mode through
    ``_mode`` and row_part's flag through ``_flag`` (:data:`ROW_PHASES`), so each phase compiles
    once: with constant modes rv40e's ball model compiled in 215 s instead of 141 s
    (bench_compile.py). Every phase is called at least once (the check sees the calls)."""
    bad, found = constant_mode_calls(BEARING_KERNEL.read_text())
    assert not bad, f"row phases called with a constant or boolean mode (pass it through _mode/_flag): {bad}"
    assert all(found.values()), found


def test_constant_modes_are_found():
    """The check flags a literal, a bool parameter passed on and a flag not passed through _flag;
    it accepts a name bound to _mode."""
    source = (
        "def a(q, jacobian, absolute):\n"
        "    row_eval(q, q, q, False, q)\n"
        "    _row_front(q, q, q, jacobian)\n"
        "    row_part(q, q, absolute, _mode(jacobian), q)\n"
        "    m = _mode(jacobian)\n"
        "    _row_back(q, q, q, m, q)\n"
    )
    bad, found = constant_mode_calls(source)
    assert bad == ["row_eval:2", "_row_front:3", "row_part:4"]
    assert found["_row_back"] == 1 and found["quasi_static_balls"] == 0
