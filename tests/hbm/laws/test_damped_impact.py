"""Damped impact law λ_n = max(0, k (w − g) + c ẇ) while w > g: restitution, dissipation per cycle,
Jacobians in every state, HBM vs time integration, Hill vs time integration, the case file."""
import math

import numpy as np
import pytest
import scipy.sparse as sp
from law_checks import aft_errors, step_error
from scipy.integrate import solve_ivp

from sarfe.hbm import (SolverOptions, continuation, make_contact_set, make_linear_model,
                       solve_frequency)
from sarfe.hbm.aft import contact_forces
from sarfe.hbm.laws import damped_impact
from sarfe.hbm.time_integration import integrate_time, integrate_transient


def stop(gap, k, rows=((1.0,),), **parameters):
    G = sp.csr_matrix(np.array(rows, dtype=float))
    return make_contact_set(G, ["damped_impact"], [0], [[-1, -1]], gap,
                            parameters=dict(normal_stiffness=k, **parameters))


@pytest.mark.parametrize("zeta", [0.05, 0.3, 0.7, 0.99, 1.0, 1.5, 3.0])
def test_restitution_formula_is_the_rebound_of_the_law(zeta):
    """e(ζ) = the exit velocity of m ẍ + c ẋ + k x = 0 when the force k x + c ẋ vanishes."""
    def force_zero(t, y):
        return y[0] + 2 * zeta * y[1]
    force_zero.terminal, force_zero.direction = True, -1
    run = solve_ivp(lambda t, y: [y[1], -2 * zeta * y[1] - y[0]], [0, 50], [0.0, 1.0],
                    events=force_zero, rtol=1e-12, atol=1e-14, max_step=0.01)
    assert damped_impact.restitution_of_damping_ratio(zeta) == pytest.approx(
        -run.y_events[0][0][1], rel=1e-8)
    e = damped_impact.restitution_of_damping_ratio(zeta)
    assert damped_impact.damping_ratio(e) == pytest.approx(zeta, rel=1e-8)


@pytest.mark.parametrize("e", [0.3, 0.6, 0.9])
def test_single_impact_rebounds_with_the_requested_restitution(e):
    """2 kg at 0.5 m/s onto a stop 1 mm away (k = 1e5 N/m), Newmark h = 1 µs: v_out = −e v_in.

    20 ms: the stop is reached at 2 ms and the contact lasts less than half a damped period,
    π/(ω_n √(1 − ζ²)) ≤ 15.2 ms at e = 0.3 (ω_n = √(k/m) = 224 rad/s), so it has ended by 17.2 ms;
    the last 2 ms are asserted force-free (the 40 ms run before only added free flight)."""
    model = make_linear_model(2.0 * np.eye(1), np.zeros((1, 1)), np.zeros((1, 1)))
    contacts = stop(1e-3, 1e5, restitution=e, effective_mass=2.0)
    out = integrate_transient(model, contacts, [0.0], [0.5], 0.02, 20000)
    assert np.all(out["contact_force"][-2000:] == 0.0)            # the impact is over
    assert -out["final_velocity"][0] / 0.5 == pytest.approx(e, rel=0.02)
    assert out["contact_force"].min() >= 0.0                       # never pulls


def test_dissipation_per_cycle_when_always_closed():
    """Deep overclosure, w = w0 + a cos ωt: a linear spring-dashpot, ∮ λ dw = π c ω a²."""
    k, c, omega, a = 1e4, 3.0, 40.0, 1e-3
    contacts = stop(-0.1, k, contact_damping=c)
    R = np.zeros((3, 1))
    R[1] = a
    force = contact_forces(contacts, R, 64, omega=omega).force
    work = -math.pi * a * force[2, 0]           # T/2 (λ_1c ṙ_1c + λ_1s ṙ_1s), ṙ_1s = −ω a
    assert work == pytest.approx(math.pi * c * omega * a * a, rel=1e-12)
    assert force[1, 0] == pytest.approx(k * a, rel=1e-12)


def test_dissipation_per_impact_cycle_vs_closed_form():
    """w = a cos ωt, gap d < a: contact from x = 0 until k x + c ẋ = 0 (x = a cos θ − d),
    ∮ λ dw = k x(θ_c)²/2 + c ω a² [θ/2 − sin 2θ/4] from θ_in = −arccos(d/a) to θ_c.
    The force jumps by c ẇ at the onset, so the sampled AFT converges like 1/N (rel. 1e-3 at
    N = 1024, 6e-6 … 4e-5 at 2¹⁴ … 2¹⁶)."""
    k, c, omega, a, d = 1e4, 30.0, 40.0, 1e-3, 0.3e-3
    contacts = stop(d, k, contact_damping=c)
    R = np.zeros((3, 1))
    R[1] = a
    force = contact_forces(contacts, R, 2 ** 16, omega=omega).force
    work = -math.pi * a * force[2, 0]
    delta = math.atan2(c * omega, k)
    theta_c = math.acos(k * d / (a * math.hypot(k, c * omega))) - delta
    theta_in = -math.acos(d / a)
    x_c = a * math.cos(theta_c) - d
    primitive = (lambda t: t / 2 - math.sin(2 * t) / 4)
    exact = 0.5 * k * x_c ** 2 + c * omega * a * a * (primitive(theta_c) - primitive(theta_in))
    assert work == pytest.approx(exact, rel=1e-4)
    assert x_c > 0                               # the cut-off ends the contact before w = g


@pytest.mark.parametrize("state, gap", [("open", 5.0), ("closed", -20.0), ("impacting", 0.4)])
def test_jacobians_in_every_state(state, gap):
    contacts = stop(gap, 50.0, contact_damping=4.0)
    R = np.zeros((7, 1))
    R[0], R[1], R[2], R[3] = 0.1, 1.0, 0.4, 0.2
    jac, omega, damping = aft_errors(contacts, R, 256, 3.0)
    assert jac < 1e-6 and omega < 1e-6 and damping < 1e-9
    r = np.array([gap + (0.3 if state != "open" else -1.0)])
    assert step_error(contacts, r, r - 0.01, np.array([2.0]), np.zeros((0, 2)), 1e-3) < 1e-6


def chain(harmonics, restitution=0.6, force=40.0):
    """2-DOF chain (1 kg – 0.5 kg, 10.5 / 34 Hz) whose tip hits a damped stop 1 mm away
    (k = 2e4 N/m, e given for the tip mass 0.5 kg), force on the first mass."""
    M = np.diag([1.0, 0.5])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    model = make_linear_model(M, 2e-4 * K + 5.0 * M, K)
    contacts = stop(1e-3, 2e4, rows=((0.0, 1.0),), restitution=restitution, effective_mass=0.5)
    F = np.zeros((2 * harmonics + 1, 2))
    F[1, 0] = force
    return model, contacts, F


def first_harmonic(U):
    return U[1] - 1j * U[2]


def test_hbm_matches_time_integration_and_hill_says_stable():
    """10 Hz, the stop closes ~24 % of the period: HBM at H = 15 within 0.5 % of Newmark
    (1024 steps, Richardson with 2048, from the H = 30 solution); Hill: stable, and the time
    integration indeed stays on the orbit."""
    omega = 2 * np.pi * 10.0
    model, contacts, F = chain(30)
    reference = solve_frequency(model, contacts, F, omega, 30, 2048)
    run = integrate_time(model, contacts, F, omega, 30, 1024, initial=reference, richardson=True)
    assert run.steady
    target = first_harmonic(run.displacement_harmonics)
    model, contacts, F = chain(15)
    solution = solve_frequency(model, contacts, F, omega, 15, 2048)
    assert solution.converged and solution.stable is True
    error = np.abs(first_harmonic(solution.displacement) - target).max() / np.abs(target).max()
    assert error < 5e-3
    assert 0.1 < np.mean(solution.contact_state == 1) < 0.5


def test_omega_derivative_of_the_residual_full_and_condensed():
    """∂R/∂ω includes (I⊗G)ᵀ ∂λ̃/∂ω (full) and C ∂λ̃/∂ω (condensed): central differences."""
    from sarfe.hbm.dynamic_stiffness import condense
    from sarfe.hbm.residual import condensed_residual, full_residual
    from sarfe.hbm.solve import make_problem

    model, contacts, F = chain(5)
    problem = make_problem(model, contacts, F, 5, 256)
    omega, step = 2 * np.pi * 10.0, 1e-6
    U = solve_frequency(model, contacts, F, omega, 5, 256).displacement
    ev = full_residual(problem, U.ravel(), omega)
    fd = (full_residual(problem, U.ravel(), omega * (1 + step), jacobian=False).residual
          - full_residual(problem, U.ravel(), omega * (1 - step), jacobian=False).residual) \
        / (2 * omega * step)
    assert np.abs(ev.omega_derivative - fd).max() < 1e-6 * np.abs(fd).max()
    x = np.asarray(contacts.gap_map @ U.T).T.ravel()

    def condensed(w, jacobian=True):
        return condensed_residual(problem, condense(model, contacts.gap_map, F, w), x,
                                  jacobian=jacobian)
    fd = (condensed(omega * (1 + step), False).residual
          - condensed(omega * (1 - step), False).residual) / (2 * omega * step)
    assert np.abs(condensed(omega).omega_derivative - fd).max() < 1e-6 * np.abs(fd).max()


@pytest.mark.slow
@pytest.mark.parametrize("branch_hz", [(9.55, 9.62), (9.72, 9.80)])
def test_hill_verdict_on_both_sides_of_the_fold_matches_time_integration(branch_hz):
    """e = 0.8, 60 N: the resonance folds over near 9.68 Hz. On the upper branch before the fold
    and the lower one after it Hill says stable (exponents ≈ −5 … −7 1/s), and Newmark started
    on each orbit stays on it (within 0.5 %, 150 periods). (At the fold itself Hill's exponent of the
    short middle branch is +0.3 … +0.4 1/s and Newmark stays: the nonsmooth-Hill question of
    issue 13, not tested here.)"""
    model, contacts, F = chain(10, restitution=0.8, force=60.0)
    branch = continuation(model, contacts, F, 2 * np.pi * 8.0, 2 * np.pi * 11.0, 10, 512)
    low, high = branch_hz
    points = [s for s in branch if low < s.omega / (2 * np.pi) < high]
    assert points
    start = points[0]
    # the contact-row count bounds the exponents (Re s < −1e-4·ω) without locating them: the
    # full Hill method's leading exponent is the one to compare with −1 1/s
    assert start.stable is True
    full = solve_frequency(model, contacts, F, start.omega, 10, 512, initial=start,
                           options=SolverOptions(stability_method="full"))
    assert full.stable is True and full.floquet_exponent < -1.0
    run = integrate_time(model, contacts, F, start.omega, 10, 1024, initial=start,
                         max_periods=150)
    # stays on the orbit; at some points the period-end state keeps a ~1e-4 wobble (the
    # trapezoidal rule rings after the c ẇ force jump at each impact onset, and the dashpot reads
    # that velocity), so the 1e-7 periodicity is not always reached — it does not grow either
    assert run.periodicity_error < 1e-3
    settled = first_harmonic(run.displacement_harmonics)
    assert np.abs(settled - first_harmonic(start.displacement)).max() < 5e-3 * np.abs(settled).max()


MATRICES_CASE = {
    "name": "damped_stop",
    "model": {"matrices": {"mass": [[1.0, 0.0], [0.0, 0.5]],
                           "stiffness": [[3e4, -1e4], [-1e4, 1e4]]}},
    "damping": {"rayleigh": {"alpha_1_s": 5.0, "beta_s": 2e-4}},
    "contacts": [{"name": "stop", "type": "damped_impact", "normal_dof": 1, "gap_m": 1e-3,
                  "normal_stiffness_N_m": 2e4, "restitution": 0.6}],
    "excitation": {"forces": [{"dof": 0, "force_N": 40.0}], "frequency_hz": [10.0]},
    "solver": {"harmonics": 15, "samples_per_period": 2048, "error_estimate": False},
}


def test_case_file_keys_and_effective_mass_from_the_model():
    """restitution with no effective_mass_kg: the pipeline takes 1/m = g M⁻¹ gᵀ (the tip, 0.5 kg);
    the result equals the ContactSet built by hand with that mass."""
    import copy

    from sarfe.case.errors import CaseError
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model

    case = load_case(MATRICES_CASE)
    nl = nonlinear_model(case, build_linear_model(case))
    assert nl.contacts.effective_mass[0] == pytest.approx(0.5, rel=1e-12)
    c = damped_impact.dashpot(nl.contacts.law_parameters(None, [0]))[0]
    assert c == pytest.approx(2 * damped_impact.damping_ratio(0.6) * math.sqrt(2e4 * 0.5))
    both = copy.deepcopy(MATRICES_CASE)
    both["contacts"][0]["damping_N_s_m"] = 3.0
    with pytest.raises(CaseError, match="exactly one of damping_N_s_m or restitution"):
        load_case(both)
    friction = copy.deepcopy(MATRICES_CASE)
    friction["contacts"][0]["friction_coefficient"] = 0.3
    with pytest.raises(CaseError, match="not allowed for a damped_impact contact"):
        load_case(friction)
