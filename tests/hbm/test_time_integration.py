"""Time integrator (Newmark average acceleration + contact Newton): closed forms, limits, order."""
import numpy as np
import pytest
import scipy.sparse as sp

import sarfe.hbm.newmark as newmark
import sarfe.hbm.time_integration as ti
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.laws.jenkins import SLIP, STICK
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.time_integration import integrate_time, linear_harmonic_response
from state_checks import assert_states_equal_away_from_ties


def first_amplitude(U, dof):
    return np.hypot(U[1, dof], U[2, dof])


def sdof(zeta=0.02, f_n=10.0):
    m, k = 1.0, (2 * np.pi * f_n) ** 2
    c = 2 * zeta * np.sqrt(k * m)
    return make_linear_model([[m]], [[c]], [[k]]), m, c, k


def two_dof():
    M = np.diag([1.0, 0.5])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    return make_linear_model(M, 2e-4 * K + 5.0 * M, K)


def closed_form(model, F, omega, steps=None):
    """Closed-form periodic response harmonic by harmonic, Û_k = (K − ω_k² M + iω_k D)⁻¹ F̂_k."""
    M, D, K = (np.asarray(x) for x in (model.mass, model.damping, model.stiffness))
    U = np.zeros_like(F)
    H = (F.shape[0] - 1) // 2
    for k in range(H + 1):
        w = k * omega
        if steps is not None and k:
            h = 2 * np.pi / (omega * steps)
            w = 2 / h * np.tan(w * h / 2)
        rhs = F[0] if k == 0 else F[2 * k - 1] - 1j * F[2 * k]
        Uk = np.linalg.solve(K - w * w * M + 1j * w * D, rhs)
        if k == 0:
            U[0] = Uk.real
        else:
            U[2 * k - 1], U[2 * k] = Uk.real, -Uk.imag
    return U


def test_linear_sdof_second_order_to_closed_form_frf():
    model, m, c, k = sdof()
    omega = 2 * np.pi * 9.5                       # near resonance: the FRF slope amplifies errors
    F = np.zeros((3, 1))
    F[1] = 1.0
    exact = 1.0 / abs(k - m * omega**2 + 1j * omega * c)
    errors = []
    for N in (64, 128, 256):
        r = integrate_time(model, None, F, omega, 1, steps_per_period=N)
        amplitude = first_amplitude(r.displacement_harmonics, 0)
        # the scheme's periodic response is the exact FRF at the warped frequency (2/h) tan(ωh/2)
        h = 2 * np.pi / (omega * N)
        warped = 2 / h * np.tan(omega * h / 2)
        assert amplitude == pytest.approx(1.0 / abs(k - m * warped**2 + 1j * warped * c), rel=1e-9)
        assert r.steady and r.periodicity_error < 1e-7
        errors.append(abs(amplitude / exact - 1))
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all(np.abs(orders - 2.0) < 0.05)
    assert errors[-1] < 1e-3
    # Richardson extrapolation in h removes the h² term
    rich = integrate_time(model, None, F, omega, 1, steps_per_period=64, richardson=True)
    assert abs(first_amplitude(rich.displacement_harmonics, 0) / exact - 1) < 0.02 * errors[0]


def test_linear_two_dof_multi_harmonic_from_rest():
    model = two_dof()
    H = 3
    F = np.zeros((2 * H + 1, 2))
    F[0] = [5.0, -2.0]                                 # static load
    F[1, 0], F[2, 1] = 10.0, 4.0                       # 1st harmonic, cos and sin on two DOFs
    F[5, 0] = 3.0                                      # 3rd harmonic
    omega, N = 2 * np.pi * 9.0, 256
    r = integrate_time(model, None, F, omega, H, steps_per_period=N, initial=np.zeros((1, 2)),
                       steady_tolerance=1e-9, output_dofs=[1])
    assert r.steady and r.periodicity_error <= 1e-9 and r.periods > 3
    U_discrete = closed_form(model, F, omega, steps=N)
    scale = np.abs(U_discrete).max()
    assert np.abs(r.displacement_harmonics - U_discrete).max() < 1e-7 * scale
    U_exact = closed_form(model, F, omega)
    assert np.abs(r.displacement_harmonics - U_exact).max() < 2e-3 * scale
    assert r.displacement.shape == (N, 1) and r.velocity.shape == (N, 1)
    assert np.allclose(r.time, np.arange(N) * 2 * np.pi / omega / N)
    assert np.allclose(linear_harmonic_response(model, F, omega, N), U_discrete, atol=1e-12 * scale)
    # the same from the sample time series of the kept DOF
    samples = U_discrete[0, 1] + sum(U_discrete[2 * k - 1, 1] * np.cos(k * omega * r.time)
                                     + U_discrete[2 * k, 1] * np.sin(k * omega * r.time)
                                     for k in range(1, H + 1))
    assert np.abs(r.displacement[:, 0] - samples).max() < 1e-6 * scale


def test_linear_response_of_a_free_floating_pair():
    """Two masses joined by one spring, nothing holding them (K singular: the rigid mode): a
    self-equilibrated static load ±f stretches the spring by f/k about the centre of mass at rest
    (the least-squares mean, u0 = ±f/(2k)); the first harmonic is the regular closed form. The
    dense path solves the regular harmonics by LU and falls back to least squares for K."""
    m, k, f = 1.0, 4e4, 3.0
    K = k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M = m * np.eye(2)
    model = make_linear_model(M, 1e-4 * K, K)
    F = np.zeros((3, 2))
    F[0] = [f, -f]
    F[1] = [1.0, 0.0]
    omega = 2 * np.pi * 15.0
    U = linear_harmonic_response(model, F, omega)
    assert U[0] == pytest.approx([f / (2 * k), -f / (2 * k)], rel=1e-12)
    exact = np.linalg.solve(K - omega**2 * M + 1j * omega * 1e-4 * K, F[1] - 1j * F[2])
    assert np.allclose(U[1] - 1j * U[2], exact.real + 1j * exact.imag, rtol=1e-12, atol=0)


def test_period_cap_is_flagged():
    model = two_dof()
    F = np.zeros((3, 2))
    F[1, 0] = 10.0
    r = integrate_time(model, None, F, 2 * np.pi * 9.0, 1, steps_per_period=64,
                       initial=np.zeros((3, 2)), max_periods=3, accelerate=False)
    assert not r.steady and r.periods == 3 and r.periodicity_error > 1e-3


def grounded_rattle(gap, k_n, dof=1, n=2):
    G = sp.csr_matrix(np.eye(n)[[dof]])
    return make_contact_set(G, ["rattle"], [0], [[-1, -1]], gap=gap, normal_stiffness=k_n)


def test_rattle_always_closed_equals_linear_spring_with_preload():
    """Overclosure g < 0 larger than the motion: λ = k_n (w − g) always, a linear spring + load."""
    model = two_dof()
    k_n, gap = 2e4, -5e-3
    F = np.zeros((5, 2))
    F[1, 0] = 20.0
    omega, N = 2 * np.pi * 12.0, 128
    r = integrate_time(model, grounded_rattle(gap, k_n), F, omega, 2, steps_per_period=N)
    K = np.asarray(model.stiffness).copy()
    K[1, 1] += k_n
    stiffened = make_linear_model(model.mass, model.damping, K)
    F_eq = F.copy()
    F_eq[0, 1] += k_n * gap                           # −Gᵀ(−k_n g): the preload pushes the DOF back
    expected = closed_form(stiffened, F_eq, omega, steps=N)
    assert np.all(r.contact_state == 1)
    assert np.abs(r.displacement_harmonics - expected).max() < 1e-8 * np.abs(expected).max()
    assert np.allclose(r.contact_force[:, 0], k_n * (r.displacement[:, 1] - gap))
    assert r.max_contact_iterations <= 3


def test_rattle_never_closing_is_linear():
    model = two_dof()
    F = np.zeros((3, 2))
    F[1, 0] = 20.0
    omega = 2 * np.pi * 12.0
    r = integrate_time(model, grounded_rattle(1.0, 1e6), F, omega, 1, steps_per_period=64)
    assert np.all(r.contact_state == 0) and np.all(r.contact_force == 0)
    assert np.allclose(r.displacement_harmonics, closed_form(model, F, omega, steps=64))


def squeak_contact(G, tangent_rows, k_t=3e4, mu=0.3, n0=10.0):
    return make_contact_set(sp.csr_matrix(G), ["squeak"], [-1], [tangent_rows], gap=0.0,
                            normal_stiffness=0.0, tangential_stiffness=k_t,
                            friction_coefficient=mu, normal_load=n0)


def test_squeak_always_stuck_equals_linear_spring():
    """μ N0 far above the tangential force: the Jenkins element is a spring k_t (first harmonic)."""
    model = two_dof()
    F = np.zeros((3, 2))
    F[1, 0] = 20.0
    omega, N, k_t = 2 * np.pi * 12.0, 128, 3e4
    contacts = squeak_contact([[0.0, 1.0]], [0, -1], k_t=k_t, mu=1.0, n0=1e6)
    r = integrate_time(model, contacts, F, omega, 1, steps_per_period=N)
    K = np.asarray(model.stiffness).copy()
    K[1, 1] += k_t
    expected = closed_form(make_linear_model(model.mass, model.damping, K), F, omega, steps=N)
    assert np.all(r.contact_state == STICK)
    assert np.abs(r.displacement_harmonics[1:] - expected[1:]).max() < 1e-8 * np.abs(expected).max()


def friction_chain():
    """3 DOF: x0 driven, (x1, x2) in-plane DOFs of a part rubbing on ground; x2 has its own spring."""
    M = np.diag([1.0, 0.4, 0.4])
    K = np.array([[2e4, -1e4, 0.0], [-1e4, 1e4, 0.0], [0.0, 0.0, 1e4]])
    return make_linear_model(M, 2e-4 * K + 4.0 * M, K)


@pytest.mark.parametrize("angle", [0.0, np.pi / 5])
def test_two_direction_friction_matches_one_direction(angle):
    """Isotropic Coulomb disk: motion along x1 only gives the 1-D result, in any tangent frame."""
    model = friction_chain()
    F = np.zeros((3, 3))
    F[1, 0] = 30.0
    omega, N = 2 * np.pi * 11.0, 128
    one = integrate_time(model, squeak_contact([[0, 1.0, 0]], [0, -1]), F, omega, 1,
                         steps_per_period=N)
    c, s = np.cos(angle), np.sin(angle)
    two = integrate_time(model, squeak_contact([[0, c, s], [0, -s, c]], [0, 1]), F, omega, 1,
                         steps_per_period=N)
    assert one.steady and two.steady
    assert np.any(one.contact_state == SLIP) and np.any(one.contact_state == STICK)
    assert_states_equal_away_from_ties(one.contact_state, two.contact_state)
    scale = np.abs(one.displacement_harmonics).max()
    assert np.abs(one.displacement_harmonics - two.displacement_harmonics).max() < 1e-6 * scale
    assert np.abs(two.displacement_harmonics[:, 2]).max() < 1e-9 * scale
    tangential = two.contact_force @ np.array([[c, s], [-s, c]])      # back to (x1, x2)
    assert np.allclose(tangential[:, 0], one.contact_force[:, 0], atol=1e-6 * 3.0)
    assert one.contact_work[0] > 0                                      # friction dissipates


def test_slip_force_is_bounded_by_coulomb_limit():
    model = friction_chain()
    F = np.zeros((3, 3))
    F[1, 0] = 30.0
    mu, n0 = 0.3, 10.0
    r = integrate_time(model, squeak_contact([[0, 1.0, 0]], [0, -1], mu=mu, n0=n0), F,
                       2 * np.pi * 11.0, 1, steps_per_period=128)
    slip = r.contact_state[:, 0] == SLIP
    assert np.allclose(np.abs(r.contact_force[slip, 0]), mu * n0)
    assert np.all(np.abs(r.contact_force[:, 0]) <= mu * n0 * (1 + 1e-12))


def test_contact_convergence_order_and_extrapolation():
    """Rattle with a kinked force: the first-harmonic amplitude still converges ~h²."""
    model = two_dof()
    contacts = grounded_rattle(1e-3, 2e4)
    F = np.zeros((3, 2))
    F[1, 0] = 40.0
    omega, H = 2 * np.pi * 10.0, 1
    amplitudes, previous = [], None
    for N in (64, 128, 256, 512):
        r = integrate_time(model, contacts, F, omega, H, steps_per_period=N, initial=previous)
        assert r.steady
        assert 0 < r.contact_state.mean() < 1
        amplitudes.append(first_amplitude(r.displacement_harmonics, 1))
        previous = r.displacement_harmonics
    differences = np.abs(np.diff(amplitudes))
    orders = np.log2(differences[:-1] / differences[1:])
    assert np.all(orders > 1.7), orders
    # Richardson from (256, 512) agrees with the h² extrapolation of (128, 256, 512)
    extrapolated = amplitudes[-1] + (amplitudes[-1] - amplitudes[-2]) / 3
    assert abs(extrapolated - amplitudes[-1]) < 2e-3 * amplitudes[-1]


def test_acceleration_and_sparse_path_give_the_same_orbit(monkeypatch):
    model = friction_chain()
    F = np.zeros((3, 3))
    F[1, 0] = 30.0
    contacts = squeak_contact([[0, 1.0, 0]], [0, -1])
    omega, N = 2 * np.pi * 11.0, 64
    fast = integrate_time(model, contacts, F, omega, 1, steps_per_period=N, steady_tolerance=1e-10)
    plain = integrate_time(model, contacts, F, omega, 1, steps_per_period=N, steady_tolerance=1e-10,
                           accelerate=False)
    assert fast.steady and plain.steady and fast.periods < plain.periods
    scale = np.abs(plain.displacement_harmonics).max()
    assert np.abs(fast.displacement_harmonics - plain.displacement_harmonics).max() < 1e-8 * scale
    monkeypatch.setattr(ti, "DENSE_LIMIT", 0)          # the output DOFs
    monkeypatch.setattr(newmark, "DENSE_LIMIT", 0)     # the propagator and the contact rows
    sparse_model = make_linear_model(*(sp.csr_matrix(np.asarray(x)) for x in
                                       (model.mass, model.damping, model.stiffness)))
    sparse = integrate_time(sparse_model, contacts, F, omega, 1, steps_per_period=N,
                            steady_tolerance=1e-10)
    assert np.abs(sparse.displacement_harmonics - fast.displacement_harmonics).max() < 1e-8 * scale


def test_input_validation():
    model = two_dof()
    F = np.zeros((3, 2))
    with pytest.raises(ValueError, match="excitation"):
        integrate_time(model, None, np.zeros((3, 3)), 10.0, 1)
    with pytest.raises(ValueError, match="omega"):
        integrate_time(model, None, F, 0.0, 1)
    with pytest.raises(ValueError, match="steps_per_period"):
        integrate_time(model, None, F, 10.0, 8, steps_per_period=10)
    with pytest.raises(ValueError, match="initial"):
        integrate_time(model, None, F, 10.0, 1, initial=np.zeros((3, 5)))


def test_many_contacts_vectorized_equals_separate_copies():
    """Two uncoupled copies of a rattle + squeak system, contacts and rows shuffled: each copy
    responds exactly like the system alone (checks the vectorized contact bookkeeping)."""
    M = np.diag([1.0, 0.3, 0.3])
    K = np.array([[2e4, -1e4, 0.0], [-1e4, 1e4, 0.0], [0.0, 0.0, 2e4]])
    D = 2e-4 * K + 8.0 * M
    F1 = np.zeros((3, 3))
    F1[1, 0], F1[1, 2], F1[2, 2] = 15.0, 3.0, 1.0
    omega, N = 2 * np.pi * 12.0, 64
    squeak = dict(tangential_stiffness=3e4, friction_coefficient=0.4, normal_load=2.0)
    # single system: rows [w (x2), q (x1), rattle on x0]
    G1 = np.array([[0, 0, 1.0], [0, 1.0, 0], [1.0, 0, 0]])
    single = make_contact_set(sp.csr_matrix(G1), ["squeak", "rattle"], [0, 2], [[1, -1], [-1, -1]],
                              gap=[-2e-4, 2e-3], normal_stiffness=[4e4, 2e4],
                              tangential_stiffness=[3e4, 0], friction_coefficient=[0.4, 0],
                              normal_load=[2.0, 0])
    alone = integrate_time(make_linear_model(M, D, K), single, F1, omega, 1, steps_per_period=N,
                           steady_tolerance=1e-10)
    assert set(np.unique(alone.contact_state[:, 0])) >= {STICK, SLIP}
    assert 0 < alone.contact_state[:, 1].mean() < 1
    Z = np.zeros((3, 3))
    big = make_linear_model(np.block([[M, Z], [Z, M]]), np.block([[D, Z], [Z, D]]),
                            np.block([[K, Z], [Z, K]]))
    # rows of the copy: copy B's rows first, in a shuffled order
    G2 = np.zeros((6, 6))
    G2[0, 5] = G2[1, 3] = G2[2, 4] = 1.0                  # copy B: w, rattle, q
    G2[3, 1] = G2[4, 0] = G2[5, 2] = 1.0                  # copy A: q, rattle, w
    contacts = make_contact_set(
        sp.csr_matrix(G2), ["squeak", "rattle", "rattle", "squeak"], [0, 1, 4, 5],
        [[2, -1], [-1, -1], [-1, -1], [3, -1]], gap=[-2e-4, 2e-3, 2e-3, -2e-4],
        normal_stiffness=[4e4, 2e4, 2e4, 4e4], tangential_stiffness=[3e4, 0, 0, 3e4],
        friction_coefficient=[0.4, 0, 0, 0.4], normal_load=[2.0, 0, 0, 2.0])
    F2 = np.hstack([F1, F1])
    both = integrate_time(big, contacts, F2, omega, 1, steps_per_period=N, steady_tolerance=1e-10)
    scale = np.abs(alone.displacement_harmonics).max()
    for copy in (slice(0, 3), slice(3, 6)):
        assert np.abs(both.displacement_harmonics[:, copy]
                      - alone.displacement_harmonics).max() < 1e-8 * scale
    for columns in ([3, 2], [0, 1]):   # stick/slip exactly at the Coulomb limit may flip by round-off
        assert np.mean(both.contact_state[:, columns] != alone.contact_state) <= 2 / N
    assert np.allclose(both.contact_work[[3, 2]], alone.contact_work, rtol=1e-6, atol=1e-12)
