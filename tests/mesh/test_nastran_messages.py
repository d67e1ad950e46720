"""Nastran deck errors are one short line with the deck's file and line of the card: a CQUAD4 on
GRIDs the deck does not have names the element and those GRIDs only (pyNastran's own message
lists every GRID of the deck); a non-numeric field names the GRID and its line, and pyNastran's
console output (``UserWarning: bad fields``, ``problem adding``) does not reach the user."""
import warnings
from pathlib import Path

import pytest

from sarfe.mesh.formats.deck import DeckError
from sarfe.mesh.formats.nastran import read_nastran
from sarfe.mesh.formats.nastran_bdf import card_line

DECK = Path(__file__).resolve().parents[2] / "meshes" / "rattle_rig_deck.bdf"
FIRST_QUAD = ("CQUAD4*                1               1             239             214\n"
              "*                    118              37")


def test_card_line_finds_small_large_and_free_fields(tmp_path):
    text = DECK.read_text()
    assert card_line(DECK, "CQUAD4", 1) == (str(DECK), 759)
    assert card_line(DECK, "MAT1", 2) == (str(DECK), 1477)
    assert card_line(DECK, "MAT1", 3) is None
    (tmp_path / "part.inc").write_text("GRID,7,,0.,0.,0.\nCQUAD4  11      1       7       8       9       10\n")
    (tmp_path / "main.bdf").write_text("BEGIN BULK\nINCLUDE 'part.inc'\nENDDATA\n")
    assert card_line(tmp_path / "main.bdf", "GRID", 7) == (str(tmp_path / "part.inc"), 1)
    assert card_line(tmp_path / "main.bdf", "CQUAD4", 11) == (str(tmp_path / "part.inc"), 2)
    assert "CQUAD4*                1" in text.splitlines()[758]
    # read through the INCLUDE, the error names the included file's line
    with pytest.raises(DeckError, match=r"part\.inc:2: CQUAD4 11: GRIDs 8, 9, 10 are not in the deck$"):
        read_nastran(tmp_path / "main.bdf")


def test_missing_grids_name_the_element_not_every_grid(tmp_path):
    deck = tmp_path / "deck.bdf"
    text = DECK.read_text()
    assert FIRST_QUAD in text
    # large field: 16 characters a field
    deck.write_text(text.replace(FIRST_QUAD, FIRST_QUAD.replace("   239", "999999")
                                 .replace("   118", "888888")))
    with pytest.raises(DeckError) as error:
        read_nastran(deck, units="mm-t-s")
    message = str(error.value)
    assert message == f"{deck}:759: CQUAD4 1: GRIDs 888888, 999999 are not in the deck"


def test_bad_field_is_one_line_with_its_card_and_no_console_output(tmp_path, capfd):
    deck = tmp_path / "deck.bdf"
    lines = DECK.read_text().splitlines(keepends=True)
    assert lines[6].startswith("GRID*                  1") and lines[7].split() == ["*", "0.0"]
    lines[7] = lines[7].replace("0.0", "abc")
    deck.write_text("".join(lines))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(DeckError) as error:
            read_nastran(deck, units="mm-t-s")
    message = str(error.value)
    assert message.startswith(f"{deck}:7: GRID 1: ") and "'ABC'" in message
    assert "\n" not in message and len(message) < 400
    assert not caught
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_duplicate_grid_names_both_cards_in_one_line(tmp_path):
    deck = tmp_path / "deck.bdf"
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,1.,1.,0.\n"
                    "GRID,2,,5.,5.,0.\nENDDATA\n")
    with pytest.raises(DeckError) as error:
        read_nastran(deck, units="mm-t-s")
    message = str(error.value)
    assert message.startswith(f"{deck}:3: GRID 2: the id is used twice: GRID 2 1. ")
    assert "GRID 2 5. 5." in message and "\n" not in message


def test_many_missing_grids_are_cut_to_a_few(tmp_path):
    """An RBE2 on 7 GRIDs the deck lacks: five ids, then the count."""
    deck = tmp_path / "deck.bdf"
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\n"
                    "RBE2,5,1,123456,11,12,13,14,15,\n,16,17\nENDDATA\n")
    with pytest.raises(DeckError) as error:
        read_nastran(deck)
    assert str(error.value) == (f"{deck}:3: RBE2 5: GRIDs 11, 12, 13, 14, 15, … (7 in all) "
                                "are not in the deck")


def test_missing_include_names_its_line_and_leaves_no_crash_file(tmp_path, monkeypatch):
    """pyNastran writes pyNastran_crash.bdf into the working folder on a missing INCLUDE; the
    file is checked first, so nothing is written and the line is named."""
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    deck = tmp_path / "deck.bdf"
    deck.write_text("SOL 103\nCEND\nBEGIN BULK\nINCLUDE 'nothere/bulk.inc'\nENDDATA\n")
    with pytest.raises(DeckError) as error:
        read_nastran(deck)
    assert str(error.value).startswith(f"{deck}:4: INCLUDE 'nothere/bulk.inc': file not found")
    assert list(work.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == [
        "deck.bdf", "work"]
