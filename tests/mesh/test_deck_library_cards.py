"""Cards engineers' decks carry (issue 32 item 1): PBARL / PBEAML sections against closed forms,
CQUADR / CTRIAR read as the shells with drilling, and analysis-only cards listed, not fatal."""
import numpy as np
import pytest

from sarfe.fe.deck_assembly import assemble_deck
from sarfe.mesh.formats.beam_library import section
from sarfe.mesh.formats.deck import DeckError
from sarfe.mesh.formats.nastran import nastran_deck


def _write(tmp_path, text, name="deck.bdf"):
    path = tmp_path / name
    path.write_text("BEGIN BULK\n" + text.strip() + "\nENDDATA\n")
    return path


@pytest.mark.parametrize("shape, dims, expected", [
    ("ROD", [0.01], (np.pi * 1e-4, np.pi * 1e-8 / 4, np.pi * 1e-8 / 4, np.pi * 1e-8 / 2)),
    ("TUBE", [0.02, 0.015], (np.pi * (4e-4 - 2.25e-4), np.pi * (1.6e-7 - 5.0625e-8) / 4,
                             np.pi * (1.6e-7 - 5.0625e-8) / 4, np.pi * (1.6e-7 - 5.0625e-8) / 2)),
    # BAR 0.02 wide (z) × 0.01 high (y); J of a 2:1 rectangle = 0.2287 a b³ (Roark / Timoshenko β)
    ("BAR", [0.02, 0.01], (2e-4, 0.02 * 1e-6 / 12, 0.01 * 8e-6 / 12, 0.2287 * 0.02 * 1e-6)),
    # BOX 0.1 wide × 0.2 high, walls 0.01: A = 0.02 − 0.08·0.18; Bredt 4 A_m² t / perimeter_m
    ("BOX", [0.1, 0.2, 0.01, 0.01], (0.02 - 0.08 * 0.18, (0.1 * 0.2**3 - 0.08 * 0.18**3) / 12,
                                     (0.2 * 0.1**3 - 0.18 * 0.08**3) / 12,
                                     4 * (0.09 * 0.19) ** 2 * 0.01 / (2 * (0.09 + 0.19)))),
    # symmetric I: height 0.2, flanges 0.1 × 0.01, web 0.005 (textbook: b h³/12 − (b − t_w) h_w³/12)
    ("I", [0.2, 0.1, 0.1, 0.005, 0.01, 0.01],
     (2 * 0.1 * 0.01 + 0.18 * 0.005, (0.1 * 0.2**3 - 0.095 * 0.18**3) / 12,
      (2 * 0.01 * 0.1**3 + 0.18 * 0.005**3) / 12, (2 * 0.1 * 0.01**3 + 0.18 * 0.005**3) / 3)),
])
def test_library_sections_equal_closed_forms(shape, dims, expected):
    area, i1, i2, i12, j = section(shape, dims)
    assert (area, i1, i2, j) == pytest.approx(expected, rel=1e-3)   # β tables: 4 digits
    assert i12 == 0.0


def test_unmodelled_library_shape_is_one_line(tmp_path):
    path = _write(tmp_path, """
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
CBAR,1,1,1,2,0.,1.,0.
PBARL,1,1,,HAT
,0.1,0.01,0.05,0.02
MAT1,1,7.e10,,0.3,2700.
""")
    with pytest.raises(DeckError) as info:
        nastran_deck(path)
    assert "PBARL 1" in str(info.value) and "HAT" in str(info.value)
    assert "\n" not in str(info.value)


def _bar_deck(tmp_path, prop, name):
    return nastran_deck(_write(tmp_path, """
GRID,1,,0.,0.,0.
GRID,2,,0.5,0.,0.
GRID,3,,1.,0.,0.
CBAR,1,1,1,2,0.,1.,0.
CBAR,2,1,2,3,0.,1.,0.
MAT1,1,7.e10,,0.3,2700.
""" + prop, name))


def test_pbarl_bar_equals_the_pbar_of_its_closed_form(tmp_path):
    """A PBARL BAR gives the same K and M as the PBAR carrying its A, I1, I2, J."""
    area, i1, i2, _, j = section("BAR", [0.02, 0.01])
    library = _bar_deck(tmp_path, "PBARL,1,1,,BAR\n,0.02,0.01", "l.bdf")
    explicit = _bar_deck(tmp_path, f"PBAR,1,1,{area!r},{i1!r},{i2!r},{j!r}", "e.bdf")
    a, b = assemble_deck(library), assemble_deck(explicit)
    assert abs(a.stiffness - b.stiffness).max() <= 1e-9 * abs(b.stiffness).max()
    assert abs(a.mass - b.mass).max() <= 1e-9 * abs(b.mass).max()


def test_pbeaml_uniform_stations_read_and_tapered_refused(tmp_path):
    deck = _bar_deck(tmp_path, "PBEAML,1,1,,TUBE\n,0.02,0.015", "u.bdf")
    assert deck.beams.area[0] == pytest.approx(np.pi * (0.02**2 - 0.015**2))
    assert deck.beams.torsion[0] == pytest.approx(np.pi * (0.02**4 - 0.015**4) / 2)


_PLATE = """
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,0.
GRID,5,,2.,0.5,0.1
PSHELL,1,1,0.01,1,,1
MAT1,1,7.e10,,0.3,2700.
"""


def test_cquadr_ctriar_read_as_cquad4_ctria3(tmp_path):
    r = assemble_deck(nastran_deck(_write(tmp_path, _PLATE + "CQUADR,1,1,1,2,3,4\nCTRIAR,2,1,2,5,3",
                                          "r.bdf")))
    plain = assemble_deck(nastran_deck(_write(tmp_path, _PLATE + "CQUAD4,1,1,1,2,3,4\n"
                                              "CTRIA3,2,1,2,5,3", "p.bdf")))
    assert abs(r.stiffness - plain.stiffness).max() == 0.0
    assert abs(r.mass - plain.mass).max() == 0.0


def test_dynamic_load_cards_are_listed_not_fatal(tmp_path):
    """LSEQ, TLOAD2, DAREA-less dynamics, SPOINT: counted in ``unsupported`` (the case's
    ignore_cards decides), never a crash of the reader."""
    deck = nastran_deck(_write(tmp_path, _PLATE + """CQUAD4,1,1,1,2,3,4
FORCE,12,1,,2.,0.,0.,1.
LSEQ,10,10,12
TLOAD2,10,10,,,0.,5.,10.
SPOINT,101
"""))
    assert {"LSEQ", "TLOAD2", "SPOINT"} <= set(deck.unsupported)
