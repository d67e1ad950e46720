"""Points coupled to the shell by its shape functions (sarfe.fe.coupling): exact rigid motion and
quadratic deflection, contact rows, and a contact at fixed coordinates that answers the same on
three meshes whose nodes miss it (against a converged 1.5 mm mesh; a node pairing does not)."""

import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.fe import fixed_dofs, free_dofs, natural_frequencies, shell_matrices
from sarfe.fe.coupling import (
    contact_operator,
    face_offsets,
    point_rotation_weights,
    point_weights,
)
from sarfe.linalg import factorize
from sarfe.fe.reference_meshes import boundary_nodes, gmsh_rectangle_triangles
from sarfe.mesh import facet_normals
from sarfe.mesh.contact_geometry import frames_from_normals, project_to_surface

RNG = np.random.default_rng(7)


def one_triangle_points(m):
    corners = RNG.normal(size=(3, 3))
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    return corners, normal / np.linalg.norm(normal), RNG.dirichlet([1, 1, 1], size=m), \
        RNG.normal(scale=0.1, size=m)


@pytest.mark.parametrize("bending", ["cubic", "linear"])
def test_rigid_motion_moves_the_offset_point_rigidly(bending):
    """u_i = a + ω × x_i, θ_i = ω  ⇒  θ_p = ω and u_p = a + ω × (x_p + z n_s) for any point,
    offset and offset direction n_s (the facet normal n by default)."""
    corners, normal, bary, z = one_triangle_points(60)
    a, omega = RNG.normal(size=3), RNG.normal(size=3)
    u = np.concatenate([np.r_[a + np.cross(omega, x), omega] for x in corners])
    element = np.zeros(60, int)
    weights = point_weights(corners, [[0, 1, 2]], element, bary, z, bending=bending)
    exact = a + np.cross(omega, bary @ corners + z[:, None] * normal)
    np.testing.assert_allclose((weights @ u).reshape(-1, 3), exact, atol=1e-13)
    tilted = normal + RNG.normal(scale=0.3, size=(60, 3))
    tilted /= np.linalg.norm(tilted, axis=1, keepdims=True)
    weights = point_weights(corners, [[0, 1, 2]], element, bary, z, tilted, bending=bending)
    exact = a + np.cross(omega, bary @ corners + z[:, None] * tilted)
    np.testing.assert_allclose((weights @ u).reshape(-1, 3), exact, atol=1e-13)
    rotation = point_rotation_weights(corners, [[0, 1, 2]], element, bary, bending=bending)
    np.testing.assert_allclose((rotation @ u).reshape(-1, 3), np.tile(omega, (60, 1)),
                               atol=1e-13)


def test_a_point_at_a_node_does_not_depend_on_the_triangle_chosen():
    """At a vertex (L = e_i) the point is the node: u_p = u_i + θ_i × z n_s whichever of the
    node's triangles holds it (the pad's pole, where the facets lean by degrees)."""
    points, triangles = gmsh_rectangle_triangles(0.05, 0.04, 0.01)
    points = points + np.column_stack([np.zeros((len(points), 2)),
                                       RNG.normal(scale=2e-3, size=len(points))])   # curved
    node = np.argmin(np.linalg.norm(points[:, :2] - [0.025, 0.02], axis=1))
    holding = np.flatnonzero(np.any(triangles == node, axis=1))
    slot = np.argmax(triangles[holding] == node, axis=1)
    bary = np.eye(3)[slot]
    direction = np.array([0.1, -0.2, 1.0]) / np.linalg.norm([0.1, -0.2, 1.0])
    weights = point_weights(points, triangles, holding, bary, 1.25e-3, direction).toarray()
    expected = np.zeros((3, 6 * len(points)))
    expected[:, 6 * node:6 * node + 3] = np.eye(3)
    expected[:, 6 * node + 3:6 * node + 6] = -np.array(
        [[0, -direction[2], direction[1]], [direction[2], 0, -direction[0]],
         [-direction[1], direction[0], 0]]) * 1.25e-3
    for p in range(len(holding)):
        np.testing.assert_allclose(weights[3 * p:3 * p + 3], expected, atol=1e-15)


def test_cubic_interpolation_is_exact_for_a_quadratic_deflection():
    """Nodal w_i and Kirchhoff rotations θ_i = ∇w_i × n of any quadratic w: the point's
    u_p = n w(x_p) − z ∇w(x_p) exactly (the Kirchhoff face displacement), inside the facet."""
    corners, normal, bary, z = one_triangle_points(60)
    e1 = np.cross(normal, [0.3, -0.2, 0.9])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    q, g, w0 = RNG.normal(size=(2, 2)), RNG.normal(size=2), RNG.normal()
    q = q + q.T

    def local(x):
        return np.stack([(x - corners[0]) @ e1, (x - corners[0]) @ e2], axis=-1)

    def deflection(x):
        s = local(x)
        return w0 + s @ g + np.einsum("...i,ij,...j->...", s, q, s)

    def slope(x):
        grad = g + 2 * local(x) @ q
        return grad[..., :1] * e1 + grad[..., 1:] * e2

    u = np.concatenate([np.r_[normal * deflection(x), np.cross(slope(x), normal)]
                        for x in corners])
    weights = point_weights(corners, [[0, 1, 2]], np.zeros(60, int), bary, z)
    x_p = bary @ corners
    exact = normal * deflection(x_p)[:, None] - z[:, None] * slope(x_p)
    np.testing.assert_allclose((weights @ u).reshape(-1, 3), exact, atol=1e-12)


def test_contact_rows_are_the_frame_times_the_relative_point_motion():
    points, triangles = gmsh_rectangle_triangles(0.05, 0.04, 0.01)
    n_dof = 6 * len(points)
    query = np.column_stack([RNG.uniform(0, 0.05, 5), RNG.uniform(0, 0.04, 5), np.zeros(5)])
    p = project_to_surface(query, points, triangles)
    weights_a = point_weights(points, triangles, p.element, p.barycentric, 1e-3)
    weights_b = point_weights(points, triangles, p.element[::-1], p.barycentric[::-1], -1e-3)
    normals = RNG.normal(size=(5, 3))
    frames = frames_from_normals(normals / np.linalg.norm(normals, axis=1, keepdims=True))
    rows = contact_operator(frames, weights_a, weights_b)
    assert sp.issparse(rows) and rows.shape == (15, n_dof)
    u = RNG.normal(size=n_dof)
    relative = ((weights_a - weights_b) @ u).reshape(5, 3)
    np.testing.assert_allclose((rows @ u).reshape(5, 3), np.einsum("pij,pj->pi", frames, relative))
    np.testing.assert_allclose((contact_operator(frames, weights_a) @ u).reshape(5, 3),
                               np.einsum("pij,pj->pi", frames, (weights_a @ u).reshape(5, 3)))


def test_face_offset_picks_the_side_facing_the_partner():
    normal = np.array([[0, 0, 1.0], [0, 0, -1.0]])
    np.testing.assert_allclose(face_offsets(normal, [0, 0, 1.0], 2e-3), [1e-3, -1e-3])
    np.testing.assert_allclose(face_offsets(normal, [0, 0, -1.0], 2e-3, offset_m=5e-4),
                               [-5e-4, 1.5e-3])


# --- a point contact on a clamped ABS plate, 100 × 100 × 2.5 mm, as in the squeak rig ----------
SIDE, T, E, NU, RHO = 0.1, 2.5e-3, 2.2e9, 0.37, 1050.0
POINTS = np.array([[0.0637, 0.0289, 0.0], [0.0291, 0.0712, 0.0]])   # contact, transfer point


def point_response(size):
    """Normal compliance at the contact (N: direct, transfer to the second point) [m/N]; the
    mass-normalized first mode at the contact: normal and, on the upper face, tangential (x);
    the normal compliance of the nearest node (today's node pairing); nearest-node distance [m]."""
    points, triangles = gmsh_rectangle_triangles(SIDE, SIDE, size)
    k, m = shell_matrices(points, triangles, T, E, NU, RHO)
    fixed = fixed_dofs(boundary_nodes(triangles))
    free = free_dofs(k.shape[0], fixed)
    p = project_to_surface(POINTS, points, triangles)
    face = face_offsets(facet_normals(points, triangles)[p.element], [0, 0, 1.0], T)
    mid = point_weights(points, triangles, p.element, p.barycentric)[:, free].toarray()
    upper = point_weights(points, triangles, p.element, p.barycentric, face)[:, free].toarray()
    factor = factorize(k[free][:, free])
    normal_rows = mid[[2, 5]]
    compliance = normal_rows @ factor.solve(normal_rows.T)
    _, modes = natural_frequencies(k, m, 1, fixed, return_modes=True)
    mode = modes[free, 0] * np.sign(mid[2] @ modes[free, 0])
    nearest = np.argmin(np.linalg.norm(points[:, None] - POINTS, axis=2), axis=0)
    node_rows = np.zeros((2, k.shape[0]))
    node_rows[[0, 1], 6 * nearest + 2] = 1.0
    node_rows = node_rows[:, free]
    return dict(direct=compliance[0, 0], transfer=compliance[0, 1], mode_normal=mid[2] @ mode,
                mode_tangential=upper[0] @ mode, both=np.diag(compliance),
                node=np.diag(node_rows @ factor.solve(node_rows.T)),
                clearance=np.min(np.linalg.norm(points - POINTS[0], axis=1)))


@pytest.fixture(scope="module")
def responses():
    return {size: point_response(size) for size in (0.005, 0.004, 0.003, 0.0015)}


def test_point_contact_is_mesh_independent_within_1_percent(responses):
    """Measured vs the 1.5 mm mesh, 5 / 4 / 3 mm: direct compliance +0.53 / +0.33 / +0.19 %
    (+0.61 / +0.47 / +0.25 % at the second point), transfer +0.38 / +0.26 / +0.13 %, first mode
    normal +0.37 / +0.22 / +0.11 %, tangential on the face (−(t/2) ∂φ/∂x) +0.24 / +0.16 / +0.06 %."""
    reference = responses[0.0015]
    for size in (0.005, 0.004, 0.003):
        r = responses[size]
        assert r["clearance"] > 0.1 * size                      # no node at the point
        for key in ("direct", "transfer", "mode_normal", "mode_tangential"):
            assert abs(r[key] / reference[key] - 1) < 0.01, (size, key, r[key] / reference[key])
    assert reference["mode_tangential"] / reference["mode_normal"] == pytest.approx(
        0.03, rel=0.2)                                          # t/2 × slope/deflection


def test_node_pairing_is_what_moved_with_the_mesh(responses):
    """Today's contact at the nearest node: its compliance swings between the meshes (the node
    sits 0.7–2 mm from the point; measured 2.3 % and 15.4 % peak to peak at the two points),
    the point's by < 0.5 % — the test above has teeth."""
    node = np.array([responses[s]["node"] for s in (0.005, 0.004, 0.003)])
    point = np.array([responses[s]["both"] for s in (0.005, 0.004, 0.003)])
    assert np.max(np.ptp(node, axis=0) / node.mean(axis=0)) > 0.05
    assert np.max(np.ptp(point, axis=0) / point.mean(axis=0)) < 0.01
