"""Every available backend solves a random SPD system like SciPy's SuperLU, with one or many RHS."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.reduction import available_solvers, choose_solver, factorize


def random_spd(n=400, seed=1):
    """Sparse SPD: a random sparse B, A = Bᵀ B + n·I-like diagonal dominance."""
    rng = np.random.default_rng(seed)
    b = sp.random(n, n, density=8 / n, random_state=rng, format="csr")
    return (b.T @ b + sp.diags(1.0 + rng.random(n))).tocsr()


@pytest.mark.parametrize("solver", available_solvers())
def test_backends_agree_with_superlu(solver):
    a = random_spd()
    rng = np.random.default_rng(2)
    rhs = rng.standard_normal((a.shape[0], 7))
    reference = factorize(a, solver="superlu").solve(rhs)
    assert np.linalg.norm(a @ reference - rhs) < 1e-10 * np.linalg.norm(rhs)
    factor = factorize(a, solver=solver)
    assert factor.name == solver
    block = factor.solve(rhs)
    assert block.shape == rhs.shape
    np.testing.assert_allclose(block, reference, rtol=0, atol=1e-10 * np.abs(reference).max())
    single = factor.solve(rhs[:, 3])
    assert single.shape == (a.shape[0],)
    np.testing.assert_allclose(single, reference[:, 3], rtol=0, atol=1e-10 * np.abs(reference).max())
    complex_rhs = rhs[:, :2] + 1j * rhs[:, 2:4]
    np.testing.assert_allclose(factor.solve(complex_rhs), reference[:, :2] + 1j * reference[:, 2:4],
                               rtol=0, atol=1e-10 * np.abs(reference).max())


def test_many_rhs_in_blocks():
    """More columns than one backend call takes (blocks of 128) give the same answer."""
    a = random_spd(200)
    rhs = np.random.default_rng(3).standard_normal((200, 300))
    x = factorize(a).solve(rhs)
    assert np.linalg.norm(a @ x - rhs) < 1e-10 * np.linalg.norm(rhs)


@pytest.mark.parametrize("solver", [s for s in available_solvers() if s != "cholespy"])
def test_symmetric_indefinite(solver):
    """A shifted stiffness K − σM (indefinite) is solved by pardiso (mtype −2) and SuperLU."""
    a = random_spd() - 3.0 * sp.eye(400)
    rhs = np.random.default_rng(4).standard_normal(400)
    x = factorize(a, solver=solver, structure="symmetric").solve(rhs)
    assert np.linalg.norm(a @ x - rhs) < 1e-9 * np.linalg.norm(rhs)


def test_cholespy_rejects_indefinite():
    if "cholespy" not in available_solvers():
        pytest.skip("cholespy not installed")
    with pytest.raises(ValueError):
        factorize(random_spd() - 50.0 * sp.eye(400), solver="cholespy")
    with pytest.raises(ValueError):
        factorize(random_spd(), solver="cholespy", structure="symmetric")


def test_auto_and_complex_matrix():
    assert choose_solver("spd") == available_solvers()[0]
    a = random_spd(100) * (1 + 0.1j)
    rhs = np.ones(100)
    factor = factorize(a)
    assert factor.name == "superlu"
    assert np.linalg.norm(a @ factor.solve(rhs) - rhs) < 1e-10 * 10
