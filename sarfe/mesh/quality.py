"""Mesh-quality checks that find a silently wrong model before any assembly.

Each check takes plain arrays (coordinates [m], connectivity as node rows) and returns the
offending element / node *ids* so a message can name them as the user's file does.

* :func:`duplicate_elements`  elements on the same node set (twice the stiffness and mass)
* :func:`coincident_nodes`    distinct nodes at the same place that nothing joins (a crack)
* :func:`degenerate_elements` shell elements of (near) zero area
"""
from __future__ import annotations

import numpy as np


def duplicate_elements(connectivity, element_ids) -> list[tuple[int, int]]:
    """Pairs (kept id, repeated id) of elements whose node sets are equal.

    connectivity (n_e, k) int node rows (all elements of one kind, e.g. shell corners padded
    with −1 for triangles in a quad block); element_ids (n_e,) the file's ids.
    The node order does not matter (a reversed copy is still a duplicate).
    """
    nodes = np.sort(np.asarray(connectivity, dtype=np.int64), axis=1)
    ids = np.asarray(element_ids)
    if len(nodes) < 2:
        return []
    _, first, owner = np.unique(nodes, axis=0, return_index=True, return_inverse=True)
    owner = np.asarray(owner).reshape(-1)
    repeated = np.flatnonzero(first[owner] != np.arange(len(nodes)))
    return [(int(ids[first[owner[i]]]), int(ids[i])) for i in repeated]


def coincident_nodes(points, node_ids, tolerance_m: float, joined=()) -> list[tuple[int, int]]:
    """Pairs of node ids closer than `tolerance_m` that are not joined on purpose.

    points (n, 3) [m]; joined: iterable of (row_a, row_b) node-row pairs that an element, a
    rigid element or a contact connects (zero-length springs, clips): those are not reported.
    """
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=float)
    ids = np.asarray(node_ids)
    if len(points) < 2:
        return []
    pairs = cKDTree(points).query_pairs(float(tolerance_m), output_type="ndarray")
    if len(pairs) == 0:
        return []
    known = {(min(a, b), max(a, b)) for a, b in joined}
    return [(int(ids[a]), int(ids[b])) for a, b in np.sort(pairs, axis=1)
            if (int(a), int(b)) not in known]


def shell_areas(points, shells) -> np.ndarray:
    """Area [m²] of each shell element: (n_e, 3) triangles or (n_e, 4) quads (−1 padding in the
    fourth column marks a triangle). A quad's area is that of its two triangles (0,1,2), (0,2,3)."""
    points = np.asarray(points, dtype=float)
    shells = np.asarray(shells, dtype=np.int64)
    a, b, c = points[shells[:, 0]], points[shells[:, 1]], points[shells[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if shells.shape[1] > 3:
        quad = shells[:, 3] >= 0
        d = points[np.where(quad, shells[:, 3], shells[:, 0])]
        area = area + np.where(quad, 0.5 * np.linalg.norm(np.cross(c - a, d - a), axis=1), 0.0)
    return area


def degenerate_elements(points, shells, element_ids, relative_tolerance: float = 1e-10):
    """Ids of shell elements with area ≤ relative_tolerance · (longest edge)² (zero-area
    elements: repeated nodes or collinear corners), which make the stiffness singular."""
    points = np.asarray(points, dtype=float)
    shells = np.asarray(shells, dtype=np.int64)
    if len(shells) == 0:
        return []
    corners = np.where(shells >= 0, shells, shells[:, :1])
    edges = points[np.roll(corners, -1, axis=1)] - points[corners]
    longest = np.max(np.einsum("ijk,ijk->ij", edges, edges), axis=1)
    small = shell_areas(points, shells) <= relative_tolerance * longest
    return [int(i) for i in np.asarray(element_ids)[small]]
