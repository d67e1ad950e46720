r"""Plate bending triangles of the facet shell: DKT and its shear-deformable extension DKMT.

Local bending DOFs per corner: [w, θx, θy] (9 per element). The rotations β = (βx, βy) =
(θy, −θx) (so that Kirchhoff gives β = −∇w) are quadratic: corner values β_i = P q_i,
P = [[0, 0, 1], [0, −1, 0]], and on edge k from corner i to j (length L, unit tangent s, outward
normal n) the midside value β_m = (β_i + β_j)/2 + s Δ_k: linear normal rotation, a quadratic
tangential increment Δ_k. Curvatures κ = [βx,x, βy,y, βx,y + βy,x], moments M = D κ.

DKT (Batoz, Bathe & Ho 1980): the Kirchhoff constraint integrated along each edge,
∫ (w,s + β_s) ds = 0, with ∫ β_s ds / L = (β_s,i + β_s,j)/2 + (2/3) Δ_k, gives
    Δ_k = (3/2) r_k,   r_k = −[(w_j − w_i)/L + (β_s,i + β_s,j)/2].
DKMT (Katili 1993): the edge integral equals L γ_s,k, the tangential transverse shear strain
γ = F Q with the shear compliance F = (G t)⁻¹ [m/N] (2×2) and the shear force from
equilibrium Q = [M_xx,x + M_xy,y, M_xy,x + M_yy,y], which for quadratic β is constant and
depends on the increments only: Q = G Δ (the P2 bubble Hessians). So
    ((2/3) I − S F G) Δ = r,   S = [s_1ᵀ; s_2ᵀ; s_3ᵀ],
and the stiffness is K = ∫ B_κᵀ D B_κ dA + A (G Δ)ᵀ F (G Δ) (bending + shear energy).
F = 0 (no transverse shear given: Nastran's PSHELL without MID3) is exactly DKT. Pure bending
(w quadratic, β = −∇w) gives r = 0, Δ = 0, no shear: the constant-curvature patch test holds
for any F, and the thin limit recovers DKT.
"""
from __future__ import annotations

import numpy as np

from sarfe.fe.membrane import EDGES

__all__ = ["CORNER_ROTATION", "dkt_rotation_field", "dkmt_rotation_field"]

#: β_i = P q_i for q_i = [w, θx, θy]
CORNER_ROTATION = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def _edge_residual(length, tangent):
    """R (n_el, 3, 9): r_k = R_k · q, r_k = −[(w_j − w_i)/L_k + s_kᵀ (β_i + β_j)/2]."""
    n_el = length.shape[0]
    sp = tangent @ CORNER_ROTATION                    # (n_el, 3, 3): s_kᵀ P
    r = np.zeros((n_el, 3, 3, 3))
    for k, (i, j) in enumerate(EDGES):
        r[:, k, i] -= 0.5 * sp[:, k]
        r[:, k, j] -= 0.5 * sp[:, k]
        r[:, k, i, 0] += 1.0 / length[:, k]
        r[:, k, j, 0] -= 1.0 / length[:, k]
    return r.reshape(n_el, 3, 9)


def _rotation_field(increments, tangent):
    """(n_el, 12, 9): P2 nodal β of corner rotations plus tangential midside increments
    Δ = increments · q (n_el, 3, 9)."""
    n_el = tangent.shape[0]
    t = np.zeros((n_el, 6, 2, 3, 3))
    t[:, np.arange(3), :, np.arange(3), :] = CORNER_ROTATION
    for k, (i, j) in enumerate(EDGES):
        t[:, 3 + k, :, i, :] += 0.5 * CORNER_ROTATION
        t[:, 3 + k, :, j, :] += 0.5 * CORNER_ROTATION
    t = t.reshape(n_el, 6, 2, 9)
    t[:, 3:] += tangent[..., None] * increments[:, :, None, :]
    return t.reshape(n_el, 12, 9)


def dkt_rotation_field(length, tangent, normal):
    """(n_el, 12, 9): [w_i, θx_i, θy_i] → P2 nodal rotations β of the DKT.

    length (n_el, 3) [m], unit tangents and outward normals (n_el, 3, 2) of the edges (the
    normal rotation is linear along an edge: only the tangents enter)."""
    return _rotation_field(1.5 * _edge_residual(length, tangent), tangent)


def _shear_from_increments(grad_l, tangent, bending):
    """G (n_el, 2, 3): shear force Q = div(D κ) [N/m] per unit increment Δ_k."""
    hessian = np.empty(grad_l.shape[:1] + (3, 2, 2))
    for k, (i, j) in enumerate(EDGES):
        outer = np.einsum("ea,eb->eab", grad_l[:, i], grad_l[:, j])
        hessian[:, k] = 4.0 * (outer + outer.transpose(0, 2, 1))
    sx, sy = tangent[..., 0], tangent[..., 1]              # (n_el, 3)
    hxx, hxy, hyy = hessian[..., 0, 0], hessian[..., 0, 1], hessian[..., 1, 1]
    dkx = np.stack([sx * hxx, sy * hxy, sx * hxy + sy * hxx], axis=1)   # ∂κ/∂x (n_el, 3, 3)
    dky = np.stack([sx * hxy, sy * hyy, sx * hyy + sy * hxy], axis=1)   # ∂κ/∂y
    dmx, dmy = bending @ dkx, bending @ dky
    return np.stack([dmx[:, 0] + dmy[:, 2], dmx[:, 2] + dmy[:, 1]], axis=1)


def dkmt_rotation_field(length, tangent, normal, grad_l, bending, shear_compliance):
    """DKMT rotation field and shear force operator.

    length (n_el, 3), tangent/normal (n_el, 3, 2) of the edges, grad_l (n_el, 3, 2) [1/m],
    bending D (n_el, 3, 3) [N·m] and shear compliance F (n_el, 2, 2) [m/N] in the element
    frame. Returns the P2 nodal rotations (n_el, 12, 9) and the shear force operator
    Q = G_q q (n_el, 2, 9) [N/m per DOF]: the shear stiffness is A G_qᵀ F G_q.
    """
    g = _shear_from_increments(grad_l, tangent, bending)          # (n_el, 2, 3)
    system = (2.0 / 3.0) * np.eye(3) - tangent @ shear_compliance @ g
    increments = np.linalg.solve(system, _edge_residual(length, tangent))
    return _rotation_field(increments, tangent), g @ increments
