"""Validation that needs the mesh (or the deck, or the matrix files) but no assembly: the groups
exist, the contacts pair, the elements are sound.

    check_mesh(case) -> info     {nodes, triangles, contact_pairs, coincident nodes} (FE), {} else
    check_deck(case) -> info     a deck case: cards, groups, quality, supports, pairing
    check_shared_pairs(case, paired, points)   one node pair in two contacts: an error

Errors are one-line CaseErrors naming the key (or the element); the fuller pre-solve checks of
``sarfe solve`` / ``sarfe validate`` are :func:`sarfe.pipeline.checks.case_checks.check_case`.
"""
from __future__ import annotations

import numpy as np

from sarfe.case.read import load_case
from sarfe.erp import nodal_normals
from sarfe.mesh import quality
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_pairs import pair_contact
from sarfe.pipeline.model.deck_model import prepare_deck
from sarfe.pipeline.model.deck_stage import contact_pairs
from sarfe.pipeline.model.erp_map import deck_surface_triangles, surface_triangles
from sarfe.pipeline.model.groups import fixed_nodes, resolve_node_group, shell_properties
from sarfe.pipeline.model.matrices_stage import build_matrices_stage


def check_mesh(case) -> dict:
    """Validation that needs the mesh but no assembly: groups exist, contacts pair. Returns info."""
    case = load_case(case)
    if not case.is_fe:
        build_matrices_stage(case)
        return {}
    config = case.config
    if config.model.fe.is_deck:
        return check_deck(case)
    mesh = load_case_mesh(case)
    fixed_nodes(case, mesh)
    shell_properties(case, mesh)
    normals = nodal_normals(mesh.points, mesh.triangles)
    paired = [pair_contact(case, mesh, c.index, normals) for c in config.contacts]
    check_shared_pairs(case, {c.name: p for c, p in zip(config.contacts, paired)}, mesh.points)
    pairs = {c.name: len(p[0]) for c, p in zip(config.contacts, paired)}
    coincident = mesh_quality(case, mesh, [(a, b) for a, b, _, _ in paired])
    for i, f in enumerate(config.excitation.forces):
        resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
    surface_triangles(case, mesh)     # erp.surface: an element group, or a node group's triangles
    return {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles, "contact_pairs": pairs,
            "coincident_node_pairs": len(coincident), "coincident_nodes": coincident[:50]}


def check_shared_pairs(case, paired: dict, points) -> None:
    """One node pair in two contacts (or twice in one) is a CaseError naming both contacts and
    where the first such pair sits: two laws at one pair add their forces (twice the stiffness,
    twice the friction), which is never what overlapping node groups mean — split the groups
    or drop the pair from one contact. ``paired``: {contact name: (a (n_p,), b (n_p,) with −1
    for ground, …)}; a pair is unordered (a–b = b–a); ``points`` (n, 3) [m]."""
    contacts = case.config.contacts
    a = [np.asarray(paired[c.name][0], dtype=np.int64) for c in contacts]
    b = [np.asarray(paired[c.name][1], dtype=np.int64) for c in contacts]
    if not a or sum(x.size for x in a) == 0:
        return
    a, b = np.concatenate(a), np.concatenate(b)
    owner = np.repeat(np.arange(len(contacts)), [len(paired[c.name][0]) for c in contacts])
    ground = b < 0
    low = np.where(ground, a, np.minimum(a, b))
    high = np.where(ground, -1, np.maximum(a, b))
    keys = np.stack([low, high], axis=1)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    repeated = np.flatnonzero(first[inverse.ravel()] != np.arange(len(keys)))
    if not repeated.size:
        return
    k = repeated[0]
    j = first[inverse.ravel()[k]]
    one, other = contacts[owner[j]], contacts[owner[k]]
    x, y, z = np.asarray(points)[a[k]]
    pair = f"{a[k]}–{'ground' if b[k] < 0 else b[k]}"
    also = (f"also in contacts[{one.index}] ({one.name})" if one.index != other.index
            else "listed twice in this contact")
    raise case.error(f"node pair {pair} at ({x:.4g}, {y:.4g}, {z:.4g}) m is {also} "
                     f"({repeated.size} shared pair(s)): two contact laws at one node pair add "
                     "their forces (twice the stiffness and friction); split the node groups or "
                     "drop the pair from one contact", ("contacts", other.index))


def mesh_quality(case, mesh, contact_pairs):
    """Duplicate and zero-area triangles are errors (0-based triangle indices); coincident nodes
    that no contact pairs are returned (0-based node indices) for validate to list."""
    where = case.config.model.fe.where
    index = np.arange(mesh.n_triangles)
    duplicates = quality.duplicate_elements(mesh.triangles, index)
    if duplicates:
        text = ", ".join(f"{b} (= {a})" for a, b in duplicates[:10])
        raise case.error(f"{len(duplicates)} duplicate triangle(s) on the same nodes (0-based "
                         f"indices): {text}", where)
    degenerate = quality.degenerate_elements(mesh.points, mesh.triangles, index)
    if degenerate:
        raise case.error(f"{len(degenerate)} zero-area triangle(s) (0-based indices): "
                         f"{', '.join(map(str, degenerate[:10]))}", where)
    joined = [(int(a), int(b)) for pa, pb in contact_pairs for a, b in zip(pa, pb) if b >= 0]
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    return [list(p) for p in quality.coincident_nodes(mesh.points, np.arange(mesh.n_nodes),
                                                      1e-9 * extent, joined)]


def check_deck(case) -> dict:
    """Validation of a deck case without assembly: cards, groups, quality, supports, pairing."""
    prepared = prepare_deck(case)
    mesh = prepared.mesh
    paired = contact_pairs(case, prepared)
    check_shared_pairs(case, paired, mesh.points)
    pairs = {name: len(p[0]) for name, p in paired.items()}
    for i, f in enumerate(case.config.excitation.forces):
        if f.load_set is not None:
            if str(f.load_set) not in prepared.deck.loads:
                raise case.error(f"load set '{f.load_set}' not in the deck (available: "
                                 f"{', '.join(sorted(prepared.deck.loads)) or 'none'})",
                                 ("excitation", "forces", i, "load_set"))
        else:
            resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
    deck_surface_triangles(case, mesh)
    return {"nodes": prepared.deck.n_nodes, "triangles": mesh.n_triangles,
            "contact_pairs": pairs, "ignored_cards": prepared.notes["ignored_cards"],
            "coincident_node_pairs": prepared.notes["coincident_node_pairs"],
            "coincident_nodes": prepared.notes["coincident_nodes"],
            "warnings": prepared.warnings}


__all__ = ["check_mesh", "check_deck", "check_shared_pairs", "mesh_quality"]
