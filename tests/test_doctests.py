"""The docstring examples of the package run as doctests in the default suite (issue 16).

Every module under flexrv/ whose source holds an example (``>>>``) is imported and its
examples are run with :mod:`doctest` (ELLIPSIS and NORMALIZE_WHITESPACE). Examples that are
too slow for the fast suite (meshing, CMS, time integration) carry ``# doctest: +SKIP`` on
every line and say why in the text; the others must pass. Equivalent to
``python -m pytest --doctest-modules flexrv`` restricted to the modules with examples, but
part of the default test run.
"""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "flexrv"


def _module(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = sorted(_module(p) for p in ROOT.rglob("*.py") if ">>>" in p.read_text(encoding="utf-8"))
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _run(name: str) -> doctest.TestResults:
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in finder.find(module, name):
        runner.run(test)
    return runner.summarize(verbose=False)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    """The module's examples give the printed output (a failure prints the diff)."""
    result = _run(name)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples of {name} failed (see stdout)"


def test_examples_run_not_only_skipped():
    """At least the units, formatting, design, cache and EHL-law examples really execute
    (a doctest run where everything is skipped would check nothing)."""
    attempted = {
        name: _run(name).attempted
        for name in ("flexrv.units", "flexrv.post.format", "flexrv.design", "flexrv.cache", "flexrv.ehl.law")
    }
    assert all(n >= 1 for n in attempted.values()), attempted
    assert sum(attempted.values()) >= 15, attempted
