"""The Abaqus reader (sarfe.mesh.formats.abaqus) on small files that use every supported keyword,
including the cases meshio crashes on (repeated *NODE, sets of sets, repeated ELSET=) or reads
silently wrong (*Instance offsets dropped, S8R midside nodes dropped, sections ignored)."""
import numpy as np
import pytest

from sarfe.mesh.formats.abaqus import read_abaqus
from sarfe.mesh.formats.deck import DeckError, to_si

E, NU, RHO, T = 2.0e3, 0.3, 1.0e-9, 2.0           # mm-t-s: MPa, t/mm³, mm

FLAT = """** a flat model: 2 x 1 mm S4R, an S3 beside it, an S8R next to it
*HEADING
test deck
*NODE, NSET=first
1, 0., 0., 0.
2, 1., 0., 0.
3, 1., 1., 0.
4, 0., 1., 0.
*NODE
5, 2., 0., 0.
6, 2., 1., 0.
*INCLUDE, INPUT=more_nodes.inc
*ELEMENT, TYPE=S4R, ELSET=plate
10, 1, 2, 3, 4
*ELEMENT, TYPE=S3, ELSET=plate
11, 2, 5, 6
*ELEMENT, TYPE=S3, ELSET=other
12, 2, 6, 3
*ELEMENT, TYPE=S8R, ELSET=quadratic
20, 5, 7, 8, 6, 9, 10, 11, 12
*ELEMENT, TYPE=SPRING1, ELSET=ground_springs
30, 4
*ELEMENT, TYPE=SPRING2, ELSET=link
31, 3, 13
*ELEMENT, TYPE=MASS, ELSET=lumps
40, 13
*NSET, NSET=gen, GENERATE
1, 5, 2
*NSET, NSET=both
gen, first
*NSET, NSET=both
13
*ELSET, ELSET=shells
plate, other
*ELSET, ELSET=shells
20
*MATERIAL, NAME=PP
*ELASTIC
2000., 0.3
*DENSITY
1e-9,
*SHELL SECTION, ELSET=shells, MATERIAL=PP
2.0, 5
*SPRING, ELSET=ground_springs
3
500.
*SPRING, ELSET=link
1, 1
250.
*MASS, ELSET=lumps
0.002
*BOUNDARY
1, 1, 3
gen, 6
2, ENCASTRE
*STEP, NAME=load
*STATIC
*CLOAD
both, 3, 1.5
4, 1, -2.
*END STEP
"""
MORE_NODES = """*NODE
7, 4., 0., 0.
8, 4., 1., 0.
9, 3., 0., 0.
10, 4., 0.5, 0.
11, 3., 1., 0.
12, 2., 0.5, 0.
13, 1., 1., 0.
"""


@pytest.fixture
def flat(tmp_path):
    (tmp_path / "more_nodes.inc").write_text(MORE_NODES)
    path = tmp_path / "flat.inp"
    path.write_text(FLAT)
    return path


def test_flat_model_every_keyword(flat):
    deck = read_abaqus(flat)
    assert list(deck.node_ids) == list(range(1, 14))          # repeated *NODE + *INCLUDE
    assert np.allclose(deck.points[deck.node_index([7])], [[4, 0, 0]])
    shells = deck.shells
    assert list(shells.element_ids) == [10, 11, 12, 20]
    # S4R → 2 triangles, S3 → 1, S8R → 6 triangles using all 8 nodes (none dropped)
    assert np.bincount(shells.triangle_element).tolist() == [2, 1, 1, 6]
    s8r = shells.triangles[shells.triangle_element == 3]
    assert set(deck.node_ids[np.unique(s8r)]) == {5, 6, 7, 8, 9, 10, 11, 12}
    # section stiffness of an isotropic shell: A11 = E t/(1-ν²), D11 = E t³/(12(1-ν²))
    assert np.allclose(shells.membrane[:, 0, 0], E * T / (1 - NU**2), rtol=1e-14)
    assert np.allclose(shells.bending[:, 0, 0], E * T**3 / (12 * (1 - NU**2)), rtol=1e-14)
    assert np.allclose(shells.membrane[:, 2, 2], E * T / (2 * (1 + NU)), rtol=1e-14)
    # total shell mass = ρ t area: area 1 (S4R) + 0.5 + 0.5 (S3) + 2 (S8R, 2 x 1 mm)
    from sarfe.mesh.quality import shell_areas
    area = shell_areas(deck.points, shells.triangles)
    assert np.sum(area * shells.mass_per_area) == pytest.approx(RHO * T * 4.0, rel=1e-12)
    # springs and the point mass
    springs = deck.springs
    assert list(springs.element_ids) == [30, 31]
    assert springs.stiffness[0].tolist() == [0, 0, 500.0, 0, 0, 0] and springs.node_b[0] == -1
    assert springs.stiffness[1].tolist() == [250.0, 0, 0, 0, 0, 0]
    assert list(deck.node_ids[[springs.node_a[1], springs.node_b[1]]]) == [3, 13]
    assert deck.point_masses.mass.tolist() == [0.002]
    # sets: GENERATE, set of sets, repeated NSET=/ELSET= append
    assert sorted(deck.node_ids[deck.node_sets["gen"]]) == [1, 3, 5]
    assert sorted(deck.node_ids[deck.node_sets["both"]]) == [1, 2, 3, 4, 5, 13]
    assert sorted(deck.element_sets["shells"]) == [10, 11, 12, 20]
    # supports: DOF range, a set, ENCASTRE
    support = deck.supports["boundary"]
    held = dict(zip(deck.node_ids[support.nodes], support.components.tolist()))
    assert held[1] == [True, True, True, False, False, True]
    assert held[2] == [True] * 6
    assert held[3] == held[5] == [False] * 5 + [True]
    # loads of the step, on every node of the set
    load = deck.loads["load"]
    assert load[deck.node_index([13])[0]].tolist() == [0, 0, 1.5, 0, 0, 0]
    assert load[deck.node_index([4])[0]].tolist() == [-2.0, 0, 1.5, 0, 0, 0]
    assert load[:, 2].sum() == pytest.approx(6 * 1.5)
    assert deck.unsupported == {}


def test_units_mm_t_s_to_si(flat):
    deck = to_si(read_abaqus(flat), "mm-t-s")
    assert np.allclose(deck.points[deck.node_index([8])], [[4e-3, 1e-3, 0]])
    assert deck.shells.membrane[0, 0, 0] == pytest.approx(E * 1e6 * T * 1e-3 / (1 - NU**2))
    assert deck.springs.stiffness[0, 2] == pytest.approx(500.0 * 1e3)           # N/mm → N/m
    assert deck.point_masses.mass[0] == pytest.approx(2.0)                      # t → kg
    assert deck.shells.mass_per_area[0] == pytest.approx(1e-9 * 1e12 * 2e-3)   # ρ t [kg/m²]


ASSEMBLY = """*PART, NAME=tab
*NODE
1, 0., 0., 0.
2, 1., 0., 0.
3, 1., 1., 0.
*ELEMENT, TYPE=S3, ELSET=tab_shells
1, 1, 2, 3
*NSET, NSET=corner
1
*SHELL SECTION, ELSET=tab_shells, MATERIAL=steel
0.5
*END PART
*ASSEMBLY, NAME=A
*INSTANCE, NAME=left, PART=tab
*END INSTANCE
*INSTANCE, NAME=right, PART=tab
10., 0., 0.
10., 0., 0., 10., 0., 1., 90.
*END INSTANCE
*NSET, NSET=tips, INSTANCE=right
2, 3
*NSET, NSET=all_tips
tips
*ELEMENT, TYPE=SPRING2, ELSET=bridge
1, left.3, right.1
*SPRING, ELSET=bridge
2, 2
1000.
*END ASSEMBLY
*MATERIAL, NAME=steel
*ELASTIC
210000., 0.3
*DENSITY
7.85e-9
*BOUNDARY
left.corner, ENCASTRE
*CLOAD
right.2, 3, 4.
"""


def test_assembly_instances_are_placed(tmp_path):
    path = tmp_path / "assembly.inp"
    path.write_text(ASSEMBLY)
    deck = read_abaqus(path)
    # instance 0 keeps its labels, instance 1 is offset by 10 (labels < 10)
    assert list(deck.node_ids) == [1, 2, 3, 11, 12, 13]
    # right: translate by (10, 0, 0), then rotate 90° about the z axis through (10, 0, 0):
    # (1, 0, 0) → (10, 1, 0); (1, 1, 0) → (9, 1, 0)
    expected = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [10, 0, 0], [10, 1, 0], [9, 1, 0]]
    assert np.allclose(deck.points, expected, atol=1e-12)
    assert list(deck.shells.element_ids) == [1, 11]
    assert sorted(deck.node_ids[deck.node_sets["tips"]]) == [12, 13]
    assert sorted(deck.node_ids[deck.node_sets["all_tips"]]) == [12, 13]
    assert sorted(deck.node_ids[deck.node_sets["right.corner"]]) == [11]
    spring = deck.springs
    assert list(deck.node_ids[[spring.node_a[0], spring.node_b[0]]]) == [3, 11]
    assert spring.stiffness[0].tolist() == [0, 1000.0, 0, 0, 0, 0]
    assert deck.node_ids[deck.supports["boundary"].nodes].tolist() == [1]
    assert deck.loads["cload"][deck.node_index([12])[0], 2] == 4.0


def _write(tmp_path, text, name="bad.inp"):
    path = tmp_path / name
    path.write_text("*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n" + text)
    return path


SECTION = ("*ELEMENT, TYPE=S3, ELSET=s\n1, 1, 2, 3\n*MATERIAL, NAME=m\n*ELASTIC\n1., 0.3\n"
           "*SHELL SECTION, ELSET=s, MATERIAL=m\n1.\n")


def test_unsupported_keywords_and_types_are_counted_not_dropped(tmp_path):
    path = _write(tmp_path, SECTION + "*ELEMENT, TYPE=C3D8R\n5, 1, 2, 3, 1, 2, 3, 1, 2\n"
                  "6, 1, 2, 3, 1, 2, 3, 1, 2\n*SURFACE, NAME=s1\ns, SPOS\n*SURFACE, NAME=s2\n"
                  "s, SNEG\n*TIE, NAME=t\ns1, s2\n")
    deck = read_abaqus(path)
    assert deck.unsupported == {"C3D8R": 2, "*SURFACE": 2, "*TIE": 1}
    deck = read_abaqus(path, ignore_cards=["c3d8r", "*SURFACE"])
    assert deck.unsupported == {"*TIE": 1}
    assert deck.ignored == {"C3D8R": 2, "*SURFACE": 2}


@pytest.mark.parametrize("text, expected", [
    (SECTION + "*BOUNDARY\n1, 1, 1, 0.5\n", r"bad.inp:13: \*BOUNDARY: prescribed displacement"),
    (SECTION + "*NSET, NSET=a\nmissing\n", r"bad.inp:13: \*NSET: NSET=a: no set 'missing'"),
    ("*ELEMENT, TYPE=S8R\n1, 1, 2, 3\n", r"bad.inp:6: \*ELEMENT: TYPE=S8R needs 8 nodes, got 3"),
    ("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n", r"shell element 1 has no \*SHELL SECTION"),
    (SECTION.replace("1.\n", "1.\n", 1) + "*SHELL SECTION, ELSET=s, MATERIAL=m, OFFSET=SPOS\n1.\n",
     r"\*SHELL SECTION: OFFSET=SPOS"),
    ("*NODE, SYSTEM=C\n9, 1, 0, 0\n", r"bad.inp:5: \*NODE: SYSTEM=C"),
    ("*ELEMENT, TYPE=S3, ELSET=s\n1, 1, 2, 99\n*MATERIAL, NAME=m\n*ELASTIC\n1., 0.3\n"
     "*SHELL SECTION, ELSET=s, MATERIAL=m\n1.\n", r"node 99 is not defined"),
    ("*NODE\n1, 5, 5, 5\n", r"bad.inp:6: \*NODE: node 1 defined twice"),
    ("*INCLUDE, INPUT=nowhere.inc\n", r"bad.inp:5: \*INCLUDE file not found"),
    (SECTION + "*BOUNDARY, OP=NEW\n1, 1, 3\n", r"bad.inp:12: \*BOUNDARY: OP=NEW"),
    ("*MATERIAL, NAME=m\n*DENSITY\n1., 20.\n2., 80.\n", r"bad.inp:6: \*DENSITY: a temperature table"),
])
def test_errors_name_file_line_and_keyword(tmp_path, text, expected):
    with pytest.raises(DeckError, match=expected) as info:
        read_abaqus(_write(tmp_path, text))
    assert "\n" not in str(info.value)


def test_abaqus_cae_export_layout():
    """An Abaqus/CAE-style export (parts, two instances, internal generated sets, a surface,
    a frequency step with output requests) reads; only *Surface is unsupported."""
    from pathlib import Path

    deck = read_abaqus(Path(__file__).with_name("abaqus_cae_plate.inp"))
    assert deck.node_ids.tolist() == [1, 2, 3, 4, 5, 6, 11, 12, 13, 14, 15, 16]
    assert np.allclose(deck.points[6:, 2], 5.0) and np.allclose(deck.points[:6, 2], 0.0)
    assert deck.unsupported == {"*SURFACE": 1}
    assert deck.shells.element_ids.tolist() == [1, 2, 11, 12]
    assert deck.node_ids[deck.supports["boundary"].nodes].tolist() == [1, 4]
    assert deck.shells.mass_per_area[0] == pytest.approx(7.8e-9 * 2.0)


def test_s8r_strip_first_bending_mode_is_the_beam_s(tmp_path):
    """A cantilever strip of ten S8R elements (split into six triangles each on all eight
    nodes): first bending frequency vs Euler–Bernoulli 1.8751²/(2π) √(EI/(ρA L⁴)), ν = 0."""
    import scipy.sparse.linalg as sla

    from sarfe.fe.deck_assembly import assemble_deck

    length, width, t, nx = 100.0, 10.0, 1.0, 10
    nid = lambda i, j: 1 + i + (2 * nx + 1) * j                          # noqa: E731
    lines = ["*NODE"]
    for j, y in enumerate((0.0, width / 2, width)):
        for i, x in enumerate(np.linspace(0, length, 2 * nx + 1)):
            if not (j == 1 and i % 2):
                lines.append(f"{nid(i, j)}, {x}, {y}, 0.")
    lines.append("*ELEMENT, TYPE=S8R, ELSET=s")
    for e in range(nx):
        i = 2 * e
        lines.append(f"{e + 1}, {nid(i, 0)}, {nid(i + 2, 0)}, {nid(i + 2, 2)}, {nid(i, 2)}, "
                     f"{nid(i + 1, 0)}, {nid(i + 2, 1)}, {nid(i + 1, 2)}, {nid(i, 1)}")
    lines += ["*NSET, NSET=clamp", f"{nid(0, 0)}, {nid(0, 1)}, {nid(0, 2)}", "*MATERIAL, NAME=m",
              "*ELASTIC", f"{E}, 0.0", "*DENSITY", f"{RHO}", "*SHELL SECTION, ELSET=s, MATERIAL=m",
              f"{t}", "*BOUNDARY", "clamp, ENCASTRE"]
    (tmp_path / "strip.inp").write_text("\n".join(lines) + "\n")
    deck = to_si(read_abaqus(tmp_path / "strip.inp"), "mm-t-s")
    system = assemble_deck(deck)
    support = deck.supports["boundary"]
    held = system.dof_index(np.repeat(support.nodes, 6), np.tile(np.arange(6), len(support.nodes)))
    free = np.setdiff1d(np.arange(system.n_dofs), held)
    omega2 = sla.eigsh(system.stiffness[free][:, free], 1, system.mass[free][:, free], sigma=0)[0]
    inertia, area = width * t**3 / 12 * 1e-12, width * t * 1e-6
    beam = 1.875104**2 / (2 * np.pi) * np.sqrt(E * 1e6 * inertia / (RHO * 1e12 * area * 0.1**4))
    assert np.sqrt(omega2[0]) / (2 * np.pi) == pytest.approx(beam, rel=2e-3)
