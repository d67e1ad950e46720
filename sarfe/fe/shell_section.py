"""The facet shell triangle of `sarfe.fe.shell` with a general shell section (A, B, D).

Same kinematics as `sarfe.fe.shell` (Allman membrane + drilling penalty, DKT bending, 6
DOF per node, element frame e1 along edge 1→2, e3 = normal); the section stiffness is given
per element instead of (t, E, ν), so laminates (PCOMP via `sarfe.mesh.laminate`), orthotropic
and anisotropic sections fit:
    K = ∫ [B_m; B_b]ᵀ [[A, B], [B, D]] [B_m; B_b] dA
with B_m the Allman membrane strain operator (ε⁰) and B_b the DKT curvature operator (κ);
the membrane–bending block B couples in-plane and out-of-plane DOFs. A, B, D are given in
the section's material axes (``material_axis``, a global vector in the element plane) and
rotated into the element frame, Ā = T_εᵀ A T_ε. The drilling penalty uses the section's
in-plane shear stiffness A66 for G t. Transverse shear flexibility is not modelled (DKT is a
Kirchhoff element): a section's ``transverse_shear`` is not used.

Mass: translations (m'' ∫ N_i N_j dA, m'' = mass per area [kg/m²]); rotary inertia
I'' [kg] on the DKT rotation field; drilling I'' A/12 (1 + δ_ij), as in `sarfe.fe.shell`;
for offset shells the first moment S'' couples in-plane translations (linear N) with the
DKT rotations, M_uβ = S'' ∫ N_i β dA (degree-4 rule, exact).
For an isotropic section (A = t Q, B = 0, D = t³/12 Q, m'' = ρ t, I'' = ρ t³/12) the matrices
equal those of `sarfe.fe.shell.shell_element_matrices` to round-off.
"""
from __future__ import annotations

import numpy as np

from sarfe.mesh.laminate import rotate_plane_stress
from sarfe.fe.shell import (_BENDING, _DEGREE4_RULE, _MEMBRANE, DRILLING_PENALTY,
                    _allman_field, _dkt_rotation_field, _to_global, _weighted_gram,
                    consistent_mass, drilling_vector, element_kinematics)

__all__ = ["section_shell_element_matrices"]


def section_shell_element_matrices(points, triangles, membrane, coupling, bending,
                                   material_axis, mass_per_area, rotary_inertia_per_area,
                                   drilling_penalty=DRILLING_PENALTY, first_moment_per_area=None):
    """Element K, M (n_el, 18, 18) in the global frame, DOFs [ux, uy, uz, rx, ry, rz] per node.

    points (n, 3) [m]; triangles (n_el, 3); membrane A (n_el, 3, 3) [N/m], coupling B
    (n_el, 3, 3) [N], bending D (n_el, 3, 3) [N·m] in the material axes, about the node plane;
    material_axis (n_el, 3) global vector; mass_per_area m'' (n_el,) [kg/m²];
    rotary_inertia_per_area I'' = ∫ρ z² dz about the node plane (n_el,) [kg];
    first_moment_per_area S'' = ∫ρ z dz (n_el,) [kg/m] (offset shells; default 0): with
    u(z) = u₀ + z β the kinetic energy is ½∫ m''|u̇₀|² + 2 S'' u̇₀·β̇ + I''|β̇|² dA.
    """
    triangles = np.asarray(triangles)
    n_el = triangles.shape[0]
    rotation, area, grad_l, length, tangent, normal, strain, w_area = element_kinematics(
        points, triangles)
    axis_local = np.einsum("eij,ej->ei", rotation, np.asarray(material_axis, float))
    angle = np.arctan2(axis_local[:, 1], axis_local[:, 0])
    a_mat = np.asarray(membrane, float)
    a_bar = rotate_plane_stress(a_mat, angle)
    b_bar = rotate_plane_stress(np.asarray(coupling, float), angle)
    d_bar = rotate_plane_stress(np.asarray(bending, float), angle)

    t_mem = _allman_field(length, normal)
    b_mem = strain @ t_mem[:, None]  # (n_el, n_q, 3, 9)
    t_rot = _dkt_rotation_field(length, tangent, normal)
    b_bend = strain @ t_rot[:, None]
    k_mem = _weighted_gram(b_mem, a_bar, w_area)
    k_bend = _weighted_gram(b_bend, d_bar, w_area)
    # Σ_q w_q B_m,qᵀ B̄ B_b,q as batched matmuls (a many-operand einsum is slow)
    k_mb = None
    if np.any(b_bar):
        n_q = b_mem.shape[1]
        coupled = (b_bar[:, None] @ b_bend) * w_area[:, :, None, None]
        k_mb = (b_mem.reshape(n_el, 3 * n_q, 9).transpose(0, 2, 1)
                @ coupled.reshape(n_el, 3 * n_q, 9))

    # drilling penalty α (G t) A g gᵀ with G t = A66 of the section
    g = drilling_vector(grad_l, t_mem)
    k_mem += (drilling_penalty * a_mat[:, 2, 2] * area)[:, None, None] * g[:, :, None] * g[:, None, :]

    stiffness = np.zeros((n_el, 18, 18))
    stiffness[:, _MEMBRANE[:, None], _MEMBRANE] = k_mem
    stiffness[:, _BENDING[:, None], _BENDING] = k_bend
    if k_mb is not None:
        stiffness[:, _MEMBRANE[:, None], _BENDING] = k_mb
        stiffness[:, _BENDING[:, None], _MEMBRANE] = k_mb.transpose(0, 2, 1)

    m_area = np.asarray(mass_per_area, float)
    rotary = np.asarray(rotary_inertia_per_area, float)
    mass, beta = consistent_mass(area, m_area, rotary, t_rot)
    if first_moment_per_area is not None and np.any(first_moment_per_area):
        # S'' ∫ L_i β_c dA: in-plane translation c of corner i against the DKT rotations
        moment = np.asarray(first_moment_per_area, float)
        points_m, weights_m = _DEGREE4_RULE
        weight = weights_m[None, :] * (moment * area)[:, None]  # (n_el, n_q)
        coupling_mass = np.einsum("eq,qi,eqcj->eicj", weight, points_m, beta)
        for i in range(3):
            for c in range(2):
                row = 6 * i + c
                mass[:, row, _BENDING] += coupling_mass[:, i, c]
                mass[:, _BENDING, row] += coupling_mass[:, i, c]

    stiffness = _to_global(stiffness, rotation)
    mass = _to_global(mass, rotation)
    return (0.5 * (stiffness + stiffness.transpose(0, 2, 1)),
            0.5 * (mass + mass.transpose(0, 2, 1)))

