"""Error lines that name the real rule or cause (review8 item 8): a corrupt matrix file, and each
kind of Craig–Bampton failure (not always 'the structure is not held')."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sarfe.case.read import CaseLoader, load_case
from sarfe.case.errors import CaseError

ROOT = Path(__file__).resolve().parents[2]


def lumped_with_mass(tmp_path, mass_file):
    data = yaml.load((ROOT / "cases" / "lumped_rattle.yaml").read_text(), Loader=CaseLoader)
    data["model"]["matrices"]["mass"] = mass_file
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_case(path)


@pytest.mark.parametrize("name, writer, fragment", [
    ("junk.npz", lambda p: p.write_text("not a zip"), "is not a NumPy .npy/.npz file"),
    ("objects.npy", lambda p: np.save(p, np.array([{"a": 1}], dtype=object), allow_pickle=True),
     "holds pickled Python objects, which sarfe does not load")])
def test_corrupt_matrix_file_names_the_problem_not_numpys_advice(tmp_path, name, writer, fragment):
    from sarfe.pipeline.checks.case_checks import check_case

    writer(tmp_path / name)
    with pytest.raises(CaseError) as error:
        check_case(lumped_with_mass(tmp_path, name), write=False)
    text = str(error.value)
    assert text.startswith(f"{tmp_path / 'case.yaml'}: model.matrices.mass: cannot read matrix "
                           f"file {tmp_path / name}: it ")
    assert fragment in text and "allow_pickle" not in text and "\n" not in text


def test_craig_bampton_failures_say_their_cause():
    """Singular K_ii (SuperLU's, numpy's or CHOLMOD's words) → not held, under model.fe.fixed;
    memory, ARPACK, anything else → that cause with the model size, under reduction."""
    from scipy.sparse.linalg import ArpackNoConvergence

    from sarfe.pipeline.model.fe_stage import reduction_error

    case = load_case(yaml.load((ROOT / "cases" / "rattle_rig.yaml").read_text(), Loader=CaseLoader))
    said = {kind: str(reduction_error(case, exc, 1200, 30)) for kind, exc in {
        "superlu": RuntimeError("Factor is exactly singular"),
        "numpy": np.linalg.LinAlgError("Singular matrix"),
        "cholmod": ValueError("matrix is not positive definite"),
        "memory": MemoryError(),
        "arpack": ArpackNoConvergence("ARPACK error -1: No convergence (361 iterations)", [], []),
        "other": ValueError("boundary_dofs must be distinct positions in [0, n)")}.items()}
    for kind in ("superlu", "numpy", "cholmod"):
        assert said[kind].startswith("model.fe.fixed: the structure is not held (singular "), said
    assert said["memory"].startswith("reduction: the Craig–Bampton reduction ran out of memory "
                                     "(1200 free DOFs, 30 boundary, 1170 interior)")
    assert said["arpack"].startswith("reduction: the eigensolver of the Craig–Bampton reduction "
                                     "did not converge")
    assert said["other"] == ("reduction: the Craig–Bampton reduction failed (1200 free DOFs, 30 "
                             "boundary, 1170 interior): ValueError: boundary_dofs must be distinct "
                             "positions in [0, n)")
    assert not any("held" in said[k] for k in ("memory", "arpack", "other"))
