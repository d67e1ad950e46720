"""Harmonic sets: a symmetric contact has no even harmonics, so the odd set gives the full-set
solution with fewer Newton unknowns; a one-sided rattle breaks the symmetry and the estimate η
says so; the Jacobian of the projected system matches finite differences."""
import numpy as np
import pytest
import scipy.sparse as sp

import sarfe.hbm.solve as solve_module
from sarfe.hbm import (ContinuationOptions, SolverOptions, continuation, make_contact_set,
                       make_linear_model, solve_frequency)
from sarfe.hbm.harmonic_set import coefficient_rows, dropped_content, harmonic_set_orders
from sarfe.hbm.dynamic_stiffness import condense
from sarfe.hbm.residual import condensed_residual, full_residual
from sarfe.hbm.solve import make_problem

H, N = 9, 256
OMEGA = 0.6          # near the first mode (0.618 rad/s): the contacts close every period


def two_dof(contacts_kind):
    """NLvib example 03's 2-DOF chain (M = I, K = [[1, −1], [−1, 2]], D = 0.03 K, 0.1 cos Ωt on
    DOF 2) with DOF 1 against one gap ('one-sided') or between two identical gaps ('two-sided',
    odd-symmetric force λ₁ − λ₂ = f(u) = −f(−u)), gap 0.5, k_n = 100; or a 1-D Jenkins element
    under a constant normal load ('friction', odd-symmetric hysteresis), or a 2-D one in the plane
    of both DOFs ('friction-2d')."""
    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    model = make_linear_model(np.eye(2), 0.03 * K, K)
    if contacts_kind == "two-sided":
        contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0], [-1.0, 0.0]]), ["rattle"] * 2,
                                    [0, 1], [[-1, -1], [-1, -1]], 0.5, 100.0)
    elif contacts_kind == "one-sided":
        contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]],
                                    0.5, 100.0)
    elif contacts_kind == "friction-2d":
        contacts = make_contact_set(sp.csr_matrix(np.eye(2)), ["squeak"], [-1], [[0, 1]],
                                    0.0, 0.0, tangential_stiffness=5.0, friction_coefficient=0.3,
                                    normal_load=0.2)
    else:
        contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["squeak"], [-1], [[0, -1]],
                                    0.0, 0.0, tangential_stiffness=5.0, friction_coefficient=0.3,
                                    normal_load=0.2)
    F = np.zeros((2 * H + 1, 2))
    F[1, 1] = 0.1
    return model, contacts, F


def count_unknowns(monkeypatch):
    """Record the size of every Newton system solved (the unknowns x)."""
    sizes = []
    newton = solve_module.newton

    def counting(evaluate, x0, *args, **kwargs):
        sizes.append(np.size(x0))
        return newton(evaluate, x0, *args, **kwargs)

    monkeypatch.setattr(solve_module, "newton", counting)
    return sizes


def test_orders_and_rows():
    assert harmonic_set_orders(None, 5) is None and harmonic_set_orders("all", 5) is None
    assert harmonic_set_orders([0, 1, 2, 3, 4, 5], 5) is None
    np.testing.assert_array_equal(harmonic_set_orders("odd", 6), [1, 3, 5])
    np.testing.assert_array_equal(harmonic_set_orders([3, 0, 1], 5), [0, 1, 3])
    np.testing.assert_array_equal(coefficient_rows([0, 1, 3]), [0, 1, 2, 5, 6])
    np.testing.assert_array_equal(coefficient_rows([1, 3]), [1, 2, 5, 6])
    for bad in ("even", [7], [0], [1.5], []):
        with pytest.raises(ValueError, match="harmonic_set"):
            harmonic_set_orders(bad, 5)


@pytest.mark.parametrize("kind", ["two-sided", "friction", "friction-2d"])
@pytest.mark.parametrize("condensation", [True, False])
def test_symmetric_contact_odd_set_equals_full_set(kind, condensation, monkeypatch):
    """Odd-symmetric force, no mean load: the full-set solution has no even harmonics, and the odd
    set reproduces it to solver tolerance with H·n_x instead of (2H+1)·n_x Newton unknowns."""
    model, contacts, F = two_dof(kind)
    options = SolverOptions(condensation=condensation)
    sizes = count_unknowns(monkeypatch)
    full = solve_frequency(model, contacts, F, OMEGA, H, N, options=options)
    full_sizes = list(sizes)
    sizes.clear()
    odd = solve_frequency(model, contacts, F, OMEGA, H, N, options=options, harmonic_set="odd")
    assert full.converged and odd.converged
    assert np.abs(full.contact_force).max() > 1e-3             # the contact does act
    even = coefficient_rows([0, 2, 4, 6, 8])
    scale = np.abs(full.displacement).max()
    assert np.abs(full.displacement[even]).max() <= 1e-9 * scale
    np.testing.assert_allclose(odd.displacement, full.displacement, rtol=0, atol=1e-9 * scale)
    assert odd.harmonic_set == "odd" and odd.harmonic_orders == (1, 3, 5, 7, 9)
    assert odd.dropped_content < 1e-9 and full.dropped_content < 1e-9
    assert odd.stable == full.stable
    width = contacts.row_count if condensation else model.dof_count
    assert set(full_sizes) == {(2 * H + 1) * width}
    assert set(sizes) == {2 * 5 * width}                   # orders 1, 3, 5, 7, 9: cos and sin


def test_auto_keeps_the_odd_set_for_a_symmetric_contact():
    model, contacts, F = two_dof("two-sided")
    s = solve_frequency(model, contacts, F, OMEGA, H, N, harmonic_set="auto")
    assert s.converged and s.harmonic_set == "odd" and s.reason == "converged"


def test_one_sided_rattle_odd_set_is_wrong_and_the_estimate_says_so():
    """A one-sided impact pushes the mean away from the gap and has even harmonics: the odd set
    misses ≥ 5 % of the response, its η is far above the 1 % default tolerance, and 'auto'
    re-solves with all orders, giving the full-set solution."""
    model, contacts, F = two_dof("one-sided")
    full = solve_frequency(model, contacts, F, OMEGA, H, N)
    odd = solve_frequency(model, contacts, F, OMEGA, H, N, harmonic_set="odd")
    assert full.converged and odd.converged
    error = np.linalg.norm(odd.displacement - full.displacement) / np.linalg.norm(full.displacement)
    assert error > 0.05
    assert abs(full.displacement[0, 0]) > 0.05 * full.amplitude(0)   # a mean the odd set lacks
    assert odd.dropped_content > 0.1 > SolverOptions().harmonic_set_tolerance
    assert full.dropped_content > 0.1                                  # what 'odd' would drop
    auto = solve_frequency(model, contacts, F, OMEGA, H, N, harmonic_set="auto")
    assert auto.converged and auto.harmonic_set == "all" and "odd set rejected" in auto.reason
    np.testing.assert_allclose(auto.displacement, full.displacement, rtol=0,
                               atol=1e-8 * np.abs(full.displacement).max())
    # the next point, started from this one, goes to all orders directly
    again = solve_frequency(model, contacts, F, OMEGA * 1.01, H, N, initial=auto,
                            harmonic_set="auto")
    assert again.harmonic_set == "all" and "previous point needed all orders" in again.reason


def test_dropped_content_is_the_relative_force_in_the_dropped_rows():
    F_nl, F_e = np.zeros((5, 1)), np.zeros((5, 1))
    F_e[1] = 3.0
    F_nl[0], F_nl[1] = 1.0, 0.0      # a mean force of 1 N next to a drive of 3 N
    assert dropped_content(F_nl, F_e, coefficient_rows([1, 2])) == pytest.approx(1 / 4)
    assert dropped_content(F_nl, F_e, np.arange(5)) == 0.0


def finite_difference(evaluate, x, h):
    columns = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        columns.append((evaluate(x + e) - evaluate(x - e)) / (2 * h))
    return np.array(columns).T


@pytest.mark.parametrize("kind, harmonic_set", [
    ("one-sided", "odd"), ("one-sided", [0, 1, 2, 5]), ("friction", "odd"),
    ("friction", [0, 1, 2, 5]), ("friction-2d", [0, 1, 2, 5])])
def test_projected_jacobian_matches_finite_differences(kind, harmonic_set):
    """∂R_𝒦/∂x and ∂R_𝒦/∂ω of the projected full and condensed residuals vs central differences,
    at the odd-set solution perturbed by a smooth random field (no sample on a kink)."""
    model, contacts, F = two_dof(kind)
    s = solve_frequency(model, contacts, F, OMEGA, H, N, harmonic_set=harmonic_set)
    problem = make_problem(model, contacts, F, H, N, harmonic_set=harmonic_set)
    rows = coefficient_rows(problem.harmonic_orders)
    rng = np.random.default_rng(3)
    U = s.displacement + 0.01 * np.abs(s.displacement).max() * rng.standard_normal(
        s.displacement.shape) / (1 + np.arange(2 * H + 1))[:, None] ** 2
    U[np.setdiff1d(np.arange(2 * H + 1), rows)] = 0.0
    slider = np.zeros((contacts.count, 2))

    x = U[rows].ravel()
    ev = full_residual(problem, x, OMEGA, slider)
    assert ev.residual.shape == (rows.size * model.dof_count,)
    J_fd = finite_difference(lambda y: full_residual(problem, y, OMEGA, slider, False).residual,
                             x, 1e-7)
    np.testing.assert_allclose(ev.jacobian.toarray(), J_fd, rtol=0,
                               atol=1e-5 * np.abs(J_fd).max())
    dR_fd = (full_residual(problem, x, OMEGA + 1e-6, slider, False).residual
             - full_residual(problem, x, OMEGA - 1e-6, slider, False).residual) / 2e-6
    np.testing.assert_allclose(ev.omega_derivative, dR_fd, rtol=0, atol=1e-6 * np.abs(dR_fd).max())

    G = contacts.gap_map
    r = np.asarray(G @ U.T).T[rows].ravel()
    cond = condense(model, G, F, OMEGA, problem.harmonic_orders)
    ev_c = condensed_residual(problem, cond, r, slider)
    J_fd = finite_difference(lambda y: condensed_residual(problem, cond, y, slider, False).residual,
                             r, 1e-7)
    np.testing.assert_allclose(ev_c.jacobian, J_fd, rtol=0, atol=1e-5 * np.abs(J_fd).max())
    cond_p, cond_m = (condense(model, G, F, OMEGA + d, problem.harmonic_orders) for d in (1e-6, -1e-6))
    dR_fd = (condensed_residual(problem, cond_p, r, slider, False).residual
             - condensed_residual(problem, cond_m, r, slider, False).residual) / 2e-6
    np.testing.assert_allclose(ev_c.omega_derivative, dR_fd, rtol=0,
                               atol=1e-6 * np.abs(dR_fd).max())


def test_condensed_projection_drops_whole_harmonic_blocks():
    """The compliance of a harmonic set is the kept blocks of the full one (C is block diagonal)."""
    model, contacts, F = two_dof("two-sided")
    orders = np.array([0, 1, 3])
    full = condense(model, contacts.gap_map, F, OMEGA)
    part = condense(model, contacts.gap_map, F, OMEGA, orders)
    keep = (coefficient_rows(orders)[:, None] * contacts.row_count
            + np.arange(contacts.row_count)).ravel()
    np.testing.assert_allclose(part.compliance, full.compliance[np.ix_(keep, keep)], rtol=1e-12)
    rows = coefficient_rows(orders)
    np.testing.assert_allclose(part.linear_response[rows], full.linear_response[rows], rtol=1e-12)
    assert np.all(part.linear_response[np.setdiff1d(np.arange(2 * H + 1), rows)] == 0)


def test_continuation_odd_set_follows_the_full_branch_and_auto_switches():
    """Symmetric contact: the odd-set sweep (through the fold) has the full sweep's peak; one-sided
    rattle: an 'auto' sweep starts odd below the contact, switches to all orders where the contact
    acts, and then matches the full-set solution at the same frequency."""
    options = ContinuationOptions(max_step=0.3, solver=SolverOptions(stability=False))
    model, contacts, F = two_dof("two-sided")
    full = continuation(model, contacts, F, 0.5, 0.75, H, N, options=options)
    odd = continuation(model, contacts, F, 0.5, 0.75, H, N, options=options, harmonic_set="odd")
    assert all(s.converged for s in full + odd)
    peak = max(s.amplitude(0) for s in full)
    assert max(s.amplitude(0) for s in odd) == pytest.approx(peak, rel=2e-3)
    assert all(s.harmonic_set == "odd" for s in odd)

    model, contacts, F = two_dof("one-sided")
    auto = continuation(model, contacts, F, 0.5, 0.7, H, N, options=options, harmonic_set="auto")
    assert all(s.converged for s in auto) and auto[-1].omega == pytest.approx(0.7)
    used = [s.harmonic_set for s in auto]
    assert used[0] == "odd" and used[-1] == "all"
    switch = used.index("all")
    assert "odd set rejected" in auto[switch].reason
    assert all(u == "all" for u in used[switch:])
    for s in auto[switch:]:
        ref = solve_frequency(model, contacts, F, s.omega, H, N, initial=s)
        np.testing.assert_allclose(s.displacement, ref.displacement, rtol=0,
                                   atol=1e-6 * np.abs(ref.displacement).max())
