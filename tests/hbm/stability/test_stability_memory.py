"""The friction-memory term of Hill's operator: the vectorized 1-D form equals the sample march;
the compiled 2-D march (slider states and the linearized march at many s) equals a plain
per-sample loop written out here."""
import numpy as np
import pytest

from sarfe.hbm import harmonics as hm
from sarfe.hbm.laws.jenkins import slider_update_derivatives
from sarfe.hbm.stability.contact_terms import (_memory_block, _memory_block_1d, _memory_blocks,
                                          _slider_march)


def one_d_states(N=256, n=3, seed=0):
    """Tangential motion q (N, n, 2) (second direction absent) and slip radii ρ (N, n) that visit
    stick, slip and separation (ρ = 0), with a periodic start of the slider."""
    theta = 2 * np.pi * np.arange(N) / N
    rng = np.random.default_rng(seed)
    amplitude = np.array([0.5, 2.0, 3.0])[:n]          # stuck, stick-slip, mostly slipping
    q = np.zeros((N, n, 2))
    q[:, :, 0] = amplitude * np.cos(theta[:, None] + rng.uniform(0, 1, n))
    rho = np.clip(1.0 + 0.8 * np.sin(2 * theta[:, None] + rng.uniform(0, 1, n)), 0, None)
    rho[N // 3: N // 3 + 5, 2] = 0.0                    # a separation on the third contact
    start = np.zeros((n, 2))
    for _ in range(3):                                  # march to the periodic start
        P, n_rho = _slider_march(q, rho, start)
        w = start.copy()
        for j in range(N):
            t = w - q[j]
            norm = np.abs(t[:, 0])
            w[:, 0] = np.where(norm > rho[j], q[j, :, 0] + rho[j] * np.sign(t[:, 0]), w[:, 0])
        start = w
    return q, rho, start


@pytest.mark.parametrize("s", [0.0, -0.3 + 0.0j, 0.05 + 0.4j, -2.0 + 1.3j])
def test_vectorized_1d_memory_equals_the_march(s):
    N, H = 256, 5
    q, rho, start = one_d_states(N)
    drho = 0.3 * np.ones_like(rho)
    k_t = np.array([1.0, 2.0, 0.5])
    P, n_rho = _slider_march(q, rho, start)
    states = P[:, :, 0, 0]
    assert np.any(states == 1.0) and np.any(states == 0.0)   # stick and resets both present
    omega = 3.0
    loop = _memory_block(s, omega, P, n_rho, drho, k_t, H, N)
    fast = _memory_block_1d(s, omega, P, n_rho, drho, k_t, H, N)
    scale = np.abs(loop[:, :, 0]).max()
    assert np.abs(fast[:, :, 0] - loop[:, :, 0]).max() <= 1e-12 * scale


def test_vectorized_1d_slider_march_equals_the_loop():
    """The clamp-scan march of 1-D sliders (stick, slip and separation) gives the sample loop's
    return-map derivatives P_j and n_j at every sample."""
    q, rho, start = one_d_states()
    P, n_rho = _slider_march(q, rho, start)
    P_fast, n_rho_fast = _slider_march(q, rho, start, one_d=True)
    assert np.allclose(P_fast, P, rtol=0, atol=1e-12)
    assert np.allclose(n_rho_fast, n_rho, rtol=0, atol=1e-12)


def two_d_states(N=128, n=3, seed=1):
    """2-D tangential motion q (N, n, 2) on ellipses and slip radii ρ (N, n) with stick, slip (in
    changing directions) and a separation; start: the slider after three periods."""
    theta = 2 * np.pi * np.arange(N) / N
    rng = np.random.default_rng(seed)
    amplitude = np.array([0.4, 1.5, 3.0])[:n]
    q = np.zeros((N, n, 2))
    q[:, :, 0] = amplitude * np.cos(theta[:, None] + rng.uniform(0, 1, n))
    q[:, :, 1] = 0.6 * amplitude * np.sin(theta[:, None] + rng.uniform(0, 1, n))
    rho = np.clip(1.0 + 0.5 * np.sin(2 * theta[:, None] + np.zeros(n)), 0, None)
    rho[N // 4: N // 4 + 4, 2] = 0.0
    w = np.zeros((n, 2))
    for _ in range(3 * N):
        w = slider_update_derivatives(w, q[_ % N], rho[_ % N])[0]
    return q, rho, w


def test_compiled_2d_slider_march_equals_the_sample_loop():
    """P_j and n_j of the compiled 2-D march equal the per-sample return map at every sample."""
    q, rho, start = two_d_states()
    P, n_rho = _slider_march(q, rho, start)
    w, states = start.copy(), []
    for j in range(q.shape[0]):
        w, state, P_j, n_j = slider_update_derivatives(w, q[j], rho[j])
        states.append(state)
        assert np.allclose(P[j], P_j, rtol=0, atol=1e-14)
        assert np.allclose(n_rho[j], n_j, rtol=0, atol=1e-14)
    assert set(np.unique(states).tolist()) == {0, 1, 2}        # separated, stick and slip visited


@pytest.mark.parametrize("s", [0.0, -0.3 + 0.2j, 0.05 + 1.4j, 40.0 - 3.0j])
def test_compiled_2d_memory_equals_the_linearized_march(s):
    """δλ̃_t at s from the compiled march over many s at once (chunked) equals the linearized return
    map marched sample by sample, δw_j = P_j (e^{−sh} δw_{j−1} − δq_j) + δq_j + n_j dρ_j δn_j, from
    the periodic start δw_{−1} = δw_{N−1} (where regular), with δλ_t = k_t (δq − δw) transformed by E."""
    N, H, omega = 128, 4, 2.0
    q, rho, start = two_d_states(N)
    n = q.shape[1]
    P_j, n_j = _slider_march(q, rho, start)
    drho, k_t = 0.2 * np.ones_like(rho), np.array([1.0, 2.0, 0.5])
    E, Phi = hm.fourier_matrices(H, N)
    C = 3 * (2 * H + 1)
    decay = np.exp(-s * 2 * np.pi / (omega * N))
    # the march as an affine map of δw_{−1}: δw_j = A_j δw_{−1} + b_j (columns: local harmonics)
    A = np.broadcast_to(np.eye(2, dtype=complex), (n, 2, 2)).copy()
    b = np.zeros((n, 2, C), complex)
    history, forced = [], []
    for j in range(N):
        dq = np.zeros((2, C))
        dq[0, 1::3], dq[1, 2::3] = Phi[j], Phi[j]
        dn = np.zeros(C)
        dn[0::3] = Phi[j]
        A = P_j[j] @ (decay * A)
        b = P_j[j] @ (decay * b - dq) + dq + n_j[j][:, :, None] * (drho[j][:, None, None] * dn)
        history.append(A)
        forced.append(b - dq)
    w0 = np.zeros_like(b)        # a contact stuck all period at s = 0: no periodic start (δw = 0)
    regular = np.abs(np.linalg.det(np.eye(2) - A)) > 1e-9
    w0[regular] = np.linalg.solve((np.eye(2) - A)[regular], b[regular])
    dw_minus_dq = np.array([hist @ w0 + f for hist, f in zip(history, forced)])   # (N, n, 2, C)
    reference = -k_t[None, :, None, None] * np.einsum("hj,jcax->hcax", E, dw_minus_dq)
    many = _memory_blocks(np.array([1.0 + 2.0j, s, 0.3j, s, -1.0]), omega, P_j, n_j, drho, k_t,
                          H, N, chunk=2)
    scale = np.abs(reference).max()
    assert np.abs(many[1] - reference).max() <= 1e-11 * scale
    assert np.abs(many[3] - reference).max() <= 1e-11 * scale


def test_refined_exponent_is_the_fixed_point_of_successive_linear_problems():
    """1-DOF Jenkins oscillator in stick-slip (m = k = 1, c = 0.02, k_t = μN = 1, F = 0.5, ω = 1.4,
    H = 7): the secant refinement lands on the fixed point s = μ(s) of the successive linear
    problems (iterated here until they converge), and s is a root of Hill's nonlinear problem:
    T(s) = s²M̃ + sD̃ + ∂R/∂ũ + C(s) is singular there."""
    import scipy.sparse as sp

    from sarfe.hbm import make_contact_set, make_linear_model, solve_frequency
    from sarfe.hbm.residual import Problem, full_residual
    from sarfe.hbm.stability.hill import _dense, _hill, _nearest, floquet_exponents, refine_exponent
    from sarfe.hbm.stability.contact_terms import ContactOperator

    model = make_linear_model(np.eye(1), 0.02 * np.eye(1), np.eye(1))
    contacts = make_contact_set(sp.csr_matrix(np.array([[1.0]])), ["squeak"], [-1], [[0, -1]],
                                gap=0.0, normal_stiffness=0.0, tangential_stiffness=1.0,
                                friction_coefficient=1.0, normal_load=1.0)
    H, N, omega = 7, 256, 1.4
    F = np.zeros((2 * H + 1, 1))
    F[1, 0] = 0.5
    solution = solve_frequency(model, contacts, F, omega, H, N)
    assert solution.converged
    problem = Problem(model, contacts, F, H, N)
    ev = full_residual(problem, solution.displacement.ravel(), omega)
    operator = ContactOperator(problem, solution.displacement, omega, ev.forces)
    assert operator.has_memory
    jacobian = _dense(ev.jacobian) + operator.correction(0.0).real.toarray()
    Mt, Dt = _hill(model, omega, H, None)
    frozen = floquet_exponents(model, omega, H, jacobian)
    s0 = frozen[np.argmax(frozen.real)]
    s, converged = refine_exponent(Mt, Dt, jacobian, operator, s0, dense=True)
    assert converged
    plain = complex(s0)
    for _ in range(500):                       # the successive linear problems, to convergence
        new = _nearest(Mt, Dt, jacobian + operator.correction(plain).toarray(), plain, True, 1)[0]
        if abs(new - plain) <= 1e-12 * max(abs(new), 1.0):
            break
        plain = new
    assert abs(s - new) <= 1e-7 * max(abs(new), 1.0)
    assert abs(s - s0) > 1e-3 * abs(s0)        # the memory moved the exponent: a real test
    T = s * s * _dense(Mt) + s * _dense(Dt) + jacobian + operator.dense_correction(s)
    singular = np.linalg.svd(T, compute_uv=False)
    assert singular[-1] <= 1e-8 * singular[0]
