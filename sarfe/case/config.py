"""Typed configuration of a case: small frozen dataclasses, one per case section and entry, built
ONCE from the validated, normalized case (:func:`sarfe.case.normalize.normalize`) and owning the
defaults.

    config = case.config                # CaseConfig(model, damping, reduction, contacts,
                                        #   excitation, solver, erp, output)
    config.solver.harmonics, config.model.fe.materials["abs"].E_Pa, config.contacts[0].gap_m …

The dataclasses' field defaults are the single source of the case defaults: ``normalize`` fills
missing keys from them (:func:`default_of`), so a default is written once. The pipeline reads these
typed fields, never a case mapping; a changed setting is a new Case with the section replaced
(:meth:`sarfe.case.read.Case.with_solver` …). The law parameters of a contact stay generic
(``ContactConfig.params``, the entry as normalized): the laws own them (:mod:`sarfe.hbm.laws`).

Defaults that disagreed and which one won:
- continuation ``max_step``: 0.1 (case layer) vs 0.25 (``sarfe.hbm.ContinuationOptions``). 0.1 is
  what every ``sarfe solve`` has used (results unchanged); it is :data:`CONTINUATION_MAX_STEP` here
  and the pipeline always passes it explicitly. The engine's 0.25 stays the default of a library
  call to ``continuation`` (documented there as the library default, not a case default).
- ERP air density, sound speed, reference power: literals 1.204 / 343.2 / 1e-12 in the case layer
  and the constants of :mod:`sarfe.erp.erp`: the erp constants are the source now.
"""
from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from sarfe.erp.cabin import PASSENGER_CAR
from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED

DEFAULT_ZETA = 0.02                 # modal damping ratio when the case gives no damping
CONTINUATION_MAX_STEP = 0.1         # see the module docstring (0.1 vs the engine's 0.25)
MATRICES_GAP_M = 0.0                # gap of a matrices contact with a normal DOF and no preload
RESULTS_DIRECTORY = "results"       # output.directory default: results/<case name>
OUTPUT_FILES = ("summary", "response", "plots", "table", "report", "sound")  # output.files default
FE_OUTPUT_FILES = ("erp_vtu", "animation")                           # … and with model.fe


def _frozen(value):
    """A read-only view of a case mapping (lists as tuples), so a config cannot be altered."""
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


def _empty():
    return MappingProxyType({})


def default_of(section, name):
    """The default of field ``name`` of the config dataclass ``section`` as a plain value for a
    case mapping (tuples as lists, read-only mappings as dicts): what ``normalize`` writes."""
    spec = section.__dataclass_fields__[name]
    value = spec.default if spec.default is not dataclasses.MISSING else spec.default_factory()
    if isinstance(value, tuple):
        return list(value)
    if isinstance(value, MappingProxyType):
        return dict(value)
    return value


# ------------------------------------------------------------------------------------------ model
@dataclass(frozen=True)
class MaterialConfig:
    """An isotropic shell material: Young's modulus E [Pa], Poisson's ratio ν, density ρ [kg/m³]."""

    E_Pa: float
    nu: float
    rho_kg_m3: float


@dataclass(frozen=True)
class GeneratorConfig:
    """model.fe.generator: a parametric mesh (:mod:`sarfe.mesh.generators`) of element size
    ``mesh_size_m`` [m] with the generator's own ``params`` (keyword arguments of its
    ``generate``, passed on as the case gives them: a plain copy, not to be edited)."""

    name: str
    mesh_size_m: float
    params: dict = field(default_factory=dict)


@dataclass(frozen=True)
class DeckConfig:
    """model.fe.deck: an engineer's Nastran/Abaqus deck (``file``, relative to the case) in the unit
    system ``units``; cards to ignore, support sets to use (empty: all of the deck's), and the
    case's own node / element groups (id lists or deck set names)."""

    file: str
    units: str = "SI"
    ignore_cards: tuple = ()
    supports: tuple = ()
    node_groups: MappingProxyType = field(default_factory=_empty)
    element_groups: MappingProxyType = field(default_factory=_empty)


@dataclass(frozen=True)
class FeConfig:
    """model.fe: the geometry ``source`` ('mesh' | 'generator' | 'deck') and its settings; the
    shell sections by element group (``materials``, ``thickness_m`` [m]; overrides on a deck) and
    the ``fixed`` node groups (all six DOFs held)."""

    source: str
    mesh: str | None = None            # the mesh file (source 'mesh'), relative to the case
    mesh_units: str = "m"              # length unit of a mesh file's coordinates
    generator: GeneratorConfig | None = None
    deck: DeckConfig | None = None
    materials: MappingProxyType = field(default_factory=_empty)      # {group: MaterialConfig}
    thickness_m: MappingProxyType = field(default_factory=_empty)    # {group: t [m]}
    fixed: tuple = ()

    @property
    def is_deck(self) -> bool:
        return self.source == "deck"

    @property
    def where(self) -> tuple:
        """Key path of the geometry source, for error messages."""
        return ("model", "fe", self.source)


@dataclass(frozen=True)
class MatricesConfig:
    """model.matrices: mass, stiffness and (optional) damping, each a file name (.npz, .npy,
    .mtx, relative to the case) or inline rows."""

    mass: object
    stiffness: object
    damping: object = None

    def entry(self, key):
        return getattr(self, key)


@dataclass(frozen=True)
class ModelConfig:
    fe: FeConfig | None = None
    matrices: MatricesConfig | None = None

    @property
    def is_fe(self) -> bool:
        return self.fe is not None


# ---------------------------------------------------------------------------------------- damping
@dataclass(frozen=True)
class ModalZetaRange:
    """ζ of the modes ``modes`` = (first, last) (1-based, inclusive) of the reduced model."""

    modes: tuple
    zeta: float


@dataclass(frozen=True)
class RayleighConfig:
    """D = α M + β K: α [1/s], β [s]."""

    alpha_1_s: float
    beta_s: float


@dataclass(frozen=True)
class DampingConfig:
    """damping: modal_zeta (a number, or per-mode-range entries) or rayleigh; both None when the
    matrices case brings its own damping matrix."""

    modal_zeta: float | tuple | None = None      # ζ, or (ModalZetaRange, …)
    rayleigh: RayleighConfig | None = None


# -------------------------------------------------------------------------------------- reduction
@dataclass(frozen=True)
class ReductionConfig:
    """reduction (FE cases): mode_count or cutoff_hz (or neither: cutoff from the excitation,
    min(cutoff_margin × H × f_max, the Newton cutoff): sarfe.pipeline.model.cutoff), at least
    min_mode_count modes, static residual vectors.

    cutoff_margin 1.0 (was 1.25, before that 1.5): door trim, 12 contact pairs, H = 15, 40–80 Hz,
    15, 10 and 5 mm (benchmarks/results/cutoff.md): the cutoff H f_max changes the contact-row
    first-harmonic amplitudes by ≤ 1.7e-4, every response harmonic by ≤ 3.1e-4 and the ERP by
    ≤ 0.012 dB(A) against 2 H f_max (1.5 at 5 mm); 0.75 H f_max moves them by 1.5e-3 /
    0.023 dB(A) (harmonics above the cutoff have no modes to live in). The per-point estimate's
    modal part (two probes, decay fitted: sarfe.accuracy.modal_truncation) brackets those changes
    at every point from 0.75 H f_max up and over-reports at H f_max by ≤ 12× (amplitude and
    dB), resolution floor included (the earlier single probe of the top fifth: 34× / 35×, which
    kept the margin at 1.25; benchmarks/results/modal_estimate.md)."""

    mode_count: int | None = None
    cutoff_hz: float | None = None
    cutoff_margin: float = 1.0
    min_mode_count: int = 10
    residual_vectors: bool = True


# --------------------------------------------------------------------------------------- contacts
@dataclass(frozen=True)
class DofReference:
    """A DOF of a matrices model: r = sign · (u[dof] − u[relative_to]) ('ground': u = 0)."""

    dof: int
    relative_to: int | str = "ground"
    sign: int = 1


@dataclass(frozen=True)
class ContactConfig:
    """One contacts[] entry: index in the case, name, law (``kind``: the entry's ``type``), where it
    acts and its gap, and ``params``: the entry's mapping as normalized, which the law reads for
    its own parameters (stiffness, friction …; :mod:`sarfe.hbm.laws`; a plain copy, not to be
    edited).

    FE (:mod:`sarfe.pipeline.model.contact_pairs`): ``between`` two node groups (b may be
    'ground'; each node of a is a contact point, its partner the closest point of b's surface
    within ``pairing_tolerance_m`` [m]), or contact ``points_m`` ((n, 3) [m]) on the element
    groups ``surfaces`` [a, b], or explicit node ``pairs`` (a deck's GRID ids), or a deck's springs
    ``from_elements`` (along ``element_axis``); ``normal`` 'auto' (the partner surface's normal,
    fitted over a patch of radius ``patch_radius_m`` [m]), 'separation' (from a's point to b's)
    or a vector. Matrices: ``normal_dof`` and ``tangential_dofs``. Every law: ``gap_m`` [m] the
    clearance between the facing surfaces (None: an FE contact's geometric surface gap) or a
    static ``preload_N`` [N], and the rattle ``tolerance_m`` [m]."""

    index: int
    name: str
    kind: str
    params: dict
    between: tuple | None = None
    pairs: tuple | None = None
    from_elements: tuple | None = None
    element_axis: int | None = None
    points_m: tuple | None = None
    surfaces: tuple | None = None
    normal: str | tuple = "auto"
    pairing_tolerance_m: float = 1e-3
    patch_radius_m: float = 2e-3
    normal_dof: DofReference | None = None
    tangential_dofs: tuple = ()
    gap_m: float | None = None
    preload_N: float | None = None
    tolerance_m: float = 0.0


# ------------------------------------------------------------------------------------- excitation
@dataclass(frozen=True)
class ForceConfig:
    """One excitation.forces entry: amplitude ``force_N`` [N] (with a deck ``load_set``: its
    ``scale``) at ``phase_deg`` [°], on a node ``group`` along the unit ``direction`` (FE), on a
    ``dof`` (matrices) or the deck's load set."""

    force_N: float
    phase_deg: float = 0.0
    group: str | None = None
    direction: tuple | None = None
    dof: int | None = None
    load_set: str | int | None = None
    scale: float = 1.0


@dataclass(frozen=True)
class BaseAccelerationConfig:
    """excitation.base_acceleration: amplitude [m/s²] at ``phase_deg`` [°] along the unit
    ``direction`` (FE) or the ``influence`` vector ι (matrices; None: all ones)."""

    amplitude_m_s2: float
    phase_deg: float = 0.0
    direction: tuple | None = None
    influence: tuple | None = None


@dataclass(frozen=True)
class SweepConfig:
    start_hz: float
    end_hz: float


@dataclass(frozen=True)
class ExcitationConfig:
    """excitation: forces (ForceConfig, …) or base_acceleration; frequency_hz (tuple) or sweep."""

    forces: tuple = ()
    base_acceleration: BaseAccelerationConfig | None = None
    frequency_hz: tuple | None = None
    sweep: SweepConfig | None = None

    @property
    def max_frequency_hz(self) -> float:
        """Highest excitation frequency [Hz] (sweep end or largest listed frequency)."""
        if self.sweep is not None:
            return max(self.sweep.start_hz, self.sweep.end_hz)
        return max(self.frequency_hz)

    @property
    def min_frequency_hz(self) -> float:
        """Lowest excitation frequency [Hz] (sweep start or smallest listed frequency)."""
        if self.sweep is not None:
            return min(self.sweep.start_hz, self.sweep.end_hz)
        return min(self.frequency_hz)


# ----------------------------------------------------------------------------------------- solver
@dataclass(frozen=True)
class ContinuationConfig:
    """solver.continuation: arc-length steps (fractions of the band, see ContinuationOptions);
    ``linear_points``: a sweep takes exact linear points where every contact stays open, closed or
    stuck and follows the branch only where one does not (:mod:`sarfe.pipeline.solve.by_need`)."""

    initial_step: float = 0.02
    min_step: float = 1e-6
    max_step: float = CONTINUATION_MAX_STEP
    max_points: int = 2000
    linear_points: bool = True


DEFAULT_ACCURACY = "balanced"


@dataclass(frozen=True)
class SolverConfig:
    """solver: harmonics H, samples_per_period N, Newton options, continuation, accuracy.
    ``resolution`` 'auto' (H, N, modes chosen for ``accuracy``) | 'fixed' (harmonics given).
    ``accuracy``: a preset 'fast' | 'balanced' | 'fine' or a target {erp_db, amplitude_rel}
    (:func:`sarfe.accuracy.target.parse_accuracy`), None: 'balanced'. ``harmonic_set`` 'all' |
    'odd' | 'auto' (:mod:`sarfe.hbm.harmonic_set`). ``prune_contacts``: contacts that never switch
    are solved linearly, with the clearance margin ``prune_margin`` (:mod:`sarfe.pipeline.solve.
    pruned_points`). ``workers`` 'auto' | n: processes for the per-point work after Newton
    (:mod:`sarfe.util.workers`). ``mesh_error``: the mesh term of the ± ('auto': on for
    generator meshes, 'not estimated' said for decks and given meshes; true: required; false: off;
    :mod:`sarfe.pipeline.solve.mesh_error`)."""

    harmonics: int = 5
    samples_per_period: int = 128
    resolution: str = "auto"
    accuracy: str | dict | None = None    # 'balanced' by default with resolution auto (normalize)
    tolerance: float = 1e-9
    max_iterations: int = 50
    stability: bool = True
    error_estimate: bool = True
    harmonic_set: str = "all"
    prune_contacts: bool = True
    prune_margin: float = 0.5
    workers: int | str = "auto"
    mesh_error: bool | str = "auto"     # the ± mesh term: 'auto' on for generator meshes (mesh_error)
    continuation: ContinuationConfig = field(default_factory=ContinuationConfig)

    @property
    def accuracy_or_default(self):
        """The accuracy budget of the run: the given one, else 'balanced'."""
        return DEFAULT_ACCURACY if self.accuracy is None else self.accuracy


def default_samples_per_period(harmonics: int) -> int:
    """N = max(64, next power of two ≥ 16 H): AFT samples per period when the case gives none."""
    return max(64, 2 ** math.ceil(math.log2(16 * harmonics)))


# -------------------------------------------------------------------------------------------- erp
@dataclass(frozen=True)
class ErpConfig:
    """erp: radiating surface (FE) or dofs/areas_m2 (matrices), air and level reference."""

    surface: str | None = None
    dofs: tuple | None = None
    areas_m2: tuple | None = None
    rho_kg_m3: float = AIR_DENSITY
    c_m_s: float = SOUND_SPEED
    radiation_loss_factor: float = 1.0
    reference_power_W: float = REFERENCE_POWER


# ------------------------------------------------------------------------------------- audibility
NO_BACKGROUND = "none"              # audibility.background: the threshold in quiet only
DEFAULT_BACKGROUND = "ev_80kmh"     # a quiet battery-electric cabin at 80 km/h, 61 dB(A)


@dataclass(frozen=True)
class CabinConfig:
    """audibility.cabin: the diffuse-field cabin from the ERP to the occupant's ear
    (:class:`sarfe.erp.cabin.Cabin`; defaults: :data:`sarfe.erp.cabin.PASSENGER_CAR`, a saloon
    with cloth seats, docs/audibility.md). ``absorption``: ᾱ, one value or one per
    ``absorption_band_hz`` centre."""

    distance_m: float = PASSENGER_CAR.distance_m
    volume_m3: float = PASSENGER_CAR.volume_m3
    surface_m2: float = PASSENGER_CAR.surface_m2
    absorption: float | tuple = PASSENGER_CAR.absorption[0]
    absorption_band_hz: tuple = ()
    directivity: float = PASSENGER_CAR.directivity


@dataclass(frozen=True)
class AudibilityConfig:
    """audibility: will the occupant hear it (:mod:`sarfe.pipeline.post.audibility_records`).
    ``background``: a shipped cabin spectrum by name (:func:`sarfe.erp.backgrounds.
    background_names`), a third-octave CSV file (resolved against the case file's folder by the
    case layer) or 'none' (the threshold in quiet only). Default :data:`DEFAULT_BACKGROUND`: the
    quietest realistic driving condition shipped (an EV has no engine noise to mask a rattle),
    so a verdict 'not audible' holds in louder cabins too. ``loudness_field``: the ISO 532-1
    field, 'diffuse' (the occupant hears the reverberant cabin from all sides) or 'free'; ``sound_duration_s``: the length of sound.wav."""

    background: str = DEFAULT_BACKGROUND
    loudness_field: str = "diffuse"
    sound_duration_s: float = 3.0
    cabin: CabinConfig = field(default_factory=CabinConfig)


# ----------------------------------------------------------------------------------------- output
@dataclass(frozen=True)
class OutputConfig:
    """output: the result folder (default results/<case name>), the files written (default
    :data:`OUTPUT_FILES`, + :data:`FE_OUTPUT_FILES` with model.fe), a target level [dB(A)] and
    ``maps``, the points with an ERP map: 'loudest', {'every': N} (every N-th reported point) or
    a tuple of frequencies [Hz] (the reported point nearest each); the loudest point always
    (:mod:`sarfe.pipeline.write.map_points`)."""

    directory: str = ""
    files: tuple = ()
    target_dba: float | None = None
    maps: str | dict | tuple = "loudest"


def default_output_directory(name: str) -> str:
    return str(Path(RESULTS_DIRECTORY) / name)


def default_output_files(fe: bool) -> list:
    return list(OUTPUT_FILES) + (list(FE_OUTPUT_FILES) if fe else [])


# ------------------------------------------------------------------------------------------- case
@dataclass(frozen=True)
class CaseConfig:
    name: str
    model: ModelConfig
    damping: DampingConfig
    reduction: ReductionConfig | None
    contacts: tuple
    excitation: ExcitationConfig
    solver: SolverConfig
    erp: ErpConfig
    output: OutputConfig
    audibility: AudibilityConfig = field(default_factory=AudibilityConfig)


# ------------------------------------------------------------------ the normalized mapping → typed
def _given(mapping, section, keys, convert=None):
    """Keyword arguments of ``section`` for the ``keys`` present in ``mapping`` (absent: the
    field's default), each through ``convert`` (default: a read-only copy)."""
    convert = convert or _frozen
    return {key: convert(mapping[key]) for key in keys if key in mapping}


def _fe_config(fe) -> FeConfig:
    source = "deck" if "deck" in fe else "mesh" if "mesh" in fe else "generator"
    generator = fe.get("generator")
    deck = None
    if source == "deck":
        deck = DeckConfig(file=fe["deck"], **_given(fe, DeckConfig, (
            "units", "ignore_cards", "supports", "node_groups", "element_groups")))
    return FeConfig(
        source=source, mesh=fe.get("mesh"),
        generator=None if generator is None else GeneratorConfig(
            name=generator["name"], mesh_size_m=generator["mesh_size_m"],
            **_given(generator, GeneratorConfig, ("params",), copy.deepcopy)),
        deck=deck,
        materials=MappingProxyType({name: MaterialConfig(m["E_Pa"], m["nu"], m["rho_kg_m3"])
                                    for name, m in fe.get("materials", {}).items()}),
        **_given(fe, FeConfig, ("mesh_units", "thickness_m", "fixed")))


def _damping_config(damping) -> DampingConfig:
    zeta = damping.get("modal_zeta")
    if isinstance(zeta, list):
        zeta = tuple(ModalZetaRange(tuple(e["modes"]), e["zeta"]) for e in zeta)
    rayleigh = damping.get("rayleigh")
    return DampingConfig(modal_zeta=zeta, rayleigh=None if rayleigh is None else RayleighConfig(
        rayleigh["alpha_1_s"], rayleigh["beta_s"]))


def _dof_reference(ref) -> DofReference:
    return DofReference(ref["dof"], **_given(ref, DofReference, ("relative_to", "sign")))


def contact_config(index: int, contact: dict) -> ContactConfig:
    """The typed contacts[index] of its normalized mapping ``contact``."""
    typed = _given(contact, ContactConfig, ("between", "pairs", "from_elements", "element_axis",
                                            "points_m", "surfaces", "normal",
                                            "pairing_tolerance_m", "patch_radius_m", "gap_m",
                                            "preload_N", "tolerance_m"))
    if "normal_dof" in contact:
        typed["normal_dof"] = _dof_reference(contact["normal_dof"])
    typed["tangential_dofs"] = tuple(_dof_reference(r) for r in contact.get("tangential_dofs", []))
    return ContactConfig(index=index, name=contact["name"], kind=contact["type"],
                         params=copy.deepcopy(contact), **typed)


def _excitation_config(exc) -> ExcitationConfig:
    base, sweep = exc.get("base_acceleration"), exc.get("sweep")
    return ExcitationConfig(
        forces=tuple(ForceConfig(force_N=load["force_N"], **_given(load, ForceConfig, (
            "phase_deg", "group", "direction", "dof", "load_set", "scale")))
            for load in exc.get("forces", [])),
        base_acceleration=None if base is None else BaseAccelerationConfig(
            amplitude_m_s2=base["amplitude_m_s2"],
            **_given(base, BaseAccelerationConfig, ("phase_deg", "direction", "influence"))),
        frequency_hz=None if exc.get("frequency_hz") is None else tuple(exc["frequency_hz"]),
        sweep=None if sweep is None else SweepConfig(sweep["start_hz"], sweep["end_hz"]))


def _solver_config(solver) -> SolverConfig:
    cont = solver["continuation"]
    prune = solver["prune_contacts"]              # true | false | {margin: m}
    margin = {"prune_margin": float(prune["margin"])} \
        if isinstance(prune, dict) and "margin" in prune else {}
    return SolverConfig(
        harmonics=solver["harmonics"], samples_per_period=solver["samples_per_period"],
        resolution=solver["resolution"], accuracy=copy.deepcopy(solver.get("accuracy")),
        tolerance=solver["tolerance"], max_iterations=solver["max_iterations"],
        stability=solver["stability"], error_estimate=solver["error_estimate"],
        harmonic_set=solver["harmonic_set"],
        prune_contacts=True if isinstance(prune, dict) else bool(prune), **margin,
        workers=solver["workers"], mesh_error=solver["mesh_error"],
        continuation=ContinuationConfig(initial_step=cont["initial_step"],
                                        min_step=cont["min_step"], max_step=cont["max_step"],
                                        max_points=cont["max_points"],
                                        linear_points=cont["linear_points"]))


def build_config(data: dict) -> CaseConfig:
    """The typed configuration of a normalized case's ``data`` (every default already filled)."""
    model = data["model"]
    erp, out = data["erp"], data["output"]
    red = data.get("reduction")
    return CaseConfig(
        name=data["name"],
        model=ModelConfig(fe=_fe_config(model["fe"]) if "fe" in model else None,
                          matrices=MatricesConfig(**_given(model["matrices"], MatricesConfig, (
                              "mass", "stiffness", "damping"))) if "matrices" in model else None),
        damping=_damping_config(data.get("damping") or {}),
        reduction=None if red is None else ReductionConfig(
            mode_count=red.get("mode_count"), cutoff_hz=red.get("cutoff_hz"),
            cutoff_margin=red["cutoff_margin"], min_mode_count=red["min_mode_count"],
            residual_vectors=red["residual_vectors"]),
        contacts=tuple(contact_config(i, c) for i, c in enumerate(data.get("contacts", []))),
        excitation=_excitation_config(data["excitation"]),
        solver=_solver_config(data["solver"]),
        erp=ErpConfig(surface=erp.get("surface"), dofs=_frozen(erp.get("dofs")),
                      areas_m2=_frozen(erp.get("areas_m2")), rho_kg_m3=erp["rho_kg_m3"],
                      c_m_s=erp["c_m_s"], radiation_loss_factor=erp["radiation_loss_factor"],
                      reference_power_W=erp["reference_power_W"]),
        output=OutputConfig(directory=out["directory"], files=tuple(out["files"]),
                            target_dba=out.get("target_dba"),
                            maps=_frozen(out["maps"])),
        audibility=_audibility_config(data.get("audibility") or {}))


def _audibility_config(section) -> AudibilityConfig:
    cabin = dict(section.get("cabin") or {})
    if isinstance(cabin.get("absorption"), list):
        cabin["absorption"] = tuple(cabin["absorption"])
    if "absorption_band_hz" in cabin:
        cabin["absorption_band_hz"] = tuple(cabin["absorption_band_hz"])
    return AudibilityConfig(cabin=CabinConfig(**cabin), **_given(
        section, AudibilityConfig, ("background", "loudness_field", "sound_duration_s"), lambda v: v))


__all__ = ["CaseConfig", "ModelConfig", "FeConfig", "GeneratorConfig", "DeckConfig",
           "MaterialConfig", "MatricesConfig", "DampingConfig", "ModalZetaRange",
           "RayleighConfig", "ReductionConfig", "ContactConfig", "DofReference", "ForceConfig",
           "BaseAccelerationConfig", "ExcitationConfig", "SweepConfig", "SolverConfig",
           "ContinuationConfig", "ErpConfig", "OutputConfig", "AudibilityConfig", "CabinConfig",
           "NO_BACKGROUND", "DEFAULT_BACKGROUND", "build_config", "contact_config",
           "default_of", "default_output_directory", "default_output_files",
           "DEFAULT_ZETA", "DEFAULT_ACCURACY", "CONTINUATION_MAX_STEP", "MATRICES_GAP_M",
           "default_samples_per_period"]
