"""The cold-start guess of a dense (reduced) model is solved harmonic by harmonic in complex form;
it must equal the assembled real (2H+1)n system that sparse models solve (ω∇⊗D couples cos and
sin of each order), with closed contacts, preloads and a harmonic set."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.solve import linearized_guess, make_problem


@pytest.mark.parametrize("harmonic_set", [None, [1, 3]])
def test_dense_guess_equals_the_assembled_real_system(harmonic_set):
    rng = np.random.default_rng(0)
    n, H = 12, 4
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    M = np.eye(n) + 0.1 * np.diag(rng.random(n))
    D = 0.01 * K + 0.02 * M
    G = sp.csr_matrix(rng.standard_normal((3, n)))
    contacts = make_contact_set(G, ["rattle"] * 3, [0, 1, 2], [[-1, -1]] * 3,
                                np.array([-1e-3, 1.0, -2e-3]), 1e3)   # two closed at u = 0
    F = rng.standard_normal((2 * H + 1, n))
    dense = make_problem(make_linear_model(M, D, K), contacts, F, H, 64,
                         harmonic_set=harmonic_set)
    sparse = make_problem(make_linear_model(*(sp.csr_matrix(a) for a in (M, D, K))), contacts, F,
                          H, 64, harmonic_set=harmonic_set)
    U_dense, U_sparse = linearized_guess(dense, 1.3), linearized_guess(sparse, 1.3)
    assert np.abs(U_dense).max() > 0
    np.testing.assert_allclose(U_dense, U_sparse, atol=1e-12 * np.abs(U_sparse).max())
