r"""Damped Newton–Raphson with backtracking line search, for R(x) = 0 with an analytic Jacobian.

    J(x_i) Δ = −R(x_i),    x_{i+1} = x_i + α Δ,   α ∈ {1, ½, ¼, …}

α is the first value with ‖R(x + αΔ)‖ < (1 − 10⁻⁴ α) ‖R(x)‖ (Armijo), else the value with the
smallest residual among those tried (nonsmooth contact laws can need a non-monotone step).
Convergence is relative: ‖R‖ ≤ tolerance · reference (the reference, e.g. ‖f̃_e‖, is given by the
evaluation), or a scaled step ‖αΔ‖ / max(‖x‖, x_scale) ≤ step_tolerance while ‖R‖ ≤ √tolerance ·
reference. A result that did not converge says why in ``reason``; it is never marked converged.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla


@dataclass(frozen=True)
class NewtonResult:
    x: np.ndarray
    evaluation: object          # last accepted evaluation (residual, jacobian, forces, …)
    converged: bool
    reason: str
    iterations: int
    residual_norm: float        # ‖R‖ / reference


class SingularJacobian(Exception):
    pass


def solve_linear(matrix, rhs):
    """Solve J Δ = b for a dense ndarray or a scipy sparse J; raises SingularJacobian."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            if sp.issparse(matrix):
                lu = spla.splu(sp.csc_matrix(matrix))
                diag = np.abs(lu.U.diagonal())
                if diag.min() <= 1e-14 * diag.max():
                    raise SingularJacobian
                x = lu.solve(rhs)
            else:
                lu, piv = sla.lu_factor(matrix, check_finite=False)
                diag = np.abs(np.diag(lu))
                if not np.all(np.isfinite(diag)) or diag.min() <= 1e-14 * diag.max():
                    raise SingularJacobian
                x = sla.lu_solve((lu, piv), rhs, check_finite=False)
        except (RuntimeError, ValueError, np.linalg.LinAlgError, Warning) as error:
            raise SingularJacobian from error
    if not np.all(np.isfinite(x)):
        raise SingularJacobian
    return x


def newton(evaluate, x0, options, x_scale=0.0, accept=None) -> NewtonResult:
    """Newton iterations on ``evaluate(x, jacobian: bool) -> Evaluation``.

    options: SolverOptions (tolerance, step_tolerance, max_iterations, line_search_steps).
    x_scale: typical magnitude of x for the step criterion. accept(evaluation): called on every
    accepted iterate (used to warm-start the friction slider state); returns True when the
    evaluation must be redone.
    """
    x = np.asarray(x0, dtype=float).copy()
    try:
        ev = evaluate(x, True)
    except FloatingPointError:
        ev = None
    if ev is None or not np.all(np.isfinite(ev.residual)):
        return NewtonResult(x, ev, False, "non-finite residual at the initial guess", 0, np.inf)
    norm = np.linalg.norm(ev.residual) / ev.reference
    tol = options.tolerance
    for iteration in range(1, options.max_iterations + 1):
        if norm <= tol:
            return NewtonResult(x, ev, True, "converged", iteration - 1, norm)
        try:
            step = solve_linear(ev.jacobian, -ev.residual)
        except SingularJacobian:
            return NewtonResult(x, ev, False, f"singular Jacobian, residual {norm:.3g}",
                                iteration - 1, norm)
        best = None
        alpha = 1.0
        for attempt in range(options.line_search_steps + 1):
            trial_x = x + alpha * step
            with np.errstate(all="ignore"):
                trial = evaluate(trial_x, attempt == 0)     # the full step usually wins
            trial_norm = np.linalg.norm(trial.residual) / trial.reference
            if np.isfinite(trial_norm) and (best is None or trial_norm < best[2]):
                best = (alpha, trial_x, trial_norm, trial)
            if np.isfinite(trial_norm) and trial_norm < (1 - 1e-4 * alpha) * norm:
                break
            alpha *= 0.5
        if best is None:
            return NewtonResult(x, ev, False, "non-finite residual", iteration, np.inf)
        alpha, x, _, ev = best
        if ev.jacobian is None:
            ev = evaluate(x, True)
        if accept is not None and accept(ev):
            ev = evaluate(x, True)
        norm = np.linalg.norm(ev.residual) / ev.reference
        if not np.isfinite(norm):
            return NewtonResult(x, ev, False, "non-finite residual", iteration, np.inf)
        scaled_step = np.linalg.norm(alpha * step) / max(np.linalg.norm(x), x_scale, 1e-300)
        if norm <= tol or (scaled_step <= options.step_tolerance and norm <= np.sqrt(tol)):
            return NewtonResult(x, ev, True, "converged", iteration, norm)
    return NewtonResult(x, ev, False,
                        f"max iterations {options.max_iterations} reached, residual {norm:.3g}",
                        options.max_iterations, norm)
