"""What engineers' decks carry and the mistakes they hold, each in validate (check_mesh) and in
solve (the linear stage it builds first) — issue 32 items 1, 3 and 7 (deck part):

- a deck part without density (``fixed: ["*"]``: tests/case/test_validate_parity.py), a force
  on an RBE2 dependent GRID
  (pyNastran's 0012_flutter), ν = 0.5 and a negative E: refused alike by both, one line;
- SPOINT / LSEQ / TLOAD2 named in ignore_cards, Abaqus *NODAL THICKNESS and a '>**' preamble,
  the Goland wing (a real 0.0006 ft web, ρ ≈ 0 with its mass in CONM2s) with explicit units:
  accepted by both (warnings, not errors).
"""
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.errors import CaseError
from sarfe.pipeline import build_linear_model, check_mesh, load_case, solve_case
from tests.pipeline.model.test_deck_checks import DECK, shipped_case
from tests.pipeline.model.test_deck_model import T_MM, plate_inp, write_case

PUBLIC = Path(__file__).resolve().parents[2] / "data" / "decks"


def both(case):
    """Run validate, then the linear stage of solve; return validate's info."""
    info = check_mesh(case)
    build_linear_model(case)
    return info


def refused_alike(case, pattern):
    """validate and solve raise the same one-line CaseError matching ``pattern``."""
    messages = []
    for run in (check_mesh, build_linear_model):
        with pytest.raises(CaseError, match=pattern) as info:
            run(case)
        messages.append(str(info.value))
    assert messages[0] == messages[1] and "\n" not in messages[0]
    return messages[0]


def _material_card(text, mid, first=None, second=None):
    """The shipped deck with MAT1 ``mid``'s large-field E (``first``) / continuation (``second``)
    line replaced."""
    lines = text.splitlines()
    row = next(i for i, line in enumerate(lines) if line.startswith(f"MAT1*{mid:>19}"))
    if first is not None:
        lines[row] = first
    if second is not None:
        lines[row + 1] = second
    return "\n".join(lines) + "\n"


def test_part_without_density_is_refused_by_validate_and_solve(tmp_path):
    """MAT1 2 (the steel striker) without ρ: its part has K and no M (was: validate passed,
    solve 'internal error: LinAlgError')."""
    text = _material_card(DECK.read_text(), 2, second="*       " + " " * 16)
    message = refused_alike(shipped_case(tmp_path, deck_text=text), r"model\.fe\.deck: a part of")
    assert "has no mass (property 2: its material has no density ρ)" in message


def _flutter_case(tmp_path, grid):
    data = {"name": "flutter0012",
            "model": {"fe": {"deck": str(PUBLIC / "0012_flutter.bdf"), "units": "SI",
                             "ignore_cards": ["AERO", "AEROS", "CAERO1", "FLFACT", "FLUTTER",
                                              "MDLPRM", "MKAERO1", "PAERO1", "SPLINE1"],
                             "node_groups": {"load": [grid]}}},
            "damping": {"modal_zeta": 0.02},
            "excitation": {"forces": [{"group": "load", "direction": "z", "force_N": 1.0}],
                           "frequency_hz": [5.0]},
            "reduction": {"mode_count": 4}}
    return load_case(data, base_dir=tmp_path)


def test_force_on_a_dependent_grid_is_named_alike_by_validate_and_solve(tmp_path):
    """pyNastran's 0012_flutter: GRID 30 follows GRID 117 through an RBE2; a force there is
    refused by both with the force's key (was: validate passed, solve blamed 'contacts')."""
    refused_alike(_flutter_case(tmp_path, 30),
                  r"excitation\.forces\[0\]\.group: GRID 30 is a dependent node of a rigid element")
    both(_flutter_case(tmp_path, 117))       # the RBE2's independent GRID is fine


def test_support_on_a_dependent_grid_is_refused_alike_by_validate_and_solve(tmp_path):
    """fixed: [a group of GRID 31] on the flutter deck: GRID 31 is an RBE2 dependent (was found
    at assembly only, after validate passed)."""
    case = _flutter_case(tmp_path, 117)
    data = dict(case.data)
    data["model"] = {"fe": {**case.data["model"]["fe"],
                            "node_groups": {"load": [117], "edge": [31]}, "fixed": ["edge"]}}
    refused_alike(load_case(data, base_dir=tmp_path),
                  r"model\.fe\.supports: a support holds GRID 31 component 1, which a rigid "
                  r"element \(RBE2/RBE3\) makes dependent")


@pytest.mark.parametrize("old, new, pattern", [
    # ν = 0.5: the case's own materials: nu has the bound ν < 0.5; the deck has it too
    ("3.7000000000E-01", "5.0000000000E-01", r"MAT1 1: ν = 0\.5 is outside -1 < ν < 0\.5"),
    # E < 0: no unit system makes it plausible — no unit advice
    ("12.2000000000E+03", "1-2.200000000E+03", r"MAT1 1: E = -2\.2e\+09 Pa must be > 0"),
])
def test_material_bounds_refused_without_unit_advice(tmp_path, old, new, pattern):
    text = DECK.read_text()
    row = next(line for line in text.splitlines() if line.startswith("MAT1*                  1"))
    text = _material_card(text, 1, first=row.replace(old, new))
    message = refused_alike(shipped_case(tmp_path, deck_text=text), pattern)
    assert "model.fe.deck" in message
    assert "looks like" not in message and "mm-kg-s" not in message


def test_spoint_lseq_tload2_in_ignore_cards_pass_validate_and_solve(tmp_path):
    """SPOINT (was an IndexError in solve after a clean validate) and LSEQ (was an
    AttributeError in the reader) listed in ignore_cards: ignored cleanly by both."""
    text = DECK.read_text().replace("ENDDATA", "SPOINT  9001\nFORCE,12,1,,2.,0.,0.,1.\n"
                                    "LSEQ,10,10,12\nTLOAD2,10,10,,,0.,5.,10.\nENDDATA")
    case = shipped_case(tmp_path, deck_text=text)
    with pytest.raises(CaseError, match=r"3 card types sarfe does not model: LSEQ \(1, first at "
                                        r".*deck\.bdf:\d+\), SPOINT \(1, first at .*\), TLOAD2"):
        check_mesh(case)
    data = dict(case.data)
    data["model"] = {"fe": {**case.data["model"]["fe"],
                            "ignore_cards": ["SPOINT", "LSEQ", "TLOAD2"]}}
    case = load_case(data, base_dir=tmp_path)
    info = both(case)
    assert info["ignored_cards"] == {"LSEQ": 1, "SPOINT": 1, "TLOAD2": 1}
    assert info["nodes"] == 376


def test_abaqus_nodal_thickness_and_preamble_are_read(tmp_path):
    """*SHELL SECTION, NODAL THICKNESS with every node at 2.5 mm and a '>**' first line: the
    same plate (mass ρ t A) as the section thickness 2.5 mm, in validate and solve."""
    inp = plate_inp()
    nodes = inp.split("*NODE\n")[1].split("*")[0].strip().splitlines()
    nodal = "\n".join(f"{line.split(',')[0]}, {T_MM}" for line in nodes)
    inp = (">**\n" + inp).replace(
        f"*SHELL SECTION, ELSET=plate, MATERIAL=PP\n{T_MM}",
        f"*SHELL SECTION, ELSET=plate, MATERIAL=PP, NODAL THICKNESS\n1.0\n*NODAL THICKNESS\n{nodal}")
    reference = build_linear_model(load_case(write_case(tmp_path, plate_inp()), base_dir=tmp_path))
    case = load_case(write_case(tmp_path, inp), base_dir=tmp_path)
    both(case)
    stage = build_linear_model(case)
    assert stage.info["total_mass_kg"] == pytest.approx(reference.info["total_mass_kg"], rel=1e-12)


def test_goland_with_its_units_is_kept_with_warnings(tmp_path):
    """The Goland wing box in ft-slug-s (PSHELL 2: a 0.0006 ft web, MAT1 ρ = 1e-4 slug/ft³ with
    the mass in CONM2s): explicit units → warnings with the evidence, the model is built; left
    at the default SI it is refused (no unit system makes ρ plausible: say the units)."""
    data = {"name": "goland",
            "model": {"fe": {"deck": str(PUBLIC / "goland_final_test.bdf"), "units": "ft-lbf-s",
                             "ignore_cards": ["DCONADD", "DCONSTR", "DESVAR", "DRESP1",
                                              "DSCREEN", "DVGRID", "DVPREL1"]}},
            "damping": {"modal_zeta": 0.02},
            "excitation": {"base_acceleration": {"direction": "z", "amplitude_m_s2": 1.0},
                           "frequency_hz": [2.0]},
            "reduction": {"mode_count": 4}}
    info = both(load_case(data, base_dir=tmp_path))
    warnings = " ".join(info["warnings"])
    assert "PSHELL 2: thickness 0.000183 m with units: ft-lbf-s — below 0.0001" in warnings
    assert "MAT1 1: ρ = 0.05154 kg/m³ with units: ft-lbf-s" in warnings
    assert len(info["warnings"]) == len(set(info["warnings"]))
    del data["model"]["fe"]["units"]
    with pytest.raises(CaseError, match=r"model\.fe\.units: .*no unit system makes the deck "
                                        r"plausible.*units: SI to keep SI"):
        check_mesh(load_case(data, base_dir=tmp_path))


def test_goland_first_mode_through_the_pipeline_matches_msc(tmp_path):
    """The deck path's own modes (supports = SPCADD 800) against MSC's stored 1.981382 Hz."""
    from sarfe.fe.deck_assembly import assemble_deck, support_dofs
    from sarfe.mesh.formats.nastran import read_nastran
    from tests.mesh.test_public_decks import deck_frequencies

    deck = read_nastran(PUBLIC / "goland_final_test.bdf", units="ft-lbf-s")
    system = assemble_deck(deck)
    hz = deck_frequencies(system, support_dofs(system, deck, 800), 1)
    assert hz[0] == pytest.approx(1.981382, rel=1e-3)
    assert np.isfinite(hz).all()


def test_cquadr_and_pbarl_decks_pass_validate_and_solve(tmp_path):
    """The shipped deck with every CQUAD4 written as CQUADR gives the same linear stage (mass,
    modes); a CBAR/PBARL ROD (r = 2 mm, 150 mm, steel MAT1 2) added between GRIDs 1 and 2 adds
    its ρ π r² L to the mass, through validate and solve alike."""
    reference = build_linear_model(shipped_case(tmp_path))
    text = DECK.read_text().replace("CQUAD4*", "CQUADR*").replace("\nCQUAD4 ", "\nCQUADR ")
    (tmp_path / "r").mkdir()
    case = shipped_case(tmp_path / "r", deck_text=text)
    both(case)
    stage = build_linear_model(case)
    assert stage.info["total_mass_kg"] == pytest.approx(reference.info["total_mass_kg"], rel=1e-12)
    assert np.allclose(stage.mode_frequencies_hz, reference.mode_frequencies_hz, rtol=1e-10)
    assert len(stage.mode_frequencies_hz) > 0
    bar = "CBAR,9001,9001,1,2,0.,0.,1.\nPBARL,9001,2,,ROD\n,2.\nENDDATA"
    (tmp_path / "b").mkdir()
    case = shipped_case(tmp_path / "b", deck_text=DECK.read_text().replace("ENDDATA", bar))
    both(case)
    stage = build_linear_model(case)
    added = 7.85e-9 * 1e12 * np.pi * 2e-3**2 * 0.150      # t/mm³ → kg/m³; r = 2 mm; L = 150 mm
    assert stage.info["total_mass_kg"] == pytest.approx(reference.info["total_mass_kg"] + added,
                                                        rel=1e-9)


def test_force_on_a_grid_without_stiffness_is_refused_alike(tmp_path):
    """A force on a GRID no element uses: solve finds it at assembly (no stiffness); validate
    assembles too and says the same."""
    text = DECK.read_text().replace("ENDDATA", "GRID,9999,,0.,0.,50.\nENDDATA")
    case = shipped_case(tmp_path, deck_text=text)
    data = dict(case.data)
    data["model"] = {"fe": {**case.data["model"]["fe"], "node_groups": {"loose": [9999]}}}
    data["excitation"] = {**case.data["excitation"],
                          "forces": [{"group": "loose", "direction": "z", "force_N": 0.05}]}
    case = load_case(data, base_dir=tmp_path)
    # validate and solve (which checks the case first) alike; the linear stage alone too
    for run in (check_mesh, lambda c: solve_case(c, write=False)):
        with pytest.raises(CaseError, match=r"excitation\.forces\[0\]\.group: the force on "
                                            r"group loose acts on no free DOF"):
            run(case)
    with pytest.raises(CaseError, match=r"excitation\.forces\[0\]\.group: GRID 9999 is a "
                                        r"dependent node of a rigid element \(RBE2/RBE3\) or has "
                                        r"no stiffness"):
        build_linear_model(case)
