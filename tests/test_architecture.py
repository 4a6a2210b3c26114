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


# ------------------------------------------------------------------ facades where ideas fork (issue 22 item 2)
#: Where the version facades of mftyre.formula.vertical must be used: everything of ours outside formula/.
FACADE_USERS = [p for d in ("mftyre", "swift", "fmu", "benchmarks") if (PROJECT / d).is_dir()
                for p in sorted((PROJECT / d).rglob("*.py")) if "formula" not in p.relative_to(PROJECT).parts]


def _is_nompres(node) -> bool:
    return (isinstance(node, ast.Attribute) and node.attr == "NOMPRES") or (
        isinstance(node, ast.Name) and node.id == "NOMPRES")


def _version_forks(source: str) -> list[str]:
    """Lines that name an MF 6.1/6.2 vertical relation (``..._61``, ``..._62``) or write the pressure increment
    (p - NOMPRES)/NOMPRES (or p/NOMPRES - 1) themselves instead of calling mftyre.formula.vertical's
    vertical_force, loaded_radius, pressure_increment."""
    found = []
    for node in ast.walk(ast.parse(source)):
        name = (node.attr if isinstance(node, ast.Attribute) else node.id if isinstance(node, ast.Name)
                else None)
        names = [a.name for a in node.names] if isinstance(node, ast.ImportFrom) else [name]
        found += [f"line {node.lineno}: {n}" for n in names if n and n.rstrip("_").endswith(("_61", "_62"))]
        if isinstance(node, ast.BinOp):
            left, op, right = node.left, node.op, node.right
            divided = isinstance(op, ast.Div) and _is_nompres(right) and isinstance(left, ast.BinOp) and isinstance(
                left.op, ast.Sub) and _is_nompres(left.right)
            ratio_less_one = isinstance(op, ast.Sub) and isinstance(left, ast.BinOp) and isinstance(
                left.op, ast.Div) and _is_nompres(left.right)
            if divided or ratio_less_one:
                found.append(f"line {node.lineno}: dpi written out")
    return found


def test_the_vertical_version_and_dpi_are_chosen_in_formula_only():
    found = {str(p.relative_to(PROJECT)): f for p in FACADE_USERS if (f := _version_forks(p.read_text("utf-8")))}
    assert found == {}


def test_the_fork_finder_finds_forks():
    assert _version_forks("from mftyre.formula.vertical import loaded_radius_62\n")
    assert _version_forks("fz = vertical.vertical_force_61(prm, rho, r, w, fx, fy, dpi, be)\n")
    assert _version_forks("dpi = (u['p'] - prm.NOMPRES) / prm.NOMPRES\n")
    assert _version_forks("dpi = p / self.params.NOMPRES - 1.0\n")
    assert not _version_forks("dpi = vertical.pressure_increment(prm, p)\nf = vertical.vertical_force(prm, rl)\n")
    assert not _version_forks("x = fz / prm.FNOMIN - 1.0\np = 0.8 * prm.NOMPRES\n")


def test_the_vocabulary_imports_nothing_of_ours():
    """mftyre/variables.py (one Variable per name for the wheels, both FMU backends, MFModel and soil) sits on the
    ground floor beside the equations: every floor may use it."""
    assert _graph()["mftyre.variables"] == set()
    assert "mftyre.variables" in _graph()["fmu.native_build"]  # the builders speak it
