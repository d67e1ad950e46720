r"""Contact pruning in ``sarfe solve``: contacts that never switch over the case's frequencies are
solved linearly (``solver.prune_contacts``, default true; the library is :mod:`sarfe.hbm.pruning`).

1. Screen (one linear pass per ω): every contact pair of the ContactSet linearized at u = 0 over
   the listed frequencies, or over a sweep's band sampled on a grid plus the natural frequencies
   ω_n of the linearized model (K + Gᵀ k G, M) inside it — where the linear response peaks.
   A pair whose relative normal motion w stays below (1 − m) g (gap g > 0) is ``open`` and dropped;
   a preloaded rattle pair whose compression w − g stays above m × its static value is ``closed``
   and becomes a spring k_n (K += k_n gᵣᵀ gᵣ, f̃_e,0 += k_n g gᵣᵀ); the rest stay ``nonlinear``.
2. Solve the points (or the continuation) on the pruned model.
3. Check every converged solution: w of the dropped pairs is still G ũ; if a decision fails
   anywhere the whole case is solved again with the full contact set. A point that did not
   converge on the pruned model cannot be checked: it is solved again at its ω with all contacts.
4. Restore each solution to the full contact set (contact displacements, forces, states of all
   pairs; residual of the full equations), so every output reads as without pruning.

Exactness: an ``open`` pair that never closes has λ ≡ 0 and a ``closed`` pair that never opens has
λ = k_n (w − g), linear — the pruned equations *are* the full equations on such a solution. A sweep
by continuation is the same curve but its adaptive points may fall at other ω.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from sarfe.case.config import ExcitationConfig, SolverConfig
from sarfe.hbm.pruning import (CLOSED, NONLINEAR, OPEN, check_pruning, linearized_stiffness,
                               prune_contacts, restore_solution, screen_contacts)
from sarfe.pipeline.model.nonlinear_model import NonlinearModel
from sarfe.pipeline.solve.by_need import points_by_need
from sarfe.pipeline.solve.points import TIME_INTEGRATION, solve_point, solver_options

SWEEP_GRID_POINTS = 201
MAX_LISTED = 20          # violations listed in the report (all are counted)
MAX_DENSE_EIGEN = 3000   # DOFs up to which the linearized natural frequencies are computed (dense)


def pruning_options(solver: SolverConfig) -> tuple:
    """(enabled, margin m) from ``solver.prune_contacts`` (true | false | {margin: m}; the margin's
    default: :class:`sarfe.case.config.SolverConfig` ``prune_margin``)."""
    return solver.prune_contacts, solver.prune_margin


def linearized_natural_frequencies(model, contacts) -> np.ndarray:
    r"""ω_n [rad/s] of K_lin φ = ω² M φ, K_lin = K + Gᵀ diag(k) G the stiffness the screening pass
    solves with (:func:`sarfe.hbm.pruning.linearized_stiffness`: closed pairs as springs k_n,
    friction tangents stuck, open pairs absent). Empty if M is singular (massless DOFs) or the model
    has more than MAX_DENSE_EIGEN DOFs (then the grid alone)."""
    if model.dof_count > MAX_DENSE_EIGEN:
        return np.zeros(0)
    dense = (lambda A: A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float))
    try:
        eigenvalues = scipy.linalg.eigh(dense(linearized_stiffness(model, contacts)[0]),
                                        dense(model.mass), eigvals_only=True)
    except (np.linalg.LinAlgError, ValueError):
        return np.zeros(0)
    return np.sqrt(np.clip(eigenvalues, 0.0, None))


def screening_frequencies(excitation: ExcitationConfig, nl: NonlinearModel) -> np.ndarray:
    """ω [rad/s] of the screening pass: the listed frequencies, or for a sweep a grid of
    SWEEP_GRID_POINTS over [start, end] plus the linearized natural frequencies inside it."""
    if excitation.sweep is None:
        return 2 * np.pi * np.asarray(excitation.frequency_hz, dtype=float)
    start, end = sorted(2 * np.pi * hz for hz in (excitation.sweep.start_hz,
                                                   excitation.sweep.end_hz))
    natural = linearized_natural_frequencies(nl.model, nl.contacts)
    inside = natural[(natural >= start) & (natural <= end)]
    return np.unique(np.concatenate([np.linspace(start, end, SWEEP_GRID_POINTS), inside]))


def pruned_model(nl: NonlinearModel, pruned) -> NonlinearModel:
    """The NonlinearModel solved after pruning (kept pairs only; groups and tolerances unused)."""
    return dataclasses.replace(nl, model=pruned.model, contacts=pruned.contacts,
                               excitation=pruned.excitation)


def contact_report(decisions, groups) -> list:
    """One entry per named contact: its decision (``nonlinear`` if any of its node pairs is kept,
    else ``open`` / ``closed`` / ``open+closed``), pair counts per decision, the smallest clearance
    and the reason of the deciding pair."""
    report = []
    for name, kind, index in groups:
        own = [decisions[i] for i in index]
        counts = {d: sum(x.decision == d for x in own) for d in (OPEN, CLOSED, NONLINEAR)}
        if counts[NONLINEAR]:
            decision = NONLINEAR
        elif counts[CLOSED] == 0:
            decision = OPEN
        elif counts[OPEN] == 0:
            decision = CLOSED
        else:
            decision = f"{OPEN}+{CLOSED}"
        deciding = [x for x in own if x.decision == NONLINEAR] or own
        clearances = np.array([x.clearance for x in deciding], dtype=float)
        pick = deciding[int(np.nanargmin(clearances))] if np.any(np.isfinite(clearances)) \
            else deciding[0]
        report.append({"name": name, "kind": kind, "decision": decision,
                       "clearance": float(pick.clearance), "pairs": counts,
                       "reason": pick.reason if len(own) == 1 else f"{pick.name}: {pick.reason}"})
    return report


def _check_samples(N):
    """Samples per period of the a-posteriori check: a multiple of N, at least 256."""
    return int(N) * max(1, -(-256 // int(N)))


def check_solutions(samples_per_period, nl: NonlinearModel, decisions, solutions) -> tuple:
    """(violations, unsolved): the decisions every converged pruned solution breaks, as
    {contact, frequency_hz, what}, and the indices of the points that did not converge."""
    samples = _check_samples(samples_per_period)
    violations, unsolved = [], []
    for index, solution in enumerate(solutions):
        if solution.method == TIME_INTEGRATION or not solution.converged:
            unsolved.append(index)
            continue
        hz = float(solution.omega) / (2 * np.pi)
        violations += [{"contact": name, "frequency_hz": hz, "what": what} for name, what in
                       check_pruning(nl.contacts, decisions, solution.displacement, samples)]
    return violations, unsolved


def restore_solutions(solver: SolverConfig, nl: NonlinearModel, decisions, solutions, unsolved,
                      linear) -> list:
    """Pruned solutions re-expressed with the full contact set; a point that did not converge on
    the pruned model is solved again at its ω with all contacts (from the pruned state)."""
    restored = []
    for index, solution in enumerate(solutions):
        if index in unsolved:
            H, N = solver.harmonics, solver.samples_per_period
            start = None if solution.method == TIME_INTEGRATION else solution
            restored.append(solve_point(nl, float(solution.omega), H, N, solver_options(solver)[0],
                                        start))
            continue
        solution = restore_solution(solution, nl.model, nl.contacts, nl.excitation, decisions)
        if linear:      # no nonlinear contact was left: say why in the point's reason
            solution = dataclasses.replace(
                solution, reason="every contact screened open or closed: exact linear solution")
        restored.append(solution)
    return restored


def solve_points_pruned(solver: SolverConfig, excitation: ExcitationConfig, nl: NonlinearModel,
                        progress=False, measure=None) -> tuple:
    """(solutions, report): the points (:func:`sarfe.pipeline.solve.by_need.points_by_need`: a
    sweep by need, else :func:`sarfe.pipeline.solve.points.solve_points`) on the pruned model,
    checked and restored to the full contact set (module docstring), or on the full model when
    pruning is off, removes nothing, or a decision fails. ``measure(ũ, ω)``: the response a sweep
    by need refines its linear peaks on (None: the contact rows'). ``report`` is summary.json's
    ``contact_pruning``."""
    enabled, margin = pruning_options(solver)

    def points(solver, excitation, nl, progress):
        if excitation.sweep is None or not solver.continuation.linear_points:
            return points_by_need(solver, excitation, nl, None, progress=progress)
        return points_by_need(solver, excitation, nl, screening_frequencies(excitation, nl),
                              linearized_natural_frequencies(nl.model, nl.contacts), measure,
                              progress)

    report = {"enabled": enabled, "applied": False, "fallback": False, "margin": margin,
              "screened_frequencies": 0, "pairs": int(nl.contacts.count),
              "nonlinear_pairs": int(nl.contacts.count), "contacts": [], "violations": [],
              "violation_count": 0, "full_model_points_hz": []}
    if not enabled or not nl.contacts.count:
        return points(solver, excitation, nl, progress=progress), report
    omegas = screening_frequencies(excitation, nl)
    decisions = screen_contacts(nl.model, nl.contacts, nl.excitation, omegas, margin=margin)
    kept = sum(d.decision == NONLINEAR for d in decisions)
    report.update(screened_frequencies=int(len(omegas)), nonlinear_pairs=int(kept),
                  contacts=contact_report(decisions, nl.groups))
    if kept == nl.contacts.count:      # nothing to remove
        return points(solver, excitation, nl, progress=progress), report
    pruned = prune_contacts(nl.model, nl.contacts, nl.excitation, decisions)
    solutions = points(solver, excitation, pruned_model(nl, pruned), progress=progress)
    violations, unsolved = check_solutions(solver.samples_per_period, nl, decisions, solutions)
    if violations:                     # a decision does not hold: solve it all again
        report.update(fallback=True, nonlinear_pairs=int(nl.contacts.count),
                      violation_count=len(violations), violations=violations[:MAX_LISTED])
        return points(solver, excitation, nl, progress=progress), report
    report.update(applied=True, full_model_points_hz=[
        float(solutions[i].omega) / (2 * np.pi) for i in unsolved])
    return restore_solutions(solver, nl, decisions, solutions, unsolved,
                             linear=not pruned.contacts.count), report


__all__ = ["pruning_options", "linearized_natural_frequencies", "screening_frequencies",
           "pruned_model", "contact_report", "check_solutions", "restore_solutions",
           "solve_points_pruned"]
