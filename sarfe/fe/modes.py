"""Lowest natural frequencies of a (constrained) FE model — verification and quick looks.

K φ = ω² M φ on the free DOFs, solved by shift-invert Lanczos (ARPACK) around
σ = −(2π·shift_hz)²: (K − σM) is positive definite even for free-free models, so it is
factorized by ``sarfe.linalg.factorize`` (PARDISO, cholespy or SuperLU, whichever is there).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from sarfe.fe.assembly import free_dofs
from sarfe.linalg import factorize

__all__ = ["natural_frequencies"]


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
    operator = factorize(k - sigma * m, structure="spd").as_operator()   # K − σM, σ < 0: SPD
    start = np.random.default_rng(0).standard_normal(k.shape[0])   # fixed: repeatable runs
    eigenvalues, vectors = sla.eigsh(k.tocsc(), count, m.tocsc(), sigma=sigma, which="LM",
                                     OPinv=operator, v0=start)
    order = np.argsort(eigenvalues)
    frequencies = np.sqrt(np.maximum(eigenvalues[order], 0.0)) / (2.0 * np.pi)
    if not return_modes:
        return frequencies
    modes = np.zeros((n, count))
    modes[free] = vectors[:, order]
    return frequencies, modes
