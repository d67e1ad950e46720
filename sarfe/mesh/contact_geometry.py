r"""Contact kinematics from the geometry: projections onto a triangle surface, surface normals
averaged over a patch of physical size, contact frames and surface gaps. Pure geometry on plain
arrays (points [m], triangles (n_tri, 3) int), vectorized over query points; no FE matrices
(:mod:`sarfe.fe.coupling` turns a projection into DOF weights).

A contact is defined by what is physical, not by mesh nodes:

* node-to-surface: the contact point x_a is projected onto the partner's triangles,
  x_b = argmin_{y ∈ S_b} |x_a − y| (:func:`project_to_surface`, element id and barycentric
  coordinates L of x_b in its triangle); the contact normal is the partner surface's normal there
  (:func:`patch_normals`), or a given one, or n = (x_b − x_a)/|x_b − x_a| where the points are
  apart (:func:`separation_normals`);
* the frame rows are [n, t₁, t₂], right-handed, t₁ × t₂ = n (:func:`frames_from_normals`); the
  relative displacement in it is [w, q₁, q₂] = frame · (u_a − u_b);
* the gap is between the surfaces, not the mid-surfaces (:func:`surface_gap`).

A mesh's nodal normal (area-weighted over the 1-ring) leans with the mesh at poles of revolved
surfaces (a node ringed by 5–7 irregular facets): on the squeak rig's pad 1.1–4.2° at mesh sizes
12–4 mm. A kernel average of the facet normals still leans (0.1–0.8° at R = 3 mm: the flat facets
cut under the curved surface, each tilted its own way), so :func:`patch_normals` fits a quadric
through the patch's nodes, which lie on the true surface, and takes its normal at the centre:
within 0.05° of the pad's axis on all those meshes (tests/mesh/test_contact_geometry.py).
:func:`facet_normal_spread_deg` reports how much the facet normals in a patch disagree (0 on a
flat plate, the half dihedral angle at a fold or ridge) for a caller's warning.
"""
from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass
from itertools import chain

import numpy as np
from scipy.spatial import cKDTree

from .geometry import facet_normals

__all__ = [
    "SurfaceProjection",
    "closest_points_on_triangles",
    "project_to_surface",
    "patch_normals",
    "facet_average_normals",
    "facet_normal_spread_deg",
    "facet_normal_residual_deg",
    "separation_normals",
    "orient_normals",
    "frames_from_normals",
    "surface_gap",
]

#: kernel quadrature on a triangle: vertices 3/60, midsides 8/60, centroid 27/60 (degree 3)
_RULE_POINTS = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0.5, 0], [0, 0.5, 0.5],
                         [0.5, 0, 0.5], [1 / 3, 1 / 3, 1 / 3]])
_RULE_WEIGHTS = np.array([3, 3, 3, 8, 8, 8, 27]) / 60.0

#: nodes a patch-normal fit reaches at least (centre + a ring), and its largest condition number
_MIN_FIT_NODES = 7
_MAX_CONDITION = 1e8


@dataclass(frozen=True)
class SurfaceProjection:
    """Closest points of m query points on a triangle surface.

    point (m, 3) [m] the closest point x_b; element (m,) int its triangle (index into the
    triangles passed); barycentric (m, 3) L with x_b = Σ L_i x_i, L_i ≥ 0, Σ L_i = 1;
    distance (m,) [m] |x_a − x_b|.
    """

    point: np.ndarray
    element: np.ndarray
    barycentric: np.ndarray
    distance: np.ndarray


def closest_points_on_triangles(query, vertices):
    """Closest point of each query point on its own triangle, vectorized over pairs.

    query (k, 3) [m]; vertices (k, 3, 3) [m] the corners x₁, x₂, x₃ of each pair's triangle.
    Returns (closest (k, 3) [m], barycentric (k, 3)).

    The plane projection's barycentric coordinates are L₁ = ((x₂ − q) × (x₃ − q))·n/|n|²,
    L₂ = ((x₃ − q) × (x₁ − q))·n/|n|², L₃ = 1 − L₁ − L₂ with n = (x₂ − x₁) × (x₃ − x₁). If all
    L_i ≥ 0 the projection is the closest point; otherwise (the triangle is convex) it lies on the
    boundary: the nearest of the three edge points x_i + s (x_j − x_i),
    s = clamp((q − x_i)·(x_j − x_i)/|x_j − x_i|², 0, 1), which covers the edge and vertex regions.
    Degenerate (zero-area) triangles get their nearest edge point.
    """
    q = np.asarray(query, dtype=float)
    x = np.asarray(vertices, dtype=float)
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    nn = np.einsum("ki,ki->k", n, n)
    rel = x - q[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        l1 = np.einsum("ki,ki->k", np.cross(rel[:, 1], rel[:, 2]), n) / nn
        l2 = np.einsum("ki,ki->k", np.cross(rel[:, 2], rel[:, 0]), n) / nn
    inside_l = np.stack([l1, l2, 1.0 - l1 - l2], axis=1)
    inside = (nn > 0) & np.all(inside_l >= 0, axis=1)
    start = x
    edge = x[:, [1, 2, 0]] - x                                     # (k, 3 edges, 3)
    length2 = np.einsum("kei,kei->ke", edge, edge)
    s = np.einsum("kei,kei->ke", q[:, None, :] - start, edge)
    s = np.clip(np.divide(s, length2, out=np.zeros_like(s), where=length2 > 0), 0.0, 1.0)
    candidates = start + s[..., None] * edge                       # (k, 3, 3)
    d2 = np.einsum("kei,kei->ke", candidates - q[:, None, :], candidates - q[:, None, :])
    best = np.argmin(d2, axis=1)
    rows = np.arange(len(q))
    s_best = s[rows, best]
    edge_l = np.zeros((len(q), 3))
    edge_l[rows, best] = 1.0 - s_best
    edge_l[rows, (best + 1) % 3] = s_best
    barycentric = np.where(inside[:, None], inside_l, edge_l)
    closest = np.einsum("kv,kvi->ki", barycentric, x)
    return closest, barycentric


def _candidate_pairs(tree, query, radius):
    """(query index, triangle index) of every centroid within `radius` (k,) of each query point;
    flattened from the tree's ragged answer."""
    found = tree.query_ball_point(query, radius, return_sorted=False)
    counts = np.fromiter(map(len, found), dtype=np.int64, count=len(query))
    tri = np.fromiter(chain.from_iterable(found), dtype=np.int64, count=int(counts.sum()))
    return np.repeat(np.arange(len(query)), counts), tri


@dataclass(frozen=True)
class _SurfaceIndex:
    """What every query on one surface (points, triangles) reuses: corners x (n_tri, 3, 3) [m],
    facet normals (n_tri, 3), a KD-tree of the triangle centroids and the largest centroid-to-
    corner distance R_max [m], the nodes on the surface and a KD-tree of them."""
    x: np.ndarray
    normal: np.ndarray
    centroid_tree: cKDTree
    reach: float
    used: np.ndarray
    node_tree: cKDTree


#: the last few surfaces indexed, by content (a contact set queries one partner surface ~10 times
#: per contact: building its trees each time was 3.3 of 6.1 CPU s on the 5 mm door trim)
_INDEX_CACHE: OrderedDict = OrderedDict()
_INDEX_CACHE_SIZE = 4


def _surface_index(p, t) -> _SurfaceIndex:
    """The :class:`_SurfaceIndex` of points p (n, 3) and triangles t (n_tri, 3), from a small
    cache keyed by the arrays' contents (a hash: equal arrays, not the same objects)."""
    key = (p.shape, t.shape, hashlib.blake2b(np.ascontiguousarray(p).data, digest_size=16)
           .hexdigest(), hashlib.blake2b(np.ascontiguousarray(t).data, digest_size=16).hexdigest())
    index = _INDEX_CACHE.get(key)
    if index is None:
        x = p[t]
        centroid = x.mean(axis=1)
        reach = np.sqrt(np.einsum("tvi,tvi->tv", x - centroid[:, None],
                                  x - centroid[:, None]).max())
        used = np.unique(t)
        index = _SurfaceIndex(x, facet_normals(p, t), cKDTree(centroid), float(reach), used,
                              cKDTree(p[used]))
        _INDEX_CACHE[key] = index
        while len(_INDEX_CACHE) > _INDEX_CACHE_SIZE:
            _INDEX_CACHE.popitem(last=False)
    _INDEX_CACHE.move_to_end(key)
    return index


def project_to_surface(query, points, triangles) -> SurfaceProjection:
    """Closest points of query (m, 3) [m] on the surface of `triangles` (n_tri, 3) over `points`.

    Candidates are pruned exactly: the nearest surface vertex is at d₀ ≥ the surface distance,
    so the closest triangle has its centroid within d₀ + R_max (R_max the largest centroid-to-
    corner distance); :func:`closest_points_on_triangles` runs on the candidate pairs and the
    nearest is kept per point (ties: the lowest triangle index).
    """
    q = np.atleast_2d(np.asarray(query, dtype=float))
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        raise ValueError("project_to_surface: no triangles to project onto")
    index = _surface_index(p, t)
    x = index.x
    d0, _ = index.node_tree.query(q)
    owner, tri = _candidate_pairs(index.centroid_tree, q, d0 * (1 + 1e-9) + index.reach + 1e-12)
    closest, bary = closest_points_on_triangles(q[owner], x[tri])
    d2 = np.einsum("ki,ki->k", closest - q[owner], closest - q[owner])
    order = np.lexsort((tri, d2, owner))
    first = order[np.unique(owner[order], return_index=True)[1]]
    return SurfaceProjection(point=closest[first], element=tri[first], barycentric=bary[first],
                             distance=np.sqrt(d2[first]))


def _patch_terms(centres, points, triangles, radius_m, reference):
    """Pairs (centre, triangle) of the patches and their kernel weights ∫_e k dA [m²] and
    oriented facet normals s_e n_e (s_e = sign(n_e · reference_c)); also each centre's
    reference normal (k_c, 3)."""
    c = np.atleast_2d(np.asarray(centres, dtype=float))
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    radius = np.broadcast_to(np.asarray(radius_m, dtype=float), (len(c),))
    if not np.all(radius > 0):
        raise ValueError(f"patch radius must be positive, got {radius_m!r} m")
    index = _surface_index(p, t)
    x, normal = index.x, index.normal
    if reference is None:
        ref = normal[project_to_surface(c, p, t).element]
    else:
        ref = np.broadcast_to(np.asarray(reference, dtype=float), c.shape)
    owner, tri = _candidate_pairs(index.centroid_tree, c, radius + index.reach)
    quad = np.einsum("qv,kvi->kqi", _RULE_POINTS, x[tri])          # (k, q, 3)
    s2 = (np.einsum("kqi,kqi->kq", quad - c[owner, None], quad - c[owner, None])
          / radius[owner, None] ** 2)
    kernel = np.where(s2 < 1.0, (1.0 - s2) ** 2, 0.0)
    area = 0.5 * np.linalg.norm(np.cross(x[tri, 1] - x[tri, 0], x[tri, 2] - x[tri, 0]), axis=1)
    weight = area * (kernel @ _RULE_WEIGHTS)
    sign = np.where(np.einsum("ki,ki->k", normal[tri], ref[owner]) < 0, -1.0, 1.0)
    return owner, tri, weight, sign[:, None] * normal[tri], ref


def facet_average_normals(centres, points, triangles, radius_m, reference=None) -> np.ndarray:
    """Unit kernel-weighted mean of the facet normals around each centre, (m, 3), radius R [m]
    a scalar or one per centre (m,):

        n(c) = N/|N|,  N = Σ_e s_e n_e ∫_e k(|x − c|/R) dA,  k(s) = (1 − s²)² (s < 1), else 0,

    ∫_e by a degree-3 rule; n_e the facet normals by winding, each turned (s_e = ±1) to agree with
    `reference` ((3,) or (m, 3)), by default with the facet normal of the triangle nearest to each
    centre. A patch smaller than the rule's spacing (no weight) falls back to the reference.
    On a faceted curved surface the facets' own tilt leaks in (0.1–0.8° on the squeak rig's pad at
    R = 3 mm): :func:`patch_normals` refines it with a fit through the nodes.
    """
    owner, _, weight, oriented, ref = _patch_terms(centres, points, triangles, radius_m, reference)
    total = np.zeros(ref.shape)
    np.add.at(total, owner, weight[:, None] * oriented)
    return _unit_or(total, ref)


def _unit_or(vectors, fallback):
    """Rows of `vectors` normalized; zero rows replaced by the normalized `fallback` rows."""
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    backup = fallback / np.linalg.norm(fallback, axis=1, keepdims=True)
    return np.where(length > 0, vectors / np.where(length > 0, length, 1.0), backup)


def _quadric_fit(centres, nodes_xyz, owner, node, guess, support):
    """One weighted least-squares fit per centre, in the frame [t₁, t₂, n₀] of `guess` with
    ξ, η, ζ scaled by the support radius ρ_s (m,) and weights k(|x − c|/ρ_s), of

        ζ = a + bξ + cη + dξ² + eξη + fη²        (≥ 6 nodes, well conditioned), else
        ζ = a + bξ + cη + d(ξ² + η²)            (≥ 4 nodes), else ζ = 0 (the guess's plane).

    Returns the frames (m, 3, 3) rows [n₀, t₁, t₂] and the coefficients (m, 6) [a, b, c, d, e, f]
    (dimensionless: lengths over ρ_s)."""
    frame = frames_from_normals(guess)                              # rows n, t1, t2
    rel = (nodes_xyz[node] - centres[owner]) / support[owner, None]
    local = np.einsum("kji,ki->kj", frame[owner], rel)              # (ζ, ξ, η)
    zeta, xi, eta = local[:, 0], local[:, 1], local[:, 2]
    weight = np.clip(1.0 - np.einsum("ki,ki->k", rel, rel), 0.0, None) ** 2
    one = np.ones_like(xi)
    m = len(centres)
    coefficients = np.zeros((m, 6))
    done = np.zeros(m, dtype=bool)
    # full quadric, then the isotropic one (its d fills d and f, e = 0)
    for design, spread in ((np.stack([one, xi, eta, xi * xi, xi * eta, eta * eta], axis=1),
                            np.eye(6)),
                           (np.stack([one, xi, eta, xi * xi + eta * eta], axis=1),
                            np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],
                                      [0, 0, 0, 1, 0, 1]], dtype=float))):
        k = design.shape[1]
        gram = np.zeros((m, k, k))
        rhs = np.zeros((m, k))
        np.add.at(gram, owner, weight[:, None, None] * design[:, :, None] * design[:, None, :])
        np.add.at(rhs, owner, (weight * zeta)[:, None] * design)
        count = np.bincount(owner, weights=(weight > 0).astype(float), minlength=m)
        fit = ~done & (count >= k)
        if fit.any():
            fit[fit] = np.linalg.cond(gram[fit]) < _MAX_CONDITION
        if fit.any():
            coefficients[fit] = np.linalg.solve(gram[fit], rhs[fit][..., None])[..., 0] @ spread
            done |= fit
    return frame, coefficients


def _fitted_normals(frame, coefficients, xi=0.0, eta=0.0):
    """Unit normal n = (n₀ − ζ_ξ t₁ − ζ_η t₂)/|…| of the fitted quadric (:func:`_quadric_fit`)
    at the scaled in-plane coordinates (ξ, η) (0: the centre), on n₀'s side; shapes broadcast
    over the leading axis."""
    b, c, d, e, f = (coefficients[..., i] for i in range(1, 6))
    slope_xi = b + 2 * d * xi + e * eta
    slope_eta = c + e * xi + 2 * f * eta
    normal = (frame[..., 0, :] - slope_xi[..., None] * frame[..., 1, :]
              - slope_eta[..., None] * frame[..., 2, :])
    return normal / np.linalg.norm(normal, axis=-1, keepdims=True)


def _patch_fit(c, p, t, radius_m, reference, iterations, min_nodes):
    """(normals (m, 3), frames, coefficients, support ρ_s (m,)) of :func:`patch_normals`."""
    index = _surface_index(p, t)
    used, tree = index.used, index.node_tree
    nearest, _ = tree.query(c, k=min(min_nodes, len(used)))
    support = np.maximum(float(radius_m), 1.25 * np.reshape(nearest, (len(c), -1))[:, -1])
    normal = facet_average_normals(c, p, t, support, reference)
    owner, local_node = _candidate_pairs(tree, c, support)
    node = used[local_node]
    frame = frames_from_normals(normal)
    coefficients = np.zeros((len(c), 6))
    for _ in range(iterations):
        frame, coefficients = _quadric_fit(c, p, owner, node, normal, support)
        normal = _fitted_normals(frame, coefficients)
    return normal, frame, coefficients, support


def patch_normals(centres, points, triangles, radius_m, reference=None, iterations: int = 2,
                  min_nodes: int = _MIN_FIT_NODES) -> np.ndarray:
    """Unit surface normal of a patch of radius R = `radius_m` [m] around each centre, (m, 3).

    The normal at c of the surface fitted through the patch: in a frame [t₁, t₂, n₀] at c, the
    weighted least-squares quadric ζ = a + bξ + cη + dξ² + eξη + fη² through the nodes of
    `triangles` within ρ_s (weights k(|x − c|/ρ_s), k(s) = (1 − s²)²) gives n = (n₀ − b t₁ − c t₂)/|…|,
    which is also the kernel-weighted mean normal of the fitted surface over the patch (the
    linear terms of ∇ζ cancel over the symmetric kernel). The nodes lie on the true surface while
    the facets cut under it, so this is exact for planes and quadrics and, to O((ρ_s/ρ)⁴), for
    curved surfaces of curvature radius ρ — unlike a facet average (:func:`facet_average_normals`,
    the first guess n₀); `iterations` re-fits in the frame of the last normal.

    Support ρ_s = max(R, 1.25 d_k): a contact patch smaller than the mesh cannot be resolved by
    it, so the fit reaches at least past the k = `min_nodes`-th nearest node (the normal of the
    fitted surface at c does not depend on ρ_s, only its accuracy does). Orientation: as
    `reference` ((3,) or (m, 3)), by default the facet normal nearest to each centre. Pass the
    partner part's triangles only (a fit across a fold or onto another part is meaningless).
    """
    c = np.atleast_2d(np.asarray(centres, dtype=float))
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    return _patch_fit(c, p, t, radius_m, reference, iterations, min_nodes)[0]


def facet_normal_spread_deg(centres, points, triangles, radius_m, reference=None) -> np.ndarray:
    """Largest angle [deg] between the patch normal (:func:`patch_normals`) and the facet normals
    inside the patch (triangles with kernel weight > 0, or the nearest one), shape (m,).

    Flat: 0; a smooth curved surface: about R/ρ rad (ρ the radius of curvature) plus the faceting
    h/ρ; an edge, fold or ridge: half the dihedral angle or more. A caller warns when it is large:
    the contact normal then depends on the patch radius and on the mesh.
    """
    owner, tri, weight, oriented, ref = _patch_terms(centres, points, triangles, radius_m,
                                                     reference)
    normal = patch_normals(centres, points, triangles, radius_m, ref)
    nearest = project_to_surface(centres, points, triangles).element
    inside = (weight > 0) | (tri == nearest[owner])
    cosine = np.clip(np.einsum("ki,ki->k", oriented, normal[owner]), -1.0, 1.0)
    spread = np.zeros(len(normal))
    np.maximum.at(spread, owner[inside], np.degrees(np.arccos(cosine[inside])))
    return spread


def facet_normal_residual_deg(centres, points, triangles, radius_m, reference=None) -> np.ndarray:
    """Largest angle [deg] between a facet's normal and the normal of the surface fitted through
    the patch (:func:`patch_normals`' quadric) at the facet's centroid, over the facets inside
    the patch (kernel weight > 0, or the nearest one), shape (m,).

    Unlike :func:`facet_normal_spread_deg` this leaves out what the smooth surface explains:
    on a plane, a sphere or a cylinder it is the faceting error only (0 on a flat plate, ≲ 2–3°
    on the squeak rig's 12 mm spherical pad at its pole on meshes of 2–12 mm, where the spread is
    8–16°), while an edge, fold, ridge or T-junction, which no quadric follows, leaves tens of
    degrees (a rib under a skin: > 40°). A caller warns when it is large: the contact normal
    there depends on the patch and the mesh, not on a surface.
    """
    c = np.atleast_2d(np.asarray(centres, dtype=float))
    p = np.asarray(points, dtype=float)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    owner, tri, weight, oriented, ref = _patch_terms(c, p, t, radius_m, reference)
    normal, frame, coefficients, support = _patch_fit(c, p, t, radius_m, ref, 2, _MIN_FIT_NODES)
    nearest = project_to_surface(c, p, t).element
    inside = (weight > 0) | (tri == nearest[owner])
    owner, tri, oriented = owner[inside], tri[inside], oriented[inside]
    rel = (p[t[tri]].mean(axis=1) - c[owner]) / support[owner, None]
    xi = np.einsum("ki,ki->k", frame[owner, 1], rel)
    eta = np.einsum("ki,ki->k", frame[owner, 2], rel)
    fitted = _fitted_normals(frame[owner], coefficients[owner], xi, eta)
    cosine = np.clip(np.einsum("ki,ki->k", oriented, fitted), -1.0, 1.0)
    residual = np.zeros(len(c))
    np.maximum.at(residual, owner, np.degrees(np.arccos(cosine)))
    return residual


def separation_normals(points_a, points_b, tolerance_m: float = 1e-9):
    """n = (x_b − x_a)/|x_b − x_a| for pairs that are apart, (m, 3), and `apart` (m,) bool
    (|x_b − x_a| > tolerance_m [m]); coincident pairs get a zero row (take their normal from
    the surface: :func:`patch_normals`)."""
    delta = np.asarray(points_b, dtype=float) - np.asarray(points_a, dtype=float)
    length = np.linalg.norm(delta, axis=-1, keepdims=True)
    apart = length[..., 0] > tolerance_m
    return np.where(apart[..., None], delta / np.where(apart[..., None], length, 1.0), 0.0), apart


def orient_normals(normals, reference) -> np.ndarray:
    """Normals (m, 3) turned (×−1) where n · reference < 0; reference (3,) or (m, 3), e.g.
    x_b − x_a so that the contact normal points from side a towards side b."""
    n = np.asarray(normals, dtype=float)
    dot = np.einsum("...i,...i->...", n, np.broadcast_to(reference, n.shape))
    return np.where((dot < 0)[..., None], -n, n)


def frames_from_normals(normals) -> np.ndarray:
    """Right-handed orthonormal frames, rows [n, t₁, t₂], shape (…, 3, 3), around unit normals
    (…, 3): t₁ = n × e_k / |n × e_k| with e_k the axis least aligned with n, t₂ = n × t₁
    (t₁ × t₂ = n). The same n always gives the same tangents (no mesh dependence)."""
    n = np.asarray(normals, dtype=float)
    axis = np.eye(3)[np.argmin(np.abs(n), axis=-1)]
    t1 = np.cross(n, axis)
    t1 = t1 / np.linalg.norm(t1, axis=-1, keepdims=True)
    return np.stack([n, t1, np.cross(n, t1)], axis=-2)


def surface_gap(mid_distance_m, thickness_a_m, thickness_b_m, offset_a_m=0.0,
                offset_b_m=0.0) -> np.ndarray:
    """Gap between the facing surfaces [m] from the distance of the mid-surfaces along the
    contact normal, d = n · (x_b − x_a) [m]:

        g = d − t_a/2 − t_b/2 − o_a − o_b,

    t_a, t_b [m] the shell thicknesses; o_a, o_b [m] how far each side's mid-surface lies from its
    mesh surface towards the partner (a shell offset such as a Nastran ZOFFS, signed). Scalars or
    arrays that broadcast. g < 0 is an overlap (e.g. mid-surfaces meshed touching)."""
    return (np.asarray(mid_distance_m, dtype=float) - 0.5 * np.asarray(thickness_a_m)
            - 0.5 * np.asarray(thickness_b_m) - np.asarray(offset_a_m) - np.asarray(offset_b_m))
