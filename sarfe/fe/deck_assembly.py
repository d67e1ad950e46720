"""`DeckModel` → global sparse K, M on 6 DOF per node, constraints eliminated.

Steps (global DOF g = 6·node + c, c = 0..5 = [ux, uy, uz, rx, ry, rz], global axes):
1. K, M summed from every element table in one coo → csr pass: shells (`sarfe.fe.deck_shells`:
   by default the commercial solver's membranes — incompatible-mode quads, constant-strain
   triangles, weak drilling penalty — with DKT/DKMT bending), solids (`sarfe.fe.solid_cells`,
   3 translations of the same nodes), beams/rods, springs, CONM2 (`sarfe.fe.line_elements`).
   Element masses lumped (:func:`lumped_mass`) unless the deck asks for coupled mass
   (PARAM,COUPMASS > 0), as the commercial solver.
2. RBE2/RBE3 eliminated exactly: u = C q (`sarfe.fe.constraints`).
3. The remaining DOFs expressed in each node's output (CD) frame: u_node = Rᵀ q_cd per
   3-component block, R = ``displacement_frames[node]`` (rows = CD axes).
   With T = C·blockdiag(Rᵀ): K_r = Tᵀ K T, M_r = Tᵀ M T, and a global load f gives Tᵀ f.
4. DOFs with no stiffness after 2–3 (zero diagonal of K_r: rotations of nodes used only by
   solids or rods, nodes used by no element) are held at zero (like Nastran's AUTOSPC) and
   listed in ``auto_held``; K_r has no zero pivot left from them.

Spring damping is returned beside K: ``structural_damping`` = Σ GE_e K_e (hysteretic, to be
multiplied by i) and ``viscous_damping`` = Σ B_e, both on the kept DOFs. The HBM model carries
only the viscous part (its D enters S_k as i kω D, and the time integration as D u̇): a case whose
deck keeps a hysteretic GE is refused (:mod:`sarfe.pipeline.model.deck_model`); with PARAM,W4 the Nastran
reader has already moved GE into B = GE·K/W4, equal to i·GE·K at ω = W4.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from sarfe.mesh.formats.deck import DeckError, DeckModel

from sarfe.fe.assembly import lumped_mass
from sarfe.fe.constraints import constraint_matrix
from sarfe.fe.deck_shells import DECK_MEMBRANE, shell_blocks
from sarfe.fe.line_elements import beam_matrices, point_mass_matrices, spring_matrices
from sarfe.fe.membrane import DRILLING_PENALTY
from sarfe.fe.solid_cells import DegenerateCellError, solid_cell_matrices

__all__ = ["DeckSystem", "assemble_deck", "support_dofs", "load_vector", "lumped_mass",
           "global_matrices", "mass_properties", "deck_mass"]

_BLOCK = 4096


@dataclass(frozen=True)
class DeckSystem:
    """Assembled deck on its kept DOFs q (n_kept,), in the nodes' CD frames.

    stiffness, mass        CSR (n_kept, n_kept) [N/m, N, N·m | kg, kg·m, kg·m²]
    structural_damping     CSR Σ GE·K of the springs; viscous_damping CSR Σ B [N·s/m …]
    dof_nodes              (n_kept,) node index of each kept DOF
    dof_components         (n_kept,) component 0..5 in the node's CD frame
    transformation         CSR (6n, n_kept): u_global = T q (global DOF 6·node + c)
    auto_held_nodes, auto_held_components (h,)  DOFs without stiffness, held at zero
    n_nodes                int
    """

    stiffness: sp.csr_matrix
    mass: sp.csr_matrix
    structural_damping: sp.csr_matrix
    viscous_damping: sp.csr_matrix
    dof_nodes: np.ndarray
    dof_components: np.ndarray
    transformation: sp.csr_matrix
    auto_held_nodes: np.ndarray
    auto_held_components: np.ndarray
    n_nodes: int

    @property
    def n_dofs(self) -> int:
        return int(self.dof_nodes.shape[0])

    def dof_index(self, nodes, components) -> np.ndarray:
        """Kept DOF numbers of (node, component) pairs (broadcast); −1 where not kept
        (dependent in a rigid element or held for having no stiffness)."""
        nodes, components = np.broadcast_arrays(np.asarray(nodes, np.int64),
                                                np.asarray(components, np.int64))
        lookup = np.full(6 * self.n_nodes, -1, np.int64)
        lookup[6 * self.dof_nodes + self.dof_components] = np.arange(self.n_dofs)
        return lookup[6 * nodes + components]

    def displacement(self, q) -> np.ndarray:
        """Global nodal displacements (n, 6) [m, rad] of kept-DOF values q (n_kept,)."""
        return (self.transformation @ np.asarray(q)).reshape(self.n_nodes, 6)


def _element_blocks(deck: DeckModel, drilling_penalty, mass="consistent",
                    membrane=DECK_MEMBRANE):
    """Yield (K_e, M_e, dofs) blocks of every element table (CONM2 never lumped)."""
    for k, m, dofs in _structural_blocks(deck, drilling_penalty, membrane, mass):
        yield k, (lumped_mass(m, dofs) if mass == "lumped" else m), dofs
    if len(deck.point_masses.node):
        m, dofs = point_mass_matrices(deck.point_masses)
        yield np.zeros_like(m), m, dofs


def _structural_blocks(deck: DeckModel, drilling_penalty, membrane=DECK_MEMBRANE,
                       mass="consistent"):
    """Yield (K_e, M_e, dofs) of shells, solids, beams and springs (``mass`` 'lumped': the
    beams' torsional inertia as the commercial solver lumps it, `beam_matrices`)."""
    yield from shell_blocks(deck, membrane, drilling_penalty)
    for kind, block in deck.solids.items():
        for start in range(0, len(block.element_ids), _BLOCK // 8):
            rows = slice(start, start + _BLOCK // 8)
            try:
                k, m, dofs = solid_cell_matrices(deck.points, block.connectivity[rows], kind,
                                                 block.young[rows], block.poisson[rows],
                                                 block.density[rows])
            except DegenerateCellError as error:
                eid = int(block.element_ids[rows][error.row])
                raise DeckError(f"{deck.source}: solid element {eid} ({kind}) has a degenerate "
                                "or inverted mapping (check its node order)") from error
            yield k, m, dofs
    if len(deck.beams.element_ids):
        try:
            yield beam_matrices(deck.points, deck.beams, lumped_torsion=mass == "lumped")
        except ValueError as error:
            raise DeckError(f"{deck.source}: {error}") from error
    if len(deck.springs.element_ids):
        k, _, _, dofs = spring_matrices(deck.points, deck.springs)
        yield k, np.zeros_like(k), dofs


def _sum_blocks(blocks, n_dof):
    """One coo → csr pass over all element blocks; K and M summed as K + iM."""
    blocks = list(blocks)
    if not blocks:
        zero = sp.csr_matrix((n_dof, n_dof))
        return zero, zero.copy()
    index_type = np.int32 if n_dof < 2**31 - 1 else np.int64
    total = sum(dofs.shape[0] * dofs.shape[1] ** 2 for _, _, dofs in blocks)
    rows = np.empty(total, index_type)
    cols = np.empty(total, index_type)
    vals = np.empty(total, complex)
    start = 0
    for k, m, dofs in blocks:
        n_el, size = dofs.shape
        stop = start + n_el * size * size
        rows[start:stop].reshape(n_el, size, size)[...] = dofs[:, :, None]
        cols[start:stop].reshape(n_el, size, size)[...] = dofs[:, None, :]
        vals[start:stop].real = k.ravel()
        vals[start:stop].imag = m.ravel()
        start = stop
    matrix = sp.coo_matrix((vals, (rows, cols)), shape=(n_dof, n_dof)).tocsr()
    del rows, cols, vals
    return (sp.csr_matrix((matrix.data.real.copy(), matrix.indices, matrix.indptr), shape=matrix.shape),
            sp.csr_matrix((matrix.data.imag.copy(), matrix.indices.copy(), matrix.indptr.copy()),
                          shape=matrix.shape))


def _spring_damping(deck, n_dof):
    if not len(deck.springs.element_ids):
        zero = sp.csr_matrix((n_dof, n_dof))
        return zero, zero.copy()
    _, structural, viscous, dofs = spring_matrices(deck.points, deck.springs)
    n_el, size = dofs.shape
    r = np.broadcast_to(dofs[:, :, None], (n_el, size, size)).ravel()
    c = np.broadcast_to(dofs[:, None, :], (n_el, size, size)).ravel()
    return (sp.csr_matrix((structural.ravel(), (r, c)), shape=(n_dof, n_dof)),
            sp.csr_matrix((viscous.ravel(), (r, c)), shape=(n_dof, n_dof)))


def _frame_transform(frames, independent):
    """(6n_indep_nodes-ish) CSR mapping CD-frame DOFs to global DOFs on the independent set.

    Column j = independent DOF (node, cd component); entries R[c_cd, c_global] (u_g = Rᵀ q).
    A node with only some of a 3-block independent keeps those columns: the rotation mixes
    components, so a partly dependent block must be in a global-axis frame (the reader
    refuses partial components on nodes with a CD system)."""
    nodes, comps = independent // 6, independent % 6
    block, local = comps // 3, comps % 3
    rows = (6 * nodes[:, None] + 3 * block[:, None] + np.arange(3)).ravel()
    vals = frames[nodes, local, :].ravel()  # R[local, global] for global = 0..2
    cols = np.repeat(np.arange(len(independent)), 3)
    return rows, cols, vals


def deck_mass(deck: DeckModel, mass=None) -> str:
    """The element mass a deck is assembled with: ``mass`` if given ('consistent' | 'lumped'),
    else the deck's own — 'consistent' for PARAM,COUPMASS > 0 (``deck.coupled_mass``), 'lumped'
    otherwise, as the commercial solver's default."""
    if mass is None:
        return "consistent" if deck.coupled_mass else "lumped"
    if mass not in ("consistent", "lumped"):
        raise ValueError(f"mass must be 'consistent' or 'lumped', got {mass!r}")
    return mass


def _drilling(deck: DeckModel, drilling_penalty, membrane):
    """α: given, else the deck's (1e-6·K6ROT) — or the Allman penalty for 'allman'."""
    if drilling_penalty is not None:
        return drilling_penalty
    return DRILLING_PENALTY if membrane == "allman" else deck.drilling_penalty


def global_matrices(deck: DeckModel, mass=None, drilling_penalty=None,
                    membrane=DECK_MEMBRANE):
    """K, M (CSR (6n, 6n), global DOFs 6·node + c, global axes) before any constraint:
    e.g. for mass properties, M's rigid-body quadratic forms. Arguments as :func:`assemble_deck`."""
    return _sum_blocks(_element_blocks(deck, _drilling(deck, drilling_penalty, membrane),
                                       deck_mass(deck, mass), membrane), 6 * deck.n_nodes)


def assemble_deck(deck: DeckModel, mass=None, drilling_penalty=None,
                  membrane=DECK_MEMBRANE) -> DeckSystem:
    """Global K, M of a deck with RBE2/RBE3 eliminated, in CD frames, zero-stiffness DOFs held.

    mass: None (the deck's: lumped unless PARAM,COUPMASS > 0, :func:`deck_mass`), 'lumped'
    (:func:`lumped_mass`) or 'consistent' (sarfe's element masses). membrane: the shells'
    membrane (:mod:`sarfe.fe.deck_shells`; default 'nastran': incompatible-mode quads, constant
    strain triangles, weak drilling penalty α = ``drilling_penalty``, None = the deck's
    1e-6·K6ROT). See the module docstring for the steps; raises DeckError naming the element
    or card.
    """
    n = deck.n_nodes
    n_dof = 6 * n
    stiffness, mass = global_matrices(deck, mass, drilling_penalty, membrane)
    structural, viscous = _spring_damping(deck, n_dof)
    try:
        c_matrix, independent = constraint_matrix(deck.points, deck.rbe2, deck.rbe3, n)
    except ValueError as error:
        raise DeckError(f"{deck.source}: {error}") from error
    # independent DOFs → the same DOFs in CD components (only identity frames change nothing)
    rows, cols, vals = _frame_transform(deck.displacement_frames, independent)
    position = np.full(n_dof, -1, np.int64)
    position[independent] = np.arange(len(independent))
    rows_in = position[rows]
    keep = (rows_in >= 0) & (vals != 0)
    frame_map = sp.csr_matrix((vals[keep], (rows_in[keep], cols[keep])),
                              shape=(len(independent), len(independent)))
    transform = (c_matrix @ frame_map).tocsr()
    k_r = (transform.T @ stiffness @ transform).tocsr()
    diagonal = k_r.diagonal()
    scale = np.abs(diagonal).max() if diagonal.size else 1.0
    # no element touches these DOFs: their diagonal is exactly zero (1e-15: round-off of the
    # constraint products; a real but soft spring sits far above it)
    held = np.abs(diagonal) <= 1e-15 * scale
    kept = np.flatnonzero(~held)
    transform = transform[:, kept].tocsr()

    def reduce(matrix):
        return (transform.T @ matrix @ transform).tocsr()

    k_kept = k_r[kept][:, kept].tocsr()
    return DeckSystem(
        stiffness=0.5 * (k_kept + k_kept.T), mass=reduce(mass),
        structural_damping=reduce(structural), viscous_damping=reduce(viscous),
        dof_nodes=independent[kept] // 6, dof_components=independent[kept] % 6,
        transformation=transform,
        auto_held_nodes=independent[held] // 6, auto_held_components=independent[held] % 6,
        n_nodes=n)


def support_dofs(system: DeckSystem, deck: DeckModel, name) -> np.ndarray:
    """Kept DOF numbers held by support set ``name`` (plus the 'permanent' GRID PS set).

    DOFs already held for lack of stiffness are skipped; a support on a DOF that a rigid
    element made dependent is a DeckError naming the node id."""
    names = [str(name)] + (["permanent"] if "permanent" in deck.supports and str(name) != "permanent" else [])
    out = []
    held = set(zip(system.auto_held_nodes.tolist(), system.auto_held_components.tolist()))
    for key in names:
        if key not in deck.supports:
            raise DeckError(f"{deck.source}: support set {key!r} not in the deck; "
                            f"available: {', '.join(deck.supports) or 'none'}")
        support = deck.supports[key]
        nodes, comps = np.nonzero(support.components)
        nodes = support.nodes[nodes]
        index = system.dof_index(nodes, comps)
        for node, comp in zip(nodes[index < 0], comps[index < 0]):
            if (int(node), int(comp)) not in held:
                raise DeckError(f"{deck.source}: support set {key}: node "
                                f"{int(deck.node_ids[node])} component {int(comp) + 1} is "
                                "dependent in a rigid element (RBE2/RBE3)")
        out.append(index[index >= 0])
    return np.unique(np.concatenate(out)) if out else np.zeros(0, np.int64)


def load_vector(system: DeckSystem, deck: DeckModel, name) -> np.ndarray:
    """Generalised load Tᵀ f (n_kept,) [N, N·m] of load set ``name`` (global nodal forces)."""
    key = str(name)
    if key not in deck.loads:
        raise DeckError(f"{deck.source}: load set {key!r} not in the deck; "
                        f"available: {', '.join(deck.loads) or 'none'}")
    return system.transformation.T @ np.asarray(deck.loads[key], float).ravel()


def mass_properties(deck: DeckModel, mass="consistent"):
    """Total mass [kg] and centre of gravity (3,) [m] from the assembled global M.

    For a unit rigid acceleration along axis c (u = e_c at every node, r_c), the inertia
    forces f = M r_c give the mass m = r_cᵀ M r_c and the moment about the origin
    Σ_n (x_n × f_n,trans + f_n,rot) = m (x_cg × e_c), from which x_cg follows."""
    _, matrix = global_matrices(deck, mass)
    n = deck.n_nodes
    moments, total = [], 0.0
    for c in range(3):
        rigid = np.zeros((n, 6))
        rigid[:, c] = 1.0
        force = (matrix @ rigid.ravel()).reshape(n, 6)
        total = force[:, c].sum() if c == 0 else total
        moments.append(np.cross(deck.points, force[:, :3]).sum(axis=0) + force[:, 3:].sum(axis=0))
    if total == 0.0:
        return 0.0, np.zeros(3)
    # m (x × e_x) = m (0, z, −y); m (x × e_y) = m (−z, 0, x)
    cg = np.array([moments[1][2], -moments[0][2], moments[0][1]]) / total
    return float(total), cg
