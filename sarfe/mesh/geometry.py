"""Geometric quantities of triangle shell meshes, vectorized over triangles.

All functions take plain arrays: `points` (n_nodes, 3) [m] and `triangles` (n_tri, 3) int.
To work on one part or on the radiating skin pass ``mesh.triangles[mesh.element_group(name)]``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components as _components


def triangle_area_vectors(points, triangles) -> np.ndarray:
    """a_e = ½ (x₁ − x₀) × (x₂ − x₀), shape (n_tri, 3) [m²]; |a_e| = area, a_e/|a_e| = facet normal."""
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64)
    return 0.5 * np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])


def triangle_areas(points, triangles) -> np.ndarray:
    """Area A_e of each triangle, shape (n_tri,) [m²]."""
    return np.linalg.norm(triangle_area_vectors(points, triangles), axis=1)


def nodal_areas(points, triangles, n_nodes: int | None = None) -> np.ndarray:
    """Lumped nodal area A_i = Σ_{e ∋ i} A_e / 3, shape (n_nodes,) [m²]; Σ A_i = total area."""
    t = np.asarray(triangles, dtype=np.int64)
    n = len(points) if n_nodes is None else n_nodes
    share = np.repeat(triangle_areas(points, t) / 3.0, 3)
    return np.bincount(t.ravel(), weights=share, minlength=n)


def _manifold_adjacency(triangles):
    """Pairs (t1, t2) sharing an edge used by exactly two triangles, and whether they agree.

    Two triangles are consistently oriented when they traverse the shared edge in opposite
    directions; `same` is +1 then and −1 when one of them has to be flipped.
    """
    t = np.asarray(triangles, dtype=np.int64)
    n_tri = len(t)
    start = t.ravel()
    end = t[:, [1, 2, 0]].ravel()
    owner = np.repeat(np.arange(n_tri), 3)
    low, high = np.minimum(start, end), np.maximum(start, end)
    forward = start < end
    order = np.lexsort((high, low))
    low, high, forward, owner = low[order], high[order], forward[order], owner[order]
    new = np.r_[True, (low[1:] != low[:-1]) | (high[1:] != high[:-1])]
    group = np.cumsum(new) - 1
    counts = np.bincount(group)
    first = np.flatnonzero(new)
    manifold = first[counts == 2]
    t1, t2 = owner[manifold], owner[manifold + 1]
    same = np.where(forward[manifold] != forward[manifold + 1], 1, -1)
    keep = t1 != t2
    return t1[keep], t2[keep], same[keep]


def orient_triangles(points, triangles, reference=None) -> np.ndarray:
    """Triangles re-ordered so each edge-connected manifold patch has one orientation.

    Patches are joined across edges shared by exactly two triangles (T-junctions such as
    rib-to-skin lines separate patches).  Each patch is then turned so that its summed area
    vector Σ a_e points along `reference` (3-vector) or, if None, so that the largest
    component of Σ a_e is positive; for (nearly) closed patches so that the enclosed volume
    is positive (outward normals).  Returns a new (n_tri, 3) array.
    """
    t = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    n_tri = len(t)
    if n_tri == 0:
        return t
    t1, t2, same = _manifold_adjacency(t)
    # spanning forest by one breadth-first search from a virtual root joined to every patch
    n_patch, patch = _components(
        sp.coo_matrix((np.ones(len(t1)), (t1, t2)), shape=(n_tri, n_tri)), directed=False)
    roots = np.unique(patch, return_index=True)[1]
    root = n_tri
    rows = np.r_[t1, np.full(len(roots), root)]
    cols = np.r_[t2, roots]
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_tri + 1, n_tri + 1)).tocsr()
    _, parent = breadth_first_order(graph, root, directed=False, return_predecessors=True)
    parent = parent[:n_tri].copy()
    parent[roots] = roots
    # sign of the relation (tri, parent) looked up in the sorted pair keys
    key = np.minimum(t1, t2) * (n_tri + 1) + np.maximum(t1, t2)
    order = np.argsort(key)
    key, same = key[order], same[order]
    query = np.minimum(np.arange(n_tri), parent) * (n_tri + 1) + np.maximum(np.arange(n_tri), parent)
    pos = np.clip(np.searchsorted(key, query), 0, max(len(key) - 1, 0))
    parity = np.where(parent == np.arange(n_tri), 1, same[pos] if len(key) else 1)
    # pointer jumping: parity to the patch root in O(log depth) vectorized passes
    while True:
        grand = parent[parent]
        if np.array_equal(grand, parent):
            parity = parity * parity[parent]
            break
        parity, parent = parity * parity[parent], grand
    flip = parity < 0
    t[flip] = t[flip][:, [0, 2, 1]]
    # one global sign per patch
    p = np.asarray(points, dtype=float)
    area = triangle_area_vectors(p, t)
    total = np.zeros((n_patch, 3))
    np.add.at(total, patch, area)
    size = np.bincount(patch, weights=np.linalg.norm(area, axis=1), minlength=n_patch)
    if reference is not None:
        score = total @ np.asarray(reference, dtype=float)
    else:
        dominant = np.argmax(np.abs(total), axis=1)
        score = total[np.arange(n_patch), dominant]
    closed = np.linalg.norm(total, axis=1) < 1e-6 * np.maximum(size, 1e-300)
    if closed.any():
        centroid = p[t].mean(axis=1)
        volume = np.bincount(patch, weights=np.einsum("ij,ij->i", centroid, area), minlength=n_patch)
        score = np.where(closed, volume, score)
    turn = (score < 0)[patch]
    t[turn] = t[turn][:, [0, 2, 1]]
    return t


def facet_normals(points, triangles) -> np.ndarray:
    """Unit normal of each triangle as ordered, shape (n_tri, 3); zero for degenerate triangles."""
    a = triangle_area_vectors(points, triangles)
    norm = np.linalg.norm(a, axis=1, keepdims=True)
    return np.divide(a, norm, out=np.zeros_like(a), where=norm > 0)


def node_normals(points, triangles, reference=None, orient: bool = True) -> np.ndarray:
    """Unit nodal normals n_i = Σ_{e ∋ i} a_e / |Σ_{e ∋ i} a_e| (area-weighted), shape (n_nodes, 3).

    The triangles are first made consistently oriented per manifold patch (`orient_triangles`).
    Nodes not used by `triangles` get a zero vector.  Pass one smooth surface (e.g. the `skin`
    group): at rib/skin T-junctions an averaged normal has no meaning.
    """
    p = np.asarray(points, dtype=float)
    t = orient_triangles(p, triangles, reference) if orient else np.asarray(triangles, dtype=np.int64)
    a = triangle_area_vectors(p, t)
    n = np.zeros((len(p), 3))
    for k in range(3):  # three vertex slots, not an element loop
        np.add.at(n, t[:, k], a)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)


def connected_components(n_nodes: int, triangles, tetrahedra=None) -> tuple[int, np.ndarray]:
    """Node-connected components of the elements.

    Returns (count, labels) with labels (n_nodes,) in 0..count-1, numbered in order of the
    lowest node index; nodes used by no element get label −1 and are not counted.
    """
    cells = [np.asarray(triangles, dtype=np.int64).reshape(-1, 3)]
    if tetrahedra is not None:
        cells.append(np.asarray(tetrahedra, dtype=np.int64)[:, :4])
    rows, cols = [], []
    for c in cells:
        for k in range(1, c.shape[1]):
            rows.append(c[:, 0])
            cols.append(c[:, k])
    rows = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    cols = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_nodes, n_nodes))
    _, raw = _components(graph, directed=False)
    used = np.zeros(n_nodes, dtype=bool)
    for c in cells:
        used[c.ravel()] = True
    labels = np.full(n_nodes, -1, dtype=np.int64)
    if used.any():
        unique, first = np.unique(raw[used], return_index=True)
        rank = np.empty(len(unique), dtype=np.int64)
        rank[np.argsort(first)] = np.arange(len(unique))
        labels[used] = rank[np.searchsorted(unique, raw[used])]
        return len(unique), labels
    return 0, labels


def orphan_nodes(n_nodes: int, triangles, tetrahedra=None) -> np.ndarray:
    """Indices of nodes referenced by no triangle and no tetrahedron."""
    used = np.zeros(n_nodes, dtype=bool)
    used[np.asarray(triangles, dtype=np.int64).ravel()] = True
    if tetrahedra is not None:
        used[np.asarray(tetrahedra, dtype=np.int64).ravel()] = True
    return np.flatnonzero(~used)


def contact_frames(mesh, tolerance: float = 1e-12) -> dict:
    """Local frame and geometric gap of every contact pair `contact_<pair>_a` / `_b` of `mesh`.

    Returns {pair: (normal (k, 3), tangents (k, 2, 3), gap (k,))} with k node pairs:
    normal n = (x_b − x_a)/|x_b − x_a| points from node a to node b, gap g = |x_b − x_a| [m];
    for coincident nodes (g ≤ tolerance) n is b's node normal on the triangles touching b,
    turned away from the triangles touching a.  Tangents t₁, t₂ complete a right-handed
    orthonormal frame (t₁ × t₂ = n).  The pair closes when (u_a − u_b)·n reaches g.
    """
    points = mesh.points
    frames = {}
    for pair, (a, b) in mesh.contact_pairs().items():
        delta = points[b] - points[a]
        gap = np.linalg.norm(delta, axis=1)
        normal = np.divide(delta, gap[:, None], out=np.zeros_like(delta), where=gap[:, None] > tolerance)
        for i in np.flatnonzero(gap <= tolerance):  # rare: only coincident pairs
            near_b = np.any(mesh.triangles == b[i], axis=1)
            near_a = np.any(mesh.triangles == a[i], axis=1)
            n = node_normals(points, mesh.triangles[near_b])[b[i]]
            side = points[mesh.triangles[near_a]].mean(axis=(0, 1)) - points[b[i]]
            normal[i] = -n if n @ side > 0 else n
        helper = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
        t1 = np.cross(helper, normal)
        t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
        t2 = np.cross(normal, t1)
        frames[pair] = (normal, np.stack([t1, t2], axis=1), gap)
    return frames
