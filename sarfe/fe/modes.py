"""Lowest natural frequencies of a (constrained) FE model — verification and quick looks.

K φ = ω² M φ on the free DOFs, solved by shift-invert Lanczos (ARPACK) around
σ = −(2π·shift_hz)²: (K − σM) is positive definite even for free-free models, so it is
factorized by sparse Cholesky (cholespy) with a SuperLU fallback. The reduction step
(``sarfe.reduction``) owns the production solvers; this is the small, self-contained check.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from .assembly import free_dofs

__all__ = ["natural_frequencies"]


def _inverse_operator(matrix):
    matrix = sp.csc_matrix(matrix)
    try:
        import cholespy

        factor = cholespy.CholeskySolverD(
            matrix.shape[0], matrix.indptr.astype(np.int32), matrix.indices.astype(np.int32),
            matrix.data.astype(np.float64), cholespy.MatrixType.CSC,
        )

        def solve(b):
            x = np.zeros(matrix.shape[0])
            factor.solve(np.ascontiguousarray(b, dtype=np.float64).ravel(), x)
            return x
    except (ImportError, ValueError, RuntimeError):
        lu = sla.splu(matrix, permc_spec="MMD_AT_PLUS_A")

        def solve(b):
            return lu.solve(np.asarray(b, dtype=np.float64).ravel())
    return sla.LinearOperator(matrix.shape, matvec=solve, dtype=np.float64)


def natural_frequencies(stiffness, mass, count=6, fixed=None, shift_hz=1.0, return_modes=False):
    """Lowest ``count`` natural frequencies [Hz] (ascending) of K φ = ω² M φ.

    stiffness, mass: sparse (n, n); fixed: DOF numbers held at zero (e.g. from
    :func:`sarfe.fe.fixed_dofs`). With ``return_modes`` also the mass-normalised mode
    shapes (n, count), zero on the fixed DOFs. Rigid-body modes appear as ≈ 0 Hz.
    """
    n = stiffness.shape[0]
    free = free_dofs(n, [] if fixed is None else fixed)
    k = sp.csr_matrix(stiffness)[free][:, free]
    m = sp.csr_matrix(mass)[free][:, free]
    sigma = -(2.0 * np.pi * shift_hz) ** 2
    operator = _inverse_operator(k - sigma * m)
    eigenvalues, vectors = sla.eigsh(k.tocsc(), count, m.tocsc(), sigma=sigma, which="LM",
                                     OPinv=operator)
    order = np.argsort(eigenvalues)
    frequencies = np.sqrt(np.maximum(eigenvalues[order], 0.0)) / (2.0 * np.pi)
    if not return_modes:
        return frequencies
    modes = np.zeros((n, count))
    modes[free] = vectors[:, order]
    return frequencies, modes
