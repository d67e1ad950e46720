"""`DeckModel`: a reader-neutral finite-element deck (Nastran bulk data, Abaqus input).

Plain numpy arrays in small frozen dataclasses. After :func:`to_si` every quantity is SI
(m, kg, s, N); node references are 0-based indices into ``DeckModel.points`` (the deck's
own GRID / node ids are kept in ``node_ids``, element ids in each table's ``element_ids``).
Components of nodal DOFs are numbered 0..5 = [ux, uy, uz, rx, ry, rz]; a component mask is
a (…, 6) bool array. Supports, loads and spring/contact directions of a node refer to its
output (displacement, Nastran "CD") frame ``displacement_frames[node]``; geometry is global.

Readers: :func:`sarfe.mesh.formats.nastran.read_nastran` (and the Abaqus reader). Assembly into
global K, M: :func:`sarfe.fe.deck_assembly.assemble_deck`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "DeckModel", "ShellElements", "SolidElements", "BeamElements", "SpringElements",
    "PointMasses", "RigidElements", "InterpolationElements", "SupportSet", "UnitSystem",
    "UNIT_SYSTEMS", "DeckError", "to_si", "SOLID_TYPES",
]

#: solid cell types and their node counts (node order as in Nastran CTETRA/CHEXA/CPENTA)
SOLID_TYPES = {"tet4": 4, "tet10": 10, "hex8": 8, "hex20": 20, "wedge6": 6}


class DeckError(ValueError):
    """A deck cannot be read or modelled; one line naming the file and the card/keyword and id."""


def _ints(n_or_shape=0):
    return np.zeros(n_or_shape, dtype=np.int64)


def _floats(shape=0):
    return np.zeros(shape, dtype=float)


@dataclass(frozen=True)
class ShellElements:
    """Shell elements (CTRIA3/CQUAD4/CTRIA6/CQUAD8, S3/S4/…) as flat facet triangles: quads
    split in two, 6/8-node elements into 4/6 triangles through their midside nodes.

    element_ids         (m,) int        deck element ids
    property_ids        (m,) int        PSHELL/PCOMP id (Abaqus: section number)
    triangles           (m_t, 3) int    node indices, counter-clockwise about the element normal
    triangle_element    (m_t,) int      row of each triangle in ``element_ids``
    membrane            (m_t, 3, 3)     A [N/m]:  N = A ε + B κ   (Voigt [xx, yy, xy], γ_xy)
    coupling            (m_t, 3, 3)     B [N]:    M = B ε + D κ   (about the node plane)
    bending             (m_t, 3, 3)     D [N·m]
    transverse_shear    (m_t, 2, 2)     G t (with any shear factor) [N/m]; zeros = not given
    material_axis       (m_t, 3)        unit vector of the section's axis 1 (the x of A/B/D)
                                        in global coordinates, in the element plane
    mass_per_area       (m_t,)          ρ t + NSM [kg/m²]
    rotary_inertia_per_area (m_t,)      ∫ ρ z² dz about the mid-surface [kg]
    thickness           (m_t,)          total thickness [m] (information, drilling penalty)
    offset              (m_t,)          mid-surface offset o along the normal from the node plane
                                        [m] (ZOFFS, PCOMP Z0 + T/2). A, B, D are about the node
                                        plane (B = B_mid + o A, D = D_mid + 2 o B_mid + o² A);
                                        the assembly adds the mass's first moment m'' o
    """

    element_ids: np.ndarray = field(default_factory=_ints)
    property_ids: np.ndarray = field(default_factory=_ints)
    triangles: np.ndarray = field(default_factory=lambda: _ints((0, 3)))
    triangle_element: np.ndarray = field(default_factory=_ints)
    membrane: np.ndarray = field(default_factory=lambda: _floats((0, 3, 3)))
    coupling: np.ndarray = field(default_factory=lambda: _floats((0, 3, 3)))
    bending: np.ndarray = field(default_factory=lambda: _floats((0, 3, 3)))
    transverse_shear: np.ndarray = field(default_factory=lambda: _floats((0, 2, 2)))
    material_axis: np.ndarray = field(default_factory=lambda: _floats((0, 3)))
    mass_per_area: np.ndarray = field(default_factory=_floats)
    rotary_inertia_per_area: np.ndarray = field(default_factory=_floats)
    thickness: np.ndarray = field(default_factory=_floats)
    offset: np.ndarray = field(default_factory=_floats)

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])


@dataclass(frozen=True)
class SolidElements:
    """One block of isotropic solid elements of a single cell type (see ``SOLID_TYPES``).

    cell_type     str              'tet4' | 'tet10' | 'hex8' | 'hex20' | 'wedge6'
    element_ids   (m,) int
    property_ids  (m,) int
    connectivity  (m, k) int       node indices in Nastran order (corners, then midsides)
    young         (m,) [Pa]; poisson (m,) [-]; density (m,) [kg/m³]
    """

    cell_type: str
    element_ids: np.ndarray
    property_ids: np.ndarray
    connectivity: np.ndarray
    young: np.ndarray
    poisson: np.ndarray
    density: np.ndarray


@dataclass(frozen=True)
class BeamElements:
    """Two-node line elements: CBAR, CBEAM (constant section), CROD (axial + torsion only).

    card          (m,) str          'CBAR' | 'CBEAM' | 'CROD' | Abaqus type
    element_ids, property_ids (m,) int
    nodes         (m, 2) int        end node indices
    orientation   (m, 3)            global vector v in the beam's x–y plane (zeros for rods)
    area (m,) [m²]; i1, i2 (m,) [m⁴] (about the element y / z axes: bending in the
    x–y plane uses I1); i12 (m,) [m⁴]; torsion (m,) J [m⁴]
    shear_factor_1, shear_factor_2 (m,) [-]  shear area = factor·A in planes 1, 2 (Timoshenko);
                                     0 = rigid in shear (Euler–Bernoulli), as Nastran's blank
    young, shear_modulus (m,) [Pa]; density (m,) [kg/m³]; mass_per_length (m,) NSM [kg/m]
    """

    card: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U8"))
    element_ids: np.ndarray = field(default_factory=_ints)
    property_ids: np.ndarray = field(default_factory=_ints)
    nodes: np.ndarray = field(default_factory=lambda: _ints((0, 2)))
    orientation: np.ndarray = field(default_factory=lambda: _floats((0, 3)))
    area: np.ndarray = field(default_factory=_floats)
    i1: np.ndarray = field(default_factory=_floats)
    i2: np.ndarray = field(default_factory=_floats)
    i12: np.ndarray = field(default_factory=_floats)
    torsion: np.ndarray = field(default_factory=_floats)
    shear_factor_1: np.ndarray = field(default_factory=_floats)
    shear_factor_2: np.ndarray = field(default_factory=_floats)
    young: np.ndarray = field(default_factory=_floats)
    shear_modulus: np.ndarray = field(default_factory=_floats)
    density: np.ndarray = field(default_factory=_floats)
    mass_per_length: np.ndarray = field(default_factory=_floats)


@dataclass(frozen=True)
class SpringElements:
    """Springs between two nodes or node-to-ground (CBUSH, CELAS1/2, Abaqus *SPRING).

    Force on node b: f = −K (u_b − u_a) in the spring frame; grounded springs (node_b = −1)
    act on node a alone.
    card          (k,) str          'CBUSH' | 'CELAS1' | 'CELAS2' | 'SPRING1' | 'SPRING2'
    element_ids, property_ids (k,) int (property 0 for CELAS2)
    node_a        (k,) int
    node_b        (k,) int          −1 = ground
    stiffness     (k, 6)            [N/m ×3, N·m/rad ×3] along the frame axes
    frames        (k, 3, 3)         rows = spring axes 1, 2, 3 in global coordinates
    structural_damping (k,)         GE [-] (damping K·GE·i)
    viscous_damping (k, 6)          B [N·s/m ×3, N·m·s/rad ×3]
    location      (k,)              CBUSH S: the spring acts at x_a + s (x_b − x_a), tied to
                                    both nodes by rigid arms; NaN = scalar spring on the node
                                    DOFs themselves (CELAS, *SPRING)
    """

    card: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U8"))
    element_ids: np.ndarray = field(default_factory=_ints)
    property_ids: np.ndarray = field(default_factory=_ints)
    node_a: np.ndarray = field(default_factory=_ints)
    node_b: np.ndarray = field(default_factory=_ints)
    stiffness: np.ndarray = field(default_factory=lambda: _floats((0, 6)))
    frames: np.ndarray = field(default_factory=lambda: _floats((0, 3, 3)))
    structural_damping: np.ndarray = field(default_factory=_floats)
    viscous_damping: np.ndarray = field(default_factory=lambda: _floats((0, 6)))
    location: np.ndarray = field(default_factory=_floats)


@dataclass(frozen=True)
class PointMasses:
    """Concentrated masses (CONM2, Abaqus *MASS/*ROTARY INERTIA).

    element_ids (p,) int; node (p,) int; mass (p,) [kg]
    offset      (p, 3)     centre of mass minus node position, global [m]
    inertia     (p, 3, 3)  inertia tensor about the centre of mass, global axes [kg·m²]
                           (positive-definite convention: I11 = ∫(y² + z²) dm, I12 = −∫xy dm)
    """

    element_ids: np.ndarray = field(default_factory=_ints)
    node: np.ndarray = field(default_factory=_ints)
    mass: np.ndarray = field(default_factory=_floats)
    offset: np.ndarray = field(default_factory=lambda: _floats((0, 3)))
    inertia: np.ndarray = field(default_factory=lambda: _floats((0, 3, 3)))


@dataclass(frozen=True)
class RigidElements:
    """RBE2: dependent nodes follow the independent node rigidly in the given components.

    element_ids (r,) int; independent (r,) int; components (r, 6) bool (CM, global axes
    of the rigid motion u_d = u_i + θ_i × (x_d − x_i), θ_d = θ_i)
    dependent (q,) int; dependent_element (q,) int row in ``element_ids``
    """

    element_ids: np.ndarray = field(default_factory=_ints)
    independent: np.ndarray = field(default_factory=_ints)
    components: np.ndarray = field(default_factory=lambda: np.zeros((0, 6), dtype=bool))
    dependent: np.ndarray = field(default_factory=_ints)
    dependent_element: np.ndarray = field(default_factory=_ints)


@dataclass(frozen=True)
class InterpolationElements:
    """RBE3: the reference node moves with the weighted least-squares rigid fit of the
    independent nodes' motions (no stiffness added).

    element_ids (r,) int; reference (r,) int; reference_components (r, 6) bool (REFC)
    independent (q,) int; independent_element (q,) int row; weights (q,) [-];
    independent_components (q, 6) bool (Ci; translations only is the common case)
    """

    element_ids: np.ndarray = field(default_factory=_ints)
    reference: np.ndarray = field(default_factory=_ints)
    reference_components: np.ndarray = field(default_factory=lambda: np.zeros((0, 6), dtype=bool))
    independent: np.ndarray = field(default_factory=_ints)
    independent_element: np.ndarray = field(default_factory=_ints)
    weights: np.ndarray = field(default_factory=_floats)
    independent_components: np.ndarray = field(default_factory=lambda: np.zeros((0, 6), dtype=bool))


@dataclass(frozen=True)
class SupportSet:
    """Held DOFs of one support set: nodes (k,) int, components (k, 6) bool (CD frames)."""

    nodes: np.ndarray
    components: np.ndarray


@dataclass(frozen=True)
class DeckModel:
    """A whole deck: nodes, elements, properties, supports, loads and groups.

    source                str            file that was read
    node_ids              (n,) int       GRID / node ids
    points                (n, 3)         global coordinates [m]
    displacement_frames   (n, 3, 3)      rows = the node's output (CD) axes in global
                                         coordinates (identity where CD = 0)
    shells, beams, springs, point_masses, rbe2, rbe3: see their classes
    solids                {cell_type: SolidElements}
    supports              {name: SupportSet}     SPC/SPC1/SPCADD set id as str, *BOUNDARY
    loads                 {name: (n, 6)}         nodal forces [N] and moments [N·m] in the
                                                 global frame (FORCE/MOMENT/DAREA by set id)
    node_sets             {name: (k,) int}       'set_<id>' (SET1), Abaqus NSET names
    element_sets          {name: (k,) int}       deck element ids: 'pid_<id>', Abaqus ELSETs
    unsupported           {card: count}          cards present that sarfe does not model
    ignored               {card: count}          cards deliberately not modelled (ignore_cards)
    unsupported_where     {card: "file:line"}    where each unsupported card first appears
    coupled_mass          bool                   the deck asks for coupled (consistent) element
                                                 mass (Nastran PARAM,COUPMASS > 0); otherwise
                                                 the commercial solvers' default, lumped
    drilling_penalty      float                  α of the shells' drilling stiffness
                                                 α C₃₃ ∫ (θz − ω)² dA (Nastran 1e-6·K6ROT,
                                                 K6ROT = 100 by default)
    notes                 tuple[str]             things a user should know (e.g. MAT1 without
                                                 density read as ρ = 0)
    """

    source: str
    node_ids: np.ndarray
    points: np.ndarray
    displacement_frames: np.ndarray
    shells: ShellElements = field(default_factory=ShellElements)
    solids: dict = field(default_factory=dict)
    beams: BeamElements = field(default_factory=BeamElements)
    springs: SpringElements = field(default_factory=SpringElements)
    point_masses: PointMasses = field(default_factory=PointMasses)
    rbe2: RigidElements = field(default_factory=RigidElements)
    rbe3: InterpolationElements = field(default_factory=InterpolationElements)
    supports: dict = field(default_factory=dict)
    loads: dict = field(default_factory=dict)
    node_sets: dict = field(default_factory=dict)
    element_sets: dict = field(default_factory=dict)
    unsupported: dict = field(default_factory=dict)
    ignored: dict = field(default_factory=dict)
    unsupported_where: dict = field(default_factory=dict)
    coupled_mass: bool = False
    drilling_penalty: float = 1e-4
    notes: tuple = ()

    @property
    def n_nodes(self) -> int:
        return int(self.points.shape[0])

    def node_index(self, ids) -> np.ndarray:
        """0-based node indices of deck node ids; DeckError names an unknown id."""
        ids = np.asarray(ids, dtype=np.int64).ravel()
        order = np.argsort(self.node_ids)
        sorted_ids = self.node_ids[order]
        pos = np.clip(np.searchsorted(sorted_ids, ids), 0, max(len(sorted_ids) - 1, 0))
        bad = (sorted_ids[pos] != ids) if len(sorted_ids) else np.ones(len(ids), bool)
        if np.any(bad):
            raise DeckError(f"{self.source}: node id {int(ids[bad][0])} is not in the deck")
        return order[pos]

    def shell_triangles_of(self, element_ids) -> np.ndarray:
        """Rows of ``shells.triangles`` belonging to the given deck element ids."""
        rows = np.flatnonzero(np.isin(self.shells.element_ids, np.asarray(element_ids)))
        return np.flatnonzero(np.isin(self.shells.triangle_element, rows))


@dataclass(frozen=True)
class UnitSystem:
    """A consistent unit system by the SI size of its length, mass and time units.

    force unit = mass·length/time² (e.g. mm-t-s: 1 t·mm/s² = 1 N; in-lbf-s: mass unit
    lbf·s²/in = 175.127 kg).
    """

    name: str
    length_m: float
    mass_kg: float
    time_s: float

    def factor(self, length=0, mass=0, time=0) -> float:
        """SI size of the unit of dimension length^a mass^b time^c."""
        return self.length_m**length * self.mass_kg**mass * self.time_s**time


_INCH = 0.0254
_LBF = 4.4482216152605
UNIT_SYSTEMS = {
    "SI": UnitSystem("SI", 1.0, 1.0, 1.0),
    "mm-t-s": UnitSystem("mm-t-s", 1e-3, 1e3, 1.0),
    "mm-kg-ms": UnitSystem("mm-kg-ms", 1e-3, 1.0, 1e-3),
    "mm-kg-s": UnitSystem("mm-kg-s", 1e-3, 1.0, 1.0),
    "m-kg-s": UnitSystem("m-kg-s", 1.0, 1.0, 1.0),
    "in-lbf-s": UnitSystem("in-lbf-s", _INCH, _LBF / _INCH, 1.0),
    "ft-lbf-s": UnitSystem("ft-lbf-s", 12 * _INCH, _LBF / (12 * _INCH), 1.0),   # mass unit: slug
}

# dimension (length, mass, time) of every float field that carries a unit
_FORCE = (1, 1, -2)
_DIMENSIONS = {
    ShellElements: {"membrane": (0, 1, -2), "coupling": _FORCE, "bending": (2, 1, -2),
                    "transverse_shear": (0, 1, -2), "mass_per_area": (-2, 1, 0),
                    "rotary_inertia_per_area": (0, 1, 0), "thickness": (1, 0, 0),
                    "offset": (1, 0, 0)},
    SolidElements: {"young": (-1, 1, -2), "density": (-3, 1, 0)},
    BeamElements: {"area": (2, 0, 0), "i1": (4, 0, 0), "i2": (4, 0, 0), "i12": (4, 0, 0),
                   "torsion": (4, 0, 0), "young": (-1, 1, -2), "shear_modulus": (-1, 1, -2),
                   "density": (-3, 1, 0), "mass_per_length": (-1, 1, 0)},
    PointMasses: {"mass": (0, 1, 0), "offset": (1, 0, 0), "inertia": (2, 1, 0)},
}


def _scaled(table, units: UnitSystem):
    changes = {name: getattr(table, name) * units.factor(*dim)
               for name, dim in _DIMENSIONS.get(type(table), {}).items()}
    return replace(table, **changes)


def _scaled_springs(springs: SpringElements, units: UnitSystem) -> SpringElements:
    # translational [force/length], rotational [force·length/rad]; viscous: × time
    k_scale = np.array([units.factor(0, 1, -2)] * 3 + [units.factor(2, 1, -2)] * 3)
    b_scale = np.array([units.factor(0, 1, -1)] * 3 + [units.factor(2, 1, -1)] * 3)
    return replace(springs, stiffness=springs.stiffness * k_scale,
                   viscous_damping=springs.viscous_damping * b_scale)


def to_si(deck: DeckModel, units) -> DeckModel:
    """The deck with every quantity converted from ``units`` (a name of ``UNIT_SYSTEMS`` or a
    `UnitSystem`) to SI: coordinates, moduli, densities, section stiffness, springs, masses,
    inertias, forces and moments."""
    if isinstance(units, str):
        if units not in UNIT_SYSTEMS:
            raise DeckError(f"unknown unit system {units!r}; use one of {', '.join(UNIT_SYSTEMS)}")
        units = UNIT_SYSTEMS[units]
    if units.factor(1) == 1.0 and units.factor(0, 1) == 1.0 and units.factor(0, 0, 1) == 1.0:
        return deck
    load_scale = np.array([units.factor(*_FORCE)] * 3 + [units.factor(2, 1, -2)] * 3)
    return replace(
        deck,
        points=deck.points * units.length_m,
        shells=_scaled(deck.shells, units),
        solids={name: _scaled(block, units) for name, block in deck.solids.items()},
        beams=_scaled(deck.beams, units),
        springs=_scaled_springs(deck.springs, units),
        point_masses=_scaled(deck.point_masses, units),
        loads={name: load * load_scale for name, load in deck.loads.items()},
    )
