"""Nastran shell sections and shell elements → `ShellElements` (part of `sarfe.mesh.formats.nastran`).

Functions take the reader (`sarfe.mesh.formats.nastran`'s converter: the cross-referenced pyNastran
model, node indices, CD frames, ``fail`` for one-line DeckErrors, ``notes``).

PSHELL: A = T·Q(MID1), D = 12I/T³ · T³/12 · Q(MID2), transverse shear TS/T · T · G(MID3),
mass T ρ(MID1) + NSM, rotary inertia ρ T³/12. PCOMP: classical lamination theory
(`sarfe.mesh.laminate`) about the laminate's mid-plane, LAM = SYM mirrored. Offsets
(ZOFFS, PCOMP Z0 + T/2) move the section to the node plane: B = B_mid + o A,
D = D_mid + 2 o B_mid + o² A. Element axes: CTRIA3/6 x along G1→G2, CQUAD4/8 x bisecting
the diagonals; THETA rotates it about the normal, MCID projects that system's x on the plane.
Facets: CQUAD4 → 2 triangles; CTRIA6 → 4 and CQUAD8 → 6 flat triangles through the midside
nodes (the facet shell has no quadratic element: the midside nodes stay in the model).
"""
from __future__ import annotations

import numpy as np

from sarfe.mesh.formats.deck import ShellElements
from sarfe.mesh.laminate import (isotropic_plane_stress, laminate_stiffness, orthotropic_plane_stress,
                       rotate_transverse_shear)

__all__ = ["shells", "plane_stress", "isotropic", "shell_section", "laminate_section"]

def plane_stress(reader, mid, card, eid):
    """(Q (3,3) [Pa], transverse shear G (2,2) [Pa], density) of a MAT1/MAT2/MAT8."""
    mat = reader.model.materials.get(int(mid))
    if mat is None:
        reader.fail(card, eid, f"material {mid} is missing or not structural")
    rho = float(mat.rho or 0.0)
    if mat.type == "MAT1":
        q = isotropic_plane_stress(mat.e, mat.nu, mat.g)
        return q, float(mat.g) * np.eye(2), rho
    if mat.type == "MAT8":
        q = orthotropic_plane_stress(mat.e11, mat.e22, mat.nu12, mat.g12)
        g1z = mat.g1z if mat.g1z else mat.g12
        g2z = mat.g2z if mat.g2z else mat.g12
        return q, np.diag([float(g1z), float(g2z)]), rho
    if mat.type == "MAT2":
        q = np.array([[mat.G11, mat.G12, mat.G13], [mat.G12, mat.G22, mat.G23],
                      [mat.G13, mat.G23, mat.G33]], float)
        return q, np.zeros((2, 2)), rho
    reader.fail(card, eid, f"material {mat.type} {mid} is not supported for this property")

def isotropic(reader, mid, card, eid):
    mat = reader.model.materials.get(int(mid))
    if mat is None or mat.type != "MAT1":
        reader.fail(card, eid, f"material {mid} must be a MAT1")
    return float(mat.e), float(mat.nu), float(mat.g), float(mat.rho or 0.0)


def shell_section(reader, prop):
    """Per property: A, B, D, Gt (2,2), mass/area, rotary inertia/area, thickness."""
    pid = prop.pid
    if prop.type == "PSHELL":
        t = float(prop.t or 0.0)
        if not prop.mid1 or t <= 0.0:
            reader.fail("PSHELL", pid, "needs MID1 and a thickness T > 0 (membrane-less "
                      "shells are not modelled)")
        if prop.mid4:
            reader.fail("PSHELL", pid, "MID4 (membrane-bending coupling) is not modelled")
        q1, _, rho = plane_stress(reader, prop.mid1, "PSHELL", pid)
        a = q1 * t
        d = np.zeros((3, 3))
        if prop.mid2 and prop.mid2 > 0:
            q2, _, _ = plane_stress(reader, prop.mid2, "PSHELL", pid)
            d = q2 * float(prop.twelveIt3) * t**3 / 12.0
        elif prop.mid2 not in (None, 0):
            reader.fail("PSHELL", pid, f"MID2 = {prop.mid2} (plane strain) is not modelled")
        shear = np.zeros((2, 2))
        if prop.mid3:
            _, g3, _ = plane_stress(reader, prop.mid3, "PSHELL", pid)
            shear = g3 * float(prop.tst) * t
        if rho == 0.0:
            reader.notes.append(f"PSHELL {pid}: material {prop.mid1} has no density (ρ = 0)")
        mass = rho * t + float(prop.nsm or 0.0)
        return a, np.zeros((3, 3)), d, shear, mass, rho * t**3 / 12.0, t, 0.0
    if prop.type == "PCOMP":
        return laminate_section(reader, prop)
    reader.fail("shell property", pid, f"{prop.type} is not supported")

def laminate_section(reader, prop):
    pid = prop.pid
    mids, thick, angles = list(prop.mids), list(prop.thicknesses), list(prop.thetas)
    if str(prop.lam).upper() == "SYM":
        mids, thick, angles = mids + mids[::-1], thick + thick[::-1], angles + angles[::-1]
    elif prop.lam not in (None, "", "BLANK"):
        reader.fail("PCOMP", pid, f"LAM = {prop.lam} is not modelled")
    thick = np.array(thick, float)
    total = float(thick.sum())
    z0 = -total / 2.0 if prop.z0 is None else float(prop.z0)
    top = -total / 2.0 + np.cumsum(thick)  # about the laminate's mid-plane; Z0 → offset
    bottom = top - thick
    mats = [plane_stress(reader, mid, "PCOMP", pid) for mid in mids]
    q = np.array([m[0] for m in mats])
    angle = np.radians(np.array(angles, float))
    a, b, d = laminate_stiffness(q, angle, bottom, top)
    g = rotate_transverse_shear(np.array([m[1] for m in mats]), angle)
    shear = np.einsum("k,kij->ij", thick, g)
    rho = np.array([m[2] for m in mats])
    mass = float(rho @ thick) + float(prop.nsm or 0.0)
    rotary = float(rho @ ((top**3 - bottom**3) / 3.0))
    return a, b, d, shear, mass, rotary, total, z0 + total / 2.0

#: facet triangles of each shell card, as local node positions (corners, then midsides):
#: CTRIA6 and CQUAD8 are divided through their midside nodes (4 and 6 flat triangles)
SUBDIVISION = {
    "CTRIA3": [[0, 1, 2]],
    "CQUAD4": [[0, 1, 2], [0, 2, 3]],
    "CTRIA6": [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]],
    "CQUAD8": [[0, 4, 7], [4, 1, 5], [5, 2, 6], [6, 3, 7], [4, 5, 6], [4, 6, 7]],
}
_CORNERS = {"CTRIA3": 3, "CQUAD4": 4, "CTRIA6": 3, "CQUAD8": 4}
#: shells read as another card: CTRIAR/CQUADR (drilling stiffness) as CTRIA3/CQUAD4, whose
#: membranes carry the drilling rotation in sarfe
ALIASES = {"CTRIAR": "CTRIA3", "CQUADR": "CQUAD4"}


def shells(reader) -> ShellElements:
    model = reader.model
    eids = [e for e, el in sorted(model.elements.items())
            if ALIASES.get(el.type, el.type) in SUBDIVISION]
    if not eids:
        return ShellElements()
    sections = {}
    nodes_all = np.full((len(eids), 8), -1, dtype=np.int64)
    kinds = []
    pids, zoffs, thetas, mcids = [], [], np.zeros(len(eids)), {}
    for row, eid in enumerate(eids):  # card fields only; geometry is vectorized below
        el = model.elements[eid]
        if any(n in (None, 0) for n in el.node_ids):
            reader.fail(el.type, eid, "midside nodes partly given: not modelled")
        nodes = [reader.node(n, el.type, eid) for n in el.node_ids]
        nodes_all[row, :len(nodes)] = nodes
        kinds.append(ALIASES.get(el.type, el.type))
        nodes = nodes[:_CORNERS[kinds[-1]]]
        zoffs.append(float(el.zoffset or 0.0))
        prop = el.pid_ref
        if prop.pid not in sections:
            sections[prop.pid] = shell_section(reader, prop)
        t_prop = sections[prop.pid][6]
        corner_t = [getattr(el, f"T{i}", None) for i in range(1, len(nodes) + 1)]
        if getattr(el, "tflag", 0) or any(
                tc not in (None, -1.0) and abs(float(tc) - t_prop) > 1e-9 * t_prop
                for tc in corner_t):
            reader.fail(el.type, eid, "corner thicknesses T1–T4 different from the "
                      "property's T are not modelled")
        if isinstance(el.theta_mcid, int):
            mcids[row] = el.theta_mcid
        elif el.theta_mcid:
            thetas[row] = np.radians(float(el.theta_mcid))
        pids.append(prop.pid)
    kinds = np.array(kinds)
    quad = np.isin(kinds, ["CQUAD4", "CQUAD8"])
    corners = np.where(quad[:, None], nodes_all[:, :4], np.column_stack([nodes_all[:, :3],
                                                                          nodes_all[:, :1]]))
    x = reader.points[corners]  # (m, 4, 3)
    # element axes: triangles x along G1→G2; quadrilaterals x bisects the diagonals' angle
    d13, d24 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
    with np.errstate(invalid="ignore", divide="ignore"):  # zero area: refused at assembly
        normal = np.where(quad[:, None], np.cross(d13, d24),
                          np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]))
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        bisector = (d13 / np.linalg.norm(d13, axis=1)[:, None]
                    - d24 / np.linalg.norm(d24, axis=1)[:, None])
        axis = np.where(quad[:, None], bisector, x[:, 1] - x[:, 0])
        axis /= np.linalg.norm(axis, axis=1)[:, None]
    axis = (np.cos(thetas)[:, None] * axis
            + np.sin(thetas)[:, None] * np.cross(normal, axis))  # THETA about the normal
    for row, mcid in mcids.items():  # MCID: x of that system projected on the plane
        xm = reader.coord_axes(mcid, x[row].mean(axis=0))[0]
        projected = xm - normal[row] * (xm @ normal[row])
        if np.linalg.norm(projected) < 1e-8:
            reader.fail(model.elements[eids[row]].type, eids[row],
                      f"MCID {mcid} axis is normal to the element")
        axis[row] = projected / np.linalg.norm(projected)
    rows = np.arange(len(eids))
    tri_nodes, tri_elem = [], []
    for kind, pattern in SUBDIVISION.items():
        pick = kinds == kind
        for local in pattern:
            tri_nodes.append(nodes_all[pick][:, local])
            tri_elem.append(rows[pick])
    tri_nodes, tri_elem = np.concatenate(tri_nodes), np.concatenate(tri_elem)
    order = np.argsort(tri_elem, kind="stable")  # an element's triangles side by side
    tri_nodes, tri_elem = tri_nodes[order], tri_elem[order]
    pids = np.array(pids, dtype=np.int64)
    keys = sorted(sections)
    table = [np.array([sections[k][i] for k in keys], float) for i in range(8)]
    which = np.searchsorted(keys, pids[tri_elem])
    a, b_mid, d_mid = table[0][which], table[1][which], table[2][which]
    # mid-surface offset from the node plane: ZOFFS + the laminate's own (PCOMP Z0 + T/2);
    # section about the node plane: B = B_mid + o A, D = D_mid + 2 o B_mid + o² A
    offset = np.array(zoffs)[tri_elem] + table[7][which]
    o = offset[:, None, None]
    return ShellElements(
        element_ids=np.array(eids, dtype=np.int64), property_ids=pids,
        triangles=tri_nodes, triangle_element=tri_elem,
        membrane=a, coupling=b_mid + o * a, bending=d_mid + 2 * o * b_mid + o**2 * a,
        transverse_shear=table[3][which], material_axis=axis[tri_elem],
        mass_per_area=table[4][which] * reader.wtmass,
        rotary_inertia_per_area=table[5][which] * reader.wtmass,
        thickness=table[6][which], offset=offset)
