"""The bibliography (flexrv/references.py, docs/references.md) and the citations that use it.

Citation syntax in code and docstrings: ``:cite:`key``` (several keys: ``:cite:`a,b```).
"""

import ast
import re
from pathlib import Path

import pytest

from flexrv.references import CITE_PATTERN, REFERENCES, SECTIONS, cite, cited_keys, markdown

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted(
    p
    for d in ("flexrv", "workflows", "benchmarks", "tests")
    if (ROOT / d).exists()
    for p in (ROOT / d).rglob("*.py")
    if p.name not in ("references.py", "test_references.py")
)


def _citations():
    out = []
    for path in SOURCES:
        text = path.read_text(encoding="utf-8")
        for line_no, line in enumerate(text.splitlines(), 1):
            for key in cited_keys(line):
                out.append((path.relative_to(ROOT).as_posix(), line_no, key))
    return out


def test_every_cited_key_exists():
    """Every ``:cite:`key``` in the package, workflows, benchmarks and tests is a key of
    flexrv.references.REFERENCES (a citation of a missing work fails here)."""
    cites = _citations()
    assert len(cites) >= 30  # the converted modules cite ~40 times; guards against a broken pattern
    missing = [f"{f}:{n}: {k}" for f, n, k in cites if k not in REFERENCES]
    assert not missing, "unknown reference keys:\n" + "\n".join(missing)


def test_cited_keys_parser():
    assert cited_keys("a :cite:`hamrock1994`, eq. 1 and :cite:`seed000,seed001`.") == [
        "hamrock1994",
        "seed000",
        "seed001",
    ]
    assert cited_keys("units [m] and [seed000] are not citations") == []
    assert CITE_PATTERN.pattern == r":cite:`([^`]+)`"


def test_seeds_are_named_and_keys_unique():
    """The five seed studies are keys seed000..seed004, each naming its study; keys are unique
    across sections, lower-case identifiers; ``cite`` names the known keys on a typo."""
    for i in range(5):
        assert f"Seed study 00{i}" in REFERENCES[f"seed00{i}"]
    n = sum(len(s) for s in SECTIONS.values())
    assert n == len(REFERENCES)
    assert all(k == k.lower() and k.replace("_", "").isalnum() for k in REFERENCES)
    assert "Comprehensive Analysis of Meshing Stiffness" in cite("seed004")
    with pytest.raises(KeyError, match="seed004"):
        cite("seed005")


def test_docs_references_md_is_generated_from_the_module():
    """docs/references.md is exactly ``python -m flexrv.references`` output (one source)."""
    assert (ROOT / "docs" / "references.md").read_text(encoding="utf-8") == markdown()


def test_no_citation_inside_runtime_strings_of_converted_modules():
    """Citations belong in docstrings and comments: a ``:cite:`` inside a non-docstring string
    constant would leak into user output. Checked over the package's AST."""
    bad = []
    for path in (p for p in SOURCES if p.is_relative_to(ROOT / "flexrv")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
                first = node.body[0]
                if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                    docstrings.add(id(first.value))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and id(node) not in docstrings
                and CITE_PATTERN.search(node.value)
            ):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not bad, bad


#: a bare seed citation ("seed" + " 004", "seeds" + " 000/001"): must be a key (":cite:`seed004`" in
#: docstrings and comments, the plain key "seed004" in output text and the presets)
BARE_SEED = re.compile(r"\b[Ss]eeds?\s+00[0-4]\b")
PACKAGE_TEXTS = sorted(p for p in (ROOT / "flexrv").rglob("*") if p.suffix in (".py", ".toml"))


def test_no_bare_seed_citation_in_the_package():
    """Every seed citation in flexrv/ (code, docstrings, comments, presets) uses a reference
    key; the pattern catches the old forms."""
    for old in ("seed" + " 004", "seeds" + " 000/001", "(seed" + " 002's", "seeds\n 003"):
        assert BARE_SEED.search(old), old
    for new in (":cite:`seed004`", "seed000/seed001", "random seed 42", "Seed study 003"):
        assert not BARE_SEED.search(new), new
    bare = [
        f"{p.relative_to(ROOT)}:{p.read_text(encoding='utf-8')[: m.start()].count(chr(10)) + 1}: {m.group(0)!r}"
        for p in PACKAGE_TEXTS
        for m in BARE_SEED.finditer(p.read_text(encoding="utf-8"))
    ]
    assert not bare, "bare seed citations (use :cite:`seed00X` or the key seed00X):\n" + "\n".join(bare)


def test_plain_seed_keys_exist():
    """The plain keys of output text and presets (``seed004``) are keys of the bibliography."""
    keys = {m.group(0) for p in PACKAGE_TEXTS for m in re.finditer(r"\bseed\d{3}\b", p.read_text(encoding="utf-8"))}
    assert keys and keys <= set(REFERENCES), keys - set(REFERENCES)
