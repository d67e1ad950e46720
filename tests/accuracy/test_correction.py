"""The Newton re-solve every estimate is made of (sarfe.accuracy.correction on the engine's
:func:`sarfe.hbm.solve.newton_from`): from a converged solution embedded in a richer H it reaches
the same periodic solution the engine's own solve finds there from a cold start (homotopy), and a
solution that already solves its problem is left where it is."""
import warnings

import numpy as np
import pytest

from sarfe.accuracy.correction import newton_correction, newton_step, samples_for
from sarfe.accuracy.measures import resize_harmonics
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.solve import newton_from
from sarfe.tradeoff.lumped import lumped_problem

OPTIONS = SolverOptions(stability=False, tolerance=1e-10)
OMEGA = 90.0        # rad/s: the 2-mass chain rattles (penalty 10 k)


def _problem():
    return lumped_problem(2, rattle_dofs=(0,), gap=1e-3, penalty_ratio=10.0, harmonics=12)


def _solve(p, H, N, initial=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_frequency(p.model, p.contacts, resize_harmonics(p.excitation, H), OMEGA, H, N,
                               initial=initial, options=OPTIONS)


def test_a_solution_is_a_fixed_point_of_newton_from():
    p = _problem()
    s = _solve(p, 5, 128)
    assert s.converged and np.abs(s.contact_force_time).max() > 0     # it rattles
    U, result = newton_from(p.model, p.contacts, resize_harmonics(p.excitation, 5),
                            s.displacement, OMEGA, 5, 128, OPTIONS)
    assert result.converged and result.iterations <= 1
    assert np.max(np.abs(U - s.displacement)) <= 1e-8 * np.max(np.abs(s.displacement))


@pytest.mark.parametrize("climb", [False, True])
def test_raise_of_H_reaches_the_engines_solution(climb):
    """H = 5 → 12: the re-solve (one Newton solve, or the ×1.5 climb) equals the engine's cold
    solve at H = 12 to its tolerance."""
    p = _problem()
    s = _solve(p, 5, 128)
    H, N = 12, samples_for(12, 128)
    reference = _solve(p, H, N)
    assert reference.converged
    if climb:
        U = newton_correction(p.model, p.contacts, p.excitation, s, H, N, OPTIONS)
    else:
        U = newton_step(p.model, p.contacts, resize_harmonics(p.excitation, H),
                        resize_harmonics(s.displacement, H), OMEGA, H, N, OPTIONS, steps=40)
    assert U is not None and U.shape == reference.displacement.shape
    scale = np.max(np.abs(reference.displacement))
    assert np.max(np.abs(U - reference.displacement)) <= 1e-6 * scale
    # and the raise changed the solution by far more than that (a real correction)
    assert np.max(np.abs(resize_harmonics(s.displacement, H) - reference.displacement)) > 1e-4 * scale
