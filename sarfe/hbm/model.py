r"""The linear part of the equation of motion, M ü + D u̇ + K u (+ f_nl) = f_e, on the kept DOFs."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class LinearModel:
    """Mass M [kg], viscous damping D [N s/m] and stiffness K [N/m] on n kept DOFs, each (n, n).

    Dense ndarrays or scipy sparse matrices. Build with :func:`make_linear_model` to validate.
    """

    mass: object
    damping: object
    stiffness: object

    @property
    def dof_count(self) -> int:
        return self.mass.shape[0]


def _symmetric(matrix, name):
    dense = matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix, dtype=float)
    scale = np.abs(dense).max() if dense.size else 0.0
    if dense.size and np.abs(dense - dense.T).max() > 1e-9 * max(scale, 1e-300):
        raise ValueError(f"{name} must be symmetric")
    return dense


def make_linear_model(mass, damping, stiffness) -> LinearModel:
    """Validate and wrap (M, D, K). ``damping=None`` means D = 0.

    Raises ValueError naming the matrix for: non-square or inconsistent shapes, non-finite entries,
    non-symmetric matrices, a mass that is not positive definite, a stiffness or damping with a
    clearly negative eigenvalue (indefinite).
    """
    if mass is None or stiffness is None:
        raise ValueError("mass and stiffness are required")
    n = mass.shape[0] if hasattr(mass, "shape") else len(mass)
    if damping is None:
        damping = sp.csr_matrix((n, n)) if sp.issparse(stiffness) else np.zeros((n, n))
    matrices = {}
    for name, matrix in (("mass", mass), ("damping", damping), ("stiffness", stiffness)):
        if not sp.issparse(matrix):
            matrix = np.atleast_2d(np.asarray(matrix, dtype=float))
        if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1]:
            raise ValueError(f"{name} must be a square matrix, got shape {matrix.shape}")
        if matrix.shape[0] != n:
            raise ValueError(f"{name} has shape {matrix.shape}, expected ({n}, {n}) like mass")
        values = matrix.data if sp.issparse(matrix) else matrix
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{name} has non-finite entries")
        matrices[name] = matrix
    if n <= 2000:  # cheap dense checks on reduced models; large sparse models are checked upstream
        for name in ("mass", "damping", "stiffness"):
            dense = _symmetric(matrices[name], name)
            eigenvalues = np.linalg.eigvalsh(dense) if n else np.zeros(0)
            scale = np.abs(eigenvalues).max() if n else 0.0
            if name == "mass" and (n and eigenvalues.min() <= 1e-12 * max(scale, 1e-300)):
                raise ValueError("mass must be symmetric positive definite")
            if name != "mass" and n and eigenvalues.min() < -1e-9 * max(scale, 1e-300):
                raise ValueError(f"{name} must be positive semi-definite (has a negative eigenvalue)")
    return LinearModel(matrices["mass"], matrices["damping"], matrices["stiffness"])
