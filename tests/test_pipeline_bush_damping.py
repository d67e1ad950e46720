"""A deck spring's structural damping GE in a case: refused in one line naming the PBUSH (the
HBM model carries viscous D only) unless the deck gives PARAM,W4, which makes it the viscous
damping GE·K/W4 that enters the reduced damping like a CBUSH B."""
import numpy as np
import pytest
import yaml

from sarfe.io.errors import CaseError
from sarfe.pipeline import build_linear_model, load_case

# a two-quad plate in mm-t-s held along x = 0, a grounded CBUSH (k3 = 5 N/mm, GE) at GRID 6
DECK = """BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,100.,0.,0.
GRID,3,,100.,100.,0.
GRID,4,,0.,100.,0.
GRID,5,,200.,0.,0.
GRID,6,,200.,100.,0.
CQUAD4,1,1,1,2,3,4
CQUAD4,3,1,2,5,6,3
PSHELL,1,1,2.,1
MAT1,1,2000.,,0.3,1.e-9
CBUSH,7,9,6,,,,,0
PBUSH,9,K,0.,0.,5.,0.,0.,0.
,,GE,0.1
SPC1,1,123456,1,4
{param}ENDDATA
"""
GE, K3_N_M = 0.1, 5.0e3


def _case(tmp_path, param=""):
    (tmp_path / "bush.bdf").write_text(DECK.format(param=param))
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
