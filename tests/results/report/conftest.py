"""A small lumped rattle + squeak case (the shipped lumped_rattle at five listed frequencies)."""
import copy
import pathlib

import pytest

from sarfe.case.read import read_yaml

CASES = pathlib.Path(__file__).parents[3] / "cases"


@pytest.fixture(scope="session")
def lumped_case_data():
    data, _ = read_yaml(CASES / "lumped_rattle.yaml")
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [40.0, 50.0, 60.0, 66.0, 75.0]
    data["solver"]["error_estimate"] = False
    data["output"] = {"target_dba": 85.0}
    return data


@pytest.fixture
def lumped_case(lumped_case_data):
    return copy.deepcopy(lumped_case_data)
