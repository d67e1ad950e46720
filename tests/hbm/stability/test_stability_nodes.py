"""The initial nodes of the contact-row count's contour (sarfe.hbm.stability.contour.upper_contour):
every step keeps every pole of det F at least half a step away — so a pole turns arg det F by at
most 2 atan(1) = π/2 over a step — checked against the distance of each pole to each step computed
by brute force, and the closed-form vertical step against a brute-force search."""
import numpy as np

from sarfe.hbm.stability.contour import _left_step, shifted_exponents, upper_contour, winding_count
from sarfe.hbm.stability.determinant import structural_exponents


def segment_distance(poles, a, b, samples=4001):
    """min over the points of the segment [a, b] of |p − point| per pole, by dense sampling."""
    t = np.linspace(0.0, 1.0, samples)
    return np.abs(poles[:, None] - (a + t * (b - a))[None]).min(axis=1)


def lightly_damped_poles(omega=100.0, harmonics=5, seed=3):
    """Shifted exponents of 40 modes (2…60 Hz·2π … a few kHz), modal damping 0.3…5 %."""
    rng = np.random.default_rng(seed)
    w = np.sort(rng.uniform(15.0, 3000.0, 40))
    zeta = rng.uniform(0.003, 0.05, 40)
    structure = structural_exponents(1.0 / w ** 2, 2.0 * zeta / w)
    return shifted_exponents(structure, omega, harmonics)


def test_left_step_is_the_largest_step_that_keeps_every_pole_half_a_step_away():
    poles = lightly_damped_poles()
    epsilon = 1e-2
    for y in (50.5, 31.0, 7.3, 0.4):
        L = _left_step(y, epsilon, poles)
        start = -epsilon + 1j * y
        assert L <= 2.0 * segment_distance(poles, start, start - 1j * L).min() * (1 + 1e-6)
        longer = 1.02 * L          # 2 % longer: some pole comes closer than half the step
        assert longer > 2.0 * segment_distance(poles, start, start - 1j * longer).min()


def test_every_contour_step_keeps_the_poles_half_a_step_away():
    omega, epsilon = 100.0, 1e-2
    poles = lightly_damped_poles(omega)
    top, X = 0.505 * omega, 5e4
    nodes = upper_contour(epsilon, X, top, poles)
    assert nodes[0] == X and nodes[1] == X + 1j * top and nodes[-1] == -epsilon
    steps = np.abs(np.diff(nodes))
    left = np.isclose(nodes[:-1].real, -epsilon) & np.isclose(nodes[1:].real, -epsilon)
    for a, b, L, on_left in zip(nodes[:-1], nodes[1:], steps, left):
        if a.real == X and b.real == X:          # the right edge: by its ends
            continue
        if on_left and L <= top / 64 * (1 + 1e-9):  # the floor of the left steps
            continue
        assert L <= 2.0 * segment_distance(poles, a, b).min() * (1 + 1e-6), (a, b)
    assert left.sum() <= 64


def test_the_count_on_these_nodes_finds_the_zeros_between_the_poles():
    """f(s) = (s − z)(s − z̄)(s − z₂)/((s − q)(s − q̄)(s − q₂)) · Π_p (s − p')/(s − p), a zero p'
    beside every pole p of the lightly damped structure (at twice its damping: det F → 1 for
    |s| → ∞ as here), z = 0.5 + 30i right of −ε: the count on the contour of
    Ω = {−ε < Re s < X, |Im s| < top} finds z and z̄ (the upper half counts both) and nothing of
    the 1240 poles and zeros left of the line (densely sampled: the same)."""
    omega, epsilon = 100.0, 1e-2
    poles = lightly_damped_poles(omega)
    partners = 2.0 * poles.real + 1j * poles.imag
    top, X = 0.505 * omega, 5e4
    zeros = np.array([0.5 + 30j, 0.5 - 30j, -3.0])
    far = np.array([-50.0 + 10j, -50.0 - 10j, -60.0])

    def log_det(s):
        s = np.asarray(s)[:, None]
        return (np.log(s - zeros).sum(axis=1) - np.log(s - far).sum(axis=1)
                + np.log(s - partners).sum(axis=1) - np.log(s - poles).sum(axis=1))

    above, below = np.concatenate([zeros, partners]), np.concatenate([far, poles])

    def arg_det(s):
        """arg f(s) = Im log f(s) mod 2π from the product of the factors, by chunks of ~1000
        points: one complex angle per point instead of 2 × 883 logs (the dense check's 42,003
        points took 6 s and 0.6 GB temporaries); the wrapped steps below are the same (6e-13)."""
        return np.concatenate([np.angle(np.prod((c[:, None] - above) / (c[:, None] - below), axis=1))
                               for c in np.array_split(np.asarray(s), max(1, len(s) // 1000))])

    nodes = upper_contour(epsilon, X, top, poles)
    count, _ = winding_count(log_det, nodes)
    assert abs(count - 2.0) < 1e-6
    fine = np.concatenate([X + 1j * np.linspace(0.0, top, 2001),
                           np.geomspace(X + epsilon, 1e-3, 20001) - epsilon + 1j * top,
                           -epsilon + 1j * np.linspace(top, 0.0, 20001)])
    assert abs(np.angle(np.exp(1j * np.diff(arg_det(fine)))).sum() / np.pi - 2.0) < 1e-6
