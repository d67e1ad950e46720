"""Quadratic solid elements through scikit-fem: chunky parts and an independent reference.

scikit-fem supplies the element (ElementTetP2 / ElementHex2 / ElementHexS2), the
(possibly curved, MeshTet2 / MeshHex2) geometry mapping, quadrature and DOF numbering;
the element matrices are formed here with batched numpy products, because scikit-fem's
form assembly loops in Python over the (3·27)² local DOF pairs of a vector Hex2 element.

Linear isotropic elasticity:
  K_e = ∫ Bᵀ C B dV with σ = λ tr(ε) I + 2 μ ε, i.e. per node pair (a, b), components (c, d):
        K[ac, bd] = ∫ λ ∂_c N_a ∂_d N_b + μ (δ_cd ∇N_a·∇N_b + ∂_d N_a ∂_c N_b) dV,
  M_e[ac, bd] = δ_cd ∫ ρ N_a N_b dV.
DOF = 3·(scalar DOF of the element) + [ux, uy, uz]; ``basis.doflocs`` gives the scalar
DOF coordinates (vertices, then edge/face/interior nodes).
"""

from __future__ import annotations

import numpy as np

from sarfe.fe.assembly import assemble

__all__ = ["solid_basis", "solid_matrices", "lame_parameters"]


def lame_parameters(young, poisson):
    """λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)) [Pa]."""
    return young * poisson / ((1 + poisson) * (1 - 2 * poisson)), young / (2 * (1 + poisson))


def solid_basis(mesh, element=None, intorder=None):
    """Scalar scikit-fem ``CellBasis`` of a quadratic 3D element on ``mesh``.

    Default element: ElementTetP2 for tetrahedral meshes, ElementHex2 for hexahedral ones.
    """
    import skfem

    if element is None:
        if isinstance(mesh, skfem.MeshTet1):
            element = skfem.ElementTetP2()
        elif isinstance(mesh, skfem.MeshHex1):
            element = skfem.ElementHex2()
        else:
            raise ValueError(f"no default quadratic element for {type(mesh).__name__}")
    return skfem.CellBasis(mesh, element, intorder=intorder)


def solid_matrices(mesh_or_basis, young, poisson, density, element=None, intorder=None):
    """Stiffness K [N/m] and consistent mass M [kg] of a 3D linear-elastic solid, CSR (3N, 3N).

    mesh_or_basis: a scikit-fem 3D mesh (MeshTet/MeshTet2/MeshHex/MeshHex2) or a scalar
    ``CellBasis``; young [Pa], poisson [-], density [kg/m³]: scalars or (n_el,) arrays.
    Returns (stiffness, mass, basis); vector DOF = 3·scalar_dof + component.
    """
    import skfem

    if isinstance(mesh_or_basis, skfem.CellBasis):
        basis = mesh_or_basis
    else:
        basis = solid_basis(mesh_or_basis, element, intorder)
    n_el = basis.nelems
    lam, mu = lame_parameters(np.broadcast_to(np.asarray(young, float), (n_el,)),
                              np.broadcast_to(np.asarray(poisson, float), (n_el,)))
    rho = np.broadcast_to(np.asarray(density, float), (n_el,))

    # gradients (n_el, n_q, n_local, 3), values (n_el, n_q, n_local), dV (n_el, n_q)
    grad = np.stack([field[0].grad for field in basis.basis], axis=0)  # (n_loc, 3, n_el, n_q)
    grad = grad.transpose(2, 3, 0, 1)
    value = np.stack([np.broadcast_to(np.asarray(field[0]), basis.dx.shape)
                      for field in basis.basis], axis=-1)
    dv = basis.dx
    n_q, n_loc = grad.shape[1], grad.shape[2]

    # A[e, a c, b d] = Σ_q dV ∂_c N_a ∂_d N_b
    flat = grad.reshape(n_el, n_q, 3 * n_loc)
    weighted = flat * dv[:, :, None]
    outer = (weighted.transpose(0, 2, 1) @ flat).reshape(n_el, n_loc, 3, n_loc, 3)
    # S[e, a, b] = Σ_q dV ∇N_a·∇N_b
    laplace = np.einsum("eacbc->eab", outer)
    eye = np.eye(3)
    stiffness = (lam[:, None, None, None, None] * outer
                 + mu[:, None, None, None, None]
                 * (laplace[:, :, None, :, None] * eye[None, None, :, None, :]
                    + outer.transpose(0, 1, 4, 3, 2)))
    scalar_mass = (value * (dv * rho[:, None])[:, :, None]).transpose(0, 2, 1) @ value
    mass = scalar_mass[:, :, None, :, None] * eye[None, None, :, None, :]

    dofs = (3 * basis.element_dofs.T[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_loc)
    n_dof = 3 * basis.N
    size = 3 * n_loc
    stiffness = stiffness.reshape(n_el, size, size)
    stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))
    return (assemble(stiffness, dofs, n_dof),
            assemble(mass.reshape(n_el, size, size), dofs, n_dof),
            basis)
