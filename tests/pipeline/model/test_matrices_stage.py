"""The matrices path of the linear stage (model.matrices): a matrix file that cannot be read is
one line naming the problem (review8 item 8), not numpy's advice to unpickle."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sarfe.case.read import CaseLoader, load_case
from sarfe.case.errors import CaseError

ROOT = Path(__file__).resolve().parents[3]


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
