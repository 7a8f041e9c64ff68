"""mkdocs hooks: generated sections and optional pages.

* A page marker ``<!-- gen:NAME -->`` is replaced by the Markdown of
  :data:`pages.GENERATORS` ``[NAME]`` (the design and results references, the command
  help, the verification table, the benchmark list, the changelog), so these sections are
  read from the code at every build. An unknown name fails the build.
* Pages that other parts of the project add (:data:`OPTIONAL_PAGES`, then any other
  top-level page not in ``mkdocs.yml``) join the navigation when their file exists, so the
  navigation never points at a missing page and no page is left out of it.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

#: optional pages: (navigation title, file under docs/), inserted before "Reference"
OPTIONAL_PAGES = (
    ("Definitions", "definitions.md"),
    ("Measured data", "measured-data.md"),
    ("Optimisation", "optimize.md"),
)

_MARKER = re.compile(r"<!--\s*gen:([a-z_]+)\s*-->")


def _pages():
    """The generator module, loaded by path (the hook is not imported as a package)."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    spec = importlib.util.spec_from_file_location("flexrv_docs_pages", HERE / "pages.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _nav_files(nav) -> set[str]:
    """Every page file named in a navigation tree."""
    out: set[str] = set()
    for item in nav or []:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        if isinstance(value, list):
            out |= _nav_files(value)
        elif isinstance(value, str):
            out.add(value)
    return out


def _title(path: Path) -> str:
    """The page's first Markdown heading, else its file name in words."""
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    return path.stem.replace("-", " ").capitalize()


def on_config(config, **kwargs):
    """Add the pages that exist but are not in the navigation (the known optional pages
    first, then any other top-level page) to a "Guides" section before "Reference"."""
    docs_dir = Path(config["docs_dir"])
    listed = _nav_files(config.get("nav"))
    present = [{title: name} for title, name in OPTIONAL_PAGES if (docs_dir / name).exists() and name not in listed]
    known = {name for _, name in OPTIONAL_PAGES} | listed
    present += [{_title(p): p.name} for p in sorted(docs_dir.glob("*.md")) if p.name not in known]
    if present and config.get("nav") is not None:
        nav = list(config["nav"])
        at = next((i for i, item in enumerate(nav) if isinstance(item, dict) and "Reference" in item), len(nav))
        nav.insert(at, {"Guides": present})
        config["nav"] = nav
    return config


def on_page_markdown(markdown, page, config, files, **kwargs):
    """Replace every ``<!-- gen:NAME -->`` marker with the generated Markdown."""
    if not _MARKER.search(markdown):
        return markdown
    pages = _pages()

    def replace(match):
        name = match.group(1)
        if name not in pages.GENERATORS:
            raise KeyError(
                f"{page.file.src_uri}: unknown generated section {name!r}; known: {sorted(pages.GENERATORS)}"
            )
        return pages.GENERATORS[name]()

    return _MARKER.sub(replace, markdown)
