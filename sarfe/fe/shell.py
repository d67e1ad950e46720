"""Flat facet shell triangle: Allman membrane + DKT plate bending, 6 DOF per node.

Each triangle is flat in its own local frame (e1 along edge 1→2, e3 = unit normal
(x2−x1)×(x3−x1), e2 = e3×e1); its 18×18 local matrices are rotated to the global
frame, K_e = Tᵀ K_local T with T = blockdiag(R, R, R, R, R, R), R = [e1; e2; e3].
Local DOF order per node: [u, v, w, θx, θy, θz] (θz = drilling rotation).

Membrane (u, v, θz): Allman (1984) triangle. The quadratic in-plane field has corner
values u_i and midside values u_ij = (u_i + u_j)/2 + (L_ij/8)(θz_j − θz_i) n_ij
(n_ij outward edge normal), strain ε = [u,x, v,y, u,y + v,x], stiffness
K_m = ∫ t Bᵀ D_m B dA, D_m = E/(1−ν²)[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]].
Its one spurious mode (equal θz at the corners, no displacement) is removed by the
drilling penalty K_d = α G t A g gᵀ with g·q = mean(θz) − ω(centroid),
ω = (v,x − u,y)/2 (Hughes–Brezzi type; zero for any rigid motion).

Bending (w, θx, θy): DKT (Batoz, Bathe & Ho 1980). With rotations β = (βx, βy) =
(θy, −θx) (so Kirchhoff gives β = −∇w), β is quadratic over the triangle; corner
values β_i from the nodal rotations, midside values from the Kirchhoff constraint
along each edge: tangential β_s = −∂w/∂s of the cubic edge w, normal β_n linear.
Curvature κ = [βx,x, βy,y, βx,y + βy,x], K_b = ∫ κᵀ D_b κ dA,
D_b = E t³/(12(1−ν²))[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]].
Both stiffness integrands are quadratic: the three-midside-point rule is exact.

Consistent mass (documented choice):
  translations u, v, w: ρ t ∫ N_i N_j dA with linear N (= ρ t A/12 (1 + δ_ij)) — the
    membrane consistent mass and the bending translational consistent mass;
  rotary inertia θx, θy: (ρ t³/12) ∫ β·β dA with the DKT rotation field (degree-4 rule);
  drilling θz: (ρ t³/12) A/12 (1 + δ_ij), a small fictitious inertia.
The sum is symmetric positive definite (translations by the linear mass, rotations by
the rotary terms), so M can be Cholesky-factorized by the reduction step.

Everything is vectorized over elements: arrays are shaped (elements, ...), no Python
loop over elements.
"""

from __future__ import annotations

import numpy as np

from sarfe.fe.assembly import assemble_pair, element_dofs

__all__ = [
    "shell_matrices",
    "shell_element_matrices",
    "local_frames",
    "DRILLING_PENALTY",
]

#: elements per vectorized block (keeps the (block, 18, 18) work arrays cache-sized)
BLOCK_SIZE = 4096

#: default α of the drilling penalty K_d = α G t A g gᵀ
DRILLING_PENALTY = 1e-2

# P2 triangle nodes: corners 0, 1, 2 then midsides (0,1), (1,2), (2,0)
_EDGES = np.array([[0, 1], [1, 2], [2, 0]])

# three midside points, weights sum to 1 (times area); exact for quadratics
_MIDSIDE_RULE = (
    np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]]),
    np.full(3, 1.0 / 3.0),
)


def _dunavant4():
    """Six-point degree-4 triangle rule (Dunavant 1985) in area coordinates."""
    a, b = 0.445948490915965, 0.091576213509771
    wa, wb = 0.223381589678011, 0.109951743655322
    points = np.array(
        [[a, a, 1 - 2 * a], [a, 1 - 2 * a, a], [1 - 2 * a, a, a],
         [b, b, 1 - 2 * b], [b, 1 - 2 * b, b], [1 - 2 * b, b, b]]
    )
    return points, np.array([wa, wa, wa, wb, wb, wb])


_DEGREE4_RULE = _dunavant4()


def _as_element_array(value, n_elements, name):
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return np.full(n_elements, float(array))
    if array.shape != (n_elements,):
        raise ValueError(f"{name} must be a scalar or shaped ({n_elements},), got {array.shape}")
    return array


def local_frames(points, triangles):
    """Local element frames.

    Returns ``rotation`` (n_el, 3, 3) with rows e1, e2, e3 (x_local = R x_global),
    ``local_xy`` (n_el, 3, 2) corner coordinates in the element plane [m] (node 0 at the
    origin, counter-clockwise) and ``area`` (n_el,) [m²].
    """
    x = np.asarray(points, dtype=float)[np.asarray(triangles)]
    d1 = x[:, 1] - x[:, 0]
    d2 = x[:, 2] - x[:, 0]
    normal = np.cross(d1, d2)
    twice_area = np.linalg.norm(normal, axis=1)
    if np.any(twice_area <= 1e-14 * np.einsum("ei,ei->e", d1, d1)):
        raise ValueError("degenerate (zero-area) triangle in the shell mesh")
    e3 = normal / twice_area[:, None]
    e1 = d1 / np.linalg.norm(d1, axis=1)[:, None]
    e2 = np.cross(e3, e1)
    rotation = np.stack([e1, e2, e3], axis=1)
    local_xy = np.einsum("eij,ekj->eki", rotation[:, :2], x - x[:, :1])
    return rotation, local_xy, 0.5 * twice_area


def _p2_gradients(area_coords, grad_l):
    """Gradients of the six P2 shape functions, (n_el, n_q, 6, 2).

    Corner a: (4 L_a − 1) ∇L_a; midside (i, j): 4 (L_i ∇L_j + L_j ∇L_i).
    """
    n_q = area_coords.shape[0]
    coeff = np.zeros((n_q, 6, 3))
    for a in range(3):
        coeff[:, a, a] = 4.0 * area_coords[:, a] - 1.0
    for m, (i, j) in enumerate(_EDGES):
        coeff[:, 3 + m, j] += 4.0 * area_coords[:, i]
        coeff[:, 3 + m, i] += 4.0 * area_coords[:, j]
    return np.einsum("qab,ebx->eqax", coeff, grad_l)


def _p2_values(area_coords):
    """Values of the six P2 shape functions at the points, (n_q, 6)."""
    corner = area_coords * (2.0 * area_coords - 1.0)
    mid = 4.0 * area_coords[:, _EDGES[:, 0]] * area_coords[:, _EDGES[:, 1]]
    return np.hstack([corner, mid])


def _strain_operator(grad_p2):
    """B (n_el, n_q, 3, 12) mapping a P2 vector field (node-major, 2 components)
    to [f_x,x, f_y,y, f_x,y + f_y,x]."""
    n_el, n_q = grad_p2.shape[:2]
    b = np.zeros((n_el, n_q, 3, 6, 2))
    b[:, :, 0, :, 0] = grad_p2[..., 0]
    b[:, :, 1, :, 1] = grad_p2[..., 1]
    b[:, :, 2, :, 0] = grad_p2[..., 1]
    b[:, :, 2, :, 1] = grad_p2[..., 0]
    return b.reshape(n_el, n_q, 3, 12)


def _edge_geometry(local_xy):
    """Edge lengths (n_el, 3), unit tangents s and outward normals n (n_el, 3, 2)."""
    d = local_xy[:, _EDGES[:, 1]] - local_xy[:, _EDGES[:, 0]]
    length = np.linalg.norm(d, axis=2)
    tangent = d / length[..., None]
    normal = np.stack([tangent[..., 1], -tangent[..., 0]], axis=2)
    return length, tangent, normal


def _allman_field(length, normal):
    """(n_el, 12, 9): [u_i, v_i, θz_i] (i = 0..2) → P2 nodal in-plane displacements."""
    n_el = length.shape[0]
    t = np.zeros((n_el, 6, 2, 3, 3))
    for a in range(3):
        t[:, a, 0, a, 0] = 1.0
        t[:, a, 1, a, 1] = 1.0
    for m, (i, j) in enumerate(_EDGES):
        t[:, 3 + m, 0, i, 0] = t[:, 3 + m, 0, j, 0] = 0.5
        t[:, 3 + m, 1, i, 1] = t[:, 3 + m, 1, j, 1] = 0.5
        drill = (length[:, m] / 8.0)[:, None] * normal[:, m]  # (n_el, 2)
        t[:, 3 + m, :, j, 2] += drill
        t[:, 3 + m, :, i, 2] -= drill
    return t.reshape(n_el, 12, 9)


def _dkt_rotation_field(length, tangent, normal):
    """(n_el, 12, 9): [w_i, θx_i, θy_i] → P2 nodal rotations β = (βx, βy).

    Corners: β = P q, P = [[0, 0, 1], [0, −1, 0]] (βx = θy, βy = −θx).
    Midside of edge i→j: β = s·3/(2L)(w_i − w_j) + (−s sᵀ/4 + n nᵀ/2)(β_i + β_j).
    """
    n_el = length.shape[0]
    p = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    t = np.zeros((n_el, 6, 2, 3, 3))
    t[:, np.arange(3), :, np.arange(3), :] = p
    q = (-0.25 * np.einsum("emx,emy->emxy", tangent, tangent)
         + 0.5 * np.einsum("emx,emy->emxy", normal, normal))
    qp = q @ p  # (n_el, 3, 2, 3)
    for m, (i, j) in enumerate(_EDGES):
        t[:, 3 + m, :, i, :] += qp[:, m]
        t[:, 3 + m, :, j, :] += qp[:, m]
        slope = (1.5 / length[:, m])[:, None] * tangent[:, m]
        t[:, 3 + m, :, i, 0] += slope
        t[:, 3 + m, :, j, 0] -= slope
    return t.reshape(n_el, 12, 9)


def _plane_stress(young, poisson):
    """(n_el, 3, 3) plane-stress matrix E/(1−ν²)[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]]."""
    d = np.zeros((young.shape[0], 3, 3))
    factor = young / (1.0 - poisson**2)
    d[:, 0, 0] = d[:, 1, 1] = factor
    d[:, 0, 1] = d[:, 1, 0] = factor * poisson
    d[:, 2, 2] = factor * (1.0 - poisson) / 2.0
    return d


# local 18-DOF indices of the membrane (u, v, θz) and bending (w, θx, θy) parts
_MEMBRANE = (6 * np.arange(3)[:, None] + np.array([0, 1, 5])).ravel()
_BENDING = (6 * np.arange(3)[:, None] + np.array([2, 3, 4])).ravel()


def element_kinematics(points, triangles):
    """What every facet-shell element needs of its geometry (this element and
    :mod:`sarfe.fe.shell_section`): rotation (n_el, 3, 3) to the element frame, area (n_el,) [m²],
    area-coordinate gradients ∇L (n_el, 3, 2) [1/m], edge length/tangent/normal, the P2 strain
    operator at the midside points (n_el, 3, 3, 12) and the rule's weights × area (n_el, 3)."""
    rotation, xy, area = local_frames(points, triangles)
    # ∇L_i = (y_j − y_k, x_k − x_j) / (2A), (i, j, k) cyclic
    nxt, prv = [1, 2, 0], [2, 0, 1]
    grad_l = np.stack(
        [xy[:, nxt, 1] - xy[:, prv, 1], xy[:, prv, 0] - xy[:, nxt, 0]], axis=2
    ) / (2.0 * area)[:, None, None]
    length, tangent, normal = _edge_geometry(xy)
    points_q, weights_q = _MIDSIDE_RULE
    strain = _strain_operator(_p2_gradients(points_q, grad_l))  # (n_el, 3, 3, 12)
    w_area = weights_q[None, :] * area[:, None]  # (n_el, n_q)
    return rotation, area, grad_l, length, tangent, normal, strain, w_area


def drilling_vector(grad_l, t_mem):
    """g (n_el, 9) of the drilling penalty, g·q = mean(θz) − ω(centroid), ω = (v,x − u,y)/2."""
    n_el = grad_l.shape[0]
    centroid = np.full((1, 3), 1.0 / 3.0)
    grad_c = _p2_gradients(centroid, grad_l)[:, 0]  # (n_el, 6, 2)
    spin = np.zeros((n_el, 6, 2))
    spin[:, :, 0] = -0.5 * grad_c[..., 1]  # ω = (v,x − u,y)/2
    spin[:, :, 1] = 0.5 * grad_c[..., 0]
    g = -np.einsum("ea,eaj->ej", spin.reshape(n_el, 12), t_mem)
    g[:, 2::3] += 1.0 / 3.0
    return g


def consistent_mass(area, mass_per_area, rotary_inertia_per_area, t_rot):
    """Element mass (n_el, 18, 18) in the element frame (module docstring): translations
    m'' A/12 (1 + δ_ij), drilling I'' A/12 (1 + δ_ij), rotary inertia I'' ∫ β·β dA on the DKT
    rotation field (degree-4 rule); m'' [kg/m²], I'' [kg] per element. Also returns the rotation
    field β at the rule's points (n_el, n_q, 2, 9)."""
    n_el = area.shape[0]
    linear = (np.ones((3, 3)) + np.eye(3)) / 12.0
    mass = np.zeros((n_el, 3, 6, 3, 6))
    m_trans = (mass_per_area * area)[:, None, None] * linear
    m_drill = (rotary_inertia_per_area * area)[:, None, None] * linear
    for c in range(3):
        mass[:, :, c, :, c] = m_trans
    mass[:, :, 5, :, 5] = m_drill
    mass = mass.reshape(n_el, 18, 18)
    points_m, weights_m = _DEGREE4_RULE
    values = _p2_values(points_m)  # (n_q, 6)
    interp = np.zeros((len(weights_m), 2, 6, 2))
    interp[:, 0, :, 0] = values
    interp[:, 1, :, 1] = values
    beta = np.einsum("qcn,enj->eqcj", interp.reshape(-1, 2, 12), t_rot)  # (n_el, n_q, 2, 9)
    m_rot = _weighted_gram(beta, np.eye(2)[None], np.broadcast_to(
        weights_m * (rotary_inertia_per_area * area)[:, None], beta.shape[:2]))
    mass[:, _BENDING[:, None], _BENDING] += m_rot
    return mass, beta


def shell_element_matrices(points, triangles, thickness, young, poisson, density,
                           drilling_penalty=DRILLING_PENALTY, local=False):
    """Element stiffness and mass matrices, each (n_el, 18, 18).

    Parameters: points (n, 3) [m], triangles (n_el, 3) int, thickness [m], young [Pa],
    poisson [-], density [kg/m³] (scalars or (n_el,) arrays), drilling_penalty α [-].
    Element DOFs: 6 per corner node, [ux, uy, uz, rx, ry, rz], node-major; global frame
    unless ``local=True`` (then the element frame of :func:`local_frames`).
    """
    triangles = np.asarray(triangles)
    n_el = triangles.shape[0]
    t = _as_element_array(thickness, n_el, "thickness")
    e = _as_element_array(young, n_el, "young")
    nu = _as_element_array(poisson, n_el, "poisson")
    rho = _as_element_array(density, n_el, "density")

    rotation, area, grad_l, length, tangent, normal, strain, w_area = element_kinematics(
        points, triangles)
    d_plane = _plane_stress(e, nu)

    # membrane: Allman + drilling penalty
    t_mem = _allman_field(length, normal)
    b_mem = strain @ t_mem[:, None]  # (n_el, n_q, 3, 9)
    k_mem = _weighted_gram(b_mem, d_plane, w_area * t[:, None])
    g = drilling_vector(grad_l, t_mem)
    shear_modulus = e / (2.0 * (1.0 + nu))
    k_mem += (drilling_penalty * shear_modulus * t * area)[:, None, None] * g[:, :, None] * g[:, None, :]

    # bending: DKT
    t_rot = _dkt_rotation_field(length, tangent, normal)
    b_bend = strain @ t_rot[:, None]
    d_bend = d_plane * (t**3 / 12.0)[:, None, None]
    k_bend = _weighted_gram(b_bend, d_bend, w_area)

    stiffness = np.zeros((n_el, 18, 18))
    stiffness[:, _MEMBRANE[:, None], _MEMBRANE] = k_mem
    stiffness[:, _BENDING[:, None], _BENDING] = k_bend

    # mass: linear consistent translations, DKT rotary inertia, small drilling inertia
    mass, _ = consistent_mass(area, rho * t, rho * t**3 / 12.0, t_rot)

    if not local:
        stiffness = _to_global(stiffness, rotation)
        mass = _to_global(mass, rotation)
    stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))
    mass = 0.5 * (mass + mass.transpose(0, 2, 1))
    return stiffness, mass


def _weighted_gram(b, d, weight):
    """Σ_q weight_q B_qᵀ D B_q, (n_el, k, k), for B (n_el, n_q, r, k), D (n_el, r, r),
    weight (n_el, n_q); batched matmuls instead of a many-operand einsum."""
    n_el, n_q, r, k = b.shape
    db = (d[:, None] @ b) * weight[:, :, None, None]
    return b.reshape(n_el, n_q * r, k).transpose(0, 2, 1) @ db.reshape(n_el, n_q * r, k)


def _to_global(matrix, rotation):
    """Tᵀ A T for T = blockdiag(R × 6); matrix (n_el, 18, 18), rotation (n_el, 3, 3).

    Done block-wise (3×3 rotations on each 3-DOF block): A·T as (n_el, 108, 3) @ R, then
    Rᵀ from the left on each of the six 3-row blocks.
    """
    n_el = matrix.shape[0]
    right = (matrix.reshape(n_el, 108, 3) @ rotation).reshape(n_el, 6, 3, 18)
    return (rotation.transpose(0, 2, 1)[:, None] @ right).reshape(n_el, 18, 18)


def shell_matrices(points, triangles, thickness, young, poisson, density,
                   drilling_penalty=DRILLING_PENALTY):
    """Global shell stiffness K [N/m, N, N·m] and consistent mass M [kg, kg·m²], CSR (6n, 6n).

    points (n, 3) [m]; triangles (n_el, 3) int; thickness [m], young [Pa], poisson [-],
    density [kg/m³] as scalars or (n_el,) arrays. DOF = 6·node + [ux, uy, uz, rx, ry, rz].
    Strain energy ½ uᵀ K u, kinetic energy ½ u̇ᵀ M u̇. Nodes not used by any triangle get
    empty rows (fix them or drop them before solving).
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be shaped (n, 3), got {points.shape}")
    triangles = np.asarray(triangles, dtype=np.int64)
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError(f"triangles must be shaped (n_el, 3), got {triangles.shape}")
    n_el = triangles.shape[0]
    properties = [_as_element_array(value, n_el, name) for value, name in
                  [(thickness, "thickness"), (young, "young"), (poisson, "poisson"),
                   (density, "density")]]
    # element blocks (not elements) are looped: K + iM of each block into one array
    combined = np.empty((n_el, 18, 18), dtype=complex)
    for start in range(0, n_el, BLOCK_SIZE):
        block = slice(start, start + BLOCK_SIZE)
        k_e, m_e = shell_element_matrices(points, triangles[block],
                                          *[p[block] for p in properties],
                                          drilling_penalty=drilling_penalty)
        combined[block].real = k_e
        combined[block].imag = m_e
    return assemble_pair(combined, None, element_dofs(triangles), 6 * points.shape[0])
