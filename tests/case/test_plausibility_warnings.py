"""Values a case accepts but no squeak-and-rattle input has (issue 32, item 8): one warning line
each, from `sarfe validate` and `sarfe solve` alike, and kept in summary.json ``warnings``
(sarfe.case.plausibility.plausibility_warnings). Before, each was accepted without a word.

- μ = 35 (a percentage for 0.35): above MAX_FRICTION_COEFFICIENT = 2;
- a base acceleration of 10 000 m/s² (1020 g): above MAX_BASE_ACCELERATION_M_S2 = 50 g;
- a contact stiffness given in N/mm (1000 for 1e6 N/m) under a 20 N preload: the penalty spring
  pressed 20 mm into the part, above MAX_PRELOAD_OVERCLOSURE_M = 1 mm.

The bounds sit between the values of practice and the usual slips, as the unit bounds do.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from small_cases import coarse_rig

from sarfe.case.plausibility import (MAX_BASE_ACCELERATION_M_S2, MAX_FRICTION_COEFFICIENT,
                                     MAX_PRELOAD_OVERCLOSURE_M, POISSON_RANGE,
                                     STANDARD_GRAVITY_M_S2, plausibility_warnings)
from sarfe.case.errors import CaseError
from sarfe.case.read import CaseLoader, load_case
from sarfe.case.schema import MATERIAL
from sarfe.cli import main
from sarfe.pipeline.checks.held_checks import contact_warnings

CASES = Path(__file__).resolve().parents[2] / "cases"


def quick_lumped() -> dict:
    """cases/lumped_rattle.yaml at one frequency, H = 3 (solves in about a second)."""
    data = yaml.load((CASES / "lumped_rattle.yaml").read_text(), Loader=CaseLoader)
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [45.0]
    data["solver"] = {"harmonics": 3, "samples_per_period": 32, "stability": False,
                      "error_estimate": False, "workers": 1}
    data["output"] = {"files": ["summary"]}
    return data


def mu_in_percent(data):
    data["contacts"][1]["friction_coefficient"] = 35.0


def shock_input(data):
    data["excitation"]["base_acceleration"]["amplitude_m_s2"] = 1.0e4


def stiffness_in_N_per_mm(data):
    contact = data["contacts"][0]
    contact.pop("gap_m")
    contact.update(preload_N=20.0, normal_stiffness_N_m=1000.0)


@pytest.mark.parametrize("change, words", [
    (mu_in_percent, ["contacts[1] (seal): friction_coefficient = 35 is above 2",
                     "a ratio, not a percentage"]),
    (shock_input, ["excitation.base_acceleration.amplitude_m_s2 = 10000 m/s² is 1.02e+03 g",
                   "above the 50 g"]),
    (stiffness_in_N_per_mm, ["contacts[0] (panel_bracket): preload_N / normal_stiffness_N_m = "
                             "20 N / 1000 N/m presses the contact 20 mm into the part",
                             "1000 N/mm = 1e6 N/m"]),
], ids=["mu-35", "base-10000", "preload-overclosure-20mm"])
def test_warned_in_validate_and_solve(tmp_path, capsys, change, words):
    data = quick_lumped()
    change(data)
    case = tmp_path / "case.yaml"
    case.write_text(yaml.safe_dump(data, sort_keys=False))
    warned = {}
    for command in ("validate", "solve"):
        code = main([command, str(case), "--output", str(tmp_path / "out"), "--quiet"])
        lines = [line for line in capsys.readouterr().err.splitlines()
                 if line.startswith("sarfe: warning: ")]
        assert code in (0, 3), lines            # accepted (a shock may leave a point unsolved)
        assert len(lines) == 1, lines
        for word in words:
            assert word in lines[0], lines[0]
        warned[command] = lines[0]
    assert warned["validate"] == warned["solve"]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert warned["solve"].removeprefix("sarfe: warning: ") in summary["warnings"]


def test_shipped_cases_raise_no_plausibility_warning():
    for path in sorted(CASES.glob("*.yaml")):
        assert plausibility_warnings(load_case(path).config) == [], path


def test_the_bounds_and_their_sources():
    """Each bound between practice and the usual slip: μ 0.1 … 1.5 < 2 < 35 (a percentage);
    5 g of a shaker < 50 g < 10 000 m/s²; 0.1 mm of a penalty spring < 1 mm < 20 mm (N/mm). The
    schema's ν range is the shared POISSON_RANGE (the deck reader uses it too)."""
    assert 1.5 < MAX_FRICTION_COEFFICIENT < 35
    assert 5 * STANDARD_GRAVITY_M_S2 < MAX_BASE_ACCELERATION_M_S2 == 50 * STANDARD_GRAVITY_M_S2 < 1e4
    assert 1e-4 < MAX_PRELOAD_OVERCLOSURE_M < 20e-3
    nu = MATERIAL["properties"]["nu"]
    assert (nu["exclusiveMinimum"], nu["exclusiveMaximum"]) == POISSON_RANGE == (-1.0, 0.5)


def test_a_node_pair_in_two_contacts_is_warned_in_validate_and_solve(tmp_path, capsys,
                                                                    monkeypatch):
    """The same node pair in two contacts (here the rig's striker pair, once more with the groups
    swapped) is said in one line by validate and solve: both laws act there. Not refused — a
    side stop (another normal) or a progressive stop (another gap) is modelled that way; a pair
    listed twice in one contact is refused (tests/case/test_validate_parity.py)."""
    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path / "cache"))
    text = coarse_rig([30.0], "{harmonics: 3, samples_per_period: 32, stability: false, "
                              "error_estimate: false, workers: 1}", "output: {files: [summary]}")
    text = text.replace("excitation:", "  - {name: tip_again, type: rattle, between: "
                        "[contact_tip_b, contact_tip_a], gap_m: 0.5e-3, pairing_tolerance_m: 1.0e-3, "
                        "normal_stiffness_N_m: 2.0e5}\nexcitation:")
    case = tmp_path / "case.yaml"
    case.write_text(text)
    seen = []
    for command in ("validate", "solve"):
        code = main([command, str(case), "--output", str(tmp_path / "out"), "--quiet"])
        lines = [line for line in capsys.readouterr().err.splitlines()
                 if line.startswith("sarfe: warning: ")]
        assert code == 0 and len(lines) == 1, lines
        assert lines[0].startswith("sarfe: warning: contacts[1] (tip_again): 1 node pair(s) also "
                                   "in contacts[0] (tip), e.g. node pair "), lines[0]
        assert "their forces add" in lines[0]
        seen.append(lines[0])
    assert seen[0] == seen[1]


def test_a_contact_partly_held_is_warned(tmp_path):
    """Pairs held on both sides (or one held node against ground) do nothing: a contact with some
    such pairs is a warning counting them, one with all a CaseError (the parity test refuses the
    latter through validate and solve)."""
    case = load_case(CASES / "rattle_rig.yaml")
    held = np.array([True, True, False, True, False, False])
    paired = {"tip": (np.array([0, 1, 2]), np.array([3, -1, 5]))}
    warnings = contact_warnings(case, paired, held, "model.fe.fixed")
    assert warnings == ["contacts[0] (tip): 2 of 3 node pairs are held on both sides (e.g. node "
                        "pair 0–3, by model.fe.fixed) and do nothing"]
    with pytest.raises(CaseError, match="every node pair of this contact is held on both sides"):
        contact_warnings(case, {"tip": (np.array([0, 1]), np.array([3, -1]))}, held, "x")
