"""A deck read with the wrong ``model.fe.units`` is refused at validate (and solve) with one line
naming model.fe.units, the deck card and its line, the value in SI, the rule and the unit
system the deck looks like — the bounds of the case keys (E ≥ 1e5 Pa, ρ ≥ 1 kg/m³, a span of
5 mm … 20 m, 1e-4 L < t < 0.1 L) applied to the deck's own MAT1/PSHELL/GRID values.

The shipped rattle_rig_deck is in mm-t-s: ABS has E = 2200 MPa, ρ = 1.05e-9 t/mm³, T = 2.5 mm
on a 150 × 150 mm plate. Read as SI, E is 2200 Pa (a gel is ~1e4 Pa); read as in-lbf-s,
ρ = 1.05e-9 lbf·s²/in⁴ = 0.011 kg/m³ (air is 1.2)."""
from pathlib import Path

import pytest

from sarfe.case.errors import CaseError
from sarfe.pipeline import load_case
from sarfe.pipeline.checks.case_checks import check_case

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "cases" / "rattle_rig_deck.yaml"
DECK = ROOT / "meshes" / "rattle_rig_deck.bdf"


def deck_line(text: str, card: str, ident: int) -> int:
    """Line number (1-based) of a large-field card ``card* <id>`` of the shipped deck."""
    for number, line in enumerate(text.splitlines(), start=1):
        if line.startswith(card + "*") and line[8:24].strip() == str(ident):
            return number
    raise AssertionError(f"{card} {ident} not in the deck")


def shipped_case(tmp_path, units="mm-t-s", deck_text=None):
    """The shipped case file with its deck (or a changed copy) and ``units`` replaced (None:
    the key left out, i.e. the default SI)."""
    deck = DECK
    if deck_text is not None:
        deck = tmp_path / "deck.bdf"
        deck.write_text(deck_text)
    text = CASE.read_text()
    assert "deck: ../meshes/rattle_rig_deck.bdf" in text and "units: mm-t-s" in text
    text = text.replace("deck: ../meshes/rattle_rig_deck.bdf", f"deck: {deck}")
    text = (text.replace("    units: mm-t-s\n", "") if units is None
            else text.replace("units: mm-t-s", f"units: {units}"))
    (tmp_path / "case.yaml").write_text(text)
    return load_case(tmp_path / "case.yaml")


def test_shipped_deck_with_its_units_is_clean(tmp_path):
    check = check_case(shipped_case(tmp_path), write=False)
    assert check.info["nodes"] == 376
    assert not any("units" in w for w in check.warnings)


def test_mm_t_s_deck_read_as_si_names_the_material_and_the_fix(tmp_path):
    """units left at its default SI: refused, naming the system the deck looks like."""
    with pytest.raises(CaseError) as error:
        check_case(shipped_case(tmp_path, units=None), write=False)
    text = str(error.value)
    line = deck_line(DECK.read_text(), "MAT1", 1)
    assert "model.fe.units: " in text and "\n" not in text
    assert f"rattle_rig_deck.bdf:{line}: MAT1 1: E = 2200 Pa with units: SI" in text
    assert "(E < 1e5 Pa)" in text
    assert "the deck looks like mm-t-s: set model.fe.units: mm-t-s" in text


def test_explicit_units_are_kept_with_a_warning_showing_the_evidence(tmp_path):
    """in-lbf-s given explicitly: E = 2200 psi = 1.52e7 Pa passes, ρ = 1.05e-9 · 175.127 kg /
    0.0254³ m³ = 0.0112 kg/m³ does not — a warning naming the card, kept as the case says."""
    from sarfe.pipeline.model.deck_model import prepare_deck

    prepared = prepare_deck(shipped_case(tmp_path, units="in-lbf-s"))
    rho = 1.05e-9 * (4.4482216152605 / 0.0254) / 0.0254**3
    text = " ".join(prepared.warnings)
    assert f"MAT1 1: ρ = {rho:.4g} kg/m³ with units: in-lbf-s" in text
    assert "kept as model.fe.units: in-lbf-s says (the deck would look plausible in mm-t-s)" in text


def test_grids_in_mm_with_si_materials_is_a_span_error_without_a_guess(tmp_path):
    """Materials retyped in SI but GRIDs and T left in mm: the span (≈ 0.26 km) is refused; no
    unit system makes E, ρ and the span plausible together, so none is suggested."""
    text = DECK.read_text()
    text = text.replace("MAT1*                  12.2000000000E+03",
                        "MAT1*                  12.2000000000E+09")
    text = text.replace("*       1.0500000000E-09", "*       1.0500000000E+03")
    text = text.replace("MAT1*                  22.1000000000E+05",
                        "MAT1*                  22.1000000000E+11")
    text = text.replace("*       7.8500000000E-09", "*       7.8500000000E+03")
    with pytest.raises(CaseError) as error:
        check_case(shipped_case(tmp_path, units=None, deck_text=text), write=False)
    message = str(error.value)
    assert "model.fe.units: " in message and "the GRIDs span " in message
    assert "no unit system makes the deck plausible" in message and "units: SI to keep" in message
    assert "(> 20 m)" in message


@pytest.mark.parametrize("thickness, rule", [("2.5000000000E+02", "above 0.1 of the model size"),
                                             ("2.5000000000E-03", "below 0.0001 of the model size")])
def test_thickness_in_another_length_unit_names_the_pshell(tmp_path, thickness, rule):
    """PSHELL 1 T = 250 mm (0.25 m) or 0.0025 mm on a plate of L ≈ 0.26 m: a warning naming the
    PSHELL (no unit system changes a thickness-to-size ratio; real thin webs exist)."""
    from sarfe.pipeline.model.deck_model import prepare_deck

    text = DECK.read_text().replace("PSHELL*                1               12.5000000000E+00",
                                    f"PSHELL*                1               1{thickness}")
    message = " ".join(prepare_deck(shipped_case(tmp_path, deck_text=text)).warnings)
    line = deck_line(text, "PSHELL", 1)
    assert f"deck.bdf:{line}: PSHELL 1: thickness " in message
    assert rule in message and "kept" in message


def test_abaqus_material_in_mpa_read_as_si(tmp_path):
    """The Abaqus path: *ELASTIC 2000 (MPa) read with units: SI names the *MATERIAL line."""
    from tests.pipeline.model.test_deck_model import plate_inp, write_case

    inp = plate_inp()
    data = write_case(tmp_path, inp)
    check_case(load_case(data, base_dir=tmp_path), write=False)          # mm-t-s: clean
    del data["model"]["fe"]["units"]          # the default SI
    with pytest.raises(CaseError) as error:
        check_case(load_case(data, base_dir=tmp_path), write=False)
    line = inp.splitlines().index("*MATERIAL, NAME=PP") + 1
    message = str(error.value)
    assert f"plate.inp:{line}: *MATERIAL, NAME=PP: E = 2000 Pa with units: SI" in message
    assert "set model.fe.units: mm-t-s" in message


def test_solve_refuses_the_wrong_units_before_any_assembly(tmp_path):
    from sarfe.pipeline import build_linear_model

    with pytest.raises(CaseError, match=r"model\.fe\.units: .*MAT1 1: E = 2200 Pa"):
        build_linear_model(shipped_case(tmp_path, units=None))
