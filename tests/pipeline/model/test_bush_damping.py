"""A deck spring's structural damping GE in a case: refused in one line naming the PBUSH (the
HBM model carries viscous D only) unless the deck gives PARAM,W4, which makes it the viscous
damping GE·K/W4 that enters the reduced damping like a CBUSH B."""
import numpy as np
import pytest
import yaml

from sarfe.case.errors import CaseError
from sarfe.pipeline import build_linear_model, load_case
from tests.pipeline.model.test_deck_model import SHEAR_DECK

# the two-quad mm-t-s plate of test_pipeline_deck (held along x = 0) with a grounded CBUSH
# (k3 = 5 N/mm, GE = 0.1) at GRID 6 in place of its shear panel
DECK = SHEAR_DECK.replace("CSHEAR,2,2,2,5,6,3\n", "CBUSH,7,9,6,,,,,0\n").replace(
    "PSHEAR,2,1,3.\n", "PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,GE,0.1\n")
GE, K3_N_M = 0.1, 5.0e3


def _case(tmp_path, param=""):
    (tmp_path / "bush.bdf").write_text(DECK.replace("ENDDATA", param + "ENDDATA"))
    data = {"name": "bush", "model": {"fe": {"deck": "bush.bdf", "units": "mm-t-s",
                                             "node_groups": {"tip": [6]}}},
            "excitation": {"forces": [{"group": "tip", "direction": "z", "force_N": 1.0}],
                           "frequency_hz": 10.0},
            "damping": {"modal_zeta": 0.01}, "reduction": {"mode_count": 4},
            "solver": {"harmonics": 1, "samples_per_period": 8, "error_estimate": False,
                       "stability": False}}
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(data))
    return load_case(data, base_dir=tmp_path)


def test_hysteretic_ge_is_refused_naming_the_pbush(tmp_path, capsys):
    from sarfe import cli

    case = _case(tmp_path)
    with pytest.raises(CaseError, match=r"PBUSH 9 \(CBUSH 7\) has structural damping GE = 0\.1"):
        build_linear_model(case)
    assert cli.main(["validate", str(tmp_path / "case.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "PBUSH 9" in err and "PARAM,W4" in err


def test_w4_makes_ge_the_viscous_damping_ge_k_over_w4(tmp_path):
    """W4 = 200 rad/s: the reduced damping on the boundary DOF uz(6) is GE·k3/W4 = 2.5 N·s/m,
    the only entry; the deck note says GE was applied that way."""
    w4 = 200.0
    stage = build_linear_model(_case(tmp_path, f"PARAM,W4,{w4}\n"))
    z = np.flatnonzero(stage.load_vectors[0])[0]
    assert stage.added_damping[z, z] == pytest.approx(GE * K3_N_M / w4, rel=1e-12)
    assert np.count_nonzero(np.abs(stage.added_damping) > 1e-12) == 1
    assert any("PARAM,W4" in note for note in stage.info["deck_notes"])
