"""The friction-memory term of Hill's operator: the vectorized 1-D form equals the sample march."""
import numpy as np
import pytest

from sarfe.hbm.stability_contacts import _memory_block, _memory_block_1d, _slider_march


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
