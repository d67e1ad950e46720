r"""Accuracy of a whole sweep as an input: a target (``fast | balanced | fine | {erp_db: x} |
{amplitude_rel: x}``) → H and N, searched cheaply at one representative point (issue 15).

1. Screening: a stepped solve of a coarse frequency grid at a low H (``start_harmonics``, N =
   ``start_samples``), no stability, no estimates.
2. The representative point: the loudest converged screening point with an active contact, by the
   A-weighted ERP P_A = Σ_k 10^{A(kf)/10} (kω)² Σ_s a_s |w_{s,k}|² (the headline the user reads);
   up to ``max_points_tuned`` − 1 more points, those with the largest contact-force spectral tail
   (:func:`sarfe.accuracy.measures.spectral_tail`: the strongest nonlinearity), are checked from
   the H found there.
3. H ladder at a point: H_{i+1} = max(H_i + 2, round(1.5 H_i)), each solve warm-started from the
   previous solution padded with zero harmonics (a few Newton iterations on the contact rows; the
   condensed compliances G Z_k⁻¹ Gᵀ come from the reduced model's cached modal basis), N_i the
   larger of the start N and 16 H_i (a power of two). The search stops at the first H_i whose
   change to H_{i+1} — first-harmonic contact amplitude (relative) and ERP level (the larger of the
   dB and dB(A) changes) — times the Richardson factor max(2, 1/(1 − H_i/H_{i+1})) (an error
   ∝ H^{−p}, p ≥ 1: :func:`sarfe.accuracy.harmonic_truncation.harmonics_richardson`) is within half the
   budget. H is capped at the audible band: H·f ≤ ``audible_top_hz`` (5 kHz; harmonics above it
   carry little of the A-weighted ERP) and ``max_harmonics``.
4. N at the chosen H: N → 2N (warm start) until RICHARDSON × the change is within the other half.
5. Craig–Bampton cutoff (FE; the case layer, :func:`sarfe.pipeline.solve.case_accuracy.case_resolution`):
   a cutoff for the Newton, not for the spectrum (issue 30): max(1 kHz, max(cutoff_margin,
   LADDER_FACTOR) · 5 · f_max), the same for every H, so the search runs on one stage and the
   sweep reuses it. The harmonics above it are answered quasi-statically (constraint modes at the
   contact DOFs, residual vectors for the loads); the per-point estimate's modal term measures that.
   Measured on the door trim (benchmarks/results/audible.md): on a 1 kHz stage the dB(A) is within
   0.011 dB of a 4 kHz one for H = 3…60, and contact forces from a smaller basis recovered on a
   larger one are no closer to the converged ERP than the smaller basis alone (no separate
   recovery cutoff); a cutoff or mode count given by the user is kept.

The level change counts dB(A) only when the finer rung reaches AUDIBLE_BOTTOM_HZ (20 Hz): below
it the A-weighting (−50 dB and falling) turns the weighted level into a measure of the top
harmonic alone.

Works on plain arrays (:class:`sarfe.accuracy.estimate.EstimateProblem`); the case layer builds
them (:mod:`sarfe.pipeline.solve.case_accuracy`) and applies the result (:func:`sarfe.pipeline.solve.case_accuracy.resolved_case`).
"""
from __future__ import annotations

import copy
import math
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np

from sarfe.accuracy.estimate import EstimateProblem
from sarfe.accuracy.harmonic_truncation import RICHARDSON, harmonics_richardson
from sarfe.accuracy.measures import erp_proxy, resize_harmonics, solution_change, spectral_tail
from sarfe.accuracy.target import parse_accuracy
from sarfe.hbm import SolverOptions, solve_frequency

AUDIBLE_TOP_HZ = 5000.0   # A-weighted ERP of impacts: harmonics in 0.5–5 kHz (issue 15)
AUDIBLE_BOTTOM_HZ = 20.0  # below it dB(A) is not a level anyone hears: the dB change is used
LADDER_FACTOR = 1.5       # H_{i+1} = max(H_i + 2, round(1.5 H_i))
SAMPLES_PER_HARMONIC = 16  # N ≥ 16 H (as the case default), a power of two


def screen_grid(problem: EstimateProblem, frequencies_hz, harmonics, samples_per_period,
                options=None):
    """Stepped solve of the grid [Hz] at H, N (warm start from the previous converged point, a
    failed point retried once cold) → list of HarmonicSolution."""
    H, N = int(harmonics), int(samples_per_period)
    solutions, previous = [], None
    for f in frequencies_hz:
        s = _solve(problem, 2 * np.pi * float(f), H, N, previous, options)
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


def a_weighted_power(solution, problem: EstimateProblem) -> float:
    """P_A ∝ the A-weighted ERP of a solution (module docstring, 2) [arbitrary units]."""
    return erp_proxy(solution.displacement, float(solution.omega), problem.erp_map,
                      problem.erp_areas, a_weighted=True)


def representative_points(solutions, problem: EstimateProblem, count: int) -> list:
    """The screening solutions to tune (module docstring, 2): the loudest converged one with an
    active contact first (any converged one when none is active), then up to ``count`` − 1 more by
    descending contact-force spectral tail."""
    converged = [s for s in solutions if s.converged]
    pool = [s for s in converged if contact_active(s, problem.contacts)] or converged
    if not pool:
        return []
    loudest = max(pool, key=lambda s: a_weighted_power(s, problem))
    rest = sorted((s for s in pool if s is not loudest),
                  key=lambda s: -spectral_tail(np.asarray(s.contact_force))
                  if np.asarray(s.contact_force).size else 0.0)
    return [loudest] + rest[:max(0, int(count) - 1)]


def ladder_samples(harmonics: int, start_samples: int) -> int:
    """N of ladder step H: the larger of the start N and 16 H, rounded up to a power of two."""
    need = max(int(start_samples), SAMPLES_PER_HARMONIC * int(harmonics), 4 * int(harmonics) + 1)
    return int(2 ** math.ceil(math.log2(need)))


def next_harmonics(harmonics: int) -> int:
    """The next rung of the H ladder: max(H + 2, round(1.5 H))."""
    return int(max(harmonics + 2, round(LADDER_FACTOR * harmonics)))


def harmonics_cap(omega: float, max_harmonics: int, audible_top_hz: float) -> int:
    """Largest H searched at ω [rad/s]: H·f ≤ audible_top_hz, at most max_harmonics (≥ 1)."""
    f = float(omega) / (2 * np.pi)
    audible = int(math.floor(audible_top_hz / f)) if f > 0 else max_harmonics
    return int(max(1, min(max_harmonics, audible)))


@dataclass(frozen=True)
class LadderResult:
    """The H search at one point: chosen H and N, its solution, the bound on its error (relative
    first-harmonic amplitude, ERP level [dB]) split into the truncation (H → next rung) and
    aliasing (N → 2N) parts with their factors applied, met, reason and one dict per solve."""

    solution: object
    harmonics: int
    samples_per_period: int
    harmonics_rel: float
    harmonics_db: float
    aliasing_rel: float
    aliasing_db: float
    met: bool
    reason: str
    history: tuple

    @property
    def amplitude_rel(self) -> float:
        return float(self.harmonics_rel + self.aliasing_rel)

    @property
    def erp_db(self) -> float:
        return float(self.harmonics_db + self.aliasing_db)


def _solve(problem, omega, H, N, guess, options):
    """Solve at (H, N) from ``guess`` (padded), cold once when the warm start fails."""
    F = resize_harmonics(problem.excitation, H)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = None if guess is None else resize_harmonics(guess.displacement, H)
        s = solve_frequency(problem.model, problem.contacts, F, omega, H, N, initial=start,
                            options=options)
        if not s.converged and start is not None:
            cold = solve_frequency(problem.model, problem.contacts, F, omega, H, N,
                                   options=options)
            s = cold if cold.converged else s
    return s


def _measured_change(problem, coarse, fine):
    """(relative first-harmonic contact amplitude change, ERP level change [dB]) from ``coarse`` to
    ``fine`` (coarse padded to fine's H). The level change is the larger of the dB and dB(A)
    changes when fine's top harmonic reaches the audible band (H f ≥ AUDIBLE_BOTTOM_HZ), else the
    dB change alone: below 20 Hz the A-weighting (−50 dB and falling) makes the weighted level a
    measure of the top harmonic only, of no acoustic meaning."""
    H, omega = int(fine.harmonics), float(fine.omega)
    U0 = resize_harmonics(coarse.displacement, H)
    U1 = np.asarray(fine.displacement, dtype=float)
    rel, db = solution_change(problem.contacts, U0, U1, omega, problem.erp_map, problem.erp_areas)
    if db != 0.0 and H * omega / (2 * np.pi) < AUDIBLE_BOTTOM_HZ:
        p0, p1 = (erp_proxy(U, omega, problem.erp_map, problem.erp_areas) for U in (U0, U1))
        db = 10 * np.log10(p1 / p0) if p0 > 0 and p1 > 0 else (0.0 if p0 == p1 else np.inf)
    return float(rel), float(abs(db))


def search_harmonics(problem: EstimateProblem, target, solution, *, max_harmonics=64,
                     max_samples=8192, audible_top_hz=AUDIBLE_TOP_HZ, start_samples=64,
                     options=None, share=0.5) -> LadderResult:
    """H ladder and N doubling at one point from a converged ``solution`` (module docstring, 3–4)
    → :class:`LadderResult`. ``share`` of the budget goes to each of truncation and aliasing."""
    target = parse_accuracy(target)
    omega = float(solution.omega)
    cap = harmonics_cap(omega, max_harmonics, audible_top_hz)
    history = []
    current = solution
    h_rel = h_db = float("inf")
    met, reason = False, ""
    while True:
        H = int(current.harmonics)
        H_next = min(cap, next_harmonics(H))
        if H_next <= H:
            reason = (f"H cap {cap} reached (H·f ≤ {audible_top_hz:.0f} Hz, max_harmonics "
                      f"{max_harmonics})")
            break
        clock = time.perf_counter()
        N_next = max(int(current.samples_per_period), ladder_samples(H_next, start_samples))
        finer = _solve(problem, omega, H_next, N_next, current, options)
        entry = {"harmonics": H_next, "samples_per_period": N_next,
                 "converged": bool(finer.converged), "iterations": int(finer.iterations),
                 "seconds": time.perf_counter() - clock}
        history.append(entry)
        if not finer.converged:
            reason = f"not converged at H = {H_next}, N = {N_next}: {finer.reason}"
            break
        rel, db = _measured_change(problem, current, finer)
        factor = harmonics_richardson(H, H_next)
        entry.update(change_rel=rel, change_db=db, factor=factor)
        if target.met_by(factor * rel, factor * db, share):
            h_rel, h_db, met = factor * rel, factor * db, True
            reason = f"change H = {H} → {H_next} within the budget"
            break
        current = finer
    if not met:     # the last solution is the best there is; its error is unknown
        return LadderResult(current, int(current.harmonics), int(current.samples_per_period),
                            h_rel, h_db, float("nan"), float("nan"), False, reason, tuple(history))
    a_rel = a_db = 0.0
    H, N = int(current.harmonics), int(current.samples_per_period)
    while 2 * N <= max_samples:
        clock = time.perf_counter()
        doubled = _solve(problem, omega, H, 2 * N, current, options)
        entry = {"harmonics": H, "samples_per_period": 2 * N, "converged": bool(doubled.converged),
                 "iterations": int(doubled.iterations), "seconds": time.perf_counter() - clock}
        history.append(entry)
        if not doubled.converged:
            a_rel = a_db = float("inf")
            met, reason = False, f"not converged at H = {H}, N = {2 * N}: {doubled.reason}"
            break
        rel, db = _measured_change(problem, current, doubled)
        entry.update(change_rel=rel, change_db=db, factor=RICHARDSON)
        a_rel, a_db = RICHARDSON * rel, RICHARDSON * db
        if target.met_by(a_rel, a_db, share):
            break
        current, N = doubled, 2 * N
    else:
        met, reason = False, f"samples cap {max_samples} reached"
    return LadderResult(current, H, N, h_rel, h_db, a_rel, a_db, met, reason, tuple(history))


def resolve_accuracy(problem: EstimateProblem, target, frequencies_hz, harmonics,
                     samples_per_period, *, start_harmonics=3, start_samples=64, max_harmonics=64,
                     max_samples=8192, max_points_tuned=3, options=None,
                     audible_top_hz=AUDIBLE_TOP_HZ) -> dict:
    """Choose H, N for ``target`` (module docstring) from a screening of ``frequencies_hz`` [Hz] at
    ``start_harmonics``, ``start_samples`` → report dict with keys harmonics, samples_per_period,
    mode_count (None: the reduction's rule follows H), estimate (the chosen point's bound),
    met, reason, frequency_hz, tuned_hz, history, seconds, text, note.

    ``harmonics``, ``samples_per_period``: the case's, kept when no screening point converges.
    ``options``: the engine's (pass stability off: the search needs none)."""
    clock = time.perf_counter()
    target = parse_accuracy(target)
    if options is None:
        options = SolverOptions(stability=False)
    options = replace(options, stability=False)
    H0, N0 = int(start_harmonics), ladder_samples(int(start_harmonics), int(start_samples))
    sols = screen_grid(problem, frequencies_hz, H0, N0, options)
    points = representative_points(sols, problem, max_points_tuned)
    if not points:
        return {"harmonics": int(harmonics), "samples_per_period": int(samples_per_period),
                "mode_count": None, "estimate": None, "met": False,
                "reason": "no grid point converged in the screening pass", "frequency_hz": None,
                "tuned_hz": [], "history": [], "note": "", "seconds": time.perf_counter() - clock,
                "text": f"accuracy {target.name}: no grid point converged; case settings kept"}
    note = "" if contact_active(points[0], problem.contacts) else (
        "no converged screening point has an active contact: tuned at a linear point")
    search = dict(max_harmonics=max_harmonics, max_samples=max_samples,
                  audible_top_hz=audible_top_hz, start_samples=start_samples, options=options)
    tuned = [(points[0], search_harmonics(problem, target, points[0], **search))]
    for s in points[1:]:     # checked from the loudest point's H, N (warm from the screening)
        H, N = tuned[0][1].harmonics, tuned[0][1].samples_per_period
        start = _solve(problem, float(s.omega), H, N, s, options)
        tuned.append((s, search_harmonics(problem, target, start if start.converged else s,
                                          **search)))
    worst_point, worst = max(tuned, key=lambda t: (t[1].harmonics, t[1].samples_per_period))
    H_all = max(r.harmonics for _, r in tuned)
    N_all = max(r.samples_per_period for _, r in tuned)
    met_all = all(r.met for _, r in tuned)
    hz = (lambda s: float(s.omega) / (2 * np.pi))
    reason = worst.reason if met_all else "; ".join(
        f"{hz(s):.2f} Hz: {r.reason}" for s, r in tuned if not r.met)
    estimate = {"harmonics": worst.harmonics, "samples_per_period": worst.samples_per_period,
                "amplitude_rel": worst.amplitude_rel, "erp_db": worst.erp_db,
                "harmonics_rel": worst.harmonics_rel, "harmonics_db": worst.harmonics_db,
                "aliasing_rel": worst.aliasing_rel, "aliasing_db": worst.aliasing_db,
                "method": "measured change to the next H rung and to 2N, Richardson factors "
                          "applied"}
    history = [dict(entry, frequency_hz=hz(s)) for s, r in tuned for entry in r.history]
    seconds = time.perf_counter() - clock
    text = (f"accuracy {target.name or 'target'} (amplitude budget {target.amplitude_budget():.2g}"
            f"{'' if target.erp_db is None else f', ERP {target.erp_db:g} dB'}): "
            f"H = {H_all}, N = {N_all} (reduction cutoff: its rule with this H)"
            f"\n  searched at {', '.join(f'{hz(s):.2f}' for s, _ in tuned)} Hz (the loudest "
            f"screening point at H = {H0} first); at {hz(worst_point):.2f} Hz: amplitude "
            f"{worst.amplitude_rel:.2e}, ERP {worst.erp_db:.3f} dB (bound)"
            f"\n  {'met' if met_all else 'NOT met'}: {reason} ({len(history)} solves, "
            f"{seconds:.1f} s)" + (f"\n  note: {note}" if note else ""))
    return {"harmonics": H_all, "samples_per_period": N_all, "mode_count": None,
            "tuned_hz": [hz(s) for s, _ in tuned], "estimate": estimate, "met": met_all,
            "reason": reason, "frequency_hz": hz(worst_point), "history": history, "note": note,
            "seconds": seconds, "text": text}


__all__ = ["AUDIBLE_TOP_HZ", "screen_grid", "contact_active", "a_weighted_power",
           "representative_points", "ladder_samples", "next_harmonics", "harmonics_cap",
           "LadderResult", "search_harmonics", "resolve_accuracy"]
