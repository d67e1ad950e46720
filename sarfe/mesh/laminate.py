"""Plane-stress material matrices and classical lamination theory (CLT), vectorized.

Voigt order [xx, yy, xy] with engineering shear γ_xy. Section resultants per unit width:
    N = A ε⁰ + B κ,   M = B ε⁰ + D κ,
    A = Σ_k Q̄_k (z_k − z_{k−1})            [N/m]
    B = ½ Σ_k Q̄_k (z_k² − z_{k−1}²)        [N]
    D = ⅓ Σ_k Q̄_k (z_k³ − z_{k−1}³)        [N·m]
with z measured from the reference (node) plane [m], Q̄_k the ply's plane-stress matrix
[Pa] rotated by its angle θ_k (counter-clockwise from the section's axis 1 to the ply's
fibre axis). Transverse shear G t per ply: Σ_k R̄_k (z_k − z_{k−1}) (no shear factor).

Section properties of the deck (`DeckModel.shells`) are computed here by the readers; the
section shell element (`sarfe.fe.shell_section`) rotates them into its frame.
"""
from __future__ import annotations

import numpy as np

__all__ = ["isotropic_plane_stress", "orthotropic_plane_stress", "rotate_plane_stress",
           "laminate_stiffness", "rotate_transverse_shear"]


def isotropic_plane_stress(young, poisson, shear_modulus=None):
    """Q (…, 3, 3) [Pa] = [[E/(1−ν²), νE/(1−ν²), 0], [νE/(1−ν²), E/(1−ν²), 0], [0, 0, G]];
    G defaults to E/(2(1+ν))."""
    young, poisson = np.asarray(young, float), np.asarray(poisson, float)
    if shear_modulus is None:
        shear_modulus = young / (2.0 * (1.0 + poisson))
    shape = np.broadcast(young, poisson, shear_modulus).shape
    q = np.zeros(shape + (3, 3))
    factor = young / (1.0 - poisson**2)
    q[..., 0, 0] = q[..., 1, 1] = factor
    q[..., 0, 1] = q[..., 1, 0] = factor * poisson
    q[..., 2, 2] = shear_modulus
    return q


def orthotropic_plane_stress(e1, e2, nu12, g12):
    """Q (…, 3, 3) [Pa] of an orthotropic ply in its axes: Q11 = E1/(1−ν12ν21),
    Q22 = E2/(1−ν12ν21), Q12 = ν12 E2/(1−ν12ν21), Q66 = G12, with ν21 = ν12 E2/E1."""
    e1, e2, nu12, g12 = (np.asarray(v, float) for v in (e1, e2, nu12, g12))
    denominator = 1.0 - nu12 * nu12 * e2 / e1
    q = np.zeros(np.broadcast(e1, e2, nu12, g12).shape + (3, 3))
    q[..., 0, 0] = e1 / denominator
    q[..., 1, 1] = e2 / denominator
    q[..., 0, 1] = q[..., 1, 0] = nu12 * e2 / denominator
    q[..., 2, 2] = g12
    return q


def _strain_rotation(angle):
    """T_ε (…, 3, 3): ε' = T_ε ε for axes rotated by ``angle`` [rad] (engineering shear)."""
    c, s = np.cos(angle), np.sin(angle)
    t = np.zeros(np.shape(angle) + (3, 3))
    t[..., 0, 0], t[..., 0, 1], t[..., 0, 2] = c * c, s * s, c * s
    t[..., 1, 0], t[..., 1, 1], t[..., 1, 2] = s * s, c * c, -c * s
    t[..., 2, 0], t[..., 2, 1], t[..., 2, 2] = -2 * c * s, 2 * c * s, c * c - s * s
    return t


def rotate_plane_stress(q, angle):
    """Q̄ = T_εᵀ Q T_ε: a (…, 3, 3) matrix given in axes at ``angle`` [rad] (counter-clockwise
    from x) expressed in the x–y axes. Works for A, B and D alike."""
    t = _strain_rotation(np.asarray(angle, float))
    return np.swapaxes(t, -1, -2) @ q @ t


def rotate_transverse_shear(g, angle):
    """R̄ = Rᵀ G R for a (…, 2, 2) transverse-shear matrix [γ_xz, γ_yz] given in axes at
    ``angle`` [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    r = np.zeros(np.shape(angle) + (2, 2))
    r[..., 0, 0], r[..., 0, 1], r[..., 1, 0], r[..., 1, 1] = c, s, -s, c
    return np.swapaxes(r, -1, -2) @ g @ r


def laminate_stiffness(ply_q, ply_angle, ply_bottom, ply_top):
    """A [N/m], B [N], D [N·m] (…, 3, 3) of laminates.

    ply_q (…, n_ply, 3, 3) [Pa] ply matrices in their own axes; ply_angle (…, n_ply) [rad];
    ply_bottom, ply_top (…, n_ply) [m] from the reference plane. Padding plies of zero
    thickness contribute nothing, so laminates of different ply counts stack in one array.
    """
    q_bar = rotate_plane_stress(np.asarray(ply_q, float), ply_angle)
    z0, z1 = np.asarray(ply_bottom, float), np.asarray(ply_top, float)
    a = np.einsum("...k,...kij->...ij", z1 - z0, q_bar)
    b = np.einsum("...k,...kij->...ij", (z1**2 - z0**2) / 2.0, q_bar)
    d = np.einsum("...k,...kij->...ij", (z1**3 - z0**3) / 3.0, q_bar)
    return a, b, d
