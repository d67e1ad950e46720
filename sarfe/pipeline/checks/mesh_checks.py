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
from sarfe.erp import nodal_normals
from sarfe.mesh import quality
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_pairs import pair_contact
from sarfe.pipeline.model.deck_checks import check_boundary_nodes
from sarfe.pipeline.model.deck_model import prepare_deck
from sarfe.pipeline.model.deck_stage import (assemble_case_deck, contact_pairs, held_kept_dofs,
                                             kept_translations)
from sarfe.pipeline.model.erp_map import deck_surface_triangles
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
    pairs = {c.name: len(p[0]) for c, p in zip(config.contacts, paired)}
    coincident = mesh_quality(case, mesh, [(a, b) for a, b, _, _ in paired])
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


def check_deck(case, assemble=True) -> dict:
    """Validation of a deck case: cards, groups, quality, supports, pairing, and (``assemble``)
    the assembly — what solve refuses there — without the modal reduction."""
    prepared = prepare_deck(case)
    mesh = prepared.mesh
    deck = prepared.deck
    paired = contact_pairs(case, prepared)
    pairs = {name: len(p[0]) for name, p in paired.items()}
    boundary = []           # (nodes, key) of the contact and force nodes
    for contact in case.config.contacts:
        a, b, _, _ = paired[contact.name]
        boundary.append((np.concatenate([a, b[b >= 0]]), ("contacts", contact.index)))
    for i, f in enumerate(case.config.excitation.forces):
        if f.load_set is not None:
            if str(f.load_set) not in deck.loads:
                raise case.error(f"load set '{f.load_set}' not in the deck (available: "
                                 f"{', '.join(sorted(deck.loads)) or 'none'})",
                                 ("excitation", "forces", i, "load_set"))
        else:
            path = ("excitation", "forces", i, "group")
            boundary.append((resolve_node_group(case, mesh, f.group, path), path))
    for nodes, path in boundary:
        check_boundary_nodes(case, deck, nodes, path)
    deck_surface_triangles(case, mesh)
    # what solve refuses at assembly (degenerate cells, rigid-element chains, force nodes
    # without stiffness): validate assembles too (no reduction)
    if assemble:
        system = assemble_case_deck(case, deck)
        held_kept_dofs(case, prepared, system)
        for nodes, path in boundary:
            kept_translations(case, system, deck, nodes, path)
    return {"nodes": prepared.deck.n_nodes, "triangles": mesh.n_triangles,
            "contact_pairs": pairs, "ignored_cards": prepared.notes["ignored_cards"],
            "coincident_node_pairs": prepared.notes["coincident_node_pairs"],
            "coincident_nodes": prepared.notes["coincident_nodes"],
            "warnings": prepared.warnings}


__all__ = ["check_mesh", "check_deck", "mesh_quality"]
