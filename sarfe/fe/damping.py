"""Linear damping models: Rayleigh on the full model, modal damping on the reduced model."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

__all__ = ["rayleigh_damping", "modal_damping"]


def rayleigh_damping(mass, stiffness, alpha, beta):
    """D = α M + β K (α [1/s], β [s]); sparse in → sparse CSR out, dense in → dense out.

    Modal damping ratio of mode i: ζ_i = α/(2ω_i) + β ω_i/2.
    """
    if alpha < 0 or beta < 0:
        raise ValueError("Rayleigh coefficients alpha and beta must be non-negative")
    if sp.issparse(mass) or sp.issparse(stiffness):
        return (alpha * sp.csr_matrix(mass) + beta * sp.csr_matrix(stiffness)).tocsr()
    return alpha * np.asarray(mass) + beta * np.asarray(stiffness)


def modal_damping(reduced_mass, reduced_stiffness, zeta):
    """Modal damping matrix D_r = M_r Φ diag(2 ζ_i ω_i) Φᵀ M_r of a (small, dense) model.

    Φ are the mass-normalised eigenvectors of K_r φ = ω² M_r φ (Φᵀ M_r Φ = I), so that
    Φᵀ D_r Φ = diag(2 ζ_i ω_i). zeta: scalar or (n,) per mode (ascending ω) [-].
    Rigid-body modes (ω² ≤ 0 up to round-off) get no damping. Returns dense (n, n).
    """
    m = reduced_mass.toarray() if sp.issparse(reduced_mass) else np.asarray(reduced_mass, float)
    k = (reduced_stiffness.toarray() if sp.issparse(reduced_stiffness)
         else np.asarray(reduced_stiffness, float))
    eigenvalues, modes = sl.eigh(k, m)
    n = eigenvalues.size
    zeta = np.asarray(zeta, dtype=float)
    if zeta.ndim == 0:
        zeta = np.full(n, float(zeta))
    if zeta.shape != (n,):
        raise ValueError(f"zeta must be a scalar or shaped ({n},), got {zeta.shape}")
    if np.any(zeta < 0):
        raise ValueError("damping ratios must be non-negative")
    tolerance = 1e-10 * max(abs(eigenvalues).max(), 1e-300)
    omega = np.sqrt(np.where(eigenvalues > tolerance, eigenvalues, 0.0))
    mass_modes = m @ modes
    damping = (mass_modes * (2.0 * zeta * omega)) @ mass_modes.T
    return 0.5 * (damping + damping.T)
