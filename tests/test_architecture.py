"""Layers point one way: a lower layer of sarfe never imports a higher one (issue 12).

Order: util, linalg < mesh < fe < reduction < hbm < erp < accuracy, case, results < pipeline < tradeoff, batch, cli. Every module's
imports — module level and inside functions — are read with ``ast`` (relative imports resolved).
"""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "sarfe"
LAYERS = {"util": 0, "linalg": 0, "mesh": 0, "fe": 1, "reduction": 2, "hbm": 3, "erp": 4,
          "accuracy": 5, "case": 5, "results": 5, "pipeline": 6, "tradeoff": 7, "batch": 7,
          "cli": 7, "__main__": 7}


def _imports(path):
    """Top-level sarfe parts (``hbm``, ``io`` …) imported by the module at ``path``."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    package = parts[:-1] if path.name != "__init__.py" else parts[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - node.level + 1]
                module = ".".join(base + ((node.module,) if node.module else ()))
                names = [module] if node.module else [f"{module}.{a.name}" for a in node.names]
            else:
                names = [node.module] if node.module != "sarfe" else \
                    [f"sarfe.{a.name}" for a in node.names]
        else:
            continue
        for name in names:
            bits = name.split(".")
            if bits[0] == "sarfe" and len(bits) > 1:
                found.add(bits[1])
    return found


def _violations():
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        source = parts[0]
        if source not in LAYERS:
            continue
        for target in _imports(path):
            if target in LAYERS and LAYERS[target] > LAYERS[source]:
                out.append((source, target, str(path.relative_to(PACKAGE.parent))))
    return out


def test_every_part_has_a_layer():
    parts = {p.relative_to(PACKAGE).with_suffix("").parts[0] for p in PACKAGE.rglob("*.py")}
    assert parts - {"__init__"} <= set(LAYERS), parts - set(LAYERS)


def test_import_reader_sees_relative_and_local_imports(tmp_path):
    assert "laws" not in LAYERS and "hbm" in _imports(PACKAGE / "pipeline" / "model" / "nonlinear_model.py")
    assert _imports(PACKAGE / "hbm" / "aft.py") == {"hbm"}


def test_no_upward_imports():
    bad = _violations()
    assert not bad, "\n".join(f"{s} imports {t}: {f}" for s, t, f in bad)


def test_fe_does_not_import_reduction():
    """fe's modal analysis factorizes K − σM with sarfe.linalg (moved below fe)."""
    bad = [v for v in _violations() if v[:2] == ("fe", "reduction")]
    assert not bad, "\n".join(f"{s} imports {t}: {f}" for s, t, f in bad)


def test_pipeline_does_not_import_study():
    """Screening/pruning live in sarfe.hbm.pruning, estimates and resolution in sarfe.accuracy."""
    bad = [v for v in _violations() if v[:2] == ("pipeline", "study")]
    assert not bad, "\n".join(f"{s} imports {t}: {f}" for s, t, f in bad)
