"""Contact geometry (sarfe.mesh.contact_geometry): closest points against brute force, the patch
normal of the squeak rig's revolved pad against its exact axis where the mesh's node normal leans
by degrees, frames and gaps."""

import numpy as np
import pytest

from sarfe.erp import nodal_normals
from sarfe.fe.reference_meshes import cylindrical_panel_triangles, gmsh_rectangle_triangles
from sarfe.mesh.contact_geometry import (
    closest_points_on_triangles,
    facet_average_normals,
    facet_normal_spread_deg,
    frames_from_normals,
    orient_normals,
    patch_normals,
    project_to_surface,
    separation_normals,
    surface_gap,
)
from sarfe.mesh.generators import squeak_rig

RNG = np.random.default_rng(29)


def angle_deg(u, v):
    u, v = np.atleast_2d(u), np.atleast_2d(v)
    cosine = np.einsum("ij,ij->i", u, v) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
    return np.degrees(np.arccos(np.clip(np.abs(cosine), 0.0, 1.0)))


def brute_force_distance(query, corners, n=400):
    """Smallest distance from query to a dense barycentric grid of the triangle (and its edges)."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    bary = np.column_stack([i[keep], j[keep], n - i[keep] - j[keep]]) / n
    samples = bary @ corners
    return np.min(np.linalg.norm(samples - query, axis=1))


def random_triangle():
    corners = RNG.normal(size=(3, 3))
    while np.linalg.norm(np.cross(corners[1] - corners[0], corners[2] - corners[0])) < 0.5:
        corners = RNG.normal(size=(3, 3))
    return corners


def region_query(corners, region):
    """A query point whose closest point on the triangle is known by construction (the
    optimality conditions of each Voronoi region): returns (query, closest, barycentric)."""
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    lift = RNG.uniform(-1, 1) * normal
    if region == "inside":
        bary = RNG.dirichlet([2, 2, 2])
        closest = bary @ corners
        return closest + lift, closest, bary
    i = RNG.integers(3)
    j, k = (i + 1) % 3, (i + 2) % 3
    if region == "edge":
        s = RNG.uniform(0.1, 0.9)
        bary = np.zeros(3)
        bary[i], bary[j] = 1 - s, s
        edge = corners[j] - corners[i]
        outward = np.cross(edge, normal)                     # in-plane, away from x_k
        outward *= np.sign(outward @ (corners[i] - corners[k]))
        closest = bary @ corners
        return closest + RNG.uniform(0.1, 1) * outward / np.linalg.norm(outward) + lift, \
            closest, bary
    # vertex: a direction d in the plane with d·(x_j − x_i) < 0 and d·(x_k − x_i) < 0
    e1 = (corners[j] - corners[i]) / np.linalg.norm(corners[j] - corners[i])
    e2 = (corners[k] - corners[i]) / np.linalg.norm(corners[k] - corners[i])
    d = e1
    while d @ e1 > -0.05 or d @ e2 > -0.05:                  # rejection: inside the cone
        d = RNG.normal(size=3)
        d -= (d @ normal) * normal
        d /= np.linalg.norm(d)
    bary = np.eye(3)[i]
    return corners[i] + RNG.uniform(0.1, 1) * d + lift, corners[i].copy(), bary


@pytest.mark.parametrize("region", ["inside", "edge", "vertex"])
def test_closest_point_on_a_triangle_by_region_against_brute_force(region):
    cases = [(c, *region_query(c, region)) for c in (random_triangle() for _ in range(40))]
    corners = np.array([c[0] for c in cases])
    query = np.array([c[1] for c in cases])
    closest, bary = closest_points_on_triangles(query, corners)
    np.testing.assert_allclose(closest, [c[2] for c in cases], atol=1e-12)
    np.testing.assert_allclose(bary, [c[3] for c in cases], atol=1e-12)
    assert np.all(bary >= -1e-15) and np.allclose(bary.sum(axis=1), 1.0)
    distance = np.linalg.norm(closest - query, axis=1)
    brute = np.array([brute_force_distance(q, c) for q, c in zip(query[:8], corners[:8])])
    # the grid never beats the exact minimum, and comes within its spacing (~3/400 of the size)
    assert np.all(brute >= distance[:8] - 1e-12)
    assert np.all(brute - distance[:8] < 2e-2)


def test_projection_onto_a_curved_surface_matches_the_exhaustive_search():
    points, triangles = cylindrical_panel_triangles(0.5, 0.4, 0.15, 24, 15)
    span = np.ptp(points, axis=0)
    query = points.min(axis=0) + RNG.uniform(-0.1, 1.1, size=(300, 3)) * span
    query[:, 2] += RNG.normal(scale=0.02, size=300)
    projection = project_to_surface(query, points, triangles)
    # exhaustive: every point against every triangle, vectorized
    m, n = len(query), len(triangles)
    every, _ = closest_points_on_triangles(np.repeat(query, n, axis=0),
                                           np.tile(points[triangles], (m, 1, 1)))
    exhaustive = np.linalg.norm(every - np.repeat(query, n, axis=0), axis=1).reshape(m, n).min(1)
    np.testing.assert_allclose(projection.distance, exhaustive, rtol=0, atol=1e-14)
    rebuilt = np.einsum("mv,mvi->mi", projection.barycentric,
                        points[triangles[projection.element]])
    np.testing.assert_allclose(rebuilt, projection.point, atol=1e-14)


@pytest.fixture(scope="module")
def rig_meshes():
    return {h: squeak_rig.generate(mesh_size=h) for h in (0.012, 0.010, 0.009, 0.008, 0.006, 0.004)}


def test_patch_normal_of_the_rig_pad_is_its_axis_where_the_node_normal_leans(rig_meshes):
    """The pad is a revolved cap (axis z): at its pole the area-weighted node normal leans with
    the mesh (1.1–4.2° on these meshes); the patch normal (R = 3 mm) is the axis within 0.1°
    (measured ≤ 0.05°); so is the normal at an off-pole node (the sphere's radius, R = 12 mm)."""
    leans, errors = [], []
    for mesh in rig_meshes.values():
        apex = mesh.node_group("contact_rub_a")
        pad = mesh.triangles[mesh.element_group("part_bump")]
        leans.append(angle_deg(nodal_normals(mesh.points, mesh.triangles)[apex], [0, 0, 1])[0])
        errors.append(angle_deg(patch_normals(mesh.points[apex], mesh.points, pad, 0.003),
                                [0, 0, 1])[0])
        ring = np.unique(pad)
        radial = np.linalg.norm(mesh.points[ring, :2], axis=1)
        off_pole = ring[np.argmin(np.abs(radial - 0.0025))]
        exact = mesh.points[off_pole] - [0.0, 0.0, 0.012]             # sphere centre
        errors.append(angle_deg(patch_normals(mesh.points[off_pole], mesh.points, pad, 0.003),
                                exact)[0])
    assert min(leans) > 1.0 and max(leans) > 4.0
    assert max(errors) < 0.1, errors
    # the facets' own average leans where the nodes' fit does not (why the fit is used)
    mesh = rig_meshes[0.010]
    apex = mesh.node_group("contact_rub_a")
    pad = mesh.triangles[mesh.element_group("part_bump")]
    assert angle_deg(facet_average_normals(mesh.points[apex], mesh.points, pad, 0.003),
                     [0, 0, 1])[0] > 0.3


def test_patch_normal_and_spread_on_flat_and_folded_surfaces():
    points, triangles = gmsh_rectangle_triangles(0.1, 0.08, 0.006)
    centres = np.column_stack([RNG.uniform(0.01, 0.09, 20), RNG.uniform(0.01, 0.07, 20),
                               np.zeros(20)])
    normal = patch_normals(centres, points, triangles, 0.004, reference=[0, 0, 1])
    np.testing.assert_allclose(normal, np.tile([0, 0, 1.0], (20, 1)), atol=1e-12)
    assert np.all(facet_normal_spread_deg(centres, points, triangles, 0.004) < 1e-6)
    # fold the rectangle by 90° about x = 0.05: a ridge; the spread sees the two faces
    folded = points.copy()
    beyond = points[:, 0] > 0.05
    folded[beyond, 2] = points[beyond, 0] - 0.05
    folded[beyond, 0] = 0.05
    ridge = np.array([[0.05, 0.04, 0.0]])
    assert 40.0 < facet_normal_spread_deg(ridge, folded, triangles, 0.004)[0] < 50.1
    # the patch normal of a symmetric ridge bisects it
    assert angle_deg(patch_normals(ridge, folded, triangles, 0.004), [-1, 0, 1])[0] < 5.0


def test_frames_separation_and_orientation():
    normals = RNG.normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    frames = frames_from_normals(normals)
    np.testing.assert_allclose(frames @ frames.transpose(0, 2, 1), np.tile(np.eye(3), (50, 1, 1)),
                               atol=1e-14)
    np.testing.assert_allclose(np.cross(frames[:, 1], frames[:, 2]), normals, atol=1e-14)
    np.testing.assert_allclose(frames[:, 0], normals)
    a = RNG.normal(size=(4, 3))
    b = a + [[0, 0, 2e-3], [0, 0, 0], [3e-3, 0, 0], [0, 0, 1e-12]]
    n, apart = separation_normals(a, b)
    assert apart.tolist() == [True, False, True, False]
    np.testing.assert_allclose(n, [[0, 0, 1], [0, 0, 0], [1, 0, 0], [0, 0, 0]], atol=1e-9)
    flipped = orient_normals(np.tile([0, 0, 1.0], (4, 1)), b - a + [[0, 0, 0]] * 4)
    assert flipped[0, 2] == 1.0
    assert orient_normals([0, 0, 1.0], [0, 0, -1.0])[2] == -1.0


def test_surface_gap_from_mid_surfaces():
    # the squeak rig meshes the pad apex on the plate's mid-surface: 2 mm of overlap
    assert surface_gap(0.0, 1.5e-3, 2.5e-3) == pytest.approx(-2.0e-3)
    np.testing.assert_allclose(surface_gap([5e-3, 4e-3], 1e-3, 2e-3, offset_a_m=[0.0, 5e-4]),
                               [3.5e-3, 2.0e-3])
