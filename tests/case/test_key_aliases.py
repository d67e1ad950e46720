"""'Did you mean' for a key written in other words (issue 31, item 6): ``mu`` is no close spelling
of ``friction_coefficient``, so close-spelling hints alone said nothing; a small table of other
words for keys (sarfe.case.messages.KEY_ALIASES) names the key a user means, in `sarfe validate`
and `sarfe solve` alike."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from sarfe.case.messages import KEY_ALIASES, suggestion
from sarfe.case.read import CaseLoader
from sarfe.case.schema import CASE_SCHEMA
from sarfe.cli import main

CASES = Path(__file__).resolve().parents[2] / "cases"


def schema_keys(node) -> set:
    keys = set()
    if isinstance(node, dict):
        keys |= set(node.get("properties", {}))
        for value in node.values():
            keys |= schema_keys(value)
    elif isinstance(node, list):
        for value in node:
            keys |= schema_keys(value)
    return keys


def rename(path, new):
    def change(data):
        for key in path[:-1]:
            data = data[key]
        data[new] = data.pop(path[-1])
    return change


EDITS = [
    ("squeak_rig", rename(("contacts", 0, "friction_coefficient"), "mu"),
     "contacts[0].mu: unknown key (did you mean 'friction_coefficient'?"),
    ("rattle_rig", rename(("model", "fe", "materials", "part_plate", "rho_kg_m3"), "density"),
     "model.fe.materials.part_plate.density: unknown key (did you mean 'rho_kg_m3'?"),
    ("rattle_rig", rename(("model", "fe", "materials", "part_beam", "E_Pa"), "E"),
     "model.fe.materials.part_beam.E: unknown key (did you mean 'E_Pa'?"),
    ("rattle_rig", rename(("contacts", 0, "normal_stiffness_N_m"), "k"),
     "contacts[0].k: unknown key (did you mean 'normal_stiffness_N_m'?"),
    ("rattle_rig", rename(("solver", "harmonics"), "H"),
     "solver.H: unknown key (did you mean 'harmonics'?"),
    ("lumped_rattle", rename(("contacts", 0, "gap_m"), "clearance"),
     "contacts[0].clearance: unknown key (did you mean 'gap_m'?"),
]


@pytest.mark.parametrize("name, change, words", EDITS,
                         ids=["mu", "density", "E", "k", "H", "clearance"])
def test_other_words_are_suggested_in_validate_and_solve(tmp_path, capsys, name, change, words):
    data = yaml.load((CASES / f"{name}.yaml").read_text(), Loader=CaseLoader)
    change(data)
    case = tmp_path / "case.yaml"
    case.write_text(yaml.safe_dump(data, sort_keys=False))
    for command in ("validate", "solve"):
        code = main([command, str(case), "--output", str(tmp_path / "out"), "--quiet"])
        lines = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(lines) == 1, lines
        assert words in lines[0], lines[0]
    assert not (tmp_path / "out").exists()


def test_every_alias_names_a_key_of_the_schema():
    keys = schema_keys(CASE_SCHEMA)
    for alias, candidates in KEY_ALIASES.items():
        assert alias == alias.lower(), alias
        assert set(candidates) <= keys, (alias, candidates)


def test_the_alias_only_where_its_key_is_allowed():
    """An alias names only a key of the mapping at hand; else case and spelling decide."""
    assert suggestion("mu", ["gap_m", "friction_coefficient"]) == "friction_coefficient"
    assert suggestion("MU", ["friction_coefficient"]) == "friction_coefficient"
    assert suggestion("mu", ["harmonics", "samples_per_period"]) is None
    assert suggestion("amplitude", ["amplitude_m_s2", "direction"]) == "amplitude_m_s2"
    assert suggestion("amplitude", ["force_N", "group"]) == "force_N"
    assert suggestion("e_pa", ["E_Pa", "nu"]) == "E_Pa"
    assert suggestion("gap_mm", ["gap_m", "type"]) == "gap_m"
