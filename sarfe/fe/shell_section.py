"""The facet shell triangle of `sarfe.fe.shell` with a general shell section (A, B, D, G t).

Same kinematics as `sarfe.fe.shell` (membrane of :mod:`sarfe.fe.membrane`, 6 DOF per node,
element frame e1 along edge 1→2, e3 = normal); the section stiffness is given per element
instead of (t, E, ν), so laminates (PCOMP via `sarfe.mesh.laminate`), orthotropic and
anisotropic sections fit:
    K = ∫ [ε_m; κ]ᵀ [[A, B], [B, D]] [ε_m; κ] dA  (+ the transverse shear energy)
with ε_m the membrane strain (ANDES: K_m from the optimal template with C = A and the basic
constant strain in the coupling; Allman: its field at the midside rule plus the drilling
penalty with C₃₃ = A66) and κ the curvature of the bending triangle
(:mod:`sarfe.fe.plate_bending`): DKT where the section gives no transverse shear, DKMT with
the compliance F = (G t)⁻¹ where it does (Nastran's PSHELL MID3, PCOMP): K_s = A G_qᵀ F G_q.
A, B, D and G t are given in the section's material axes (``material_axis``, a global vector in
the element plane) and rotated into the element frame, Ā = T_εᵀ A T_ε, Ḡ = Rᵀ G R.

Mass: translations (m'' ∫ N_i N_j dA, m'' = mass per area [kg/m²]); rotary inertia
I'' [kg] on the bending triangle's rotation field; drilling I'' A/12 (1 + δ_ij), as in
`sarfe.fe.shell`; for offset shells the first moment S'' couples in-plane translations
(linear N) with the rotations, M_uβ = S'' ∫ N_i β dA (degree-4 rule, exact).
For an isotropic section without transverse shear (A = t Q, B = 0, D = t³/12 Q, m'' = ρ t,
I'' = ρ t³/12) the matrices equal those of `sarfe.fe.shell.shell_element_matrices` to round-off.
"""
from __future__ import annotations

import numpy as np

from sarfe.fe.membrane import DRILLING_PENALTY
from sarfe.fe.plate_bending import dkmt_rotation_field, dkt_rotation_field
from sarfe.fe.shell import (BENDING_DOFS, DEFAULT_MEMBRANE, DEGREE4_RULE, MEMBRANE_DOFS,
                            consistent_mass, element_kinematics, membrane_stiffness, to_global,
                            weighted_gram)
from sarfe.mesh.laminate import rotate_plane_stress, rotate_transverse_shear

__all__ = ["section_shell_element_matrices", "shear_compliance"]


def shear_compliance(transverse_shear, angle):
    """F = Ḡ⁻¹ (n_el, 2, 2) [m/N] in the element frame, Ḡ = Rᵀ (G t) R for G t (n_el, 2, 2)
    [N/m] given in axes at ``angle`` (n_el,) [rad]; zero where no shear stiffness is given
    (a zero or singular G t: Kirchhoff, rigid in transverse shear)."""
    g_bar = rotate_transverse_shear(np.asarray(transverse_shear, float), angle)
    det = g_bar[:, 0, 0] * g_bar[:, 1, 1] - g_bar[:, 0, 1] * g_bar[:, 1, 0]
    given = det > 1e-12 * np.maximum(np.abs(g_bar).max(axis=(1, 2)), 1e-300) ** 2
    out = np.zeros_like(g_bar)
    out[given] = np.linalg.inv(g_bar[given])
    return out


def section_shell_element_matrices(points, triangles, membrane, coupling, bending,
                                   material_axis, mass_per_area, rotary_inertia_per_area,
                                   drilling_penalty=DRILLING_PENALTY, first_moment_per_area=None,
                                   transverse_shear=None, formulation=DEFAULT_MEMBRANE,
                                   drilling_inertia=True):
    """Element K, M (n_el, 18, 18) in the global frame, DOFs [ux, uy, uz, rx, ry, rz] per node.

    points (n, 3) [m]; triangles (n_el, 3); membrane A (n_el, 3, 3) [N/m], coupling B
    (n_el, 3, 3) [N], bending D (n_el, 3, 3) [N·m] in the material axes, about the node plane;
    material_axis (n_el, 3) global vector; mass_per_area m'' (n_el,) [kg/m²];
    rotary_inertia_per_area I'' = ∫ρ z² dz about the node plane (n_el,) [kg];
    first_moment_per_area S'' = ∫ρ z dz (n_el,) [kg/m] (offset shells; default 0): with
    u(z) = u₀ + z β the kinetic energy is ½∫ m''|u̇₀|² + 2 S'' u̇₀·β̇ + I''|β̇|² dA;
    transverse_shear G t (n_el, 2, 2) [N/m] in the material axes (None or zeros: Kirchhoff,
    DKT); formulation: the membrane, 'andes' | 'allman' | 'cst' (drilling_penalty α for
    'allman' and 'cst'); drilling_inertia False leaves the drilling rotation without mass.
    """
    triangles = np.asarray(triangles)
    n_el = triangles.shape[0]
    geometry = element_kinematics(points, triangles)
    axis_local = np.einsum("eij,ej->ei", geometry.rotation, np.asarray(material_axis, float))
    angle = np.arctan2(axis_local[:, 1], axis_local[:, 0])
    a_bar = rotate_plane_stress(np.asarray(membrane, float), angle)
    b_bar = rotate_plane_stress(np.asarray(coupling, float), angle)
    d_bar = rotate_plane_stress(np.asarray(bending, float), angle)

    k_mem, b_mem = membrane_stiffness(geometry, a_bar, formulation, drilling_penalty)
    compliance = (None if transverse_shear is None
                  else shear_compliance(transverse_shear, angle))
    k_shear = None
    if compliance is not None and np.any(compliance):
        t_rot, shear_force = dkmt_rotation_field(geometry.length, geometry.tangent,
                                                 geometry.normal, geometry.grad_l, d_bar,
                                                 compliance)
        k_shear = geometry.area[:, None, None] * (
            shear_force.transpose(0, 2, 1) @ compliance @ shear_force)
    else:
        t_rot = dkt_rotation_field(geometry.length, geometry.tangent, geometry.normal)
    b_bend = geometry.strain @ t_rot[:, None]
    k_bend = weighted_gram(b_bend, d_bar, geometry.w_area)
    if k_shear is not None:
        k_bend += k_shear
    # Σ_q w_q B_m,qᵀ B̄ B_b,q as batched matmuls (a many-operand einsum is slow)
    k_mb = None
    if np.any(b_bar):
        n_q = b_mem.shape[1]
        coupled = (b_bar[:, None] @ b_bend) * geometry.w_area[:, :, None, None]
        k_mb = (np.ascontiguousarray(b_mem).reshape(n_el, 3 * n_q, 9).transpose(0, 2, 1)
                @ coupled.reshape(n_el, 3 * n_q, 9))

    stiffness = np.zeros((n_el, 18, 18))
    stiffness[:, MEMBRANE_DOFS[:, None], MEMBRANE_DOFS] = k_mem
    stiffness[:, BENDING_DOFS[:, None], BENDING_DOFS] = k_bend
    if k_mb is not None:
        stiffness[:, MEMBRANE_DOFS[:, None], BENDING_DOFS] = k_mb
        stiffness[:, BENDING_DOFS[:, None], MEMBRANE_DOFS] = k_mb.transpose(0, 2, 1)

    m_area = np.asarray(mass_per_area, float)
    rotary = np.asarray(rotary_inertia_per_area, float)
    mass, beta = consistent_mass(geometry.area, m_area, rotary, t_rot, drilling_inertia)
    if first_moment_per_area is not None and np.any(first_moment_per_area):
        # S'' ∫ L_i β_c dA: in-plane translation c of corner i against the rotations
        moment = np.asarray(first_moment_per_area, float)
        points_m, weights_m = DEGREE4_RULE
        weight = weights_m[None, :] * (moment * geometry.area)[:, None]  # (n_el, n_q)
        coupling_mass = np.einsum("eq,qi,eqcj->eicj", weight, points_m, beta)
        for i in range(3):
            for c in range(2):
                row = 6 * i + c
                mass[:, row, BENDING_DOFS] += coupling_mass[:, i, c]
                mass[:, BENDING_DOFS, row] += coupling_mass[:, i, c]

    stiffness = to_global(stiffness, geometry.rotation)
    mass = to_global(mass, geometry.rotation)
    return (0.5 * (stiffness + stiffness.transpose(0, 2, 1)),
            0.5 * (mass + mass.transpose(0, 2, 1)))
