r"""Accuracy of a whole sweep as an input: a target (``fast | balanced | fine | {erp_db: x} |
{amplitude_rel: x}``) → H, N and the fixed-interface mode count.

1. a stepped solve over a coarse grid of frequencies at the given H, N (screening);
2. the grid points with active contacts and the largest a-posteriori estimates (nonlinearity is
   strongest there) are refined by :func:`sarfe.accuracy.estimates.choose_resolution` (H up until the
   truncation estimate, then N up until the aliasing estimate are each within half the budget);
3. models with modal truncation: the mode count from
   :func:`sarfe.accuracy.estimates.suggest_mode_count` (doubled when the modal estimate — the
   re-solve on the coarser Craig–Bampton model, (4) there — exceeds half the budget).

Works on plain arrays (:class:`sarfe.accuracy.estimates.EstimateProblem`); the case layer builds
them (:mod:`sarfe.pipeline.accuracy`) and applies the result with :func:`apply_resolution`.
"""
from __future__ import annotations

import copy
import time
import warnings

import numpy as np

from .estimates import (EstimateProblem, choose_resolution, parse_accuracy, problem_error_estimate,
                        resize_harmonics, suggest_mode_count)


def screen_grid(problem: EstimateProblem, frequencies_hz, harmonics, samples_per_period,
                options=None):
    """Stepped solve of the grid [Hz] at H, N (warm start from the previous converged point, a
    failed point retried once cold) → list of HarmonicSolution."""
    from sarfe.hbm import solve_frequency

    H, N = int(harmonics), int(samples_per_period)
    solutions, previous = [], None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for f in frequencies_hz:
            omega = 2 * np.pi * float(f)
            F = resize_harmonics(problem.excitation, H)
            s = solve_frequency(problem.model, problem.contacts, F, omega, H, N, initial=previous,
                                options=options)
            if not s.converged and previous is not None:
                retry = solve_frequency(problem.model, problem.contacts, F, omega, H, N,
                                        options=options)
                s = retry if retry.converged else s
            solutions.append(s)
            previous = s if s.converged else None
    return solutions


def contact_active(solution, contacts) -> bool:
    """Some contact carries a force at some instant (a normal force or a constant normal load)."""
    if not contacts.count:
        return False
    if np.any(np.asarray(contacts.normal_load) > 0):
        return True
    rows = np.asarray(contacts.normal_row)
    rows = rows[rows >= 0]
    force = np.asarray(solution.contact_force_time)
    return bool(rows.size and np.max(force[:, rows], initial=0.0) > 0)


def resolve_accuracy(problem: EstimateProblem, target, frequencies_hz, harmonics,
                     samples_per_period, *, start_harmonics=3, start_samples=64, max_harmonics=64,
                     max_samples=8192, max_points_tuned=3, options=None, mode_frequencies_hz=None,
                     max_frequency_hz=None, current_modes=None) -> dict:
    """Choose H, N (and mode count) for ``target`` (module docstring) over the screening grid
    ``frequencies_hz`` solved at ``harmonics``, ``samples_per_period`` → report dict with keys
    harmonics, samples_per_period, mode_count (None without ``mode_frequencies_hz``), mode,
    estimate, met, reason, frequency_hz, tuned_hz, history, seconds, text, note."""
    clock = time.perf_counter()
    target = parse_accuracy(target)
    sols = screen_grid(problem, frequencies_hz, harmonics, samples_per_period, options)
    converged = [s for s in sols if s.converged]
    if not converged:
        return {"harmonics": int(harmonics), "samples_per_period": int(samples_per_period),
                "mode_count": None, "mode": None, "estimate": None, "met": False,
                "reason": "no grid point converged in the screening pass", "frequency_hz": None,
                "tuned_hz": [], "history": [], "note": "", "seconds": time.perf_counter() - clock,
                "text": f"accuracy {target.name}: no grid point converged; case settings kept"}
    estimates = {id(s): problem_error_estimate(s, problem) for s in converged}
    active = [s for s in converged if contact_active(s, problem.contacts)]
    note = ("no converged screening point has an active contact (the others did not converge): "
            "tuned at a linear point, the choice may be too coarse for the impacts"
            if not active and len(converged) < len(sols) else "")
    candidates = sorted(active or converged,
                        key=lambda s: -np.nan_to_num(estimates[id(s)].amplitude_rel))

    def adapt(s, H0, N0):
        return choose_resolution(target, problem.model, problem.contacts, problem.excitation,
                                 float(s.omega), harmonics=H0, samples_per_period=N0,
                                 max_harmonics=max_harmonics, max_samples=max_samples,
                                 erp_map=problem.erp_map, erp_areas=problem.erp_areas,
                                 modal_dofs=problem.modal_dofs, residual_dofs=problem.residual_dofs,
                                 initial=resize_harmonics(s.displacement, H0))

    tuned = []
    for s in candidates[:max_points_tuned]:
        resolution = adapt(s, start_harmonics, start_samples)
        lost = (contact_active(s, problem.contacts) and resolution.solution is not None
                and not contact_active(resolution.solution, problem.contacts))
        if lost:   # contact vanished from the coarse start: adapt from the case's H, N instead
            resolution = adapt(s, int(harmonics), int(samples_per_period))
            note = (note + "; " if note else "") + (
                f"{s.omega / (2 * np.pi):.2f} Hz: no contact at H = {start_harmonics}, adapted "
                f"from the case's H = {harmonics}")
        tuned.append((s, resolution))
    worst, resolution = max(tuned, key=lambda t: (t[1].harmonics, t[1].samples_per_period))
    H_all = max(r.harmonics for _, r in tuned)
    N_all = max(r.samples_per_period for _, r in tuned)
    met_all = all(r.met for _, r in tuned)
    mode = None
    if mode_frequencies_hz is not None:
        freqs = np.asarray(mode_frequencies_hz, dtype=float)
        mode = suggest_mode_count(freqs, max_frequency_hz, H_all, target,
                                  modal_rel=resolution.estimate.modal_rel, current=current_modes)
        if mode["mode_count"] >= len(freqs):
            mode["note"] = (f"all {len(freqs)} computed modes are below the cutoff: the linear stage "
                            "computes more when mode_count is set")
    e = resolution.estimate
    hz = (lambda s: float(s.omega) / (2 * np.pi))
    tuned_text = ", ".join(f"{hz(s):.2f}" for s, _ in tuned)
    reason = resolution.reason if met_all else "; ".join(
        f"{hz(s):.2f} Hz: {r.reason}" for s, r in tuned if not r.met)
    text = (f"accuracy {target.name or 'target'} (amplitude budget {target.amplitude_budget():.2g}):"
            f" H = {H_all}, N = {N_all}"
            + (f", mode_count = {mode['mode_count']} ({mode['reason']})" if mode else "")
            + f"\n  tuned at {tuned_text} Hz "
            f"(active contacts, largest screening estimates); at {hz(worst):.2f} Hz: "
            f"amplitude {e.amplitude_rel:.2e} (H→{e.extended_harmonics}: {e.harmonics_rel:.2e}, "
            f"N→2N: {e.aliasing_rel:.2e}, modes: {e.modal_rel:.2e}), ERP {e.erp_db:.3f} dB"
            f"\n  {'met' if met_all else 'NOT met'}: {reason} "
            f"({len(resolution.history)} rounds, {time.perf_counter() - clock:.1f} s)"
            + (f"\n  note: {note}" if note else ""))
    return {"harmonics": H_all, "samples_per_period": N_all,
            "tuned_hz": [hz(s) for s, _ in tuned],
            "mode_count": None if mode is None else mode["mode_count"], "mode": mode,
            "estimate": e.as_dict(), "met": met_all, "reason": reason,
            "frequency_hz": hz(worst), "history": resolution.history, "note": note,
            "seconds": time.perf_counter() - clock, "text": text}


def apply_resolution(case_data: dict, report: dict) -> dict:
    """Case data (a copy) with solver.harmonics / samples_per_period and reduction.mode_count set,
    ``resolution: fixed`` (chosen; ``accuracy`` stays the run's error budget)."""
    data = copy.deepcopy(case_data)
    data.setdefault("solver", {})
    data["solver"]["harmonics"] = int(report["harmonics"])
    data["solver"]["samples_per_period"] = int(report["samples_per_period"])
    data["solver"]["resolution"] = "fixed"
    if report.get("mode_count"):
        red = data.setdefault("reduction", {})
        red.pop("cutoff_hz", None)
        red["mode_count"] = int(report["mode_count"])
    return data


__all__ = ["screen_grid", "contact_active", "resolve_accuracy", "apply_resolution"]
