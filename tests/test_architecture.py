"""The shape of the code (shared/DESIGN.md): no import circles between our modules (counting imports inside
functions too), the equations on the ground floor importing nothing of ours, no private name imported across
modules."""
from __future__ import annotations

import ast
from functools import lru_cache
from pathlib import Path

PROJECT = Path(__file__).resolve().parents[1]
PACKAGES = ("mftyre", "swift", "fmu")


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in (PROJECT / package).rglob("*.py"):
            parts = path.relative_to(PROJECT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


MODULES = _modules()


@lru_cache(maxsize=None)
def _imports(name: str) -> list[tuple[str, list[str]]]:
    """(imported module, imported names) of every import statement in module ``name``, anywhere in it."""
    path = MODULES[name]
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            target = ".".join(base + ([node.module] if node.module else []))
            found.append((target, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            found.extend((a.name, []) for a in node.names)
    return found


def _graph() -> dict[str, set[str]]:
    edges = {m: set() for m in MODULES}
    for m in MODULES:
        for target, names in _imports(m):
            submodules = {f"{target}.{n}" for n in names} & MODULES.keys()
            if submodules:
                edges[m] |= submodules - {m}
            if target in MODULES and target != m and len(submodules) < len(names or [None]):
                edges[m].add(target)
    return edges


def _circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan), ignoring a package's own __init__ importing
    its submodules to re-export them (the package's face, not a floor)."""
    edges = {m: {t for t in ts if not (MODULES[m].name == "__init__.py" and t.startswith(m + "."))}
             for m, ts in edges.items()}
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in edges:
        if v not in index:
            visit(v)
    return out


def test_no_import_circles():
    assert _circles(_graph()) == []


def test_the_circle_finder_finds_a_circle():
    edges = {m: set() for m in MODULES}
    edges["mftyre.cli"].add("mftyre.demo")
    edges["mftyre.demo"].add("mftyre.cli")
    assert _circles(edges) == [["mftyre.cli", "mftyre.demo"]]


def test_the_equations_import_nothing_of_ours_but_each_other():
    graph = _graph()
    for m in MODULES:
        if m.startswith("mftyre.formula"):
            outside = {t for t in graph[m] if not t.startswith("mftyre.formula")}
            assert not outside, f"{m} imports {sorted(outside)}"


def test_no_private_name_imported_from_another_module():
    private = []
    for m in MODULES:
        for target, names in _imports(m):
            if target.split(".")[0] in PACKAGES and target != m:
                private += [f"{m}: {target}.{n}" for n in names if n.startswith("_") and not n.startswith("__")]
    assert private == []


def test_the_vocabulary_imports_nothing_of_ours():
    """mftyre/variables.py (one Variable per name for the wheels, both FMU backends, MFModel and soil) sits on the
    ground floor beside the equations: every floor may use it."""
    assert _graph()["mftyre.variables"] == set()
    assert "mftyre.variables" in _graph()["fmu.native_build"]  # the builders speak it
