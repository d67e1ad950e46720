"""The A-weighted ERP level as a quadratic form (sarfe.erp.level_sensitivity): the level of
sarfe.erp.erp and its exact gradient."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.erp.erp import equivalent_radiated_power
from sarfe.erp.level_sensitivity import a_weighted_level


def random_case(seed=3, H=5, n=7, n_s=11):
    rng = np.random.default_rng(seed)
    U = rng.normal(size=(2 * H + 1, n)) * 1e-5
    N = rng.normal(size=(n_s, n))
    areas = rng.uniform(0.01, 0.1, n_s)
    return U, N, areas


def test_level_is_the_erp_level_and_the_gradient_is_exact():
    """L_A equals equivalent_radiated_power's A-weighted total (1e-12 dB); ∂L_A/∂ũ equals central
    differences along random directions (L_A is smooth: 10 log10 of a positive quadratic form),
    for a dense and a sparse map."""
    U, N, areas = random_case()
    omega = 2 * np.pi * 80.0
    level, gradient = a_weighted_level(U, omega, N, areas, density=1.2, sound_speed=340.0,
                                       radiation_loss_factor=0.5)
    reference = equivalent_radiated_power(U @ N.T, omega, areas, density=1.2, sound_speed=340.0,
                                          radiation_loss_factor=0.5).level_total_a_db
    assert level == pytest.approx(reference, abs=1e-12)
    assert np.all(gradient[0] == 0.0)                      # the static term does not radiate
    rng = np.random.default_rng(7)
    for _ in range(3):
        direction = rng.normal(size=U.shape) * 1e-5
        h = 1e-4
        fd = (a_weighted_level(U + h * direction, omega, N, areas)[0]
              - a_weighted_level(U - h * direction, omega, N, areas)[0]) / (2 * h)
        assert np.sum(gradient * direction) == pytest.approx(fd, rel=1e-7)
    sparse_level, sparse_gradient = a_weighted_level(U, omega, sp.csr_matrix(N), areas,
                                                     density=1.2, sound_speed=340.0,
                                                     radiation_loss_factor=0.5)
    assert sparse_level == pytest.approx(level, abs=1e-12)
    np.testing.assert_allclose(sparse_gradient, gradient, rtol=1e-12)


def test_silent_surface():
    U, N, areas = random_case()
    level, gradient = a_weighted_level(np.zeros_like(U), 100.0, N, areas)
    assert level == -np.inf and np.all(np.isnan(gradient))
