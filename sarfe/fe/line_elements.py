"""Two-node line elements of a deck: beams (bars), rods, springs; point masses. Vectorized.

Beam (CBAR, CBAR-like CBEAM) — 12×12 Timoshenko beam in its local frame (Przemieniecki):
local x = (x_b − x_a)/L, y = the part of the orientation vector v normal to x, z = x × y.
Axial E A/L, torsion G J/L; bending in the x–y plane (v, θz) with I1, in the x–z plane
(w, θy) with I2; shear flexibility Φ_i = 12 E I_i / (G k_i A L²) with the shear-area factor
k_i (k = 0: Φ = 0, Euler–Bernoulli, Nastran's blank K1/K2 for PBAR). Mass: consistent
(cubic Hermite) for bending, linear for axial and torsion (polar ρ(I1 + I2)), with ρ A + NSM.
Rod (CROD/CONROD): axial and torsion stiffness; translational consistent mass in all three
directions. K_global = Tᵀ K_local T with T = blockdiag(R, R, R, R), R rows = local axes.

Spring (CBUSH/CELAS): force in its frame F (rows = axes) f = K_s (d), d the relative motion
of the spring point. For CBUSH the spring point x_s = x_a + s (x_b − x_a) is tied to both
nodes by rigid arms: d = G_b u_b − G_a u_a, G_n = [[I, −[x_s − x_n]×], [0, I]] (6×6);
CELAS springs (location NaN) act on the node DOFs directly (G = I). Grounded: u_b = 0.
K_e = [−G_a, G_b]ᵀ Fᵀ diag(k) F [−G_a, G_b] with F = blockdiag(F, F).

Point mass (CONM2) at offset e from its node: rigid transfer u_cg = u + θ × e,
M_node = Gᵀ diag(m I, I_cg) G, G = [[I, −[e]×], [0, I]] (6×6).
"""
from __future__ import annotations

import numpy as np

__all__ = ["beam_matrices", "spring_matrices", "point_mass_matrices", "cross_matrix",
           "rigid_arm"]


def cross_matrix(r):
    """[r]× (…, 3, 3) with [r]× a = r × a."""
    r = np.asarray(r, float)
    out = np.zeros(r.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def rigid_arm(r):
    """G (…, 6, 6) = [[I, −[r]×], [0, I]]: motion of a point at r from a node (u + θ × r, θ)."""
    r = np.asarray(r, float)
    g = np.zeros(r.shape[:-1] + (6, 6))
    g[..., :3, :3] = np.eye(3)
    g[..., 3:, 3:] = np.eye(3)
    g[..., :3, 3:] = -cross_matrix(r)
    return g


def _beam_frames(points, nodes, orientation, is_rod, card, element_ids):
    x = np.asarray(points, float)[nodes]
    axis = x[:, 1] - x[:, 0]
    length = np.linalg.norm(axis, axis=1)
    if np.any(length <= 0):
        row = int(np.flatnonzero(length <= 0)[0])
        raise ValueError(f"{card[row]} {int(element_ids[row])} has zero length")
    ex = axis / length[:, None]
    v = np.where(is_rod[:, None], _any_normal(ex), orientation)
    ey = v - np.einsum("ei,ei->e", v, ex)[:, None] * ex
    norm = np.linalg.norm(ey, axis=1)
    parallel = norm <= 1e-9 * np.linalg.norm(v, axis=1)
    if np.any(parallel):
        row = int(np.flatnonzero(parallel)[0])
        raise ValueError(f"{card[row]} {int(element_ids[row])}: orientation vector parallel to "
                         "its axis (or zero)")
    ey /= norm[:, None]
    return np.stack([ex, ey, np.cross(ex, ey)], axis=1), length


def _any_normal(ex):
    trial = np.where(np.abs(ex[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    return trial - np.einsum("ei,ei->e", trial, ex)[:, None] * ex


def _bending_block(ei, length, phi, sign):
    """(n, 4, 4) Timoshenko bending stiffness on [w_a, θ_a, w_b, θ_b]; sign = +1 for the
    x–y plane (v, θz), −1 for the x–z plane (w, θy)."""
    L = length
    s = sign
    k = np.zeros((len(L), 4, 4))
    c = ei / (L**3 * (1 + phi))
    k[:, 0, 0] = k[:, 2, 2] = 12 * c
    k[:, 0, 2] = k[:, 2, 0] = -12 * c
    k[:, 0, 1] = k[:, 1, 0] = k[:, 0, 3] = k[:, 3, 0] = s * 6 * L * c
    k[:, 2, 1] = k[:, 1, 2] = k[:, 2, 3] = k[:, 3, 2] = -s * 6 * L * c
    k[:, 1, 1] = k[:, 3, 3] = (4 + phi) * L**2 * c
    k[:, 1, 3] = k[:, 3, 1] = (2 - phi) * L**2 * c
    return k


def _bending_mass(m, length, sign):
    """(n, 4, 4) consistent (cubic Hermite) bending mass on [w_a, θ_a, w_b, θ_b]; the x–z
    plane (sign −1) flips the rotation rows/columns."""
    base = np.array([[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]], float)
    power = np.array([[0, 1, 0, 1], [1, 2, 1, 2], [0, 1, 0, 1], [1, 2, 1, 2]])
    d = np.array([1.0, sign, 1.0, sign])
    return (m / 420)[:, None, None] * base * np.outer(d, d) * length[:, None, None] ** power


def beam_matrices(points, beams, lumped_torsion=False):
    """Element K, M (n, 12, 12) global and DOFs (n, 12) of a `BeamElements` table.

    lumped_torsion: the torsional inertia as Nastran lumps it — none for a CBAR, ρ I_p L/2 on
    each end of a CBEAM — instead of the consistent ρ I_p L [[2, 1], [1, 2]]/6 (I_p = I1 + I2;
    measured on pyNastran's beam_modes deck: the torsion mode 3555 Hz of MSC's is 3555 Hz with
    this rule, 2567 Hz with the consistent one)."""
    card = np.asarray(beams.card)
    n = len(card)
    is_rod = np.isin(card, ["CROD", "CONROD", "ROD"])
    if np.any((beams.i12 != 0) & ~is_rod):
        row = int(np.flatnonzero((beams.i12 != 0) & ~is_rod)[0])
        raise ValueError(f"{card[row]} {int(beams.element_ids[row])}: I12 ≠ 0 is not modelled")
    rotation, L = _beam_frames(points, beams.nodes, beams.orientation, is_rod, card,
                               beams.element_ids)
    e, g, a = beams.young, beams.shear_modulus, beams.area
    k = np.zeros((n, 12, 12))
    m = np.zeros((n, 12, 12))
    pair = np.array([[1.0, -1.0], [-1.0, 1.0]])
    consistent = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    ax, tor = [0, 6], [3, 9]
    k[:, np.ix_(ax, ax)[0], np.ix_(ax, ax)[1]] = (e * a / L)[:, None, None] * pair
    k[:, np.ix_(tor, tor)[0], np.ix_(tor, tor)[1]] = (g * beams.torsion / L)[:, None, None] * pair
    line_mass = (beams.density * a + beams.mass_per_length) * L
    bend = ~is_rod
    with np.errstate(divide="ignore", invalid="ignore"):
        phi_y = np.where(beams.shear_factor_1 > 0,
                         12 * e * beams.i1 / (g * beams.shear_factor_1 * a * L**2), 0.0)
        phi_z = np.where(beams.shear_factor_2 > 0,
                         12 * e * beams.i2 / (g * beams.shear_factor_2 * a * L**2), 0.0)
    plane_y, plane_z = [1, 5, 7, 11], [2, 4, 8, 10]
    iy, iz = np.ix_(plane_y, plane_y), np.ix_(plane_z, plane_z)
    k[:, iy[0], iy[1]] += np.where(bend[:, None, None],
                                   _bending_block(e * beams.i1, L, phi_y, +1.0), 0.0)
    k[:, iz[0], iz[1]] += np.where(bend[:, None, None],
                                   _bending_block(e * beams.i2, L, phi_z, -1.0), 0.0)
    m[:, np.ix_(ax, ax)[0], np.ix_(ax, ax)[1]] = line_mass[:, None, None] * consistent
    polar = beams.density * (beams.i1 + beams.i2) * L
    if lumped_torsion:
        polar = np.where(card == "CBAR", 0.0, polar)
        m[:, np.ix_(tor, tor)[0], np.ix_(tor, tor)[1]] = polar[:, None, None] * np.eye(2) / 2.0
    else:
        m[:, np.ix_(tor, tor)[0], np.ix_(tor, tor)[1]] = polar[:, None, None] * consistent
    rod_mass = np.zeros((n, 4, 4))
    rod_mass[:, np.ix_([0, 2], [0, 2])[0], np.ix_([0, 2], [0, 2])[1]] = line_mass[:, None, None] * consistent
    m[:, iy[0], iy[1]] = np.where(bend[:, None, None], _bending_mass(line_mass, L, +1.0), rod_mass)
    m[:, iz[0], iz[1]] = np.where(bend[:, None, None], _bending_mass(line_mass, L, -1.0), rod_mass)
    t = np.zeros((n, 12, 12))
    for block in range(4):
        t[:, 3 * block:3 * block + 3, 3 * block:3 * block + 3] = rotation
    tt = t.transpose(0, 2, 1)
    dofs = (6 * np.asarray(beams.nodes)[:, :, None] + np.arange(6)).reshape(n, 12)
    return tt @ k @ t, tt @ m @ t, dofs


def spring_matrices(points, springs):
    """Element K (n, 12, 12), the K·GE and viscous B matrices alike, and DOFs (n, 12).

    Grounded springs (node_b = −1): the node-b half of their matrices is zero and their DOF
    list repeats node a's DOFs there (adds nothing)."""
    x = np.asarray(points, float)
    a = np.asarray(springs.node_a)
    b = np.asarray(springs.node_b)
    grounded = b < 0
    b_safe = np.where(grounded, a, b)
    location = np.asarray(springs.location, float)
    arms = np.isfinite(location) & ~grounded
    frac = np.where(arms, location, 0.0)
    xs = x[a] + frac[:, None] * (x[b_safe] - x[a])
    ga = np.where(arms[:, None, None], rigid_arm(xs - x[a]), np.eye(6))
    gb = np.where(arms[:, None, None], rigid_arm(xs - x[b_safe]), np.eye(6))
    gb = np.where(grounded[:, None, None], 0.0, gb)
    n = len(a)
    frame6 = np.zeros((n, 6, 6))
    frame6[:, :3, :3] = springs.frames
    frame6[:, 3:, 3:] = springs.frames
    relative = frame6 @ np.concatenate([-ga, gb], axis=2)  # (n, 6, 12)

    def element(values):
        return relative.transpose(0, 2, 1) @ (np.asarray(values, float)[:, :, None] * relative)

    dofs = (6 * np.stack([a, b_safe], 1)[:, :, None] + np.arange(6)).reshape(n, 12)
    stiffness = element(springs.stiffness)
    structural = stiffness * np.asarray(springs.structural_damping, float)[:, None, None]
    return stiffness, structural, element(springs.viscous_damping), dofs


def point_mass_matrices(masses):
    """Nodal 6×6 mass matrices (p, 6, 6) [kg, kg·m, kg·m²] and DOFs (p, 6) of CONM2s."""
    p = len(masses.node)
    m_cg = np.zeros((p, 6, 6))
    m_cg[:, :3, :3] = np.asarray(masses.mass, float)[:, None, None] * np.eye(3)
    m_cg[:, 3:, 3:] = masses.inertia
    g = rigid_arm(masses.offset)
    dofs = 6 * np.asarray(masses.node)[:, None] + np.arange(6)
    return g.transpose(0, 2, 1) @ m_cg @ g, dofs
