r"""Points coupled to a facet shell by its shape functions (a distributing, RBE3-like interpolation):
the displacement of a point at fixed coordinates — on the mid-surface or on a shell face — as a
sparse weight matrix W on the global DOFs, u_p = W u, so that a contact is mesh independent:

    [w, q₁, q₂]_p = frame_p · (W_a − W_b)_p u          (:func:`contact_operator`),

and a force f at the point loads the shell with Wᵀ f (the same work, f · u_p).

DOFs: global, node-major, 6 per node, [ux, uy, uz, rx, ry, rz] (:mod:`sarfe.fe.shell`).

A point p lies in the flat facet (x₁, x₂, x₃) with barycentric coordinates L = (L₁, L₂, L₃)
(:func:`sarfe.mesh.contact_geometry.project_to_surface`); n is the facet's unit normal by winding,
n = (x₂ − x₁) × (x₃ − x₁)/|…|, P_t = I − n nᵀ, and z [m] the signed distance of the point from the
mid-surface along the shell normal (±t/2 on a face, plus a shell offset: :func:`face_offsets`).

Mid-surface, ``bending="cubic"`` (default): the in-plane part is linear, P_t Σ L_i u_i; the
normal displacement is the reduced Hermite cubic on the nodal deflections w_i = n·u_i and the
Kirchhoff slopes ∇w_i = n × θ_i (Zienkiewicz's triangle, exact for quadratic w, the cubic the
DKT bending element has along its edges):

    w(L) = Σ_i c_i w_i + Σ_i Σ_{j≠i} d_ij s_ij,   s_ij = ∇w_i·(x_j − x_i) = θ_i·((x_j − x_i) × n),
    c_i = 3L_i² − 2L_i³ + 2L₁L₂L₃,   d_ij = L_i² L_j + ½ L₁L₂L₃.

Face (z ≠ 0): the shell's normal turns by θ, so the point moves by θ_p × (z n_s), with θ_p the
rotation at the point — in-plane part ∇w × n from the cubic, drilling part n nᵀ Σ L_i θ_i — and
n_s the shell normal (the facet normal n by default; the smooth surface's normal for a point at
a node of a curved shell). For n_s = n that is the Kirchhoff face displacement −z ∇w(p)
(∇ = Σ_m ∂/∂L_m ∇L_m, ∇L_i = n × (x_k − x_j)/(2A), (i, j, k) cyclic):

    u_p = P_t Σ_i L_i u_i + n w(p) − z ∇w(p).

A tangential force F_t there carries the moment z F_t into bending, which a force at the
mid-surface does not. ``bending="linear"``: u_p = Σ_i L_i u_i + θ_p × (z n_s), θ_p = Σ_i L_i θ_i
(exact only at the nodes: −3 % in the point compliance of a 5 mm plate mesh, the cubic +0.6 %).
Both move a rigid body exactly: u = a + ω × x gives θ_p = ω, u_p = a + ω × (x_p + z n_s); at a
node (L = e_i) both give u_i + θ_i × z n_s, whichever of its triangles holds the point.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["point_weights", "point_rotation_weights", "face_offsets", "contact_operator"]

_CYCLIC = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])   # (i, j, k) cyclic
_OTHERS = np.array([[1, 2], [2, 0], [0, 1]])            # j ≠ i for each i


def _cross_matrix(v):
    """[v]× (…, 3, 3) with [v]× a = v × a."""
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def _cubic_terms(bary):
    """Values and L-derivatives of the reduced Hermite cubic's shape functions.

    Returns c (m, 3), dc/dL (m, 3 i, 3 l), d (m, 3 i, 2 j) for j = _OTHERS[i], dd/dL (m, 3, 2, 3).
    """
    m = len(bary)
    prod = np.prod(bary, axis=1)                                   # L1 L2 L3
    dprod = np.stack([bary[:, 1] * bary[:, 2], bary[:, 2] * bary[:, 0],
                      bary[:, 0] * bary[:, 1]], axis=1)            # ∂(L1L2L3)/∂L_l
    c = 3 * bary**2 - 2 * bary**3 + 2 * prod[:, None]
    dc = 2 * np.repeat(dprod[:, None, :], 3, axis=1)
    dc[:, np.arange(3), np.arange(3)] += 6 * bary - 6 * bary**2
    li = bary[:, :, None]                                          # L_i
    lj = bary[:, _OTHERS]                                          # L_j, (m, 3, 2)
    d = li**2 * lj + 0.5 * prod[:, None, None]
    dd = np.repeat(0.5 * dprod[:, None, None, :], 3, axis=1).repeat(2, axis=2)
    i_idx = np.arange(3)[:, None].repeat(2, axis=1)                # (3, 2)
    rows = np.arange(m)[:, None, None]
    dd[rows, i_idx, np.arange(2), i_idx] += 2 * li * lj            # ∂/∂L_i: 2 L_i L_j
    dd[rows, i_idx, np.arange(2), _OTHERS] += li**2                # ∂/∂L_j: L_i²
    return c, dc, d, dd


def _facet_geometry(points, triangles, element):
    """Corners (m, 3, 3), unit normal n (m, 3) and area gradients ∇L_i (m, 3, 3) [1/m]."""
    x = np.asarray(points, dtype=float)[np.asarray(triangles, dtype=np.int64)[element]]
    area_vector = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])   # 2A n
    twice_area = np.linalg.norm(area_vector, axis=1)
    if np.any(twice_area <= 0):
        raise ValueError("point_weights: a point lies in a zero-area triangle")
    n = area_vector / twice_area[:, None]
    edge = x[:, _CYCLIC[:, 2]] - x[:, _CYCLIC[:, 1]]               # x_k − x_j for each i
    grad = np.cross(n[:, None, :], edge) / twice_area[:, None, None]
    return x, n, grad


def _point_blocks(points, triangles, element, barycentric, bending):
    """Blocks (m, 3 nodes, 3 rows, 6 DOFs) of the mid-surface translation u_p and of the
    rotation θ_p at each point, and the facet normals n (m, 3).

    cubic: u_p = Σ_i [L_i P_t + c_i n nᵀ] u_i + n g_iᵀ θ_i  (g_i = Σ_j d_ij e_ij),
           θ_p = (∇w × n) + n nᵀ Σ_i L_i θ_i,  ∇w = Σ_i ∇c_i nᵀ u_i + G_i θ_i  (G_i = Σ_j ∇d_ij e_ijᵀ);
    linear: u_p = Σ_i L_i u_i,  θ_p = Σ_i L_i θ_i.
    """
    element = np.asarray(element, dtype=np.int64).reshape(-1)
    bary = np.asarray(barycentric, dtype=float).reshape(-1, 3)
    x, n, grad = _facet_geometry(points, triangles, element)
    m = len(element)
    nn = n[:, :, None] * n[:, None, :]                             # n nᵀ
    eye = np.broadcast_to(np.eye(3), (m, 3, 3, 3))
    zero = np.zeros((m, 3, 3, 3))
    if bending == "linear":
        lin = bary[:, :, None, None] * eye
        return np.concatenate([lin, zero], 3), np.concatenate([zero, lin], 3), n
    if bending != "cubic":
        raise ValueError(f"bending must be 'cubic' or 'linear', got {bending!r}")
    c, dc, d, dd = _cubic_terms(bary)
    arm = np.cross(x[:, _OTHERS] - x[:, :, None], n[:, None, None, :])  # e_ij (m, 3, 2, 3)
    grad_c = np.einsum("mil,mla->mia", dc, grad)                  # ∇c_i (m, 3, 3)
    grad_d = np.einsum("mijl,mla->mija", dd, grad)                # ∇d_ij (m, 3, 2, 3)
    g = np.einsum("mij,mijb->mib", d, arm)                        # Σ_j d_ij e_ij
    big_g = np.einsum("mija,mijb->miab", grad_d, arm)             # Σ_j ∇d_ij ⊗ e_ij
    p_t = np.eye(3) - nn
    translation = np.concatenate(
        [bary[:, :, None, None] * p_t[:, None] + c[:, :, None, None] * nn[:, None],
         n[:, None, :, None] * g[:, :, None, :]], 3)
    slope = np.concatenate([grad_c[..., None] * n[:, None, None, :], big_g], 3)   # ∇w
    turn = -np.einsum("mab,mibk->miak", _cross_matrix(n), slope)  # ∇w × n = −n × ∇w
    rotation = turn + np.concatenate([zero, bary[:, :, None, None] * nn[:, None]], 3)
    return translation, rotation, n


def _sparse_rows(blocks, node_of_point, n_nodes):
    """CSR (3m, 6 n_nodes) from blocks (m, 3 nodes, 3 rows, 6) and the points' nodes (m, 3)."""
    m = len(blocks)
    rows = np.broadcast_to(3 * np.arange(m)[:, None, None, None]
                           + np.arange(3)[None, None, :, None], blocks.shape)
    cols = np.broadcast_to(6 * node_of_point[:, :, None, None] + np.arange(6), blocks.shape)
    return sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(3 * m, 6 * n_nodes))


def point_weights(points, triangles, element, barycentric, offset_m=0.0, offset_direction=None,
                  bending="cubic", n_nodes=None):
    """Sparse W (3m, 6·n_nodes) with u_p = W u: translations [m] of m points in the shell,

        u_p = u_mid(p) + θ_p × (z n_s)       (module docstring; = u_mid − z ∇w for n_s = n).

    points (n_nodes, 3) [m], triangles (n_tri, 3) int; element (m,) the triangle of each point and
    barycentric (m, 3) its coordinates L there (a projection: project_to_surface); offset_m scalar
    or (m,) [m] the signed distance z of the point from the mid-surface (0: mid-surface; a face:
    :func:`face_offsets`); offset_direction (3,) or (m, 3) the unit shell normal n_s it is taken
    along, by default the facet normal n by winding (give the smooth surface's normal, e.g.
    sarfe.mesh.contact_geometry.patch_normals, for a point at a node of a curved shell, where the
    facets disagree); bending "cubic" or "linear". Rows 3p + [x, y, z] (global axes); each point
    touches its 3 nodes' 18 DOFs.
    """
    element = np.asarray(element, dtype=np.int64).reshape(-1)
    tri = np.asarray(triangles, dtype=np.int64)
    translation, rotation, n = _point_blocks(points, tri, element, barycentric, bending)
    z = np.broadcast_to(np.asarray(offset_m, dtype=float), (len(element),))
    direction = n if offset_direction is None else np.broadcast_to(
        np.asarray(offset_direction, dtype=float), n.shape)
    arm = _cross_matrix(z[:, None] * direction)                   # θ × (z n_s) = −[z n_s]× θ
    blocks = translation - np.einsum("mab,mibk->miak", arm, rotation)
    return _sparse_rows(blocks, tri[element], len(points) if n_nodes is None else int(n_nodes))


def point_rotation_weights(points, triangles, element, barycentric, bending="cubic",
                           n_nodes=None):
    """Sparse R (3m, 6·n_nodes) with θ_p = R u [rad]: the rotation at m points in the shell
    (cubic: in-plane part ∇w × n of the Hermite cubic, drilling part n nᵀ Σ L_i θ_i; linear:
    Σ L_i θ_i). Rᵀ m loads the shell with a point moment m [N m]. Arguments as
    :func:`point_weights`."""
    element = np.asarray(element, dtype=np.int64).reshape(-1)
    tri = np.asarray(triangles, dtype=np.int64)
    _, rotation, _ = _point_blocks(points, tri, element, barycentric, bending)
    return _sparse_rows(rotation, tri[element], len(points) if n_nodes is None else int(n_nodes))


def face_offsets(facet_normal, toward, thickness_m, offset_m=0.0) -> np.ndarray:
    """Signed distance z [m] of the face that looks `toward` a partner, along the facet normal,
    (m,): z = sign(n · toward) t/2 + o, with t [m] the thickness and o [m] the mid-surface's
    offset from the mesh surface along n (a shell offset such as ZOFFS; 0 without).
    facet_normal (m, 3) by winding; toward (3,) or (m, 3), e.g. the contact normal (side a) or
    its opposite (side b)."""
    n = np.asarray(facet_normal, dtype=float)
    side = np.where(np.einsum("...i,...i->...", n, np.broadcast_to(toward, n.shape)) < 0, -1.0, 1.0)
    return side * 0.5 * np.asarray(thickness_m, dtype=float) + np.asarray(offset_m, dtype=float)


def contact_operator(frames, weights_a, weights_b=None):
    """Contact rows G (3m, n_dof), [w, q₁, q₂]_p = G_p u = frame_p (W_a − W_b)_p u.

    frames (m, 3, 3) rows [n, t₁, t₂] (normal from a towards b); weights_a, weights_b sparse
    (3m, n_dof) from :func:`point_weights` (weights_b None: side b is the ground). Row 3p is the
    normal approach w of point p, rows 3p + 1, 3p + 2 its tangential slips [m per m of u].
    """
    frames = np.asarray(frames, dtype=float).reshape(-1, 3, 3)
    m = len(frames)
    rows = np.broadcast_to(3 * np.arange(m)[:, None, None] + np.arange(3)[:, None], (m, 3, 3))
    cols = np.broadcast_to(3 * np.arange(m)[:, None, None] + np.arange(3), (m, 3, 3))
    rotate = sp.csr_matrix((frames.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * m, 3 * m))
    relative = weights_a if weights_b is None else weights_a - weights_b
    return sp.csr_matrix(rotate @ relative)
