"""Abaqus / CalculiX beams (B31, B32, B32R with *BEAM SECTION) read into the deck's Timoshenko
beams (sarfe.mesh.formats.abaqus_beams): section constants, the local 1-direction, 3-node beams
through their middle node, and one-line refusals."""
import numpy as np
import pytest
import scipy.sparse.linalg as sla

from sarfe.fe.deck_assembly import assemble_deck, load_vector, support_dofs
from sarfe.mesh.formats.abaqus import read_abaqus
from sarfe.mesh.formats.abaqus_beams import beam_section_constants
from sarfe.mesh.formats.deck import DeckError

E, NU = 2.1e5, 0.3


def _deck(tmp_path, kind="B31", section="RECT", dims="4., 2.", direction="0., 1., 0.",
          options="", n=8, load_dof=2, extra=""):
    """A cantilever along x (length 100) of n elements, held at x = 0, unit load at the tip."""
    per = 2 if kind == "B31" else 3
    nodes = (n * (per - 1)) + 1
    lines = ["*NODE, NSET=all"] + [f"{i + 1}, {100.0 * i / (nodes - 1)}, 0., 0."
                                   for i in range(nodes)]
    lines += [f"*ELEMENT, TYPE={kind}, ELSET=beam"]
    lines += [f"{e + 1}, " + ", ".join(str(e * (per - 1) + j + 1) for j in range(per))
              for e in range(n)]
    lines += [f"*BEAM SECTION, ELSET=beam, MATERIAL=steel, SECTION={section}{options}", dims]
    if direction:
        lines.append(direction)
    lines += ["*MATERIAL, NAME=steel", "*ELASTIC", f"{E}, {NU}", "*DENSITY", "7.8e-9",
              "*BOUNDARY", "1, 1, 6", extra, "*STEP", "*STATIC", "*CLOAD",
              f"{nodes}, {load_dof}, 1.", "*END STEP"]
    path = tmp_path / "beam.inp"
    path.write_text("\n".join(line for line in lines if line) + "\n")
    return path


def _tip(path, dof):
    deck = read_abaqus(path)
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, "boundary")
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    q = np.zeros(system.n_dofs)
    q[free] = sla.spsolve(system.stiffness[free][:, free].tocsc(),
                          load_vector(system, deck, next(iter(deck.loads)))[free])
    return system.displacement(q)[-1, dof], deck


@pytest.mark.parametrize("kind", ["B31", "B32R"])
@pytest.mark.parametrize("load_dof, inertia", [(2, 2.0 * 4.0**3 / 12), (3, 4.0 * 2.0**3 / 12)])
def test_rect_cantilever_tip_deflection_is_timoshenkos(tmp_path, kind, load_dof, inertia):
    """RECT a = 4 along n₁ = y, b = 2: a tip load along y bends about I = b a³/12, along z about
    a b³/12; deflection F L³/(3 E I) + F L/(k G A), k = 10 (1 + ν)/(12 + 11 ν) (Cowper)."""
    tip, deck = _tip(_deck(tmp_path, kind=kind, load_dof=load_dof), load_dof - 1)
    k = 10 * (1 + NU) / (12 + 11 * NU)
    expected = 100.0**3 / (3 * E * inertia) + 100.0 / (k * E / (2 * (1 + NU)) * 8.0)
    assert tip == pytest.approx(expected, rel=1e-9)
    assert len(deck.beams.card) == (8 if kind == "B31" else 16)     # B32R: two per element


def test_default_direction_1_is_minus_z(tmp_path):
    """Without a direction line n₁ = (0, 0, −1): a = 4 lies along z, so a load along z bends
    about b a³/12."""
    tip, _ = _tip(_deck(tmp_path, direction="", load_dof=3), 2)
    k = 10 * (1 + NU) / (12 + 11 * NU)
    expected = 100.0**3 / (3 * E * (2.0 * 4.0**3 / 12)) + 100.0 / (k * E / (2 * (1 + NU)) * 8.0)
    assert tip == pytest.approx(expected, rel=1e-9)


def test_section_constants_closed_forms():
    area, i1, i2, j, k = beam_section_constants("PIPE", [0.11, 0.01], 0.3)
    assert area == pytest.approx(np.pi * (0.11**2 - 0.1**2))
    assert i1 == i2 == pytest.approx(np.pi * (0.11**4 - 0.1**4) / 4) and j == pytest.approx(2 * i1)
    assert 0.5 < k < 0.54                                   # thin tube: 2 (1 + ν)/(4 + 3 ν) = 0.531
    area, i1, i2, j, k = beam_section_constants("CIRC", [2.0, 2.0], 0.3)
    assert (area, i1, j) == pytest.approx((np.pi, np.pi / 4, np.pi / 2))
    assert k == pytest.approx(6 * 1.3 / 8.8)


@pytest.mark.parametrize("change, expected", [
    (dict(section="BOX", dims="4., 2., .2, .2, .2, .2"), "SECTION=BOX is not modelled"),
    (dict(options=", OFFSET1=0.5"), "OFFSET1=0.5 (beam offset) is not supported"),
    (dict(dims="4."), "SECTION=RECT needs 2 positive dimensions"),
    (dict(extra="*NODAL THICKNESS\n2, 3."), "*NODAL THICKNESS on a beam's node"),
])
def test_beam_refusals_are_one_line_naming_the_file(tmp_path, change, expected):
    with pytest.raises(DeckError) as info:
        read_abaqus(_deck(tmp_path, **change))
    message = str(info.value)
    assert "\n" not in message and "beam.inp:" in message and expected in message


def test_beam_without_section_is_refused(tmp_path):
    path = tmp_path / "beam.inp"
    path.write_text("*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n*ELEMENT, TYPE=B31, ELSET=b\n1, 1, 2\n")
    with pytest.raises(DeckError, match="beam element 1 has no \\*BEAM SECTION"):
        read_abaqus(path)
