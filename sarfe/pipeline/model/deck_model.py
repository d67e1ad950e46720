r"""The deck path of the linear stage: an engineer's Nastran / Abaqus deck as it is.

    deck file ──read (pyNastran / sarfe.mesh.formats.abaqus), to SI──▶ DeckModel
      ├─ unsupported cards: an error unless named in ``ignore_cards`` (then recorded)
      ├─ units: the deck's own E, ρ, span and thickness in SI held against the bounds of the
      │  case keys (an error on model.fe.units naming the card and the system it looks like)
      ├─ YAML overrides of a group's material / thickness (the deck's own by default)
      ├─ CBUSH/CELAS named by a contact's ``from_elements`` leave the linear model (their
      │  dashpots B stay as parallel dampers; rotational K and GE refused)
      ├─ quality: duplicate / zero-area elements (errors), coincident unjoined nodes (noted)
      ├─ supports (SPC sets, *BOUNDARY, fixed groups) and the rigid-body check
      └─ K, M (sarfe.fe.deck_assembly, RBE2/RBE3 eliminated: u = C q)   → sarfe.pipeline.model.deck_stage

then Craig–Bampton exactly as the generator path (:mod:`sarfe.pipeline.model.fe_stage`): boundary =
translations of contact and excitation nodes, ERP surface = the deck's shells (or a group).
Groups: deck sets (``set_<id>`` SET1, ``pid_<id>`` properties, Abaqus NSET/ELSET names) and the
case's ``model.fe.node_groups`` / ``element_groups`` (GRID / element id lists or a set name).
Contact ``pairs`` are GRID ids here. The views of the deck that the generator-path helpers
expect (a :class:`~sarfe.mesh.PanelMesh` of the shells with every deck node as a point) are
built by :func:`deck_panel_mesh`.
"""
from __future__ import annotations

import dataclasses
import fnmatch
import re
from pathlib import Path

import numpy as np

from sarfe.case.read import Case
from sarfe.mesh import PanelMesh
from sarfe.mesh.formats.abaqus import read_abaqus
from sarfe.mesh.formats.deck import DeckError, to_si
from sarfe.mesh.formats.nastran import read_nastran
from sarfe.pipeline.model.deck_checks import (DECK_KEY, card_key, check_material_bounds,
                                              check_quality, check_supports_on_dependents,
                                              check_units,
                                              free_rigid_motions, has_mass, ignored_mass,
                                              massless_parts,
                                              joined_pairs, support_mask, used_nodes)
from sarfe.pipeline.model.deck_springs import hysteretic_spring, springs_to_contacts


# ----------------------------------------------------------------------------------- reading
def read_case_deck(case: Case):
    """The case's deck in SI, ``ignore_cards`` applied; errors name model.fe.deck."""
    deck_config = case.config.model.fe.deck
    path = case.resolve(deck_config.file)
    try:
        if path.suffix.lower() == ".inp":
            deck = to_si(read_abaqus(path), deck_config.units)
        else:
            deck = read_nastran(path, units=deck_config.units)
    except DeckError as exc:
        raise case.error(str(exc), DECK_KEY) from None
    return apply_ignore_cards(case, deck)


def apply_ignore_cards(case: Case, deck):
    """Move the cards named in ``ignore_cards`` from ``unsupported`` to ``ignored``; any card
    left unsupported is an error listing every such card with its count."""
    ignore = {card_key(c): c for c in case.config.model.fe.deck.ignore_cards}
    unsupported, ignored = {}, dict(deck.ignored)
    for card, count in deck.unsupported.items():
        (ignored if card_key(card) in ignore else unsupported)[card] = count
    present = {card_key(c) for c in list(deck.unsupported) + list(deck.ignored)}
    for j, (key, name) in enumerate(ignore.items()):
        if key not in present:
            raise case.error(f"'{name}' is not an unsupported card of this deck (unsupported: "
                             f"{_listing(deck.unsupported) or 'none'})",
                             ("model", "fe", "ignore_cards", j))
    if unsupported:
        raise case.error(f"the deck has {len(unsupported)} card type"
                         f"{'s' if len(unsupported) > 1 else ''} sarfe does not model: "
                         f"{_listing(unsupported, deck.unsupported_where)}; support them or name "
                         "them in model.fe.ignore_cards", DECK_KEY)
    return dataclasses.replace(deck, unsupported={}, ignored=ignored)


def _listing(counts: dict, where=None) -> str:
    """"CAERO1 (1, first at deck.bdf:12), …" — every card with its count and first line."""
    where = where or {}
    return ", ".join(f"{card} ({count}" + (f", first at {where[card]})" if card in where else ")")
                     for card, count in sorted(counts.items()))


def deck_files(path, seen=None) -> list:
    """The deck file and every file it INCLUDEs (Nastran ``INCLUDE 'x'``, Abaqus
    ``*INCLUDE, INPUT=x``), recursively, for the linear-stage key."""
    path = Path(path)
    seen = [] if seen is None else seen
    if path in seen or not path.is_file():
        return seen
    seen.append(path)
    pattern = re.compile(r"^\s*\*?\s*INCLUDE\b[^=']*(?:=\s*|\s+')([^'\s,]+)", re.IGNORECASE)
    with open(path, errors="replace") as handle:
        for line in handle:
            match = pattern.match(line)
            if match:
                deck_files(path.parent / match.group(1).strip("'\""), seen)
    return seen


# ------------------------------------------------------------------------------------ groups
def _ids_or_set(case, deck, value, path, kind):
    """Node indices (kind 'node') or element ids (kind 'element') of a group definition:
    an id list, or a deck set name / number."""
    if isinstance(value, (list, tuple)):
        if kind == "node":
            return _node_indices(case, deck, value, path)
        known = np.concatenate([deck.shells.element_ids, deck.springs.element_ids,
                                *[b.element_ids for b in deck.solids.values()],
                                deck.beams.element_ids])
        missing = np.setdiff1d(value, known)
        if missing.size:
            raise case.error(f"element id {int(missing[0])} is not in the deck", path)
        return np.unique(np.asarray(value, dtype=np.int64))
    sets = deck.node_sets if kind == "node" else deck.element_sets
    name = str(value)
    for candidate in (name, f"set_{name}", f"pid_{name}"):
        if candidate in sets:
            return sets[candidate]
    raise case.error(f"{kind} set '{name}' not in the deck (available: "
                     f"{', '.join(sorted(sets)[:30]) or 'none'})", path)


def _node_indices(case, deck, grid_ids, path):
    try:
        return deck.node_index(grid_ids)
    except DeckError as exc:
        raise case.error(str(exc).split(": ", 1)[-1], path) from None


def deck_panel_mesh(case: Case, deck):
    """PanelMesh view of the deck: every deck node a point (index = deck node index), the shell
    triangles, node groups = deck node sets + ``model.fe.node_groups`` (+ the nodes of each
    element group), element groups = triangles of deck element sets + ``element_groups``."""
    deck_config = case.config.model.fe.deck
    shells = deck.shells
    node_groups = {name: np.asarray(nodes) for name, nodes in deck.node_sets.items()}
    element_groups = {}
    element_sets = dict(deck.element_sets)
    for name, value in deck_config.node_groups.items():
        node_groups[name] = _ids_or_set(case, deck, value, ("model", "fe", "node_groups", name), "node")
    for name, value in deck_config.element_groups.items():
        element_sets[name] = _ids_or_set(case, deck, value, ("model", "fe", "element_groups", name),
                                         "element")
    for name, ids in element_sets.items():
        rows = deck.shell_triangles_of(ids)
        if rows.size:
            element_groups[name] = rows
            node_groups.setdefault(name, np.unique(shells.triangles[rows]))
    return PanelMesh(deck.points, shells.triangles, node_groups, element_groups)


# --------------------------------------------------------------------------------- overrides
def apply_overrides(case: Case, deck, mesh):
    """Shell sections of the element groups named in ``materials`` / ``thickness_m`` replaced by
    isotropic ones: A = t Q, B = 0, D = t³/12 Q, ρ t (later keys win; the deck's own elsewhere).
    A thickness alone keeps the deck's material (A, B, D and mass scaled by t'/t, (t'/t)³)."""
    fe = case.config.model.fe
    materials, thickness = fe.materials, fe.thickness_m
    if not materials and not thickness:
        return deck
    s = deck.shells
    membrane, coupling, bending = s.membrane.copy(), s.coupling.copy(), s.bending.copy()
    mass, inertia, t = s.mass_per_area.copy(), s.rotary_inertia_per_area.copy(), s.thickness.copy()

    def rows_of(key, name):
        if name == "*":
            return np.arange(s.n_triangles)
        groups = [g for g in mesh.element_groups if fnmatch.fnmatchcase(g, name)]
        if not groups:
            raise case.error(f"element group '{name}' not in the deck (available: "
                             f"{', '.join(sorted(mesh.element_groups)[:30])}, or '*')",
                             ("model", "fe", key, name))
        return np.unique(np.concatenate([mesh.element_groups[g] for g in groups]))

    for name, value in thickness.items():
        rows = rows_of("thickness_m", name)
        ratio = value / np.where(t[rows] > 0, t[rows], value)
        membrane[rows] *= ratio[:, None, None]
        coupling[rows] *= (ratio**2)[:, None, None]
        bending[rows] *= (ratio**3)[:, None, None]
        mass[rows] *= ratio
        inertia[rows] *= ratio**3
        t[rows] = value
    for name, material in materials.items():
        rows = rows_of("materials", name)
        E, nu, rho = material.E_Pa, material.nu, material.rho_kg_m3
        q = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
        membrane[rows] = t[rows, None, None] * q
        coupling[rows] = 0.0
        bending[rows] = (t[rows] ** 3 / 12)[:, None, None] * q
        mass[rows] = rho * t[rows]
        inertia[rows] = rho * t[rows] ** 3 / 12
    shells = dataclasses.replace(s, membrane=membrane, coupling=coupling, bending=bending,
                                 mass_per_area=mass, rotary_inertia_per_area=inertia, thickness=t)
    return dataclasses.replace(deck, shells=shells)


def grid_pairs(case: Case, deck) -> dict:
    """{contact index: [[a, b], …]} of the contacts that list ``pairs``: their GRID ids as deck
    node indices ('ground' kept), for :func:`sarfe.pipeline.model.contact_pairs.resolve_contact`."""
    out = {}
    for contact in case.config.contacts:
        i = contact.index
        if contact.pairs is None:
            continue
        out[i] = [[grid if grid == "ground" else
                   int(_node_indices(case, deck, [grid], ("contacts", i, "pairs", j, k))[0])
                   for k, grid in enumerate(pair)]
                  for j, pair in enumerate(contact.pairs)]
    return out


# ---------------------------------------------------------------------------- the whole model
@dataclasses.dataclass(frozen=True)
class PreparedDeck:
    """A case's deck checked and ready to assemble (everything validate needs, no matrices).

    deck: DeckModel (SI, overrides applied, contact springs removed); mesh: its PanelMesh view;
    held: (n, 6) bool supports (CD components); element_contacts: {name: ElementContact};
    pairs: {contact index: node-index pairs} of the contacts listing GRID-id ``pairs``
    (:func:`grid_pairs`); notes: {key: value} for info;
    warnings: one-line warnings (validate and solve print them; summary.json ``warnings``).
    """

    deck: object
    mesh: object
    held: np.ndarray
    element_contacts: dict
    pairs: dict
    notes: dict
    warnings: tuple = ()


def prepare_deck(case: Case) -> PreparedDeck:
    """Read and check a case's deck (module docstring) up to, not including, assembly."""
    deck = read_case_deck(case)
    if deck.shells.n_triangles == 0:
        raise case.error("the deck has no shell elements (the ERP surface is made of shells)",
                         DECK_KEY)
    check_material_bounds(case, deck)
    unit_warnings = check_units(case, deck)   # the deck's own values, before any YAML override
    mesh = deck_panel_mesh(case, deck)
    deck = apply_overrides(case, deck, mesh)
    deck, element_contacts, contact_warnings = springs_to_contacts(case, deck)
    if not has_mass(deck):
        raise case.error("the deck has no mass (" + ("; ".join(deck.notes) or "no density, "
                         "no point masses") + "): give densities (or materials overrides)", DECK_KEY)
    massless = massless_parts(deck)
    if massless:
        raise case.error("; ".join(massless[:3]) + ": give its material a density (or a "
                         "materials override)", DECK_KEY)
    unjoined_mass = np.setdiff1d(deck.point_masses.node, used_nodes(deck))
    if unjoined_mass.size:
        raise case.error(f"point mass on GRID {int(deck.node_ids[unjoined_mass[0]])} which no "
                         "element connects (its mass would be lost)", DECK_KEY)
    joined = joined_pairs(deck, [(c.nodes_a, c.nodes_b) for c in element_contacts.values()])
    quality = check_quality(case, deck, joined)
    held = support_mask(case, deck, mesh)
    check_supports_on_dependents(case, deck, held)
    free = free_rigid_motions(case, deck, held)
    if free:
        raise case.error("the structure is not held after the supports: " + "; ".join(free)
                         + " (check model.fe.supports / fixed)", ("model", "fe", "supports"))
    deck_config = case.config.model.fe.deck
    notes = {"deck": str(case.resolve(deck_config.file)),
             "units": deck_config.units,
             "ignored_cards": dict(deck.ignored),
             "ignored_mass_kg": ignored_mass(case, deck.ignored),
             "coincident_nodes": [list(p) for p in quality["coincident_nodes"][:50]],
             "coincident_node_pairs": len(quality["coincident_nodes"]),
             "support_sets": [str(s) for s in deck_config.supports]
             or sorted(deck.supports),
             "contact_elements": {k: v.element_ids.tolist() for k, v in element_contacts.items()},
             "deck_notes": list(deck.notes)}
    if len(deck.springs.element_ids) and np.any(deck.springs.structural_damping):
        raise case.error(hysteretic_spring(deck.springs), DECK_KEY)
    if len(deck.springs.element_ids) and np.any(deck.springs.viscous_damping):
        notes["spring_damping"] = "the springs' viscous damping B is added to the case's damping"
    return PreparedDeck(deck, mesh, held, element_contacts, grid_pairs(case, deck), notes,
                        tuple(unit_warnings) + tuple(contact_warnings))


__all__ = ["read_case_deck", "apply_ignore_cards", "deck_files", "deck_panel_mesh",
           "apply_overrides", "grid_pairs", "PreparedDeck", "prepare_deck"]
