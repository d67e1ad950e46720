"""The Newton linear solve with the unit columns of the condensed Jacobian eliminated first (rows
without contact stiffness: ∂R_c/∂r̃_i = e_i) equals the plain LU solve, in a fixed-ω Newton and in
the bordered system of the continuation (whose extra row fills those columns), and still reports
a singular matrix."""
import numpy as np
import pytest

from sarfe.hbm.newton import SingularJacobian, solve_linear


def condensed_jacobian(n=60, unit=(3, 4, 10, 11, 12, 40, 41, 59), seed=0):
    """J = I + C J_λ with the columns ``unit`` of J_λ zero (open contact rows)."""
    rng = np.random.default_rng(seed)
    C = rng.normal(size=(n, n)) / n
    J_lam = rng.normal(size=(n, n))
    J_lam[:, list(unit)] = 0.0
    return np.eye(n) + C @ J_lam, np.array(unit)


def test_fixed_frequency_step_equals_the_plain_solve():
    J, unit = condensed_jacobian()
    b = np.random.default_rng(1).normal(size=J.shape[0])
    x = solve_linear(J, b, unit)
    assert np.abs(x - np.linalg.solve(J, b)).max() <= 1e-12 * np.abs(x).max()
    assert np.abs(J @ x - b).max() <= 1e-12 * np.abs(b).max()


def test_bordered_system_equals_the_plain_solve():
    J, unit = condensed_jacobian()
    rng = np.random.default_rng(2)
    x_scale, omega_scale = 3e-4, 40.0
    A = np.block([[J * x_scale, rng.normal(size=(J.shape[0], 1)) * omega_scale],
                  [rng.normal(size=(1, J.shape[0] + 1))]])
    b = rng.normal(size=A.shape[0])
    x = solve_linear(A, b, unit)
    assert np.abs(x - np.linalg.solve(A, b)).max() <= 1e-10 * np.abs(x).max()


def test_singular_reduced_block_is_reported():
    J, unit = condensed_jacobian()
    other = np.setdiff1d(np.arange(J.shape[0]), unit)
    J[other[1]] = J[other[0]]               # two equal rows of the loaded block
    J[other[1], unit] = 0.0
    J[other[0], unit] = 0.0
    with pytest.raises(SingularJacobian):
        solve_linear(J, np.ones(J.shape[0]), unit)
