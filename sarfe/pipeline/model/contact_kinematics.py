r"""Contact kinematics of an FE model from its geometry: where each contact point lies on each
side's shell, the face the force acts on, the contact frame and the rows of the gap map.

    ShellSurface(points, triangles, thickness, offset)      the shells a contact touches
    side_triangles(surface, nodes, exclude)                 a side's part: its connected bodies
    node_locations(triangles, nodes, allowed) -> (element, L)   a node as a point (L = e_k)
    surface_locations(surface, x, allowed) -> (element, L, x_s, distance)  projection, snapped
    offset_normals(surface, x, element, allowed, radius)    shell normal n_s at each point
    body_side(surface, x, element, allowed, radius)         where the side's body lies from x
    side_motion(surface, element, L, toward, n_s) -> (W, z)    u_face = W u, z [m]
    contact_rows(frames, W_a, W_b) -> G (3 n_p, 6 n_nodes)  rows [w, q₁, q₂] per point

A contact point p of side a lies at x_a in the triangle ``element`` with barycentric L
(:func:`sarfe.mesh.contact_geometry.project_to_surface`; a node: L = e_k); its partner x_b is the
closest point of side b's surface. The force acts on the face of each shell that looks at the
partner, z = ±t/2 + o from the mid-surface along the shell normal n_s (:func:`sarfe.fe.coupling.
face_offsets`), so u_face = u_mid(p) + θ_p × (z n_s) = W u (:func:`sarfe.fe.coupling.point_weights`:
shape functions, a tangential force carries its moment z F into bending) and the rows of the gap
map are [w, q₁, q₂]_p = frame_p (W_a − W_b)_p u. The surface gap is n·(x_b + z_b n_sb − x_a −
z_a n_sa): mid-surface distance less the half thicknesses (and offsets) of the facing shells.

Barycentric coordinates below :data:`SNAP` are set to 0 (the point moves by at most 0.1 % of its
element's size onto the edge or node it practically lies on), so a spot the generator put at a
node couples to that node's 6 DOFs, not to 18, and the Craig–Bampton boundary stays small.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import chain

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from sarfe.fe.coupling import contact_operator, face_offsets, point_weights
from sarfe.mesh.contact_geometry import patch_normals, project_to_surface
from sarfe.mesh.geometry import connected_components, facet_normals

#: barycentric coordinates below this are snapped to 0 (module docstring)
SNAP = 1e-3
#: weights below this fraction of a row's largest are dropped (round-off of the cubic at a node)
DROP = 1e-10


@dataclass(frozen=True)
class ShellSurface:
    """The shells of a model, as a contact sees them: points (n, 3) [m], triangles (n_t, 3),
    thickness (n_t,) [m] and the mid-surface's offset from the mesh surface along each facet's
    normal (n_t,) [m] (a Nastran ZOFFS; 0 for a generated mesh)."""

    points: np.ndarray
    triangles: np.ndarray
    thickness: np.ndarray
    offset: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.points)


def side_triangles(surface: ShellSurface, nodes, exclude=None) -> np.ndarray:
    """Triangle indices of the bodies (shell components joined through shared nodes) that hold
    any of `nodes`; triangles touching any of `exclude` (the other side's nodes, where both sides
    belong to one body) left out. Empty when no node lies on a shell."""
    t = surface.triangles
    _, label = connected_components(surface.n_nodes, t)
    on_shell = np.zeros(surface.n_nodes, bool)
    on_shell[t.ravel()] = True
    nodes = np.asarray(nodes, dtype=np.int64)
    bodies = np.unique(label[nodes[on_shell[nodes]]])
    keep = np.isin(label[t[:, 0]], bodies)
    if exclude is not None and len(exclude):
        keep &= ~np.isin(t, np.asarray(exclude, dtype=np.int64)).any(axis=1)
    return np.flatnonzero(keep)


def node_locations(triangles, nodes, allowed):
    """Each node as a point of the shell: (element (m,) a triangle of `allowed` that holds it, or
    −1 off the shells; barycentric (m, 3) = e_k, k the node's corner in that triangle)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    allowed = np.asarray(allowed, dtype=np.int64)
    owner = np.full(int(max(triangles.max(initial=0), nodes.max(initial=0))) + 1, -1)
    corner = np.zeros_like(owner)
    t = triangles[allowed]
    owner[t.ravel()] = np.repeat(allowed, 3)
    corner[t.ravel()] = np.tile(np.arange(3), len(allowed))
    element = owner[nodes]
    bary = np.zeros((len(nodes), 3))
    bary[np.arange(len(nodes)), corner[nodes]] = 1.0
    bary[element < 0] = 0.0
    return element, bary


def snap(barycentric) -> np.ndarray:
    """Barycentric coordinates (m, 3) with entries below :data:`SNAP` set to 0, renormalized."""
    bary = np.where(np.asarray(barycentric) < SNAP, 0.0, barycentric)
    return bary / bary.sum(axis=1, keepdims=True)


def surface_locations(surface: ShellSurface, x, allowed):
    """Closest points of x (m, 3) on the triangles `allowed`: (element (m,) global triangle
    index, snapped barycentric (m, 3), the point x_s (m, 3) [m], distance |x − x_s| (m,) [m])."""
    allowed = np.asarray(allowed, dtype=np.int64)
    projection = project_to_surface(x, surface.points, surface.triangles[allowed])
    element = allowed[projection.element]
    bary = snap(projection.barycentric)
    point = np.einsum("mv,mvi->mi", bary, surface.points[surface.triangles[element]])
    return element, bary, point, projection.distance


def point_coordinates(surface: ShellSurface, element, bary, fallback) -> np.ndarray:
    """x = Σ L_i x_i (m, 3) [m] of located points; `fallback` (m, 3) where element < 0."""
    on = element >= 0
    x = np.array(fallback, dtype=float, copy=True)
    x[on] = np.einsum("mv,mvi->mi", bary[on], surface.points[surface.triangles[element[on]]])
    return x


def offset_normals(surface: ShellSurface, x, element, allowed, radius_m) -> np.ndarray:
    """Shell normal n_s (m, 3) at each located point: the patch normal of the side's surface
    (:func:`sarfe.mesh.contact_geometry.patch_normals`, radius `radius_m` [m]) turned to agree
    with its element's facet normal (by winding); 0 rows off the shells."""
    out = np.zeros((len(element), 3))
    on = element >= 0
    if on.any():
        facet = facet_normals(surface.points, surface.triangles[element[on]])
        out[on] = patch_normals(x[on], surface.points, surface.triangles[allowed], radius_m,
                                reference=facet)
    return out


def body_side(surface: ShellSurface, x, allowed, radius_m) -> np.ndarray:
    """(m, 3) [m]: mean position, relative to x, of the side's nodes within ρ of each point
    (ρ = max(radius_m, 2 × the longest edge of the side's triangle nearest to x)) — where the
    side's body lies, to orient a normal between coincident points; 0 rows where none is near."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    tri = surface.triangles[np.asarray(allowed, dtype=np.int64)]
    if len(tri) == 0:
        return np.zeros((len(x), 3))
    p = surface.points
    nodes = np.unique(tri)
    edges = np.linalg.norm(p[tri] - p[tri[:, [1, 2, 0]]], axis=2).max(axis=1)
    _, near = cKDTree(p[tri].mean(axis=1)).query(x)
    found = cKDTree(p[nodes]).query_ball_point(x, np.maximum(radius_m, 2.0 * edges[near]))
    counts = np.fromiter(map(len, found), dtype=np.int64, count=len(x))
    owner = np.repeat(np.arange(len(x)), counts)
    node = nodes[np.fromiter(chain.from_iterable(found), dtype=np.int64, count=int(counts.sum()))]
    total = np.zeros((len(x), 3))
    np.add.at(total, owner, p[node] - x[owner])
    return total / np.maximum(counts, 1)[:, None]


def side_motion(surface: ShellSurface, element, bary, toward, shell_normal, nodes=None,
                faces=True):
    """(W (3m, 6 n_nodes) sparse, z (m,) [m]) of m located points: u_face = W u of the face that
    looks `toward` (m, 3) (the partner), at z = ±t/2 + o along n_s = `shell_normal` (m, 3)
    (:func:`sarfe.fe.coupling.point_weights`, cubic bending; z along the facet normal, which n_s
    agrees with); ``faces=False``: the mid-surface (z = 0: a deck spring's grid point). A point
    off the shells (element −1) moves with the translations of its node in `nodes` (m,)."""
    element = np.asarray(element, dtype=np.int64)
    m, n = len(element), surface.n_nodes
    z = np.zeros(m)
    on = element >= 0
    parts, order = [], []
    if on.any():
        if faces:
            facet = facet_normals(surface.points, surface.triangles[element[on]])
            z[on] = face_offsets(facet, toward[on], surface.thickness[element[on]],
                                 surface.offset[element[on]])
        parts.append(point_weights(surface.points, surface.triangles, element[on], bary[on],
                                   offset_m=z[on], offset_direction=shell_normal[on], n_nodes=n))
        order.append(np.flatnonzero(on))
    if not on.all():
        parts.append(node_translations(np.asarray(nodes)[~on], n))
        order.append(np.flatnonzero(~on))
    stacked = sp.vstack(parts).tocsr()
    rows = (3 * np.concatenate(order)[:, None] + np.arange(3)).ravel()
    permute = sp.csr_matrix((np.ones(3 * m), (rows, np.arange(3 * m))), shape=(3 * m, 3 * m))
    return sp.csr_matrix(permute @ stacked), z


def node_translations(node_of_point, n_nodes) -> sp.csr_matrix:
    """W (3m, 6 n_nodes) of points that move with their node's translations."""
    m = len(node_of_point)
    r = np.arange(3 * m)
    c = (6 * np.repeat(np.asarray(node_of_point, dtype=np.int64), 3) + np.tile(np.arange(3), m))
    return sp.csr_matrix((np.ones(3 * m), (r, c)), shape=(3 * m, 6 * n_nodes))


def contact_rows(frames, weights_a, weights_b=None) -> sp.csr_matrix:
    """G (3 n_p, n_dof) = frame (W_a − W_b) (:func:`sarfe.fe.coupling.contact_operator`) with the
    round-off entries (below :data:`DROP` of their row's largest) removed, so that the DOFs a
    row touches — the Craig–Bampton boundary — are only those that move it."""
    g = contact_operator(frames, weights_a, weights_b).tocsr()
    g.sum_duplicates()
    largest = np.zeros(g.shape[0])
    row_of = np.repeat(np.arange(g.shape[0]), np.diff(g.indptr))
    np.maximum.at(largest, row_of, np.abs(g.data))
    g.data[np.abs(g.data) < DROP * largest[row_of]] = 0.0
    g.eliminate_zeros()
    return g


def face_points(x, z, shell_normal) -> np.ndarray:
    """Points on the faces (m, 3) [m]: x + z n_s."""
    return np.asarray(x) + np.asarray(z)[:, None] * np.asarray(shell_normal)


__all__ = ["SNAP", "DROP", "ShellSurface", "side_triangles", "node_locations", "snap",
           "surface_locations", "point_coordinates", "offset_normals", "body_side", "side_motion",
           "node_translations", "contact_rows", "face_points"]

