"""A small clamped plate (K, M) for the reduction tests.

Flat facet shell (``sarfe.fe.shell_matrices``, 6 DOF/node) on a structured triangle mesh of a
0.3 m × 0.2 m × 2.5 mm ABS plate clamped along x = 0. If the shell element is not importable,
a scikit-fem trilinear hexahedral solid plate (3 DOF/node) stands in: the tests compare the
reduced model with the full model it came from, so any SPD (K, M) pair is a valid check.
"""
from dataclasses import dataclass

import numpy as np
import pytest

LENGTH, WIDTH, THICKNESS = 0.3, 0.2, 2.5e-3
YOUNG, POISSON, DENSITY = 2.2e9, 0.35, 1050.0


@dataclass(frozen=True)
class PlateModel:
    stiffness: object  # free-DOF CSR
    mass: object
    free_dofs: np.ndarray
    total_dof_count: int
    points: np.ndarray
    dofs_per_node: int
    boundary_nodes: np.ndarray


def structured_triangles(nx, ny, length=LENGTH, width=WIDTH):
    x, y = np.meshgrid(np.linspace(0, length, nx + 1), np.linspace(0, width, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    index = np.arange(len(points)).reshape(nx + 1, ny + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    return points, np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def _shell_plate(nx, ny):
    try:
        from sarfe.fe import shell_matrices
    except ImportError:
        from sarfe.fe.shell import shell_matrices

    points, triangles = structured_triangles(nx, ny)
    stiffness, mass = shell_matrices(points, triangles, THICKNESS, YOUNG, POISSON, DENSITY)
    return points, stiffness, mass, 6


def _solid_plate(nx, ny):
    from skfem import Basis, BilinearForm, ElementHex1, ElementVector, MeshHex
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshHex.init_tensor(np.linspace(0, LENGTH, nx + 1), np.linspace(0, WIDTH, ny + 1),
                               np.linspace(0, THICKNESS, 2))
    basis = Basis(mesh, ElementVector(ElementHex1()))
    stiffness = linear_elasticity(*lame_parameters(YOUNG, POISSON)).assemble(basis)

    @BilinearForm
    def mass_form(u, v, w):
        return DENSITY * dot(u, v)

    # skfem's vector DOFs are interleaved per node (3*node + component) for this element
    return mesh.p.T, stiffness, mass_form.assemble(basis), 3


def plate_model(nx=16, ny=12):
    from sarfe.reduction import free_dofs_system

    try:
        points, stiffness, mass, per_node = _shell_plate(nx, ny)
    except ImportError:
        points, stiffness, mass, per_node = _solid_plate(nx, ny)
    clamped_nodes = np.flatnonzero(np.isclose(points[:, 0], 0.0))
    fixed = (per_node * clamped_nodes[:, None] + np.arange(per_node)).ravel()
    k_ff, m_ff, free = free_dofs_system(stiffness, mass, fixed)
    # four boundary (contact/excitation) nodes on the mid-surface side z = 0
    targets = np.array([[LENGTH, 0.0], [LENGTH, WIDTH], [0.5 * LENGTH, 0.5 * WIDTH], [0.75 * LENGTH, 0.25 * WIDTH]])
    on_bottom = np.flatnonzero(np.isclose(points[:, 2], 0.0))
    distance = np.linalg.norm(points[on_bottom, None, :2] - targets[None], axis=2)
    boundary_nodes = on_bottom[np.argmin(distance, axis=0)]
    return PlateModel(k_ff, m_ff, free, stiffness.shape[0], points, per_node, boundary_nodes)


@pytest.fixture(scope="session")
def plate():
    return plate_model()
