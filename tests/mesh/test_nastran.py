"""Nastran decks read through pyNastran into DeckModel: real public decks and small written ones.

The real decks live in ../shared/decks (pyNastran's models, see its README and REFERENCE.json);
their mass properties and coordinates are checked against pyNastran's own functions, their
natural frequencies against the commercial solver's stored results.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from sarfe.mesh.formats.deck import DeckError, to_si
from sarfe.mesh.formats.nastran import nastran_deck, read_nastran

# beside the checkout (CI), or beside the folder of worktrees (/work/wt/<name> → /work/shared)
DECKS = next((root / "shared" / "decks" for root in Path(__file__).resolve().parents[3:5]
              if (root / "shared" / "decks").is_dir()),
             Path(__file__).resolve().parents[2].parent / "shared" / "decks")
needs_decks = pytest.mark.skipif(not (DECKS / "REFERENCE.json").is_file(),
                                 reason=f"public decks folder {DECKS} is absent")
DECK_FILES = ["a101x.dat", "plate.bdf", "plate_py.dat", "mode_solid_shell_bar.bdf"]


def _pynastran_model(path):
    from sarfe.mesh.formats.nastran_bdf import load_bdf

    return load_bdf(Path(path))


@needs_decks
@pytest.mark.parametrize("name", DECK_FILES)
def test_deck_mass_and_cg_equal_pynastran(name):
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties as pyn_mass

    from sarfe.fe.deck_assembly import mass_properties

    deck = read_nastran(DECKS / name)
    mass, cg = mass_properties(deck)
    ref_mass, ref_cg, _ = pyn_mass(_pynastran_model(DECKS / name))
    assert mass == pytest.approx(float(ref_mass), rel=1e-6, abs=1e-300)
    if ref_mass > 0:
        size = np.ptp(deck.points, axis=0).max()
        assert np.allclose(cg, ref_cg, rtol=0, atol=1e-6 * size)


@needs_decks
def test_a101x_cylindrical_grids_in_global_coordinates():
    deck = nastran_deck(DECKS / "a101x.dat")
    model = _pynastran_model(DECKS / "a101x.dat")
    xyz = model.get_xyz_in_coord(cid=0, sort_ids=True)
    assert np.allclose(deck.points, xyz, rtol=0, atol=1e-9)
    # independent of pyNastran's transform: CORD2C 1 has the basic axes at the origin, so a
    # GRID with CP = 1 at (r, θ°, z) lies at (r cos θ, r sin θ, z)
    cylindrical = [n for n in model.nodes.values() if n.cp == 1]
    assert len(cylindrical) > 30
    for node in cylindrical:
        r, theta, z = node.xyz
        expected = [r * np.cos(np.radians(theta)), r * np.sin(np.radians(theta)), z]
        assert np.allclose(deck.points[deck.node_index([node.nid])[0]], expected, atol=1e-9)
    assert len(deck.rbe3.element_ids) == 2
    # GRDSET PS = 3456 holds those components of every GRID
    assert deck.supports["permanent"].components[:, 2:].all()


@needs_decks
def test_include_followed_and_every_card_accounted_for():
    deck = read_nastran(DECKS / "mode_solid_shell_bar.bdf")
    assert {k: len(v.element_ids) for k, v in deck.solids.items()} == {
        "hex8": 1, "wedge6": 2, "tet4": 2}
    assert sorted(deck.beams.card) == ["CBAR", "CBEAM", "CROD", "CROD"]
    assert len(deck.shells.element_ids) == 12 and deck.shells.n_triangles == 16
    assert deck.unsupported == {}
    # SPCADD 2 = SPC1 set 123456: GRIDs 22–25 clamped, 5–13 rotations held
    support = deck.supports["2"]
    held = dict(zip(deck.node_ids[support.nodes].tolist(), support.components.tolist()))
    assert all(held[n] == [True] * 6 for n in (22, 23, 24, 25))
    assert all(held[n] == [False] * 3 + [True] * 3 for n in range(5, 14))
    # LOAD 123458 = 1.0 · 1.0 · FORCE 10000 (10 000 along z on GRID 13)
    load = deck.loads["123458"]
    assert load[deck.node_index([13])[0], 2] == pytest.approx(10000.0)
    assert np.count_nonzero(load) == 1
    plate = read_nastran(DECKS / "plate.bdf")
    assert plate.unsupported == {"PLOAD4": 2}  # pressure loads are not modelled: listed
    assert any("no density" in note for note in plate.notes)


@needs_decks
def test_units_convert_every_quantity():
    deck = nastran_deck(DECKS / "mode_solid_shell_bar.bdf")
    si = to_si(deck, "in-lbf-s")
    assert np.allclose(si.points, deck.points * 0.0254)
    lbf_per_in2 = 4.4482216152605 / 0.0254**2
    assert np.allclose(si.solids["hex8"].young, deck.solids["hex8"].young * lbf_per_in2)
    assert np.allclose(si.beams.i1, deck.beams.i1 * 0.0254**4)
    assert np.allclose(si.loads["10000"], deck.loads["10000"] * np.r_[[4.4482216152605] * 3,
                                                                     [4.4482216152605 * 0.0254] * 3])


def _write(tmp_path, text, name="deck.bdf"):
    path = tmp_path / name
    path.write_text("BEGIN BULK\n" + text.strip() + "\nENDDATA\n")
    return path


_PLATE = """
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,0.
PSHELL,1,1,0.01,1
MAT1,1,7.e10,,0.3,2700.
"""


@pytest.mark.parametrize("card, needle", [
    ("CQUAD4,1,1,1,2,3,4\nCELAS2,9,1000.,1,1,2,2", "components"),
    ("CQUAD4,1,1,1,2,3,4\nCBUSH,9,7,1,,,,,\nPBUSH,7,K,1.,1.,1.,1.,1.,1.", "CID"),
])
def test_lossy_features_are_refused_with_one_line(tmp_path, card, needle):
    path = _write(tmp_path, _PLATE + card)
    with pytest.raises(DeckError) as info:
        read_nastran(path)
    message = str(info.value)
    assert needle in message and str(path) in message and "\n" not in message


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_quadratic_shells_become_facets_through_their_midside_nodes(tmp_path):
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties as pyn_mass

    from sarfe.fe.deck_assembly import assemble_deck, mass_properties

    path = _write(tmp_path, _PLATE + """
GRID,5,,0.5,0.,0.
GRID,6,,1.,0.5,0.
GRID,7,,0.5,1.,0.
GRID,8,,0.,0.5,0.
GRID,9,,2.,0.,0.
GRID,10,,1.5,0.,0.
GRID,11,,1.5,0.5,0.
CQUAD8,1,1,1,2,3,4,5,6,+
+,7,8
CTRIA6,2,1,2,9,3,10,11,6
""")
    deck = read_nastran(path)
    assert deck.shells.n_triangles == 6 + 4
    assert set(np.unique(deck.shells.triangles)) == set(range(11))  # midside nodes kept
    mass, cg = mass_properties(deck)
    ref_mass, ref_cg, _ = pyn_mass(_pynastran_model(path))
    assert mass == pytest.approx(float(ref_mass), rel=1e-9)
    assert np.allclose(cg, ref_cg, atol=1e-9)
    assert len(assemble_deck(deck).auto_held_nodes) == 0


def test_theta_field_and_unsupported_cards_counted(tmp_path):
    deck = read_nastran(_write(tmp_path, _PLATE + "CQUAD4,1,1,1,2,3,4,30.\nPLOAD2,3,1.,1\n"
                                                  "TEMP,4,1,20."))
    assert deck.shells.n_triangles == 2
    assert np.allclose(deck.shells.material_axis[0], [np.cos(np.pi / 6), np.sin(np.pi / 6), 0])
    assert deck.unsupported == {"PLOAD2": 1, "TEMP": 1}


def test_zoffs_is_honoured_as_a_section_about_the_node_plane(tmp_path):
    from sarfe.fe.deck_assembly import mass_properties

    deck = read_nastran(_write(tmp_path, _PLATE + "CQUAD4,1,1,1,2,3,4,,0.002"))
    assert np.allclose(deck.shells.offset, 0.002)
    assert np.allclose(deck.shells.coupling, 0.002 * deck.shells.membrane)
    mass, cg = mass_properties(deck)
    assert mass == pytest.approx(2700 * 0.01)
    assert np.allclose(cg, [0.5, 0.5, 0.002])  # the mass sits on the offset mid-surface


def test_broken_deck_is_one_line_error(tmp_path):
    path = _write(tmp_path, _PLATE + "CQUAD4,1,99,1,2,3,4")  # property 99 missing
    with pytest.raises(DeckError) as info:
        read_nastran(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(DeckError, match="not found"):
        read_nastran(tmp_path / "missing.bdf")


def test_clt_of_symmetric_cross_ply_equals_hand_values(tmp_path):
    e1, e2, nu12, g12, ply = 140e9, 10e9, 0.3, 5e9, 0.25e-3
    deck = read_nastran(_write(tmp_path, """
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
CTRIA3,1,1,1,2,3
MAT8,1,1.4e11,1.e10,0.3,5.e9,,,1600.
PCOMP,1,,,,,,,SYM
,1,2.5-4,0.,,1,2.5-4,90.
"""))
    d = 1.0 - nu12**2 * e2 / e1
    q11, q22, q12 = e1 / d, e2 / d, nu12 * e2 / d
    h = 4 * ply
    a = deck.shells.membrane[0]
    assert a[0, 0] == pytest.approx((q11 + q22) * h / 2, rel=1e-12)
    assert a[1, 1] == pytest.approx((q11 + q22) * h / 2, rel=1e-12)
    assert a[0, 1] == pytest.approx(q12 * h, rel=1e-12)
    assert a[2, 2] == pytest.approx(g12 * h, rel=1e-12)
    assert np.abs(deck.shells.coupling[0]).max() < 1e-9 * a[0, 0] * h
    bending = deck.shells.bending[0]
    assert bending[0, 0] == pytest.approx(q11 * 14 * ply**3 / 3 + q22 * 2 * ply**3 / 3, rel=1e-12)
    assert bending[1, 1] == pytest.approx(q22 * 14 * ply**3 / 3 + q11 * 2 * ply**3 / 3, rel=1e-12)
    assert bending[2, 2] == pytest.approx(g12 * h**3 / 12, rel=1e-12)
    assert deck.shells.mass_per_area[0] == pytest.approx(1600 * h)


@needs_decks
def test_reference_frequencies_file_is_there():
    reference = json.loads((DECKS / "REFERENCE.json").read_text())
    assert len(reference["mode_solid_shell_bar.bdf"]["frequencies_hz"]) == 3


def test_darea_in_cd_frame_and_load_combination(tmp_path):
    deck = read_nastran(_write(tmp_path, """
CORD2R,2,,0.,0.,0.,0.,0.,1.
,0.,1.,0.
GRID,1,,0.,0.,0.,2
DAREA,5,1,1,3.
MOMENT,6,1,,2.,0.,0.,1.
FORCE,8,1,2,4.,1.,0.,0.
LOAD,7,2.,1.,8,0.5,6
"""))
    # CD (and FORCE CID) 2 has its x along global y: component 1 acts along +y
    assert np.allclose(deck.loads["5"][0], [0, 3, 0, 0, 0, 0])
    assert np.allclose(deck.loads["8"][0], [0, 4, 0, 0, 0, 0])
    assert np.allclose(deck.loads["7"][0], 2.0 * np.array([0, 4, 0, 0, 0, 1.0]))


def test_blank_grid_fields_and_grdset_defaults(tmp_path):
    # blank coordinates are 0.0; GRDSET supplies CP/CD/PS for GRIDs that leave them blank
    # (pyNastran 1.4 reads GRDSET but does not apply its CP/PS: sarfe does)
    deck = read_nastran(_write(tmp_path, """
CORD2R,3,,0.,0.,1.,0.,0.,2.
,1.,0.,1.
GRDSET,,3,,,,,6
GRID,1
GRID,2,,1.
GRID,3,,1.,1.
GRID,4,,0.,1.
CTRIA3,1,1,1,2,3
CTRIA3,2,1,1,3,4
PSHELL,1,1,0.01,1
MAT1,1,7.e10,,0.3,2700.
"""))
    assert np.allclose(deck.points, [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
    assert deck.supports["permanent"].components[:, 5].all()
    assert any("GRDSET" in note for note in deck.notes)  # blank and explicit 0 read alike
