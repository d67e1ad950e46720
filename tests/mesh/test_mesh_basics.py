"""PanelMesh data structure and vectorized geometry helpers, against closed forms."""
import numpy as np
import pytest

from sarfe.mesh import (GroupError, PanelMesh, connected_components, nodal_areas, node_normals,
                        orient_triangles, orphan_nodes, triangle_areas)


def grid(n=4, size=1.0):
    """Flat square [0, size]² split into 2 n² triangles with randomly flipped orientation."""
    x = np.linspace(0, size, n + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tri = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    flip = np.random.default_rng(0).random(len(tri)) < 0.5
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return points, tri


def test_nodal_areas_sum_and_values():
    points, tri = grid(4, 2.0)
    areas = nodal_areas(points, tri)
    assert areas.sum() == pytest.approx(4.0, rel=1e-14)
    assert triangle_areas(points, tri) == pytest.approx(np.full(len(tri), 4.0 / 32))


def test_orientation_and_normals_on_sphere_and_plate():
    points, tri = grid(5)
    oriented = orient_triangles(points, tri)
    normals = node_normals(points, tri)
    assert np.allclose(normals, [0, 0, 1])
    assert np.allclose(node_normals(points, tri, reference=[0, 0, -1]), [0, 0, -1])
    assert len(oriented) == len(tri)
    # closed sphere: outward normals, unit length
    theta, phi = np.meshgrid(np.linspace(0.3, np.pi - 0.3, 8), np.linspace(0, 2 * np.pi, 13)[:-1])
    from scipy.spatial import ConvexHull
    p = np.column_stack([np.sin(theta.ravel()) * np.cos(phi.ravel()),
                         np.sin(theta.ravel()) * np.sin(phi.ravel()), np.cos(theta.ravel())])
    p = np.vstack([p, [[0, 0, 1], [0, 0, -1]]])
    hull = ConvexHull(p).simplices.copy()
    flip = np.random.default_rng(1).random(len(hull)) < 0.5
    hull[flip] = hull[flip][:, [0, 2, 1]]
    n = node_normals(p, hull)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", n, p) > 0.9)


def test_components_orphans_subset_and_group_errors():
    points, tri = grid(2)
    second = tri + len(points)
    points2 = np.vstack([points, points + [0, 0, 1], [[9, 9, 9]]])
    mesh = PanelMesh(points2, np.vstack([tri, second]),
                     node_groups={"clip_1": [0], "contact_x_a": [1], "contact_x_b": [len(points) + 1]},
                     element_groups={"part_a": np.arange(len(tri)),
                                     "part_b": np.arange(len(tri), 2 * len(tri))})
    count, labels = connected_components(mesh.n_nodes, mesh.triangles)
    assert count == 2 and labels[-1] == -1
    assert list(orphan_nodes(mesh.n_nodes, mesh.triangles)) == [mesh.n_nodes - 1]
    part = mesh.part("b")
    assert part.n_nodes == len(points) and part.n_triangles == len(tri)
    assert list(part.node_groups["contact_x_b"]) == [1] and len(part.node_groups["clip_1"]) == 0
    assert list(mesh.contact_pairs()) == ["x"]
    with pytest.raises(GroupError, match="available: clip_1, contact_x_a, contact_x_b"):
        mesh.node_group("clamp")
    with pytest.raises(KeyError):
        mesh.element_group("skin")
    with pytest.raises(ValueError):
        PanelMesh(points, tri + 100)
    assert not mesh.points.flags.writeable
