"""Isoparametric solid cells of a deck (tet4, tet10, hex8, hex20, wedge6), vectorized.

Node order as Nastran's CTETRA / CHEXA / CPENTA (corners, then midsides in the card's
order); the element matrices of linear isotropic elasticity
    K_e = ∫ Bᵀ C B dV,  C: σ = λ tr(ε) I + 2 μ ε,   M_e[ac, bd] = δ_cd ∫ ρ N_a N_b dV,
are formed for all cells of a block at once (arrays (cells, quadrature points, nodes, 3)).
hex8 carries Wilson–Taylor incompatible modes (three bubbles (1 − ξ_i²) per component,
condensed per element), as Nastran's CHEXA does not lock in bending either.
Shape-function gradients on the reference cell are exact (complex-step differentiation of
the polynomial shape functions); quadrature: scikit-fem's tetrahedron rules, Gauss–Legendre
products on hexahedra and wedges (full integration: 2³ for hex8, 3³ for hex20). wedge6 is
the plain linear cell and is stiff in bending (shear locking: FACTS.md measures +40…90 % on
a one-layer plate) — model thin parts with shells or with quadratic cells.

DOFs: the 3 translations of each node; :func:`solid_cell_matrices` returns element
matrices and their node-major DOF lists on 6-DOF nodes (6·node + [0, 1, 2]).
"""
from __future__ import annotations

import numpy as np

from sarfe.fe.solid import lame_parameters

__all__ = ["solid_cell_matrices", "shape_functions", "DegenerateCellError"]


class DegenerateCellError(ValueError):
    """A cell's isoparametric map has a zero or sign-changing Jacobian; ``row`` is its row."""

    def __init__(self, message, row):
        super().__init__(message)
        self.row = row

_HEX_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
_HEX_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [1, 5], [2, 6], [3, 7],
                       [4, 5], [5, 6], [6, 7], [7, 4]])
_TET_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])


def _tet4(x):
    return np.stack([1 - x[0] - x[1] - x[2], x[0], x[1], x[2]])


def _tet10(x):
    lam = _tet4(x)
    corner = lam * (2 * lam - 1)
    mid = 4 * lam[_TET_EDGES[:, 0]] * lam[_TET_EDGES[:, 1]]
    return np.concatenate([corner, mid])


def _hex8(x):
    c = _HEX_CORNERS[:, :, None]
    return np.prod(1 + c * x[None], axis=1) / 8


def _hex20(x):
    c = _HEX_CORNERS[:, :, None]
    corner = np.prod(1 + c * x[None], axis=1) / 8 * ((c * x[None]).sum(axis=1) - 2)
    mid = []
    for a, b in _HEX_EDGES:
        m = (_HEX_CORNERS[a] + _HEX_CORNERS[b]) / 2  # one coordinate is 0 on this edge
        k = int(np.flatnonzero(m == 0)[0])
        value = (1 - x[k] ** 2) / 4
        for j in range(3):
            if j != k:
                value = value * (1 + m[j] * x[j])
        mid.append(value)
    return np.concatenate([corner, np.stack(mid)])


def _wedge6(x):
    tri = np.stack([1 - x[0] - x[1], x[0], x[1]])
    return np.concatenate([tri * (1 - x[2]) / 2, tri * (1 + x[2]) / 2])


_SHAPES = {"tet4": _tet4, "tet10": _tet10, "hex8": _hex8, "hex20": _hex20, "wedge6": _wedge6}


def _gauss_product(n_line):
    g, w = np.polynomial.legendre.leggauss(n_line)
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1)
    return grid, np.einsum("i,j,k->ijk", w, w, w).ravel()


def _quadrature(cell_type):
    """Points (3, n_q) on the reference cell and weights (n_q,)."""
    if cell_type.startswith("tet"):
        from skfem.quadrature import get_quadrature
        from skfem.refdom import RefTet

        return get_quadrature(RefTet, 2 if cell_type == "tet4" else 4)
    if cell_type == "hex8":
        return _gauss_product(2)
    if cell_type == "hex20":
        return _gauss_product(3)
    # wedge: 3-point (degree-2) triangle rule × 2-point Gauss in ζ ∈ [−1, 1]
    tri = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
    g, w = np.polynomial.legendre.leggauss(2)
    points = np.array([[r, s, z] for r, s in tri for z in g]).T
    return points, np.array([wz / 6 for _ in tri for wz in w])


def shape_functions(cell_type, points):
    """Values (n_q, k) and reference gradients (n_q, k, 3) at reference points (3, n_q)."""
    shape = _SHAPES[cell_type]
    values = shape(points.astype(complex)).real.T
    step = 1e-30
    grads = []
    for j in range(3):
        shifted = points.astype(complex)
        shifted[j] += 1j * step
        grads.append(shape(shifted).imag.T / step)
    return values, np.stack(grads, axis=-1)


def _elastic_gram(grad_1, grad_2, dv, lam, mu):
    """∫ B₁ᵀ C B₂ dV (n_el, 3k₁, 3k₂) for gradients (n_el, n_q, k, 3):
    K[ac, bd] = Σ_q dV (λ ∂_c N_a ∂_d M_b + μ (δ_cd ∇N_a·∇M_b + ∂_d N_a ∂_c M_b))."""
    n_el, _, k1, _ = grad_1.shape
    k2 = grad_2.shape[2]
    left = (grad_1.reshape(n_el, -1, 3 * k1) * dv[:, :, None]).transpose(0, 2, 1)
    outer = (left @ grad_2.reshape(n_el, -1, 3 * k2)).reshape(n_el, k1, 3, k2, 3)
    laplace = np.einsum("eacbc->eab", outer)
    eye = np.eye(3)
    gram = (lam[:, None, None, None, None] * outer
            + mu[:, None, None, None, None]
            * (laplace[:, :, None, :, None] * eye[None, None, :, None, :]
               + outer.transpose(0, 1, 4, 3, 2)))
    return gram.reshape(n_el, 3 * k1, 3 * k2)


def _incompatible_mode_gradients(x_ref, jac, det):
    """Gradients (n_el, n_q, 3, 3) of the Wilson bubbles (1 − ξ_i²), i = 1..3, with the
    centroid Jacobian J₀ and Taylor's factor det J₀ / det J (passes the patch test)."""
    ref_grad = np.zeros((x_ref.shape[1], 3, 3))  # (n_q, bubble, ξ)
    for i in range(3):
        ref_grad[:, i, i] = -2.0 * x_ref[i]
    jac0 = jac.mean(axis=1)  # J at the centroid: Gauss points are symmetric, J is multilinear
    grad = np.einsum("qai,eij->eqaj", ref_grad, np.linalg.inv(jac0))
    return grad * (np.linalg.det(jac0)[:, None] / det)[:, :, None, None]


def solid_cell_matrices(points, cells, cell_type, young, poisson, density):
    """Element K [N/m], M [kg] (n_el, 3k, 3k) and DOFs (n_el, 3k) on 6-DOF nodes.

    points (n, 3) [m]; cells (n_el, k) node indices; young [Pa], poisson [-], density
    [kg/m³] as (n_el,) arrays. DOF of local node a, component c: 6·cells[:, a] + c.
    Raises ValueError naming the first cell with a degenerate (zero-volume) mapping.
    """
    cells = np.asarray(cells, dtype=np.int64)
    n_el, k = cells.shape
    x_ref, weights = _quadrature(cell_type)
    values, ref_grad = shape_functions(cell_type, np.asarray(x_ref, float))
    x = np.asarray(points, float)[cells]  # (n_el, k, 3)
    jac = np.einsum("qai,eaj->eqji", ref_grad, x)  # (n_el, n_q, 3 [x], 3 [ξ]): ∂x_j/∂ξ_i
    det = np.linalg.det(jac)
    if np.any(np.abs(det) < 1e-300) or np.any(np.sign(det) != np.sign(det[:, :1])):
        bad = np.flatnonzero((np.abs(det) < 1e-300).any(1) | (np.sign(det) != np.sign(det[:, :1])).any(1))
        raise DegenerateCellError(f"solid cell row {int(bad[0])} ({cell_type}) has a "
                                  "degenerate or inverted mapping", int(bad[0]))
    # ∂N/∂ξ_i = Σ_j ∂N/∂x_j J[j, i]  →  grad_x = ref_grad · J⁻¹ (row vectors)
    grad = np.einsum("qai,eqij->eqaj", ref_grad, np.linalg.inv(jac))
    dv = np.abs(det) * weights[None, :]
    lam, mu = lame_parameters(np.asarray(young, float), np.asarray(poisson, float))
    rho = np.asarray(density, float)

    stiffness = _elastic_gram(grad, grad, dv, lam, mu)
    if cell_type == "hex8":  # Wilson–Taylor incompatible modes, condensed out
        bubble = _incompatible_mode_gradients(np.asarray(x_ref, float), jac, det)
        k_ua = _elastic_gram(grad, bubble, dv, lam, mu)
        k_aa = _elastic_gram(bubble, bubble, dv, lam, mu)
        stiffness = stiffness - k_ua @ np.linalg.solve(k_aa, k_ua.transpose(0, 2, 1))
    eye = np.eye(3)
    scalar_mass = np.einsum("qa,eq,qb->eab", values, dv * rho[:, None], values)
    mass = scalar_mass[:, :, None, :, None] * eye[None, None, :, None, :]
    stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))
    dofs = (6 * cells[:, :, None] + np.arange(3)).reshape(n_el, 3 * k)
    return stiffness, mass.reshape(n_el, 3 * k, 3 * k), dofs
