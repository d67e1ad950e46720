r"""The steps of the pseudo-arclength sweep (:mod:`sarfe.hbm.continuation`) in scaled unknowns
z = (x / x_s, ω / ω_s): the bordered system and the unit tangent, the corrector on the hyperplane
t_iᵀ(z − z_p) = 0 or the sphere ‖z − z_i‖ = Δs, the step past a corner of a nonsmooth branch and
the stop at the band edge. Each is a plain function of an evaluator R(z) (no sweep state).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from sarfe.hbm.harmonic_set import expand_rows
from sarfe.hbm.newton import SingularJacobian, newton, solve_linear
from sarfe.hbm.residual import Evaluation
from sarfe.hbm.solve import solve_from

COS_BEHIND = -0.9        # a corner step's point at more than ~154° from t_i: the old piece behind

DENSE_BELOW = 500        # a sparse J of fewer rows is bordered and factorized dense (sp.bmat and
                         # SuperLU cost more than the dense LU there: 1-DOF Jenkins, 15 rows)


def bordered(jacobian, d_omega, x_scale, omega_scale, row, row_scale=1.0):
    """[[J x_s, ∂R/∂ω ω_s], [row · row_scale]] (sparse like J, dense below DENSE_BELOW rows)."""
    if sp.issparse(jacobian) and jacobian.shape[0] < DENSE_BELOW:
        jacobian = jacobian.toarray()
    if sp.issparse(jacobian):
        return sp.bmat([[jacobian * x_scale, sp.csc_matrix(d_omega[:, None] * omega_scale)],
                        [sp.csr_matrix(row[None, :-1] * row_scale),
                         sp.csr_matrix(row[None, -1:] * row_scale)]], format="csc")
    # filled in place: np.block's scaled copies took 1.6 ms at 589 rows (P1), this 0.2 ms
    n = jacobian.shape[0]
    kind = np.result_type(jacobian, d_omega, row, x_scale, omega_scale, row_scale)
    out = np.empty((n + 1, n + 1), dtype=kind)
    np.multiply(jacobian, x_scale, out=out[:n, :n])
    np.multiply(d_omega, omega_scale, out=out[:n, n])
    np.multiply(row, row_scale, out=out[n])
    return out


def tangent(evaluation, x_scale, omega_scale, previous):
    """Unit tangent of the solution curve in scaled unknowns, oriented like ``previous``."""
    A = bordered(evaluation.jacobian, evaluation.omega_derivative, x_scale, omega_scale, previous)
    rhs = np.zeros(A.shape[0])
    rhs[-1] = 1.0
    t = solve_linear(A, rhs, evaluation.unit_columns if isinstance(A, np.ndarray) else None)
    t /= np.linalg.norm(t)
    return t if t @ previous >= 0 else -t


def switch_set(tangent_z, rows_from, harmonics, width, x_scale_from, x_scale_to):
    """A tangent in scaled unknowns of a harmonic set → the same direction with all rows."""
    x = expand_rows(tangent_z[:-1] * x_scale_from, rows_from, harmonics, width).ravel()
    t = np.append(x / x_scale_to, tangent_z[-1])
    return t / np.linalg.norm(t)


def rescaled(z, factor):
    """z = (x / x_s, ω / ω_s) (a point or a direction) in the unknowns scaled by x_s · factor."""
    return np.append(z[:-1] / factor, z[-1])


def band_edge(problem, solutions, point, omega_start, options, slider):
    """The branch turned back past ω_start at ``point``: solved at exactly ω_start instead (start:
    the secant between the last reported point and ``point``) and the sweep stops there, saying so."""
    last = solutions[-1]
    fraction = (omega_start - last.omega) / (point.omega - last.omega)
    guess = last.displacement + fraction * (point.displacement - last.displacement)
    edge = solve_from(problem, omega_start, guess, options, slider)
    reason = (f"the branch turned back past the start of the band ({omega_start:.6g} rad/s): "
              "sweep stopped at the band edge")
    solutions.append(replace(edge, reason=f"{edge.reason}; sweep stopped: {reason}"))
    return solutions


def corrector(evaluate_z, z, predicted, t, step, x_scale, span, options, accept, travel=None,
               cos_min=0.0):
    """Newton on R(z) = 0 with t·(z − z_p) = 0 (hyperplane), or ‖z − z_i‖² = Δs² when t is None
    (sphere). Returns the converged NewtonResult within 3 Δs of z_i, or None. A sphere point must
    lie ahead: cos(z − z_i, d) > ``cos_min`` with d = ``travel`` (default z_p − z_i)."""
    def augmented(zz, jacobian):
        e = evaluate_z(zz, jacobian)
        if t is not None:
            extra, row = t @ (zz - predicted), t
        else:
            d = zz - z
            extra, row = (d @ d - step**2) / (2 * step), d / step
        residual = np.append(e.residual, e.reference * extra)
        J = (bordered(e.jacobian, e.omega_derivative, x_scale, span, row, e.reference)
             if jacobian else None)
        return Evaluation(residual, J, None, e.forces, e.reference,
                          e.unit_columns if isinstance(J, np.ndarray) else None)

    try:
        result = newton(augmented, predicted, options, x_scale=1.0, accept=accept)
    except SingularJacobian:
        return None
    if result.converged and np.linalg.norm(result.x - z) <= 3 * step:
        ahead = predicted - z if travel is None else travel
        if t is None and (result.x - z) @ ahead <= cos_min * np.linalg.norm(
                result.x - z) * np.linalg.norm(ahead):
            return None          # the sphere's backward intersection
        return result
    return None


def corner_step(evaluate_z, z, t, radius, x_scale, span, options, accept):
    r"""A step past a corner of the branch just ahead of z_i, where the correctors stall: the
    piece ahead leaves at an angle to t_i (the direction of travel: the secant from z_{i−1}) that
    no hyperplane t_iᵀ(z − z_p) = 0 meets near z_i, and whose sphere point the plain sphere
    corrector rejects as lying 'behind' (more than 90° from t_i).

    A sphere ‖z − z_i‖ = r meets the branch twice: on the piece behind z_i and on the piece
    ahead. The point behind is found first (Newton on the sphere from z_i − r t_i); the piece
    ahead is then sought from z_i + r t_B, z_i − r t_B and z_i + r t_i, where t_B is the tangent at
    z_i + (r/8) t_i (past the corner: the contact state of the piece ahead holds there), and the
    first converged point that is not the point behind (farther than 10⁻³ r from it; where the
    point behind was not found: cos(z − z_i, t_i) > ``COS_BEHIND``) is taken, for r = ``radius``,
    r/8, r/64. The test by position, not angle, also passes a fold at a corner, whose piece ahead
    returns almost antiparallel to t_i. Measured on cases/lumped_rattle.yaml with k_n = 10⁹ N/m,
    where the panel first touches the bracket (42.4 Hz): the piece ahead at 110° from t_i, found
    from z_i − r t_B in 5 Newton iterations for r = 10⁻³ … 0.02.
    Returns (NewtonResult, cosine of z − z_i with t_i) or None."""
    for r in (radius, radius / 8, radius / 64):
        behind = corrector(evaluate_z, z, z - r * t, None, r, x_scale, span, options, accept,
                           cos_min=-2.0)
        try:
            beyond = tangent(evaluate_z(z + r / 8 * t, True), x_scale, span, t)
        except SingularJacobian:
            beyond = t
        for start in (z + r * beyond, z - r * beyond, z + r * t):
            result = corrector(evaluate_z, z, start, None, r, x_scale, span, options, accept,
                               cos_min=-2.0)
            if result is None:
                continue
            d = result.x - z
            cosine = float(d @ t / np.linalg.norm(d))
            if (np.linalg.norm(result.x - behind.x) > 1e-3 * r if behind is not None
                    else cosine > COS_BEHIND):
                return result, cosine
    return None
