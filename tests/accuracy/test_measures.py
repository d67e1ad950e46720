"""The measures of a solution change (sarfe.accuracy.measures): spectral tail and energy per
harmonic on closed-form spectra, and the level change 10 log₁₀(P'/P) of P = Σ_k (kω)² |w_k|²."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.accuracy.measures import (erp_proxy, harmonic_energy, resize_harmonics,
                                     solution_change, spectral_tail)
from sarfe.hbm import make_contact_set


def test_spectral_tail_and_energy():
    X = np.zeros((2 * 4 + 1, 1))
    X[1], X[8] = 1.0, 0.1          # k = 1 cos, k = 4 sin
    assert spectral_tail(X) == pytest.approx(0.1 / np.hypot(1, 0.1))
    e = harmonic_energy(X)
    assert e.tolist() == pytest.approx([0, 1, 0, 0, 0.01])
    assert spectral_tail(np.zeros((5, 2))) == 0.0


def test_change_of_a_scaled_response_is_its_level():
    """ũ' = 2ũ: the contact amplitude changes by 100 %, the ERP (∝ |ũ|²) by 20 log₁₀ 2 = 6.02 dB,
    weighted or not; a third harmonic adds (3ω)² |u₃|² to P."""
    omega = 2 * np.pi * 100.0
    U = np.zeros((2 * 3 + 1, 2))
    U[1] = [1e-3, 2e-3]
    contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]],
                                gap=1.0, normal_stiffness=100.0)
    rel, db = solution_change(contacts, U, 2 * U, omega, None, None)
    assert rel == pytest.approx(1.0) and db == pytest.approx(20 * np.log10(2.0))
    V = U.copy()
    V[5] = [1e-4, 0.0]              # k = 3 cos on DOF 1
    p, q = erp_proxy(U, omega), erp_proxy(V, omega)
    assert q - p == pytest.approx((3 * omega) ** 2 * 1e-8)
    assert resize_harmonics(V, 1).shape == (3, 2) and resize_harmonics(U, 5)[7:].sum() == 0.0
