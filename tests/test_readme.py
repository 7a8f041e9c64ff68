"""README.md is a user's page: short, readable in a terminal, without history, and every
command it shows exists in the CLI with the options it shows."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
MAX_LINES = 150
MAX_CHARS = 200


def _text() -> str:
    return README.read_text(encoding="utf-8")


def test_readme_is_short():
    """At most 150 lines, none longer than 200 characters."""
    lines = _text().splitlines()
    assert len(lines) <= MAX_LINES, f"README.md has {len(lines)} lines (at most {MAX_LINES})"
    long = [(i + 1, len(line)) for i, line in enumerate(lines) if len(line) > MAX_CHARS]
    assert not long, f"README.md lines over {MAX_CHARS} characters (line, length): {long}"


def test_readme_has_no_history():
    """No ISO date, no commit hash (7 to 40 hex digits with a digit and a letter), no issue
    number: history belongs in CHANGELOG.md."""
    text = _text()
    dates = re.findall(r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b", text)
    assert not dates, f"dates in README.md: {dates}"
    hashes = [h for h in re.findall(r"\b[0-9a-f]{7,40}\b", text) if re.search(r"\d", h) and re.search(r"[a-f]", h)]
    assert not hashes, f"commit hashes in README.md: {hashes}"
    issues = re.findall(r"(?i)\bissues? #?\d+|(?<![\w&])#\d+\b", text)
    assert not issues, f"issue numbers in README.md: {issues}"


def _readme_invocations() -> list[list[str]]:
    """Every ``flexrv ...`` invocation of the README: code spans and lines of code blocks,
    cut at shell operators and comments, with table escapes (``\\|``) undone."""
    text = _text()
    fragments = re.findall(r"`([^`\n]*flexrv [^`\n]*)`", text)
    for block in re.findall(r"```(?:bash|sh)?\n(.*?)```", text, flags=re.S):
        fragments += block.splitlines()
    calls = []
    for frag in fragments:
        frag = frag.replace("\\|", "|").split("#")[0]
        for part in re.split(r"&&|;|>|\|\|", frag):
            words = part.replace("[", " ").replace("]", " ").replace("|", " ").split()
            if len(words) > 1 and words[0] == "flexrv":
                calls.append(words)
    return calls


def test_readme_commands_exist():
    """Each command the README shows is a command of ``flexrv`` and each ``--option`` it
    shows with it is an option of that command (read from the CLI itself)."""
    typer = pytest.importorskip("typer")
    from flexrv.cli import app

    group = typer.main.get_command(app)
    calls = _readme_invocations()
    assert len(calls) >= 15, calls
    shown = set()
    for words in calls:
        name = words[1]
        if name.startswith("-") or name.isupper():  # an option or a placeholder (COMMAND)
            continue
        assert name in group.commands, f"README shows `flexrv {name}`, not a command: {sorted(group.commands)}"
        shown.add(name)
        opts = {
            o for p in group.commands[name].params for o in getattr(p, "opts", []) + getattr(p, "secondary_opts", [])
        }
        for word in words[2:]:
            if word.startswith("--"):
                assert word.split("=")[0] in opts | {"--help"}, f"`flexrv {name}` has no option {word}"
    missing = set(group.commands) - shown
    assert not missing, f"commands missing from the README's table: {sorted(missing)}"
