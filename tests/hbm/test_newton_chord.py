"""Chord steps of the fixed-frequency Newton (the last LU reused while ‖R‖ contracts) reach the
same root as plain Newton within the tolerance, with fewer Jacobian builds; one factorization
serves several right-hand sides."""
from dataclasses import dataclass

import numpy as np

from sarfe.hbm.newton import factorize, newton
from sarfe.hbm.solution import SolverOptions


@dataclass(frozen=True)
class _Evaluation:
    residual: np.ndarray
    jacobian: object
    reference: float
    unit_columns: np.ndarray = None


def _penalty_problem(n=40, seed=3):
    """R(x) = A x + k·max(x − g, 0)³ − f: a stiff one-sided cubic contact on every unknown
    (smooth enough for quadratic Newton convergence), root by construction unknown."""
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(n, n)) / np.sqrt(n)
    A = np.eye(n) * 2.0 + B @ B.T
    f = rng.normal(size=n) * 3.0
    g, k = 0.2, 50.0
    calls = {"jacobian": 0}

    def evaluate(x, jacobian):
        open_ = np.maximum(x - g, 0.0)
        R = A @ x + k * open_**3 - f
        J = None
        if jacobian:
            calls["jacobian"] += 1
            J = A + np.diag(3 * k * open_**2)
        return _Evaluation(R, J, float(np.linalg.norm(f)))
    return evaluate, calls, n


def test_chord_reaches_the_newton_root_with_fewer_jacobians():
    options = SolverOptions(tolerance=1e-12)
    evaluate, calls, n = _penalty_problem()
    plain = newton(evaluate, np.zeros(n), options)
    plain_jacobians = calls["jacobian"]
    calls["jacobian"] = 0
    chord = newton(evaluate, np.zeros(n), options, chord=True)
    assert plain.converged and chord.converged
    assert np.linalg.norm(chord.evaluation.residual) <= 1e-12 * np.linalg.norm(
        evaluate(np.zeros(n), False).reference)
    assert np.abs(chord.x - plain.x).max() <= 1e-10 * np.abs(plain.x).max()
    assert calls["jacobian"] < plain_jacobians


def test_one_factorization_serves_several_right_hand_sides():
    rng = np.random.default_rng(0)
    J = np.eye(30) + rng.normal(size=(30, 30)) / 30
    J[:, [2, 7, 8]] = 0.0
    J[[2, 7, 8], [2, 7, 8]] = [1.0, 2.0, 0.5]
    solve = factorize(J, np.array([2, 7, 8]))
    for seed in range(3):
        b = np.random.default_rng(seed + 10).normal(size=30)
        assert np.abs(solve(b) - np.linalg.solve(J, b)).max() <= 1e-12 * np.abs(
            np.linalg.solve(J, b)).max()
