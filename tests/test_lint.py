"""The tree passes ruff's lint (rules E, F, W, I; line length 120; pyproject [tool.ruff]) and is
formatted by ``ruff format``: the same checks CI runs."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _ruff() -> list[str] | None:
    exe = shutil.which("ruff")
    if exe:
        return [exe]
    try:
        import ruff  # noqa: F401
    except ImportError:
        return None
    return [sys.executable, "-m", "ruff"]


RUFF = _ruff()
pytestmark = pytest.mark.skipif(RUFF is None, reason="ruff is not installed (pip install -e '.[test]')")


def test_ruff_check():
    proc = subprocess.run([*RUFF, "check", "--output-format", "concise", "."], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]


def test_ruff_format():
    proc = subprocess.run([*RUFF, "format", "--check", "."], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]


def _history_files() -> set[str]:
    import re

    pattern = re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b|\b[Ii]ssues? #?\d+")
    found = set()
    for path in sorted((ROOT / "flexrv").rglob("*.py")):
        if pattern.search(path.read_text(encoding="utf-8")):
            found.add(path.relative_to(ROOT).as_posix())
    return found


def test_no_dates_or_issue_numbers_in_code():
    """Code says what and why; when and by how much belongs in CHANGELOG.md. No module of
    ``flexrv`` carries an ISO date or an issue number."""
    found = sorted(_history_files())
    assert not found, f"dates or issue numbers in: {found} (move the history to CHANGELOG.md)"
