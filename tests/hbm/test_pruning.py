"""Model only what the scene requires: contact screening/pruning."""
import warnings

import numpy as np
import pytest

from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.pruning import (CLOSED, NONLINEAR, OPEN, check_pruning,
                               prune_contacts, screen_contacts, solve_frequency_pruned,
                               subset_contacts)
from sarfe.tradeoff.lumped import lumped_problem

OPTIONS = SolverOptions(stability=False)


def scene():
    """3 masses: DOF 0 rattles (1 mm gap), DOF 1 has a 1 m gap (never closes), DOF 2 is preloaded
    by 1 kN into its contact (never opens); a friction contact on DOF 1."""
    return lumped_problem(3, rattle_dofs=(0, 1, 2), gap=[1e-3, 1.0, -1e-2], zeta=0.05, force=10.0,
                          squeak_dofs=(1,), harmonics=5)


def sweep(p):
    w = p.natural_frequencies_rad_s
    return np.concatenate([np.linspace(0.5 * w[0], 1.5 * w[-1], 60), w])


def test_screen_decisions():
    p = scene()
    d = screen_contacts(p.model, p.contacts, p.excitation, sweep(p))
    assert [x.decision for x in d] == [NONLINEAR, OPEN, CLOSED, NONLINEAR]
    assert all(x.reason for x in d)
    assert d[1].clearance > 0.9 and d[2].clearance >= 0.5


def test_subset_contacts_keeps_laws():
    p = scene()
    sub = subset_contacts(p.contacts, [0, 3])
    assert sub.count == 2 and sub.row_count == 2
    assert list(sub.kind) == ["rattle", "squeak"] and sub.names == ("rattle_0", "squeak_1")
    assert sub.tangent_rows[1, 0] == 1 and sub.normal_row[1] == -1


@pytest.mark.timeout(300)
@pytest.mark.parametrize("omega", [70.0, 150.0, 260.0])
def test_pruned_solution_is_identical(omega):
    p = scene()
    d = screen_contacts(p.model, p.contacts, p.excitation, sweep(p))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        full = solve_frequency(p.model, p.contacts, p.excitation, omega, 5, 128, options=OPTIONS)
        pruned, report = solve_frequency_pruned(p.model, p.contacts, p.excitation, omega, 5, 128,
                                                d, options=OPTIONS)
    assert full.converged and pruned.converged
    assert report["dropped"] == ["rattle_1", "rattle_2"] and not report["fallback"]
    scale = np.abs(full.displacement).max()
    np.testing.assert_allclose(pruned.displacement, full.displacement, atol=1e-8 * scale)
    np.testing.assert_allclose(pruned.contact_force, full.contact_force,
                               atol=1e-8 * np.abs(full.contact_force).max())
    assert pruned.residual_norm < 1e-6


def test_violated_decision_falls_back():
    """A decision taken on a weak excitation does not hold at a strong one: the check catches it."""
    p = lumped_problem(1, rattle_dofs=(0,), gap=1e-3, force=0.1, harmonics=3)
    d = screen_contacts(p.model, p.contacts, p.excitation, [90.0])
    assert d[0].decision == OPEN
    strong = lumped_problem(1, rattle_dofs=(0,), gap=1e-3, force=10.0, harmonics=3)
    pruned = prune_contacts(strong.model, strong.contacts, strong.excitation, d)
    assert pruned.contacts.count == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s, report = solve_frequency_pruned(strong.model, strong.contacts, strong.excitation, 90.0,
                                           3, 64, d, options=OPTIONS)
    assert report["violations"] and report["fallback"]
    assert s.converged and np.abs(s.contact_force_time).max() > 0
    assert check_pruning(strong.contacts, d, s.displacement)  # still violated: it does close


def test_linear_responses_equal_linearized_guess():
    """The screening pass (harmonic by harmonic, complex) solves the same system as the engine's
    linearized start guess (one real system of all harmonics)."""
    from sarfe.hbm.solve import linearized_guess, make_problem
    from sarfe.hbm.pruning import linear_responses

    p = scene()
    omegas = [60.0, 150.0, 300.0]
    problem = make_problem(p.model, p.contacts, p.excitation, 5, 64)
    for omega, U in zip(omegas, linear_responses(p.model, p.contacts, p.excitation, omegas)):
        reference = linearized_guess(problem, omega)
        np.testing.assert_allclose(U, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


def test_contact_report_groups_node_pairs():
    """Per named contact: nonlinear if any node pair is kept, else open / closed; pair counts."""
    from sarfe.pipeline.solve.pruned_points import contact_report
    from sarfe.hbm.pruning import ContactDecision

    d = [ContactDecision(0, "a[0]", "rattle", OPEN, 0.9, "far"),
         ContactDecision(1, "a[1]", "rattle", NONLINEAR, 0.2, "near"),
         ContactDecision(2, "b[0]", "rattle", OPEN, 0.8, "far"),
         ContactDecision(3, "b[1]", "rattle", OPEN, 0.6, "less far"),
         ContactDecision(4, "c", "rattle", CLOSED, 0.7, "preloaded")]
    groups = [("a", "rattle", np.array([0, 1])), ("b", "rattle", np.array([2, 3])),
              ("c", "rattle", np.array([4]))]
    report = contact_report(d, groups)
    assert [r["decision"] for r in report] == [NONLINEAR, OPEN, CLOSED]
    assert report[0]["pairs"] == {OPEN: 1, CLOSED: 0, NONLINEAR: 1}
    assert report[1]["clearance"] == 0.6 and report[1]["reason"] == "b[1]: less far"
    assert report[2]["reason"] == "preloaded"
