"""The house rules of sarfe's package layout (issues 12 and 28), read from the source with ``ast``.

- Layers point one way: a lower layer never imports a higher one. Order: util, linalg, mesh < fe <
  reduction < hbm < erp < accuracy, case, results < pipeline < tradeoff, batch, cli.
- No import circle between modules, function-local imports counted.
- Function-local sarfe imports only where a module is heavy and optional (``LOCAL_IMPORTS``, ≤ 20).
- No module over 600 lines; no module basename reused for a different concept; no import of another
  module's ``_private`` name.

Every module's imports — module level and inside functions — are read with ``ast`` (relative
imports resolved). ``from A import b`` is an edge to the module ``A.b`` where that is a module, else
to ``A`` (a module or a package's ``__init__``).
"""
from __future__ import annotations

import ast
from collections import Counter
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "sarfe"
LAYERS = {"util": 0, "linalg": 0, "mesh": 0, "fe": 1, "reduction": 2, "hbm": 3, "erp": 4,
          "accuracy": 5, "case": 5, "results": 5, "pipeline": 6, "tradeoff": 7, "batch": 7,
          "compare": 7, "cli": 7, "__main__": 7}
MAX_LINES = 600
#: basenames several modules may share: each is the same concept in its own package
SHARED_BASENAMES = {"__init__", "__main__", "cli"}
#: (importing module, imported module): the function-local sarfe imports allowed, each because the
#: imported module is heavy (its library's import costs seconds) and optional (most runs never use it)
LOCAL_IMPORTS = {
    ("sarfe.results.render", "sarfe.results.plots"):
        "matplotlib: the fallback surface map, drawn only when the pyvista render child fails",
    ("sarfe.hbm.laws.jenkins", "sarfe.hbm.laws.jenkins_march"):
        "numba (0.39 s of import): only 2-D friction (a squeak contact with two tangent rows) needs "
        "the compiled disk-projection march",
    ("sarfe.hbm.stability.contact_terms", "sarfe.hbm.stability.march"):
        "numba: only the friction memory of 2-D sliders in the Hill stability needs it",
}


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_local(node, parents) -> bool:
    q = parents.get(node)
    while q is not None:
        if isinstance(q, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            return True
        q = parents.get(q)
    return False


def imports(name: str):
    """(target module, imported names, function-local?) of every sarfe import of module ``name``."""
    path = MODULES[name]
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    parents = {c: n for n in ast.walk(tree) for c in ast.iter_child_nodes(n)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "sarfe":
                    yield alias.name, (), _is_local(node, parents)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module.split(".")[0] != "sarfe":
                continue
            local = _is_local(node, parents)
            plain = []
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                if sub in MODULES:
                    yield sub, (), local
                else:
                    plain.append(alias.name)
            if plain:
                yield module, tuple(plain), local


def graph() -> dict:
    return {name: {t for t, _, _ in imports(name) if t in MODULES and t != name} for name in MODULES}


def layer_of(name: str):
    return LAYERS.get(name.split(".")[1]) if "." in name else None


def test_every_part_has_a_layer():
    parts = {name.split(".")[1] for name in MODULES if "." in name}
    assert parts <= set(LAYERS), parts - set(LAYERS)


def test_no_upward_imports():
    bad = [f"{name} imports {target}" for name in MODULES for target, _, _ in imports(name)
           if "." in target and layer_of(name) is not None and layer_of(target) is not None
           and layer_of(target) > layer_of(name)]
    assert not bad, "\n".join(bad)


def strongly_connected(edges: dict) -> list:
    """Tarjan's strongly connected components with more than one module (the import circles)."""
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
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in edges:
        if v not in index:
            visit(v)
    return out


def test_no_import_circles():
    circles = strongly_connected(graph())
    assert not circles, "\n".join(" ↔ ".join(c) for c in circles)


def test_circle_finder_finds_a_circle():
    assert strongly_connected({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_function_local_imports_are_listed():
    found = {(name, target) for name in MODULES for target, _, local in imports(name) if local}
    assert len(LOCAL_IMPORTS) <= 20
    unlisted = sorted(found - set(LOCAL_IMPORTS))
    assert not unlisted, "\n".join(f"{a} imports {b} inside a function" for a, b in unlisted)
    stale = sorted(set(LOCAL_IMPORTS) - found)
    assert not stale, stale


def test_no_module_over_the_limit():
    big = {name: n for name, p in MODULES.items()
           if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not big, big


def test_no_basename_reused():
    names = Counter(p.stem for p in MODULES.values())
    reused = sorted(n for n, c in names.items() if c > 1 and n not in SHARED_BASENAMES)
    assert not reused, {n: [m for m, p in MODULES.items() if p.stem == n] for n in reused}


def test_no_private_names_across_modules():
    bad = [f"{name} imports {n} from {target}" for name in MODULES
           for target, names, _ in imports(name) if target != name
           for n in names if n.startswith("_") and not n.startswith("__")]
    assert not bad, "\n".join(bad)
