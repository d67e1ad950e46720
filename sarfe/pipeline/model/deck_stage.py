r"""The linear stage of a deck case: K, M of the prepared deck (:mod:`sarfe.pipeline.model.
deck_model`) → supports → Craig–Bampton with the DOFs the contact rows touch and the force nodes'
translations as boundary → contact geometry, load vectors and the ERP map, as :func:`sarfe.pipeline.model.fe_stage.
build_fe_stage` does for a generated mesh. The kept DOFs q of the deck (rigid elements eliminated, CD frames) relate to the
global DOFs by u = T q (`DeckSystem.transformation`); the reduced model handed on is expressed on
all 6n global DOFs (:func:`expanded_reduced_model`) so ERP and VTU recovery see dependent nodes.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from sarfe.case.read import Case
from sarfe.fe.deck_assembly import assemble_deck, load_vector
from sarfe.mesh.formats.deck import DeckError
from sarfe.pipeline.model.contact_kinematics import ShellSurface
from sarfe.pipeline.model.contact_pairs import (boundary_dofs, contact_geometry,
                                                reduced_coordinates, resolve_contact,
                                                spring_contact)
from sarfe.pipeline.model.cutoff import stage_cutoff_hz
from sarfe.pipeline.model.deck_checks import DECK_KEY, check_boundary_nodes
from sarfe.pipeline.model.deck_model import prepare_deck
from sarfe.pipeline.model.erp_map import deck_surface_triangles, erp_map
from sarfe.pipeline.model.groups import resolve_node_group
from sarfe.pipeline.model.stage import next_step
from sarfe.reduction.craig_bampton import craig_bampton
from sarfe.reduction.reduced_model import free_dofs_system
from sarfe.util.progress import bar as progress_bar

_LOADED_BOUNDARY_LIMIT = 60   # load-set DOFs kept physically up to this count (else residuals)


def assemble_case_deck(case: Case, deck):
    """The deck's `DeckSystem`; an assembly refusal (degenerate cell, I12 ≠ 0, an undetermined
    RBE3, …) is a one-line CaseError on model.fe.deck."""
    try:
        return assemble_deck(deck)
    except DeckError as exc:
        raise case.error(str(exc), DECK_KEY) from None


def kept_translations(case, system, deck, nodes, path):
    """(len(nodes), 3) kept DOF numbers of the translations of `nodes` (global axes; rotated CD
    frames and rigid-element dependents were refused before assembly: `check_boundary_nodes`)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    dofs = system.dof_index(nodes[:, None], np.arange(3)[None, :])
    if np.any(dofs < 0):
        bad = nodes[np.argmax((dofs < 0).any(axis=1))]
        raise case.error(f"GRID {int(deck.node_ids[bad])} is a dependent node of a rigid element "
                         "(RBE2/RBE3) or has no stiffness: use an independent node", path)
    return dofs


def _kept_dofs(case, system, deck, nodes, components, path, held_ok=False):
    """Kept DOF numbers (m,) of the global DOFs (node, component 0–5) the contact rows touch
    (rotated CD frames and rigid-element dependents of the contact nodes were refused before
    assembly: `check_boundary_nodes`); one without stiffness is a one-line error, or −1 with
    ``held_ok`` when it was held for lack of stiffness (a contact row through it sees u = 0)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    components = np.asarray(components, dtype=np.int64)
    dofs = system.dof_index(nodes, components)
    bad = dofs < 0
    if held_ok and np.any(bad):
        auto = set(zip(system.auto_held_nodes.tolist(), system.auto_held_components.tolist()))
        bad &= ~np.array([(int(n), int(c)) in auto for n, c in zip(nodes, components)])
    if np.any(bad):
        raise case.error(f"GRID {int(deck.node_ids[nodes[np.argmax(bad)]])} is a dependent node "
                         "of a rigid element (RBE2/RBE3) or has no stiffness: use an independent "
                         "node", path)
    return dofs


def _load_set_vector(case, system, deck, load, path):
    name = str(load.load_set)
    if name not in deck.loads:
        raise case.error(f"load set '{name}' not in the deck (available: "
                         f"{', '.join(sorted(deck.loads)) or 'none'})", path)
    return load_vector(system, deck, name)


def expanded_reduced_model(reduced, transform, free, boundary_global):
    """The reduced model seen on all 6n global DOFs: u_g = T_f u_f with u_f = B q, so the
    'interior basis' of every non-boundary global DOF is (T_f B) — dependent nodes of rigid
    elements and CD-frame DOFs recovered exactly for ERP and the VTU files. Boundary DOFs
    must be global DOFs themselves (independent, basic frame: checked by the caller)."""
    t_free = transform[:, free].tocsc()
    n_b = reduced.boundary_count
    full = np.asarray(t_free[:, reduced.boundary_dofs].todense()) @ np.eye(n_b, reduced.reduced_dof_count) \
        if n_b else np.zeros((transform.shape[0], reduced.reduced_dof_count))
    full = full + t_free[:, reduced.interior_dofs] @ reduced.interior_basis
    total = transform.shape[0]
    is_boundary = np.zeros(total, dtype=bool)
    is_boundary[boundary_global] = True
    interior = np.flatnonzero(~is_boundary)
    return dataclasses.replace(reduced, boundary_dofs=np.asarray(boundary_global),
                               interior_dofs=interior, interior_basis=full[interior],
                               full_dof_count=total, free_dofs=None, total_dof_count=total)


def deck_shell_surface(prepared) -> ShellSurface:
    """The deck's shells as the contacts see them: thickness and mid-surface offset (ZOFFS) of
    each triangle, as read (YAML thickness overrides applied)."""
    shells = prepared.deck.shells
    return ShellSurface(prepared.deck.points, shells.triangles, np.asarray(shells.thickness),
                        np.asarray(shells.offset))


def contact_pairs(case: Case, prepared) -> dict:
    """{contact name: ResolvedContact} of a prepared deck: spring contacts from their elements
    (:func:`sarfe.pipeline.model.contact_pairs.spring_contact`), the others resolved as for a
    mesh (their ``pairs`` GRID ids as node indices: ``prepared.pairs``)."""
    surface = deck_shell_surface(prepared)
    resolved = {}
    for contact in case.config.contacts:
        e = prepared.element_contacts.get(contact.name)
        resolved[contact.name] = (
            spring_contact(contact.name, e, surface) if e is not None else
            resolve_contact(case, prepared.mesh, contact.index, surface,
                            prepared.pairs.get(contact.index)))
    return resolved


def held_kept_dofs(case: Case, prepared, system) -> np.ndarray:
    """Kept DOF numbers the supports hold; a support on a DOF a rigid element made dependent
    is an error (DOFs held for lack of stiffness are skipped)."""
    deck = prepared.deck
    nodes, components = np.nonzero(prepared.held)
    fixed = system.dof_index(nodes, components)
    auto = set(zip(system.auto_held_nodes.tolist(), system.auto_held_components.tolist()))
    for node, comp in zip(nodes[fixed < 0], components[fixed < 0]):
        if (int(node), int(comp)) not in auto:
            raise case.error(f"a support holds GRID {int(deck.node_ids[node])} component "
                             f"{int(comp) + 1}, which a rigid element (RBE2/RBE3) makes dependent",
                             ("model", "fe", "supports"))
    return fixed[fixed >= 0]


def _craig_bampton(case: Case, k_ff, m_ff, boundary_positions, residual_loads):
    """(ReducedModel, cutoff) with the case's reduction settings; a solver failure is one line."""
    red = case.config.reduction
    use_residuals = red.residual_vectors
    cutoff = stage_cutoff_hz(case.config)
    loads = np.stack(residual_loads, axis=1) if residual_loads and use_residuals else None
    try:
        def reduce(mode_count, cutoff_hz):
            return craig_bampton(k_ff, m_ff, boundary_positions, mode_count=mode_count,
                                 cutoff_hz=cutoff_hz, residual_vectors=use_residuals,
                                 residual_loads=loads)
        reduced = reduce(red.mode_count, cutoff)
        if red.mode_count is None and reduced.mode_count < red.min_mode_count:
            reduced = reduce(min(red.min_mode_count,
                                 k_ff.shape[0] - len(boundary_positions) - 1), None)
    except Exception as error:   # any solver's failure (PARDISO, CHOLMOD, ARPACK): one line
        raise case.error(f"the structure is not held (singular stiffness: "
                         f"{' '.join(str(error).split())[:200]}); check the supports and for "
                         "mechanisms (unconnected parts, hinges)", ("model", "fe", "supports")) from None
    return reduced, cutoff


def build_deck_stage(case: Case, progress=False) -> dict:
    """The linear stage of a deck case (the fields of :class:`sarfe.pipeline.model.stage.
    LinearStage`)."""
    timings, clock = {}, time.perf_counter()
    stages = progress_bar(progress, "linear stage", 4, "step")
    prepared = prepare_deck(case)
    deck, mesh = prepared.deck, prepared.mesh
    timings["deck_s"] = time.perf_counter() - clock

    # contacts and loads first: the errors a user is most likely to make
    paired = contact_pairs(case, prepared)
    exc = case.config.excitation
    forces = exc.forces
    group_nodes = [None if f.load_set is not None else
                   resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
                   for i, f in enumerate(forces)]
    radiating = deck_surface_triangles(case, mesh)
    for contact in case.config.contacts:      # as validate: before any assembly
        a, b = paired[contact.name].nodes_a, paired[contact.name].nodes_b
        check_boundary_nodes(case, deck, np.concatenate([a, b[b >= 0]]), ("contacts", contact.index))
    for i, nodes in enumerate(group_nodes):
        if nodes is not None:
            check_boundary_nodes(case, deck, nodes, ("excitation", "forces", i, "group"))

    next_step(stages, "assembly")
    clock = time.perf_counter()
    system = assemble_case_deck(case, deck)
    timings["assembly_s"] = time.perf_counter() - clock
    mass_kg = _translational_mass(system, deck)
    if not mass_kg > 0:
        raise case.error("the deck has no mass (" + ("; ".join(deck.notes) or "no density, "
                         "no point masses") + "): give densities (or materials overrides)", DECK_KEY)
    next_step(stages, "reduction")
    n_kept = system.n_dofs
    fixed = held_kept_dofs(case, prepared, system)
    k_ff, m_ff, free = free_dofs_system(system.stiffness, system.mass, fixed)
    position = np.full(n_kept, -1)
    position[free] = np.arange(len(free))

    # boundary = DOFs the contact rows touch, translations of the force nodes (+ loaded DOFs of
    # small load sets)
    touched = boundary_dofs(paired)
    contact_kept = _kept_dofs(case, system, deck, touched // 6, touched % 6, ("contacts",),
                              held_ok=True)
    nodes = np.unique(np.concatenate([g for g in group_nodes if g is not None]
                                     + [np.zeros(0, np.int64)]).astype(np.int64))
    for contact in case.config.contacts:      # each on its own key, as validate
        r = paired[contact.name]
        kept_translations(case, system, deck, np.concatenate([r.nodes_a, r.nodes_b[r.nodes_b >= 0]]),
                          ("contacts", contact.index))
    for i, group in enumerate(group_nodes):
        if group is not None:
            kept_translations(case, system, deck, group, ("excitation", "forces", i, "group"))
    boundary_kept = np.union1d(contact_kept[contact_kept >= 0], kept_translations(
        case, system, deck, nodes, ("excitation", "forces")).ravel())
    set_vectors = [(_load_set_vector(case, system, deck, f, ("excitation", "forces", i, "load_set"))
                    if f.load_set is not None else None) for i, f in enumerate(forces)]
    loaded = np.unique(np.concatenate([np.flatnonzero(v) for v in set_vectors if v is not None]
                                      + [np.zeros(0, np.int64)]))
    residual_loads = []
    basic = np.all(np.isclose(deck.displacement_frames[system.dof_nodes[loaded]], np.eye(3),
                              atol=1e-12), axis=(1, 2))
    if 0 < len(loaded) <= _LOADED_BOUNDARY_LIMIT and basic.all():   # boundary = global DOFs
        boundary_kept = np.union1d(boundary_kept, loaded)
    else:
        residual_loads += [v[free] for v in set_vectors if v is not None]
    boundary_kept = np.unique(boundary_kept)
    boundary_positions = position[boundary_kept]
    boundary_positions = boundary_positions[boundary_positions >= 0]

    base_load = None
    if exc.base_acceleration is not None:   # rigid translation ι in the kept (CD) DOFs; −M ι
        direction = np.asarray(exc.base_acceleration.direction, dtype=float)
        local = np.einsum("nij,j->ni", deck.displacement_frames, direction)
        iota = np.where(system.dof_components < 3,
                        local[system.dof_nodes, np.minimum(system.dof_components, 2)], 0.0)
        base_load = -(m_ff @ iota[free])
        residual_loads.append(base_load)

    clock = time.perf_counter()
    reduced, cutoff = _craig_bampton(case, k_ff, m_ff, boundary_positions, residual_loads)
    timings["reduction_s"] = time.perf_counter() - clock
    next_step(stages, "contacts, loads, ERP map")
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count
    kept_of_boundary = free[reduced.boundary_dofs]
    boundary_global = 6 * system.dof_nodes[kept_of_boundary] + system.dof_components[kept_of_boundary]

    def reduced_load(vector_free):
        out = np.zeros(n_r)
        out[:n_b] = vector_free[reduced.boundary_dofs]
        out += reduced.interior_basis.T @ vector_free[reduced.interior_dofs]
        return out

    loads = np.zeros((len(forces), n_r))
    coords_of = reduced_coordinates(boundary_global, deck.n_nodes)

    for i, (load, nodes_i, vector) in enumerate(zip(forces, group_nodes, set_vectors)):
        if vector is not None:
            loads[i] = reduced_load(vector[free])
            continue
        c = coords_of(nodes_i)
        for comp in range(3):
            ok = c[:, comp] >= 0
            np.add.at(loads[i], c[ok, comp], load.direction[comp] / len(nodes_i))
    base = reduced_load(base_load) if base_load is not None else None

    added_damping = None
    if system.viscous_damping.nnz:    # dampers of the deck: D_r = Bᵀ D_ff B, B = [I 0; Ψ Φ]
        basis = np.zeros((len(free), n_r))
        basis[reduced.boundary_dofs, np.arange(n_b)] = 1.0
        basis[reduced.interior_dofs] = reduced.interior_basis
        d_ff = system.viscous_damping[free][:, free]
        added_damping = basis.T @ (d_ff @ basis)
    expanded = expanded_reduced_model(reduced, system.transformation, free, boundary_global)
    contacts = contact_geometry(paired, boundary_global, n_r)
    erp_nodes, areas, surface_map = erp_map(mesh, radiating, expanded)
    next_step(stages, None)
    info = {"nodes": int(deck.n_nodes), "triangles": int(mesh.n_triangles),
            "total_dofs": int(6 * deck.n_nodes), "kept_dofs": int(n_kept),
            "free_dofs": int(len(free)), "held_dofs": int(len(fixed)),
            "auto_held_dofs": int(len(system.auto_held_nodes)), "boundary_dofs": int(n_b),
            "modes": int(reduced.mode_count), "residual_vectors": int(reduced.residual_vector_count),
            "reduced_dofs": int(n_r), "cutoff_hz": None if cutoff is None else float(cutoff),
            "radiating_nodes": int(len(erp_nodes)), "radiating_area_m2": float(areas.sum()),
            "linear_solver": reduced.solver,
            "total_mass_kg": mass_kg,
            **prepared.notes}
    return dict(kind="fe", mass=reduced.mass, stiffness=reduced.stiffness, damping=None,
                load_vectors=loads, base_vector=base, contacts=contacts, erp_map=surface_map,
                erp_areas=areas, erp_nodes=erp_nodes, mesh=mesh, reduced=expanded,
                mode_frequencies_hz=reduced.mode_frequencies_hz, info=info, timings=timings,
                node_ids=deck.node_ids, added_damping=added_damping)


def _translational_mass(system, deck) -> float:
    """Total mass [kg] = ιᵀ M ι for a rigid translation along x (all kept DOFs, before supports)."""
    local = deck.displacement_frames[:, :, 0]          # x in each node's CD components
    iota = np.where(system.dof_components < 3,
                    local[system.dof_nodes, np.minimum(system.dof_components, 2)], 0.0)
    return float(iota @ (system.mass @ iota))


__all__ = ["build_deck_stage", "deck_shell_surface", "contact_pairs", "expanded_reduced_model",
           "held_kept_dofs", "assemble_case_deck", "kept_translations"]
