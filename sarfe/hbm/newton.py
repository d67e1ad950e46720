r"""Damped Newton–Raphson with backtracking line search, for R(x) = 0 with an analytic Jacobian.

    J(x_i) Δ = −R(x_i),    x_{i+1} = x_i + α Δ,   α ∈ {1, ½, ¼, …}

α is the first value with ‖R(x + αΔ)‖ < (1 − 10⁻⁴ α) ‖R(x)‖ (Armijo), else the value with the
smallest residual among those tried (nonsmooth contact laws can need a non-monotone step).
Convergence is relative: ‖R‖ ≤ tolerance · reference (the reference, e.g. ‖f̃_e‖, is given by the
evaluation), or a scaled step ‖αΔ‖ / max(‖x‖, x_scale) ≤ step_tolerance while ‖R‖ ≤ √tolerance ·
reference. A result that did not converge says why in ``reason``; it is never marked converged.

With ``chord=True`` the LU of the last Jacobian is reused for further steps while each divides
‖R‖ by at least 4 (:data:`CHORD_CONTRACTION`), and rebuilt at the current iterate otherwise
(:func:`newton`); the convergence test is the same.
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

    ``unit_columns``: see :func:`factorize`."""
    return factorize(matrix, unit_columns)(rhs)


def factorize(matrix, unit_columns=None):
    """The LU factorization of J as a function b ↦ J⁻¹ b (dense ndarray or scipy sparse J);
    raises SingularJacobian (here or in the solve: non-finite result). One factorization serves
    several right-hand sides (the chord steps of :func:`newton`).

    ``unit_columns``: indices i whose columns of a dense J are d_i e_i apart from rows outside i
    (a condensed contact row that carries no contact stiffness: ∂R_c/∂r̃_i = e_i, ×x_s in a
    bordered system whose extra row may fill them). They are eliminated first (Schur complement
    on the diagonal block d):

        (J_oo − J_oi d⁻¹ J_io) Δ_o = b_o − J_oi d⁻¹ b_i,     Δ_i = d⁻¹ (b_i − J_io Δ_o),

    so one LU of the |o| rows (the loaded contact rows and the border) replaces the full one."""
    with _singular_as_error():
        if sp.issparse(matrix):
            lu = spla.splu(sp.csc_matrix(matrix))
            diag = np.abs(lu.U.diagonal())
            if diag.min() <= 1e-14 * diag.max():
                raise SingularJacobian
            solve = lu.solve
        elif unit_columns is not None and len(unit_columns) >= UNIT_SHARE * matrix.shape[0]:
            solve = _eliminating(matrix, np.asarray(unit_columns, dtype=int))
        else:
            solve = _dense_lu(matrix)

    def apply(rhs):
        with _singular_as_error():
            x = solve(rhs)
        if not np.all(np.isfinite(x)):
            raise SingularJacobian
        return x
    return apply


class _singular_as_error:
    """Context: LU failures and numerical warnings (ill-conditioned J) raise SingularJacobian."""

    def __enter__(self):
        import warnings

        self._warnings = warnings.catch_warnings()
        self._warnings.__enter__()
        warnings.simplefilter("error")
        return self

    def __exit__(self, kind, error, trace):
        self._warnings.__exit__(kind, error, trace)
        if kind is not None and issubclass(kind, (RuntimeError, ValueError,
                                                  np.linalg.LinAlgError, Warning)):
            raise SingularJacobian from error
        return False


def _dense_lu(matrix, scale=0.0):
    """LU with the singularity test min|U_jj| ≤ 10⁻¹⁴ max(max|U_jj|, scale) → b ↦ J⁻¹ b."""
    lu, piv = sla.lu_factor(matrix, check_finite=False)
    diag = np.abs(np.diag(lu))
    if not np.all(np.isfinite(diag)) or diag.min() <= 1e-14 * max(diag.max(), scale):
        raise SingularJacobian
    return lambda rhs: sla.lu_solve((lu, piv), rhs, check_finite=False)


def _eliminating(A, unit):
    """:func:`factorize` with the ``unit`` columns eliminated (see there) → b ↦ A⁻¹ b."""
    n = A.shape[0]
    mask = np.zeros(n, dtype=bool)
    mask[unit] = True
    other = np.flatnonzero(~mask)
    # the four blocks by two row takes and four column takes (half the time of np.ix_ copies
    # of a 621-row bordered J: 0.5 instead of 1.0 ms)
    rows_i, rows_o = A.take(unit, axis=0), A.take(other, axis=0)
    A_ii, A_io = rows_i.take(unit, axis=1), rows_i.take(other, axis=1)
    A_oi, S = rows_o.take(unit, axis=1), rows_o.take(other, axis=1)
    d = np.diagonal(A_ii).copy()
    # off-diagonal entries of A_ii: more nonzeros than on its diagonal
    if np.count_nonzero(A_ii) > np.count_nonzero(d) or np.any(np.abs(d) <= 1e-14 * np.abs(d).max(
            initial=0.0)) or not np.all(np.isfinite(d)):
        return _dense_lu(A)             # not the structure claimed: the plain LU
    filled = np.flatnonzero(A_oi.any(axis=1))          # (the border row; none at fixed ω)
    coupling = None
    if filled.size:
        coupling = A_oi[filled] / d
        S[filled] -= coupling @ A_io
    solve_o = _dense_lu(S, np.abs(d).max()) if other.size else None

    def solve(b):
        b = np.asarray(b)
        b_i, b_o = b[unit], b[other]
        if coupling is not None:
            b_o[filled] -= coupling @ b_i
        y_o = solve_o(b_o) if solve_o is not None else np.zeros((0,) + b.shape[1:])
        x = np.empty(b.shape, dtype=np.result_type(A, b))
        x[other] = y_o
        x[unit] = ((b_i - A_io @ y_o).T / d).T
        return x
    return solve


CHORD_CONTRACTION = 0.25
"""A chord step (the last factorized Jacobian reused) is taken when it reduces ‖R‖ at least by this
factor; otherwise the Jacobian is rebuilt at the current iterate and a Newton step follows."""


def newton(evaluate, x0, options, x_scale=0.0, accept=None, chord=False) -> NewtonResult:
    """Newton iterations on ``evaluate(x, jacobian: bool) -> Evaluation``.

    options: SolverOptions (tolerance, step_tolerance, max_iterations, line_search_steps).
    x_scale: typical magnitude of x for the step criterion. accept(evaluation): called on every
    accepted iterate (used to warm-start the friction slider state); returns True when the
    evaluation must be redone.
    chord: reuse the last LU factorization of J while it contracts (module docstring of
    :data:`CHORD_CONTRACTION`): Δ = −J(x_k)⁻¹ R(x_i), i > k, accepted when ‖R(x_i + Δ)‖ ≤
    CHORD_CONTRACTION ‖R(x_i)‖, else J(x_i) is built and a damped Newton step taken. Each chord
    step costs one residual without Jacobian and one pair of triangular solves instead of an AFT
    Jacobian, its assembly and an LU; the convergence test is the same, so the converged x
    satisfies the same tolerance. ``iterations`` counts chord and Newton steps alike;
    ``options.max_iterations`` caps the Newton steps only (each accepted chord step divides ‖R‖
    by 4 or more, so there are at most log₄(‖R₀‖/tolerance) of them).
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
    solve = None            # the factorized Jacobian J(x_k) (of an earlier iterate in chord steps)
    iteration, newton_steps = 0, 0
    while newton_steps < options.max_iterations:
        iteration += 1
        if norm <= tol:
            return NewtonResult(x, ev, True, "converged", iteration - 1, norm)
        if chord and solve is not None and ev.jacobian is None:
            with np.errstate(all="ignore"):
                try:
                    step = solve(-ev.residual)
                    trial = evaluate(x + step, False)
                    trial_norm = np.linalg.norm(trial.residual) / trial.reference
                except SingularJacobian:
                    trial_norm = np.inf
            if np.isfinite(trial_norm) and trial_norm <= CHORD_CONTRACTION * norm:
                x, ev, norm = x + step, trial, trial_norm
                if accept is not None and accept(ev):
                    ev = evaluate(x, False)
                    norm = np.linalg.norm(ev.residual) / ev.reference
                scaled_step = np.linalg.norm(step) / max(np.linalg.norm(x), x_scale, 1e-300)
                if norm <= tol or (scaled_step <= options.step_tolerance and norm <= np.sqrt(tol)):
                    return NewtonResult(x, ev, True, "converged", iteration, norm)
                continue
            ev = evaluate(x, True)           # the chord stalled: J at the current iterate
            norm = np.linalg.norm(ev.residual) / ev.reference
        newton_steps += 1
        try:
            solve = factorize(ev.jacobian, ev.unit_columns)
            step = solve(-ev.residual)
        except SingularJacobian:
            return NewtonResult(x, ev, False, f"singular Jacobian, residual {norm:.3g}",
                                iteration - 1, norm)
        best = None
        alpha = 1.0
        for attempt in range(options.line_search_steps + 1):
            trial_x = x + alpha * step
            with np.errstate(all="ignore"):     # the full step usually wins (J there is next)
                trial = evaluate(trial_x, attempt == 0 and not chord)
            trial_norm = np.linalg.norm(trial.residual) / trial.reference
            if np.isfinite(trial_norm) and (best is None or trial_norm < best[2]):
                best = (alpha, trial_x, trial_norm, trial)
            if np.isfinite(trial_norm) and trial_norm < (1 - 1e-4 * alpha) * norm:
                break
            alpha *= 0.5
        if best is None:
            return NewtonResult(x, ev, False, "non-finite residual", iteration, np.inf)
        alpha, x, _, ev = best
        if ev.jacobian is None and not (chord and alpha == 1.0):
            ev = evaluate(x, True)       # (a damped step: the next step is Newton's again)
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
                        iteration, norm)
