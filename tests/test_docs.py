"""The documentation site builds with every warning as an error, and its generated
reference pages are complete: every field of the design model is on the TOML reference
page, every declared output on the results page, every pinned reference value on the
verification page."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _pages():
    spec = importlib.util.spec_from_file_location("flexrv_docs_pages", ROOT / "docs" / "gen" / "pages.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _schema_paths(schema: dict, defs: dict, prefix: str = "") -> list[str]:
    """Leaf field paths of a pydantic JSON schema (independent of the page generator's walk
    over ``model_fields``): ``$ref`` / ``anyOf`` objects are walked, arrays of objects get
    ``[]``, maps of objects ``{name}``."""

    def resolve(s):
        if "$ref" in s:
            return defs[s["$ref"].split("/")[-1]]
        for key in ("anyOf", "oneOf", "allOf"):
            objs = [resolve(x) for x in s.get(key, []) if "$ref" in x or x.get("type") == "object"]
            objs = [o for o in objs if "properties" in o]
            if objs:
                return objs[0]
        return s

    out = []
    for name, prop in schema.get("properties", {}).items():
        sub = resolve(prop)
        path = f"{prefix}{name}"
        if "properties" in sub:
            out += _schema_paths(sub, defs, path + ".")
        elif sub.get("type") == "array" and "properties" in resolve(sub.get("items", {})):
            out += _schema_paths(resolve(sub["items"]), defs, path + "[].")
        elif isinstance(sub.get("additionalProperties"), dict) and "properties" in resolve(sub["additionalProperties"]):
            out += _schema_paths(resolve(sub["additionalProperties"]), defs, path + ".{name}.")
        else:
            out.append(path)
    return out


def test_design_reference_lists_every_field():
    """Every leaf field of :class:`flexrv.design.model.Reducer` (from its JSON schema) is a
    row of the generated design reference, with a unit column, a range and a meaning."""
    from flexrv.design.model import Reducer

    schema = Reducer.model_json_schema()
    paths = _schema_paths(schema, schema.get("$defs", {}))
    assert len(paths) > 100, paths
    page = _pages().design_reference()
    missing = [p for p in paths if f"| `{p}` |" not in page]
    assert not missing, f"fields missing from the design reference: {missing}"
    rows = [line for line in page.splitlines() if line.startswith("| `")]
    assert len(rows) == len(paths), (len(rows), len(paths))
    assert all(line.count(" | ") >= 4 and not line.rstrip().endswith("|  |") for line in rows)


def test_design_reference_ranges_and_units():
    """Spot checks against the model: a bounded integer, a unit from the name, a choice."""
    page = _pages().design_reference()
    row = next(line for line in page.splitlines() if line.startswith("| `first_stage.sun_teeth` |"))
    assert "≥ 8 and ≤ 200" in row
    row = next(line for line in page.splitlines() if line.startswith("| `first_stage.module_mm` |"))
    assert "| mm |" in row and "> 0.2 and ≤ 20" in row
    row = next(line for line in page.splitlines() if line.startswith("| `carrier.body_model` |"))
    assert "`condensed_fe`" in row and "`rigid`" in row


def test_tolerances_reference_lists_every_error_field():
    from flexrv.design import tolerances

    page = _pages().tolerances_reference()
    for name in tolerances._allowed_names():
        assert f"`{name}`" in page
    for name in tolerances.Tolerance.model_fields:
        assert f"| `{name}` |" in page


def _mkdocs_available() -> bool:
    return importlib.util.find_spec("mkdocs") is not None and importlib.util.find_spec("material") is not None


@pytest.mark.skipif(not _mkdocs_available(), reason="mkdocs-material is not installed (pip install -e '.[docs]')")
def test_docs_build_strict(tmp_path):
    """``mkdocs build --strict`` succeeds (a broken link, a page missing from the navigation or
    a failing generator is an error), and the generated pages are complete: every declared
    output on the results page, every pinned case on the verification page, every command on
    the commands page."""
    import typer

    from flexrv.cli import app
    from flexrv.model.outputs import declared_outputs
    from tests.reference_values import REFERENCE

    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    results = (site / "results-reference" / "index.html").read_text(encoding="utf-8")
    for name in declared_outputs():
        assert f"<code>{name}</code>" in results, name
    verification = (site / "verification" / "index.html").read_text(encoding="utf-8")
    for name in REFERENCE:
        assert f"<code>{name}</code>" in verification, name
    commands = (site / "commands" / "index.html").read_text(encoding="utf-8")
    for name in typer.main.get_command(app).commands:
        assert f"flexrv {name}" in commands, name
    assert (site / "img" / "te_rv40e_grade5.png").stat().st_size > 10_000


def test_docs_name_only_existing_files():
    """Every test file, benchmark and module path a documentation page or the README names
    exists (a glob such as ``tests/test_ehl_*.py`` must match at least one file)."""
    import re

    pages = [*sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md"]
    missing = []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for path in set(re.findall(r"\b((?:tests|benchmarks|flexrv|docs)/[\w/*.-]+\.(?:py|md|toml|png))\b", text)):
            if not list(ROOT.glob(path)):
                missing.append(f"{page.name}: {path}")
    assert not missing, missing
