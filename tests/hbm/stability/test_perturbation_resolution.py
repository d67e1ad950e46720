"""The time integrator's decay rate against closed forms (:mod:`sarfe.hbm.stability.perturbation`).

The trapezoidal rule maps an exponent s to the step factor z(s) = (1 + sh/2)/(1 − sh/2), so a
linear time-invariant system's monodromy multipliers are exactly z(s_k)^N (h = T/N): a mode far
above the step's resolution (ω_k h ≫ 2) decays at ln|z|/h ≈ −ζω_k/(1 + (ω_k h/2)²), nearly
undamped. The check's rate must be the leading exponent of the resolved directions (Hill's
−ζ₁ω₁), and Hill's contact operator for a contact stuck all period must give the stuck linear
system's eigenvalues."""
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.linalg as sla

from sarfe.hbm import make_contact_set, make_linear_model, solve_frequency
from sarfe.hbm.dynamic_stiffness import dynamic_stiffness_matrix
from sarfe.hbm.residual import Problem, full_residual
from sarfe.hbm.stability.contact_terms import ContactOperator
from sarfe.hbm.stability.hill import hill_stability
from sarfe.hbm.stability.perturbation import RESOLVED, perturbation_check

ZETA = 0.02


def chain_with_stiff_mode():
    """Unit masses 0-3 in a chain (unit springs, grounded at both ends) and a light mass (1e-4 kg)
    on a 100 N/m spring from mass 3 (ω ≈ 1000 rad/s), every undamped mode damped by ζ = 0.02
    (D = M Φ diag(2ζω_k) Φᵀ M): the exponents are s_k = −ζω_k ± iω_k√(1 − ζ²) exactly.
    Returns (model, ω_k [rad/s], s_k (upper half-plane))."""
    n = 5
    M = np.diag([1.0, 1.0, 1.0, 1.0, 1e-4])
    K = np.zeros((n, n))
    for a, b, k in ((0, 1, 1.0), (1, 2, 1.0), (2, 3, 1.0), (3, 4, 100.0)):
        K[np.ix_([a, b], [a, b])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[0, 0] += 1.0
    K[3, 3] += 1.0
    w2, modes = sla.eigh(K, M)
    wk = np.sqrt(w2)
    D = M @ modes @ np.diag(2 * ZETA * wk) @ modes.T @ M
    s = wk * (-ZETA + 1j * np.sqrt(1 - ZETA ** 2))
    return make_linear_model(M, 0.5 * (D + D.T), K), wk, s


def trapezoidal_rate(s, h):
    """ln|z(s)|/h [1/s]: the decay per unit time of the trapezoidal rule's step factor."""
    return np.log(np.abs((1 + 0.5 * s * h) / (1 - 0.5 * s * h))) / h


def test_linear_rate_is_the_slowest_resolved_mode():
    """Ω = 0.8 rad/s, 64 steps per period (h = 0.123 s): the 1000 rad/s mode (ωh = 123) decays in
    the integrator at −0.0053 1/s instead of −20 1/s, above the true leading exponent −ζω₁ =
    −0.0085 1/s that Hill gives; the check's rate is the slowest resolved one and equals
    ln|z(s₁)|/h, the unresolved rate ln|z(s₅)|/h (closed forms)."""
    model, wk, s = chain_with_stiff_mode()
    omega, H, N = 0.8, 3, 64
    F = np.zeros((2 * H + 1, 5))
    F[1, 1] = 1.0
    S = dynamic_stiffness_matrix(model, omega, H)
    U = np.linalg.solve(S.toarray(), F.ravel()).reshape(F.shape)
    hill = hill_stability(model, omega, H, S)
    assert hill.leading == pytest.approx(-ZETA * wk[0], rel=1e-8)
    check = perturbation_check(model, None, F, SimpleNamespace(omega=omega, displacement=U),
                               steps_per_period=N, newton_steps=1)
    h = 2 * np.pi / (omega * N)
    assert wk[-1] * h > 100                                     # the stiff mode is unresolved
    assert check.unresolved_rate == pytest.approx(trapezoidal_rate(s[-1], h), rel=1e-4)
    assert check.unresolved_rate > -0.7 * ZETA * wk[0]          # the old max: above Hill's
    assert check.rate == pytest.approx(trapezoidal_rate(s[0], h), rel=1e-4)
    assert check.rate == pytest.approx(hill.leading, rel=2e-3)  # ω₁h = 0.052: 1/(1 + 7e-4)
    assert check.stable and hill.stable
    assert np.sum(check.resolution < RESOLVED) == 2             # the stiff mode's pair only


def test_stuck_contact_hill_and_integrator_are_the_stuck_system():
    """A Jenkins contact (k_n = 5, k_t = 3 N/m, load 0.8 N, penalty closed throughout: λ_n ≥ 1.5 N,
    μ = 1) on the chain, driven weakly (0.01 N): |λ_t|/λ_n ≤ 0.41, stuck all period, so the orbit's
    exponents are the eigenvalues of the linear stuck system (K + Gᵀ diag(k_n, k_t) G, same M, D).
    Hill with the friction memory gives its leading one; the integrator's multipliers are z(s_k)^N
    of it (to 1e-8) plus the slider's two neutral directions (|μ| = 1: a stuck offset is a history
    constant, so the rate is 0), and the stiff pair is the unresolved one."""
    model, _, _ = chain_with_stiff_mode()
    G = np.zeros((2, 5))
    G[0, 0], G[1, 1] = 1.0, 1.0
    contacts = make_contact_set(G, ["squeak"], [0], [[1, -1]], -1.0, 5.0, 3.0, 1.0, 0.8)
    omega, H, N = 0.8, 3, 64
    F = np.zeros((2 * H + 1, 5))
    F[1, 2] = 0.01
    sol = solve_frequency(model, contacts, F, omega, H, N)
    assert sol.converged
    force = np.asarray(sol.contact_force_time)
    assert np.all(force[:, 0] > 0.8)                              # the penalty closed throughout
    assert np.all(np.abs(force[:, 1]) < 0.5 * force[:, 0])       # stuck at every sample (μ = 1)
    Ks = model.stiffness + G.T @ np.diag([5.0, 3.0]) @ G
    n = 5
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(model.mass, Ks), -np.linalg.solve(model.mass, model.damping)]])
    exact = np.linalg.eigvals(A)
    problem = Problem(model, contacts, F, H, N)
    ev = full_residual(problem, sol.displacement.ravel(), omega)
    hill = hill_stability(model, omega, H, ev.jacobian,
                          operator=ContactOperator(problem, sol.displacement, omega, ev.forces))
    assert hill.leading == pytest.approx(exact.real.max(), rel=1e-6)
    check = perturbation_check(model, contacts, F, sol, steps_per_period=N, newton_steps=1)
    h = 2 * np.pi / (omega * N)
    expected = np.sort(np.abs(((1 + 0.5 * exact * h) / (1 - 0.5 * exact * h)) ** N))
    found = np.sort(np.abs(check.multipliers))
    assert found[-2:] == pytest.approx(1.0, abs=1e-6)       # the slider's two neutral directions
    assert np.allclose(found[:-2], expected, rtol=1e-6)
    assert check.rate == pytest.approx(0.0, abs=1e-6 * omega)           # the slider, resolved
    stiff = exact[np.argmax(np.abs(exact.imag))]                         # the ≈ 1000 rad/s mode
    assert check.unresolved_rate == pytest.approx(trapezoidal_rate(stiff, h), rel=1e-4)
