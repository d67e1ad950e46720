r"""The a-posteriori error estimate of one harmonic-balance solution: how far ũ (2H+1, n) at ω,
solving R_{H,N}(ũ) = S(ω) ũ + f̃_nl^{(N)}(ũ) − f̃_e = 0, is from the converged answer, on the
quantities users read (:mod:`sarfe.accuracy.measures`: the first-harmonic contact amplitude and
the ERP level), from three sources, each a change of ũ re-solved by Newton
(:mod:`sarfe.accuracy.correction`):

- harmonic truncation H → H' and AFT aliasing N → 2N (:mod:`sarfe.accuracy.harmonic_truncation`,
  Richardson factors (3));
- modal truncation of a Craig–Bampton model: two coarser models extrapolated
  (:mod:`sarfe.accuracy.modal_truncation`, (4)–(5));
- spectral tails (2) of the contact displacements and forces, reported only.

Before any re-solve, the indicator (6)–(7) of :mod:`sarfe.accuracy.contact_resolution` asks
whether H' reaches the decay of the contacts' impacts at all; where it does not (a stiff contact's
impact far shorter than T / (2H')), the change to H' bounds nothing: the point gets no bound
(``amplitude_rel``, ``erp_db`` inf, the reason in ``notes``, ρ and the impact's duration in
``contact_resolution``) and no re-solve is made.

``amplitude_rel`` = (3)·harmonics_rel + 2·aliasing_rel + modal_rel + AMPLITUDE_FLOOR, likewise
``erp_db`` (+ ERP_FLOOR_DB) (triangle inequality over the three sources; harmonics_rel,
aliasing_rel are the raw changes, modal_rel already includes its factor; the floors, only where a
contact carries force, are the estimate's resolution: on the stuck-friction points of the FE cases
the true errors are 5e-5 amplitude and 1e-4 dB, below what the parts resolve).
benchmarks/results/accuracy.md compares them with the true error on every shipped case.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import scipy.linalg

from sarfe.accuracy.contact_resolution import contact_resolution
from sarfe.accuracy.harmonic_truncation import (RICHARDSON, aliasing_change, extended_harmonics,
                                                harmonics_richardson, reach_harmonics,
                                                truncation_change)
from sarfe.accuracy.measures import first_harmonic_amplitude, spectral_tail
from sarfe.accuracy.modal_truncation import CoarserModels, modal_truncation_estimate

AMPLITUDE_FLOOR = 1e-4       # added to every estimate of a point with an active contact: the
ERP_FLOOR_DB = 0.01          # estimate's resolution (stuck-friction points of the FE cases have
                             # true errors 5e-5 / 1e-4 dB that no part resolves)


@dataclass(frozen=True)
class ErrorEstimate:
    """Error estimates of one solution (module docstring). NaN where not computed.

    harmonics_rel / harmonics_db: H → ``extended_harmonics`` (1); aliasing_rel / aliasing_db:
    N → 2N (1); modal_rel / modal_db: two probes of the top modes removed, extrapolated (4, 5);
    displacement_tail / force_tail: (2).
    amplitude_rel, erp_db: the Richardson factors × (harmonics, aliasing parts) + modal part + the
    floors (module docstring; what the run's accuracy check compares with the target).
    seconds: time spent estimating.
    basis_top_hz: the highest fixed-interface mode of a Craig–Bampton model [Hz] (NaN otherwise):
    harmonics of the H' re-solve above it are answered by the residual vectors, whose Ritz
    frequencies sit just above it — there the reduced model's own error enters the harmonics
    change (:func:`basis_limited_extension`).
    contact_resolution: :meth:`sarfe.accuracy.contact_resolution.ContactResolution.as_dict` of
    the point (None: not asked); when not ``resolved`` the point has no bound (inf), and only
    then is it in :meth:`as_dict`.
    """

    harmonics: int
    samples_per_period: int
    extended_harmonics: int
    harmonics_rel: float
    harmonics_db: float
    aliasing_rel: float
    aliasing_db: float
    modal_rel: float
    modal_db: float
    displacement_tail: float
    force_tail: float
    amplitude_rel: float
    erp_db: float
    seconds: float = 0.0
    notes: tuple = field(default=())
    basis_top_hz: float = float("nan")
    contact_resolution: dict | None = None

    def as_dict(self) -> dict:
        data = asdict(self)
        data["notes"] = list(self.notes)
        if self.contact_resolution is None or self.contact_resolution["resolved"]:
            data.pop("contact_resolution")     # said only where it withholds the bound
        return data


def estimate_errors(solution, model, contacts, excitation, *, erp_map=None, erp_areas=None,
                    modal_dofs=None, residual_dofs=None, harmonics_extension=None, aliasing=True,
                    truncation=True, options=None, steps=None, coarser=None) -> ErrorEstimate:
    """Error estimates of a converged :class:`HarmonicSolution` (module docstring).

    model, contacts, excitation f̃_e (2H+1, n) [N]: the problem the solution solves.
    erp_map (n_s, n), erp_areas (n_s,) [m²]: radiating normal displacements (default all DOFs).
    modal_dofs: indices of the fixed-interface modal coordinates, sorted by frequency (None for a
    model without modal truncation); residual_dofs: the Craig–Bampton residual modes (4).
    harmonics_extension: H' (default :func:`sarfe.accuracy.harmonic_truncation.
    extended_harmonics`). coarser: the :class:`sarfe.accuracy.modal_truncation.CoarserModels` the
    modal part takes its coarser models from (default: the model's own).
    """
    clock = time.perf_counter()
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    notes = []
    R = np.asarray(solution.contact_displacement, dtype=float)
    lam = np.asarray(solution.contact_force, dtype=float)
    disp_tail = spectral_tail(R) if R.size else spectral_tail(U)
    force_tail = spectral_tail(lam) if lam.size else 0.0
    a_ref = np.max(first_harmonic_amplitude(contacts, U), initial=0.0) or None
    common = dict(erp_map=erp_map, erp_areas=erp_areas, options=options, ref_amplitude=a_ref,
                  steps=steps)

    nan = float("nan")
    h_rel = h_db = a_rel = a_db = nan
    H_ext = int(harmonics_extension or extended_harmonics(H))
    resolution = contact_resolution(solution, model, contacts, excitation, H_ext) \
        if truncation and contacts.count else None
    if resolution is not None and not resolution.resolved:    # no bound: nothing to re-solve
        inf = float("inf")
        return ErrorEstimate(
            harmonics=H, samples_per_period=N, extended_harmonics=H_ext, harmonics_rel=nan,
            harmonics_db=nan, aliasing_rel=nan, aliasing_db=nan, modal_rel=nan, modal_db=nan,
            displacement_tail=disp_tail, force_tail=force_tail, amplitude_rel=inf, erp_db=inf,
            seconds=time.perf_counter() - clock, notes=(resolution.note(),),
            contact_resolution=resolution.as_dict())
    if truncation:
        h_rel, h_db, H_ext, more = truncation_change(solution, model, contacts, excitation, H_ext,
                                                     **common)
        notes.extend(more)
    if aliasing:
        a_rel, a_db, more = aliasing_change(solution, model, contacts, excitation, **common)
        notes.extend(more)
    m_rel = m_db = nan
    if truncation and modal_dofs is not None and len(modal_dofs):
        modal = modal_truncation_estimate(solution, model, contacts, excitation, modal_dofs,
                                          residual_dofs, coarser=coarser, **common)
        m_rel, m_db = modal.amplitude_rel, modal.erp_db
        notes.extend(modal.notes)
    factor = harmonics_richardson(H, H_ext)
    parts_rel = [f * x for f, x in ((factor, h_rel), (RICHARDSON, a_rel)) if not np.isnan(x)]
    parts_db = [f * abs(x) for f, x in ((factor, h_db), (RICHARDSON, a_db)) if not np.isnan(x)]
    parts_rel += [m_rel] if np.isfinite(m_rel) else []
    parts_db += [m_db] if np.isfinite(m_db) else []
    active = lam.size and np.max(np.abs(np.asarray(solution.contact_force_time)), initial=0.0) > 0
    if active:     # resolution floor: below it the parts cannot be told from round-off
        parts_rel.append(AMPLITUDE_FLOOR)
        parts_db.append(ERP_FLOOR_DB)
    if not getattr(solution, "converged", True):
        notes.append(f"solution not converged: {getattr(solution, 'reason', '')}")
    return ErrorEstimate(
        harmonics=H, samples_per_period=N, extended_harmonics=H_ext,
        harmonics_rel=h_rel, harmonics_db=h_db, aliasing_rel=a_rel, aliasing_db=a_db,
        modal_rel=m_rel, modal_db=m_db, displacement_tail=disp_tail, force_tail=force_tail,
        amplitude_rel=float(sum(parts_rel)) if parts_rel else nan,
        erp_db=float(sum(parts_db)) if parts_db else nan,
        seconds=time.perf_counter() - clock, notes=tuple(notes),
        contact_resolution=None if resolution is None else resolution.as_dict())


@dataclass(frozen=True)
class EstimateProblem:
    """What :func:`problem_error_estimate` needs of a case's point, as plain arrays: the problem
    (model, contacts, excitation f̃_e (2H_e+1, n) [N]), the radiating normal displacements
    (erp_map (n_s, n), erp_areas (n_s,) [m²]; None: all DOFs, unit areas), the Craig–Bampton
    fixed-interface modal coordinates (sorted by frequency) and residual modes (None for models
    without modal truncation), the model's highest natural frequency [Hz] (None: unknown) and the
    :class:`sarfe.accuracy.modal_truncation.CoarserModels` its estimates share (None: the
    model's own, :func:`sarfe.accuracy.modal_truncation.coarser_models`)."""

    model: object
    contacts: object
    excitation: np.ndarray
    erp_map: object = None
    erp_areas: object = None
    modal_dofs: object = None
    residual_dofs: object = None
    highest_mode_hz: float | None = None
    coarser: CoarserModels | None = None


def problem_error_estimate(solution, problem: EstimateProblem, options=None) -> ErrorEstimate:
    """:func:`estimate_errors` of a case's point with H' reaching past the model's highest mode
    (:func:`sarfe.accuracy.harmonic_truncation.reach_harmonics`); on a Craig–Bampton model
    (modal_dofs given) the highest kept mode is recorded as ``basis_top_hz``."""
    H_ext = reach_harmonics(int(solution.harmonics), float(solution.omega), problem.highest_mode_hz)
    estimate = estimate_errors(solution, problem.model, problem.contacts, problem.excitation,
                               erp_map=problem.erp_map, erp_areas=problem.erp_areas,
                               modal_dofs=problem.modal_dofs, residual_dofs=problem.residual_dofs,
                               harmonics_extension=H_ext, options=options,
                               coarser=problem.coarser)
    top = problem.highest_mode_hz
    if problem.modal_dofs is not None and len(problem.modal_dofs) and top is not None \
            and np.isfinite(top):
        estimate = replace(estimate, basis_top_hz=float(top))
    return estimate


def basis_limited_extension(estimate: dict, frequency_hz: float) -> bool:
    """True when the harmonics change of ``estimate`` (an :meth:`ErrorEstimate.as_dict`) reached
    past the top of its Craig–Bampton basis, H' f > basis_top_hz: the harmonics between the top
    and H' f are answered by the residual vectors, and the change includes the reduced model's
    own error there. Measured on P1 at 5 mm (benchmarks/results/accuracy_5mm.md): with the top at
    H f_max (cutoff_margin 1.0) the first harmonics above it overshoot the truth's contact
    amplitude 1.3–1.8× (the residual vectors' Ritz frequencies start just above the cutoff) and
    the change H → 2H is 1.4–1.6× the true one; with the top at 1.25 H f_max, 0.8–1.5×."""
    top = estimate.get("basis_top_hz", float("nan"))
    top = float("nan") if top is None else float(top)
    return bool(np.isfinite(top) and int(estimate["extended_harmonics"]) * frequency_hz > top)


def highest_natural_frequency_hz(model):
    """Highest undamped natural frequency [Hz] of a small dense model (None above 2000 DOFs)."""
    if model.dof_count > 2000:
        return None
    dense = (lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float))
    values = scipy.linalg.eigh(dense(model.stiffness), dense(model.mass), eigvals_only=True)
    return float(np.sqrt(max(values.max(initial=0.0), 0.0)) / (2 * np.pi))


__all__ = ["AMPLITUDE_FLOOR", "ERP_FLOOR_DB", "ErrorEstimate", "estimate_errors", "EstimateProblem",
           "problem_error_estimate", "basis_limited_extension", "highest_natural_frequency_hz"]
