r"""Contacts of an FE case from the geometry: their points, frames, surface gaps and the rows of
the gap map, on the full mesh and then on the reduced coordinates.

    resolve_contact(case, mesh, index, surface) -> ResolvedContact     (one contacts[] entry)
    spring_contact(name, spring, surface) -> ResolvedContact           (a deck's CBUSH/CELAS)
    boundary_dofs(resolved) -> global DOFs the contact rows touch      (the Craig–Bampton boundary)
    contact_geometry(resolved, boundary_global, n_r) -> {name: ContactGeometry}  (reduced rows)
    reduced_coordinates(boundary_global, n_nodes) -> coords_of(nodes) → (m, 3)   (load nodes)

Where a contact acts (:mod:`sarfe.pipeline.model.contact_kinematics`):

* ``between: [a, b]``: every node x_a of group a is a contact point; its partner x_b is the
  closest point of b's surface (the shells of the bodies holding b's nodes, or ``surfaces[1]``)
  within ``pairing_tolerance_m``, coupled by the shape functions of the triangle it lies in — not
  the nearest node, so the contact does not move with the mesh. b = ``ground``: no partner.
* ``points_m: [[x, y, z], …]`` with ``surfaces: [a, b]``: points by coordinates, projected on
  both surfaces (each within ``pairing_tolerance_m``): independent of any node.
* ``pairs: [[a, b], …]``: node to node (an engineer's deck defines them), b may be ground.
* ``from_elements`` (deck springs): node to node along the spring axis, at the grid points.

The normal n (from a towards b): ``auto`` — the partner surface's normal at x_b, fitted over a
patch of radius ``patch_radius_m`` (:func:`sarfe.mesh.contact_geometry.patch_normals`: not one
node's leaning mesh normal; a grounded contact: side a's own); ``separation`` — (x_b − x_a)/|…|;
``[x, y, z]`` — given; a spring's axis. Between coincident points (a pad meshed onto a plate's
mid-surface) ``auto`` points away from side a's body. The frame rows are [n, t₁, t₂]
(:func:`sarfe.mesh.contact_geometry.frames_from_normals`) and the rows of G are
[w, q₁, q₂]_p = frame_p (u_face,a − u_face,b): the forces act on the facing shell faces (±t/2 and
any offset from the mid-surfaces), so a friction force bends the shells by its moment.
The geometric gap is the surface gap g = n·(x_b,face − x_a,face) — the mid-surface distance less
the half thicknesses — used when a contact gives neither ``gap_m`` nor ``preload_N``.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import laws
from sarfe.mesh.contact_geometry import (facet_normal_residual_deg, frames_from_normals,
                                         orient_normals, patch_normals, separation_normals)
from sarfe.mesh.geometry import facet_normals
from sarfe.pipeline.model.contact_kinematics import (ShellSurface, body_side, contact_rows,
                                                     face_points, node_locations,
                                                     node_translations, offset_normals,
                                                     point_coordinates, side_motion,
                                                     side_triangles, surface_locations)
from sarfe.pipeline.model.groups import available, resolve_node_group

#: a contact normal fitted where the facets leave the fitted surface by more than this [deg]
#: (an edge, fold, ridge or T-junction under the point) is warned about. Calibrated on the
#: squeak rig's spherical pad (radius 12 mm) at its pole: ≤ 11.3° over meshes of 2–12 mm at the
#: default patch (where the fit reaches the fold at the pad's rim), 1.2–3.4° at ≤ 6 mm; a rib
#: under the door trim's skin: 63–90°.
NORMAL_RESIDUAL_WARN_DEG = 20.0
#: points closer than this [m] are coincident (no separation direction)
COINCIDENT_M = 1e-9


@dataclass(frozen=True)
class ResolvedContact:
    """One named contact on the full mesh: n_p contact points.

    points (n_p, 3) [m] x_a on side a's mid-surface; partner_points (n_p, 3) [m] x_b (x_a for
    ground); nodes_a, nodes_b (n_p,) the node at (or nearest in the element of) each point, −1 for
    ground — for reports and maps; frames (n_p, 3, 3) rows [n, t₁, t₂]; operator CSR
    (3 n_p, 6 n_nodes): rows 3p, 3p+1, 3p+2 = w, q₁, q₂ of point p per global DOF; gaps (n_p,) [m]
    the surface gap; warnings: one line each."""

    name: str
    points: np.ndarray
    partner_points: np.ndarray
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    operator: sp.csr_matrix
    gaps: np.ndarray
    warnings: tuple = ()
    normal_stiffness: np.ndarray | None = None
    tangential_stiffness: np.ndarray | None = None


@dataclass(frozen=True)
class ContactGeometry:
    """One named contact of the linear stage (FE): its points and frames (as
    :class:`ResolvedContact`) and its rows on the reduced coordinates, rows CSR (3 n_p, n_r):
    [w, q₁, q₂]_p = rows[3p:3p+3] q (boundary coordinates only); distances (n_p,) [m] the surface
    gap (the default gap); per-point deck spring stiffness [N/m] where a contact replaces springs.
    """

    name: str
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    rows: sp.csr_matrix
    distances: np.ndarray
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    normal_stiffness: np.ndarray | None = None
    tangential_stiffness: np.ndarray | None = None


# ------------------------------------------------------------------------------ surfaces, points
def group_triangles(case, mesh, name, path) -> np.ndarray:
    """Triangle indices of the element groups matching `name` (glob) — a ``surfaces`` entry."""
    groups = [g for g in mesh.element_groups if fnmatch.fnmatchcase(g, name)]
    if not groups:
        raise case.error(f"element group '{name}' not in mesh (available: "
                         f"{available(mesh.element_groups)})", path)
    return np.unique(np.concatenate([mesh.element_groups[g] for g in groups]))


def _sides(case, contact, mesh, surface, nodes_a, nodes_b, p):
    """Triangles of side a and side b (None: ground) — ``surfaces`` or the bodies holding the
    nodes (one body holding both: each side without the other's node ring)."""
    if contact.surfaces is not None:
        tri_a = group_triangles(case, mesh, contact.surfaces[0], p + ("surfaces", 0))
        tri_b = (None if contact.surfaces[1] == "ground" else
                 group_triangles(case, mesh, contact.surfaces[1], p + ("surfaces", 1)))
        return tri_a, tri_b
    tri_a = side_triangles(surface, nodes_a)
    if nodes_b is None:
        return tri_a, None
    tri_b = side_triangles(surface, nodes_b)
    if np.intersect1d(tri_a, tri_b).size:           # one body: keep the sides apart
        tri_a = side_triangles(surface, nodes_a, exclude=nodes_b)
        tri_b = side_triangles(surface, nodes_b, exclude=nodes_a)
    return tri_a, tri_b


def _too_far(case, distance, tolerance, subject, label, path):
    """CaseError when any distance (n,) [m] exceeds ``pairing_tolerance_m``: '<k> of <n>
    <subject> within … (farthest: <label(j)> at <d> m)'."""
    far = distance > tolerance * (1 + 1e-9) + 1e-12
    if np.any(far):
        worst = int(np.argmax(distance))
        raise case.error(f"{np.count_nonzero(far)} of {len(distance)} {subject} within "
                         f"pairing_tolerance_m = {tolerance:g} m (farthest: {label(worst)} at "
                         f"{distance[worst]:.3g} m)", path)


def _explicit_pairs(case, mesh, contact, pairs, p):
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
    return a, b


@dataclass(frozen=True)
class _Located:
    """Both sides of n_p contact points (private record of :func:`_locate`)."""

    x_a: np.ndarray
    element_a: np.ndarray
    bary_a: np.ndarray
    nodes_a: np.ndarray
    x_b: np.ndarray
    element_b: np.ndarray
    bary_b: np.ndarray
    nodes_b: np.ndarray
    ground: np.ndarray
    tri_a: np.ndarray
    tri_b: np.ndarray | None


def _locate(case, mesh, surface, contact, pairs, p) -> _Located:
    """Side a and side b of each contact point (module docstring)."""
    tolerance = contact.pairing_tolerance_m
    empty = np.zeros(0, dtype=np.int64)
    if contact.pairs is not None:
        a, b = _explicit_pairs(case, mesh, contact, pairs, p)
        tri_a, tri_b = _sides(case, contact, mesh, surface, a, b[b >= 0], p)
        el_a, l_a = node_locations(surface.triangles, a, tri_a)
        el_b, l_b = node_locations(surface.triangles, np.maximum(b, 0),
                                   tri_b if tri_b is not None else empty)
        el_b[b < 0] = -1
        x_a = surface.points[a]
        x_b = np.where(b[:, None] >= 0, surface.points[np.maximum(b, 0)], x_a)
        return _Located(x_a, el_a, l_a, a, x_b, el_b, l_b, b, b < 0, tri_a, tri_b)
    if contact.points_m is not None:
        given = np.asarray(contact.points_m, dtype=float).reshape(-1, 3)
        tri_a, tri_b = _sides(case, contact, mesh, surface, None, None, p)
        el_a, l_a, x_a, d_a = surface_locations(surface, given, tri_a)
        _too_far(case, d_a, tolerance, f"points_m have no point of surface "
                 f"'{contact.surfaces[0]}'", lambda j: f"point {j}", p + ("points_m",))
        a = surface.triangles[el_a, np.argmax(l_a, axis=1)]
        group_b = contact.surfaces[1]
    else:
        group_a, group_b = contact.between
        a = resolve_node_group(case, mesh, group_a, p + ("between", 0))
        nodes_b = (None if group_b == "ground" else
                   resolve_node_group(case, mesh, group_b, p + ("between", 1)))
        tri_a, tri_b = _sides(case, contact, mesh, surface, a, nodes_b, p)
        el_a, l_a = node_locations(surface.triangles, a, tri_a)
        x_a = surface.points[a]
        if tri_b is not None and len(tri_b) == 0:     # b's nodes are on no shell: node to node
            return _nearest_nodes(case, surface, contact, x_a, el_a, l_a, a, nodes_b, tri_a, p)
    n_p = len(x_a)
    if tri_b is None:                                 # ground
        return _Located(x_a, el_a, l_a, a, x_a.copy(), np.full(n_p, -1), np.zeros((n_p, 3)),
                        np.full(n_p, -1), np.ones(n_p, bool), tri_a, None)
    el_b, l_b, x_b, distance = surface_locations(surface, x_a, tri_b)
    if contact.points_m is not None:
        _too_far(case, distance, tolerance, f"points_m have no point of surface '{group_b}'",
                 lambda j: f"point {j}", p + ("points_m",))
    else:
        _too_far(case, distance, tolerance, f"nodes of '{contact.between[0]}' have no point of "
                 f"the surface of '{group_b}'", lambda j: f"node {a[j]}", p + ("between",))
    b = surface.triangles[el_b, np.argmax(l_b, axis=1)]
    return _Located(x_a, el_a, l_a, a, x_b, el_b, l_b, b, np.zeros(n_p, bool), tri_a, tri_b)


def _nearest_nodes(case, surface, contact, x_a, el_a, l_a, a, nodes_b, tri_a, p) -> _Located:
    """Partner nodes off the shells (a deck's mass or beam node): the nearest node of group b."""
    from scipy.spatial import cKDTree   # (scipy.spatial costs ~0.3 s to import: pairing only)

    distance, nearest = cKDTree(surface.points[nodes_b]).query(x_a)
    _too_far(case, distance, contact.pairing_tolerance_m, f"nodes of '{contact.between[0]}' "
             f"have no node of '{contact.between[1]}'", lambda j: f"node {a[j]}",
             p + ("between",))
    b = nodes_b[nearest]
    n_p = len(a)
    return _Located(x_a, el_a, l_a, a, surface.points[b], np.full(n_p, -1), np.zeros((n_p, 3)),
                    b, np.zeros(n_p, bool), tri_a, np.zeros(0, dtype=np.int64))


# ------------------------------------------------------------------------------------- normals
def _normals(case, contact, surface, at: _Located, p):
    """Unit normals (n_p, 3) from a towards b and the fit residual [deg] of the surface they came
    from (NaN where not fitted; :func:`sarfe.mesh.contact_geometry.facet_normal_residual_deg`)."""
    x_a, x_b, ground, tri_a, tri_b = at.x_a, at.x_b, at.ground, at.tri_a, at.tri_b
    n_p = len(x_a)
    residual = np.full(n_p, np.nan)
    radius = contact.patch_radius_m
    if isinstance(contact.normal, (list, tuple)):
        vector = np.asarray(contact.normal, dtype=float)
        length = np.linalg.norm(vector)
        if length == 0 or not np.isfinite(length):
            raise case.error("normal vector must be non-zero", p + ("normal",))
        return np.broadcast_to(vector / length, (n_p, 3)).copy(), residual
    direction, apart = separation_normals(x_a, x_b, COINCIDENT_M)
    apart &= ~ground
    if contact.normal == "separation":
        if not apart.all():
            j = int(np.argmin(apart))
            raise case.error(f"point {j} and its partner coincide (or the partner is the "
                             "ground): 'separation' has no direction there; give normal: "
                             "'auto' or [x, y, z]", p + ("normal",))
        return direction, residual
    normal = np.zeros((n_p, 3))
    fitted = ~ground & (tri_b is not None and len(tri_b) > 0)
    if np.any(fitted):
        tri = surface.triangles[tri_b]
        normal[fitted] = patch_normals(x_b[fitted], surface.points, tri, radius)
        residual[fitted] = facet_normal_residual_deg(x_b[fitted], surface.points, tri, radius)
    own = ~fitted & (at.element_a >= 0)
    if np.any(own):        # grounded (or partner off the shells): side a's own surface normal
        facet = facet_normals(surface.points, surface.triangles[at.element_a[own]])
        tri = surface.triangles[tri_a]
        normal[own] = patch_normals(x_a[own], surface.points, tri, radius, reference=facet)
        residual[own] = facet_normal_residual_deg(x_a[own], surface.points, tri, radius, facet)
    if not np.all(fitted | own):
        raise case.error("contact point(s) on no shell triangle have no surface normal; give "
                         "normal: [x, y, z] or 'separation'", p + ("normal",))
    normal[apart] = orient_normals(normal[apart], x_b[apart] - x_a[apart])
    touching = ~apart & ~ground
    if np.any(touching):   # coincident: from a towards b = away from a's body, into b's
        body = -body_side(surface, x_a[touching], tri_a, radius)
        if tri_b is not None and len(tri_b):
            body += body_side(surface, x_b[touching], tri_b, radius)
        side = np.einsum("ij,ij->i", normal[touching], body)
        if np.any(np.abs(side) <= 1e-6 * np.linalg.norm(body, axis=1) + 1e-15):
            raise case.error("coincident contact points between surfaces that lie in one plane: "
                             "the side a faces is not defined; give normal: [x, y, z]",
                             p + ("normal",))
        normal[touching] *= np.where(side < 0, -1.0, 1.0)[:, None]
    return normal, residual


def _warnings(contact, index, at: _Located, normal, residual, gaps) -> tuple:
    """One line per finding: a folded surface under the normal, a geometric overlap used as gap."""
    warnings = []
    bent = np.nan_to_num(residual) > NORMAL_RESIDUAL_WARN_DEG
    if np.any(bent):
        j = int(np.nanargmax(residual))
        warnings.append(
            f"contacts[{index}] ({contact.name}): the surface under {np.count_nonzero(bent)} of "
            f"{len(gaps)} point(s) is folded (facets leave the fitted surface by up to "
            f"{residual[j]:.0f}° at point {j}, {np.round(at.x_b[j], 4).tolist()} m: an edge, "
            "ridge or junction): its normal depends on the mesh; give normal: [x, y, z]")
    if (contact.gap_m is None and contact.preload_N is None
            and np.any((gaps < 0) & ~at.ground)):
        j = int(np.argmin(np.where(at.ground, np.inf, gaps)))
        mid = float(normal[j] @ (at.x_b[j] - at.x_a[j]))
        warnings.append(
            f"contacts[{index}] ({contact.name}): the facing surfaces overlap by "
            f"{-gaps[j] * 1e3:.3g} mm in the mesh (point {j}: mid-surfaces {mid * 1e3:.3g} mm "
            "apart, less the half thicknesses): the contact starts closed with that "
            "interference; give gap_m (the clearance between the surfaces) or preload_N")
    return tuple(warnings)


def resolve_contact(case, mesh, index, surface: ShellSurface, pairs=None) -> ResolvedContact:
    """Points, frames, rows and surface gaps of contacts[index] (module docstring). ``pairs``:
    explicit pairs as mesh node indices when the case gives them in other numbers (a deck's GRID
    ids: :func:`sarfe.pipeline.model.deck_model.grid_pairs`). Errors: one-line CaseErrors naming
    the key."""
    contact = case.config.contacts[index]
    p = ("contacts", index)
    at = _locate(case, mesh, surface, contact, pairs, p)
    normal, residual = _normals(case, contact, surface, at, p)
    radius = contact.patch_radius_m
    x_a = point_coordinates(surface, at.element_a, at.bary_a, at.x_a)
    ns_a = offset_normals(surface, x_a, at.element_a, at.tri_a, radius)
    w_a, z_a = side_motion(surface, at.element_a, at.bary_a, normal, ns_a, nodes=at.nodes_a)
    face_a = face_points(x_a, z_a, ns_a)
    ground = at.ground
    if ground.all():
        w_b, face_b = None, face_a
    else:
        tri = at.tri_b if at.tri_b is not None else np.zeros(0, dtype=np.int64)
        ns_b = offset_normals(surface, at.x_b, at.element_b, tri, radius)
        w_b, z_b = side_motion(surface, at.element_b, at.bary_b, -normal, ns_b,
                               nodes=np.maximum(at.nodes_b, 0))
        w_b = sp.diags(np.repeat(~ground, 3).astype(float)) @ w_b
        face_b = face_points(at.x_b, z_b, ns_b)
    gaps = np.where(ground, 0.0, np.einsum("ij,ij->i", normal, face_b - face_a))
    frames = frames_from_normals(normal)
    rows = contact_rows(frames, w_a, w_b)
    if not laws.uses_tangent(laws.law(contact.kind), contact.params):
        rows = normal_rows_only(rows)
    return ResolvedContact(contact.name, x_a, at.x_b, at.nodes_a,
                           np.where(ground, -1, at.nodes_b), frames, rows, gaps,
                           _warnings(contact, index, at, normal, residual, gaps))


def normal_rows_only(rows: sp.csr_matrix) -> sp.csr_matrix:
    """G (3 n_p, n_dof) with the tangent rows 3p+1, 3p+2 emptied: a law without a tangent element
    (rattle) uses only w, so its Craig–Bampton boundary is only what moves w."""
    keep = np.zeros(rows.shape[0])
    keep[::3] = 1.0
    out = sp.csr_matrix(sp.diags(keep) @ rows)
    out.eliminate_zeros()
    return out


def spring_contact(name, spring, surface: ShellSurface) -> ResolvedContact:
    """A contact made of deck springs (:class:`sarfe.pipeline.model.deck_springs.ElementContact`):
    node to node at the grid points (where the deck's element connects them), along the spring
    axis; the gap is the grid points' distance along it (0 to ground)."""
    a, b = spring.nodes_a, spring.nodes_b
    n = surface.n_nodes
    w_a = node_translations(a, n)
    w_b = sp.diags(np.repeat(b >= 0, 3).astype(float)) @ node_translations(np.maximum(b, 0), n)
    x_a = surface.points[a]
    x_b = np.where(b[:, None] >= 0, surface.points[np.maximum(b, 0)], x_a)
    gaps = np.einsum("ij,ij->i", spring.frames[:, 0], x_b - x_a)
    return ResolvedContact(name, x_a, x_b, a, b, spring.frames,
                           contact_rows(spring.frames, w_a, w_b), gaps,
                           normal_stiffness=spring.normal_stiffness,
                           tangential_stiffness=spring.tangential_stiffness)


def node_pairs(resolved: dict) -> dict:
    """{name: (nodes_a (n_p,), nodes_b (n_p,), −1 for ground)}: each contact point's node on
    either side (the node it lies at, or the nearest of its element) — what the input checks
    (shared pairs, held pairs, element quality at joined nodes) name."""
    return {name: (r.nodes_a, r.nodes_b) for name, r in resolved.items()}


# -------------------------------------------------------------------------- reduced coordinates
def boundary_dofs(resolved: dict) -> np.ndarray:
    """Global DOFs (6·node + component) that the rows of the contacts {name: ResolvedContact}
    touch: the contact points' element nodes, rotations where the face offset or the bending
    interpolation moves a point — the Craig–Bampton boundary of the contacts."""
    touched = [np.unique(r.operator.indices) for r in resolved.values()]
    return np.unique(np.concatenate(touched + [np.zeros(0, dtype=np.int64)])).astype(np.int64)


def contact_geometry(resolved: dict, boundary_global, n_r: int) -> dict:
    """{name: ContactGeometry}: each contact's rows on the reduced coordinates q = [q_b, q_m]
    (``boundary_global`` (n_b,): the global DOF of each boundary coordinate, in order). Columns
    of DOFs held fixed drop out (u = 0); every other touched DOF is on the boundary
    (:func:`boundary_dofs`)."""
    boundary_global = np.asarray(boundary_global, dtype=np.int64)
    out = {}
    for name, r in resolved.items():
        kept = r.operator.tocsc()[:, boundary_global]
        rows = sp.hstack([kept, sp.csr_matrix((kept.shape[0], n_r - len(boundary_global)))])
        out[name] = ContactGeometry(name, r.nodes_a, r.nodes_b, r.frames, rows.tocsr(), r.gaps,
                                    r.points, r.normal_stiffness, r.tangential_stiffness)
    return out


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


__all__ = ["NORMAL_RESIDUAL_WARN_DEG", "COINCIDENT_M", "ResolvedContact", "ContactGeometry",
           "group_triangles", "resolve_contact", "normal_rows_only", "node_pairs", "spring_contact", "boundary_dofs",
           "contact_geometry", "reduced_coordinates"]
