"""Checks of a deck before any assembly (used by :mod:`sarfe.pipeline.deck`): element quality,
the supports as held DOFs, whether the structure is held (rigid motions left per connected part),
the mass of ignored cards. Each raises or returns what a one-line CaseError names."""
from __future__ import annotations

import numpy as np

from sarfe.io.case import Case

DECK_KEY = ("model", "fe", "deck")


def card_key(name: str) -> str:
    return str(name).upper().lstrip("*").strip()


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

    fe = case.config.model.fe.data
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
    joined by shells, solids, beams, two-node springs with some stiffness and rigid /
    interpolation elements. A spring without stiffness (a dashpot, e.g. the damping B kept from a
    spring turned into a contact) uses its nodes but joins nothing: it carries no static load."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = deck.n_nodes
    springs = deck.springs
    stiff = np.any(springs.stiffness != 0.0, axis=1)
    spring_edges = np.stack([springs.node_a, springs.node_b], axis=1)
    edges = [deck.shells.triangles[:, [0, 1]], deck.shells.triangles[:, [1, 2]],
             deck.beams.nodes, spring_edges[stiff],
             np.stack([deck.rbe2.independent[deck.rbe2.dependent_element], deck.rbe2.dependent], 1),
             np.stack([deck.rbe3.reference[deck.rbe3.independent_element], deck.rbe3.independent], 1)]
    for block in deck.solids.values():
        c = block.connectivity
        edges += [np.stack([c[:, 0], c[:, k]], axis=1) for k in range(1, c.shape[1])]
    edges = np.concatenate([e.reshape(-1, 2) for e in edges]).astype(np.int64)
    used = np.zeros(n, dtype=bool)
    used[edges[edges >= 0]] = True
    used[spring_edges[spring_edges >= 0]] = True
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


def ignored_mass(case: Case, ignored: dict) -> dict:
    """{card: mass [kg] its elements and masses carry} of the ignored cards of a Nastran deck
    (pyNastran's mass properties, PARAM,WTMASS included; 0 for loads and other massless cards);
    None per card for an Abaqus file (not computed)."""
    if not ignored:
        return {}
    fe = case.config.model.fe.data
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
        key = card_key(card)
        cards = [el for el in list(model.elements.values()) + list(model.masses.values())
                 if el.type == key]
        try:   # each card's own Mass() (pyNastran: ρ, thickness/area and NSM of its property)
            masses[card] = float(sum(el.Mass() for el in cards)) * scale
        except Exception:   # a card pyNastran cannot weigh: say so rather than guess
            masses[card] = None
    return masses


def has_mass(deck) -> bool:
    """Whether any element or point mass of the deck carries mass."""
    return bool(np.any(deck.shells.mass_per_area > 0) or np.any(deck.point_masses.mass > 0)
                or any(np.any(b.density > 0) for b in deck.solids.values())
                or np.any(deck.beams.density > 0) or np.any(deck.beams.mass_per_length > 0))


def used_nodes(deck) -> np.ndarray:
    _, _, used = connected_parts(deck)
    return np.flatnonzero(used)
