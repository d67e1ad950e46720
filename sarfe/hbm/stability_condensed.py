r"""Floquet exponents on the contact rows: Hill's problem condensed through the linear structure.

Hill's operator (:mod:`sarfe.hbm.stability`) is T(s) = T_lin(s) + (I⊗G)ᵀ 𝒥(s) (I⊗G) with the
linear part T_lin(s) = s² M̃ + s D̃ + S(ω), block diagonal over the harmonics, and the contact term
𝒥(s) on the (2H+1)·n_rows contact rows (the AFT Jacobian, Jenkins memory at s, and s × the contact
damping of rate-dependent laws). Its eigenvalues away from the linear ones are the roots of

    T_c(s) r̃ = ( I + C(s) 𝒥(s) ) r̃ = 0,     C(s) = (I⊗G) T_lin(s)⁻¹ (I⊗G)ᵀ,

a nonlinear eigenproblem of the contact-row size, whatever the FE size. Harmonic k of T_lin is
I₂⊗A + J₂⊗B (J₂ = [[0, 1], [−1, 0]]) with A ± iB = Z(s ± ikω), Z(λ) = λ²M + λD + K, so

    C_k(s) = I₂⊗½(Y₊ + Y₋) + J₂⊗(Y₊ − Y₋)/(2i),   Y± = G Z(s ± ikω)⁻¹ Gᵀ,

and G Z(λ)⁻¹ Gᵀ = L diag(1/(λ − μ_j)) R from one state-space eigen-decomposition of (M, D, K) per
model (μ_j its 2n eigenvalues, L = G X_u, R = (X⁻¹)_v M⁻¹ Gᵀ): no factorization per point or per s.

Roots are found by Newton on the eigenvalue ν(s) of T_c(s) of smallest modulus,
s ← s − ν/ν′ with ν′ = yᴴ T_c′ x / yᴴx (left/right eigenvectors; T_c′ by a central difference),
from a bounded set of starts: the ``modes`` exponents of the averaged linearization
(M, D, K + Gᵀ 𝒥̄ G), 𝒥̄ the mean (harmonic 0) contact stiffness, shifted into the strip
|Im s| ≤ ω/2 and taken nearest the imaginary axis, plus the previous point's exponents. Only those
exponents are seen — the ones that decide the verdict when the starts are near them; the choice is
measured against the full Hill result in tests/hbm/test_stability_condensed.py.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

_RESOLVENTS: dict = {}


def _dense(matrix):
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)


class ModalResolvent:
    """G Z(λ)⁻¹ Gᵀ = L diag(1/(λ − μ)) R of a linear model (module docstring); poles μ (2n,)."""

    def __init__(self, model, gap_map):
        M, D, K = (_dense(a).astype(float) for a in (model.mass, model.damping, model.stiffness))
        n = M.shape[0]
        Minv = la.inv(M)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
        self.poles, X = la.eig(A)
        G = _dense(gap_map).astype(float)
        Xinv = la.inv(X)
        self.left = G @ X[:n]                        # (n_rows, 2n)
        self.right = Xinv[:, n:] @ Minv @ G.T        # (2n, n_rows)
        self.model, self.gap_map = model, gap_map

    def __call__(self, lam):
        """G Z(λ)⁻¹ Gᵀ (n_rows, n_rows) complex."""
        return (self.left / (lam - self.poles)) @ self.right


def resolvent(model, gap_map):
    """The :class:`ModalResolvent` of (model, gap_map), cached per model object."""
    key = (id(model), id(gap_map))
    hit = _RESOLVENTS.get(key)
    if hit is None or hit.model is not model or hit.gap_map is not gap_map:
        if len(_RESOLVENTS) > 8:
            _RESOLVENTS.clear()
        hit = _RESOLVENTS[key] = ModalResolvent(model, gap_map)
    return hit


def compliance(res, s, omega, harmonics):
    """C(s) ((2H+1) n_rows square, complex, harmonic-major) of the module docstring."""
    nr = res.left.shape[0]
    P = 2 * harmonics + 1
    C = np.zeros((P * nr, P * nr), complex)
    C[:nr, :nr] = res(s)
    for k in range(1, harmonics + 1):
        plus, minus = res(s + 1j * k * omega), res(s - 1j * k * omega)
        even, odd = 0.5 * (plus + minus), (plus - minus) / 2j
        c, si = slice((2 * k - 1) * nr, 2 * k * nr), slice(2 * k * nr, (2 * k + 1) * nr)
        C[c, c], C[si, si], C[c, si], C[si, c] = even, even, odd, -odd
    return C


def _smallest(T):
    """(ν, x, y): eigenvalue of smallest modulus with right and left eigenvectors."""
    values, left, right = la.eig(T, left=True, right=True)
    i = int(np.argmin(np.abs(values)))
    return values[i], right[:, i], left[:, i]


def condensed_roots(res, omega, harmonics, contact_jacobian, starts, iterations=25,
                    tolerance=1e-9):
    """Roots s of det(I + C(s) 𝒥(s)) from each start (Newton on the smallest eigenvalue).

    contact_jacobian: s ↦ 𝒥(s) (dense, complex). Returns (roots (m,), converged (m,) bool)."""
    size = res.left.shape[0] * (2 * harmonics + 1)
    eye = np.eye(size)

    def T(s):
        return eye + compliance(res, s, omega, harmonics) @ contact_jacobian(s)

    roots, ok = [], []
    delta = 1e-6 * max(abs(omega), 1.0)
    for s0 in starts:
        s, converged = complex(s0), False
        for _ in range(iterations):
            if not np.isfinite(s) or abs(s - s0) > 2.0 * abs(omega) + abs(s0):
                break          # ran away from its start: another start owns that root
            with np.errstate(all="ignore"):
                Ts = T(s)
            if not np.all(np.isfinite(Ts)):
                break
            nu, x, y = _smallest(Ts)
            with np.errstate(all="ignore"):
                slope = np.vdot(y, (T(s + delta) - T(s - delta)) @ x) / (2 * delta) / np.vdot(y, x)
            if not np.isfinite(slope) or slope == 0:
                break
            step = nu / slope
            s = s - step
            if abs(step) <= tolerance * max(abs(s), abs(omega)):
                converged = True
                break
        roots.append(s)
        ok.append(converged)
    return np.array(roots, complex), np.array(ok, bool)


def averaged_starts(model, gap_map, mean_jacobian, omega, modes):
    """``modes`` exponents of (M, D, K + Gᵀ 𝒥̄ G) nearest the imaginary axis, shifted into the strip
    |Im s| ≤ ω/2 (with Im s ≥ 0 representatives)."""
    M, D, K = (_dense(a).astype(float) for a in (model.mass, model.damping, model.stiffness))
    G = _dense(gap_map).astype(float)
    K = K + G.T @ np.real(_dense(mean_jacobian)) @ G
    n = M.shape[0]
    Minv = la.inv(M)
    values = la.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]]))
    shifted = values - 1j * omega * np.round(values.imag / omega)
    shifted = np.where(shifted.imag < 0, shifted.conj(), shifted)
    order = np.argsort(-shifted.real)
    return shifted[order[:modes]]


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
        self.GG = sp.kron(sp.identity(2 * harmonics + 1), sp.csr_matrix(gap_projected),
                          format="csr")

    def correction(self, s):
        return (self.GG.T @ self.operator.rows_correction(s) @ self.GG).tocsr()


def condensed_stability(model, contacts, omega, harmonics, forces, operator=None, tolerance=1e-6,
                        max_modes=40):
    """Hill stability on the Ritz basis of :func:`ritz_basis` → StabilityResult (the exponents,
    verdict and notes of :func:`sarfe.hbm.stability.hill_stability` on the projected problem).

    forces: the AFT :class:`ContactForces` of the orbit (all harmonic rows); operator: the
    :class:`ContactOperator` (friction memory), or None."""
    from .aft import jacobian_matrix
    from .model import make_linear_model
    from .linear import dynamic_stiffness_matrix
    from .stability import hill_stability

    nr, H = contacts.row_count, int(harmonics)
    base = jacobian_matrix(forces.blocks, nr, H)
    basis = ritz_basis(model, contacts.gap_map, base[:nr, :nr].toarray(), omega, H, max_modes)
    project = lambda a: basis.T @ _dense(a) @ basis  # noqa: E731
    reduced = make_linear_model(project(model.mass), project(model.damping),
                                project(model.stiffness))
    G_p = _dense(contacts.gap_map) @ basis
    GG = sp.kron(sp.identity(2 * H + 1), sp.csr_matrix(G_p), format="csr")
    jacobian = dynamic_stiffness_matrix(reduced, omega, H) + GG.T @ base @ GG
    damping = (GG.T @ jacobian_matrix(forces.damping_blocks, nr, H) @ GG).tocsr() \
        if forces.damping_blocks else None
    projected = None if operator is None else _ProjectedOperator(operator, G_p, H)
    return hill_stability(reduced, omega, H, jacobian.tocsr(), tolerance,
                          contact_damping=damping, operator=projected)
