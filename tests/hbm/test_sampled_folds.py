"""sarfe.hbm.sampled_folds.step_over: past a turn of ω the branch goes on (a zig-zag of the sampled
branch, stepped over) or it does not (a genuine fold: None).

Closed-form branches in scaled unknowns z = (x, ω): a fold ω = 1 − (x − 1)² has no solution past
ω = 1; a zig-zag x ↦ ω = x + ε sin(x / δ) (ε > δ: its slope changes sign, folds every ~πδ) has one
solution for each ω past its turns, ahead along the travel."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from sarfe.hbm.sampled_folds import STEP_OVER, step_over


def _solver(branch_x):
    """solve_at(ω) for a branch x(ω) (None: no solution) → (point, z)."""
    def solve_at(omega):
        x = branch_x(omega)
        point = SimpleNamespace(converged=x is not None, omega=omega)
        return point, np.array([np.nan if x is None else x, omega])
    return solve_at


def test_a_genuine_fold_is_not_stepped_over():
    z = np.array([1.0, 1.0])                       # the fold's tip
    travel = np.array([0.1, 0.19])                  # from x = 0.9 on the lower sheet
    fold = _solver(lambda w: None if w > 1.0 else 1.0 - np.sqrt(1.0 - w))
    assert step_over(fold, z, travel, 1.0, 1.0) is None


def test_a_zigzag_of_the_sampled_branch_is_stepped_over():
    eps, delta = 2e-4, 1e-4
    xs = np.linspace(0.0, 1.0, 200001)
    ws = xs + eps * np.sin(xs / delta)
    turn = np.flatnonzero(np.diff(np.sign(np.diff(ws))) < 0)[100]   # a turn of ω (max)
    z = np.array([xs[turn], ws[turn]])

    def onward(w):                                  # the solution of the mean branch past the turn
        k = np.flatnonzero((ws[:-1] - w) * (ws[1:] - w) <= 0)
        k = k[xs[k] > z[0]]
        return xs[k[0]] if k.size else None

    over = step_over(_solver(onward), z, np.array([0.05, 0.05]), 1.0, 1.0)
    assert over is not None
    point, z_new, share = over
    assert share in STEP_OVER and point.omega > z[1] and z_new[0] > z[0]
