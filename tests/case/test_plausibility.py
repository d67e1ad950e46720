"""Numbers the schema cannot judge (sarfe.case.plausibility): a non-finite value anywhere, and
values that betray a unit mistake — each one line naming the key, its unit and the line."""
import math
from pathlib import Path

import pytest

from sarfe.case.errors import CaseError
from sarfe.case.plausibility import AUDIBLE_LIMIT_HZ, MAX_MESH_SIZE_M, MIN_E_PA, MIN_RHO_KG_M3
from sarfe.case.read import load_case, read_yaml

CASES = Path(__file__).resolve().parents[2] / "cases"


def _edited(name, edit):
    data, _ = read_yaml(CASES / f"{name}.yaml")
    edit(data)
    return data


@pytest.mark.parametrize("name, edit, where, words", [
    ("rattle_rig", lambda d: d["model"]["fe"]["materials"]["part_plate"].update(E_Pa=2200.0),
     "model.fe.materials.part_plate.E_Pa", "given in MPa or GPa? E_Pa is in pascals"),
    ("rattle_rig", lambda d: d["model"]["fe"]["materials"]["part_beam"].update(rho_kg_m3=7.85e-6),
     "model.fe.materials.part_beam.rho_kg_m3", "lighter than air — given in t/mm³"),
    ("rattle_rig", lambda d: d["model"]["fe"]["generator"].update(mesh_size_m=10.0),
     "model.fe.generator.mesh_size_m", "given in mm? mesh_size_m is in metres"),
    ("rattle_rig", lambda d: d["excitation"].update(sweep={"start_hz": 24.0, "end_hz": 4.0e4}),
     "excitation.sweep", "above the audible range"),
    ("lumped_rattle", lambda d: d["excitation"]["base_acceleration"].update(amplitude_m_s2=-3.0),
     "excitation.base_acceleration.amplitude_m_s2", "must be >= 0 (an amplitude)"),
    ("lumped_rattle", lambda d: d["contacts"][0].update(gap_m=math.nan),
     "contacts[0].gap_m", "must be a finite number, got .nan"),
])
def test_unit_mistakes_and_non_finite_numbers_are_one_line(name, edit, where, words):
    with pytest.raises(CaseError) as error:
        load_case(_edited(name, edit), base_dir=CASES)
    text = str(error.value)
    assert text.startswith(f"{where}: ") and words in text and "\n" not in text


def test_bounds_are_the_units_of_a_trim_part():
    """The bounds sit between a plausible value in SI and the same value in the usual wrong unit:
    ABS in MPa (2200) < E bound < ABS in Pa; steel in t/mm³ < ρ bound < polymer foam in kg/m³;
    a 1 m element is no trim part's; 20 kHz is the top of hearing."""
    assert 2.2e3 < MIN_E_PA < 2.2e9 and 7.85e-9 < MIN_RHO_KG_M3 < 30.0
    assert MAX_MESH_SIZE_M == 1.0 and AUDIBLE_LIMIT_HZ == 20e3
