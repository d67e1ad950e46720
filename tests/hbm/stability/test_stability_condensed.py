"""The condensed stability method (Hill on a bounded Ritz basis, sarfe.hbm.stability.condensed)
against the full Hill method: same verdicts on NLvib example 03 over a sweep through both folds,
on the squeak rig (friction memory) and on the shipped cases."""
import numpy as np
import pytest

from sarfe.hbm import ContinuationOptions, SolverOptions, continuation, solve_frequency
from sarfe.hbm.stability.condensed import condensed_stability, ritz_basis
from tests.hbm.shipped_points import full_hill, shipped_case_points


def both(model, contacts, F, s):
    full, ev, op = full_hill(model, contacts, F, s)
    cond = condensed_stability(model, contacts, s.omega, s.harmonics, ev.forces, op)
    return full, cond


def test_example03_sweep_verdicts_equal():
    """Every point of the NLvib 03 sweep (H = 11, N = 512; lower branch, the 1:3 region, the
    peak, the middle branch, past the second fold): condensed verdict = full verdict."""
    from tests.hbm.test_solver import example03
    model, contacts, F = example03()
    H, N = 11, 512
    sols = continuation(model, contacts, F[:2 * H + 1], 0.5, 0.8, H, N,
                        options=ContinuationOptions(max_step=0.3,
                                                    solver=SolverOptions(stability=False)))
    verdicts = []
    for s in sols[::3]:
        full, cond = both(model, contacts, F[:2 * H + 1], s)
        assert cond.stable is full.stable
        assert cond.leading == pytest.approx(full.leading, abs=1e-6)
        verdicts.append(full.stable)
    assert True in verdicts and False in verdicts


def test_ritz_basis_is_identity_for_small_models_and_bounded_for_big():
    from tests.hbm.test_solver import chain
    model = chain(60)
    import scipy.sparse as sp
    G = sp.csr_matrix(([1.0], ([0], [30])), shape=(1, 60))
    basis = ritz_basis(model, G, np.array([[0.0]]), 0.01, 3)
    assert basis.shape == (60, 11)           # 10 modes (min) + 1 static response
    np.testing.assert_allclose(basis.T @ basis, np.eye(11), atol=1e-10)
    assert ritz_basis(chain(8), sp.csr_matrix(np.eye(8)[:1]), np.zeros((1, 1)), 1.0, 3).shape == (8, 8)


def test_squeak_rig_condensed_equals_full(squeak_rig):
    """28 reduced DOFs → 10 + modes + 3 static responses: the leading exponent within 1e-4."""
    nl, sols = squeak_rig
    for s in sols:
        full, cond = both(nl.model, nl.contacts, nl.excitation, s)
        assert cond.stable is full.stable is True
        assert cond.leading == pytest.approx(full.leading, rel=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lumped_rattle", "rattle_rig", "rattle_rig_deck", "squeak_rig",
                                  "door_trim", "instrument_panel"])
def test_shipped_cases_condensed_equals_full(name):
    """Shipped cases at their own settings (H ≤ 5): every solved point, both methods."""
    nl, H, points = shipped_case_points(name)
    for f, s in points:
        full, cond = both(nl.model, nl.contacts, nl.excitation[:2 * H + 1], s)
        assert cond.stable is full.stable, (f, full, cond)
