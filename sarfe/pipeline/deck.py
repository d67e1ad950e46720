r"""The deck path of the linear stage: an engineer's Nastran / Abaqus deck as it is.

    deck file ──read (pyNastran / sarfe.mesh.abaqus), to SI──▶ DeckModel
      ├─ unsupported cards: an error unless named in ``ignore_cards`` (then recorded)
      ├─ YAML overrides of a group's material / thickness (the deck's own by default)
      ├─ CBUSH/CELAS named by a contact's ``from_elements`` leave the linear model
      ├─ quality: duplicate / zero-area elements (errors), coincident unjoined nodes (noted)
      ├─ supports (SPC sets, *BOUNDARY, fixed groups) and the rigid-body check
      └─ K, M (sarfe.fe.deck_assembly, RBE2/RBE3 eliminated: u = C q)

then Craig–Bampton exactly as the generator path (:mod:`sarfe.pipeline.linear`): boundary =
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

from sarfe.io.case import Case

DECK_KEY = ("model", "fe", "deck")


# ----------------------------------------------------------------------------------- reading
def read_case_deck(case: Case):
    """The case's deck in SI, ``ignore_cards`` applied; errors name model.fe.deck."""
    from sarfe.mesh.deck import DeckError, to_si

    fe = case.data["model"]["fe"]
    path = case.resolve(fe["deck"])
    try:
        if path.suffix.lower() == ".inp":
            from sarfe.mesh.abaqus import read_abaqus
            deck = to_si(read_abaqus(path), fe["units"])
        else:
            from sarfe.mesh.nastran import read_nastran
            deck = read_nastran(path, units=fe["units"])
    except DeckError as exc:
        raise case.error(str(exc), DECK_KEY) from None
    return apply_ignore_cards(case, deck)


def _card_key(name: str) -> str:
    return str(name).upper().lstrip("*").strip()


def apply_ignore_cards(case: Case, deck):
    """Move the cards named in ``ignore_cards`` from ``unsupported`` to ``ignored``; any card
    left unsupported is an error listing every such card with its count."""
    ignore = {_card_key(c): c for c in case.data["model"]["fe"]["ignore_cards"]}
    unsupported, ignored = {}, dict(deck.ignored)
    for card, count in deck.unsupported.items():
        (ignored if _card_key(card) in ignore else unsupported)[card] = count
    present = {_card_key(c) for c in list(deck.unsupported) + list(deck.ignored)}
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
    if isinstance(value, list):
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
    from sarfe.mesh.deck import DeckError
    try:
        return deck.node_index(grid_ids)
    except DeckError as exc:
        raise case.error(str(exc).split(": ", 1)[-1], path) from None


def deck_panel_mesh(case: Case, deck):
    """PanelMesh view of the deck: every deck node a point (index = deck node index), the shell
    triangles, node groups = deck node sets + ``model.fe.node_groups`` (+ the nodes of each
    element group), element groups = triangles of deck element sets + ``element_groups``."""
    from sarfe.mesh import PanelMesh

    fe = case.data["model"]["fe"]
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
    fe = case.data["model"]["fe"]
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
    """(deck without the springs named by ``from_elements``, {contact name: ElementContact}).

    The contact normal is the spring axis ``element_axis`` (default: the translational axis of
    largest stiffness; a CELAS has one); the normal stiffness is the spring's along it and the
    tangential stiffness the mean of the other two translational ones (squeak).
    """
    from sarfe.pipeline.linear import frame_from_normal

    springs = deck.springs
    remove = np.zeros(len(springs.element_ids), dtype=bool)
    contacts = {}
    for i, contact in enumerate(case.data["contacts"]):
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
        contacts[contact["name"]] = ElementContact(ids, springs.node_a[rows], springs.node_b[rows],
                                                   frame_from_normal(normal), k_n, k_t)
    if not remove.any():
        return deck, contacts
    keep = ~remove
    kept = dataclasses.replace(
        springs, **{f.name: getattr(springs, f.name)[keep] for f in dataclasses.fields(springs)})
    return dataclasses.replace(deck, springs=kept), contacts


def contact_case(case: Case, deck) -> Case:
    """The case with contact ``pairs`` GRID ids turned into deck node indices (for
    :func:`sarfe.pipeline.linear.pair_contact`)."""
    data = copy.deepcopy(case.data)
    for i, contact in enumerate(data["contacts"]):
        for j, pair in enumerate(contact.get("pairs", [])):
            for k, grid in enumerate(pair):
                if grid != "ground":
                    pair[k] = int(_node_indices(case, deck, [grid], ("contacts", i, "pairs", j, k))[0])
    return dataclasses.replace(case, data=data)


# ------------------------------------------------------------------------------- quality
def check_quality(case: Case, deck, joined=()) -> dict:
    """Duplicate and zero-area shell elements are errors (with their ids); coincident nodes
    that no element, rigid element or contact joins are returned as a note."""
    from sarfe.mesh import quality

    shells = deck.shells
    corners = -np.ones((len(shells.element_ids), 4), dtype=np.int64)
    rows = np.flatnonzero(np.r_[True, np.diff(shells.triangle_element) != 0])
    # element corners: the first triangle's nodes plus the second triangle's last node (quads)
    counts = np.bincount(shells.triangle_element, minlength=len(shells.element_ids))
    corners[:, :3] = shells.triangles[rows]
    quad = counts == 2
    corners[quad, 3] = shells.triangles[rows[quad] + 1, 2]
    several = counts > 2      # split higher-order elements: check their triangles only
    duplicates = quality.duplicate_elements(corners[~several], shells.element_ids[~several])
    if duplicates:
        text = ", ".join(f"{b} (= {a})" for a, b in duplicates[:10])
        raise case.error(f"{len(duplicates)} duplicate shell element(s) on the same nodes: "
                         f"{text}", DECK_KEY)
    degenerate = quality.degenerate_elements(deck.points, shells.triangles,
                                             shells.element_ids[shells.triangle_element])
    if degenerate:
        ids = sorted(set(degenerate))
        raise case.error(f"{len(ids)} zero-area shell element(s): "
                         f"{', '.join(map(str, ids[:10]))}", DECK_KEY)
    extent = float(np.linalg.norm(np.ptp(deck.points, axis=0))) if deck.n_nodes else 0.0
    pairs = quality.coincident_nodes(deck.points, deck.node_ids, 1e-9 * max(extent, 1e-9), joined)
    return {"coincident_nodes": pairs}


def joined_pairs(deck, contacts=()):
    """Node-index pairs joined by springs, rigid elements and contacts (coincidence intended)."""
    pairs = [np.stack([deck.springs.node_a, deck.springs.node_b], axis=1)]
    pairs.append(np.stack([deck.rbe2.independent[deck.rbe2.dependent_element],
                           deck.rbe2.dependent], axis=1))
    pairs.append(np.stack([deck.rbe3.reference[deck.rbe3.independent_element],
                           deck.rbe3.independent], axis=1))
    for a, b in contacts:
        pairs.append(np.stack([np.asarray(a), np.asarray(b)], axis=1))
    pairs = np.concatenate([p.reshape(-1, 2) for p in pairs])
    return [(int(a), int(b)) for a, b in pairs if a >= 0 and b >= 0]


# ---------------------------------------------------------------------------------- supports
def support_mask(case: Case, deck, mesh) -> np.ndarray:
    """(n, 6) bool held components, in each node's displacement (CD) frame, from the chosen
    support sets (all of the deck's when ``supports`` is not given; ``permanent`` GRID PS
    always) and the ``fixed`` node groups (all six components)."""
    from sarfe.pipeline.linear import resolve_node_group

    fe = case.data["model"]["fe"]
    chosen = [str(s) for s in fe.get("supports", [])] or sorted(deck.supports)
    if "permanent" in deck.supports and "permanent" not in chosen:
        chosen.append("permanent")
    held = np.zeros((deck.n_nodes, 6), dtype=bool)
    for j, name in enumerate(chosen):
        if name not in deck.supports:
            raise case.error(f"support set '{name}' not in the deck (available: "
                             f"{', '.join(sorted(deck.supports)) or 'none'})",
                             ("model", "fe", "supports", j))
        support = deck.supports[name]
        held[support.nodes] |= support.components
    for i, group in enumerate(fe.get("fixed", [])):
        nodes = resolve_node_group(case, mesh, group, ("model", "fe", "fixed", i),
                                   allow_elements=False)
        held[nodes] = True
    return held


def connected_parts(deck) -> tuple[int, np.ndarray, np.ndarray]:
    """(count, part of every node (n,), whether a node is used by any element (n,)): nodes
    joined by shells, solids, beams, two-node springs and rigid / interpolation elements."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = deck.n_nodes
    edges = [deck.shells.triangles[:, [0, 1]], deck.shells.triangles[:, [1, 2]],
             deck.beams.nodes, np.stack([deck.springs.node_a, deck.springs.node_b], axis=1),
             np.stack([deck.rbe2.independent[deck.rbe2.dependent_element], deck.rbe2.dependent], 1),
             np.stack([deck.rbe3.reference[deck.rbe3.independent_element], deck.rbe3.independent], 1)]
    for block in deck.solids.values():
        c = block.connectivity
        edges += [np.stack([c[:, 0], c[:, k]], axis=1) for k in range(1, c.shape[1])]
    edges = np.concatenate([e.reshape(-1, 2) for e in edges]).astype(np.int64)
    used = np.zeros(n, dtype=bool)
    used[edges[edges >= 0]] = True
    used[deck.springs.node_a] = True
    edges = edges[(edges >= 0).all(axis=1)]
    graph = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    count, part = connected_components(graph, directed=False)
    return count, part, used


def _rigid_arm(r):
    """(k, 6, 6) rigid motion [u; θ] at offsets r (k, 3) of a unit [t; θ]: [[I, −[r]×], [0, I]]."""
    r = np.asarray(r, dtype=float)
    out = np.zeros((len(r), 6, 6))
    out[:, :3, :3] = out[:, 3:, 3:] = np.eye(3)
    out[:, 0, 4], out[:, 0, 5] = r[:, 2], -r[:, 1]
    out[:, 1, 3], out[:, 1, 5] = -r[:, 2], r[:, 0]
    out[:, 2, 3], out[:, 2, 4] = r[:, 1], -r[:, 0]
    return out


_MOTIONS = ["translation x", "translation y", "translation z",
            "rotation about x", "rotation about y", "rotation about z"]


def free_rigid_motions(case: Case, deck, held) -> list[str]:
    """Rigid-body motions left after the supports, per connected part (before any solve).

    For the nodes of a part, the six rigid motions u = t + θ × (x − x̄) (θ scaled by the part's
    size) are tested against the held DOFs and the grounded springs: motions the constraint rows
    do not see (singular values ≤ 1e-9 of the largest) are free. Returns messages naming the
    free components and the part's node count (empty when everything is held). Mechanisms
    inside a part are not detected here (the factorization reports them)."""
    count, part, used = connected_parts(deck)
    springs = deck.springs
    grounded = springs.node_b < 0
    problems = []
    for p in range(count):
        nodes = np.flatnonzero((part == p) & used)
        if nodes.size == 0:
            continue
        x = deck.points[nodes]
        centre = x.mean(axis=0)
        size = max(float(np.linalg.norm(np.ptp(x, axis=0))), 1e-9)
        # rigid motion of every node for unit motions of the part: (k, 6, 6) = [[I, −[r]×], [0, I]]
        motion = _rigid_arm(x - centre) * np.r_[np.ones(3), np.full(3, 1 / size)]
        frames = np.zeros((len(nodes), 6, 6))      # global → each node's CD components
        frames[:, :3, :3] = frames[:, 3:, 3:] = deck.displacement_frames[nodes]
        rows = [np.einsum("kab,kbc->kac", frames, motion)[held[nodes]]]
        in_part = np.isin(springs.node_a, nodes) & grounded
        if np.any(in_part):
            local = np.searchsorted(nodes, springs.node_a[in_part])
            rotation = np.zeros((len(local), 6, 6))
            rotation[:, :3, :3] = rotation[:, 3:, 3:] = springs.frames[in_part]
            along = np.einsum("kab,kbc->kac", rotation, motion[local])      # spring axes
            weight = np.sqrt(springs.stiffness[in_part] > 0)
            rows.append((along * weight[:, :, None]).reshape(-1, 6))
        constraint = np.concatenate(rows) if rows else np.zeros((0, 6))
        if constraint.shape[0] == 0:
            free = np.eye(6)
        else:
            _, sigma, vt = np.linalg.svd(constraint, full_matrices=True)
            rank = int(np.sum(sigma > 1e-9 * sigma.max())) if sigma.size else 0
            free = vt[rank:]
        if len(free):
            share = np.einsum("ij,ij->j", free, free)   # |P e_k|² of each unit motion in the free space
            names = [_MOTIONS[k] for k in range(6) if share[k] > 1e-3]
            grids = deck.node_ids[nodes]
            problems.append(f"a part of {len(nodes)} nodes (GRIDs {int(grids.min())}…"
                            f"{int(grids.max())}) is free in {len(free)} rigid-body "
                            f"motion{'s' if len(free) > 1 else ''} ({', '.join(names)})")
    return problems


# ---------------------------------------------------------------------------- the whole model
@dataclasses.dataclass(frozen=True)
class PreparedDeck:
    """A case's deck checked and ready to assemble (everything validate needs, no matrices).

    deck: DeckModel (SI, overrides applied, contact springs removed); mesh: its PanelMesh view;
    held: (n, 6) bool supports (CD components); element_contacts: {name: ElementContact};
    case: the case with GRID-id pairs turned into node indices; notes: {key: value} for info.
    """

    deck: object
    mesh: object
    held: np.ndarray
    element_contacts: dict
    case: Case
    notes: dict


def prepare_deck(case: Case) -> PreparedDeck:
    """Read and check a case's deck (module docstring) up to, not including, assembly."""
    deck = read_case_deck(case)
    if deck.shells.n_triangles == 0:
        raise case.error("the deck has no shell elements (the ERP surface is made of shells)",
                         DECK_KEY)
    mesh = deck_panel_mesh(case, deck)
    deck = apply_overrides(case, deck, mesh)
    deck, element_contacts = springs_to_contacts(case, deck)
    if not _has_mass(deck):
        raise case.error("the deck has no mass (" + ("; ".join(deck.notes) or "no density, "
                         "no point masses") + "): give densities (or materials overrides)", DECK_KEY)
    unjoined_mass = np.setdiff1d(deck.point_masses.node, _used_nodes(deck))
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
    notes = {"deck": str(case.resolve(case.data["model"]["fe"]["deck"])),
             "units": case.data["model"]["fe"]["units"],
             "ignored_cards": dict(deck.ignored),
             "ignored_mass_kg": ignored_mass(case, deck.ignored),
             "coincident_nodes": [list(p) for p in quality["coincident_nodes"][:50]],
             "coincident_node_pairs": len(quality["coincident_nodes"]),
             "support_sets": [str(s) for s in case.data["model"]["fe"].get("supports", [])]
             or sorted(deck.supports),
             "contact_elements": {k: v.element_ids.tolist() for k, v in element_contacts.items()},
             "deck_notes": list(deck.notes)}
    if len(deck.springs.element_ids) and np.any(deck.springs.structural_damping):
        notes["spring_damping"] = ("the springs' structural damping GE is not applied (the "
                                   "viscous B is): hysteretic damping is not a constant D")
    elif len(deck.springs.element_ids) and np.any(deck.springs.viscous_damping):
        notes["spring_damping"] = "the springs' viscous damping B is added to the case's damping"
    return PreparedDeck(deck, mesh, held, element_contacts, contact_case(case, deck), notes)


def ignored_mass(case: Case, ignored: dict) -> dict:
    """{card: mass [kg] its elements and masses carry} of the ignored cards of a Nastran deck
    (pyNastran's mass properties, PARAM,WTMASS included; 0 for loads and other massless cards);
    None per card for an Abaqus file (not computed)."""
    if not ignored:
        return {}
    fe = case.data["model"]["fe"]
    path = case.resolve(fe["deck"])
    if path.suffix.lower() == ".inp":
        return {card: None for card in ignored}
    from sarfe.mesh.deck import UNIT_SYSTEMS
    from sarfe.mesh.nastran import _load_bdf

    model = _load_bdf(path)
    wtmass = model.params["WTMASS"].values[0] if "WTMASS" in model.params else 1.0
    scale = UNIT_SYSTEMS[fe["units"]].factor(0, 1) * wtmass
    masses = {}
    for card in ignored:
        key = _card_key(card)
        cards = [el for el in list(model.elements.values()) + list(model.masses.values())
                 if el.type == key]
        try:   # each card's own Mass() (pyNastran: ρ, thickness/area and NSM of its property)
            masses[card] = float(sum(el.Mass() for el in cards)) * scale
        except Exception:   # a card pyNastran cannot weigh: say so rather than guess
            masses[card] = None
    return masses


def _has_mass(deck) -> bool:
    """Whether any element or point mass of the deck carries mass."""
    return bool(np.any(deck.shells.mass_per_area > 0) or np.any(deck.point_masses.mass > 0)
                or any(np.any(b.density > 0) for b in deck.solids.values())
                or np.any(deck.beams.density > 0) or np.any(deck.beams.mass_per_length > 0))


def _used_nodes(deck) -> np.ndarray:
    _, _, used = connected_parts(deck)
    return np.flatnonzero(used)


def total_mass(deck) -> float:
    """Σ ρ t A of the shells + point masses + solids/beams are left to the assembly [kg]
    (for the summary; the assembled M is the reference)."""
    from sarfe.mesh.quality import shell_areas

    shells = deck.shells
    return float(np.sum(shell_areas(deck.points, shells.triangles) * shells.mass_per_area)
                 + np.sum(deck.point_masses.mass))


# ------------------------------------------------------------------------------ linear stage
_LOADED_BOUNDARY_LIMIT = 60   # load-set DOFs kept physically up to this count (else residuals)


def _assemble(case: Case, deck):
    from sarfe.fe.deck_assembly import assemble_deck
    from sarfe.mesh.deck import DeckError

    try:
        return assemble_deck(deck)
    except DeckError as exc:
        raise case.error(str(exc), DECK_KEY) from None


def _kept_translations(case, system, deck, nodes, path):
    """(len(nodes), 3) kept DOF numbers of the translations of `nodes` (global axes)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    rotated = ~np.all(np.isclose(deck.displacement_frames[nodes], np.eye(3), atol=1e-12),
                      axis=(1, 2))
    if np.any(rotated):
        raise case.error(f"GRID {int(deck.node_ids[nodes[np.argmax(rotated)]])} has a rotated "
                         "displacement frame (CD): contact and force nodes must use the basic "
                         "frame", path)
    dofs = system.dof_index(nodes[:, None], np.arange(3)[None, :])
    if np.any(dofs < 0):
        bad = nodes[np.argmax((dofs < 0).any(axis=1))]
        raise case.error(f"GRID {int(deck.node_ids[bad])} is a dependent node of a rigid element "
                         "(RBE2/RBE3) or has no stiffness: use an independent node", path)
    return dofs


def _load_set_vector(case, system, deck, load, path):
    from sarfe.fe.deck_assembly import load_vector

    name = str(load["load_set"])
    if name not in deck.loads:
        raise case.error(f"load set '{name}' not in the deck (available: "
                         f"{', '.join(sorted(deck.loads)) or 'none'})", path)
    return load_vector(system, deck, name)


def _expanded(reduced, transform, free, boundary_global):
    """The reduced model seen on all 6n global DOFs: u_g = T_f u_f with u_f = B q, so the
    'interior basis' of every non-boundary global DOF is (T_f B) — dependent nodes of rigid
    elements and CD-frame DOFs recovered exactly for ERP and the VTU files."""
    from sarfe.reduction.craig_bampton import ReducedModel

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


def build_deck_stage(case: Case, progress=False) -> dict:
    """The linear stage of a deck case (the fields of :class:`sarfe.pipeline.linear.LinearStage`)."""
    import time

    from sarfe.erp import nodal_areas, nodal_normals
    from sarfe.pipeline.linear import (ContactGeometry, _bar, _step, default_cutoff_hz,
                                       pair_contact, resolve_node_group)
    from sarfe.reduction.craig_bampton import craig_bampton, free_dofs_system
    from sarfe.reduction.recovery import normal_velocity_basis

    timings, clock = {}, time.perf_counter()
    stages = _bar(progress, "linear stage", 4, unit="step")
    prepared = prepare_deck(case)
    deck, mesh, work = prepared.deck, prepared.mesh, prepared.case
    data = case.data
    timings["deck_s"] = time.perf_counter() - clock

    # contacts and loads first: the errors a user is most likely to make
    normals_all = nodal_normals(mesh.points, mesh.triangles)
    paired = {}
    for i, c in enumerate(data["contacts"]):
        if c["name"] in prepared.element_contacts:
            e = prepared.element_contacts[c["name"]]
            distance = np.zeros(len(e.nodes_a))
            b = e.nodes_b >= 0
            distance[b] = np.einsum("ij,ij->i", e.frames[b, 0],
                                    deck.points[e.nodes_b[b]] - deck.points[e.nodes_a[b]])
            paired[c["name"]] = (e.nodes_a, e.nodes_b, e.frames, distance)
        else:
            paired[c["name"]] = pair_contact(work, mesh, i, normals_all)
    exc = data["excitation"]
    forces = exc.get("forces", [])
    group_nodes = [None if "load_set" in f else
                   resolve_node_group(work, mesh, f["group"], ("excitation", "forces", i, "group"))
                   for i, f in enumerate(forces)]
    surface = data["erp"].get("surface")
    if surface is None:
        radiating = mesh.triangles
    elif surface in mesh.element_groups:
        radiating = mesh.triangles[mesh.element_groups[surface]]
    else:
        raise case.error(f"element group '{surface}' not in the deck (available: "
                         f"{', '.join(sorted(mesh.element_groups)[:30])})", ("erp", "surface"))

    _step(stages, "assembly")
    clock = time.perf_counter()
    system = _assemble(case, deck)
    timings["assembly_s"] = time.perf_counter() - clock
    mass_kg = _translational_mass(system, deck)
    if not mass_kg > 0:
        raise case.error("the deck has no mass (" + ("; ".join(deck.notes) or "no density, "
                         "no point masses") + "): give densities (or materials overrides)", DECK_KEY)
    _step(stages, "reduction")
    n_kept = system.n_dofs
    fixed = system.dof_index(*np.nonzero(prepared.held))
    held_nodes, held_comps = np.nonzero(prepared.held)
    auto = set(zip(system.auto_held_nodes.tolist(), system.auto_held_components.tolist()))
    for node, comp in zip(held_nodes[fixed < 0], held_comps[fixed < 0]):
        if (int(node), int(comp)) not in auto:
            raise case.error(f"a support holds GRID {int(deck.node_ids[node])} component "
                             f"{int(comp) + 1}, which a rigid element (RBE2/RBE3) makes dependent",
                             ("model", "fe", "supports"))
    k_ff, m_ff, free = free_dofs_system(system.stiffness, system.mass, fixed[fixed >= 0])
    position = np.full(n_kept, -1)
    position[free] = np.arange(len(free))

    # boundary = translations of contact and force nodes (+ loaded DOFs of small load sets)
    contact_nodes = [np.concatenate([a, b[b >= 0]]) for a, b, _, _ in paired.values()]
    nodes = np.unique(np.concatenate(contact_nodes + [g for g in group_nodes if g is not None]
                                     + [np.zeros(0, np.int64)]).astype(np.int64))
    boundary_kept = _kept_translations(case, system, deck, nodes, ("contacts",)).ravel()
    set_vectors = [(_load_set_vector(case, system, deck, f, ("excitation", "forces", i, "load_set"))
                    if "load_set" in f else None) for i, f in enumerate(forces)]
    loaded = np.unique(np.concatenate([np.flatnonzero(v) for v in set_vectors if v is not None]
                                      + [np.zeros(0, np.int64)]))
    residual_loads = []
    if 0 < len(loaded) <= _LOADED_BOUNDARY_LIMIT:
        boundary_kept = np.union1d(boundary_kept, loaded)
    else:
        residual_loads += [v[free] for v in set_vectors if v is not None]
    boundary_kept = np.unique(boundary_kept)
    boundary_positions = position[boundary_kept]
    boundary_positions = boundary_positions[boundary_positions >= 0]

    base_load = None
    if "base_acceleration" in exc:   # rigid translation ι in the kept (CD) DOFs; −M ι
        direction = np.asarray(exc["base_acceleration"]["direction"], dtype=float)
        local = np.einsum("nij,j->ni", deck.displacement_frames, direction)
        iota = np.where(system.dof_components < 3,
                        local[system.dof_nodes, np.minimum(system.dof_components, 2)], 0.0)
        base_load = -(m_ff @ iota[free])
        residual_loads.append(base_load)

    clock = time.perf_counter()
    red = data["reduction"]
    use_residuals = red.get("residual_vectors", True)
    cutoff = red.get("cutoff_hz", None if "mode_count" in red else default_cutoff_hz(case))
    loads_matrix = np.stack(residual_loads, axis=1) if residual_loads and use_residuals else None
    try:
        def reduce(mode_count, cutoff_hz):
            return craig_bampton(k_ff, m_ff, boundary_positions, mode_count=mode_count,
                                 cutoff_hz=cutoff_hz, residual_vectors=use_residuals,
                                 residual_loads=loads_matrix)
        reduced = reduce(red.get("mode_count"), cutoff)
        if "mode_count" not in red and reduced.mode_count < red["min_mode_count"]:
            reduced = reduce(min(red["min_mode_count"], len(free) - len(boundary_positions) - 1),
                             None)
    except Exception as exc_:   # any solver's failure (PARDISO, CHOLMOD, ARPACK): one line
        raise case.error(f"the structure is not held (singular stiffness: {' '.join(str(exc_).split())[:200]}); "
                         "check the supports and for mechanisms (unconnected parts, hinges)",
                         ("model", "fe", "supports")) from None
    timings["reduction_s"] = time.perf_counter() - clock
    _step(stages, "contacts, loads, ERP map")
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count
    kept_of_boundary = free[reduced.boundary_dofs]
    boundary_global = 6 * system.dof_nodes[kept_of_boundary] + system.dof_components[kept_of_boundary]

    def reduced_load(vector_free):
        out = np.zeros(n_r)
        out[:n_b] = vector_free[reduced.boundary_dofs]
        out += reduced.interior_basis.T @ vector_free[reduced.interior_dofs]
        return out

    loads = np.zeros((len(forces), n_r))
    coord = np.full(6 * deck.n_nodes, -1)
    coord[boundary_global] = np.arange(n_b)

    def coords_of(nodes_):
        nodes_ = np.asarray(nodes_)
        out = np.full((len(nodes_), 3), -1)
        ok = nodes_ >= 0
        out[ok] = coord[6 * nodes_[ok, None] + np.arange(3)]
        return out

    for i, (load, nodes_i, vector) in enumerate(zip(forces, group_nodes, set_vectors)):
        if vector is not None:
            loads[i] = reduced_load(vector[free])
            continue
        c = coords_of(nodes_i)
        for comp in range(3):
            ok = c[:, comp] >= 0
            np.add.at(loads[i], c[ok, comp], load["direction"][comp] / len(nodes_i))
    base = reduced_load(base_load) if base_load is not None else None

    added_damping = None
    if system.viscous_damping.nnz:    # dampers of the deck: D_r = Bᵀ D_ff B, B = [I 0; Ψ Φ]
        basis = np.zeros((len(free), n_r))
        basis[reduced.boundary_dofs, np.arange(n_b)] = 1.0
        basis[reduced.interior_dofs] = reduced.interior_basis
        d_ff = system.viscous_damping[free][:, free]
        added_damping = basis.T @ (d_ff @ basis)
    expanded = _expanded(reduced, system.transformation, free, boundary_global)
    contacts = {}
    for name, (a, b, frames, distance) in paired.items():
        geometry = ContactGeometry(name, a, b, frames, coords_of(a), coords_of(b), distance)
        e = prepared.element_contacts.get(name)
        if e is not None:   # per-pair stiffness of the springs the contact replaces
            geometry = dataclasses.replace(geometry, normal_stiffness=e.normal_stiffness,
                                           tangential_stiffness=e.tangential_stiffness)
        contacts[name] = geometry
    erp_nodes = np.unique(radiating)
    areas = nodal_areas(mesh.points, radiating)[erp_nodes]
    normals = nodal_normals(mesh.points, radiating)[erp_nodes]
    erp_map = normal_velocity_basis(expanded, normals, erp_nodes)
    _step(stages, None)
    info = {"nodes": int(deck.n_nodes), "triangles": int(mesh.n_triangles),
            "total_dofs": int(6 * deck.n_nodes), "kept_dofs": int(n_kept),
            "free_dofs": int(len(free)), "held_dofs": int(np.count_nonzero(fixed >= 0)),
            "auto_held_dofs": int(len(system.auto_held_nodes)), "boundary_dofs": int(n_b),
            "modes": int(reduced.mode_count), "residual_vectors": int(reduced.residual_vector_count),
            "reduced_dofs": int(n_r), "cutoff_hz": None if cutoff is None else float(cutoff),
            "radiating_nodes": int(len(erp_nodes)), "radiating_area_m2": float(areas.sum()),
            "linear_solver": reduced.solver,
            "total_mass_kg": mass_kg,
            **prepared.notes}
    return dict(kind="fe", mass=reduced.mass, stiffness=reduced.stiffness, damping=None,
                load_vectors=loads, base_vector=base, contacts=contacts, erp_map=erp_map,
                erp_areas=areas, erp_nodes=erp_nodes, mesh=mesh, reduced=expanded,
                mode_frequencies_hz=reduced.mode_frequencies_hz, info=info, timings=timings,
                node_ids=deck.node_ids, added_damping=added_damping)


def _translational_mass(system, deck) -> float:
    """Total mass [kg] = ιᵀ M ι for a rigid translation along x (all kept DOFs, before supports)."""
    local = deck.displacement_frames[:, :, 0]          # x in each node's CD components
    iota = np.where(system.dof_components < 3,
                    local[system.dof_nodes, np.minimum(system.dof_components, 2)], 0.0)
    return float(iota @ (system.mass @ iota))


def check_deck(case: Case) -> dict:
    """Validation of a deck case without assembly: cards, groups, quality, supports, pairing."""
    from sarfe.erp import nodal_normals
    from sarfe.pipeline.linear import pair_contact, resolve_node_group

    prepared = prepare_deck(case)
    mesh, work = prepared.mesh, prepared.case
    normals = nodal_normals(mesh.points, mesh.triangles)
    pairs = {}
    for i, c in enumerate(case.data["contacts"]):
        e = prepared.element_contacts.get(c["name"])
        pairs[c["name"]] = len(e.nodes_a) if e is not None else len(
            pair_contact(work, mesh, i, normals)[0])
    for i, f in enumerate(case.data["excitation"].get("forces", [])):
        if "load_set" in f:
            if str(f["load_set"]) not in prepared.deck.loads:
                raise case.error(f"load set '{f['load_set']}' not in the deck (available: "
                                 f"{', '.join(sorted(prepared.deck.loads)) or 'none'})",
                                 ("excitation", "forces", i, "load_set"))
        else:
            resolve_node_group(work, mesh, f["group"], ("excitation", "forces", i, "group"))
    surface = case.data["erp"].get("surface")
    if surface is not None and surface not in mesh.element_groups:
        raise case.error(f"element group '{surface}' not in the deck", ("erp", "surface"))
    return {"nodes": prepared.deck.n_nodes, "triangles": mesh.n_triangles,
            "contact_pairs": pairs, "ignored_cards": prepared.notes["ignored_cards"],
            "coincident_node_pairs": prepared.notes["coincident_node_pairs"],
            "coincident_nodes": prepared.notes["coincident_nodes"]}
