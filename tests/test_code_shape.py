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
