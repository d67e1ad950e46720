"""The checks reading a deck runs before any assembly (:func:`sarfe.pipeline.model.deck_model.
prepare_deck`; part of building the model, so they live in the model stage): element quality, the
supports as held DOFs, whether the structure is held (rigid motions left per connected part), the
mass of ignored cards, the plausibility of the deck's units. Each raises or returns what a one-line
CaseError names."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from sarfe.case.plausibility import (MIN_E_PA, MIN_RHO_KG_M3, POISSON_RANGE, SPAN_RANGE_M,
                                     THICKNESS_RANGE)
from sarfe.case.read import Case
from sarfe.mesh import quality
from sarfe.mesh.formats.abaqus import section_values
from sarfe.mesh.formats.deck import UNIT_SYSTEMS
from sarfe.mesh.formats.nastran_bdf import card_where, load_bdf
from sarfe.pipeline.model.groups import resolve_node_group

DECK_KEY = ("model", "fe", "deck")


def card_key(name: str) -> str:
    return str(name).upper().lstrip("*").strip()


# ------------------------------------------------------------------------------- quality
def check_quality(case: Case, deck, joined=()) -> dict:
    """Duplicate and zero-area shell elements are errors (with their ids); coincident nodes
    that no element, rigid element or contact joins are returned as a note."""
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
    fe = case.config.model.fe
    chosen = [str(s) for s in fe.deck.supports] or sorted(deck.supports)
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
    for i, group in enumerate(fe.fixed):
        nodes = resolve_node_group(case, mesh, group, ("model", "fe", "fixed", i),
                                   allow_elements=False)
        held[nodes] = True
    return held


def connected_parts(deck) -> tuple[int, np.ndarray, np.ndarray]:
    """(count, part of every node (n,), whether a node is used by any element (n,)): nodes
    joined by shells, solids, beams, two-node springs with some stiffness and rigid /
    interpolation elements. A spring without stiffness (a dashpot, e.g. the damping B kept from a
    spring turned into a contact) uses its nodes but joins nothing: it carries no static load."""
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
    deck_config = case.config.model.fe.deck
    path = case.resolve(deck_config.file)
    if path.suffix.lower() == ".inp":
        return {card: None for card in ignored}
    model = load_bdf(path)
    wtmass = model.params["WTMASS"].values[0] if "WTMASS" in model.params else 1.0
    scale = UNIT_SYSTEMS[deck_config.units].factor(0, 1) * wtmass
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


def massless_parts(deck) -> list[str]:
    """Connected parts (:func:`connected_parts`) none of whose nodes carries mass — their DOFs
    would have K but no M, and the modal reduction cannot factor M (LinAlgError) — as messages
    naming the part's GRIDs and the properties without density."""
    count, part, used = connected_parts(deck)
    heavy = np.zeros(deck.n_nodes, dtype=bool)
    shells = deck.shells
    heavy[shells.triangles[shells.mass_per_area > 0].ravel()] = True
    for block in deck.solids.values():
        heavy[block.connectivity[block.density > 0].ravel()] = True
    beams = deck.beams
    heavy[beams.nodes[(beams.density > 0) | (beams.mass_per_length > 0)].ravel()] = True
    heavy[deck.point_masses.node[deck.point_masses.mass > 0]] = True
    problems = []
    for p in range(count):
        nodes = np.flatnonzero((part == p) & used)
        if nodes.size == 0 or heavy[nodes].any():
            continue
        grids = deck.node_ids[nodes]
        in_part = np.isin(shells.triangles, nodes).any(axis=1)
        pids = np.unique(shells.property_ids[shells.triangle_element[in_part]])
        pids = np.concatenate([pids, np.unique(beams.property_ids[np.isin(beams.nodes, nodes)
                                                                  .any(axis=1)])])
        for block in deck.solids.values():
            pids = np.concatenate([pids, block.property_ids[np.isin(block.connectivity, nodes)
                                                             .any(axis=1)]])
        shown = ", ".join(str(int(i)) for i in np.unique(pids)[:5] if i > 0)
        problems.append(f"a part of {len(nodes)} nodes (GRIDs {int(grids.min())}…"
                        f"{int(grids.max())}) has no mass"
                        + (f" (property {shown}: its material has no density ρ)" if shown else ""))
    return problems


def check_material_bounds(case: Case, deck) -> None:
    """E > 0 and −1 < ν < 0.5 for every material of the deck — the bounds the case's own
    ``materials`` keys have (schema) — as a one-line CaseError on model.fe.deck naming the card;
    no unit advice (no unit system makes a modulus negative). ν of a shell section is read where
    the section is isotropic (A₁₁ = A₂₂, A₆₆ = (A₁₁ − A₁₂)/2: ν = A₁₂/A₁₁), of a beam from
    ν = E/(2G) − 1, of a solid as given."""
    deck_config = case.config.model.fe.deck
    path = case.resolve(deck_config.file)
    a = deck.shells.membrane
    a11, a22, a12, a66 = a[:, 0, 0], a[:, 1, 1], a[:, 0, 1], a[:, 2, 2]
    iso = np.isclose(a11, a22, rtol=1e-9) & np.isclose(a66, (a11 - a12) / 2, rtol=1e-9) & (a11 != 0)
    shell_nu = np.where(iso, np.divide(a12, a11, out=np.zeros_like(a11), where=a11 != 0), 0.0)
    beams = deck.beams
    beam_nu = np.divide(beams.young, 2 * beams.shear_modulus, out=np.ones_like(beams.young),
                        where=beams.shear_modulus != 0) - 1
    tables = [("shell", _section_moduli(deck.shells), shell_nu), ("beam", beams.young, beam_nu)]
    tables += [(f"solid:{kind}", b.young, b.poisson) for kind, b in deck.solids.items()]
    for table, young, nu in tables:
        bad_e = np.flatnonzero(np.nan_to_num(young, nan=1.0) <= 0)
        if bad_e.size:
            row = int(bad_e[0])
            where = _card_of(path, deck, deck_config.units, "E", table, row, float(young[row]))
            raise case.error(f"{where}: E = {young[row]:.4g} Pa must be > 0", DECK_KEY)
        low, high = POISSON_RANGE         # the schema's bounds of materials: nu
        bad_nu = np.flatnonzero((nu >= high - 1e-12) | (nu <= low))
        if bad_nu.size:
            row = int(bad_nu[0])
            where = _card_of(path, deck, deck_config.units, "E", table, row, float(young[row]))
            raise case.error(f"{where}: ν = {nu[row]:.4g} is outside {low:g} < ν < {high:g} (the "
                             "bounds of a case's materials: nu)", DECK_KEY)


def dependent_components(deck) -> np.ndarray:
    """(n, 6) bool: the components a rigid element makes dependent — an RBE2's dependent nodes
    in its CM components, an RBE3's reference node in its REFC components (the reader refuses
    partial masks on CD-frame nodes, so global and CD components agree where partial)."""
    dependent = np.zeros((deck.n_nodes, 6), dtype=bool)
    rbe2, rbe3 = deck.rbe2, deck.rbe3
    if len(rbe2.dependent):
        np.logical_or.at(dependent, rbe2.dependent, rbe2.components[rbe2.dependent_element])
    if len(rbe3.reference):
        np.logical_or.at(dependent, rbe3.reference, rbe3.reference_components)
    return dependent


def check_supports_on_dependents(case: Case, deck, held) -> None:
    """A support on a component a rigid element makes dependent: the one-line CaseError solve
    gives at assembly (:func:`sarfe.pipeline.model.deck_stage.held_kept_dofs`), before it."""
    both = held & dependent_components(deck)
    if np.any(both):
        node, comp = np.argwhere(both)[0]
        raise case.error(f"a support holds GRID {int(deck.node_ids[node])} component "
                         f"{int(comp) + 1}, which a rigid element (RBE2/RBE3) makes dependent",
                         ("model", "fe", "supports"))


def check_boundary_nodes(case: Case, deck, nodes, path) -> None:
    """Contact and force nodes become physical boundary DOFs (translations, global axes): a
    node with a rotated CD frame, or whose translations a rigid element makes dependent (an
    RBE2 dependent node, an RBE3 reference node), is a one-line CaseError at ``path`` — the
    same check validate and solve make before any assembly (a node without stiffness is found
    at assembly)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    if nodes.size == 0:
        return
    rotated = ~np.all(np.isclose(deck.displacement_frames[nodes], np.eye(3), atol=1e-12),
                      axis=(1, 2))
    if np.any(rotated):
        raise case.error(f"GRID {int(deck.node_ids[nodes[np.argmax(rotated)]])} has a rotated "
                         "displacement frame (CD): contact and force nodes must use the basic "
                         "frame", path)
    dependent = dependent_components(deck)[:, :3].any(axis=1)
    if np.any(dependent[nodes]):
        bad = nodes[np.argmax(dependent[nodes])]
        raise case.error(f"GRID {int(deck.node_ids[bad])} is a dependent node of a rigid element "
                         "(RBE2/RBE3): use an independent node", path)


def used_nodes(deck) -> np.ndarray:
    _, _, used = connected_parts(deck)
    return np.flatnonzero(used)


# ------------------------------------------------------------------------------------- units
UNITS_KEY = ("model", "fe", "units")
# upper bounds used only to pick a suggested unit system (never an error): stiffer than
# diamond or denser than osmium is not a material
_SUGGEST_MAX_E_PA, _SUGGEST_MAX_RHO_KG_M3 = 1.2e12, 2.3e4


def _section_moduli(shells) -> np.ndarray:
    """(m_t,) largest in-plane modulus [Pa] of each triangle's section, from its membrane
    stiffness A = t Q: E₁ = (A₁₁ − A₁₂²/A₂₂)/t, E₂ = (A₂₂ − A₁₂²/A₁₁)/t (exactly E for a
    MAT1, E₁₁/E₂₂ for a MAT8, laminate averages for a PCOMP)."""
    a = shells.membrane
    t = np.where(shells.thickness > 0, shells.thickness, np.nan)
    a11, a22, a12 = a[:, 0, 0], a[:, 1, 1], a[:, 0, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        e1 = (a11 - a12**2 / np.where(a22 != 0, a22, np.inf)) / t
        e2 = (a22 - a12**2 / np.where(a11 != 0, a11, np.inf)) / t
    return np.fmax(e1, e2)


def _section_densities(shells) -> np.ndarray:
    """(m_t,) density [kg/m³] of each triangle's section from its rotary inertia per area
    I = ∫ ρ z² dz = ρ t³/12: ρ = 12 I / t³ (a PSHELL's MID1 ρ, without the NSM that ρ t + NSM
    would mix in; a laminate's through-thickness average for a PCOMP); 0 where t = 0."""
    t = shells.thickness
    return np.divide(12.0 * shells.rotary_inertia_per_area, t**3, out=np.zeros_like(t),
                     where=t > 0)


def model_span(deck) -> float:
    """Bounding-box diagonal L [m] of the GRIDs that elements use (a stray reference GRID of a
    coordinate system does not count); 0 for no such GRID."""
    used = used_nodes(deck)
    return float(np.linalg.norm(np.ptp(deck.points[used], axis=0))) if used.size else 0.0


def unit_findings(deck) -> list[tuple]:
    """Values of a deck (in SI after its unit conversion) that no trim part has — the
    plausibility bounds of the case keys (:mod:`sarfe.case.plausibility`):

        E < 1e5 Pa, 0 < ρ < 1 kg/m³ (shell sections, solids, beams),
        model span L (:func:`model_span`) > 20 m or < 5 mm,
        shell thickness t > 0.1 L or t < 1e-4 L.

    Returns (quantity, table, row, value) per finding, worst first within a quantity:
    quantity 'E' [Pa], 'rho' [kg/m³], 'span' [m], 'thickness' [m]; table 'shell' (row = a
    triangle), 'solid:<cell type>' or 'beam' (row = an element row), 'grid' (row = None)."""
    moduli = [("shell", _section_moduli(deck.shells))]
    t = deck.shells.thickness
    densities = [("shell", _section_densities(deck.shells))]
    for kind, block in deck.solids.items():
        moduli.append((f"solid:{kind}", block.young))
        densities.append((f"solid:{kind}", block.density))
    moduli.append(("beam", deck.beams.young))
    densities.append(("beam", deck.beams.density))
    findings = []
    for quantity, tables, bad in (("E", moduli, lambda v: v < MIN_E_PA),
                                  ("rho", densities, lambda v: (v > 0) & (v < MIN_RHO_KG_M3))):
        for table, values in tables:
            rows = np.flatnonzero(bad(np.nan_to_num(values, nan=np.inf)))
            if rows.size:
                worst = int(rows[np.argmin(values[rows])])
                findings.append((quantity, table, worst, float(values[worst])))
    span = model_span(deck)
    if span > SPAN_RANGE_M[1] or 0 < span < SPAN_RANGE_M[0]:
        findings.append(("span", "grid", None, span))
    if span > 0 and t.size:
        low, high = THICKNESS_RANGE
        for rows in (np.flatnonzero(t > high * span), np.flatnonzero((t > 0) & (t < low * span))):
            if rows.size:
                worst = int(rows[np.argmax(np.abs(np.log(t[rows] / span)))])
                findings.append(("thickness", "shell", worst, float(t[worst])))
    return findings


def suggested_units(deck, units: str):
    """The unit system (a name of UNIT_SYSTEMS) under which the deck's moduli, densities and
    span would all be plausible (the errors' bounds, and E ≤ 1.2e12 Pa, ρ ≤ 2.3e4 kg/m³),
    closest to a typical trim part (median E 1e9 Pa, ρ 1e3 kg/m³, L 0.5 m, summed on a log
    scale); None when no other system passes.
    The deck is in SI as read with ``units``: a value v of dimension (l, m, t) becomes
    v · f_candidate / f_units."""
    moduli = np.concatenate([_section_moduli(deck.shells), deck.beams.young,
                             *[b.young for b in deck.solids.values()]])
    rho = np.concatenate([_section_densities(deck.shells), deck.beams.density,
                          *[b.density for b in deck.solids.values()]])
    span = model_span(deck)
    # (values, dimension, plausible range, typical value)
    quantities = [(moduli[np.isfinite(moduli) & (moduli > 0)], (-1, 1, -2),
                   (MIN_E_PA, _SUGGEST_MAX_E_PA), 1e9),
                  (rho[rho > 0], (-3, 1, 0), (MIN_RHO_KG_M3, _SUGGEST_MAX_RHO_KG_M3), 1e3),
                  (np.array([span]) if span > 0 else np.zeros(0), (1, 0, 0), SPAN_RANGE_M, 0.5)]
    current = UNIT_SYSTEMS[units]
    best, best_score = None, np.inf
    for name, system in UNIT_SYSTEMS.items():
        if system.factor(1) == current.factor(1) and system.factor(0, 1) == current.factor(0, 1) \
                and system.factor(0, 0, 1) == current.factor(0, 0, 1):
            continue                      # the same system (or an alias of it, m-kg-s = SI)
        score, plausible = 0.0, True
        for values, dim, (low, high), typical in quantities:
            if not values.size:
                continue
            scaled = values * system.factor(*dim) / current.factor(*dim)
            plausible &= bool(low <= scaled.min() and scaled.max() <= high)
            score += abs(np.log10(np.median(scaled) / typical))
        if plausible and score < best_score:
            best, best_score = name, score
    return best


_RULES = {"E": "E < 1e5 Pa", "rho": "ρ < 1 kg/m³"}
_SYMBOL = {"E": ("E", "Pa"), "rho": ("ρ", "kg/m³")}
_DIMENSION = {"E": (-1, 1, -2), "rho": (-3, 1, 0), "thickness": (1, 0, 0)}


def units_given(case: Case) -> bool:
    """Whether the case file names model.fe.units itself (not the default SI)."""
    return "units" in (case.data.get("model", {}).get("fe", {}) or {})


def check_units(case: Case, deck) -> list[str]:
    """The plausibility of the deck's units (:func:`unit_findings`), as one line per finding
    naming the deck card (file:line: MAT1 1, PSHELL 1, …), the value in SI, the rule and, when
    one fits, the unit system the deck looks like:

        deck.bdf:1473: MAT1 1: E = 2200 Pa with units: SI — implausible for a trim part
        (E < 1e5 Pa); the deck looks like mm-t-s: set model.fe.units: mm-t-s

    Returns the warnings. E, ρ or span findings are a CaseError on model.fe.units while the case
    leaves ``units`` at its default (with the system the deck looks like, if one fits); an
    explicit ``units:`` wins and the finding is a warning (a real structure with near-zero ρ
    and its mass in CONM2s, e.g. the Goland wing, is kept). Thickness-to-size findings are
    warnings (no unit system changes a ratio of lengths: a real thin web or thick laminate is
    kept). What no unit system can make plausible — E ≤ 0, ν outside (−1, 0.5) — is refused by
    :func:`check_material_bounds`."""
    findings = unit_findings(deck)
    if not findings:
        return []
    deck_config = case.config.model.fe.deck
    units, path = deck_config.units, case.resolve(deck_config.file)
    suggestion = suggested_units(deck, units)
    explicit = units_given(case)
    warnings = []
    for quantity, table, row, value in findings:
        if quantity == "thickness":
            span = model_span(deck)
            low, high = THICKNESS_RANGE
            rule = (f"above {high:g} of the model size {span:.3g} m" if value > high * span
                    else f"below {low:g} of the model size {span:.3g} m")
            where = _card_of(path, deck, units, quantity, table, row, value)
            warnings.append(f"{where}: thickness {value:.3g} m with units: {units} — {rule}; "
                            "kept (check that the thickness and the GRIDs share a length unit)")
            continue
        if quantity == "span":
            side = f"> {SPAN_RANGE_M[1]:g} m" if value > SPAN_RANGE_M[1] else \
                f"< {SPAN_RANGE_M[0] * 1e3:g} mm"
            text = (f"{path}: the GRIDs span {value:.3g} m with units: {units} — "
                    f"implausible for a trim part ({side})")
        else:
            symbol, unit = _SYMBOL[quantity]
            where = _card_of(path, deck, units, quantity, table, row, value)
            text = (f"{where}: {symbol} = {value:.4g} {unit} with units: {units} — implausible "
                    f"for a trim part ({_RULES[quantity]})")
        if not explicit:
            advice = (f"the deck looks like {suggestion}: set model.fe.units: {suggestion}"
                      if suggestion else "no unit system makes the deck plausible: check the "
                      "deck's values")
            raise case.error(f"{text}; {advice} (or units: {units} to keep {units})", UNITS_KEY)
        warnings.append(f"{text}; kept as model.fe.units: {units} says" +
                        (f" (the deck would look plausible in {suggestion})" if suggestion else ""))
    return list(dict.fromkeys(warnings))      # one card found by several tables: once


def _card_of(path, deck, units, quantity, table, row, value) -> str:
    """'file:line: CARD id' of the value found: the material (E, ρ) or property (thickness)
    card of a Nastran deck; the *MATERIAL / *SHELL SECTION line of an Abaqus file whose value
    in SI equals it; else the element."""
    if table == "shell":
        element = int(deck.shells.triangle_element[row])
        eid, pid = int(deck.shells.element_ids[element]), int(deck.shells.property_ids[element])
    elif table == "beam":
        eid, pid = int(deck.beams.element_ids[row]), int(deck.beams.property_ids[row])
    else:
        block = deck.solids[table.split(":", 1)[1]]
        eid, pid = int(block.element_ids[row]), int(block.property_ids[row])
    if path.suffix.lower() == ".inp":
        scale = UNIT_SYSTEMS[units].factor(*_DIMENSION[quantity])
        for where, key, raw in section_values(path):
            if key == quantity and np.isclose(raw * scale, value, rtol=1e-6):
                return where
        return f"{path}: element {eid}"
    model = load_bdf(path)
    if table == "beam" and pid == 0:    # CONROD: the material is on the element
        card = model.elements.get(eid)
    else:
        card = model.properties.get(pid)
    if card is None:
        return card_where(path, str(deck.beams.card[row]) if table == "beam" else "element", eid)
    if quantity == "thickness" or card.type == "PCOMP":
        return card_where(path, card.type, pid)
    mid = getattr(card, "mid1", None) or getattr(card, "mid", None)
    material = model.materials.get(int(mid)) if mid else None
    if material is None:
        return card_where(path, card.type, getattr(card, "pid", eid))
    return card_where(path, material.type, int(mid))
