"""Validation that needs the mesh (or the deck, or the matrix files) but no assembly: the groups
exist, the contacts pair, the elements are sound.

    check_mesh(case) -> info     {nodes, triangles, contact_pairs, coincident nodes} (FE), {} else
    check_deck(case) -> info     a deck case: cards, groups, quality, supports, pairing

Errors are one-line CaseErrors naming the key (or the element); the fuller pre-solve checks of
``sarfe solve`` / ``sarfe validate`` are :func:`sarfe.pipeline.checks.case_checks.check_case`.
"""
from __future__ import annotations

import numpy as np

from sarfe.case.read import load_case
from sarfe.mesh import quality
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.deck_model import prepare_deck
from sarfe.pipeline.model.deck_stage import contact_pairs
from sarfe.pipeline.model.erp_map import deck_surface_triangles
from sarfe.pipeline.model.fe_stage import resolve_contacts
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
    resolved = resolve_contacts(case, mesh)
    pairs = {name: len(r.nodes_a) for name, r in resolved.items()}
    coincident = mesh_quality(case, mesh, [(r.nodes_a, r.nodes_b) for r in resolved.values()])
    for i, f in enumerate(config.excitation.forces):
        resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
    surface = config.erp.surface
    if surface is not None and surface not in mesh.element_groups:
        resolve_node_group(case, mesh, surface, ("erp", "surface"))
    return {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles, "contact_pairs": pairs,
            "coincident_node_pairs": len(coincident), "coincident_nodes": coincident[:50]}


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
    resolved = contact_pairs(case, prepared)
    pairs = {name: len(r.nodes_a) for name, r in resolved.items()}
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
            "warnings": prepared.warnings + tuple(w for r in resolved.values()
                                                  for w in r.warnings)}


__all__ = ["check_mesh", "check_deck", "mesh_quality"]
