"""Harmonic-balance solver: NLvib example 03 (fold, three solutions, stability), condensation, energy
balance of friction contacts, bad input and extreme parameters."""
import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm import (ContinuationOptions, SolverOptions, continuation, make_contact_set,
                       make_linear_model, solve_frequency)
from sarfe.hbm.harmonics import derivative_matrix

H03, N03 = 21, 1024


def example03(penalty=100.0, gap=1.0, damping=0.03):
    """NLvib example 03: M = I, K = [[1, −1], [−1, 2]], D = 0.03 K, F = [0, 0.1] cos Ωt,
    unilateral spring k = 100, gap 1 on DOF 1 against ground."""
    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    model = make_linear_model(np.eye(2), damping * K, K)
    contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]], gap,
                                penalty)
    F = np.zeros((2 * H03 + 1, 2))
    F[1, 1] = 0.1
    return model, contacts, F


@pytest.fixture(scope="module")
def sweep03():
    model, contacts, F = example03()
    calls = []
    options = ContinuationOptions(max_step=0.3, solver=SolverOptions(stability=False))
    sols = continuation(model, contacts, F, 0.5, 0.8, H03, N03, options=options,
                        progress=lambda done, total: calls.append(done))
    return sols, calls


def test_example03_sweep_passes_the_fold_and_matches_peak(sweep03):
    sols, calls = sweep03
    assert all(s.converged for s in sols)
    omega = np.array([s.omega for s in sols])
    amplitude = np.array([s.amplitude(1) for s in sols])
    assert omega[0] == 0.5 and omega[-1] == pytest.approx(0.8, abs=1e-12)
    assert np.any(np.diff(omega) < 0)          # the branch turns back at the folds
    peak = amplitude.argmax()
    assert amplitude[peak] == pytest.approx(0.9374, rel=2e-3)
    assert omega[peak] == pytest.approx(0.7512, abs=2e-3)
    assert calls[-1] == 1.0 and min(calls) >= 0
    assert max(s.residual_norm for s in sols) < 1e-6


def test_example03_three_solutions_at_070_middle_unstable(sweep03):
    sols, _ = sweep03
    model, contacts, F = example03()
    omega = np.array([s.omega for s in sols])
    crossings = np.flatnonzero((omega[:-1] - 0.7) * (omega[1:] - 0.7) < 0)
    assert crossings.size == 3
    found = []
    for i in crossings:
        f = (0.7 - omega[i]) / (omega[i + 1] - omega[i])
        guess = sols[i].displacement + f * (sols[i + 1].displacement - sols[i].displacement)
        found.append(solve_frequency(model, contacts, F, 0.7, H03, N03, initial=guess))
    found.sort(key=lambda s: s.amplitude(1))
    assert all(s.converged for s in found)
    low, mid, high = (s.amplitude(1) for s in found)
    assert low < mid - 0.1 and mid < high - 0.1
    assert [s.stable for s in found[:2]] == [True, False]
    # the upper branch: stable, or (default stability) not resolved at H = 21 — the count with the
    # contact coupling at 15 harmonics finds a real exponent there (sarfe/hbm/stability/trust.py)
    assert found[2].stable is True or "not resolved in H" in found[2].stability_note
    assert found[1].floquet_exponent > 0 > found[0].floquet_exponent


def test_linear_branch_floquet_exponent_is_modal_damping():
    """Contact open: exponents are the linear eigenvalues; leading Re = −0.03 λ_min(K) / 2."""
    model, contacts, F = example03()
    s = solve_frequency(model, contacts, F, 0.5, H03, N03)
    assert s.converged and s.stable
    assert np.all(s.contact_state == 0)
    lam = (3 - np.sqrt(5)) / 2
    assert s.floquet_exponent == pytest.approx(-0.03 * lam / 2, rel=1e-8)


def test_condensed_and_full_newton_agree():
    model, contacts, F = example03()
    a = solve_frequency(model, contacts, F, 0.75, H03, 256,
                        options=SolverOptions(condensation=True, stability=False))
    b = solve_frequency(model, contacts, F, 0.75, H03, 256,
                        options=SolverOptions(condensation=False, stability=False))
    assert a.converged and b.converged
    np.testing.assert_allclose(a.displacement, b.displacement, atol=1e-9)


def chain(n_mass=6, sparse=False, damping=0.02):
    """Lumped chain grounded at both ends: k = 1, m = 1."""
    K = sp.diags([2.0 * np.ones(n_mass), -np.ones(n_mass - 1), -np.ones(n_mass - 1)], [0, 1, -1])
    M = sp.identity(n_mass)
    if not sparse:
        K, M = K.toarray(), M.toarray()
    return make_linear_model(M, damping * K, K)


def dissipated(harmonics_a, harmonics_b):
    """∮ a d b over one period from harmonics (2H+1, m): π Σ_k k (a_kc b_ks − a_ks b_kc), per column."""
    H = (harmonics_a.shape[0] - 1) // 2
    db = derivative_matrix(H) @ harmonics_b
    return np.pi * np.sum(harmonics_a[1:] * db[1:], axis=0)


@pytest.mark.parametrize("two_d", [False, True])
def test_friction_energy_balance(two_d):
    """Galerkin HB conserves energy over the kept harmonics: input work = viscous + friction, and
    the Jenkins element dissipates (∮ λ_t dq > 0)."""
    n = 4
    model = chain(n)
    G = sp.csr_matrix(np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]))
    tangent = [[1, 2]] if two_d else [[1, -1]]
    contacts = make_contact_set(G, ["squeak"], [0], tangent, -0.05, 5.0, 3.0, 0.3, 0.8)
    H, N = 7, 256
    F = np.zeros((2 * H + 1, n))
    F[1, 2], F[2, 3] = 0.3, 0.2
    s = solve_frequency(model, contacts, F, 0.8, H, N)
    assert s.converged, s.reason
    assert np.any(s.contact_state == 2) and np.any(s.contact_state == 1)
    U = s.displacement
    work_in = np.sum(dissipated(F, U))
    viscous = np.sum(dissipated(np.asarray(model.damping @ (0.8 * derivative_matrix(H) @ U).T).T, U))
    friction = np.sum(dissipated(s.contact_force, s.contact_displacement)[1:])
    normal = dissipated(s.contact_force, s.contact_displacement)[0]
    assert friction > 0
    assert work_in == pytest.approx(viscous + friction + normal, rel=1e-6)
    assert s.friction_passes >= 2


def test_stuck_friction_is_a_linear_spring():
    """Small load: the slider never slips and the response is that of K + k_t on the tangent row."""
    n = 3
    model = chain(n)
    G = sp.csr_matrix(np.array([[0, 1.0, 0]]))
    contacts = make_contact_set(G, ["squeak"], [-1], [[0, -1]], 0.0, 0.0, 2.0, 0.5, 10.0)
    H, N = 3, 256
    F = np.zeros((2 * H + 1, n))
    F[1, 0] = 0.01
    s = solve_frequency(model, contacts, F, 0.9, H, N)
    assert s.converged and np.all(s.contact_state == 1)
    K = np.asarray(model.stiffness) + 2.0 * np.outer(G.toarray(), G.toarray())
    Z = K - 0.81 * np.asarray(model.mass) + 0.9j * np.asarray(model.damping)
    z = np.linalg.solve(Z, F[1] - 1j * F[2])
    np.testing.assert_allclose(s.displacement[1], z.real, atol=1e-12)
    np.testing.assert_allclose(s.displacement[2], -z.imag, atol=1e-12)


def test_sparse_chain_many_contacts_condensed_matches_full():
    n = 30
    model = chain(n, sparse=True)
    rows = np.arange(0, n - 1, 3)
    G = sp.csr_matrix((np.r_[np.ones(rows.size), -np.ones(rows.size)],
                       (np.r_[np.arange(rows.size), np.arange(rows.size)], np.r_[rows, rows + 1])),
                      shape=(rows.size, n))
    contacts = make_contact_set(G, ["rattle"] * rows.size, np.arange(rows.size),
                                -np.ones((rows.size, 2)), 0.02, 50.0)
    H, N = 5, 128
    F = np.zeros((2 * H + 1, n))
    F[1, n // 2] = 0.2
    a = solve_frequency(model, contacts, F, 0.3, H, N, options=SolverOptions(condensation=True))
    b = solve_frequency(model, contacts, F, 0.3, H, N, options=SolverOptions(condensation=False))
    assert a.converged and b.converged and np.any(a.contact_state == 1)
    np.testing.assert_allclose(a.displacement, b.displacement, atol=1e-9)
    assert a.stable == b.stable


# ---------------------------------------------------------------- bad input -------------------

def test_bad_model_input():
    with pytest.raises(ValueError, match="stiffness"):
        make_linear_model(np.eye(2), None, np.eye(3))
    with pytest.raises(ValueError, match="mass"):
        make_linear_model(np.array([[1.0, 0.5], [0.0, 1.0]]), None, np.eye(2))
    with pytest.raises(ValueError, match="mass"):
        make_linear_model(np.diag([1.0, -1.0]), None, np.eye(2))
    with pytest.raises(ValueError, match="stiffness"):
        make_linear_model(np.eye(2), None, -np.eye(2))


def test_bad_contact_input():
    G = sp.csr_matrix([[1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match="normal_stiffness"):
        make_contact_set(G, ["rattle"], [0], [[-1, -1]], 0.0, -1.0)
    with pytest.raises(ValueError, match="friction_coefficient"):
        make_contact_set(G, ["squeak"], [0], [[1, -1]], 0.0, 1.0, 1.0, -0.2)


def test_bad_harmonics_and_shapes():
    model, contacts, F = example03()
    with pytest.raises(ValueError, match="harmonics"):
        solve_frequency(model, contacts, F[:1], 0.7, 0, 16)
    with pytest.raises(ValueError, match="samples_per_period"):
        solve_frequency(model, contacts, F, 0.7, H03, 2 * H03)
    with pytest.warns(UserWarning, match="4H\\+1"):
        solve_frequency(model, contacts, F, 0.7, H03, 2 * H03 + 1,
                        options=SolverOptions(stability=False))
    with pytest.raises(ValueError, match="excitation"):
        solve_frequency(model, contacts, F[:, :1], 0.7, H03, N03)
    with pytest.raises(ValueError, match="omega"):
        solve_frequency(model, contacts, F, -1.0, H03, N03)
    with pytest.raises(ValueError, match="gap_map"):
        wrong = make_contact_set(sp.csr_matrix([[1.0, 0, 0]]), ["rattle"], [0], [[-1, -1]], 1.0, 1.0)
        solve_frequency(model, wrong, F, 0.7, H03, N03)


# ---------------------------------------------------------------- extremes --------------------

def converged_or_flagged(s):
    finite = np.all(np.isfinite(s.displacement)) and np.all(np.isfinite(s.contact_force))
    assert (s.converged and finite and s.residual_norm < 1e-6) or (not s.converged and s.reason)


@pytest.mark.parametrize("penalty", [1e-2, 1e2, 1e6])
def test_extreme_penalty_stiffness(penalty):
    """Penalty 1e-2 … 1e6 × the structural stiffness: converged or flagged, never NaN; far from
    the contact resonance (unique solution) it converges."""
    model, contacts, F = example03(penalty=penalty)
    for omega in (0.62, 0.7, 0.9):
        s = solve_frequency(model, contacts, F, omega, H03, N03, options=SolverOptions(stability=False))
        converged_or_flagged(s)
        if omega == 0.9:
            assert s.converged, (penalty, omega, s.reason)


def test_gap_zero_and_preload():
    """Touching (g = 0) and preloaded (g < 0) contacts on a 1-DOF oscillator converge (condensed and
    full); NLvib 03 with g = 0 is converged or flagged (DOF 1 is held only by the contact there and
    single-point Newton from the linear guess can stall: use continuation)."""
    model = make_linear_model(np.eye(1), 0.1 * np.eye(1), np.eye(1))
    H, N = 5, 256
    F = np.zeros((2 * H + 1, 1))
    F[1, 0] = 0.1
    for gap in (0.0, -0.05):
        contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["rattle"], [0], [[-1, -1]], gap, 100.0)
        for condensation in (True, False):
            s = solve_frequency(model, contacts, F, 0.3, H, N,
                                options=SolverOptions(condensation=condensation))
            assert s.converged, s.reason
            assert np.any(s.contact_state == 1) and np.any(s.contact_state == 0)
    model, contacts, F = example03(gap=-0.5)
    s = solve_frequency(model, contacts, F, 0.7, H03, N03)
    assert s.converged and np.all(s.contact_state == 1)
    model, contacts, F = example03(gap=0.0)
    converged_or_flagged(solve_frequency(model, contacts, F, 0.7, H03, 256,
                                         options=SolverOptions(max_iterations=20)))


def test_zero_friction_coefficient_and_zero_damping():
    model = chain(3, damping=0.0)
    G = sp.csr_matrix(np.array([[1.0, 0, 0], [0, 1.0, 0]]))
    contacts = make_contact_set(G, ["squeak"], [0], [[1, -1]], 0.0, 10.0, 5.0, 0.0, 1.0)
    H, N = 5, 256
    F = np.zeros((2 * H + 1, 3))
    F[1, 1] = 0.1
    s = solve_frequency(model, contacts, F, 0.6, H, N)
    converged_or_flagged(s)
    assert s.converged


def test_undamped_exact_resonance_does_not_crash():
    """D = 0 and ω at a linear eigenfrequency: S_1(ω) is singular, condensation falls back."""
    model, contacts, F = example03(damping=0.0)
    omega = np.sqrt((3 - np.sqrt(5)) / 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        s = solve_frequency(model, contacts, F, omega, H03, 256)
    converged_or_flagged(s)


def test_free_floating_structure_is_flagged():
    """Two free masses with a contact between them: K singular at k = 0 (rigid body mode)."""
    K = np.array([[1.0, -1.0], [-1.0, 1.0]])
    model = make_linear_model(np.eye(2), 0.01 * K, K)
    contacts = make_contact_set(sp.csr_matrix([[1.0, -1.0]]), ["rattle"], [0], [[-1, -1]], 0.5, 10.0)
    H, N = 5, 128
    F = np.zeros((2 * H + 1, 2))
    F[1, 0] = 0.1
    s = solve_frequency(model, contacts, F, 1.3, H, N)
    converged_or_flagged(s)


def test_hill_sparse_shift_invert_matches_dense():
    """The sparse shift-invert path of the Hill problem keeps the same exponents as the dense one."""
    from sarfe.hbm.residual import full_residual
    from sarfe.hbm.solve import make_problem
    from sarfe.hbm.stability.hill import floquet_exponents

    model, contacts, F = example03()
    s = solve_frequency(model, contacts, F, 0.7, H03, 256)
    problem = make_problem(model, contacts, F, H03, 256)
    J = full_residual(problem, s.displacement.ravel(), 0.7).jacobian
    dense = floquet_exponents(model, 0.7, H03, J)
    sparse = floquet_exponents(model, 0.7, H03, J, dense_limit=10)
    key = lambda v: np.sort_complex(np.round(v, 8))  # noqa: E731
    np.testing.assert_allclose(key(dense), key(sparse), atol=1e-7)


def test_downward_sweep_and_point_cap():
    model, contacts, F = example03()
    options = ContinuationOptions(solver=SolverOptions(stability=False))
    sols = continuation(model, contacts, F, 0.8, 0.5, H03, N03, options=options)
    omega = np.array([s.omega for s in sols])
    assert all(s.converged for s in sols) and omega[-1] == pytest.approx(0.5, abs=1e-12)
    assert np.any(np.diff(omega) > 0)
    assert max(s.amplitude(1) for s in sols) == pytest.approx(0.9374, rel=2e-3)
    capped = continuation(model, contacts, F, 0.8, 0.5, H03, 256,
                          options=ContinuationOptions(max_points=5,
                                                      solver=SolverOptions(stability=False)))
    assert len(capped) == 5 and "max_points" in capped[-1].reason


def test_non_converged_point_is_flagged():
    model, contacts, F = example03()
    guess = np.zeros_like(F)
    guess[1, 0] = 3.0
    s = solve_frequency(model, contacts, F, 0.75, H03, 256, initial=guess,
                        options=SolverOptions(max_iterations=1, stability=False))
    assert not s.converged and "max iterations 1 reached" in s.reason and s.stable is None
