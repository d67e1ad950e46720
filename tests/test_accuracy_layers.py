"""The error estimators and accuracy resolution live below the case layer (issue 12): sarfe/accuracy
imports only the engine and lower layers, and sarfe/pipeline reaches no estimate through sarfe/study."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "sarfe"


def _imports(folder):
    """(file, imported module) for every import in the package folder, function-local ones too."""
    for path in sorted((ROOT / folder).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                yield path.name, node.module
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    yield path.name, alias.name


def test_accuracy_imports_no_higher_layer():
    higher = ("sarfe.pipeline", "sarfe.study", "sarfe.batch", "sarfe.cli")
    bad = [(f, m) for f, m in _imports("accuracy") if m.startswith(higher)]
    assert not bad, bad


def test_pipeline_takes_no_estimate_from_study():
    bad = [(f, m) for f, m in _imports("pipeline")
           if m.startswith(("sarfe.study.accuracy", "sarfe.study.resolve"))]
    assert not bad, bad
