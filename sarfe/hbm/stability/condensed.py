r"""Hill stability without the eigen-solve of the full reduced Hill matrix: Hill's problem on a
bounded Ritz basis that keeps the contacts exact.

Hill's operator (:mod:`sarfe.hbm.stability.hill`) is T(s) = T_lin(s) + (I⊗G)ᵀ 𝒥(s) (I⊗G): the linear
structure, block diagonal over the harmonics, plus the contact term on the (2H+1)·n_rows contact
rows (the AFT Jacobian, the Jenkins memory at s, s × the contact damping of rate-dependent laws).
The exponents that decide stability are those nearest the imaginary axis; they live in the
low-frequency motion of the structure loaded by the contacts. With u = Ψ q,

    Ψ = orth[ Φ_m , K̄⁻¹ Gᵀ ],   K̄ = K + Gᵀ 𝒥̄ G   (𝒥̄: mean contact stiffness, harmonic 0),

Φ_m the modes of (M, K̄) up to 2(H+1)ω (10 … 40 of them) and K̄⁻¹Gᵀ the static responses to unit
contact forces (the local flexibility a stiff contact sees), T(s) is projected to
(I⊗Ψ)ᵀ T(s) (I⊗Ψ): the same Hill problem — frozen exponents, friction-memory refinement, strip
selection, notes — of order 2(2H+1)(m + n_rows), whatever the FE and reduced model size. The
contacts act on G Ψ exactly; only the linear structure's high modes are truncated (their static
part is kept by the attachment vectors). When m + n_rows ≥ n, Ψ = I and the result is the full one.
Measured against the full Hill method in tests/hbm/stability/test_stability_condensed.py and
benchmarks/bench_stability.py.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from sarfe.hbm.aft import jacobian_matrix
from sarfe.hbm.dynamic_stiffness import dynamic_stiffness_matrix
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.stability.hill import hill_stability


def _dense(matrix):
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)


def ritz_basis(model, gap_map, mean_jacobian, omega, harmonics, max_modes=40, min_modes=10):
    r"""Ψ (n, r), orthonormal columns: the modes of the averaged linearization (M, K + Gᵀ 𝒥̄ G)
    up to 2(H+1)ω (at least ``min_modes``, at most ``max_modes``) and the static responses
    K̄⁻¹ Gᵀ to unit contact forces (the contacts' local flexibility); Ψ = I when r ≥ n."""
    M, K = (_dense(a).astype(float) for a in (model.mass, model.stiffness))
    n = M.shape[0]
    G = _dense(gap_map).astype(float)
    if min_modes + G.shape[0] >= n:
        return np.eye(n)
    K = K + G.T @ np.real(_dense(mean_jacobian)) @ G
    K = 0.5 * (K + K.T)
    values, vectors = la.eigh(K, M)
    frequencies = np.sqrt(np.abs(values))
    m = int(np.clip(np.count_nonzero(frequencies <= 2 * (harmonics + 1) * abs(omega)),
                    min_modes, max_modes))
    static = la.solve(K, G.T)
    basis, _ = la.qr(np.hstack([vectors[:, :m], static]), mode="economic")
    return basis if basis.shape[1] < n else np.eye(n)


class _ProjectedOperator:
    """The contact term's s-dependence (:class:`ContactOperator`) seen in the Ritz basis."""

    def __init__(self, operator, gap_projected, harmonics):
        self.operator, self.has_memory = operator, operator.has_memory
        self.gap, self.P = np.asarray(gap_projected), 2 * harmonics + 1

    def correction(self, s):
        """(I⊗G_Ψ)ᵀ Δ𝒥(s) (I⊗G_Ψ) (CSR): G_Ψ = GΨ is dense, so the product is formed densely per
        harmonic block pair (a sparse triple product of the same took 0.4 s at H = 15)."""
        return sp.csr_matrix(self.dense_correction(s))

    def dense_correction(self, s):
        """:meth:`correction` as an ndarray (the Hill matrix of a Ritz basis is dense)."""
        return _project_rows(self.operator.rows_correction(s), self.gap, self.P)


def _project_rows(rows_matrix, gap, P):
    """(I⊗G)ᵀ X (I⊗G) for X ((P n_rows)², harmonic-major, sparse or dense) and G (n_rows, r)
    dense: ((P r)², dense)."""
    n_rows, r = gap.shape
    X = _dense(rows_matrix).reshape(P, n_rows, P, n_rows)
    return np.einsum("ia,hikj,jb->hakb", gap, X, gap, optimize=True).reshape(P * r, P * r)


def condensed_stability(model, contacts, omega, harmonics, forces, operator=None, tolerance=1e-6,
                        max_modes=40):
    """Hill stability on the Ritz basis of :func:`ritz_basis` → StabilityResult (the exponents,
    verdict and notes of :func:`sarfe.hbm.stability.hill.hill_stability` on the projected problem).

    forces: the AFT :class:`ContactForces` of the orbit (all harmonic rows); operator: the
    :class:`ContactOperator` (friction memory), or None."""
    nr, H = contacts.row_count, int(harmonics)
    base = jacobian_matrix(forces.blocks, nr, H)
    basis = ritz_basis(model, contacts.gap_map, base[:nr, :nr].toarray(), omega, H, max_modes)
    project = lambda a: basis.T @ _dense(a) @ basis  # noqa: E731
    reduced = make_linear_model(project(model.mass), project(model.damping),
                                project(model.stiffness))
    G_p = _dense(contacts.gap_map) @ basis
    jacobian = (_dense(dynamic_stiffness_matrix(reduced, omega, H))    # dense: G_p couples all
                + _project_rows(base, G_p, 2 * H + 1))                  # harmonics on the contacts
    damping = sp.csr_matrix(_project_rows(jacobian_matrix(forces.damping_blocks, nr, H), G_p,
                                          2 * H + 1)) if forces.damping_blocks else None
    projected = None if operator is None else _ProjectedOperator(operator, G_p, H)
    return hill_stability(reduced, omega, H, jacobian, tolerance,
                          contact_damping=damping, operator=projected)
