"""Layer order and import cycles of the flexrv package (issue 16), checked over the AST.

Every ``import`` / ``from ... import`` of every module under flexrv/ is read with :mod:`ast`,
including the imports inside functions (a third of all imports), and resolved to a flexrv
module. Two rules:

1. a module imports only from its own layer or below (``flexrv.LAYERS``, lowest first);
2. the module import graph has no cycle.

Today's violations are listed below, each with its reason. The test fails on any violation
that is not listed, and also on a listed violation that has disappeared (delete its line:
the lists only shrink).
"""

from __future__ import annotations

import ast
from pathlib import Path

import flexrv

ROOT = Path(__file__).resolve().parents[1] / "flexrv"

#: (importer, imported) -> reason. Upward imports that exist today.
ALLOWED_UPWARD: dict[tuple[str, str], str] = {}

#: import cycles (sets of modules of one strongly connected component) -> reason
ALLOWED_CYCLES: dict[frozenset, str] = {}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _resolve(name: str) -> str | None:
    """The flexrv module an imported dotted name refers to (None outside flexrv)."""
    if name != "flexrv" and not name.startswith("flexrv."):
        return None
    while name not in MODULES and "." in name:
        name = name.rsplit(".", 1)[0]
    return name if name in MODULES else None


def import_edges() -> set[tuple[str, str]]:
    """(importer, imported) flexrv modules, from every import statement of every module."""
    edges = set()
    for mod, path in MODULES.items():
        package = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    src = ".".join(base + ([node.module] if node.module else []))
                else:
                    src = node.module or ""
                subs = [f"{src}.{a.name}" for a in node.names if f"{src}.{a.name}" in MODULES]
                # ``from pkg import submodule`` depends on the submodule; the package itself only
                # when an attribute of it is imported
                names = subs + ([src] if len(subs) < len(node.names) else [])
            for name in names:
                target = _resolve(name)
                if target is not None and target != mod:
                    edges.add((mod, target))
    return edges


def _layer_of(mod: str) -> int | None:
    parts = mod.split(".")
    if len(parts) < 2 or parts[1] == "__main__":
        return None  # the package facade and the entry point are outside the order
    for i, names in enumerate(flexrv.LAYERS):
        if parts[1] in names:
            return i
    raise AssertionError(f"{mod}: '{parts[1]}' is in no layer of flexrv.LAYERS; add it there")


def upward_imports() -> set[tuple[str, str]]:
    out = set()
    for a, b in import_edges():
        la, lb = _layer_of(a), _layer_of(b)
        if la is not None and lb is not None and lb > la:
            out.add((a, b))
    return out


def import_cycles() -> list[frozenset]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    graph: dict[str, list[str]] = {m: [] for m in MODULES}
    for a, b in import_edges():
        graph[a].append(b)
    index, low, on, stack, sccs, counter = {}, {}, set(), [], [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(graph[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(graph[w])))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = set()
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.add(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        sccs.append(frozenset(comp))
    return sccs


def test_layers_are_declared_once_and_cover_the_package():
    """flexrv.LAYERS names each top-level module/subpackage once, and every one is named."""
    names = [n for layer in flexrv.LAYERS for n in layer]
    assert len(names) == len(set(names))
    present = {m.split(".")[1] for m in MODULES if m.count(".") >= 1} - {"__main__"}
    assert present <= set(names), present - set(names)


def test_scanner_sees_imports_inside_functions():
    """The scan reads function-level imports too: studies.compare imports simulation only inside
    run_compare(), and the edge is found."""
    assert ("flexrv.studies.compare", "flexrv.simulation") in import_edges()


def test_geometry_does_not_import_design():
    """geometry sits below design (``flexrv.LAYERS``): its functions take numbers, or a design
    object passed in, and import nothing from flexrv.design; design validation (contact ratio,
    undercut, assembly interference) calls geometry."""
    edges = import_edges()
    assert not [e for e in edges if e[0].startswith("flexrv.geometry") and e[1].startswith("flexrv.design")]
    assert ("flexrv.design.model", "flexrv.geometry.involute") in edges


def test_no_new_upward_import():
    """Every import goes to the importer's own layer or below, except the allowlisted ones."""
    new = sorted(upward_imports() - set(ALLOWED_UPWARD))
    assert not new, "upward imports (a lower layer importing a higher one):\n" + "\n".join(
        f"  {a} -> {b}" for a, b in new
    )


def test_allowlisted_upward_imports_still_exist():
    """An allowlisted violation that has been removed must leave the list (it only shrinks)."""
    gone = sorted(set(ALLOWED_UPWARD) - upward_imports())
    assert not gone, "fixed - delete from ALLOWED_UPWARD:\n" + "\n".join(f"  {a} -> {b}" for a, b in gone)


def test_no_new_import_cycle():
    """No cycle in the module import graph (function-level imports included), except the
    allowlisted ones; an allowlisted cycle that is gone must leave the list."""
    cycles = set(import_cycles())
    new = cycles - set(ALLOWED_CYCLES)
    assert not new, "import cycles:\n" + "\n".join("  " + " <-> ".join(sorted(c)) for c in new)
    gone = set(ALLOWED_CYCLES) - cycles
    assert not gone, "fixed - delete from ALLOWED_CYCLES: " + str([sorted(c) for c in gone])


def test_readme_states_the_same_layer_order():
    """README.md writes the layer order once, identically to flexrv.LAYERS (private modules
    such as ``_version`` are left out of the prose)."""
    import re

    text = " ".join((ROOT.parent / "README.md").read_text(encoding="utf-8").split())
    match = re.search(r"Layers, lowest first \(`flexrv\.LAYERS`[^)]*\): ((?:[\w/]+ < )+[\w/]+)", text)
    assert match, "README.md: no 'Layers, lowest first (`flexrv.LAYERS` ...): a < b < ...' sentence"
    expected = " < ".join("/".join(n for n in layer if not n.startswith("_")) for layer in flexrv.LAYERS)
    assert match.group(1) == expected
