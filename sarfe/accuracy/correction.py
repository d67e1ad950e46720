r"""The Newton correction every estimate of :mod:`sarfe.accuracy` is made of: a solution ũ of
R_{H,N}(ũ) = S(ω) ũ + f̃_nl^{(N)}(ũ) − f̃_e = 0, embedded in another discretization (H', N') or
projected on another model, leaves a residual there; Newton iterations of that problem from it,
the first being

    δ = −J_{H',N'}(ũ)⁻¹ R_{H',N'}(ũ),                                           (1)

give the change of the solution. From a start this close they take one to a few iterations
(condensed on the contact rows: :func:`sarfe.hbm.solve.newton_from`, :func:`newton_step`). A raise
H → H' large enough to change an impact's active set may not converge in one solve:
:func:`newton_correction` then raises H in steps of ×1.5 and stops at the last converged H''.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from sarfe.accuracy.measures import resize_harmonics
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.newton import SingularJacobian
from sarfe.hbm.solve import newton_from

REFINE_ITERATIONS = 40  # Newton iterations allowed per raise of H (1) before stopping the climb
ESTIMATE_ITERATIONS = 8      # Newton iterations of one estimate solve (1) (usually 1–4)
ESTIMATE_TOLERANCE = 1e-7    # its relative residual: the changes sought are ≥ 1e-4 of a₁
STALLED_RESIDUAL = 1e-5      # a solve stalled below this residual (at a kink) is still used


def samples_for(harmonics: int, samples_per_period: int) -> int:
    """N kept at least 4H+1 (no aliasing of quadratic terms), as a power of two when N was one."""
    return doubled_to(samples_per_period, 4 * harmonics + 1)


def doubled_to(samples_per_period: int, need: float) -> int:
    """N doubled until N ≥ ``need``."""
    N = int(samples_per_period)
    while N < need:
        N *= 2
    return int(N)


def newton_step(model, contacts, excitation, U, omega, harmonics, samples_per_period,
                options=None, steps=None):
    """The (H', N') problem solved from ũ (2H'+1, n) [m] by Newton (1), condensed on the contact
    rows as the engine solves it (:func:`sarfe.hbm.solve.newton_from`) → ũ' (2H'+1, n), or None
    when the Jacobian is singular, Newton stalls above STALLED_RESIDUAL or ũ' is not finite.
    ``steps``: at most that many iterations (default ESTIMATE_ITERATIONS, relative residual
    ESTIMATE_TOLERANCE, at most 3 line-search halvings); from a start this close they are
    usually 1–4."""
    base = options or SolverOptions()
    options = replace(base, stability=False, max_iterations=int(steps or ESTIMATE_ITERATIONS),
                      tolerance=max(base.tolerance, ESTIMATE_TOLERANCE),
                      line_search_steps=min(base.line_search_steps, 3))
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            U_new, result = newton_from(model, contacts, excitation, U, omega, harmonics,
                                        samples_per_period, options)
        except SingularJacobian:
            return None
    if not (result.converged or result.residual_norm <= STALLED_RESIDUAL):
        return None     # (stalled at a kink of the sampled forces close by: kept)
    return U_new if np.all(np.isfinite(U_new)) else None


def engine_solve(model, contacts, excitation, U, omega, harmonics, samples_per_period, options):
    """ũ of :func:`sarfe.hbm.solve_frequency` from U (at most REFINE_ITERATIONS), None if it fails."""
    quick = replace(options or SolverOptions(), max_iterations=REFINE_ITERATIONS, stability=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            s = solve_frequency(model, contacts, excitation, omega, harmonics, samples_per_period,
                                initial=U, options=quick)
        except (ValueError, np.linalg.LinAlgError):
            return None
    U_new = np.asarray(s.displacement, dtype=float)
    return U_new if s.converged and np.all(np.isfinite(U_new)) else None


def newton_correction(model, contacts, excitation, solution, harmonics, samples_per_period,
                      options=None, robust=False):
    """(1) climbing: the solution of the (H', N') problem from ũ embedded in it, H raised to H' in
    steps of ×1.5 (N ≥ 4H + 1, retried with N/H kept when a step stalls), each a
    :func:`newton_step` warm-started from the last → (2H''+1, n) [m], H'' ≤ H'. The fallback when
    one solve at H' does not converge (an impact whose active set a large raise changes a lot);
    the climb stops at the last converged H''. None when no raise converges. excitation f̃_e
    (2H_e+1, n) [N] (resized). ``robust``: each raise by the engine's own solve (full line search,
    REFINE_ITERATIONS, the full-DOF fallback: :func:`engine_solve`) instead of
    :func:`newton_step` — slower, the last resort."""
    H0, H_target = int(solution.harmonics), int(harmonics)
    N = int(samples_per_period)
    omega = float(solution.omega)
    steps = [H_target] if H_target <= H0 else []
    H = H0
    while H < H_target:
        H = min(H_target, max(H + 2, int(round(1.5 * H))))
        steps.append(H)
    best = None
    previous = np.asarray(solution.displacement, dtype=float)
    solve = engine_solve if robust else newton_step
    for H in steps:     # N ≥ 4H + 1; a stalled raise is tried once more with N/H kept
        first = N if H_target <= H0 else samples_for(H, N)
        scaled = N if H_target <= H0 else doubled_to(N, max(4 * H + 1, N * H / max(H0, 1)))
        refined = None
        for N_try in (first, scaled) if scaled != first else (first,):
            refined = solve(model, contacts, resize_harmonics(excitation, H),
                            resize_harmonics(previous, H), omega, H, N_try, options)
            if refined is not None:
                break
        if refined is None:
            break
        best = previous = refined
    return best


__all__ = ["REFINE_ITERATIONS", "ESTIMATE_ITERATIONS", "ESTIMATE_TOLERANCE", "STALLED_RESIDUAL",
           "samples_for", "doubled_to", "newton_step", "engine_solve", "newton_correction"]
