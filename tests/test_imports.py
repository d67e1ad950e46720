"""A run imports only what its case needs (issue 13, performance): starting ``sarfe`` and reading
a case load none of the heavy libraries; a solve that writes no figure, report or HDF5 file never
imports matplotlib, jinja2 or h5py (they load on first use, :mod:`sarfe.util.lazy`)."""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("matplotlib", "pandas", "dask", "distributed", "pyarrow", "numba", "pyfftw", "h5py",
         "jinja2", "pyvista", "vtk", "meshio", "gmsh", "pyNastran", "skfem", "scipy.optimize")


def _imported_after(code: str) -> list:
    """The HEAVY modules in sys.modules after running ``code`` in a fresh interpreter."""
    probe = code + f"\nimport sys, json\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    done = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True,
                          timeout=300, env={"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg",
                                            "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_cli_start_and_case_reading_import_no_heavy_library():
    assert _imported_after(
        "import sarfe.cli\nsarfe.cli.build_parser()\n"
        "from sarfe.pipeline import load_case, solve_case, results_table\n"
        "load_case('cases/lumped_rattle.yaml')") == []


def test_a_solve_without_figures_imports_no_plotting_library(tmp_path):
    code = (
        "from sarfe.pipeline import load_case, solve_case\n"
        "data = load_case('benchmarks/peer/nlvib03.yaml').data\n"
        "data['excitation'].pop('sweep')\n"
        "data['excitation']['frequency_hz'] = [0.12]\n"
        "data['solver'].update(harmonics=5, samples_per_period=64)\n"
        "data['output']['files'] = ['summary', 'table']\n"
        f"result = solve_case(data, output_dir={str(tmp_path / 'out')!r})\n"
        "assert result.summary['all_converged']")
    assert _imported_after(code) == []
    assert (tmp_path / "out" / "summary.json").exists()
