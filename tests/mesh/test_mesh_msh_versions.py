"""Gmsh MSH 2.2 and 4.1 files of the same mesh load to the same model (issue 14: MSH 2.2 writes
a triangle once per physical group, which used to double its stiffness, mass and area), and a
file meshio cannot read gives sarfe's one-line MeshError naming the file (meshio exits)."""
import numpy as np
import pytest

from sarfe.mesh import MeshError, load_mesh
from sarfe.mesh.geometry import triangle_areas
from sarfe.mesh.gmsh_model import gmsh_session


def write_plate(path, version):
    """0.1 x 0.05 m plate; its surface in two physical groups, one edge a node group."""
    with gmsh_session() as gmsh:
        gmsh.model.occ.addRectangle(0, 0, 0, 0.1, 0.05)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [1], name="skin")
        gmsh.model.addPhysicalGroup(2, [1], name="part_carrier")
        gmsh.model.addPhysicalGroup(1, [1], name="clip_1")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.02)
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.write(str(path))
    return path


def test_msh22_and_msh41_give_identical_models(tmp_path):
    old = load_mesh(write_plate(tmp_path / "plate22.msh", 2.2))
    new = load_mesh(write_plate(tmp_path / "plate41.msh", 4.1))
    # the radiating area is the plate's area once, not twice
    assert triangle_areas(old.points, old.triangles).sum() == pytest.approx(0.1 * 0.05, rel=1e-12)
    assert np.allclose(old.points, new.points, rtol=0, atol=1e-15)
    assert np.array_equal(old.triangles, new.triangles)
    assert old.element_groups.keys() == new.element_groups.keys()
    for name in new.element_groups:
        assert np.array_equal(old.element_groups[name], new.element_groups[name])
        assert len(new.element_groups[name]) == new.n_triangles
    for name in new.node_groups:
        assert np.array_equal(old.node_groups[name], new.node_groups[name])


@pytest.mark.parametrize("name, text", [
    ("short.inp", "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=S3\n1, 1, 2\n"),
    ("nobulk.bdf", "GRID,1,,0.,0.,0.\nCTRIA3,1,1,1,2,3\n"),
    ("cut.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0\n"),
])
def test_reader_errors_are_one_line_mesh_errors(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MeshError) as info:   # never SystemExit from meshio
        load_mesh(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message


NODES = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n"


@pytest.mark.parametrize("name, text, expected", [
    # issue 14's silent losses through meshio, now refused with the card and its line
    ("clip.bdf", "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,1.,1.,0.\n"
                 "CTRIA3,1,1,1,2,3\nCBUSH,2,5,1,3,,,,0\nCONM2,3,2,,0.5\nENDDATA\n",
     r"it would drop CBUSH \(1, first at line 6\), CONM2 \(1, first at line 7\)"),
    ("cyl.bdf", "BEGIN BULK\nGRID,1,7,1.,0.,0.\nENDDATA\n", r"cyl.bdf:2: GRID in coordinate system CP=7"),
    ("quad8.bdf", "BEGIN BULK\nCQUAD8,1,1,1,2,3,4,5,6\n,7,8\n", r"CQUAD8 \(1, first at line 2\)"),
    ("s8r.inp", NODES + "*ELEMENT, TYPE=S8R\n1, 1, 2, 3, 4, 1, 2, 3, 4\n",
     r"\*ELEMENT, TYPE=S8R \(1, first at line 6\)"),
    ("inst.inp", "*PART, NAME=p\n" + NODES + "*END PART\n*ASSEMBLY, NAME=a\n"
                 "*INSTANCE, NAME=i, PART=p\n5., 0., 0.\n*END INSTANCE\n*END ASSEMBLY\n",
     r"\*INSTANCE \(1, first at line 9\)"),
])
def test_mesh_path_refuses_what_it_would_drop(tmp_path, name, text, expected):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MeshError, match=expected) as info:
        load_mesh(path)
    assert "model.fe.deck" in str(info.value) and "\n" not in str(info.value)


def test_quality_checks_name_ids():
    from sarfe.mesh import quality

    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [1, 1, 0]], float)
    shells = np.array([[0, 1, 2, -1], [0, 1, 2, 3], [2, 1, 0, -1], [0, 1, 4, -1], [1, 2, 5, -1]])
    ids = np.array([10, 11, 12, 13, 14])
    assert quality.duplicate_elements(shells, ids) == [(10, 12)]       # reversed copy
    assert quality.degenerate_elements(points, shells, ids) == [13, 14]  # collinear, repeated point
    assert np.allclose(quality.shell_areas(points, shells[:2]), [0.5, 1.0])
    node_ids = np.arange(1, 7)
    assert quality.coincident_nodes(points, node_ids, 1e-9) == [(3, 6)]
    assert quality.coincident_nodes(points, node_ids, 1e-9, joined=[(2, 5)]) == []
