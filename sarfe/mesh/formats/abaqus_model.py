"""Abaqus parts and instances flattened into a :class:`sarfe.mesh.formats.deck.DeckModel`.

:func:`build_deck_model` takes what :mod:`sarfe.mesh.formats.abaqus`'s reader collected (scopes
of labels, sets, sections, springs, masses; instances with their placement x' = a + R_ab(θ)(x + t
− a); supports and concentrated loads) and numbers it globally: instance k's labels become
``k·10^d + label``, sets of a part are named ``<instance>.<set>``. Shells become triangles (S4:
two, S8R: six on its corner and midside nodes) with the isotropic plane-stress sections

    A = t Q,  D = t³/12 Q,  Q = E/(1 − ν²) [[1, ν, 0], [ν, 1, 0], [0, 0, (1 − ν)/2]],

mass per area ρ t and rotary inertia ρ t³/12 (in the file's units). Beams (B31, B32, B32R):
:mod:`sarfe.mesh.formats.abaqus_beams`.
"""
from __future__ import annotations

import math

import numpy as np

from sarfe.mesh.formats.abaqus_beams import BEAM_NODES, beam_table
from sarfe.mesh.formats.deck import DeckError, DeckModel, PointMasses, ShellElements, SpringElements, SupportSet

# nodes per element of the element types read: shells, point elements (springs, masses)
SHELL_NODES = {"S3": 3, "S3R": 3, "S4": 4, "S4R": 4, "S8R": 8}
POINT_ELEMENT_NODES = {"SPRING1": 1, "SPRING2": 2, "MASS": 1}
# S8R (corners 0-3, midsides 4-7 on edges 01, 12, 23, 30) → six linear triangles
_S8R_TRIANGLES = np.array([[0, 4, 7], [4, 1, 5], [5, 2, 6], [7, 6, 3], [4, 5, 6], [4, 6, 7]])


def rotation_matrix(axis_a, axis_b, angle_deg):
    """Rodrigues rotation matrix about the axis a → b by angle_deg (right-handed)."""
    axis = np.asarray(axis_b, float) - np.asarray(axis_a, float)
    norm = np.linalg.norm(axis)
    if norm == 0.0:
        raise ValueError("rotation axis points a and b coincide")
    k = axis / norm
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    t = math.radians(angle_deg)
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def build_deck_model(reader) -> DeckModel:
    """Flatten parts and instances into global numbered arrays."""
    placements = ([(reader.model, None)] if not reader.instances else
                  [(inst.scope, inst) for inst in reader.instances] + [(reader.assembly, None)])
    node_ids, points, index_of = [], [], {}
    scoped = []   # (scope, offset, resolve node ref → global id)
    for scope, inst in placements:
        offset = inst.offset if inst else (len(reader.instances) * reader.label_base
                                           if reader.instances else 0)
        labels = np.array(list(scope.nodes), dtype=np.int64)
        xyz = np.array(list(scope.nodes.values()), dtype=float).reshape(-1, 3)
        if inst is not None:
            xyz = xyz + inst.translation
            if isinstance(inst.rotation, tuple):
                a, b, angle = inst.rotation
                xyz = a + (xyz - a) @ rotation_matrix(a, b, angle).T
        for label in labels + offset:
            index_of[int(label)] = len(index_of)
        node_ids.append(labels + offset)
        points.append(xyz)
        scoped.append((scope, offset, inst))
    node_ids = np.concatenate(node_ids) if node_ids else np.zeros(0, np.int64)
    points = np.concatenate(points) if points else np.zeros((0, 3))

    def global_node(ref, scope, offset, where):
        """Global node id of a node reference ('12' or, at assembly level, 'inst.12')."""
        text = str(ref)
        if "." in text and reader.instances:
            inst_name, _, label = text.rpartition(".")
            inst = next((i for i in reader.instances if i.name.upper() == inst_name.upper()), None)
            if inst is None:
                raise DeckError(f"{where}: no instance {inst_name!r} for node {text!r}")
            value = inst.offset + int(label)
        else:
            value = offset + int(text)
        if value not in index_of:
            raise DeckError(f"{where}: node {text} is not defined")
        return value

    offsets = {inst.name.upper(): inst.offset for inst in reader.instances}

    def set_ids(labels, offset):
        """Global ids of set entries: labels of the scope, or (instance | None, label)."""
        return np.unique(np.array([offsets[e[0]] + e[1] if isinstance(e, tuple) and e[0]
                                   else offset + (e[1] if isinstance(e, tuple) else e)
                                   for e in labels], dtype=np.int64))

    # sets (node sets as indices, element sets as ids), qualified with the instance name
    node_sets, element_sets = {}, {}
    for scope, offset, inst in scoped:
        prefix = f"{inst.name}." if inst is not None else ""
        for name, labels in scope.nsets.values():
            ids = set_ids(labels, offset)
            missing = [int(i) for i in ids if int(i) not in index_of]
            if missing:
                raise DeckError(f"{reader.path}: *NSET {name}: node {missing[0]} is not defined")
            node_sets[prefix + name] = np.array([index_of[int(i)] for i in ids], dtype=np.int64)
        for name, labels in scope.elsets.values():
            element_sets[prefix + name] = set_ids(labels, offset)

    # elements
    shell_rows, spring_rows, mass_rows, beam_rows = [], [], [], []
    for scope, offset, inst in scoped:
        section_of, spring_of, mass_of = {}, {}, {}
        beam_of = _beam_sections(scope, reader.materials)
        elsets = {key: {e[1] if isinstance(e, tuple) else e for e in labels}
                  for key, (_, labels) in scope.elsets.items()}
        for elset, material, thickness, where in scope.sections:
            if elset.upper() not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            elset = elset.upper()
            mat = reader.materials.get(material)
            if mat is None:
                raise DeckError(f"{where}: no *MATERIAL {material!r}")
            for key in ("E", "nu"):
                if key not in mat:
                    raise DeckError(f"{mat['where']}: material {material!r} has no isotropic "
                                    "*ELASTIC (E, ν)")
            for label in elsets[elset]:
                section_of[label] = (mat["E"], mat["nu"], mat.get("rho", 0.0), thickness)
        for elset, dofs, k, where in scope.springs:
            if elset not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            for label in elsets[elset]:
                spring_of[label] = (dofs, k, where)
        for elset, mass, where in scope.masses:
            if elset not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            for label in elsets[elset]:
                mass_of[label] = mass
        nodal_t = {}                       # *NODAL THICKNESS: node index → t
        for ref, t, where in scope.nodal_thickness:
            if str(ref).rpartition(".")[2].isdigit():
                targets = [index_of[global_node(ref, scope, offset, where)]]
            elif str(ref).upper() in scope.nsets:
                targets = [index_of[global_node(n, scope, offset, where)]
                           for n in scope.nsets[str(ref).upper()][1]]
            else:
                raise DeckError(f"{where}: no node set {ref!r}")
            nodal_t.update(dict.fromkeys(targets, t))
        for label, kind, refs, where in scope.elements:
            nodes = [index_of[global_node(r, scope, offset, where)] for r in refs]
            element_id = offset + label
            if kind in BEAM_NODES:
                if label not in beam_of:
                    raise DeckError(f"{where}: beam element {label} has no *BEAM SECTION")
                if any(n in nodal_t for n in nodes):
                    raise DeckError(f"{where}: beam element {label}: *NODAL THICKNESS on a beam's "
                                    "node (a tapered beam) is not supported")
                beam_rows.append((element_id, kind, nodes, beam_of[label]))
            elif kind in SHELL_NODES:
                if label not in section_of:
                    raise DeckError(f"{where}: shell element {label} has no *SHELL SECTION")
                section = section_of[label]
                if section[3] is None:        # NODAL THICKNESS: the mean of its nodes' values
                    missing = [n for n in nodes if n not in nodal_t]
                    if missing:
                        raise DeckError(f"{where}: element {label}: node {int(node_ids[missing[0]])}"
                                        " has no *NODAL THICKNESS (its section asks for one)")
                    section = section[:3] + (float(np.mean([nodal_t[n] for n in nodes])),)
                shell_rows.append((element_id, kind, nodes, section))
            elif kind == "MASS":
                if label not in mass_of:
                    raise DeckError(f"{where}: MASS element {label} has no *MASS")
                mass_rows.append((element_id, nodes[0], mass_of[label]))
            else:
                if label not in spring_of:
                    raise DeckError(f"{where}: spring element {label} has no *SPRING")
                dofs, k, swhere = spring_of[label]
                if kind == "SPRING2" and (len(dofs) != 2 or dofs[0] != dofs[1]):
                    raise DeckError(f"{swhere}: SPRING2 between different DOFs {dofs} is not "
                                    "supported (same DOF at both ends)")
                if not 1 <= dofs[0] <= 6:
                    raise DeckError(f"{swhere}: DOF {dofs[0]} outside 1..6")
                spring_rows.append((element_id, kind, nodes[0],
                                    nodes[1] if kind == "SPRING2" else -1, dofs[0] - 1, k))

    top = len(reader.instances) * reader.label_base if reader.instances else 0

    def node_index(text, where):
        return index_of[global_node(text, None, top, where)]

    deck_path = str(reader.path)
    supports = {}
    if reader.boundary:
        held = np.zeros((len(node_ids), 6), dtype=bool)
        for ref, components, where in reader.boundary:
            for node in _node_reference(ref, node_sets, node_index, where):
                held[node, np.array(components) - 1] = True
        nodes = np.flatnonzero(held.any(axis=1))
        supports["boundary"] = SupportSet(nodes, held[nodes])
    loads = {}
    for name, ref, dof, value, where in reader.cloads:
        table = loads.setdefault(name, np.zeros((len(node_ids), 6)))
        for node in _node_reference(ref, node_sets, node_index, where):
            table[node, dof - 1] += value

    return DeckModel(
        source=deck_path, node_ids=node_ids, points=points,
        displacement_frames=np.broadcast_to(np.eye(3), (len(node_ids), 3, 3)).copy(),
        shells=_shell_table(shell_rows, points), beams=beam_table(beam_rows),
        springs=_spring_table(spring_rows),
        point_masses=_mass_table(mass_rows), supports=supports, loads=loads,
        node_sets=node_sets, element_sets=element_sets,
        unsupported=dict(reader.unsupported), ignored=dict(reader.ignored),
        unsupported_where=dict(reader.unsupported_where))


def _beam_sections(scope, materials):
    """{element label: (E, ν, ρ, section, dims, direction 1, where)} of a scope's
    ``*BEAM SECTION`` lines."""
    elsets = {key: {e[1] if isinstance(e, tuple) else e for e in labels}
              for key, (_, labels) in scope.elsets.items()}
    beam_of = {}
    for elset, material, kind, dims, direction, where in scope.beam_sections:
        if elset.upper() not in elsets:
            raise DeckError(f"{where}: no element set {elset!r}")
        mat = materials.get(material)
        if mat is None or "E" not in mat or "nu" not in mat:
            raise DeckError(f"{where}: no *MATERIAL {material!r} with an isotropic *ELASTIC (E, ν)")
        for label in elsets[elset.upper()]:
            beam_of[label] = (mat["E"], mat["nu"], mat.get("rho", 0.0), kind, dims, direction, where)
    return beam_of


def _node_reference(ref, node_sets, node_index, where):
    """Node indices of a *BOUNDARY/*CLOAD reference: a node label ('12', 'Inst-1.12') or the
    name of a node set (case-insensitive, 'Inst-1.Set' for a part's set)."""
    text = str(ref)
    if text.rpartition(".")[2].isdigit():
        return [node_index(text, where)]
    for name, nodes in node_sets.items():
        if name.upper() == text.upper():
            return list(nodes)
    raise DeckError(f"{where}: no node set {text!r}")


def _shell_table(rows, points) -> ShellElements:
    if not rows:
        return ShellElements()
    ids, triangles, owner, sections = [], [], [], []
    for row, (element_id, kind, nodes, section) in enumerate(rows):
        nodes = np.asarray(nodes, dtype=np.int64)
        if kind in ("S3", "S3R"):
            local = nodes[None, :]
        elif kind in ("S4", "S4R"):
            local = nodes[[[0, 1, 2], [0, 2, 3]]]
        else:
            local = nodes[_S8R_TRIANGLES]
        ids.append(element_id)
        triangles.append(local)
        owner.extend([row] * len(local))
        sections.extend([section] * len(local))
    triangles = np.concatenate(triangles)
    young, poisson, density, thickness = (np.array(v, dtype=float) for v in zip(*sections))
    q = (young / (1 - poisson**2))[:, None, None] * np.stack([
        np.stack([np.ones_like(poisson), poisson, 0 * poisson], axis=-1),
        np.stack([poisson, np.ones_like(poisson), 0 * poisson], axis=-1),
        np.stack([0 * poisson, 0 * poisson, (1 - poisson) / 2], axis=-1)], axis=1)
    edge = points[triangles[:, 1]] - points[triangles[:, 0]]
    length = np.linalg.norm(edge, axis=1, keepdims=True)
    axis = np.divide(edge, length, out=np.zeros_like(edge), where=length > 0)
    return ShellElements(
        element_ids=np.array(ids, dtype=np.int64), property_ids=np.zeros(len(ids), np.int64),
        triangles=triangles, triangle_element=np.array(owner, dtype=np.int64),
        membrane=thickness[:, None, None] * q, coupling=np.zeros_like(q),
        bending=(thickness**3 / 12)[:, None, None] * q,
        transverse_shear=np.zeros((len(triangles), 2, 2)), material_axis=axis,
        mass_per_area=density * thickness, rotary_inertia_per_area=density * thickness**3 / 12,
        thickness=thickness, offset=np.zeros(len(triangles)))


def _spring_table(rows) -> SpringElements:
    if not rows:
        return SpringElements()
    ids, cards, a, b, component, k = zip(*rows)
    stiffness = np.zeros((len(rows), 6))
    stiffness[np.arange(len(rows)), component] = k
    return SpringElements(
        card=np.array(cards), element_ids=np.array(ids, dtype=np.int64),
        property_ids=np.zeros(len(rows), np.int64), node_a=np.array(a, dtype=np.int64),
        node_b=np.array(b, dtype=np.int64), stiffness=stiffness,
        frames=np.broadcast_to(np.eye(3), (len(rows), 3, 3)).copy(),
        structural_damping=np.zeros(len(rows)), viscous_damping=np.zeros((len(rows), 6)),
        location=np.full(len(rows), np.nan))       # scalar springs on the node DOFs


def _mass_table(rows) -> PointMasses:
    if not rows:
        return PointMasses()
    ids, nodes, mass = zip(*rows)
    return PointMasses(element_ids=np.array(ids, dtype=np.int64),
                       node=np.array(nodes, dtype=np.int64), mass=np.array(mass, dtype=float),
                       offset=np.zeros((len(rows), 3)), inertia=np.zeros((len(rows), 3, 3)))

