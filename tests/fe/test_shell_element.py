"""Facet shell element: rigid-body modes, patch tests, invariance, mass, input handling."""

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse.linalg as sla

from sarfe.fe import fixed_dofs, free_dofs, shell_element_matrices, shell_matrices
from sarfe.fe.reference_meshes import (
    boundary_nodes,
    cylindrical_panel_triangles,
    rectangle_triangles,
)

E, NU, RHO, H = 2.2e9, 0.35, 1050.0, 2.5e-3


def rotation_matrix(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def rigid_motions(points):
    """(6n, 6) columns: three translations and three infinitesimal rotations u = θ × x."""
    n = len(points)
    modes = np.zeros((n, 6, 6))
    for c in range(3):
        modes[:, c, c] = 1.0
        axis = np.eye(3)[c]
        modes[:, :3, 3 + c] = np.cross(axis, points)
        modes[:, 3 + c, 3 + c] = 1.0
    return modes.reshape(6 * n, 6)


def count_zero_modes(stiffness, mass, relative=1e-12):
    """Eigenvalues below ``relative`` × the largest (rigid modes sit at round-off, ~1e-17; the
    softest bending mode of the curved patch at ~7e-9 of the stiff drilling/membrane end)."""
    eigenvalues = sl.eigh(stiffness, mass, eigvals_only=True)
    return int(np.sum(eigenvalues < relative * eigenvalues.max())), eigenvalues


def curved_mesh():
    """Doubly curved free patch: a cylinder panel bent further into a saddle."""
    points, triangles = cylindrical_panel_triangles(0.3, 0.8, 0.2, 6, 5)
    points = points.copy()
    points[:, 2] += 0.4 * (points[:, 1] - 0.1) ** 2
    return points, triangles


def test_single_free_element_has_exactly_six_rigid_modes():
    points = np.array([[0.0, 0.0, 0.0], [0.11, 0.02, 0.01], [0.03, 0.09, -0.02]])
    k, m = shell_matrices(points, [[0, 1, 2]], H, E, NU, RHO)
    n_zero, eigenvalues = count_zero_modes(k.toarray(), m.toarray())
    assert n_zero == 6
    assert eigenvalues[6] > 1e-6 * eigenvalues.max()  # seventh clearly elastic


def test_free_curved_mesh_has_exactly_six_rigid_modes_and_no_rigid_forces():
    points, triangles = curved_mesh()
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    n_zero, eigenvalues = count_zero_modes(k.toarray(), m.toarray())
    assert n_zero == 6
    rigid = rigid_motions(points)
    forces = k @ rigid
    scale = abs(k).max() * np.abs(rigid).max()
    assert np.abs(forces).max() < 1e-9 * scale


def test_mass_is_positive_definite_and_rigid_translation_mass_is_exact():
    points, triangles = curved_mesh()
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    np.linalg.cholesky(m.toarray())  # raises if not positive definite
    x = points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1).sum()
    rigid = rigid_motions(points)
    for c in range(3):
        assert rigid[:, c] @ (m @ rigid[:, c]) == pytest.approx(RHO * H * area, rel=1e-12)


def test_stiffness_and_mass_are_symmetric_csr_of_6n():
    points, triangles = curved_mesh()
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    assert k.format == "csr" and m.format == "csr"
    assert k.shape == m.shape == (6 * len(points), 6 * len(points))
    assert abs(k - k.T).max() <= 1e-12 * abs(k).max()
    assert abs(m - m.T).max() <= 1e-12 * abs(m).max()


# ---------------------------------------------------------------- patch tests

def patch_mesh():
    """Distorted patch with interior nodes (4 × 4 cells, irregular interior)."""
    return rectangle_triangles(0.1, 0.08, 4, 4, pattern="alternating", distortion=0.3, seed=3)


def tilt(points, vectors=None):
    """Apply one fixed rigid 3D rotation (to points, or to 3-vectors per node)."""
    rotation = rotation_matrix([0.3, -0.7, 0.5], 0.9)
    return (points if vectors is None else vectors) @ rotation.T, rotation


def solve_with_boundary_values(k, u_exact, boundary_dofs):
    """Impose u_exact on boundary DOFs, solve K u = 0 on the rest."""
    free = free_dofs(k.shape[0], boundary_dofs)
    u = u_exact.copy()
    u[free] = 0.0
    rhs = -(k @ u)[free]
    u[free] = sla.spsolve(k[free][:, free].tocsc(), rhs)
    return u, free


@pytest.mark.parametrize("tilted", [False, True])
def test_membrane_patch_constant_strain(tilted):
    """u = a + ε·x (linear) with θz = its rotation ω: interior residual 0, solve reproduces it."""
    points, triangles = patch_mesh()
    n = len(points)
    grad = np.array([[1.2e-3, -0.4e-3], [0.9e-3, -0.7e-3]])  # ∂(u, v)/∂(x, y)
    inplane = points[:, :2] @ grad.T + np.array([1e-4, -2e-4])
    omega = 0.5 * (grad[1, 0] - grad[0, 1])
    u_local = np.zeros((n, 6))
    u_local[:, :2] = inplane
    u_local[:, 5] = omega
    if tilted:
        points_g, rotation = tilt(points)
        u_global = np.hstack([u_local[:, :3] @ rotation.T, u_local[:, 3:] @ rotation.T])
    else:
        points_g, u_global = points, u_local
    k, _ = shell_matrices(points_g, triangles, H, E, NU, RHO)
    u_exact = u_global.ravel()
    boundary = fixed_dofs(boundary_nodes(triangles))
    free = free_dofs(6 * n, boundary)
    residual = (k @ u_exact)[free]
    boundary_force = np.abs(k @ u_exact).max()
    assert np.abs(residual).max() < 1e-9 * boundary_force
    u, _ = solve_with_boundary_values(k, u_exact, boundary)
    assert np.allclose(u, u_exact, rtol=0, atol=1e-9 * np.abs(u_exact).max())
    # exact strain energy ½ εᵀ D ε t A
    strain = np.array([grad[0, 0], grad[1, 1], grad[0, 1] + grad[1, 0]])
    d = E / (1 - NU**2) * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])
    energy = 0.5 * u_exact @ (k @ u_exact)
    assert energy == pytest.approx(0.5 * strain @ d @ strain * H * 0.1 * 0.08, rel=1e-10)


@pytest.mark.parametrize("tilted", [False, True])
def test_bending_patch_constant_curvature(tilted):
    """w = −(κx x² + κy y² + κxy x y)/2, θx = w,y, θy = −w,x: exact curvature and field."""
    points, triangles = patch_mesh()
    n = len(points)
    kx, ky, kxy = 0.8, -0.5, 0.6  # curvature [1/m]: [βx,x, βy,y, βx,y + βy,x]
    x, y = points[:, 0], points[:, 1]
    w = -(kx * x**2 + ky * y**2 + kxy * x * y) / 2
    w_x = -(kx * x + kxy * y / 2)
    w_y = -(ky * y + kxy * x / 2)
    u_local = np.zeros((n, 6))
    u_local[:, 2] = w
    u_local[:, 3] = w_y
    u_local[:, 4] = -w_x
    if tilted:
        points_g, rotation = tilt(points)
        u_global = np.hstack([u_local[:, :3] @ rotation.T, u_local[:, 3:] @ rotation.T])
    else:
        points_g, u_global = points, u_local
    k, _ = shell_matrices(points_g, triangles, H, E, NU, RHO)
    u_exact = u_global.ravel()
    boundary = fixed_dofs(boundary_nodes(triangles))
    free = free_dofs(6 * n, boundary)
    assert np.abs((k @ u_exact)[free]).max() < 1e-9 * np.abs(k @ u_exact).max()
    u, _ = solve_with_boundary_values(k, u_exact, boundary)
    assert np.allclose(u, u_exact, rtol=0, atol=1e-8 * np.abs(u_exact).max())
    # energy of the exact constant curvature: ½ κᵀ D_b κ A
    curvature = np.array([kx, ky, kxy])
    d_b = E * H**3 / (12 * (1 - NU**2)) * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])
    energy = 0.5 * u_exact @ (k @ u_exact)
    assert energy == pytest.approx(0.5 * curvature @ d_b @ curvature * 0.1 * 0.08, rel=1e-10)


def test_pure_bending_moment_on_distorted_patch_gives_exact_curvature():
    """Edge moment m_x [N·m/m] on x = 0 and x = a of a free, distorted plate strip:
    Kirchhoff solution κx = m_x/D_b, κy = −ν κx, κxy = 0 everywhere (β_n is linear on an
    edge, so trapezoidal nodal moments are the consistent loads)."""
    a, b = 0.12, 0.06
    points, triangles = rectangle_triangles(a, b, 6, 3, distortion=0.35, seed=7)
    n = len(points)
    moment = 2.0
    load = np.zeros((n, 6))
    for edge_x, sign in [(0.0, -1.0), (a, 1.0)]:
        nodes = np.flatnonzero(np.isclose(points[:, 0], edge_x))
        nodes = nodes[np.argsort(points[nodes, 1])]
        segment = np.diff(points[nodes, 1])
        tributary = np.zeros(len(nodes))
        tributary[:-1] += segment / 2
        tributary[1:] += segment / 2
        load[nodes, 4] += sign * moment * tributary  # work m_x βx = m_x θy
    k, _ = shell_matrices(points, triangles, H, E, NU, RHO)
    corners = [0, np.flatnonzero(np.isclose(points[:, 0], a) & np.isclose(points[:, 1], 0))[0],
               np.flatnonzero(np.isclose(points[:, 0], 0) & np.isclose(points[:, 1], b))[0]]
    supports = np.union1d(fixed_dofs(np.arange(n), "ux uy rz"), fixed_dofs(corners, "uz"))
    free = free_dofs(6 * n, supports)
    u = np.zeros(6 * n)
    u[free] = sla.spsolve(k[free][:, free].tocsc(), load.ravel()[free])
    u = u.reshape(n, 6)
    d_b = E * H**3 / (12 * (1 - NU**2))
    kappa_x = moment / (d_b * (1 - NU**2))
    # θy = −w,x = κx x + c1, θx = w,y = −κy y + c2 (exact fields, fitted at all nodes)
    design = np.column_stack([points[:, 0], points[:, 1], np.ones(n)])
    fit_y = np.linalg.lstsq(design, u[:, 4], rcond=None)[0]
    fit_x = np.linalg.lstsq(design, u[:, 3], rcond=None)[0]
    assert fit_y[0] == pytest.approx(kappa_x, rel=1e-9)
    assert fit_x[1] == pytest.approx(NU * kappa_x, rel=1e-9)  # κy = −ν κx
    assert abs(fit_y[1]) < 1e-9 * kappa_x and abs(fit_x[0]) < 1e-9 * kappa_x
    residual = u[:, 4] - design @ fit_y
    assert np.abs(residual).max() < 1e-9 * kappa_x * a


# ---------------------------------------------------------------- invariance

def lowest_frequencies(points, triangles, count=8, fixed=None):
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    free = free_dofs(k.shape[0], [] if fixed is None else fixed)
    eigenvalues = sl.eigh(k[free][:, free].toarray(), m[free][:, free].toarray(),
                          eigvals_only=True, subset_by_index=[0, count - 1])
    return np.sqrt(np.maximum(eigenvalues, 0)) / (2 * np.pi)


def test_frequencies_invariant_under_rigid_rotation():
    points, triangles = curved_mesh()
    clamp = fixed_dofs(np.flatnonzero(points[:, 1] < 1e-9))
    reference = lowest_frequencies(points, triangles, fixed=clamp)
    rotated = points @ rotation_matrix([1.0, 2.0, -0.5], 2.1).T + np.array([0.3, -1.0, 2.0])
    moved = lowest_frequencies(rotated, triangles, fixed=clamp)
    assert np.allclose(moved, reference, rtol=1e-7)
    # free-free: the six rigid modes stay (near) zero, the elastic ones unchanged
    free_ref = lowest_frequencies(points, triangles, count=10)
    free_rot = lowest_frequencies(rotated, triangles, count=10)
    assert np.all(free_rot[:6] < 1e-4 * free_rot[6])
    assert np.allclose(free_rot[6:], free_ref[6:], rtol=1e-7)


def test_frequencies_invariant_under_node_renumbering_and_orientation():
    points, triangles = curved_mesh()
    clamp_nodes = np.flatnonzero(points[:, 1] < 1e-9)
    reference = lowest_frequencies(points, triangles, fixed=fixed_dofs(clamp_nodes))
    rng = np.random.default_rng(1)
    order = rng.permutation(len(points))
    new_index = np.empty_like(order)
    new_index[order] = np.arange(len(order))
    renumbered = new_index[triangles][:, [0, 2, 1]]  # also flip every normal
    renumbered = np.roll(renumbered, 1, axis=1)
    moved = lowest_frequencies(points[order], renumbered, fixed=fixed_dofs(new_index[clamp_nodes]))
    assert np.allclose(moved, reference, rtol=1e-7)


# ---------------------------------------------------------------- inputs

def test_per_element_properties_match_scalars_and_are_used():
    points, triangles = curved_mesh()
    n_el = len(triangles)
    k1, m1 = shell_matrices(points, triangles, H, E, NU, RHO)
    k2, m2 = shell_matrices(points, triangles, np.full(n_el, H), np.full(n_el, E),
                            np.full(n_el, NU), np.full(n_el, RHO))
    assert abs(k1 - k2).max() == 0 and abs(m1 - m2).max() == 0
    thick = np.where(np.arange(n_el) < n_el // 2, H, 2 * H)
    k3, m3 = shell_matrices(points, triangles, thick, E, NU, RHO)
    rigid = rigid_motions(points)[:, 0]
    total = RHO * rigid @ (m3 @ rigid) / (RHO * rigid @ (m1 @ rigid))
    assert 1.0 < total < 2.0
    with pytest.raises(ValueError):
        shell_matrices(points, triangles, np.full(n_el + 1, H), E, NU, RHO)
    with pytest.raises(ValueError):
        shell_matrices(points[:, :2], triangles, H, E, NU, RHO)


def test_degenerate_triangle_is_rejected():
    points = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    with pytest.raises(ValueError, match="degenerate"):
        shell_matrices(points, [[0, 1, 2]], H, E, NU, RHO)


def test_fixed_dofs_components():
    assert list(fixed_dofs([2, 0])) == [0, 1, 2, 3, 4, 5, 12, 13, 14, 15, 16, 17]
    assert list(fixed_dofs([1], "translations")) == [6, 7, 8]
    assert list(fixed_dofs([1], "rotations")) == [9, 10, 11]
    assert list(fixed_dofs([1, 1], "uz rx")) == [8, 9]
    assert list(fixed_dofs([0], [5, 2])) == [2, 5]
    with pytest.raises(ValueError):
        fixed_dofs([0], "uw")
    with pytest.raises(ValueError):
        fixed_dofs([0], [6])
    assert list(free_dofs(8, [1, 3])) == [0, 2, 4, 5, 6, 7]


def test_single_pass_pair_assembly_equals_separate_assembly():
    from sarfe.fe import assemble, assemble_pair, element_dofs

    points, triangles = curved_mesh()
    k_e, m_e = shell_element_matrices(points, triangles, H, E, NU, RHO)
    dofs = element_dofs(triangles)
    k, m = assemble_pair(k_e, m_e, dofs, 6 * len(points))
    assert abs(k - assemble(k_e, dofs, 6 * len(points))).max() == 0
    assert abs(m - assemble(m_e, dofs, 6 * len(points))).max() == 0
    k_full, m_full = shell_matrices(points, triangles, H, E, NU, RHO)
    assert abs(k_full - k).max() <= 1e-12 * abs(k).max()
