"""Typed configuration of a case: one small frozen dataclass per case section, built ONCE from the
validated, normalized case (:func:`sarfe.case.normalize.normalize`) and owning the defaults.

    config = case.config                # built once per Case; CaseConfig(model, damping, reduction,
                                        #   contacts, excitation, solver, erp, output)
    config.solver.harmonics, config.solver.continuation.max_step, config.erp.density_kg_m3 ...

The section dataclasses' field defaults are the single source of the case defaults: the case
layer's ``normalize`` fills missing keys from them (``SolverConfig.tolerance`` …), so a default is
written once. The law parameters of a contact stay generic (``ContactConfig.params``, the mapping of
the case entry): the laws own them (:mod:`sarfe.hbm.laws`). Sections whose content is a model
description read by the model builders (model.fe, model.matrices) keep their mapping next to the
few typed fields the pipeline asks for.

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
import math
from dataclasses import dataclass, field
from types import MappingProxyType

from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED

DEFAULT_ZETA = 0.02                 # modal damping ratio when the case gives no damping
CONTINUATION_MAX_STEP = 0.1         # see the module docstring (0.1 vs the engine's 0.25)


def _frozen(value):
    """A read-only view of a case mapping (lists as tuples), so a config cannot be altered."""
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


# ------------------------------------------------------------------------------------------ model
@dataclass(frozen=True)
class FeConfig:
    """model.fe: ``source`` 'mesh' | 'generator' | 'deck' and the section's mapping (read by the
    mesh / deck builders: thickness_m, materials, supports, groups …)."""

    source: str
    data: MappingProxyType

    @property
    def is_deck(self) -> bool:
        return self.source == "deck"

    @property
    def where(self) -> tuple:
        """Key path of the geometry source, for error messages."""
        return ("model", "fe", "mesh" if self.source == "mesh" else
                "deck" if self.source == "deck" else "generator")


@dataclass(frozen=True)
class MatricesConfig:
    """model.matrices: the file (or inline) entries of mass, stiffness, damping by key."""

    data: MappingProxyType

    def entry(self, key):
        return self.data.get(key)


@dataclass(frozen=True)
class ModelConfig:
    fe: FeConfig | None = None
    matrices: MatricesConfig | None = None

    @property
    def is_fe(self) -> bool:
        return self.fe is not None


# ---------------------------------------------------------------------------------------- damping
@dataclass(frozen=True)
class DampingConfig:
    """damping: modal_zeta (a number or per-mode-range entries) or rayleigh {alpha, beta}; both
    None when the matrices case brings its own damping matrix."""

    modal_zeta: object = None
    rayleigh: MappingProxyType | None = None
    data: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))


# -------------------------------------------------------------------------------------- reduction
@dataclass(frozen=True)
class ReductionConfig:
    """reduction (FE cases): mode_count or cutoff_hz (or neither: cutoff from the excitation),
    cutoff_margin × H × f_max, at least min_mode_count modes, static residual vectors.

    cutoff_margin 1.0 (was 1.25, before that 1.5): door trim, 12 contact pairs, H = 15, 40–80 Hz,
    15, 10 and 5 mm (benchmarks/results/cutoff.md): the cutoff H f_max changes the contact-row
    first-harmonic amplitudes by ≤ 1.7e-4, every response harmonic by ≤ 3.1e-4 and the ERP by
    ≤ 0.012 dB(A) against 2 H f_max (1.5 at 5 mm); 0.75 H f_max moves them by 1.5e-3 /
    0.023 dB(A) (harmonics above the cutoff have no modes to live in). The per-point estimate's
    modal part (two probes, decay fitted: sarfe.accuracy.estimates (5)) brackets those changes
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
class ContactConfig:
    """One contacts[] entry: index in the case, name, law (``kind``: the entry's ``type``), and the
    entry's mapping ``params`` (gap_m, stiffness, … — owned by the law, :mod:`sarfe.hbm.laws`,
    which reads it as the case gave it: a plain copy, not to be edited)."""

    index: int
    name: str
    kind: str
    params: dict

    def get(self, key, default=None):
        return self.params.get(key, default)

    def __getitem__(self, key):
        return self.params[key]


# ------------------------------------------------------------------------------------- excitation
@dataclass(frozen=True)
class SweepConfig:
    start_hz: float
    end_hz: float
    points: int | None = None
    data: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True)
class ExcitationConfig:
    """excitation: forces (tuple of entries) or base_acceleration; frequency_hz (tuple) or sweep."""

    forces: tuple = ()
    base_acceleration: MappingProxyType | None = None
    frequency_hz: tuple | None = None
    sweep: SweepConfig | None = None
    data: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))

    @property
    def max_frequency_hz(self) -> float:
        """Highest excitation frequency [Hz] (sweep end or largest listed frequency)."""
        if self.sweep is not None:
            return max(self.sweep.start_hz, self.sweep.end_hz)
        return max(self.frequency_hz)


# ----------------------------------------------------------------------------------------- solver
@dataclass(frozen=True)
class ContinuationConfig:
    """solver.continuation: arc-length steps (fractions of the band, see ContinuationOptions)."""

    initial_step: float = 0.02
    min_step: float = 1e-6
    max_step: float = CONTINUATION_MAX_STEP
    max_points: int = 2000


@dataclass(frozen=True)
class SolverConfig:
    """solver: harmonics H, samples_per_period N, Newton options, continuation, accuracy.
    ``resolution`` 'auto' (H, N, modes chosen for ``accuracy``) | 'fixed' (harmonics given).
    ``workers`` 'auto' | n: processes for the per-point work after Newton (:mod:`sarfe.util.workers`)."""

    harmonics: int = 5
    samples_per_period: int = 128
    resolution: str = "auto"
    accuracy: object = None          # 'balanced' by default with resolution auto (see normalize)
    tolerance: float = 1e-9
    max_iterations: int = 50
    stability: bool = True
    error_estimate: bool = True
    harmonic_set: object = "all"
    prune_contacts: object = True
    workers: object = "auto"         # processes for the per-point work: 'auto' | n (sarfe.util.workers)
    continuation: ContinuationConfig = field(default_factory=ContinuationConfig)

    @property
    def accuracy_or_default(self):
        """The accuracy budget of the run: the given one, else 'balanced'."""
        return DEFAULT_ACCURACY if self.accuracy is None else self.accuracy


DEFAULT_ACCURACY = "balanced"


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


# ----------------------------------------------------------------------------------------- output
@dataclass(frozen=True)
class OutputConfig:
    directory: str = ""
    files: tuple = ()
    target_dba: float | None = None


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


def _fe_config(fe) -> FeConfig:
    source = "deck" if "deck" in fe else "mesh" if "mesh" in fe else "generator"
    return FeConfig(source=source, data=_frozen(fe))


def build_config(data: dict) -> CaseConfig:
    """The typed configuration of a normalized case's ``data`` (every default already filled)."""
    model = data["model"]
    solver, exc, erp, out = data["solver"], data["excitation"], data["erp"], data["output"]
    cont = solver["continuation"]
    damping = data.get("damping") or {}
    red = data.get("reduction")
    sweep = exc.get("sweep")
    return CaseConfig(
        name=data["name"],
        model=ModelConfig(fe=_fe_config(model["fe"]) if "fe" in model else None,
                          matrices=MatricesConfig(_frozen(model["matrices"]))
                          if "matrices" in model else None),
        damping=DampingConfig(modal_zeta=_frozen(damping.get("modal_zeta")),
                              rayleigh=_frozen(damping.get("rayleigh")), data=_frozen(damping)),
        reduction=None if red is None else ReductionConfig(
            mode_count=red.get("mode_count"), cutoff_hz=red.get("cutoff_hz"),
            cutoff_margin=red["cutoff_margin"], min_mode_count=red["min_mode_count"],
            residual_vectors=red["residual_vectors"]),
        contacts=tuple(ContactConfig(index=i, name=c["name"], kind=c["type"],
                                     params=copy.deepcopy(c))
                       for i, c in enumerate(data.get("contacts", []))),
        excitation=ExcitationConfig(
            forces=_frozen(exc.get("forces", [])), base_acceleration=_frozen(
                exc.get("base_acceleration")),
            frequency_hz=None if exc.get("frequency_hz") is None else tuple(exc["frequency_hz"]),
            sweep=None if sweep is None else SweepConfig(
                start_hz=sweep["start_hz"], end_hz=sweep["end_hz"], points=sweep.get("points"),
                data=_frozen(sweep)),
            data=_frozen(exc)),
        solver=SolverConfig(
            harmonics=solver["harmonics"], samples_per_period=solver["samples_per_period"],
            resolution=solver["resolution"], accuracy=copy.deepcopy(solver.get("accuracy")),
            tolerance=solver["tolerance"], max_iterations=solver["max_iterations"],
            stability=solver["stability"], error_estimate=solver["error_estimate"],
            harmonic_set=copy.deepcopy(solver["harmonic_set"]),
            prune_contacts=copy.deepcopy(solver["prune_contacts"]),
            workers=solver["workers"],
            continuation=ContinuationConfig(initial_step=cont["initial_step"],
                                            min_step=cont["min_step"], max_step=cont["max_step"],
                                            max_points=cont["max_points"])),
        erp=ErpConfig(surface=erp.get("surface"), dofs=_frozen(erp.get("dofs")),
                      areas_m2=_frozen(erp.get("areas_m2")), rho_kg_m3=erp["rho_kg_m3"],
                      c_m_s=erp["c_m_s"], radiation_loss_factor=erp["radiation_loss_factor"],
                      reference_power_W=erp["reference_power_W"]),
        output=OutputConfig(directory=out["directory"], files=tuple(out["files"]),
                            target_dba=out.get("target_dba")))


__all__ = ["CaseConfig", "ModelConfig", "FeConfig", "MatricesConfig", "DampingConfig",
           "ReductionConfig", "ContactConfig", "ExcitationConfig", "SweepConfig", "SolverConfig",
           "ContinuationConfig", "ErpConfig", "OutputConfig", "build_config",
           "DEFAULT_ZETA", "DEFAULT_ACCURACY", "CONTINUATION_MAX_STEP",
           "default_samples_per_period"]
