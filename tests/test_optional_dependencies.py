"""The ``batch`` extra (pyproject ``[project.optional-dependencies]``) is optional: a solve runs and
writes its files without Dask, pandas and pyarrow, and ``sarfe batch`` without them stops with one
line naming the extra to install (exit 2, nothing run). A missing package is emulated in a fresh
interpreter by ``sys.modules[name] = None``: ``import name`` then raises ModuleNotFoundError and
``importlib.util.find_spec(name)`` returns None, as when the package is not installed."""
import json
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BATCH_EXTRA = ("dask", "distributed", "pandas", "pyarrow")


def _run_without(packages, code: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter in which ``packages`` cannot be imported."""
    probe = f"import sys\nsys.modules.update(dict.fromkeys({tuple(packages)!r}))\n" + code
    return subprocess.run([sys.executable, "-c", probe], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env={"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg",
                                            "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})


def test_batch_extra_is_optional_in_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    runtime = " ".join(project["dependencies"]).lower()
    batch = " ".join(project["optional-dependencies"]["batch"]).lower()
    for name in ("dask", "pandas", "pyarrow"):
        assert name in batch and name not in runtime


def test_solve_writes_its_files_without_the_batch_extra(tmp_path):
    code = (
        "from sarfe.pipeline import load_case, solve_case\n"
        f"data = load_case({str(ROOT / 'cases' / 'lumped_rattle.yaml')!r}).data\n"
        "data['excitation'].pop('sweep')\n"
        "data['excitation']['frequency_hz'] = [45.0, 50.0]\n"
        f"result = solve_case(data, output_dir={str(tmp_path / 'out')!r})\n"
        "assert result.summary['all_converged']\n"
        f"print([m for m in sys.modules if m.split('.')[0] in {BATCH_EXTRA!r} and sys.modules[m]])")
    done = _run_without(BATCH_EXTRA, code, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [p["frequency_hz"] for p in summary["points"]] == [45.0, 50.0]


def test_batch_without_the_extra_is_one_line_naming_it(tmp_path):
    study = tmp_path / "study.yaml"
    study.write_text("base_case: case.yaml\n")
    code = "from sarfe.cli import main\nsys.exit(main(['batch', 'study.yaml']))"
    done = _run_without(("pandas",), code, tmp_path)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "pandas" in lines[0] and "sarfe[batch]" in lines[0] and "pyarrow" not in lines[0]
    assert not (tmp_path / "results").exists()                 # nothing run, no output folder
    # --workers 0 runs in this process: Dask is not needed, the table packages are
    code = "from sarfe.cli import main\nsys.exit(main(['batch', '--workers', '0', 'study.yaml']))"
    done = _run_without(("distributed", "pyarrow"), code, tmp_path)
    assert done.returncode == 2
    assert "pyarrow" in done.stderr and "distributed" not in done.stderr
    done = _run_without(("distributed",), code.replace("'--workers', '0', ", ""), tmp_path)
    assert done.returncode == 2 and "distributed" in done.stderr and "sarfe[batch]" in done.stderr
