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


UNIT_SHARE = 0.05     # unit columns are eliminated when at least this share of the unknowns


def solve_linear(matrix, rhs, unit_columns=None):
    """Solve J Δ = b for a dense ndarray or a scipy sparse J; raises SingularJacobian.

    ``unit_columns``: indices i whose columns of a dense J are d_i e_i apart from rows outside i
    (a condensed contact row that carries no contact stiffness: ∂R_c/∂r̃_i = e_i, ×x_s in a
    bordered system whose extra row may fill them). They are eliminated first (Schur complement
    on the diagonal block d):

        (J_oo − J_oi d⁻¹ J_io) Δ_o = b_o − J_oi d⁻¹ b_i,     Δ_i = d⁻¹ (b_i − J_io Δ_o),

    so one LU of the |o| rows (the loaded contact rows and the border) replaces the full one."""
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
            elif unit_columns is not None and len(unit_columns) >= UNIT_SHARE * matrix.shape[0]:
                x = _solve_eliminating(matrix, rhs, np.asarray(unit_columns, dtype=int))
            else:
                x = _dense_solve(matrix, rhs)
        except (RuntimeError, ValueError, np.linalg.LinAlgError, Warning) as error:
            raise SingularJacobian from error
    if not np.all(np.isfinite(x)):
        raise SingularJacobian
    return x


def _dense_solve(matrix, rhs, scale=0.0):
    """LU solve with the singularity test min|U_jj| ≤ 10⁻¹⁴ max(max|U_jj|, scale)."""
    lu, piv = sla.lu_factor(matrix, check_finite=False)
    diag = np.abs(np.diag(lu))
    if not np.all(np.isfinite(diag)) or diag.min() <= 1e-14 * max(diag.max(), scale):
        raise SingularJacobian
    return sla.lu_solve((lu, piv), rhs, check_finite=False)


def _solve_eliminating(A, b, unit):
    """:func:`solve_linear` with the ``unit`` columns eliminated (see there)."""
    n = A.shape[0]
    mask = np.zeros(n, dtype=bool)
    mask[unit] = True
    other = np.flatnonzero(~mask)
    d = A[unit, unit]
    A_ii = A[np.ix_(unit, unit)]
    if np.any(A_ii[~np.eye(unit.size, dtype=bool)]) or np.any(np.abs(d) <= 1e-14 * np.abs(d).max(
            initial=0.0)) or not np.all(np.isfinite(d)):
        return _dense_solve(A, b)       # not the structure claimed: the plain LU
    A_io, A_oi = A[np.ix_(unit, other)], A[np.ix_(other, unit)]
    S = A[np.ix_(other, other)]
    b = np.asarray(b)
    b_i, b_o = b[unit], b[other]
    filled = np.flatnonzero(A_oi.any(axis=1))          # (the border row; none at fixed ω)
    if filled.size:
        S = S.copy()
        coupling = A_oi[filled] / d
        S[filled] -= coupling @ A_io
        b_o = b_o.copy()
        b_o[filled] -= coupling @ b_i
    y_o = _dense_solve(S, b_o, np.abs(d).max()) if other.size else np.zeros((0,) + b.shape[1:])
    x = np.empty(b.shape, dtype=np.result_type(A, b))
    x[other] = y_o
    x[unit] = ((b_i - A_io @ y_o).T / d).T
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
            step = solve_linear(ev.jacobian, -ev.residual, ev.unit_columns)
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
