r"""Hill stability of a periodic solution (Floquet exponents from the harmonic-balance Jacobian).

A perturbation y = e^{st} p(θ) of the periodic solution obeys the linearized periodic system; with
p in the same truncated Fourier basis (all kept DOFs), this is the quadratic eigenproblem

    ( s² M̃ + s D̃ + ∂R/∂ũ ) p̃ = 0,     M̃ = I⊗M,   D̃ = I⊗D + 2ω ∇⊗M + (I⊗G)ᵀ E diag(∂λ/∂ṙ) Φ (I⊗G),
    ∂R/∂ũ = S(ω) + (I⊗G)ᵀ ∂λ̃/∂r̃ (I⊗G)   (the Newton Jacobian on all DOFs),

the last term of D̃ (``contact_damping``) being the velocity terms of rate-dependent contact laws
(δṙ = s δr + ω ∂δr/∂θ; the ω∂/∂θ part is already in ∂λ̃/∂r̃),

solved in first-order form [[0, I], [−∂R/∂ũ, −D̃]] z = s [[I, 0], [0, M̃]] z: densely when
2(2H+1)n ≤ ``dense_limit``, else by sparse shift-invert (ARPACK, σ = 0) for the eigenvalues nearest
the origin. The (2H+1)·2n eigenvalues are the 2n Floquet exponents repeated with shifts i k ω plus
truncation artefacts; following Krack & Gross (2019, §3.6) we keep the 2n with the smallest |Im s|
(the ones whose eigenvectors are dominated by the low harmonics), plus any further eigenvalue in
the strip |Im s| ≤ 1.01 ω/2 (at a period-doubling the two exponents of a real multiplier pair and
their conjugates all sit near Im s = ±ω/2, ~0.2 % off with truncation, and compete for two places;
without this the unstable one was dropped on NLvib example 03). The solution is stable when the
largest real part of the kept exponents ≤ tolerance · ω. For the hysteretic Jenkins element the
Jacobian of the harmonic map is the linearization used (stick = spring k_t).

Caveat (nonsmooth contact): the AFT Jacobian jumps when a sample crosses a kink, so det ∂R/∂ũ can
change sign without a fold; on NLvib 03 two of ~30 points of the unstable middle branch come out
"stable" (leading exponent ≈ −0.004/s). Time integration agreed with the verdict at the points
checked away from bifurcations (Ω = 0.598 unstable, 0.702 stable, 0.7035 middle unstable).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .linear import hill_matrices


def floquet_exponents(model, omega, harmonics, jacobian, dense_limit=3000, max_exponents=120,
                      contact_damping=None):
    """Kept Floquet exponents s [1/s] (≥ 2n) of a solution, given ∂R/∂ũ (sparse or dense).

    On the sparse path at most ``max_exponents`` exponents nearest the origin are computed (all 2n
    representatives lie in the strip |Im s| ≤ ω/2, hence near 0; for 2n > max_exponents only the
    ones of the lowest modes are checked). contact_damping: (I⊗G)ᵀ E diag(∂λ/∂ṙ) Φ (I⊗G) or None.
    """
    n = model.dof_count
    Mt, Dt = hill_matrices(model, omega, harmonics)
    if contact_damping is not None:
        Dt = (Dt + sp.csr_matrix(contact_damping)).tocsr()
    size = Mt.shape[0]
    keep = 2 * n
    if 2 * size <= dense_limit:
        Minv = np.kron(np.eye(2 * harmonics + 1), np.linalg.inv(_dense(model.mass)))
        J = _dense(jacobian)
        A = np.block([[np.zeros((size, size)), np.eye(size)],
                      [-Minv @ J, -Minv @ _dense(Dt)]])
        values = np.linalg.eigvals(A)
    else:
        A = sp.bmat([[None, sp.identity(size)], [-sp.csr_matrix(jacobian), -Dt]], format="csc")
        B = sp.block_diag([sp.identity(size), Mt], format="csc")
        keep = min(keep, max_exponents)
        count = min(2 * size - 2, keep + max(20, keep // 2))
        values = spla.eigs(A, k=count, M=B, sigma=0.0, which="LM", return_eigenvectors=False)
    values = values[np.isfinite(values)]
    order = np.argsort(np.abs(values.imag), kind="stable")
    # the 2n with the smallest |Im s|, and every other one in the strip |Im s| ≤ ω/2: at a
    # period-doubling both exponents of a real multiplier pair sit at Im s = ±ω/2 and compete with
    # their conjugates for the same places
    in_strip = np.abs(values.imag[order]) <= 0.5 * abs(omega) * (1 + 1e-2)
    in_strip[:keep] = True
    return values[order[in_strip]]


def hill_stability(model, omega, harmonics, jacobian, tolerance=1e-6, dense_limit=3000,
                   contact_damping=None):
    """(stable, leading exponent max Re s [1/s]) of a periodic solution (see module docstring)."""
    try:
        values = floquet_exponents(model, omega, harmonics, jacobian, dense_limit,
                                   contact_damping=contact_damping)
    except (np.linalg.LinAlgError, RuntimeError, ValueError, spla.ArpackError):
        return None, float("nan")
    if values.size == 0:
        return None, float("nan")
    leading = float(values.real.max())
    return bool(leading <= tolerance * abs(omega)), leading


def _dense(matrix):
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix, dtype=float)
