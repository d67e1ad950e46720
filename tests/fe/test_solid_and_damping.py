"""scikit-fem quadratic solid wrapper and damping models."""

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp
import skfem
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from sarfe.fe import modal_damping, rayleigh_damping, shell_matrices
from sarfe.fe.reference_meshes import rectangle_triangles
from sarfe.fe.solid import solid_matrices

E, NU, RHO = 2.2e9, 0.35, 1050.0


def small_block(kind):
    cells = skfem.MeshHex1.init_tensor(np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 2),
                                       np.linspace(0, 0.004, 2))
    if kind == "hex2":
        return skfem.MeshHex2.from_mesh(cells), skfem.ElementHex2()
    return cells.to_meshtet(), skfem.ElementTetP2()


@pytest.mark.parametrize("kind", ["hex2", "tet2"])
def test_solid_matrices_match_scikit_fem_forms(kind):
    """Same spectrum as scikit-fem's own ElementVector assembly (different DOF order)."""
    mesh, element = small_block(kind)
    k, m, basis = solid_matrices(mesh, E, NU, RHO)
    vector = skfem.Basis(mesh, skfem.ElementVector(element))
    k_ref = skfem.asm(linear_elasticity(*lame_parameters(E, NU)), vector)

    @skfem.BilinearForm
    def mass_form(u, v, w):
        return RHO * dot(u, v)

    m_ref = skfem.asm(mass_form, vector)
    ours = sl.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    theirs = sl.eigh(k_ref.toarray(), m_ref.toarray(), eigvals_only=True)
    assert np.allclose(ours[6:], theirs[6:], rtol=1e-8)
    assert np.all(np.abs(ours[:6]) < 1e-8 * ours[6])  # six rigid-body modes
    volume = 0.02 * 0.01 * 0.004
    ones = np.zeros(k.shape[0])
    ones[0::3] = 1.0
    assert ones @ (m @ ones) == pytest.approx(RHO * volume, rel=1e-12)


def test_rayleigh_damping_ratios():
    points, triangles = rectangle_triangles(0.1, 0.1, 3, 3)
    k, m = shell_matrices(points, triangles, 2e-3, E, NU, RHO)
    d = rayleigh_damping(m, k, 2.0, 1e-5)
    assert sp.issparse(d)
    assert abs(d - (2.0 * m + 1e-5 * k)).max() == 0
    dense = rayleigh_damping(m.toarray(), k.toarray(), 2.0, 1e-5)
    assert np.allclose(dense, d.toarray())
    with pytest.raises(ValueError):
        rayleigh_damping(m, k, -1.0, 0.0)


def test_modal_damping_diagonalises_with_requested_ratios():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(8, 8))
    mass = a @ a.T + 8 * np.eye(8)
    b = rng.normal(size=(8, 8))
    stiffness = 1e4 * (b @ b.T + np.eye(8))
    zeta = np.linspace(0.01, 0.05, 8)
    damping = modal_damping(mass, stiffness, zeta)
    eigenvalues, modes = sl.eigh(stiffness, mass)
    modal = modes.T @ damping @ modes
    assert np.allclose(modal, np.diag(2 * zeta * np.sqrt(eigenvalues)), atol=1e-9 * modal.max())
    # scalar ζ, sparse inputs; free-free model: rigid modes get no damping
    points, triangles = rectangle_triangles(0.1, 0.1, 2, 2)
    k, m = shell_matrices(points, triangles, 2e-3, E, NU, RHO)
    d = modal_damping(m, k, 0.02)
    rigid = np.zeros(k.shape[0])
    rigid[2::6] = 1.0  # uz translation
    assert np.abs(d @ rigid).max() < 1e-8 * np.abs(d).max()
    with pytest.raises(ValueError):
        modal_damping(mass, stiffness, np.ones(3))


def test_natural_frequencies_free_free_and_modes_mass_normalised():
    from sarfe.fe import natural_frequencies

    points, triangles = rectangle_triangles(0.1, 0.08, 4, 4)
    k, m = shell_matrices(points, triangles, 2e-3, E, NU, RHO)
    f, modes = natural_frequencies(k, m, 8, return_modes=True)
    dense = sl.eigh(k.toarray(), m.toarray(), eigvals_only=True)[:8]
    assert np.all(f[:6] < 1e-3 * f[6])
    assert np.allclose(f[6:], np.sqrt(dense[6:]) / (2 * np.pi), rtol=1e-8)
    assert np.allclose(modes.T @ (m @ modes), np.eye(8), atol=1e-8)
