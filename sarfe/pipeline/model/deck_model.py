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

then Craig–Bampton exactly as the generator path (:mod:`sarfe.pipeline.model.linear_stage`): boundary =
translations of contact and excitation nodes, ERP surface = the deck's shells (or a group).
Groups: deck sets (``set_<id>`` SET1, ``pid_<id>`` properties, Abaqus NSET/ELSET names) and the
case's ``model.fe.node_groups`` / ``element_groups`` (GRID / element id lists or a set name).
Contact ``pairs`` are GRID ids here. The views of the deck that the generator-path helpers
expect (a :class:`~sarfe.mesh.PanelMesh` of the shells with every deck node as a point) are
built by :func:`deck_panel_mesh`.
"""
from __future__ import annotations

import copy
import dataclasses
import fnmatch

import numpy as np

from sarfe.case.read import Case
from sarfe.pipeline.checks.deck_checks import (card_key, check_quality, check_units, free_rigid_motions,
                                        has_mass, ignored_mass, joined_pairs, support_mask,
                                        used_nodes)

DECK_KEY = ("model", "fe", "deck")


# ----------------------------------------------------------------------------------- reading
def read_case_deck(case: Case):
    """The case's deck in SI, ``ignore_cards`` applied; errors name model.fe.deck."""
    from sarfe.mesh.formats.deck import DeckError, to_si

    fe = case.config.model.fe.data
    path = case.resolve(fe["deck"])
    try:
        if path.suffix.lower() == ".inp":
            from sarfe.mesh.formats.abaqus import read_abaqus
            deck = to_si(read_abaqus(path), fe["units"])
        else:
            from sarfe.mesh.formats.nastran import read_nastran
            deck = read_nastran(path, units=fe["units"])
    except DeckError as exc:
        raise case.error(str(exc), DECK_KEY) from None
    return apply_ignore_cards(case, deck)


def apply_ignore_cards(case: Case, deck):
    """Move the cards named in ``ignore_cards`` from ``unsupported`` to ``ignored``; any card
    left unsupported is an error listing every such card with its count."""
    ignore = {card_key(c): c for c in case.config.model.fe.data["ignore_cards"]}
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
        raise case.error(f"the deck has cards sarfe does not model: {_listing(unsupported)}; "
                         "support them or name them in model.fe.ignore_cards", DECK_KEY)
    return dataclasses.replace(deck, unsupported={}, ignored=ignored)


def _listing(counts: dict) -> str:
    return ", ".join(f"{card} ({count})" for card, count in sorted(counts.items()))


def deck_files(path, seen=None) -> list:
    """The deck file and every file it INCLUDEs (Nastran ``INCLUDE 'x'``, Abaqus
    ``*INCLUDE, INPUT=x``), recursively, for the linear-stage key."""
    import re
    from pathlib import Path

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
    from sarfe.mesh.formats.deck import DeckError
    try:
        return deck.node_index(grid_ids)
    except DeckError as exc:
        raise case.error(str(exc).split(": ", 1)[-1], path) from None


def deck_panel_mesh(case: Case, deck):
    """PanelMesh view of the deck: every deck node a point (index = deck node index), the shell
    triangles, node groups = deck node sets + ``model.fe.node_groups`` (+ the nodes of each
    element group), element groups = triangles of deck element sets + ``element_groups``."""
    from sarfe.mesh import PanelMesh

    fe = case.config.model.fe.data
    shells = deck.shells
    node_groups = {name: np.asarray(nodes) for name, nodes in deck.node_sets.items()}
    element_groups = {}
    element_sets = dict(deck.element_sets)
    for name, value in fe["node_groups"].items():
        node_groups[name] = _ids_or_set(case, deck, value, ("model", "fe", "node_groups", name), "node")
    for name, value in fe["element_groups"].items():
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
    fe = case.config.model.fe.data
    materials, thickness = fe.get("materials", {}), fe.get("thickness_m", {})
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
        E, nu, rho = material["E_Pa"], material["nu"], material["rho_kg_m3"]
        q = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
        membrane[rows] = t[rows, None, None] * q
        coupling[rows] = 0.0
        bending[rows] = (t[rows] ** 3 / 12)[:, None, None] * q
        mass[rows] = rho * t[rows]
        inertia[rows] = rho * t[rows] ** 3 / 12
    shells = dataclasses.replace(s, membrane=membrane, coupling=coupling, bending=bending,
                                 mass_per_area=mass, rotary_inertia_per_area=inertia, thickness=t)
    return dataclasses.replace(deck, shells=shells)


# -------------------------------------------------------------------------- springs → contacts
@dataclasses.dataclass(frozen=True)
class ElementContact:
    """A contact made of deck springs: one node pair per element (b = −1: ground), the spring
    axis as normal (frames rows [normal, t1, t2]) and its stiffness [N/m] along the axes."""

    element_ids: np.ndarray
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    normal_stiffness: np.ndarray
    tangential_stiffness: np.ndarray


def springs_to_contacts(case: Case, deck):
    """(deck without the springs named by ``from_elements``, {contact name: ElementContact},
    warnings: one line per contact whose law has no tangent element (rattle) but whose springs
    are stiff across their axis — that shear stiffness leaves the model, said, never silently).

    The contact normal is the spring axis ``element_axis`` (default: the translational axis of
    largest stiffness; a CELAS has one); the normal stiffness is the spring's along it and the
    tangential stiffness the mean of the other two translational ones (squeak).

    What the contact law has no place for is kept or refused, never dropped: the spring's
    viscous damping B (all six components, PARAM,W4's GE·K/W4 included) stays in the linear
    model as a damper between the same nodes (the element kept with its stiffness set to 0), a
    dashpot parallel to the contact whether it is open or closed; a nonzero rotational stiffness
    K4–K6 or structural damping GE is a one-line CaseError naming the element.
    """
    from sarfe.hbm import laws
    from sarfe.pipeline.model.linear_stage import frame_from_normal

    springs = deck.springs
    remove = np.zeros(len(springs.element_ids), dtype=bool)
    contacts, warnings = {}, []
    for i, kind, contact in ((c.index, c.kind, c.params) for c in case.config.contacts):
        if "from_elements" not in contact:
            continue
        p = ("contacts", i, "from_elements")
        ids = np.asarray(contact["from_elements"], dtype=np.int64)
        rows = np.array([np.flatnonzero(springs.element_ids == e)[:1] for e in ids], dtype=object)
        missing = [int(e) for e, r in zip(ids, rows) if len(r) == 0]
        if missing:
            raise case.error(f"element {missing[0]} is not a CBUSH/CELAS spring of the deck", p)
        rows = np.array([int(r[0]) for r in rows])
        if np.any(remove[rows]):
            raise case.error("an element is already used by another contact", p)
        _refuse_what_a_contact_cannot_carry(case, springs, rows, p)
        remove[rows] = True
        k = springs.stiffness[rows, :3]
        if "element_axis" in contact:
            axis = np.full(len(rows), contact["element_axis"] - 1)
        else:
            axis = np.argmax(k, axis=1)
            tied = np.sum(np.isclose(k, k.max(axis=1, keepdims=True), rtol=1e-12), axis=1) > 1
            if np.any(tied & (np.count_nonzero(k, axis=1) > 1)):
                raise case.error(f"element {int(ids[np.argmax(tied)])} is equally stiff along two "
                                 "axes; give element_axis: 1, 2 or 3", p)
        normal = springs.frames[rows, axis]
        k_n = k[np.arange(len(rows)), axis]
        if np.any(k_n <= 0):
            raise case.error(f"element {int(ids[np.argmax(k_n <= 0)])} has no stiffness along "
                             "its contact axis", p)
        others = np.ones((len(rows), 3), dtype=bool)
        others[np.arange(len(rows)), axis] = False
        k_t = k[others].reshape(len(rows), 2).mean(axis=1)
        if np.any(k_t > 0) and not laws.uses_tangent(laws.law(kind), contact):
            r = int(np.argmax(k_t))
            warnings.append(f"contacts[{i}] ({contact['name']}): a {kind} contact has no "
                            f"tangential stiffness: the cross-axis stiffness of its springs "
                            f"(up to {float(k_t[r]):g} N/m, {_spring_name(springs, rows[r])}) "
                            "leaves the model; type: squeak keeps it as the stick stiffness")
        contacts[contact["name"]] = ElementContact(ids, springs.node_a[rows], springs.node_b[rows],
                                                   frame_from_normal(normal), k_n, k_t)
    if not remove.any():
        return deck, contacts, warnings
    # a spring's dashpot B stays as a parallel linear damper between its nodes (stiffness 0)
    damper = remove & np.any(springs.viscous_damping != 0.0, axis=1)
    keep = ~remove | damper
    stiffness = np.where(damper[:, None], 0.0, springs.stiffness)
    fields = {f.name: getattr(springs, f.name) for f in dataclasses.fields(springs)}
    fields["stiffness"] = stiffness
    kept = dataclasses.replace(springs, **{name: value[keep] for name, value in fields.items()})
    return dataclasses.replace(deck, springs=kept), contacts, warnings


def _spring_name(springs, i) -> str:
    """'PBUSH 9 (CBUSH 7)' / 'PELAS 3 (CELAS1 5)' / 'CELAS2 5' of spring row i."""
    card, eid, pid = str(springs.card[i]), int(springs.element_ids[i]), int(springs.property_ids[i])
    return {"CBUSH": f"PBUSH {pid} (CBUSH {eid})", "CELAS1": f"PELAS {pid} (CELAS1 {eid})"}.get(
        card, f"{card} {eid}")


def _refuse_what_a_contact_cannot_carry(case: Case, springs, rows, path):
    """One-line CaseError for the first spring of a contact whose rotational stiffness K4–K6 or
    structural damping GE no contact law carries (a contact acts on the translations of its node
    pair, and the HBM model has no hysteretic i·GE·K); a zero value is nothing lost."""
    rotational = springs.stiffness[rows, 3:]
    if np.any(rotational != 0.0):
        r = int(np.flatnonzero(np.any(rotational != 0.0, axis=1))[0])
        c = int(np.flatnonzero(rotational[r])[0])
        raise case.error(f"{_spring_name(springs, rows[r])} has rotational stiffness K{c + 4} = "
                         f"{float(rotational[r, c]):g} N·m/rad, which a contact cannot carry: set "
                         "K4–K6 to 0 (or put them on a separate CBUSH between the same GRIDs, "
                         "kept linear)", path)
    ge = springs.structural_damping[rows]
    if np.any(ge != 0.0):
        r = int(np.flatnonzero(ge)[0])
        raise case.error(f"{_spring_name(springs, rows[r])} has structural damping GE = "
                         f"{float(ge[r]):g}, which a contact cannot carry: add PARAM,W4 (GE·K/W4 "
                         "is then kept as a viscous damper parallel to the contact) or remove GE",
                         path)


def contact_case(case: Case, deck) -> Case:
    """The case with contact ``pairs`` GRID ids turned into deck node indices (for
    :func:`sarfe.pipeline.model.linear_stage.pair_contact`)."""
    data = copy.deepcopy(case.data)
    for i, contact in enumerate(data["contacts"]):
        for j, pair in enumerate(contact.get("pairs", [])):
            for k, grid in enumerate(pair):
                if grid != "ground":
                    pair[k] = int(_node_indices(case, deck, [grid], ("contacts", i, "pairs", j, k))[0])
    return dataclasses.replace(case, data=data)


# ---------------------------------------------------------------------------- the whole model
@dataclasses.dataclass(frozen=True)
class PreparedDeck:
    """A case's deck checked and ready to assemble (everything validate needs, no matrices).

    deck: DeckModel (SI, overrides applied, contact springs removed); mesh: its PanelMesh view;
    held: (n, 6) bool supports (CD components); element_contacts: {name: ElementContact};
    case: the case with GRID-id pairs turned into node indices; notes: {key: value} for info;
    warnings: one-line warnings (validate and solve print them; summary.json ``warnings``).
    """

    deck: object
    mesh: object
    held: np.ndarray
    element_contacts: dict
    case: Case
    notes: dict
    warnings: tuple = ()


def prepare_deck(case: Case) -> PreparedDeck:
    """Read and check a case's deck (module docstring) up to, not including, assembly."""
    deck = read_case_deck(case)
    if deck.shells.n_triangles == 0:
        raise case.error("the deck has no shell elements (the ERP surface is made of shells)",
                         DECK_KEY)
    check_units(case, deck)          # the deck's own values, before any YAML override
    mesh = deck_panel_mesh(case, deck)
    deck = apply_overrides(case, deck, mesh)
    deck, element_contacts, contact_warnings = springs_to_contacts(case, deck)
    if not has_mass(deck):
        raise case.error("the deck has no mass (" + ("; ".join(deck.notes) or "no density, "
                         "no point masses") + "): give densities (or materials overrides)", DECK_KEY)
    unjoined_mass = np.setdiff1d(deck.point_masses.node, used_nodes(deck))
    if unjoined_mass.size:
        raise case.error(f"point mass on GRID {int(deck.node_ids[unjoined_mass[0]])} which no "
                         "element connects (its mass would be lost)", DECK_KEY)
    joined = joined_pairs(deck, [(c.nodes_a, c.nodes_b) for c in element_contacts.values()])
    quality = check_quality(case, deck, joined)
    held = support_mask(case, deck, mesh)
    free = free_rigid_motions(case, deck, held)
    if free:
        raise case.error("the structure is not held after the supports: " + "; ".join(free)
                         + " (check model.fe.supports / fixed)", ("model", "fe", "supports"))
    fe = case.config.model.fe.data
    notes = {"deck": str(case.resolve(fe["deck"])),
             "units": fe["units"],
             "ignored_cards": dict(deck.ignored),
             "ignored_mass_kg": ignored_mass(case, deck.ignored),
             "coincident_nodes": [list(p) for p in quality["coincident_nodes"][:50]],
             "coincident_node_pairs": len(quality["coincident_nodes"]),
             "support_sets": [str(s) for s in fe.get("supports", [])]
             or sorted(deck.supports),
             "contact_elements": {k: v.element_ids.tolist() for k, v in element_contacts.items()},
             "deck_notes": list(deck.notes)}
    if len(deck.springs.element_ids) and np.any(deck.springs.structural_damping):
        raise case.error(_hysteretic_spring(deck.springs), DECK_KEY)
    if len(deck.springs.element_ids) and np.any(deck.springs.viscous_damping):
        notes["spring_damping"] = "the springs' viscous damping B is added to the case's damping"
    return PreparedDeck(deck, mesh, held, element_contacts, contact_case(case, deck), notes,
                        tuple(contact_warnings))


def _hysteretic_spring(springs) -> str:
    """One line naming the first spring with structural damping GE, which the HBM model (viscous
    D only, also in time integration) cannot carry; PARAM,W4 makes it viscous at reading."""
    i = int(np.flatnonzero(springs.structural_damping)[0])
    return (f"{_spring_name(springs, i)} has structural damping GE = "
            f"{float(springs.structural_damping[i]):g}, "
            "which sarfe cannot apply as hysteretic i·GE·K: add PARAM,W4 (the frequency in rad "
            "per deck time unit at which GE·K/W4 becomes viscous, as in Nastran transient) or "
            "remove GE")


def check_deck(case: Case) -> dict:
    """Validation of a deck case without assembly: cards, groups, quality, supports, pairing."""
    from sarfe.pipeline.model.linear_stage import resolve_node_group
    from sarfe.pipeline.model.deck_stage import contact_pairs, radiating_triangles

    prepared = prepare_deck(case)
    mesh, work = prepared.mesh, prepared.case
    pairs = {name: len(p[0]) for name, p in contact_pairs(prepared).items()}
    for i, f in enumerate(case.config.excitation.forces):
        if "load_set" in f:
            if str(f["load_set"]) not in prepared.deck.loads:
                raise case.error(f"load set '{f['load_set']}' not in the deck (available: "
                                 f"{', '.join(sorted(prepared.deck.loads)) or 'none'})",
                                 ("excitation", "forces", i, "load_set"))
        else:
            resolve_node_group(work, mesh, f["group"], ("excitation", "forces", i, "group"))
    radiating_triangles(case, mesh)
    return {"nodes": prepared.deck.n_nodes, "triangles": mesh.n_triangles,
            "contact_pairs": pairs, "ignored_cards": prepared.notes["ignored_cards"],
            "coincident_node_pairs": prepared.notes["coincident_node_pairs"],
            "coincident_nodes": prepared.notes["coincident_nodes"],
            "warnings": prepared.warnings}
