"""Deck springs turned into contacts (``from_elements``) keep or refuse what the contact law has
no place for, never drop it: a CBUSH dashpot B stays in the linear model as a damper parallel to
the contact (checked against the closed-form 1-DOF resonance amplitude F/(c ω) through HBM with
the contact open all the time); a rotational stiffness K4–K6 or a structural damping GE is
refused in one line naming the element, at validate and at solve."""
import math

import numpy as np
import pytest
import yaml

from sarfe.case.errors import CaseError
from sarfe.pipeline import build_linear_model, load_case, solve_case
from tests.pipeline.model.test_deck_model import SHEAR_DECK

# the two-quad mm-t-s plate of test_pipeline_deck (held along x = 0, the ERP surface) beside a
# 1-DOF oscillator at GRID 10: a CONM2 of 1 kg on grounded CELAS2 springs of 10 N/mm along x, y
# and z (rotations held; x, y unforced), and the grounded CBUSH 7 (K3 = 5 N/mm, dashpot B3)
# that becomes the contact
OSCILLATOR = ("GRID,10,,400.,0.,0.\nCONM2,20,10,,1.e-3\nCELAS2,21,10.,10,3\n"
              "CELAS2,22,10.,10,1\nCELAS2,23,10.,10,2\nCBUSH,7,9,10,,,,,0\nSPC1,1,456,10\n")
M_KG, K_N_M = 1.0, 1.0e4
OMEGA_N = math.sqrt(K_N_M / M_KG)                           # 100 rad/s


def _deck(bush):
    return SHEAR_DECK.replace("CSHEAR,2,2,2,5,6,3\n", OSCILLATOR).replace(
        "PSHEAR,2,1,3.\n", bush)


def _case(tmp_path, bush, contact=True):
    (tmp_path / "bush.bdf").write_text(_deck(bush))
    data = {"name": "bush", "model": {"fe": {"deck": "bush.bdf", "units": "mm-t-s",
                                             "node_groups": {"mass": [10]}}},
            "excitation": {"forces": [{"group": "mass", "direction": "z", "force_N": 1.0}],
                           "frequency_hz": OMEGA_N / (2 * math.pi)},
            "damping": {"modal_zeta": 0.0}, "reduction": {"mode_count": 4},
            "solver": {"harmonics": 1, "samples_per_period": 16, "error_estimate": False,
                       "stability": False}}
    if contact:    # a rattle stop 10 mm away: never reached by the ~0.5 mm motion
        data["contacts"] = [{"name": "stop", "type": "rattle", "from_elements": [7],
                             "gap_m": 0.01}]
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(data))
    return load_case(data, base_dir=tmp_path)


@pytest.mark.parametrize("b_n_s_mm", [0.02, 0.05])
def test_cbush_dashpot_stays_parallel_to_the_open_contact(tmp_path, b_n_s_mm):
    """m ü + c u̇ + k u = F at ω = √(k/m): |u| = F/(c ω) with c = B3 of the contact's CBUSH
    (20 / 50 N·s/m → 0.5 / 0.2 mm), the contact open throughout (its stiffness K3 gone)."""
    c = b_n_s_mm * 1e3
    bush = f"PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,B,0.,0.,{b_n_s_mm},0.,0.,0.\n"
    case = _case(tmp_path, bush)
    stage = build_linear_model(case)
    z = int(np.flatnonzero(stage.load_vectors[0])[0])            # the boundary DOF uz(10)
    assert stage.added_damping[z, z] == pytest.approx(c, rel=1e-12)
    assert np.count_nonzero(np.abs(stage.added_damping) > 1e-12) == 1
    result = solve_case(case, linear_stage=stage, write=False)
    point = result.summary["points"][0]
    assert point["converged"] and point["contacts"][0]["open_fraction"] == 1.0
    u = np.asarray(result.solutions[0].displacement)[1:3, z]     # cos, sin of harmonic 1 [m]
    assert np.hypot(*u) == pytest.approx(1.0 / (c * OMEGA_N), rel=1e-6)
    # the damping is the dashpot's: u lags F by 90° (the spring K3 left with the contact)
    assert abs(u[0]) < 1e-6 * abs(u[1])


def test_contact_without_dashpot_leaves_no_element_behind(tmp_path):
    """B = 0: nothing to keep — the CBUSH leaves the linear model entirely (no added damping)."""
    stage = build_linear_model(_case(tmp_path, "PBUSH,9,K,0.,0.,5.,0.,0.,0.\n"))
    assert stage.added_damping is None


@pytest.mark.parametrize("bush, expected", [
    ("PBUSH,9,K,0.,0.,5.,0.,2000.,0.\n",
     r"PBUSH 9 \(CBUSH 7\) has rotational stiffness K5 = 2 N·m/rad, which a contact cannot "
     r"carry: set K4–K6 to 0"),
    ("PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,GE,0.1\n",
     r"PBUSH 9 \(CBUSH 7\) has structural damping GE = 0\.1, which a contact cannot carry: "
     r"add PARAM,W4"),
])
def test_what_a_contact_cannot_carry_is_refused_in_one_line(tmp_path, capsys, bush, expected):
    from sarfe import cli

    case = _case(tmp_path, bush)
    with pytest.raises(CaseError, match=r"contacts\[0\]\.from_elements: " + expected):
        build_linear_model(case)
    path = str(tmp_path / "case.yaml")
    for argv in (["validate", path], ["solve", path, "--output", str(tmp_path / "out"), "--quiet"]):
        assert cli.main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "CBUSH 7" in err and "Traceback" not in err, err


def test_w4_makes_ge_a_dashpot_parallel_to_the_contact(tmp_path):
    """With PARAM,W4 the GE of the contact's CBUSH is read as B = GE·K/W4 (Nastran's transient
    rule) and kept like a B: GE·K3/W4 = 0.1 · 5000 / 100 = 5 N·s/m on uz(10)."""
    bush = "PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,GE,0.1\nPARAM,W4,100.\n"
    stage = build_linear_model(_case(tmp_path, bush))
    z = int(np.flatnonzero(stage.load_vectors[0])[0])
    assert stage.added_damping[z, z] == pytest.approx(0.1 * 5.0e3 / 100.0, rel=1e-12)


def test_rattle_contact_says_the_cross_axis_stiffness_it_drops(tmp_path, capsys):
    """A rattle contact acts along the spring axis only: the CBUSH's K1, K2 (mean 2.5 N/mm across
    the K3 axis) leave the model, and validate and solve say so in one warning line (a squeak
    contact keeps it as its stick stiffness: no warning)."""
    from sarfe import cli
    from sarfe.pipeline.checks.case_checks import check_case

    case = _case(tmp_path, "PBUSH,9,K,2.,3.,5.,0.,0.,0.\n")
    (line,) = [w for w in check_case(case, write=False).warnings if "tangential" in w]
    assert line.startswith("contacts[0] (stop): a rattle contact has no tangential stiffness")
    assert "2500 N/m" in line and "PBUSH 9 (CBUSH 7)" in line
    assert cli.main(["validate", str(tmp_path / "case.yaml")]) == 0
    assert line in capsys.readouterr().err
    result = solve_case(case, write=False)
    assert line in result.summary["warnings"]


def test_a_mass_hung_on_a_contact_dashpot_alone_is_not_held(tmp_path):
    """The CBUSH that becomes the contact keeps its dashpot B, but a dashpot holds nothing
    statically: with the grounded CELAS2 springs removed and the CBUSH run from GRID 10 to the
    plate, the 1 kg at GRID 10 hangs on the contact alone, so the check names it free (before: the kept damper counted as a joint and
    the singular stiffness went on to the factorization)."""
    bush = "PBUSH,9,K,0.,0.,5.,0.,0.,0.\n,,B,0.,0.,0.02,0.,0.,0.\n"
    case = _case(tmp_path, bush)
    deck = (tmp_path / "bush.bdf").read_text()
    (tmp_path / "bush.bdf").write_text("".join(   # CBUSH 7 from GRID 10 to the plate's GRID 5
        line.replace("CBUSH,7,9,10,", "CBUSH,7,9,10,5") + "\n"
        for line in deck.splitlines() if not line.startswith("CELAS2")))
    with pytest.raises(CaseError, match=r"a part of 1 nodes \(GRIDs 10…10\) is free in 3 "
                                        r"rigid-body motions \(translation x, translation y, "
                                        r"translation z\)"):
        build_linear_model(case)
