"""AFT of the contact laws: describing functions in closed form and analytic Jacobians vs finite differences."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm import harmonics as hm
from sarfe.hbm.aft import contact_forces, jacobian_matrix, pointwise_jacobian
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.laws.jenkins import compose_clamps, jenkins_periodic_1d, slider_update


def single_row_contact(kind, gap=0.0, k_n=1.0, k_t=0.0, mu=0.0, n0=0.0, normal=True):
    G = sp.identity(1, format="csr")
    return make_contact_set(G, [kind], [0 if normal else -1], [[-1 if normal else 0, -1]],
                            gap, k_n, k_t, mu, n0)


@pytest.mark.parametrize("gap", [-0.3, 0.0, 0.4, 0.9])
def test_unilateral_spring_describing_function(gap):
    a, k, H, N = 1.0, 250.0, 3, 2**14
    contacts = single_row_contact("rattle", gap=gap, k_n=k)
    X = np.zeros((2 * H + 1, 1))
    X[1] = a
    F = contact_forces(contacts, X, N, jacobian=False).force
    phi = np.arccos(gap / a)
    c0 = k / np.pi * (a * np.sin(phi) - gap * phi)
    c1 = k * a / np.pi * (phi - np.sin(phi) * np.cos(phi))
    assert F[0, 0] == pytest.approx(c0, rel=1e-6)
    assert F[1, 0] == pytest.approx(c1, rel=1e-6)
    assert abs(F[2, 0]) < 1e-9 * k * a


@pytest.mark.parametrize("amplitude", [0.05, 0.2, 1.0, 5.0])
def test_jenkins_describing_function(amplitude):
    """q = a cos θ, constant normal load N; sign convention: λ_t = k_t (q − w) acts on the structure
    as +Gᵀλ on the left-hand side, so the dissipated work ∮ λ dq = −π a s1 > 0 means s1 < 0."""
    k_t, mu, N0, H, N = 100.0, 0.5, 10.0, 3, 2**14
    contacts = single_row_contact("squeak", k_t=k_t, mu=mu, n0=N0, normal=False)
    X = np.zeros((2 * H + 1, 1))
    X[1] = amplitude
    F = contact_forces(contacts, X, N, jacobian=False).force
    limit = mu * N0
    if k_t * amplitude <= limit:
        c1, s1 = k_t * amplitude, 0.0
    else:
        theta = np.arccos(1 - 2 * limit / (k_t * amplitude))
        c1 = k_t * amplitude / np.pi * (theta - np.sin(theta) * np.cos(theta))
        s1 = -4 * limit / np.pi * (1 - limit / (k_t * amplitude))
    assert F[1, 0] == pytest.approx(c1, rel=1e-6)
    assert F[2, 0] == pytest.approx(s1, rel=1e-6, abs=1e-9 * limit)


def test_clamp_scan_matches_sample_march():
    rng = np.random.default_rng(0)
    N, n = 300, 7
    q = np.cumsum(rng.normal(size=(N, n)), axis=0)
    rho = np.abs(rng.normal(size=(N, n))) * 2.0
    rho[rng.random((N, n)) < 0.05] = 0.0
    A, B = compose_clamps(q - rho, q + rho)
    start = rng.normal(size=n)
    w = start.copy()
    for j in range(N):
        w = np.clip(w, q[j] - rho[j], q[j] + rho[j])
        np.testing.assert_array_equal(np.clip(start, A[j], B[j]), w)
    # periodic after one pass, and the same as the pointwise 1-D return map
    res = jenkins_periodic_1d(q, rho, start)
    w = res["slider_end"].copy()
    for j in range(N):
        w, _ = slider_update(w[:, None], q[j][:, None], rho[j])
        w = w[:, 0]
        np.testing.assert_allclose(w, res["slider"][j], rtol=0, atol=1e-14 * np.abs(q).max())
    np.testing.assert_allclose(w, res["slider_end"], rtol=0, atol=1e-14 * np.abs(q).max())


def test_pointwise_jacobian_is_E_diag_Phi():
    rng = np.random.default_rng(1)
    for H, N in ((4, 9), (4, 12), (7, 64)):
        d = rng.normal(size=(N, 3))
        E, Phi = hm.fourier_matrices(H, N)
        blocks = pointwise_jacobian(d, H)
        for c in range(3):
            np.testing.assert_allclose(blocks[c], E @ (d[:, c, None] * Phi), atol=1e-12)


def finite_difference(contacts, X, N, start, h, columns=None):
    P = X.size
    columns = np.arange(P) if columns is None else columns
    J = np.empty((P, len(columns)))
    for col, i in enumerate(columns):
        Xp, Xm = X.copy(), X.copy()
        Xp.flat[i] += h
        Xm.flat[i] -= h
        Fp = contact_forces(contacts, Xp, N, slider_start=start, jacobian=False).force
        Fm = contact_forces(contacts, Xm, N, slider_start=start, jacobian=False).force
        J[:, col] = ((Fp - Fm) / (2 * h)).ravel()
    return J


def random_state(rng, H, n_rows, amplitude=1.0):
    X = rng.normal(size=(2 * H + 1, n_rows)) * amplitude / (1 + hm.harmonic_orders(H))[:, None] ** 2
    return X


def contact_mix():
    """Rows: 0 rattle (grounded), 1 rattle, 2-3 squeak 1-D (n, t), 4-6 squeak 2-D (n, t1, t2),
    7 squeak 1-D constant normal load, 8-9 squeak 2-D constant normal load, 10 squeak sticking."""
    G = sp.identity(11, format="csr")
    kind = ["rattle", "rattle", "squeak", "squeak", "squeak", "squeak", "squeak"]
    normal = [0, 1, 2, 4, -1, -1, -1]
    tangent = [[-1, -1], [-1, -1], [3, -1], [5, 6], [7, -1], [8, 9], [10, -1]]
    gap = [0.3, -0.2, 0.1, 0.0, 0.0, 0.0, 0.0]
    k_n = [50.0, 80.0, 40.0, 60.0, 0.0, 0.0, 0.0]
    k_t = [0.0, 0.0, 30.0, 25.0, 20.0, 35.0, 1.0]
    mu = [0.0, 0.0, 0.4, 0.3, 0.5, 0.6, 0.5]
    n0 = [0.0, 0.0, 0.0, 0.0, 3.0, 4.0, 100.0]
    return make_contact_set(G, kind, normal, tangent, gap, k_n, k_t, mu, n0)


def test_jacobian_matches_finite_differences_all_states():
    rng = np.random.default_rng(3)
    contacts = contact_mix()
    H, N = 3, 128
    X = random_state(rng, H, 11)
    for row, gap in ((0, 0.3), (1, -0.2), (2, 0.1), (4, 0.0)):   # normal rows cross their gap
        X[0, row], X[1, row] = gap, 0.6
    start = np.full((contacts.count, 2), np.nan)
    start[6, 0] = X[0, 10] + 0.1 * X[1, 10]   # inside the stick range: history constant w0
    result = contact_forces(contacts, X, N, slider_start=start)
    # every state is visited
    st = result.state
    assert {0, 1} <= set(np.unique(st[:, :2]))
    for c in (2, 3):
        assert {0, 1, 2} <= set(np.unique(st[:, c])), c
    for c in (4, 5):
        assert {1, 2} <= set(np.unique(st[:, c])), c
    assert np.all(st[:, 6] == 1)
    J = jacobian_matrix(result.blocks, 11, H).toarray()
    dense = jacobian_matrix(result.blocks, 11, H, dense=True)
    np.testing.assert_allclose(J, dense, rtol=0, atol=1e-13 * np.abs(dense).max())
    columns = np.sort(rng.choice(X.size, 40, replace=False))   # a random half of the columns
    J = J[:, columns]
    J_fd = finite_difference(contacts, X, N, start, 1e-7, columns)
    scale = np.abs(J_fd).max()
    np.testing.assert_allclose(J, J_fd, atol=1e-5 * scale)


def test_grounded_and_node_to_node_rows_through_residual():
    """Gap map rows with one node (grounded) or two nodes: f̃_nl = Gᵀ λ̃, ∂f̃_nl/∂ũ = Gᵀ J G."""
    from sarfe.hbm.residual import nonlinear_force

    rng = np.random.default_rng(4)
    G = sp.csr_matrix(np.array([[1.0, 0, 0], [1.0, -1.0, 0], [0, 0, 1.0]]))
    contacts = make_contact_set(G, ["rattle", "squeak"], [0, 1], [[-1, -1], [2, -1]],
                                [0.1, 0.0], [40.0, 30.0], [0.0, 20.0], [0.0, 0.4], [0.0, 1.0])
    H, N = 3, 128
    U = random_state(rng, H, 3)
    f, jac, _ = nonlinear_force(contacts, U, N)
    P = U.size
    J_fd = np.empty((P, P))
    for i in range(P):
        Up, Um = U.copy(), U.copy()
        Up.flat[i] += 1e-7
        Um.flat[i] -= 1e-7
        J_fd[:, i] = (nonlinear_force(contacts, Up, N, jacobian=False)[0]
                      - nonlinear_force(contacts, Um, N, jacobian=False)[0]).ravel() / 2e-7
    np.testing.assert_allclose(jac.toarray(), J_fd, atol=1e-5 * np.abs(J_fd).max())
