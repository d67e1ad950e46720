"""The compiled 2-D Jenkins march equals the sample-by-sample return map (issue 15).

Reference: periods marched with the pointwise return map w_j = q_j + Proj_{|x| ≤ ρ_j}(w_{j−1} − q_j)
(:func:`sarfe.hbm.laws.jenkins.slider_update`, plain numpy) from the gauge start w = 0 until the
slider at θ_0 repeats; the compiled kernels must give the same periodic forces and states to
round-off, and their Jacobian must match finite differences of the forces.
"""
import numpy as np
import pytest

from sarfe.hbm import harmonics as hm
from sarfe.hbm.laws.jenkins import STICK, periodic_forces, slider_update

H, N, n = 5, 128, 6
THETA = 2 * np.pi * np.arange(N) / N
PARAMETERS = {"tangential_stiffness": np.linspace(1.0, 2.0, n),
              "friction_coefficient": np.full(n, 0.5)}


def displacement(amplitude):
    """Elliptic tangential orbits (N, n, 2) [m] and a normal force (N, n) [N] that lifts off on
    the last contact."""
    q = np.zeros((N, n, 2))
    for c in range(n):
        q[:, c, 0] = amplitude * (np.cos(THETA + c) + 0.3 * np.sin(2 * THETA))
        q[:, c, 1] = amplitude * 0.7 * np.sin(THETA + 0.5 * c) + 0.1
    normal = 1.0 + 0.5 * np.cos(THETA)[:, None] * np.ones(n)
    normal[:, -1] = np.maximum(normal[:, -1] - 1.2, 0.0)
    return q, normal


def reference_march(q, normal):
    rho = PARAMETERS["friction_coefficient"] * normal / PARAMETERS["tangential_stiffness"]
    w = np.zeros((n, 2))
    for _ in range(20000):
        start = w.copy()
        slider = np.empty_like(q)
        for j in range(N):
            w, _ = slider_update(w, q[j], rho[j])
            slider[j] = w
        if np.abs(w - start).max() <= 1e-13:
            break
    return PARAMETERS["tangential_stiffness"][None, :, None] * (q - slider)


def forces(q, normal, jacobian=False):
    return periodic_forces(PARAMETERS, q, np.zeros(n, bool), normal, 10.0 * np.ones((N, n)),
                           None, H, N, jacobian, 1e-12, 50, np.arange(2 * H + 1))


@pytest.mark.parametrize("amplitude", [0.05, 0.5, 2.0])
def test_compiled_march_equals_pointwise_return_map(amplitude):
    q, normal = displacement(amplitude)
    force, state, _, _, _ = forces(q, normal)
    expected = reference_march(q, normal)
    assert np.abs(force - expected).max() <= 1e-9 * np.abs(expected).max()
    if amplitude == 0.05:               # stuck contacts keep the spring of assembly: λ_t = k_t q
        stuck = np.all(state == STICK, axis=0)
        assert stuck[:-1].all()
        k_t = PARAMETERS["tangential_stiffness"][stuck]
        assert np.abs(force[:, stuck] - k_t[None, :, None] * q[:, stuck]).max() < 1e-14


@pytest.mark.parametrize("amplitude", [0.05, 0.5])
def test_compiled_march_jacobian_matches_finite_differences(amplitude):
    """∂λ̃_t/∂(q̃, λ̃_n) with ∂λ_n/∂w = 10 N/m: central differences of the harmonics, perturbing
    q̃ and, through λ_n = λ_n0 + 10 w, the normal harmonics."""
    q, normal = displacement(amplitude)
    _, _, _, _, J = forces(q, normal, jacobian=True)
    Q = hm.harmonic_coefficients(q, H)                    # (2H+1, n, 2)
    step = 1e-7
    for h in (0, 1, 4):
        for l in range(3):
            delta = np.zeros((2 * H + 1, n, 3))
            delta[h, :, l] = step
            shifted = []
            for sign in (1.0, -1.0):
                d = hm.time_samples(sign * delta.reshape(2 * H + 1, -1), N).reshape(N, n, 3)
                f = forces(hm.time_samples((Q + sign * delta[:, :, 1:]).reshape(2 * H + 1, -1),
                                           N).reshape(N, n, 2),
                           normal + 10.0 * d[:, :, 0])[0]
                shifted.append(hm.harmonic_coefficients(f, H))
            column = (shifted[0] - shifted[1]) / (2 * step)      # (2H+1, n, 2)
            for c in range(n - 1):       # the separating contact has kinks at lift-off
                analytic = J[c, :, 3 * h + l].reshape(2 * H + 1, 3)[:, 1:]
                assert np.abs(analytic - column[:, c]).max() < 1e-5 * max(
                    1.0, np.abs(column[:, c]).max()), (h, l, c)


@pytest.mark.parametrize("mean_normal, offset", [(1.6, 0.0), (1.2, 0.0), (1.6, -1.2)])
def test_one_direction_gauge_and_jacobian(mean_normal, offset):
    """1-D stuck contact under a varying normal load: the periodic slider is the assembly position
    0 clipped to the interval [A, B] of periodic starts (1.6: 0 inside, λ_t = k_t q; 1.2: 0 below
    A, the slider rests on the edge A; offset −1.2: a static tangential displacement beyond the
    interval, 0 above B); the Jacobian matches central differences in each case."""
    from sarfe.hbm.laws.jenkins import compose_clamps
    p = {"tangential_stiffness": np.ones(1), "friction_coefficient": np.ones(1)}
    Q = np.zeros((2 * H + 1, 1, 2))
    Q[0, 0, 0], Q[1, 0, 0], Q[4, 0, 0] = offset, 1.0, 0.3
    L = np.zeros((2 * H + 1, 1))
    L[0], L[1], L[2] = mean_normal, -0.5, 0.3

    def evaluate(Q, L, jacobian=False):
        q = hm.time_samples(Q.reshape(2 * H + 1, -1), N).reshape(N, 1, 2)
        return periodic_forces(p, q, np.ones(1, bool), hm.time_samples(L, N), 10.0 * np.ones((N, 1)),
                               None, H, N, jacobian, 1e-12, 50, np.arange(2 * H + 1))
    q = hm.time_samples(Q[:, :, 0], N)
    rho = hm.time_samples(L, N)
    A, B = compose_clamps(q - rho, q + rho)
    force, state, slider_end, _, J = evaluate(Q, L, True)
    assert np.all(state == STICK) and A[-1, 0] < B[-1, 0]
    assert (A[-1, 0] < 0 < B[-1, 0]) == (mean_normal == 1.6 and offset == 0.0)
    assert slider_end[0, 0] == pytest.approx(np.clip(0.0, A[-1, 0], B[-1, 0]), abs=1e-14)
    assert np.abs(force[:, 0, 0] - (q[:, 0] - slider_end[0, 0])).max() < 1e-12
    step = 1e-7
    for h in range(2 * H + 1):
        for l in (0, 1):
            plus, minus = (Q.copy(), L.copy()), (Q.copy(), L.copy())
            if l == 1:
                plus[0][h, 0, 0] += step
                minus[0][h, 0, 0] -= step
            else:                                   # λ_n = λ_n0 + 10 w
                plus[1][h] += 10 * step
                minus[1][h] -= 10 * step
            column = (hm.harmonic_coefficients(evaluate(*plus)[0][:, 0, 0], H)
                      - hm.harmonic_coefficients(evaluate(*minus)[0][:, 0, 0], H)) / (2 * step)
            assert np.abs(column - J[0, 1::3, 3 * h + l]).max() < 1e-6


def stuck_orbits():
    """Two 2-D contacts that can stick the whole period but not at w = 0 (|q_j| > ρ_j):
    0: an ellipse around (1, 0) with ρ = 0.5 + 0.1 cos θ (the nearest point of S lies on one disk);
    1: q = (1, 0.45 sin θ), ρ = 0.5 (S is a lens; its point nearest to 0 is a corner of two disks).
    Returns harmonics Q (2H+1, 2, 2) [m] and normal-force harmonics L (2H+1, 2) [N] (k_t = μ = 1,
    so ρ = λ_n)."""
    Q = np.zeros((2 * H + 1, 2, 2))
    L = np.zeros((2 * H + 1, 2))
    Q[0, 0, 0], Q[1, 0, 0], Q[2, 0, 1], Q[3, 0, 0] = 1.0, 0.2, 0.3, 0.05
    L[0, 0], L[1, 0] = 0.5, 0.1
    Q[0, 1, 0], Q[2, 1, 1] = 1.0, 0.45
    L[0, 1] = 0.5
    return Q, L


def stuck_forces(Q, L, jacobian=False):
    p = {"tangential_stiffness": np.ones(2), "friction_coefficient": np.ones(2)}
    q = hm.time_samples(Q.reshape(2 * H + 1, -1), N).reshape(N, 2, 2)
    return periodic_forces(p, q, np.zeros(2, bool), hm.time_samples(L, N), 10.0 * np.ones((N, 2)),
                           None, H, N, jacobian, 1e-12, 50, np.arange(2 * H + 1))


def test_stuck_slider_is_the_point_of_the_stick_set_nearest_to_assembly():
    """The gauge of a contact that never slips: the constant slider w₀ nearest to w = 0 among those
    with |w₀ − q_j| ≤ ρ_j at every sample. Reference: scipy's SLSQP on min |w|² under those N
    constraints; and w₀ is a periodic state of the pointwise return map with no slip."""
    from scipy.optimize import minimize
    Q, L = stuck_orbits()
    force, state, slider, _, _ = stuck_forces(Q, L)
    q = hm.time_samples(Q.reshape(2 * H + 1, -1), N).reshape(N, 2, 2)
    rho = hm.time_samples(L, N)
    assert np.all(state == STICK)
    for c in range(2):
        constraints = {"type": "ineq", "fun": lambda w, c=c: rho[:, c] ** 2
                       - np.sum((w - q[:, c]) ** 2, axis=1)}
        best = minimize(lambda w: w @ w, q[:, c].mean(axis=0), constraints=constraints,
                        method="SLSQP", options={"ftol": 1e-15, "maxiter": 500})
        assert np.linalg.norm(slider[c] - best.x) < 1e-7, (c, slider[c], best.x)
        w = slider[c].copy()
        for j in range(N):
            w, st = slider_update(w, q[j, c], rho[j, c])
        assert np.linalg.norm(w - slider[c]) < 1e-12
    assert slider[1] == pytest.approx([1.0 - np.sqrt(0.5**2 - 0.45**2), 0.0], abs=1e-12)
    assert np.abs(force - (q - slider[None])).max() < 1e-12


def test_stuck_slider_jacobian_matches_finite_differences():
    """The mean rows carry ∂w₀/∂X of the stuck gauge (one active disk; a corner of two): central
    differences of λ̃_t in every harmonic of q̃ and of λ̃_n (λ_n = λ_n0 + 10 w)."""
    Q, L = stuck_orbits()
    _, _, _, _, J = stuck_forces(Q, L, True)
    step = 1e-7
    for h in range(2 * H + 1):
        for l in range(3):
            plus, minus = (Q.copy(), L.copy()), (Q.copy(), L.copy())
            if l:
                plus[0][h, :, l - 1] += step
                minus[0][h, :, l - 1] -= step
            else:
                plus[1][h] += 10 * step
                minus[1][h] -= 10 * step
            column = (hm.harmonic_coefficients(stuck_forces(*plus)[0], H)
                      - hm.harmonic_coefficients(stuck_forces(*minus)[0], H)) / (2 * step)
            for c in range(2):
                analytic = J[c, :, 3 * h + l].reshape(2 * H + 1, 3)[:, 1:]
                assert np.abs(analytic - column[:, c]).max() < 1e-6, (h, l, c)
