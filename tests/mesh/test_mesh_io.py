"""load_mesh round trips through meshio-written .inp, .bdf and .msh files; units; errors."""
import meshio
import numpy as np
import pytest

from sarfe.mesh import MeshError, load_mesh

POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0], [2, 0, 0], [2, 1, 0],
                   [7, 7, 7]], dtype=float)  # last node unused → dropped
TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])
QUADS = np.array([[1, 4, 5, 2]])
# expected after loading: quad split into (1,4,5), (1,5,2); node 6 dropped
EXPECTED_TRIANGLES = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])


def check(mesh, scale=1.0):
    assert np.allclose(mesh.points, POINTS[:6] * scale, rtol=1e-12, atol=0)
    assert np.array_equal(mesh.triangles, EXPECTED_TRIANGLES)


def test_abaqus_sets(tmp_path):
    path = tmp_path / "panel.inp"
    meshio.write(path, meshio.Mesh(POINTS, [("triangle", TRIANGLES), ("quad", QUADS)],
                                   point_sets={"clip_1": np.array([0, 3])},
                                   cell_sets={"part_b": [np.array([], dtype=int), np.array([0])]}),
                 file_format="abaqus")
    mesh = load_mesh(path)
    check(mesh)
    assert list(mesh.node_group("clip_1")) == [0, 3]
    assert list(mesh.element_group("part_b")) == [2, 3]
    assert list(mesh.node_group("part_b")) == [1, 2, 4, 5]
    check(load_mesh(path, length_unit="mm"), 1e-3)


def test_abaqus_shell_element_types(tmp_path):
    nodes = "\n".join(f"{i + 1}, {x}, {y}, {z}" for i, (x, y, z) in enumerate(POINTS))
    path = tmp_path / "shell.inp"
    path.write_text(f"*NODE\n{nodes}\n*ELEMENT, TYPE=S3, ELSET=skin\n1, 1, 2, 3\n2, 1, 3, 4\n"
                    "*ELEMENT, TYPE=S4R, ELSET=part_b\n3, 2, 5, 6, 3\n*ELSET, ELSET=both\n2, 3\n")
    mesh = load_mesh(path, length_unit="mm")
    check(mesh, 1e-3)
    assert list(mesh.element_group("skin")) == [0, 1]
    assert list(mesh.element_group("both")) == [1, 2, 3]


def test_nastran_property_groups(tmp_path):
    path = tmp_path / "panel.bdf"
    meshio.write(path, meshio.Mesh(POINTS, [("triangle", TRIANGLES), ("quad", QUADS)],
                                   cell_data={"nastran:ref": [np.array([1, 1]), np.array([7])]}),
                 file_format="nastran")
    mesh = load_mesh(path, length_unit="mm")
    check(mesh, 1e-3)
    assert list(mesh.element_group("pid_1")) == [0, 1]
    assert list(mesh.element_group("pid_7")) == [2, 3]
    assert list(mesh.node_group("pid_7")) == [1, 2, 4, 5]


def test_gmsh_physical_groups(tmp_path):
    path = tmp_path / "panel.msh"
    cells = [("triangle", TRIANGLES), ("quad", QUADS), ("vertex", np.array([[3]]))]
    data = {"gmsh:physical": [np.array([1, 1]), np.array([2]), np.array([3])],
            "gmsh:geometrical": [np.array([1, 1]), np.array([2]), np.array([3])]}
    meshio.write(path, meshio.Mesh(POINTS, cells, cell_data=data,
                                   field_data={"part_a": np.array([1, 2]), "part_b": np.array([2, 2]),
                                               "excite_1": np.array([3, 0])}),
                 file_format="gmsh22", binary=False)
    mesh = load_mesh(path)
    check(mesh)
    assert list(mesh.element_group("part_a")) == [0, 1]
    assert list(mesh.element_group("part_b")) == [2, 3]
    assert list(mesh.node_group("excite_1")) == [3]
    assert list(mesh.node_group("part_a")) == [0, 1, 2, 3]


def test_errors(tmp_path):
    with pytest.raises(MeshError, match="not found"):
        load_mesh(tmp_path / "missing.msh")
    bad = tmp_path / "bad.inp"
    bad.write_text("*NODE\n1, 0, 0\n*ELEMENT, TYPE=S3\n1, 1, 2, 99\n")
    with pytest.raises(MeshError) as info:
        load_mesh(bad)
    assert "\n" not in str(info.value)
    with pytest.raises(MeshError, match="unknown mesh file type"):
        (tmp_path / "x.stl").write_text("solid")
        load_mesh(tmp_path / "x.stl")
    with pytest.raises(MeshError, match="unknown length unit"):
        load_mesh(bad, length_unit="furlong")


def test_tetrahedra_kept_and_shells_split(tmp_path):
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    path = tmp_path / "solid.inp"
    meshio.write(path, meshio.Mesh(points, [("tetra", np.array([[0, 1, 2, 3]])),
                                            ("triangle", np.array([[1, 2, 4]]))]),
                 file_format="abaqus")
    mesh = load_mesh(path)
    assert np.array_equal(mesh.tetrahedra, [[0, 1, 2, 3]])
    assert np.array_equal(mesh.triangles, [[1, 2, 4]])


def test_panel_mesh_copies_inputs():
    from sarfe.mesh import PanelMesh

    points = np.zeros((3, 3))
    mesh = PanelMesh(points, [[0, 1, 2]])
    points[0, 0] = 1.0  # caller's array stays writable and independent
    assert mesh.points[0, 0] == 0.0
