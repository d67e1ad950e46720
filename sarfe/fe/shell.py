"""Flat facet shell triangle: drilling membrane + DKT plate bending, 6 DOF per node.

Each triangle is flat in its own local frame (e1 along edge 1→2, e3 = unit normal
(x2−x1)×(x3−x1), e2 = e3×e1); its 18×18 local matrices are rotated to the global
frame, K_e = Tᵀ K_local T with T = blockdiag(R, R, R, R, R, R), R = [e1; e2; e3].
Local DOF order per node: [u, v, w, θx, θy, θz] (θz = drilling rotation).

Membrane (u, v, θz): :mod:`sarfe.fe.membrane`, C = t D_m, D_m = E/(1−ν²)[[1,ν,0],[ν,1,0],
[0,0,(1−ν)/2]] — the Allman (1984) triangle with the drilling penalty K_d = α G t A g gᵀ
(``membrane="allman"``, ``DEFAULT_MEMBRANE``), Felippa's optimal ANDES triangle
(``"andes"``) or the constant-strain triangle with a weak penalty (``"cst"``).

Bending (w, θx, θy): DKT (Batoz, Bathe & Ho 1980), :mod:`sarfe.fe.plate_bending`. With
rotations β = (βx, βy) = (θy, −θx) (so Kirchhoff gives β = −∇w), β is quadratic over the
triangle; corner values β_i from the nodal rotations, midside values from the Kirchhoff
constraint along each edge. Curvature κ = [βx,x, βy,y, βx,y + βy,x], K_b = ∫ κᵀ D_b κ dA,
D_b = E t³/(12(1−ν²))[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]]; the integrand is quadratic: the
three-midside-point rule is exact. (Sections with transverse shear use the DKMT extension,
:mod:`sarfe.fe.shell_section`.)

Mass: consistent (``mass="consistent"``, ``DEFAULT_MASS``; documented choice below) or its HRZ
lumping (``"lumped"``, :func:`sarfe.fe.assembly.lumped_mass`: corners m''A/3, rotary block kept).
Consistent mass:
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

from dataclasses import dataclass

import numpy as np

from sarfe.fe.assembly import assemble_pair, element_dofs, lumped_mass
from sarfe.fe.membrane import (DRILLING_PENALTY, EDGES, MEMBRANES,
                               allman_field, andes_basic_strain, andes_stiffness,
                               cst_stiffness, cst_strain, drilling_vector, p2_gradients)
from sarfe.fe.plate_bending import dkt_rotation_field

__all__ = [
    "shell_matrices",
    "shell_element_matrices",
    "local_frames",
    "element_kinematics",
    "ElementGeometry",
    "membrane_stiffness",
    "consistent_mass",
    "weighted_gram",
    "to_global",
    "DRILLING_PENALTY",
    "DEFAULT_MEMBRANE",
    "DEFAULT_MASS",
    "MEMBRANE_DOFS",
    "BENDING_DOFS",
    "DEGREE4_RULE",
]

#: the triangle membrane of generated meshes (`sarfe.fe.shell.shell_matrices`); decks use the
#: commercial solver's elements (`sarfe.fe.deck_shells`). On triangle meshes of a clamped
#: cylindrical panel the optimal triangle was not more accurate than Allman + penalty (its
#: true drilling stiffness ties the facets of a curved mesh more tightly: 30 × 22 mesh
#: +0.71 % vs +0.48 % on mode 1 against the 160 × 120 converged shell), so this stays "allman";
#: "andes" is the switch (exact in-plane bending of rectangular pairs, no penalty).
DEFAULT_MEMBRANE = "allman"

#: element mass of generated meshes (:func:`shell_matrices`): 'consistent' | 'lumped'. Lumped
#: was measured more accurate (Leissa clamped plate at 20 mm: −0.42 … −1.08 % vs +0.45 … +2.98 %;
#: clamped cylindrical panel 30 × 22: −0.01 … −0.40 % vs +0.37 … +1.17 % of the converged
#: shell); it stays "consistent" until the lead lands it (it moves the shipped cases' numbers).
DEFAULT_MASS = "consistent"

#: elements per vectorized block (keeps the (block, 18, 18) work arrays cache-sized)
BLOCK_SIZE = 4096

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


#: six-point degree-4 rule (area coordinates (6, 3), weights (6,) summing to 1)
DEGREE4_RULE = _dunavant4()


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


def _p2_values(area_coords):
    """Values of the six P2 shape functions at the points, (n_q, 6)."""
    corner = area_coords * (2.0 * area_coords - 1.0)
    mid = 4.0 * area_coords[:, EDGES[:, 0]] * area_coords[:, EDGES[:, 1]]
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
    d = local_xy[:, EDGES[:, 1]] - local_xy[:, EDGES[:, 0]]
    length = np.linalg.norm(d, axis=2)
    tangent = d / length[..., None]
    normal = np.stack([tangent[..., 1], -tangent[..., 0]], axis=2)
    return length, tangent, normal


def _plane_stress(young, poisson):
    """(n_el, 3, 3) plane-stress matrix E/(1−ν²)[[1,ν,0],[ν,1,0],[0,0,(1−ν)/2]]."""
    d = np.zeros((young.shape[0], 3, 3))
    factor = young / (1.0 - poisson**2)
    d[:, 0, 0] = d[:, 1, 1] = factor
    d[:, 0, 1] = d[:, 1, 0] = factor * poisson
    d[:, 2, 2] = factor * (1.0 - poisson) / 2.0
    return d


#: local 18-DOF indices of the membrane (u, v, θz) and bending (w, θx, θy) parts
MEMBRANE_DOFS = (6 * np.arange(3)[:, None] + np.array([0, 1, 5])).ravel()
BENDING_DOFS = (6 * np.arange(3)[:, None] + np.array([2, 3, 4])).ravel()


@dataclass(frozen=True)
class ElementGeometry:
    """What every facet-shell triangle needs of its geometry (this element and
    :mod:`sarfe.fe.shell_section`), all in the element frame of :func:`local_frames`.

    rotation (n_el, 3, 3) global → element; local_xy (n_el, 3, 2) corners [m]; area (n_el,) [m²];
    grad_l (n_el, 3, 2) area-coordinate gradients ∇L [1/m]; length (n_el, 3) [m], tangent and
    outward normal (n_el, 3, 2) of the edges (i → i+1); strain (n_el, 3, 3, 12) the P2 strain
    operator at the three midside points; w_area (n_el, 3) the rule's weights × area [m²].
    """

    rotation: np.ndarray
    local_xy: np.ndarray
    area: np.ndarray
    grad_l: np.ndarray
    length: np.ndarray
    tangent: np.ndarray
    normal: np.ndarray
    strain: np.ndarray
    w_area: np.ndarray


def element_kinematics(points, triangles) -> ElementGeometry:
    """The :class:`ElementGeometry` of triangles (n_el, 3) on points (n, 3) [m]."""
    rotation, xy, area = local_frames(points, triangles)
    # ∇L_i = (y_j − y_k, x_k − x_j) / (2A), (i, j, k) cyclic
    nxt, prv = [1, 2, 0], [2, 0, 1]
    grad_l = np.stack(
        [xy[:, nxt, 1] - xy[:, prv, 1], xy[:, prv, 0] - xy[:, nxt, 0]], axis=2
    ) / (2.0 * area)[:, None, None]
    length, tangent, normal = _edge_geometry(xy)
    points_q, weights_q = _MIDSIDE_RULE
    strain = _strain_operator(p2_gradients(points_q, grad_l))  # (n_el, 3, 3, 12)
    w_area = weights_q[None, :] * area[:, None]  # (n_el, n_q)
    return ElementGeometry(rotation, xy, area, grad_l, length, tangent, normal, strain, w_area)


def membrane_stiffness(geometry: ElementGeometry, c, membrane=DEFAULT_MEMBRANE,
                       drilling_penalty=DRILLING_PENALTY):
    """Membrane stiffness (n_el, 9, 9) on [u_i, v_i, θz_i] and its strain operator at the
    rule's points (n_el, 3, 3, 9) (for membrane–bending coupling), :mod:`sarfe.fe.membrane`.

    c (n_el, 3, 3) membrane stiffness [N/m]; membrane 'andes' (the strain operator is its
    constant basic strain) or 'allman' (Allman field + penalty α C₃₃ A g gᵀ).
    """
    if membrane not in MEMBRANES:
        raise ValueError(f"membrane must be one of {MEMBRANES}, got {membrane!r}")
    if membrane == "cst":
        k_mem = cst_stiffness(geometry.grad_l, geometry.area, c, drilling_penalty)
        strain = cst_strain(geometry.grad_l)
        return k_mem, np.broadcast_to(strain[:, None], strain.shape[:1] + (3,) + strain.shape[1:])
    if membrane == "andes":
        k_mem = andes_stiffness(geometry.local_xy, geometry.area, c)
        basic = andes_basic_strain(geometry.local_xy, geometry.area)
        return k_mem, np.broadcast_to(basic[:, None], basic.shape[:1] + (3,) + basic.shape[1:])
    t_mem = allman_field(geometry.length, geometry.normal)
    b_mem = geometry.strain @ t_mem[:, None]  # (n_el, n_q, 3, 9)
    k_mem = weighted_gram(b_mem, c, geometry.w_area)
    g = drilling_vector(geometry.grad_l, t_mem)
    k_mem += (drilling_penalty * c[:, 2, 2] * geometry.area)[:, None, None] * (
        g[:, :, None] * g[:, None, :])
    return k_mem, b_mem


def consistent_mass(area, mass_per_area, rotary_inertia_per_area, t_rot, drilling_inertia=True):
    """Element mass (n_el, 18, 18) in the element frame (module docstring): translations
    m'' A/12 (1 + δ_ij), drilling I'' A/12 (1 + δ_ij) (left out with ``drilling_inertia=False``:
    a drilling DOF held only by a penalty gets no mass), rotary inertia I'' ∫ β·β dA on the
    bending triangle's rotation field t_rot (degree-4 rule); m'' [kg/m²], I'' [kg] per element.
    Also returns the rotation field β at the rule's points (n_el, n_q, 2, 9)."""
    n_el = area.shape[0]
    linear = (np.ones((3, 3)) + np.eye(3)) / 12.0
    mass = np.zeros((n_el, 3, 6, 3, 6))
    m_trans = (mass_per_area * area)[:, None, None] * linear
    for c in range(3):
        mass[:, :, c, :, c] = m_trans
    if drilling_inertia:
        mass[:, :, 5, :, 5] = (rotary_inertia_per_area * area)[:, None, None] * linear
    mass = mass.reshape(n_el, 18, 18)
    points_m, weights_m = DEGREE4_RULE
    values = _p2_values(points_m)  # (n_q, 6)
    interp = np.zeros((len(weights_m), 2, 6, 2))
    interp[:, 0, :, 0] = values
    interp[:, 1, :, 1] = values
    beta = np.einsum("qcn,enj->eqcj", interp.reshape(-1, 2, 12), t_rot)  # (n_el, n_q, 2, 9)
    m_rot = weighted_gram(beta, np.eye(2)[None], np.broadcast_to(
        weights_m * (rotary_inertia_per_area * area)[:, None], beta.shape[:2]))
    mass[:, BENDING_DOFS[:, None], BENDING_DOFS] += m_rot
    return mass, beta


def shell_element_matrices(points, triangles, thickness, young, poisson, density,
                           drilling_penalty=DRILLING_PENALTY, local=False,
                           membrane=DEFAULT_MEMBRANE):
    """Element stiffness and mass matrices, each (n_el, 18, 18).

    Parameters: points (n, 3) [m], triangles (n_el, 3) int, thickness [m], young [Pa],
    poisson [-], density [kg/m³] (scalars or (n_el,) arrays); membrane 'andes' | 'allman',
    drilling_penalty α [-] (Allman only). Element DOFs: 6 per corner node, [ux, uy, uz, rx,
    ry, rz], node-major; global frame unless ``local=True`` (the frame of :func:`local_frames`).
    """
    triangles = np.asarray(triangles)
    n_el = triangles.shape[0]
    t = _as_element_array(thickness, n_el, "thickness")
    e = _as_element_array(young, n_el, "young")
    nu = _as_element_array(poisson, n_el, "poisson")
    rho = _as_element_array(density, n_el, "density")

    geometry = element_kinematics(points, triangles)
    d_plane = _plane_stress(e, nu)
    k_mem, _ = membrane_stiffness(geometry, d_plane * t[:, None, None], membrane,
                                  drilling_penalty)

    # bending: DKT
    t_rot = dkt_rotation_field(geometry.length, geometry.tangent, geometry.normal)
    b_bend = geometry.strain @ t_rot[:, None]
    d_bend = d_plane * (t**3 / 12.0)[:, None, None]
    k_bend = weighted_gram(b_bend, d_bend, geometry.w_area)

    stiffness = np.zeros((n_el, 18, 18))
    stiffness[:, MEMBRANE_DOFS[:, None], MEMBRANE_DOFS] = k_mem
    stiffness[:, BENDING_DOFS[:, None], BENDING_DOFS] = k_bend

    # mass: linear consistent translations, DKT rotary inertia, small drilling inertia
    mass, _ = consistent_mass(geometry.area, rho * t, rho * t**3 / 12.0, t_rot)

    if not local:
        stiffness = to_global(stiffness, geometry.rotation)
        mass = to_global(mass, geometry.rotation)
    stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))
    mass = 0.5 * (mass + mass.transpose(0, 2, 1))
    return stiffness, mass


def weighted_gram(b, d, weight):
    """Σ_q weight_q B_qᵀ D B_q, (n_el, k, k), for B (n_el, n_q, r, k), D (n_el, r, r),
    weight (n_el, n_q); batched matmuls instead of a many-operand einsum."""
    n_el, n_q, r, k = b.shape
    db = (d[:, None] @ b) * weight[:, :, None, None]
    return b.reshape(n_el, n_q * r, k).transpose(0, 2, 1) @ db.reshape(n_el, n_q * r, k)


def to_global(matrix, rotation):
    """Tᵀ A T for T = blockdiag(R × 6); matrix (n_el, 18, 18), rotation (n_el, 3, 3).

    Done block-wise (3×3 rotations on each 3-DOF block): A·T as (n_el, 108, 3) @ R, then
    Rᵀ from the left on each of the six 3-row blocks.
    """
    n_el = matrix.shape[0]
    right = (matrix.reshape(n_el, 108, 3) @ rotation).reshape(n_el, 6, 3, 18)
    return (rotation.transpose(0, 2, 1)[:, None] @ right).reshape(n_el, 18, 18)


def shell_matrices(points, triangles, thickness, young, poisson, density,
                   drilling_penalty=DRILLING_PENALTY, membrane=None, mass=None):
    """Global shell stiffness K [N/m, N, N·m] and mass M [kg, kg·m²], CSR (6n, 6n).

    points (n, 3) [m]; triangles (n_el, 3) int; thickness [m], young [Pa], poisson [-],
    density [kg/m³] as scalars or (n_el,) arrays. DOF = 6·node + [ux, uy, uz, rx, ry, rz].
    Strain energy ½ uᵀ K u, kinetic energy ½ u̇ᵀ M u̇. Nodes not used by any triangle get
    empty rows (fix them or drop them before solving). membrane: 'allman' | 'andes' | 'cst'
    (:mod:`sarfe.fe.membrane`), drilling_penalty α for 'allman' and 'cst'; mass: 'consistent'
    (module docstring) or 'lumped' (:func:`sarfe.fe.assembly.lumped_mass`: corners m''A/3,
    rotary inertia kept). None: this module's switches ``DEFAULT_MEMBRANE`` and
    ``DEFAULT_MASS``, read at the call.
    """
    membrane = DEFAULT_MEMBRANE if membrane is None else membrane
    mass = DEFAULT_MASS if mass is None else mass
    if membrane not in MEMBRANES:
        raise ValueError(f"membrane must be one of {MEMBRANES}, got {membrane!r}")
    if mass not in ("consistent", "lumped"):
        raise ValueError(f"mass must be 'consistent' or 'lumped', got {mass!r}")
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
                                          drilling_penalty=drilling_penalty,
                                          membrane=membrane)
        combined[block].real = k_e
        combined[block].imag = (lumped_mass(m_e, element_dofs(triangles[block])) if mass == "lumped"
                                else m_e)
    return assemble_pair(combined, None, element_dofs(triangles), 6 * points.shape[0])
