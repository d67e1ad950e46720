r"""Fixed-interface modes by ARPACK (``scipy.sparse.linalg.eigsh``), the fallback of the block Lanczos.

Single-vector shift-invert Lanczos at σ = 0 with OPinv = K_ii⁻¹ on K_ii φ = ω² M_ii φ: ARPACK
iterates on OP = K_ii⁻¹ M_ii and returns λ = 1/ν. For a cutoff frequency the modes are found in
blocks of ``_MODE_BLOCK``, each run on the operator deflated of the modes already found,

    OP_j = (I − Φ Φᵀ M_ii) K_ii⁻¹ M_ii,

until the highest frequency found exceeds the cutoff. Craig–Bampton uses it when asked
(``eigensolver="arpack"``) and when the block Lanczos cannot run (a tiny interior whose Krylov
space fills before the wanted modes converge). Kept apart from :mod:`sarfe.reduction.lanczos`: a
different algorithm (ARPACK's implicitly restarted single-vector Lanczos, its own convergence
test) with nothing in common with the block engine but the operator.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

_MODE_BLOCK = 24  # fixed-interface modes requested per ARPACK run when searching up to a cutoff


def arpack_modes(stiffness_ii, mass_ii, operator, mode_count, cutoff_hz, progress, seed=0):
    """Lowest modes of K_ii φ = ω² M_ii φ via shift-invert (σ = 0) Lanczos, in blocks when cut off.

    stiffness_ii, mass_ii: (n_i, n_i) sparse K_ii [N/m], M_ii [kg] (eigsh uses K_ii for its shape
    only); operator(y) = K_ii⁻¹ y; mode_count: modes wanted (None: all up to the cutoff);
    cutoff_hz [Hz] or None; progress(found, mode_count) after each run, or None.
    Returns ω² (n_m,) [rad²/s²] ascending and Φ (n_i, n_m) with Φᵀ M_ii Φ = I.
    """
    n = mass_ii.shape[0]
    rng = np.random.default_rng(seed)
    eigenvalues = np.empty(0)
    modes = np.empty((n, 0))
    target = mode_count if mode_count is not None else np.inf
    cutoff_omega2 = (2 * np.pi * cutoff_hz) ** 2 if cutoff_hz is not None else np.inf
    while True:
        want = int(min(target - len(eigenvalues), _MODE_BLOCK if cutoff_hz is not None else target,
                       n - len(eigenvalues) - 2))
        if want <= 0:
            break
        found = modes

        def deflated(y, found=found):
            x = operator(y)
            if found.shape[1]:
                x = x - found @ (found.T @ (mass_ii @ x))  # project out found modes (M-orthogonal)
            return x

        opinv = spla.LinearOperator((n, n), matvec=deflated, dtype=float)
        start = rng.standard_normal(n)
        if found.shape[1]:
            start -= found @ (found.T @ (mass_ii @ start))
        values, vectors = spla.eigsh(stiffness_ii, k=want, M=mass_ii, sigma=0.0, OPinv=opinv, which="LM", v0=start)
        # with OPinv given, eigsh only uses A for its shape; eigenvalues are λ = σ + 1/ν of OP = OPinv M
        order = np.argsort(values)
        values, vectors = values[order], vectors[:, order]
        scale = np.sqrt(np.einsum("ij,ij->j", vectors, mass_ii @ vectors))
        eigenvalues = np.concatenate([eigenvalues, values])
        modes = np.hstack([modes, vectors / scale])
        if progress is not None:
            progress(len(eigenvalues), mode_count)
        if cutoff_hz is None or values[-1] > cutoff_omega2:
            break
    order = np.argsort(eigenvalues)
    eigenvalues, modes = eigenvalues[order], modes[:, order]
    if cutoff_hz is not None:
        keep = eigenvalues <= cutoff_omega2
        if mode_count is not None:
            keep &= np.arange(len(eigenvalues)) < mode_count
        eigenvalues, modes = eigenvalues[keep], modes[:, keep]
    return eigenvalues, modes
