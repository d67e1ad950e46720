"""The one σ = 0 block Lanczos (sarfe/reduction/lanczos.py) against closed forms.

An axial bar of linear two-node elements (consistent mass) whose two end nodes are the
Craig–Bampton boundary: the fixed-interface problem is the fixed–fixed bar with N interior
nodes, spacing h = L/(N + 1), whose discrete eigenpairs are known exactly,

    ω_j² = (6 E / (ρ h²)) (1 − cos θ_j) / (2 + cos θ_j),   θ_j = j π / (N + 1),
    φ_j(x_i) ∝ sin(j π x_i / L)                            (j = 1 … N).
"""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.linalg import factorize
from sarfe.reduction import craig_bampton
from sarfe.reduction.lanczos import m_orthonormal, shifted_block_lanczos

LENGTH, YOUNG, DENSITY, AREA = 1.0, 2.2e9, 1050.0, 1e-4      # m, Pa, kg/m³, m²
INTERIOR = 600                                               # N interior nodes


def bar(interior=INTERIOR):
    """Free–free bar K [N/m], M [kg] (CSR) on interior + 2 nodes, and the node positions [m]."""
    elements = interior + 1
    h = LENGTH / elements
    first, second = np.arange(elements), np.arange(1, elements + 1)
    rows = np.concatenate([first, first, second, second])
    cols = np.concatenate([first, second, first, second])
    unit = np.concatenate([np.ones(elements), -np.ones(elements), -np.ones(elements),
                           np.ones(elements)])
    consistent = np.concatenate([2 * np.ones(elements), np.ones(elements), np.ones(elements),
                                 2 * np.ones(elements)])
    size = (elements + 1, elements + 1)
    stiffness = sp.csr_matrix((YOUNG * AREA / h * unit, (rows, cols)), shape=size)
    mass = sp.csr_matrix((DENSITY * AREA * h / 6 * consistent, (rows, cols)), shape=size)
    return stiffness, mass, np.linspace(0.0, LENGTH, elements + 1)


def closed_form_omega2(count, interior=INTERIOR):
    """ω_j² [rad²/s²], j = 1 … count, of the fixed–fixed discrete bar (module docstring)."""
    h = LENGTH / (interior + 1)
    theta = np.arange(1, count + 1) * np.pi / (interior + 1)
    return 6 * YOUNG / (DENSITY * h ** 2) * (1 - np.cos(theta)) / (2 + np.cos(theta))


@pytest.mark.parametrize("mode_count, cutoff_hz", [(40, None), (None, 2.0e4), (12, 2.0e4),
                                                    (60, 2.0e4)])
def test_uncapped_block_lanczos_gives_the_bar_closed_form(mode_count, cutoff_hz):
    """Craig–Bampton's uncapped σ = 0 block Lanczos (no cap: n_i = 600 < 8e7/n_i) on the bar with
    its ends as boundary: the fixed–fixed closed form to 1e-10 relative in ω², with mode_count
    only (40 modes), cutoff only (every mode ≤ 20 kHz: 27 of them), and both (the first
    min(mode_count, N(cutoff))); Φᵀ M_ii Φ = I and each mode the sampled sine sin(j π x / L)."""
    stiffness, mass, x = bar()
    reduced = craig_bampton(stiffness, mass, [0, INTERIOR + 1], mode_count=mode_count,
                            cutoff_hz=cutoff_hz)
    assert reduced.timings["eigensolver"] == "block"               # not the ARPACK fallback
    exact = closed_form_omega2(INTERIOR)
    below = np.count_nonzero(exact <= (2 * np.pi * cutoff_hz) ** 2) if cutoff_hz else INTERIOR
    count = min(mode_count if mode_count is not None else INTERIOR, below)
    assert cutoff_hz is None or below == 27
    omega2 = (2 * np.pi * reduced.mode_frequencies_hz) ** 2
    assert len(omega2) == count
    np.testing.assert_allclose(omega2, exact[:count], rtol=1e-10, atol=0)
    phi = reduced.fixed_interface_modes
    m_ii = mass[1:-1][:, 1:-1]
    np.testing.assert_allclose(phi.T @ (m_ii @ phi), np.eye(count), atol=1e-10)
    sines = np.sin(np.outer(x[1:-1], np.arange(1, count + 1)) * np.pi / LENGTH)
    cosines = np.abs(np.einsum("ij,ij->j", phi, m_ii @ sines)) / np.sqrt(
        np.einsum("ij,ij->j", sines, m_ii @ sines))
    np.testing.assert_allclose(cosines, 1.0, atol=1e-9)


def test_growing_store_and_sigma_zero_ritz_values():
    """shifted_block_lanczos at σ = 0 with room for only 24 columns (the store doubles as the run
    grows to ~100): the converged Ritz values are the bar's closed form to 1e-10, and the
    vectors M-orthonormal — the store's growth loses nothing."""
    stiffness, mass, _ = bar()
    k_ii, m_ii = stiffness[1:-1][:, 1:-1].tocsr(), mass[1:-1][:, 1:-1].tocsr()
    factor = factorize(k_ii, structure="spd")
    exact = closed_form_omega2(30)

    def satisfied(lam, converged):
        order = np.argsort(lam)
        return converged[order][:31].all()

    lam, converged, vectors = shifted_block_lanczos(m_ii, factor.solve, 0.0, satisfied,
                                                    INTERIOR, capacity=24)
    order = np.argsort(lam)[:30]
    assert len(lam) > 48 and converged[order].all()                 # grew at least twice
    np.testing.assert_allclose(lam[order], exact, rtol=1e-10, atol=0)
    phi = vectors(order)
    np.testing.assert_allclose(phi.T @ (m_ii @ phi), np.eye(30), atol=1e-10)


def test_m_orthonormal_drops_dependent_columns():
    """m_orthonormal: Qᵀ M Q = I on a block whose third column is the sum of the first two (rank
    2), and the returned M Q equals M times Q."""
    _, mass, _ = bar(20)
    block = np.random.default_rng(1).standard_normal((mass.shape[0], 2))
    block = np.column_stack([block, block.sum(axis=1)])
    q, mq = m_orthonormal(block, mass)
    assert q.shape[1] == 2
    np.testing.assert_allclose(q.T @ (mass @ q), np.eye(2), atol=1e-12)
    np.testing.assert_allclose(mq, mass @ q, rtol=0, atol=1e-12 * np.abs(mq).max())
