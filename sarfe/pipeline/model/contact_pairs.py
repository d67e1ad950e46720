r"""Contact geometry of an FE case: the node pairs of each named contact, their local frames and
geometric gaps, and the reduced coordinates of both sides.

    pair_contact(case, mesh, index, normals) -> (a, b, frames, distance)
    frame_from_normal(normals (…, 3)) -> (…, 3, 3) rows [n, t1, t2]
    reduced_coordinates(boundary_global, n_nodes) -> coords_of(nodes) → (m, 3)
    contact_geometry(paired, coords_of) -> {name: ContactGeometry}

Pairs: ``between: [a, b]`` pairs every node of group a with the nearest node of group b (within
``pairing_tolerance_m``; b = −1 for ``ground``), or ``pairs`` lists them. The normal n of a pair
is the mesh's nodal normal at a (``normal: auto``, turned to point from a towards b) or the given
vector; the tangents complete a right-handed frame. The geometric gap is g = n·(x_b − x_a) [m]
(0 for ground or coincident nodes). A contact row is w = n·(u_a − u_b), q_i = t_i·(u_a − u_b).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.pipeline.model.groups import resolve_node_group


@dataclass(frozen=True)
class ContactGeometry:
    """Node pairs of one named contact (FE) and their local frames.

    nodes_a, nodes_b (n_p,) mesh node indices (b = −1 for ground); frames (n_p, 3, 3) rows
    [normal, tangent 1, tangent 2] (unit, normal from a towards b); coords_a, coords_b (n_p, 3)
    reduced coordinate of each translation ux, uy, uz (−1 where fixed or ground).
    """

    name: str
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    coords_a: np.ndarray
    coords_b: np.ndarray
    distances: np.ndarray      # (n_p,) [m] n·(x_b − x_a), the geometric gap (0 for ground)
    # (n_p,) [N/m] per-pair stiffness of deck springs turned into this contact (from_elements)
    normal_stiffness: np.ndarray | None = None
    tangential_stiffness: np.ndarray | None = None


def frame_from_normal(normals):
    """Rows [n, t1, t2] (…, 3, 3) of right-handed orthonormal frames around unit normals (…, 3)."""
    n = np.asarray(normals, dtype=float)
    axis = np.eye(3)[np.argmin(np.abs(n), axis=-1)]
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(n, t1)
    return np.stack([n, t1, t2], axis=-2)


def pair_contact(case, mesh, index, normals_all, pairs=None):
    """Node pairs and frames of contacts[index] (nearest-node pairing or explicit pairs):
    (a (n_p,), b (n_p,) with −1 for ground, frames (n_p, 3, 3), geometric gaps (n_p,) [m]).
    ``pairs``: the explicit pairs as mesh node indices when the case gives them in other numbers
    (a deck's GRID ids: :func:`sarfe.pipeline.model.deck_model.grid_pairs`), else the case's."""
    from scipy.spatial import cKDTree   # (scipy.spatial costs ~0.3 s to import: pairing only)

    contact = case.config.contacts[index]
    p = ("contacts", index)
    points = mesh.points
    if contact.pairs is not None:
        pairs = contact.pairs if pairs is None else pairs
        for j, (na, nb) in enumerate(pairs):
            for k, node in enumerate((na, nb)):
                if node == "ground":
                    if k == 0:
                        raise case.error("the first node cannot be 'ground'", p + ("pairs", j, 0))
                    continue
                if not 0 <= node < mesh.n_nodes:
                    raise case.error(f"node {node} out of range (mesh has {mesh.n_nodes} nodes)",
                                     p + ("pairs", j, k))
        a = np.array([q[0] for q in pairs], dtype=int)
        b = np.array([-1 if q[1] == "ground" else q[1] for q in pairs], dtype=int)
    else:
        group_a, group_b = contact.between
        a = resolve_node_group(case, mesh, group_a, p + ("between", 0))
        if group_b == "ground":
            b = np.full(len(a), -1)
        else:
            nodes_b = resolve_node_group(case, mesh, group_b, p + ("between", 1))
            distance, nearest = cKDTree(points[nodes_b]).query(points[a])
            tolerance = contact.pairing_tolerance_m
            far = distance > tolerance * (1 + 1e-9) + 1e-12
            if np.any(far):
                worst = int(np.argmax(distance))
                raise case.error(
                    f"{np.count_nonzero(far)} of {len(a)} nodes of '{group_a}' have no node of "
                    f"'{group_b}' within pairing_tolerance_m = {tolerance:g} m (farthest: node "
                    f"{a[worst]} at {distance[worst]:.3g} m)", p + ("between",))
            b = nodes_b[nearest]
    offset = np.where(b[:, None] >= 0, points[np.maximum(b, 0)] - points[a], 0.0)
    separation = np.linalg.norm(offset, axis=1)
    if contact.normal == "auto":
        normal = normals_all[a].copy()
        if np.any(np.linalg.norm(normal, axis=1) < 0.5):
            raise case.error("node(s) with no surface normal (not on any shell triangle); give "
                             "normal: [x, y, z]", p + ("normal",))
        apart = separation > 1e-9
        flip = apart & (np.einsum("ij,ij->i", normal, offset) < 0)
        normal[flip] *= -1.0
    else:
        vector = np.asarray(contact.normal, dtype=float)
        length = np.linalg.norm(vector)
        if length == 0 or not np.isfinite(length):
            raise case.error("normal vector must be non-zero", p + ("normal",))
        normal = np.broadcast_to(vector / length, (len(a), 3))
    # geometric gap along the normal (the default gap of the pair; 0 for coincident nodes)
    distance = np.einsum("ij,ij->i", normal, offset)
    return a, b, frame_from_normal(normal), distance


def reduced_coordinates(boundary_global, n_nodes):
    """A function: nodes (m,) → (m, 3) reduced coordinates of their translations (−1 when fixed,
    not on the boundary, or the node is −1). ``boundary_global`` (n_b,): the global DOF index
    6·node + component of each boundary coordinate, in reduced order."""
    coord = np.full(6 * n_nodes, -1)
    coord[boundary_global] = np.arange(len(boundary_global))

    def coords_of(nodes):
        nodes = np.asarray(nodes)
        out = np.full((len(nodes), 3), -1)
        ok = nodes >= 0
        out[ok] = coord[6 * nodes[ok, None] + np.arange(3)]
        return out
    return coords_of


def contact_geometry(paired, coords_of) -> dict:
    """{name: ContactGeometry} of the pairs {name: (a, b, frames, distance)} with the reduced
    coordinates of both sides (``coords_of``: :func:`reduced_coordinates`)."""
    return {name: ContactGeometry(name, a, b, frames, coords_of(a), coords_of(b), distance)
            for name, (a, b, frames, distance) in paired.items()}


__all__ = ["ContactGeometry", "frame_from_normal", "pair_contact", "reduced_coordinates",
           "contact_geometry"]
