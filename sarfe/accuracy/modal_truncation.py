r"""The modal-truncation part of a solution's error estimate, for a Craig–Bampton model
(coordinates [q_b, q_m, q_r]: boundary DOFs, fixed-interface modes, residual modes — the modal
ones in increasing frequency).

The coarser model the same reduction would give with the top fraction q of the modes (at least
one) left out — those modes and the residual modes replaced by the static responses of their span
to the loads the residual modes stand for (:func:`coarser_basis`), the modal damping rebuilt on its
own eigenmodes (:func:`rebuilt_modal_damping`) — is solved by Newton from the solution projected
on it (:mod:`sarfe.accuracy.correction`, (1)). Its change d of a₁ and of the ERP level
(:func:`sarfe.accuracy.measures.solution_change`) is the error of the coarser model minus that of
the kept one; with an error ∝ m^{−p} in the mode count m (:func:`mode_richardson`)

    e(m) = d / ((m/m')^p − 1)                                                       (4)

Two probes, q = 1/20 and 1/5 (MODE_PROBES), give d₁, d₂ with m₁' = 19m/20, m₂' = 4m/5; p is fitted
from d₂/d₁ = (r₂^p − 1)/(r₁^p − 1), r_i = m/m_i', kept in [1, 2.5] (MODE_DECAY), and

    modal_rel, modal_db = d₂ / (r₂^p − 1)                                           (5)

(:func:`modal_extrapolation`, separately for a₁ and the level). p = 1 is the slowest decay the
modal density of a plate allows (the factors 19 and 4); the cap 2.5 is conservative against the
measured decay: from 0.75 to 1.0 H f_max the true changes fall ≈ 10× (p ≈ 8 in m) on the door trim
(benchmarks/results/cutoff.md). A single probe of the top fifth with p = 1 (the earlier rule, (5)
with p = 1: never exceeded) probes ≈ 0.8 H f_max from a cutoff of H f_max, where the top harmonics
lose their nearly resonant modes, and over-reported up to 35× (with the floor of
:mod:`sarfe.accuracy.estimate`). Against the measured changes (benchmarks/results/
modal_estimate.md: door trim 15/10/5 mm at 0.75 and 1.0 H f_max, demo case at 1.0 and 1.25, 44
points) (5) plus the floor brackets every point, the closest 1.4× (amplitude) / 2.2× (dB), and
over-reports at H f_max by ≤ 12× (amplitude and dB). It costs two small re-solves instead of one
(≈ 0.02 s each at 5 mm, ≈ 1 % of a point) and builds two coarser models per stage
(:class:`CoarserModels`). It is the only part that sees the modes at the contact DOFs: those are
boundary DOFs, whose coordinates a truncation without re-solving would not change.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from sarfe.accuracy.correction import newton_correction, newton_step
from sarfe.accuracy.measures import resize_harmonics, solution_change
from sarfe.hbm.modal import dense_matrix
from sarfe.hbm.model import LinearModel

MODE_PROBES = (0.05, 0.2)    # fractions of the fixed-interface modes the two modal probes leave out (5)
MODE_DECAY = (1.0, 2.5)      # bounds of the fitted decay p of the modal error ∝ m^{−p} (5)


def coarser_basis(model, excitation, boundary_count, removed, residual=()):
    """T (n, n') of the coarser Craig–Bampton model (4): the coordinates ``removed`` and
    ``residual`` (the residual modes) are replaced by the static responses of the set S they span to
    the loads the residual modes stand for — unit boundary accelerations (columns M_Sb) and the
    excitation (f̃_e,S, cosine and sine rows) —

        W = K_SS⁻¹ [M_Sb, f_S],  M-orthonormalized (rank-revealing),

    i.e. the basis a reduction with the modes ``removed`` left out would have built (its residual
    modes). Without residual modes the removed coordinates are just dropped. The boundary DOFs are
    the first ``boundary_count`` coordinates."""
    n = model.dof_count
    removed = np.asarray(removed, dtype=int)
    residual = np.asarray(residual, dtype=int)
    S = np.concatenate([removed, residual])
    keep = np.setdiff1d(np.arange(n), S)
    blocks = [np.eye(n)[:, keep]]
    if residual.size:
        M, K = dense_matrix(model.mass), dense_matrix(model.stiffness)
        boundary = np.arange(int(boundary_count))
        F = np.asarray(excitation, dtype=float)
        loads = np.column_stack([M[np.ix_(S, boundary)], F[1, S], F[2, S]])
        W0 = np.linalg.solve(K[np.ix_(S, S)], loads)
        # unit M-norm columns and the rank rule of the reduction's own residual modes
        # (sarfe.reduction.craig_bampton.residual_modes: relative tolerance 1e-8): a unit
        # rotational boundary acceleration (rotary inertia ρt³/12) loads far less than a
        # translational one, and a threshold relative to the largest column dropped its direction
        norms = np.sqrt(np.einsum("ij,ij->j", W0, M[np.ix_(S, S)] @ W0))
        W0 = W0[:, norms > 0] / norms[norms > 0]
        gram = W0.T @ M[np.ix_(S, S)] @ W0
        values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
        ok = values > 1e-8 ** 2
        W = np.zeros((n, int(ok.sum())))
        W[S] = W0 @ vectors[:, ok] / np.sqrt(values[ok])
        blocks.append(W)
    return np.column_stack(blocks)


def rebuilt_modal_damping(model, small):
    """``small`` with its damping rebuilt the way the case built the original's, when that is modal
    damping: D = M Φ diag(2 ζ_j ω_j) Φᵀ M over the model's own eigenmodes, ζ_j by mode index taken
    from the original (Φᵀ D Φ diagonal). Modal damping depends on the basis — a coarser reduction
    puts different high system modes, with different 2 ζ ω_j, under the quasi-static response —
    and the coarser model of (4) is meant to be the case's reduction with fewer modes."""
    if model.damping is None:
        return small
    M, K, D = dense_matrix(model.mass), dense_matrix(model.stiffness), dense_matrix(model.damping)
    w2, phi = scipy.linalg.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
    modal = phi.T @ D @ phi
    off = modal - np.diag(np.diag(modal))
    if np.abs(off).max(initial=0.0) > 1e-6 * np.abs(np.diag(modal)).max(initial=1e-300):
        return small                                   # not modal damping: keep the projection
    omega = np.sqrt(np.clip(w2, 1e-300, None))
    zeta = np.diag(modal) / (2 * omega)
    Ms, Ks = dense_matrix(small.mass), dense_matrix(small.stiffness)
    w2s, phis = scipy.linalg.eigh(0.5 * (Ks + Ks.T), 0.5 * (Ms + Ms.T))
    weighted = Ms @ phis
    Ds = (weighted * (2.0 * zeta[:len(w2s)] * np.sqrt(np.clip(w2s, 0.0, None)))) @ weighted.T
    return LinearModel(small.mass, 0.5 * (Ds + Ds.T), small.stiffness)


@dataclass(frozen=True)
class CoarserModel:
    """The coarser model of (4): basis T (n, n'), its LinearModel Tᵀ(M, D, K)T (modal damping
    rebuilt), its ContactSet (gap map G T) and the number of modes left out."""

    basis: np.ndarray
    model: LinearModel
    contacts: object
    removed: int


def coarser_model(model, contacts, excitation, modal_dofs, residual_dofs=(), fraction=0.2):
    """:class:`CoarserModel` of (4) with the top ``fraction`` of ``modal_dofs`` (at least one)
    left out (built, not cached: :class:`CoarserModels`)."""
    modal_dofs = np.asarray(modal_dofs, dtype=int)
    residual_dofs = np.asarray(residual_dofs, dtype=int)
    removed = modal_dofs[-max(1, int(len(modal_dofs) * fraction)):]
    T = coarser_basis(model, excitation, int(modal_dofs.min()), removed, residual_dofs)

    def project(A):
        if A is None:
            return None
        return T.T @ (A @ T if hasattr(A, "toarray") else np.asarray(A) @ T)

    small = LinearModel(project(model.mass), project(model.damping), project(model.stiffness))
    small = rebuilt_modal_damping(model, small)
    small_contacts = replace(contacts, gap_map=sp.csr_matrix(contacts.gap_map @ T))
    return CoarserModel(T, small, small_contacts, len(removed))


class CoarserModels:
    """The coarser models (4) of one model, built on first use and kept: a coarser model depends
    on the problem (model, contacts, excitation, modes, fraction), not on the point, only its start
    does — every estimate of a sweep re-solves the same ones (and the engine's per-model caches,
    e.g. :func:`sarfe.hbm.modal.cached_modal_basis`, serve them from the second point on). A
    caller may own one (:class:`sarfe.accuracy.estimate.EstimateProblem`, ``coarser``); else
    :func:`coarser_models` gives the one that lives as long as the model object. Entries are
    keyed on the identity of contacts and excitation (held) and the mode indices."""

    def __init__(self):
        self._models = {}

    def get(self, model, contacts, excitation, modal_dofs, residual_dofs=(),
            fraction=0.2) -> CoarserModel:
        """:func:`coarser_model`, built once per (model, contacts, excitation, modes, fraction)."""
        modal_dofs = np.asarray(modal_dofs, dtype=int)
        residual_dofs = np.asarray(residual_dofs, dtype=int)
        key = (id(model), id(contacts), id(excitation), modal_dofs.tobytes(),
               residual_dofs.tobytes(), float(fraction))
        hit = self._models.get(key)
        if hit is not None and hit[0] is model and hit[1] is contacts and hit[2] is excitation:
            return hit[3]
        built = coarser_model(model, contacts, excitation, modal_dofs, residual_dofs, fraction)
        self._models[key] = (model, contacts, excitation, built)
        return built


_OF_MODEL: dict = {}     # id(model) → CoarserModels, dropped when the model is collected


def coarser_models(model) -> CoarserModels:
    """The :class:`CoarserModels` of ``model`` for callers that own none: one per model object,
    dropped when the model is garbage-collected (the pattern of the engine's per-model caches; a
    pipeline builds its estimate problem per point, the model once per stage)."""
    key = id(model)
    models = _OF_MODEL.get(key)
    if models is None:
        models = CoarserModels()
        try:
            weakref.finalize(model, _OF_MODEL.pop, key, None)
        except TypeError:        # not weak-referenceable: not kept (ids could be reused)
            return models
        _OF_MODEL[key] = models
    return models


def modal_truncation_change(solution, model, contacts, excitation, modal_dofs, residual_dofs=(),
                            erp_map=None, erp_areas=None, options=None, ref_amplitude=None,
                            steps=None, fraction=0.2, coarser=None):
    r"""(4): change of the solution on the coarser model T (:func:`coarser_basis`, the top
    ``fraction`` of the modes ``modal_dofs`` — at least one — left out), re-solved (1) from the
    solution projected on it → (relative amplitude change, |ERP level change| [dB], modes left
    out) or None when the re-solve fails. modal_dofs: the fixed-interface modal coordinates in
    increasing frequency; residual_dofs: the residual modes (rebuilt for the coarser model).
    ``coarser``: the :class:`CoarserModels` to take it from (default :func:`coarser_models`).
    """
    coarser = coarser_models(model) if coarser is None else coarser
    small = coarser.get(model, contacts, excitation, modal_dofs, residual_dofs, fraction)
    T = small.basis
    U = np.asarray(solution.displacement, dtype=float)
    # start: the M-orthogonal projection of ũ on span T
    M = model.mass.toarray() if hasattr(model.mass, "toarray") else np.asarray(model.mass)
    start = np.linalg.solve(small.model.mass, ((U @ M) @ T).T).T
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    F_small = resize_harmonics(np.asarray(excitation) @ T, H)
    U_small = newton_step(small.model, small.contacts, F_small, start, float(solution.omega), H, N,
                          options, steps)
    if U_small is None:
        U_small = newton_correction(small.model, small.contacts, F_small,
                                    SimpleNamespace(displacement=start, omega=solution.omega,
                                                    harmonics=H), H, N, options)
    if U_small is None:
        return None
    rel, db = solution_change(contacts, U, U_small @ T.T, float(solution.omega), erp_map,
                              erp_areas, ref_amplitude)
    return rel, abs(db), small.removed


def mode_richardson(modes, coarser_modes, decay=1.0) -> float:
    """1 / ((m/m')^p − 1): the kept model's error from the change m' → m modes (4), for an error
    ∝ m^{−p} (p = ``decay``). With plate-like modal density (ω_j ∝ j, constant per Hz, the slowest
    among shells) both the quasi-static share of the omitted modes without residual modes, Σ_{j>m}
    (ω/ω_j)², and the basis dependence of modal damping (2 ζ ω/ω_h on the quasi-static response,
    ω_h ∝ m the highest system mode) decay like m^{−1}: p = 1 is the slowest decay; for m' = 4m/5
    the factor is then 4, for m' = 19m/20 it is 19."""
    return float(1.0 / ((modes / max(coarser_modes, 1)) ** decay - 1.0))


def mode_decay(modes, coarser, changes) -> float:
    """p of (5), fitted from the changes d₁, d₂ of two probes m₁' > m₂' (fewer modes left out
    first): d_i = e (r_i^p − 1), r_i = m/m_i', so d₂/d₁ = (r₂^p − 1)/(r₁^p − 1), increasing in p;
    solved by Brent's method and kept in MODE_DECAY (a ratio at or below its p = 1 value — the
    changes not decaying, or not monotone — gives p = 1, the slowest decay of
    :func:`mode_richardson`)."""
    from scipy.optimize import brentq     # (0.2–0.4 s to import; no other module needs it)

    (m1, m2), (d1, d2) = coarser, changes
    if not (m1 > m2 and d1 > 0 and np.isfinite(d2)):
        return MODE_DECAY[0]
    r1, r2 = modes / m1, modes / m2
    lo, hi = MODE_DECAY
    mismatch = (lambda p: (r2 ** p - 1.0) / (r1 ** p - 1.0) - d2 / d1)
    if mismatch(lo) >= 0.0:
        return lo
    if mismatch(hi) <= 0.0:
        return hi
    return float(brentq(mismatch, lo, hi, xtol=1e-13))


def modal_extrapolation(modes, coarser, changes) -> tuple[float, float]:
    """(5): the kept model's modal-truncation error from the changes d_i of the probes with m_i'
    modes (fewer modes left out first) → (error, fitted p): d / (r^p − 1) of the largest probe
    (the last), p = :func:`mode_decay`. With p = 1 (changes that do not decay) that is the single
    top-fifth probe × 4; a steeper decay lowers the factor to 1/(1.25^2.5 − 1) = 1.34."""
    p = mode_decay(modes, coarser, changes) if len(changes) == 2 else MODE_DECAY[0]
    return float(changes[-1] * mode_richardson(modes, coarser[-1], p)), float(p)


@dataclass(frozen=True)
class ModalEstimate:
    """(5) of one solution: amplitude_rel, erp_db [dB] (NaN when no probe converged), notes."""

    amplitude_rel: float
    erp_db: float
    notes: tuple = ()


def modal_truncation_estimate(solution, model, contacts, excitation, modal_dofs, residual_dofs=(),
                              erp_map=None, erp_areas=None, options=None, ref_amplitude=None,
                              steps=None, coarser=None) -> ModalEstimate:
    """(4)–(5): the probes of MODE_PROBES (:func:`modal_truncation_change`) extrapolated with the
    fitted decay (:func:`modal_extrapolation`)."""
    residual_dofs = () if residual_dofs is None else residual_dofs
    kept = len(modal_dofs)
    probes = [modal_truncation_change(solution, model, contacts, excitation, modal_dofs,
                                      residual_dofs, erp_map, erp_areas, options, ref_amplitude,
                                      steps, fraction, coarser)
              for fraction in MODE_PROBES]
    probes = [p for p in probes if p is not None]
    if not probes:
        return ModalEstimate(float("nan"), float("nan"), notes=("modal estimate: singular Jacobian",))
    coarser_counts = [kept - p[2] for p in probes]
    m_rel, _ = modal_extrapolation(kept, coarser_counts, [p[0] for p in probes])
    m_db, _ = modal_extrapolation(kept, coarser_counts, [p[1] for p in probes])
    notes = (("modal estimate: one probe did not converge (p = 1 on the other)",)
             if len(probes) < len(MODE_PROBES) else ())
    return ModalEstimate(m_rel, m_db, notes)


__all__ = ["MODE_PROBES", "MODE_DECAY", "coarser_basis", "rebuilt_modal_damping", "CoarserModel",
           "coarser_model", "CoarserModels", "coarser_models", "modal_truncation_change",
           "mode_richardson", "mode_decay", "modal_extrapolation", "ModalEstimate",
           "modal_truncation_estimate"]
