r"""Membrane triangles with a corner drilling rotation, in the element plane.

Local DOFs per element: [u_0, v_0, θz_0, u_1, v_1, θz_1, u_2, v_2, θz_2] (9), corners in the
element frame (x_ij = x_i − x_j, y_ij = y_i − y_j, A the area). The membrane stiffness C [N/m]
relates the resultants N = C ε, ε = [u,x, v,y, u,y + v,x] (C = t E/(1−ν²)[[1,ν,0],[ν,1,0],
[0,0,(1−ν)/2]] for an isotropic sheet, the section's A matrix in general).

``"andes"`` — Felippa's optimal ANDES triangle ("OPT", Felippa 2003, CMAME 192, 2125–2168),
K_m = K_b + K_h:
  basic (constant strain, patch test by construction): K_b = L C Lᵀ / (4A), with the lumping
    matrix L (9×3) of the Allman-type boundary displacement (α_b = 3/2);
  higher order: K_h = (3/4) β₀ A T_θuᵀ (Σ_{k=4,5,6} Q_kᵀ T_eᵀ C T_e Q_k) T_θu, where
    θ̃ = T_θu q are the corner rotations minus the mean (CST) rotation ω = (v,x − u,y)/2,
    Q_1..3 (3×3) give the natural (edge) strains at the corners from θ̃ with the optimal
    β₁…β₉ = (1, 2, 1, 0, 1, −1, −1, −1, −2), Q_4..6 the edge midpoints, and T_e turns edge
    strains into Cartesian ones; β₀ = max(2/ĉ − 3/2, 1/100) from the material's mean
    compliance ĉ (isotropic C: β₀ = max((1 − 4ν²)/2, 1/100)). Two triangles making a
  rectangle of any aspect ratio store exactly the energy of pure in-plane bending.
  K_h vanishes on every linear displacement field with θz equal to its rotation ω, so the
  constant-strain states stay exact; K_m has exactly three zero eigenvalues (rigid motions).
``"allman"`` — Allman (1984): the quadratic field with midside values
  u_ij = (u_i + u_j)/2 + (L_ij/8)(θz_j − θz_i) n_ij, K = ∫ Bᵀ C B dA (three-midside rule), plus
  the drilling penalty K_d = α C₃₃ A g gᵀ, g·q = mean(θz) − ω(centroid), which removes its
  spurious mode (equal θz at the corners). Locks in in-plane bending (energy 1.8 … 4.7 × the
  exact for rectangle pairs of aspect 1 … 4).
``"cst"`` — the constant-strain triangle (no θz in the field) plus the weak penalty
  α C₃₃ ∫ (θz − ω)² dA: Nastran's CTRIA3 (α = 1e-6 · K6ROT), used for decks.

A true drilling membrane (ANDES, Allman) ties the in-plane rotation of a shell to a beam or a
folded shell meeting it, which the commercial solver's weak penalty does not (measured on decks:
benchmarks/results/shell_decks.md, sarfe.fe.deck_shells). Everything is vectorized over
elements: arrays shaped (n_el, ...).
"""
from __future__ import annotations

import numpy as np

__all__ = ["MEMBRANES", "DRILLING_PENALTY", "andes_stiffness",
           "andes_basic_strain", "optimal_beta0", "allman_field", "drilling_vector",
           "cst_stiffness", "cst_strain", "p2_gradients", "EDGES"]

#: membrane formulations understood by the shell elements
MEMBRANES = ("andes", "allman", "cst")


#: default α of the Allman drilling penalty K_d = α C₃₃ A g gᵀ (unused by "andes")
DRILLING_PENALTY = 1e-2

#: P2 triangle nodes: corners 0, 1, 2 then midsides (0,1), (1,2), (2,0)
EDGES = np.array([[0, 1], [1, 2], [2, 0]])

# optimal (OPT) template parameters: α_b and β₁…β₉
_ALPHA_B = 1.5
_BETA = np.array([1.0, 2.0, 1.0, 0.0, 1.0, -1.0, -1.0, -1.0, -2.0])
# Q_2, Q_3 use the β's cyclically permuted (rows = edges 21, 32, 13)
_Q_ORDER = np.array([[[0, 1, 2], [3, 4, 5], [6, 7, 8]],
                     [[8, 6, 7], [2, 0, 1], [5, 3, 4]],
                     [[4, 5, 3], [7, 8, 6], [1, 2, 0]]])


def optimal_beta0(c):
    """β₀ (n_el,) of the optimal triangle for membrane stiffness C (n_el, 3, 3).

    β₀ = max(2/ĉ − 3/2, 1/100), ĉ = C̄₁₁ C⁻¹₁₁ averaged over directions (Felippa 2003): a
    closed form in the entries of C, dimensionless. Isotropic: β₀ = max((1 − 4ν²)/2, 1/100).
    """
    e11, e12, e13 = c[:, 0, 0], c[:, 0, 1], c[:, 0, 2]
    e22, e23, e33 = c[:, 1, 1], c[:, 1, 2], c[:, 2, 2]
    det = (e11 * e22 * e33 + 2 * e12 * e13 * e23 - e11 * e23**2 - e22 * e13**2
           - e33 * e12**2)
    w = (-6 * e12**3 + 5 * e11**2 * e22 - 5 * e12**2 * e22
         - e22 * (75 * e13**2 + 14 * e13 * e23 + 3 * e23**2)
         + 2 * e12 * (7 * e13**2 + 46 * e13 * e23 + 7 * e23**2)
         - e11 * (5 * e12**2 + 3 * e13**2 - 6 * e12 * e22 - 5 * e22**2 + 14 * e13 * e23
                  + 75 * e23**2)
         + (3 * e11**2 + 82 * e11 * e22 + 3 * e22**2
            - 4 * (6 * e12**2 + 5 * e13**2 - 6 * e13 * e23 + 5 * e23**2)) * e33
         + 4 * (5 * e11 - 6 * e12 + 5 * e22) * e33**2)
    mean_compliance = w / (128.0 * det)
    return np.maximum(2.0 / mean_compliance - 1.5, 0.01)


def andes_basic_strain(local_xy, area):
    """Constant strain ε₀ = Lᵀ q / (2A) (n_el, 3, 9) of the basic stiffness: the mean
    strain of the Allman-type boundary displacement (α_b = 3/2)."""
    return _lumping(local_xy).transpose(0, 2, 1) / (2.0 * area)[:, None, None]


def _lumping(local_xy):
    """L (n_el, 9, 3) without the factor h/2: force lumping of a constant stress."""
    x, y = local_xy[..., 0], local_xy[..., 1]
    n_el = x.shape[0]
    lump = np.zeros((n_el, 3, 3, 3))
    # corner i with its opposite edge (j, k): (i, j, k) cyclic
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        yjk, xkj = y[:, j] - y[:, k], x[:, k] - x[:, j]
        lump[:, i, 0, 0], lump[:, i, 0, 2] = yjk, xkj
        lump[:, i, 1, 1], lump[:, i, 1, 2] = xkj, yjk
        # drilling rows: α_b/6 · (y_jk (y_ik − y_ji), x_kj (x_ki − x_ij), 2 (x_ki y_ik − x_ij y_ji))
        yik, yji = y[:, i] - y[:, k], y[:, j] - y[:, i]
        xki, xij = x[:, k] - x[:, i], x[:, i] - x[:, j]
        lump[:, i, 2, 0] = _ALPHA_B * yjk * (yik - yji) / 6.0
        lump[:, i, 2, 1] = _ALPHA_B * xkj * (xki - xij) / 6.0
        lump[:, i, 2, 2] = _ALPHA_B * (xki * yik - xij * yji) / 3.0
    return lump.reshape(n_el, 9, 3)


def _deviatoric_rotation(local_xy, area):
    """T_θu (n_el, 3, 9): θ̃_i = θz_i − ω, ω = (v,x − u,y)/2 of the linear (CST) field."""
    x, y = local_xy[..., 0], local_xy[..., 1]
    n_el = x.shape[0]
    mean = np.zeros((n_el, 3, 3))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        # −ω = Σ_i (x_kj u_i + y_kj v_i) / (4A), x_kj = x_k − x_j, (i, j, k) cyclic
        mean[:, i, 0] = (x[:, k] - x[:, j]) / (4.0 * area)
        mean[:, i, 1] = (y[:, k] - y[:, j]) / (4.0 * area)
    t = np.broadcast_to(mean.reshape(n_el, 1, 9), (n_el, 3, 9)).copy()
    for i in range(3):
        t[:, i, 3 * i + 2] += 1.0
    return t


def andes_stiffness(local_xy, area, c, beta0=None):
    """Optimal ANDES membrane stiffness K_b + K_h (n_el, 9, 9) [N/m, N, N·m] (module docstring).

    local_xy (n_el, 3, 2) corners in the element plane [m], counter-clockwise; area (n_el,)
    [m²]; c (n_el, 3, 3) membrane stiffness [N/m]; beta0 (n_el,) overrides :func:`optimal_beta0`.
    """
    lump = _lumping(local_xy)
    k_basic = lump @ c @ lump.transpose(0, 2, 1) / (4.0 * area)[:, None, None]
    beta0 = optimal_beta0(c) if beta0 is None else np.broadcast_to(beta0, area.shape)
    # edge k runs from corner k to corner k + 1 (Felippa's sides 21, 32, 13)
    length2 = np.sum((local_xy[:, [1, 2, 0]] - local_xy) ** 2, axis=2)
    # T_e (n_el, 3, 3): Cartesian strain = T_e · edge strains (edges 21, 32, 13)
    # with (y_23 y_13, x_23 x_13, y_23 x_31 + x_32 y_13) ℓ21² … cyclic, / (4A²)
    x, y = local_xy[..., 0], local_xy[..., 1]
    t_e = np.zeros(c.shape)
    for k in range(3):                             # edge k: corners (k, k+1), opposite k+2
        a, b, o = k, (k + 1) % 3, (k + 2) % 3
        ya, yb = y[:, b] - y[:, o], y[:, a] - y[:, o]      # y_bo… as (y_23, y_13) for edge 21
        xa, xb = x[:, b] - x[:, o], x[:, a] - x[:, o]
        t_e[:, 0, k] = ya * yb * length2[:, k]
        t_e[:, 1, k] = xa * xb * length2[:, k]
        t_e[:, 2, k] = -(ya * xb + xa * yb) * length2[:, k]
    t_e /= (4.0 * area**2)[:, None, None]
    beta = _BETA[_Q_ORDER]                          # (3 corners, 3 edges, 3)
    q_corner = (2.0 * area / 3.0)[:, None, None, None] * beta[None] / length2[:, None, :, None]
    q_mid = 0.5 * (q_corner + q_corner[:, [1, 2, 0]])   # Q4 = (Q1+Q2)/2, Q5, Q6
    strain_mid = t_e[:, None] @ q_mid                  # (n_el, 3, 3, 3): Cartesian per θ̃
    k_theta = np.einsum("emji,ejk,emkl->eil", strain_mid, c, strain_mid)
    t_rot = _deviatoric_rotation(local_xy, area)
    k_high = (0.75 * beta0 * area)[:, None, None] * (
        t_rot.transpose(0, 2, 1) @ k_theta @ t_rot)
    return k_basic + k_high


def cst_strain(grad_l):
    """Constant strain operator (n_el, 3, 9) of the linear field, ε = [u,x, v,y, u,y + v,x]
    on [u_i, v_i, θz_i] (θz columns zero); grad_l (n_el, 3, 2) area-coordinate gradients."""
    n_el = grad_l.shape[0]
    b = np.zeros((n_el, 3, 3, 3))
    b[:, 0, :, 0] = grad_l[..., 0]
    b[:, 1, :, 1] = grad_l[..., 1]
    b[:, 2, :, 0] = grad_l[..., 1]
    b[:, 2, :, 1] = grad_l[..., 0]
    return b.reshape(n_el, 3, 9)


def cst_stiffness(grad_l, area, c, drilling_penalty):
    """Constant-strain triangle with a Hughes–Brezzi drilling penalty (n_el, 9, 9): the
    membrane of Nastran's CTRIA3, K = A Bᵀ C B + α C₃₃ ∫ (θz − ω)² dA with θz linear between
    the corners and ω = (v,x − u,y)/2 constant (Nastran: α = 1e-6 · K6ROT)."""
    n_el = area.shape[0]
    b = cst_strain(grad_l)
    k = area[:, None, None] * (b.transpose(0, 2, 1) @ c @ b)
    spin = np.zeros((n_el, 3, 3))
    spin[:, :, 0] = -0.5 * grad_l[..., 1]
    spin[:, :, 1] = 0.5 * grad_l[..., 0]
    spin = spin.reshape(n_el, 9)                     # ω = spin · q
    pick = np.zeros((3, 9))
    pick[np.arange(3), 3 * np.arange(3) + 2] = 1.0   # θz of the corners
    linear = (np.ones((3, 3)) + np.eye(3)) / 12.0
    ones = pick.sum(axis=0)
    penalty = (pick.T @ linear @ pick)[None] * area[:, None, None]
    cross = np.einsum("i,ej->eij", ones, spin) * (area / 3.0)[:, None, None]
    penalty = penalty - cross - cross.transpose(0, 2, 1) + area[:, None, None] * np.einsum(
        "ei,ej->eij", spin, spin)
    return k + (drilling_penalty * c[:, 2, 2])[:, None, None] * penalty


def p2_gradients(area_coords, grad_l):
    """Gradients of the six P2 shape functions, (n_el, n_q, 6, 2), at area coordinates
    (n_q, 3): corner a: (4 L_a − 1) ∇L_a; midside (i, j): 4 (L_i ∇L_j + L_j ∇L_i)."""
    n_q = area_coords.shape[0]
    coeff = np.zeros((n_q, 6, 3))
    for a in range(3):
        coeff[:, a, a] = 4.0 * area_coords[:, a] - 1.0
    for m, (i, j) in enumerate(EDGES):
        coeff[:, 3 + m, j] += 4.0 * area_coords[:, i]
        coeff[:, 3 + m, i] += 4.0 * area_coords[:, j]
    return np.einsum("qab,ebx->eqax", coeff, grad_l)


def allman_field(length, normal):
    """(n_el, 12, 9): [u_i, v_i, θz_i] (i = 0..2) → P2 nodal in-plane displacements of the
    Allman field; length (n_el, 3) and outward normals (n_el, 3, 2) of the edges."""
    n_el = length.shape[0]
    t = np.zeros((n_el, 6, 2, 3, 3))
    for a in range(3):
        t[:, a, 0, a, 0] = 1.0
        t[:, a, 1, a, 1] = 1.0
    for m, (i, j) in enumerate(EDGES):
        t[:, 3 + m, 0, i, 0] = t[:, 3 + m, 0, j, 0] = 0.5
        t[:, 3 + m, 1, i, 1] = t[:, 3 + m, 1, j, 1] = 0.5
        drill = (length[:, m] / 8.0)[:, None] * normal[:, m]  # (n_el, 2)
        t[:, 3 + m, :, j, 2] += drill
        t[:, 3 + m, :, i, 2] -= drill
    return t.reshape(n_el, 12, 9)


def drilling_vector(grad_l, t_mem):
    """g (n_el, 9) of the Allman drilling penalty, g·q = mean(θz) − ω(centroid),
    ω = (v,x − u,y)/2; grad_l (n_el, 3, 2) area-coordinate gradients, t_mem the Allman field."""
    n_el = grad_l.shape[0]
    centroid = np.full((1, 3), 1.0 / 3.0)
    grad_c = p2_gradients(centroid, grad_l)[:, 0]  # (n_el, 6, 2)
    spin = np.zeros((n_el, 6, 2))
    spin[:, :, 0] = -0.5 * grad_c[..., 1]  # ω = (v,x − u,y)/2
    spin[:, :, 1] = 0.5 * grad_c[..., 0]
    g = -np.einsum("ea,eaj->ej", spin.reshape(n_el, 12), t_mem)
    g[:, 2::3] += 1.0 / 3.0
    return g
