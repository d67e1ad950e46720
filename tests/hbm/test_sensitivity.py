"""Adjoint sensitivities of the A-weighted ERP level (sarfe.hbm.sensitivity,
sarfe.erp.level_sensitivity) against central finite differences of full re-solves.

The lumped panel (tests/hbm/lumped_panel.py) at 46 Hz under twice the nominal base acceleration:
the panel rattles on the bracket (closed 6.6 % of the period) and the seal slips (18 %). dL_A/dp of
the rattle's gap and k_n and of the seal's μ, N0 and k_t from one adjoint solve, against
(L_A(p + h) − L_A(p − h)) / 2h of two Newton re-solves (warm started, tolerance 1e-12) at two
relative steps h/p = 1e-4 and 1e-5: both in the linear range of the difference (they agree with
each other), the adjoint within 2 % of each. Measured: |adjoint/FD − 1| ≤ 1e-6 for every
parameter and both steps (the adjoint differentiates the same sampled AFT the re-solves solve; a
step of 1e-3 crosses a stick/slip sample of the seal and is 0.9 % off for μ and N0).
"""
import numpy as np
import pytest

import lumped_panel as panel
from sarfe.erp.level_sensitivity import a_weighted_level, level_sensitivities
from sarfe.hbm.onset import excitation_onset
from sarfe.hbm.solution import SolverOptions
from sarfe.hbm.solve import solve_frequency

H, N = 7, 256
OMEGA = 2 * np.pi * 46.0
LEVEL = 3.0
TIGHT = SolverOptions(stability=False, tolerance=1e-12, full_tolerance=1e-10)
CONTACT = {"gap": panel.RATTLE, "normal_stiffness": panel.RATTLE,
           "friction_coefficient": panel.SEAL, "normal_load": panel.SEAL,
           "tangential_stiffness": panel.SEAL}


@pytest.fixture(scope="module")
def point():
    model, contacts = panel.model(), panel.contacts()
    F = panel.excitation(H, LEVEL)
    solution = solve_frequency(model, contacts, F, OMEGA, H, N, options=TIGHT)
    assert solution.converged
    level, sensitivities = level_sensitivities(model, contacts, F, solution, panel.ERP_MAP,
                                               panel.ERP_AREAS)
    return model, contacts, F, solution, level, sensitivities


def level_at(point, name, value):
    model, _, F, solution, _, _ = point
    changed = solve_frequency(model, panel.contacts(**{name: value}), F, OMEGA, H, N,
                              initial=solution, options=TIGHT)
    assert changed.converged
    return a_weighted_level(changed.displacement, OMEGA, panel.ERP_MAP, panel.ERP_AREAS)[0]


def test_the_point_has_both_contacts_active(point):
    model, contacts, F, solution, _, sensitivities = point
    state = solution.contact_state
    assert np.mean(state[:, panel.RATTLE] == 1) > 0.03       # closed
    assert np.mean(state[:, panel.SEAL] == 2) > 0.1          # slip
    assert np.all(excitation_onset(model, contacts, F, OMEGA).factor < 1)
    assert sensitivities.method == "condensed"


@pytest.mark.parametrize("name", list(CONTACT))
def test_adjoint_equals_central_differences_of_resolves(point, name):
    _, _, _, _, _, sensitivities = point
    adjoint = sensitivities.derivative[name][CONTACT[name]]
    nominal = panel.NOMINAL[name]
    differences = []
    for relative in (1e-4, 1e-5):
        h = relative * nominal
        differences.append((level_at(point, name, nominal + h)
                            - level_at(point, name, nominal - h)) / (2 * h))
    assert differences[0] == pytest.approx(differences[1], rel=1e-3)       # linear range
    for fd in differences:
        assert adjoint == pytest.approx(fd, rel=2e-2)
    assert abs(adjoint * nominal) > 1e-3        # a real effect: > 1e-3 dB per relative change
    assert np.isnan(sensitivities.derivative[name][1 - CONTACT[name]])    # the other law: n/a


def test_condensed_and_full_adjoints_agree(point):
    model, contacts, F, solution, _, condensed = point
    _, full = level_sensitivities(model, contacts, F, solution, panel.ERP_MAP, panel.ERP_AREAS,
                                  condensed=False)
    assert full.method == "full"
    for name, values in condensed.derivative.items():
        np.testing.assert_allclose(values, full.derivative[name], rtol=1e-8)
    np.testing.assert_allclose(condensed.force_adjoint, full.force_adjoint, rtol=1e-8,
                               atol=1e-10 * np.abs(full.force_adjoint).max())


def test_only_the_slip_limit_matters_for_a_seal_without_normal_dof(point):
    """The seal's force depends on μ and N0 only through μ N0: μ ∂L/∂μ = N0 ∂L/∂N0."""
    _, contacts, _, _, _, sensitivities = point
    relative = sensitivities.per_relative_change(contacts)
    assert relative["friction_coefficient"][panel.SEAL] == pytest.approx(
        relative["normal_load"][panel.SEAL], rel=1e-5)


def test_force_derivatives_of_the_penalty_law_are_the_closed_form():
    """λ_n = k_n max(0, w − g): ∂λ̃/∂g = −E(k_n 1_closed), ∂λ̃/∂k_n = E max(0, w − g) (the sampled
    law's Fourier coefficients), against the difference derivatives of the AFT force."""
    from sarfe.hbm.harmonics import harmonic_coefficients, time_samples
    from sarfe.hbm.sensitivity import force_parameter_derivatives

    contacts = panel.contacts()
    R = np.zeros((2 * H + 1, contacts.row_count))
    R[1, 0], R[2, 0], R[3, 0] = 2e-4, -1e-4, 3e-5                       # closes part of the period
    w = time_samples(R, N)[:, 0]
    closed = w > panel.NOMINAL["gap"]
    derivatives = force_parameter_derivatives(contacts, R, N, OMEGA, ("gap", "normal_stiffness"))
    dgap, uses, _ = derivatives["gap"]
    assert uses.tolist() == [True, False]
    np.testing.assert_allclose(dgap[:, 0], harmonic_coefficients(-1e6 * closed, H),
                               atol=1e-6 * 1e6)
    dk = derivatives["normal_stiffness"][0]
    np.testing.assert_allclose(dk[:, 0], harmonic_coefficients(
        np.maximum(w - panel.NOMINAL["gap"], 0.0), H), atol=1e-9 * 1e-4)
    assert np.all(dgap[:, 1] == 0.0)


def test_a_harmonic_set_solution():
    """A point solved on the orders {0, 1, 2, 3, 5} only: the adjoint works on the kept rows as
    Newton did (condensed = full) and equals the difference of re-solves on the same set."""
    model, contacts, F = panel.model(), panel.contacts(), panel.excitation(H, LEVEL)
    options = SolverOptions(stability=False, tolerance=1e-12, full_tolerance=1e-3,
                            harmonic_set=[0, 1, 2, 3, 5])
    solution = solve_frequency(model, contacts, F, OMEGA, H, N, options=options)
    assert solution.converged and solution.harmonic_orders == (0, 1, 2, 3, 5)
    derivative = {}
    for condensed in (True, False):
        derivative[condensed] = level_sensitivities(
            model, contacts, F, solution, panel.ERP_MAP, panel.ERP_AREAS, names=("gap",),
            condensed=condensed)[1].derivative["gap"][panel.RATTLE]
    assert derivative[True] == pytest.approx(derivative[False], rel=1e-9)
    h = 1e-5 * panel.NOMINAL["gap"]
    levels = [a_weighted_level(solve_frequency(
        model, panel.contacts(gap=panel.NOMINAL["gap"] + step), F, OMEGA, H, N, initial=solution,
        options=options).displacement, OMEGA, panel.ERP_MAP, panel.ERP_AREAS)[0]
        for step in (h, -h)]
    assert derivative[True] == pytest.approx((levels[0] - levels[1]) / (2 * h), rel=2e-2)
