"""Validation that needs the mesh (or the deck, or the matrix files) but no assembly: the groups
exist, the contacts pair, the elements are sound.

    check_mesh(case) -> info     {nodes, triangles, contact_pairs, coincident nodes} (FE), {} else
    check_deck(case) -> info     a deck case: cards, groups, quality, supports, pairing, held
                                 inputs (:mod:`sarfe.pipeline.checks.held_checks`)
    shared_pair_warnings(case, paired, points)   one node pair in two contacts: a warning

Errors are one-line CaseErrors naming the key (or the element); the fuller pre-solve checks of
``sarfe solve`` / ``sarfe validate`` are :func:`sarfe.pipeline.checks.case_checks.check_case`.
"""
from __future__ import annotations

import numpy as np

from sarfe.case.read import load_case
from sarfe.mesh import quality
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.checks.held_checks import (check_something_free, contact_warnings,
                                               load_warnings)
from sarfe.pipeline.checks.run_cost import weyl_mode_density
from sarfe.pipeline.model.contact_pairs import node_pairs
from sarfe.pipeline.model.deck_checks import check_boundary_nodes, connected_parts
from sarfe.pipeline.model.deck_model import prepare_deck
from sarfe.pipeline.model.deck_stage import (assemble_case_deck, contact_pairs, held_kept_dofs,
                                             kept_translations)
from sarfe.pipeline.model.erp_map import deck_surface_triangles, surface_triangles
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
    surface_triangles(case, mesh)     # erp.surface: an element group, or a node group's triangles
    return {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles, "contact_pairs": pairs,
            "coincident_node_pairs": len(coincident), "coincident_nodes": coincident[:50]}


def shared_pair_warnings(case, paired: dict, points) -> list:
    """A node pair in two contacts: one warning line per pair of contacts, naming both and where
    the first shared pair sits — two laws at one pair add their forces (twice the stiffness and
    friction where both act along the same normal), which is what overlapping node groups give
    by mistake, but also how a side stop (another ``normal``) or a progressive stop (another
    ``gap_m``) is modelled; so it is said, not refused. A pair listed twice in one contact is a
    CaseError. ``paired``: {contact name: (a (n_p,), b (n_p,) with −1 for ground, …)}; a pair is
    unordered (a–b = b–a); ``points`` (n, 3) [m]."""
    contacts = case.config.contacts
    sizes = [len(paired[c.name][0]) for c in contacts]
    if not sum(sizes):
        return []
    a = np.concatenate([np.asarray(paired[c.name][0], dtype=np.int64) for c in contacts])
    b = np.concatenate([np.asarray(paired[c.name][1], dtype=np.int64) for c in contacts])
    owner = np.repeat(np.arange(len(contacts)), sizes)
    low = np.where(b < 0, a, np.minimum(a, b))
    high = np.where(b < 0, -1, np.maximum(a, b))
    _, first, inverse = np.unique(np.stack([low, high], axis=1), axis=0, return_index=True,
                                  return_inverse=True)
    first = first[inverse.ravel()]                  # the first occurrence of each entry's pair
    repeated = np.flatnonzero(first != np.arange(len(a)))
    warnings, said = [], set()
    for k in repeated:
        j = first[k]
        one, other = contacts[owner[j]], contacts[owner[k]]
        x, y, z = np.asarray(points)[a[k]]
        pair = f"node pair {a[k]}–{'ground' if b[k] < 0 else b[k]} at ({x:.4g}, {y:.4g}, {z:.4g}) m"
        if one.index == other.index:
            raise case.error(f"{pair} is listed twice in this contact; give each pair once",
                             ("contacts", other.index))
        if (one.index, other.index) in said:
            continue
        said.add((one.index, other.index))
        count = int(np.count_nonzero((owner[repeated] == other.index)
                                     & (owner[first[repeated]] == one.index)))
        warnings.append(f"contacts[{other.index}] ({other.name}): {count} node pair(s) also in "
                        f"contacts[{one.index}] ({one.name}), e.g. {pair}: both laws act there "
                        "and their forces add (twice the stiffness and friction along one "
                        "normal) — split the node groups unless a second direction or gap is "
                        "meant")
    return warnings


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
    """Validation of a deck case: cards, groups, quality, supports, pairing, something free to
    move, forces and contacts on free nodes, contact and force nodes independent, and
    (``assemble``) the assembly — what solve refuses there — without the modal reduction."""
    prepared = prepare_deck(case)
    mesh, deck = prepared.mesh, prepared.deck
    held = prepared.held[:, :3].all(axis=1)
    used = connected_parts(deck)[2]
    held |= ~used
    check_something_free(case, held, used, ("model", "fe", "fixed") if case.config.model.fe.fixed
                         else ("model", "fe", "supports"))
    resolved = contact_pairs(case, prepared)
    paired = node_pairs(resolved)
    shared = shared_pair_warnings(case, paired, mesh.points)
    pairs = {name: len(p[0]) for name, p in paired.items()}
    boundary = []           # (nodes, key) of the contact and force nodes
    for contact in case.config.contacts:
        a, b = paired[contact.name]
        boundary.append((np.concatenate([a, b[b >= 0]]), ("contacts", contact.index)))
    load_nodes = []
    for i, f in enumerate(case.config.excitation.forces):
        if f.load_set is not None:
            load_nodes.append(None)
            if str(f.load_set) not in deck.loads:
                raise case.error(f"load set '{f.load_set}' not in the deck (available: "
                                 f"{', '.join(sorted(deck.loads)) or 'none'})",
                                 ("excitation", "forces", i, "load_set"))
        else:
            path = ("excitation", "forces", i, "group")
            load_nodes.append(resolve_node_group(case, mesh, f.group, path))
            boundary.append((load_nodes[-1], path))
    for nodes, path in boundary:
        check_boundary_nodes(case, deck, nodes, path)
    held_by = "the supports or model.fe.fixed, or on no element"
    shared += load_warnings(case, held, load_nodes, held_by)
    shared += contact_warnings(case, paired, held, held_by, labels=deck.node_ids)
    radiating = np.unique(deck_surface_triangles(case, mesh)).size
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
            "free_nodes": int(np.count_nonzero(~held)), "radiating_nodes": int(radiating),
            "mode_density_per_hz": shell_mode_density(deck),
            "warnings": list(prepared.warnings) + shared
                        + [w for r in resolved.values() for w in r.warnings]}


def shell_mode_density(deck) -> float | None:
    """The Weyl modal density [modes/Hz] of a deck's shells (:func:`sarfe.pipeline.checks.
    run_cost.weyl_mode_density` with each triangle's ρ t + NSM and √(D₁₁ D₂₂)); None without
    shells."""
    shells = deck.shells
    if shells.n_triangles == 0:
        return None
    bending = np.sqrt(np.abs(shells.bending[:, 0, 0] * shells.bending[:, 1, 1]))
    keep = (bending > 0) & (shells.mass_per_area > 0)
    return weyl_mode_density(deck.points, shells.triangles[keep], shells.mass_per_area[keep],
                             bending[keep])


__all__ = ["check_mesh", "check_deck", "shell_mode_density", "shared_pair_warnings", "mesh_quality"]
