r"""Four-node membrane quadrilateral for decks' CQUAD4 / S4: incompatible modes (QM6) plus a
Hughes–Brezzi drilling penalty, on the quad's mean plane with rigid warping offsets.

Geometry: mean plane through the centroid x̄ with normal e3 = (x₃ − x₁) × (x₄ − x₂)/|…| (the
diagonals' cross product), e1 along the bisector of the diagonals projected on the plane,
e2 = e3 × e1 (Nastran's CQUAD4 element axes). Corner i sits at the height h_i = (x_i − x̄)·e3
above the plane (±h for a warped quad); its projection is tied to the node by a rigid offset,
u_p = u_i + θ_i × (−h_i e3), so a rigid motion of the nodes is a rigid motion of the plane quad.

Membrane (u, v in the plane): bilinear N_i(ξ, η) = (1 + ξξ_i)(1 + ηη_i)/4 plus the incompatible
modes 1 − ξ², 1 − η² per component (QM6, Taylor–Beresford–Wilson 1976): their derivatives use
the centre Jacobian J₀ scaled by det J₀ / det J, so that ∫ B_inc dA = 0 and constant strain is
exact on any quad (patch test); a rectangle bends in its plane exactly. With the 2×2 Gauss rule
K = ∫ [B_c B_i]ᵀ C [B_c B_i] dA, the 4 internal DOFs condensed: K_cc − K_ci K_ii⁻¹ K_ic.
Drilling: K_d = α C₃₃ ∫ (θz − ω)² dA, θz bilinear from the corners, ω = (v,x − u,y)/2 of the
bilinear field (2×2 rule); as Nastran's CQUAD4 with α = 1e-6 · K6ROT. The drilling rotation is
only weakly tied to the membrane: a beam or a folded shell meeting the quad does not clamp
its in-plane rotation (as in the commercial solver; a true drilling membrane such as
:mod:`sarfe.fe.membrane`'s "andes" does).

All arrays are shaped (n_quad, ...): no loop over elements.
"""
from __future__ import annotations

import numpy as np

__all__ = ["quad_frames", "quad_membrane_matrices", "regular_quads"]

_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0])
_GAUSS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) / np.sqrt(3.0)


def quad_frames(points, quads):
    """Mean-plane frames of quads (n_q, 4) on points (n, 3) [m].

    Returns rotation (n_q, 3, 3) (rows e1, e2, e3), plane coordinates (n_q, 4, 2) [m] of the
    projected corners about the centroid, and heights h (n_q, 4) [m] of the corners above it.
    """
    x = np.asarray(points, float)[np.asarray(quads)]
    d13, d24 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
    normal = np.cross(d13, d24)
    # parallel diagonals (a degenerate quad) leave e3 arbitrary: regular_quads rejects those
    size = np.maximum(np.linalg.norm(normal, axis=1), 1e-300)
    e3 = normal / size[:, None]
    u13 = d13 / np.linalg.norm(d13, axis=1)[:, None]
    u24 = d24 / np.linalg.norm(d24, axis=1)[:, None]
    bisector = u13 - u24
    bisector -= np.einsum("ei,ei->e", bisector, e3)[:, None] * e3
    e1 = bisector / np.maximum(np.linalg.norm(bisector, axis=1), 1e-300)[:, None]
    e2 = np.cross(e3, e1)
    rotation = np.stack([e1, e2, e3], axis=1)
    local = np.einsum("eij,ekj->eki", rotation, x - x.mean(axis=1, keepdims=True))
    return rotation, local[..., :2], local[..., 2]


def regular_quads(points, quads, min_corner_ratio=0.05):
    """(n_q,) bool: quads whose projection on the mean plane is convex with every corner
    Jacobian det J_i = (x_{i+1} − x_i) × (x_{i−1} − x_i) ≥ ``min_corner_ratio`` × their mean
    (the bilinear map is then one-to-one; a concave, arrow-shaped or degenerate pair of facets
    is not a quadrilateral element)."""
    _, xy, _ = quad_frames(points, quads)
    ahead = np.roll(xy, -1, axis=1) - xy
    behind = np.roll(xy, 1, axis=1) - xy
    corner = ahead[..., 0] * behind[..., 1] - ahead[..., 1] * behind[..., 0]
    return (corner.mean(axis=1) > 0) & (corner.min(axis=1) >= min_corner_ratio
                                         * corner.mean(axis=1))


def _gradients(xy):
    """Physical gradients at the 2×2 Gauss points: bilinear (n_q, 4, 4, 2), incompatible
    (n_q, 4, 2, 2) (QM6: centre Jacobian, det J₀/det J), and det J (n_q, 4)."""
    xi, eta = _GAUSS[:, 0], _GAUSS[:, 1]
    # dN_i/dξ, dN_i/dη at each Gauss point: (4 points, 4 nodes)
    dxi = 0.25 * _XI[None] * (1.0 + eta[:, None] * _ETA[None])
    deta = 0.25 * _ETA[None] * (1.0 + xi[:, None] * _XI[None])
    natural = np.stack([dxi, deta], axis=2)                      # (4 g, 4 nodes, 2)
    jac = natural.transpose(0, 2, 1)[None] @ xy[:, None]         # J[a, b] = ∂x_b/∂ξ_a
    det = jac[..., 0, 0] * jac[..., 1, 1] - jac[..., 0, 1] * jac[..., 1, 0]
    if np.any(det <= 0.0):
        raise ValueError("quadrilateral with a non-positive Jacobian (concave or misordered)")
    inv = np.linalg.inv(jac)                                      # ∂ξ_a/∂x_b as inv[b, a]
    grad = natural[None] @ inv.transpose(0, 1, 3, 2)             # (n_q, 4 g, 4 nodes, 2)
    centre = np.einsum("na,enb->eab", 0.25 * np.stack([_XI, _ETA], 1), xy)
    det0 = centre[:, 0, 0] * centre[:, 1, 1] - centre[:, 0, 1] * centre[:, 1, 0]
    inv0 = np.linalg.inv(centre)
    # incompatible modes P₁ = 1 − ξ², P₂ = 1 − η²: dP/dξ = (−2ξ, 0), (0, −2η)
    natural_inc = np.zeros((4, 2, 2))
    natural_inc[:, 0, 0] = -2.0 * xi
    natural_inc[:, 1, 1] = -2.0 * eta
    grad_inc = (natural_inc[None] @ inv0.transpose(0, 2, 1)[:, None]) * (
        det0[:, None] / det)[..., None, None]
    return grad, grad_inc, det


def _strain(grad):
    """[ε_xx, ε_yy, γ_xy] operator (…, 3, 2k) of a vector field with k scalar shape
    functions of gradients grad (…, k, 2), DOFs node-major [u, v]."""
    shape = grad.shape[:-2]
    k = grad.shape[-2]
    b = np.zeros(shape + (3, k, 2))
    b[..., 0, :, 0] = grad[..., 0]
    b[..., 1, :, 1] = grad[..., 1]
    b[..., 2, :, 0] = grad[..., 1]
    b[..., 2, :, 1] = grad[..., 0]
    return b.reshape(shape + (3, 2 * k))


def quad_membrane_matrices(points, quads, c, drilling_penalty):
    """Membrane stiffness (n_q, 24, 24) of quads in the global frame, DOFs [ux, uy, uz, rx, ry,
    rz] per corner, node-major (the bending and mass come from the quad's two triangles).

    points (n, 3) [m]; quads (n_q, 4) counter-clockwise; c (n_q, 3, 3) membrane stiffness [N/m]
    in the quad's element axes (:func:`quad_frames`); drilling_penalty α (scalar or (n_q,)).
    """
    rotation, xy, height = quad_frames(points, quads)
    n_q = xy.shape[0]
    grad, grad_inc, det = _gradients(xy)
    weight = det                                          # 2×2 Gauss weights are 1
    b_c = _strain(grad)                                   # (n_q, 4 g, 3, 8)
    b_i = _strain(grad_inc)                               # (n_q, 4 g, 3, 4)
    # Σ_g w_g B_gᵀ C B_g as batched matmuls over the stacked (4 g × 3 strains) rows
    b_all = np.concatenate([b_c, b_i], axis=3)            # (n_q, 4 g, 3, 12)
    cb = (c[:, None] @ b_all) * weight[:, :, None, None]
    k_all = b_all.reshape(n_q, 12, 12).transpose(0, 2, 1) @ cb.reshape(n_q, 12, 12)
    k_cc, k_ci, k_ii = k_all[:, :8, :8], k_all[:, :8, 8:], k_all[:, 8:, 8:]
    k_uv = k_cc - k_ci @ np.linalg.solve(k_ii, k_ci.transpose(0, 2, 1))

    # drilling penalty on [u, v, θz] per node: g_gauss·q = θz(ξ) − ω(ξ)
    xi, eta = _GAUSS[:, 0], _GAUSS[:, 1]
    n_values = 0.25 * (1 + xi[:, None] * _XI) * (1 + eta[:, None] * _ETA)   # (4 g, 4 nodes)
    g = np.zeros((n_q, 4, 4, 3))
    g[..., 0] = 0.5 * grad[..., 1]                        # −(−u,y)/2
    g[..., 1] = -0.5 * grad[..., 0]                       # −v,x/2
    g[..., 2] = n_values[None]
    g = g.reshape(n_q, 4, 12)
    alpha = np.broadcast_to(np.asarray(drilling_penalty, float), (n_q,))
    k_drill = (alpha * c[:, 2, 2])[:, None, None] * (
        g.transpose(0, 2, 1) @ (g * weight[:, :, None]))

    membrane = np.zeros((n_q, 4, 3, 4, 3))
    membrane[:, :, :2, :, :2] = k_uv.reshape(n_q, 4, 2, 4, 2)
    membrane = membrane.reshape(n_q, 12, 12) + k_drill
    # [u_p, v_p, θz]_i = W_i [u, v, w, θx, θy, θz]_i: u_p = u − h θy, v_p = v + h θx
    warp = np.zeros((n_q, 4, 3, 4, 6))
    for i in range(4):
        warp[:, i, 0, i, 0] = warp[:, i, 1, i, 1] = warp[:, i, 2, i, 5] = 1.0
        warp[:, i, 0, i, 4] = -height[:, i]
        warp[:, i, 1, i, 3] = height[:, i]
    warp = warp.reshape(n_q, 12, 24)
    local = warp.transpose(0, 2, 1) @ membrane @ warp     # (n_q, 24, 24) element axes
    return _to_global(local, rotation)


def _to_global(local, rotation):
    """Tᵀ A T (n_q, 24, 24) for T = blockdiag(R × 8), rotation (n_q, 3, 3) rows e1, e2, e3."""
    n_q = local.shape[0]
    right = (local.reshape(n_q, 192, 3) @ rotation).reshape(n_q, 8, 3, 24)
    rotated = (rotation.transpose(0, 2, 1)[:, None] @ right).reshape(n_q, 24, 24)
    return 0.5 * (rotated + rotated.transpose(0, 2, 1))
