r"""det F(s) of the contact rows, F(s) = I + C(s) 𝒥(s), evaluated at many exponents s at once: the
function whose zeros the contact-row count (:mod:`sarfe.hbm.stability.rows`) counts.

Hill's operator (:mod:`sarfe.hbm.stability.hill`) is T(s) = L(s) + (I⊗G)ᵀ 𝒥(s) (I⊗G) with the
linear structure L(s) = s² M̃ + s D̃ + S(ω) and the contact term 𝒥(s) on the (2H+1)·n_rows contact
rows (the AFT Jacobian, the Jenkins memory at s, s × the dashpots of rate-dependent laws;
:class:`sarfe.hbm.stability.contact_terms.ContactOperator`). Where L(s) is regular,

    det T(s) = det L(s) · det F(s),      F(s) = I + C(s) 𝒥(s),      C(s) = (I⊗G) L(s)⁻¹ (I⊗G)ᵀ,

so every exponent of T that is not a (damped) exponent of the linear structure is a zero of the
small matrix F(s) [(2H+1) n_rows square, only the rows the contacts load]. L(s) is block diagonal
over the harmonics; for harmonic k its (cos, sin) block acts on z± = a ∓ i b through Z(s ± ikω),
Z(λ) = K + λ D + λ² M, and the modal basis of the model (:mod:`sarfe.hbm.modal`, Vᵀ K V = I,
Vᵀ M V = diag μ, Vᵀ D V = diag δ) gives every G Z(λ)⁻¹ Gᵀ without a factorization:

    A(λ) = G K⁻¹ Gᵀ + (GV) diag(−a/(1+a)) (GV)ᵀ,   a_j = λ δ_j + λ² μ_j,
    C_k(s) = [[½(A₊ + A₋), ½i(A₋ − A₊)], [½i(A₊ − A₋), ½(A₊ + A₋)]],   A± = A(s ± ikω),

(C₀(s) = A(s) for the mean), which at s = 0 is the condensed compliance of the Newton solver.

Evaluation (:class:`ContactRowDeterminant`; cost per s independent of the FE size): only the
loaded rows R enter (𝒥 vanishes elsewhere, so det(I + C𝒥) = det(I + C_LL 𝒥_LL), S = (2H+1)|R|);
in the exponential basis W (per harmonic the rows (cos ∓ i sin)/√2, unitary) C is block diagonal,
W C Wᴴ = ⊕_m A(s + imω), m = 0, ±1, …, ±H, so

    det F = Π_m det A(s + imω) · det(C_LL⁻¹ + 𝒥_LL),   C_LL⁻¹ = Wᴴ (⊕_m A(s + imω)⁻¹) W

(C_LL⁻¹ is formed in the real basis of 𝒥 — per harmonic k a 2|R| block from A(s ± ikω)⁻¹ —, so
𝒥 is never transformed): one LU of order S per s and 2H+1 small |R|² inverses; GV, G K⁻¹ Gᵀ are
per model (:func:`row_products`), the pointwise part of 𝒥 and the normal rows of the friction
groups per point, the Jenkins memory rows per s by one compiled march for all s of a contour
(:mod:`sarfe.hbm.stability.march`). The poles of det F are the structure's exponents
(:func:`structural_exponents`) shifted by imω.
"""
from __future__ import annotations

import weakref

import numpy as np
import scipy.sparse as sp
from scipy.linalg import get_lapack_funcs

from sarfe.hbm.aft import jacobian_matrix
from sarfe.hbm.modal import cached_modal_basis, modal_basis

STABILITY_DAMPING_TOLERANCE = 1e-6   # modal-diagonal damping check of the count's basis (see below)
GROWTH_LIMIT = 1e6           # block LU of det F and its leading block: largest eliminated part


def structural_exponents(flexibility, damping):
    """Roots of μ_j s² + δ_j s + 1 = 0 per mode (2 n_modes,) complex [1/s]: the exponents of the
    structure without contacts (K-orthonormal modes: μ_j = 1/ω_j² [s²], δ_j [s])."""
    mu, delta = np.asarray(flexibility, float), np.asarray(damping, float)
    root = np.sqrt(delta.astype(complex) ** 2 - 4.0 * mu)
    return np.concatenate([(-delta + root) / (2 * mu), (-delta - root) / (2 * mu)])


_ROW_PRODUCTS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_STABILITY_BASES: dict = {}


def stability_basis(model):
    r"""The modal basis of ``model`` for the count: :func:`sarfe.hbm.modal.cached_modal_basis`
    (the one Newton's condensation uses), else — a dense model whose damping the Newton path
    rejected as not modal-diagonal at 10⁻¹⁰ — :func:`modal_basis` with the damping check at
    ``STABILITY_DAMPING_TOLERANCE`` (10⁻⁶), cached per model. Dropping the off-diagonal modal
    damping Δ_ij perturbs every compliance block A(λ) relatively by at most
    |Δ_ij|/√(δ_i δ_j) ≤ 10⁻⁶ (:mod:`sarfe.hbm.modal`), so arg det F moves by O(10⁻⁶) rad along a
    contour whose steps turn it by ≤ π/3: the count is unchanged. (The shipped rattle rig's modal ζ
    damping comes out of the Craig–Bampton reduction diagonal to 1.9·10⁻¹⁰: with the Newton
    tolerance alone every point of its sweep went to the Ritz method instead of the count.)"""
    basis = cached_modal_basis(model) or cached_modal_basis(model)
    if basis is not None or sp.issparse(model.stiffness):
        return basis
    key = id(model)
    if key not in _STABILITY_BASES:
        try:
            weakref.finalize(model, _STABILITY_BASES.pop, key, None)
        except TypeError:         # not weak-referenceable: no cache
            return modal_basis(model, tolerance=STABILITY_DAMPING_TOLERANCE)
        _STABILITY_BASES[key] = modal_basis(model, tolerance=STABILITY_DAMPING_TOLERANCE)
    return _STABILITY_BASES[key]


def row_products(basis, gap_map):
    """(GV (n_rows, n_modes) [1/√(N/m)], G K⁻¹ Gᵀ (n_rows, n_rows) [m/N]) of a model's modal basis
    and its gap map: per model, not per point — computed on the first call and kept with the
    basis (dropped with it)."""
    entry = _ROW_PRODUCTS.get(basis)
    if entry is not None and entry[0] is gap_map:
        return entry[1], entry[2]
    G = gap_map.toarray() if sp.issparse(gap_map) else np.asarray(gap_map, float)
    products = (G @ basis.modes, G @ basis.static_solve(G.T))
    _ROW_PRODUCTS[basis] = (gap_map,) + products
    return products


class ContactRowDeterminant:
    """s ↦ det F(s) on the loaded contact rows (module docstring), for one periodic solution,
    evaluated at many s at once (the friction-memory march runs once for all of them).

    basis: :class:`sarfe.hbm.modal.ModalBasis` of the model; gap_map G (n_rows, n); omega [rad/s];
    harmonics H; jacobian: 𝒥_AFT (P n_rows square, harmonic-major); damping_jacobian: the
    dashpot part of rate-dependent laws or None; operator: ContactOperator (friction memory) or
    None.

    Only the loaded contact rows R enter (rows or columns of 𝒥 that are not identically zero, for
    every harmonic: L = {(h, r): r ∈ R}, size S = P |R|): 𝒥 vanishes outside L × L, so
    det(I + C 𝒥) = det(I + C_LL 𝒥_LL) and neither 𝒥 nor C is formed on the other rows. 𝒥_LL(s)
    is the s-independent part (pointwise laws, the normal rows of the friction groups) plus the
    tangent rows of the memory groups scattered at s, both in the real (AFT) basis; C_LL(s) is
    block diagonal over the harmonics, given by the |R|² blocks A(s + imω) of the exponential
    basis (:meth:`compliance_blocks`; :meth:`log_determinants` inverts them, :meth:`matrices`
    forms I + C𝒥). ``probes`` [0, ω, 10ω, (0.37 + 0.21i)ω]: the exponents at which the memory
    rows are first evaluated — their union of non-zero rows is R, the first three serve the norm
    of 𝒥 in the exponent bound of :func:`sarfe.hbm.stability.rows.contact_row_counts`
    (:attr:`probe_terms`)."""

    def __init__(self, basis, gap_map, omega, harmonics, jacobian, damping_jacobian=None,
                 operator=None):
        self.n_rows, self.H, self.omega = gap_map.shape[0], int(harmonics), float(omega)
        self.gap_modes, static = row_products(basis, gap_map)                # GV, G K⁻¹ Gᵀ
        self.mu, self.delta = basis.flexibility, basis.damping
        P, n_rows = 2 * self.H + 1, self.n_rows
        sparse = (lambda a: sp.csr_matrix(a))  # noqa: E731
        self.memory = operator if operator is not None and operator.has_memory else None
        groups = self.memory.memory if self.memory is not None else []
        # the s-independent part: 𝒥_AFT + the pointwise correction (= the pointwise groups) + the
        # normal rows of the friction groups
        fixed = sparse(jacobian).astype(float)
        if operator is not None:
            fixed = fixed + sparse(operator.pointwise_correction)
        if groups:
            fixed = fixed + jacobian_matrix([(g["rows"], g["normal"]) for g in groups], n_rows,
                                            self.H)
        damping = None if damping_jacobian is None else sparse(damping_jacobian)
        self.probes = np.array([0.0, 1.0, 10.0, 0.37 + 0.21j]) * self.omega
        coefficients = self.memory.memory_coefficients(self.probes) if groups else []
        used = [_nonzero_rows(fixed, n_rows), _nonzero_rows(damping, n_rows)]
        for (rows, coeff) in coefficients:
            t_used = np.any(coeff != 0, axis=(0, 1, 4))                        # (n_g, 2)
            c_used = np.any((coeff != 0).reshape(coeff.shape[:4] + (P, 3)), axis=(0, 1, 3, 4))
            used += [rows[:, 1:][t_used], rows[c_used]]
        R = np.unique(np.concatenate(used)).astype(int)
        R = R[R >= 0]
        self.rows = R                                                          # loaded rows R
        self.loaded = (np.arange(P)[:, None] * n_rows + R[None]).ravel()       # L in (P n_rows)
        width = R.size
        self.size = S = P * width
        self.fixed = fixed[self.loaded][:, self.loaded].toarray()               # real basis
        self.damping = None if damping is None else \
            damping[self.loaded][:, self.loaded].toarray()
        position = np.full(n_rows + 1, -1)
        position[R] = np.arange(width)                     # position[-1] = −1: an absent row
        self.scatter = [_scatter_index(rows, position, width, P) for rows, _ in coefficients]
        # GV and G K⁻¹ Gᵀ on R; the products g_a g_b of the upper triangle for A(λ)
        upper = np.triu_indices(width)
        self._upper = upper
        GV = self.gap_modes[R]
        self._pairs = GV[upper[0]] * GV[upper[1]]                              # (n_pairs, n)
        self._static = static[np.ix_(R, R)]
        self.probe_terms = self.contact_terms(self.probes[:3], coefficients=[
            (rows, coeff[:3]) for rows, coeff in coefficients]) if S else np.zeros((3, 0, 0))

    def contact_terms(self, s, coefficients=None):
        """𝒥_LL(s) (n_s, S, S) complex, for s (n_s,), in the harmonic-major real basis of the
        AFT (mean, cos 1, sin 1, …; ``coefficients``: the memory rows at s, when already
        evaluated)."""
        s = np.asarray(s, dtype=complex)
        S = self.size
        J = np.empty((s.size, S, S), complex)
        J[:] = self.fixed
        if self.memory is not None:
            if coefficients is None:
                coefficients = self.memory.memory_coefficients(s)
            flat = J.reshape(s.size, S * S)
            for (_, coeff), (mask, index, unique) in zip(coefficients, self.scatter):
                values = coeff[:, mask]                                        # (n_s, entries)
                if unique:
                    flat[:, index] += values
                else:                   # contacts sharing a row: accumulate
                    np.add.at(flat, (slice(None), index), values)
        if self.damping is not None:
            J += s[:, None, None] * self.damping[None]
        return J

    def compliance_blocks(self, s):
        """A(λ_b) = G Z(λ_b)⁻¹ Gᵀ on the loaded rows, λ_b = s + i m_b ω for the exponential rows
        m = 0, 1, −1, 2, −2, …, H, −H: (n_s, 2H+1, |R|, |R|) complex (module docstring)."""
        s = np.asarray(s, dtype=complex)
        m = np.zeros(2 * self.H + 1)
        m[1::2], m[2::2] = np.arange(1, self.H + 1), -np.arange(1, self.H + 1)
        lam = s[:, None] + 1j * self.omega * m                                  # (n_s, 2H+1)
        a = lam[..., None] * self.delta + lam[..., None] ** 2 * self.mu
        q = (-a / (1.0 + a)).reshape(-1, self.mu.size)                         # (n_s (2H+1), n)
        pairs = np.empty((q.shape[0], self._pairs.shape[0]), complex)           # (…, n_pairs)
        pairs.real = np.ascontiguousarray(q.real) @ self._pairs.T     # the parts written in place
        pairs.imag = np.ascontiguousarray(q.imag) @ self._pairs.T
        width = self.rows.size
        A = np.empty((q.shape[0], width, width), complex)
        i, j = self._upper
        A[:, i, j] = pairs
        A[:, j, i] = pairs
        A += self._static
        return A.reshape(s.size, 2 * self.H + 1, width, width)

    def matrices(self, s, coefficients=None):
        """F(s) = I + C(s)𝒥(s) on the loaded rows (n_s, S, S) complex, in the real basis: C is
        block diagonal over the harmonics, its (cos k, sin k) block formed from A(s ± ikω)
        (:func:`_real_blocks`), one |R|² product per block row and column."""
        s = np.asarray(s, dtype=complex)
        width, S = self.rows.size, self.size
        J = self.contact_terms(s, coefficients).reshape(s.size, 2 * self.H + 1, width, S)
        F = _real_block_product(self.compliance_blocks(s), J).reshape(s.size, S, S)
        F[:, np.arange(S), np.arange(S)] += 1.0
        return F

    def coarse_size(self, harmonics):
        """S' = (2H'+1)|R|: the leading rows of the harmonic-major loaded rows L that carry the
        contact coupling cut to H' ≤ H harmonics (:meth:`log_determinants`)."""
        return (2 * int(harmonics) + 1) * self.rows.size

    def log_determinants(self, s, chunk=4, coarse=None):
        """log det F(s) (n_s,) complex: log|det| + i arg det (nan where det F = 0); the memory
        rows for all s in one march, ``chunk`` exponents at a time (4: at P1, S = 465, the chunk's
        (4, S, S) complex terms, 14 MB, stay in cache for the LUs that read them — 6 % less CPU
        per Hill point than 8, the same values bit for bit: every s is computed alone).

        With the compliance blocks A_b(s) regular, det F = det C · det(C⁻¹ + 𝒥): the blocks are
        inverted (|R|² each), C⁻¹ is block diagonal over the harmonics in the real basis (its
        (cos k, sin k) block formed from A(s ± ikω)⁻¹, :func:`_real_blocks`) and added to 𝒥, so
        no product C𝒥 is formed, and det C = Π_b det A_b (W C Wᴴ = ⊕_b A_b, W unitary) is a
        product of small determinants. A block that does not
        invert to 10⁻⁸ (two loaded rows with dependent gap maps, a transmission zero) sends its s
        to the product form I + C𝒥 (:meth:`matrices`).

        ``coarse`` = H' < H: also log det F' of the contact coupling cut to H' harmonics, as a
        second column ((n_s, 2)). In the harmonic-major order 𝒥 at H' is the leading S' × S'
        block of 𝒥 at H (the AFT Jacobian's Galerkin block, the pointwise parts, and the friction
        memory rows, whose march is linear column by column:
        tests/hbm/stability/test_stability_trust.py) and C⁻¹ is block diagonal over the harmonics, so

            det F' = Π_{|m| ≤ H'} det A(s + imω) · det (C⁻¹ + 𝒥)[:S', :S']

        (in the product form: F' = F[:S', :S'], C being block diagonal). Both come from the same
        compliance blocks, contact terms and memory march; the leading block is a second LU."""
        s = np.asarray(s, dtype=complex)
        out = np.empty((s.size, 1 if coarse is None else 2), complex)
        memory = self.memory.memory_coefficients(s) if self.memory is not None else None
        P, width, S = 2 * self.H + 1, self.rows.size, self.size
        sizes = [S] if coarse is None else [S, self.coarse_size(coarse)]
        blocks = [P] if coarse is None else [P, 2 * int(coarse) + 1]
        for first in range(0, s.size, chunk):
            sc = s[first:first + chunk]
            part = None if memory is None else [(rows, coeff[first:first + chunk])
                                                for rows, coeff in memory]
            J = self.contact_terms(sc, part)
            A = self.compliance_blocks(sc)                                     # (m, P, |R|, |R|)
            with np.errstate(all="ignore"):
                try:
                    inverse = np.linalg.inv(A)
                    check = np.abs(A @ inverse - np.eye(width)).max(axis=(1, 2, 3))
                except np.linalg.LinAlgError:
                    inverse, check = None, np.full(sc.size, np.inf)
            regular = np.isfinite(check) & (check <= 1e-8)
            value = np.empty((sc.size, len(sizes)), complex)
            if np.any(regular):
                M = (J if regular.all() else J[regular]).reshape(-1, P, width, P, width)
                _add_real_blocks(M, inverse[regular])
                sign_A, logabs_A = np.linalg.slogdet(A[regular])
                logdet_A = logabs_A + 1j * np.angle(sign_A)                       # (m, P)
                v = _log_determinants(M.reshape(-1, S, S), sizes)
                for column, count in enumerate(blocks):
                    v[:, column] += logdet_A[:, :count].sum(axis=1)
                value[regular] = v
            if not np.all(regular):     # (J is intact: M was a copy when some s failed)
                F = _real_block_product(A[~regular], J[~regular].reshape(-1, P, width, S))
                F = F.reshape(-1, S, S)
                F[:, np.arange(S), np.arange(S)] += 1.0
                value[~regular] = _log_determinants(F, sizes)
            out[first:first + chunk] = value
        out.imag = np.angle(np.exp(1j * out.imag))                             # arg in (−π, π]
        return out[:, 0] if coarse is None else out


def _log_determinants(M, sizes, growth=GROWTH_LIMIT):
    """log det of M (n, S, S) and, for ``sizes`` = [S, S'], of its leading S' × S' block:
    (n, len(sizes)) complex, log|det| + i arg det, nan where det = 0.

    One size: LAPACK's LU (np.linalg.slogdet). Two: one LU of the leading block,
    M = [[M₁₁, M₁₂], [M₂₁, M₂₂]], det M = det M₁₁ · det(M₂₂ − M₂₁ M₁₁⁻¹ M₁₂): M₁₁'s LU gives
    det M₁₁ and the solve, the Schur complement (order S − S') its own LU — about one LU of order
    S for both determinants instead of S³ + S'³. Partial pivoting inside M₁₁ only is backward
    stable while the eliminated part stays small: where max|M₂₁ M₁₁⁻¹ M₁₂| > ``growth``·max|M₂₂|
    (M₁₁ nearly singular: s near a zero of det M₁₁) or M₁₁ is singular, det M is taken from its
    own LU (np.linalg.slogdet). (max|M₂₂| ≤ max|M|: at least as strict as the guard against
    max|M| it replaces, without reading all S² entries per s; measured on P1 15 mm, the rattle
    rig and NLvib 03: max|M|/max|M₂₂| ≤ 8.4, the eliminated part ≤ 45·max|M₂₂|, far below 10⁶.)"""
    n, S = M.shape[0], M.shape[1]
    out = np.empty((n, len(sizes)), complex)
    if len(sizes) == 1:
        sign, logabs = np.linalg.slogdet(M)
        out[:, 0] = np.where(np.isfinite(logabs) & (sign != 0), logabs + 1j * np.angle(sign),
                             np.nan)
        return out
    size = sizes[1]
    getrf, getrs = get_lapack_funcs(("getrf", "getrs"), (M,))
    fallback = []
    for k in range(n):
        lu, piv, info = getrf(M[k, :size, :size])
        diagonal = np.diagonal(lu)
        if info != 0 or not np.all(np.isfinite(diagonal)):     # det M₁₁ = 0 (or not finite)
            out[k, 1] = np.nan
            fallback.append(k)
            continue
        swaps = np.count_nonzero(piv != np.arange(size))
        out[k, 1] = np.log(np.abs(diagonal)).sum() + 1j * np.angle(
            np.prod(diagonal / np.abs(diagonal)) * (-1.0) ** swaps)
        solved, info = getrs(lu, piv, M[k, :size, size:])
        eliminated = M[k, size:, :size] @ solved
        schur = M[k, size:, size:] - eliminated
        if info != 0 or not np.abs(eliminated).max(initial=0.0) <= growth * np.abs(
                M[k, size:, size:]).max(initial=0.0):
            fallback.append(k)
            continue
        sign, logabs = np.linalg.slogdet(schur)
        out[k, 0] = out[k, 1] + logabs + 1j * np.angle(sign) if (
            np.isfinite(logabs) and sign != 0) else np.nan
    if fallback:
        out[fallback, :1] = _log_determinants(M[fallback], sizes[:1])
    return out


def _real_blocks(X):
    """The real-basis blocks of a harmonic block-diagonal operator given in the exponential basis
    by the blocks X_b (n_s, 2H+1, w, w), b ↔ m = 0, +1, −1, +2, −2, …: the mean block X₀ and per
    harmonic k, with X± = X(±k) (W maps (cos, sin) to ((cos − i sin)/√2, (cos + i sin)/√2)),

        Wᴴ diag(X₊, X₋) W = [[½(X₊ + X₋), ½i(X₋ − X₊)], [½i(X₊ − X₋), ½(X₊ + X₋)]].

    Returns (X₀ (n_s, w, w), half = ½(X₊ + X₋), skew = ½i(X₋ − X₊)), the last two (n_s, H, w, w)."""
    plus, minus = X[:, 1::2], X[:, 2::2]
    return X[:, 0], 0.5 * (plus + minus), 0.5j * (minus - plus)


def _add_real_blocks(M, X):
    """M += the block-diagonal operator of the exponential blocks X (:func:`_real_blocks`),
    M (n_s, P, w, P, w) in the real basis (in place)."""
    mean, half, skew = _real_blocks(X)
    P = M.shape[1]
    cos, sin = np.arange(1, P, 2), np.arange(2, P, 2)
    M[:, 0, :, 0, :] += mean
    M[:, cos, :, cos, :] += np.moveaxis(half, 1, 0)
    M[:, cos, :, sin, :] += np.moveaxis(skew, 1, 0)
    M[:, sin, :, cos, :] -= np.moveaxis(skew, 1, 0)
    M[:, sin, :, sin, :] += np.moveaxis(half, 1, 0)


def _real_block_product(X, J):
    """(block-diagonal operator of the exponential blocks X) @ J, J (n_s, P, w, S) in the real
    basis → (n_s, P, w, S)."""
    mean, half, skew = _real_blocks(X)
    out = np.empty(J.shape, complex)
    out[:, 0] = mean @ J[:, 0]
    cos, sin = J[:, 1::2], J[:, 2::2]
    out[:, 1::2] = half @ cos + skew @ sin
    out[:, 2::2] = half @ sin - skew @ cos
    return out


def _nonzero_rows(matrix, n_rows):
    """Contact rows r of the (P n_rows)² sparse ``matrix`` with a non-zero in some row or column
    (h n_rows + r) (int array; empty for None)."""
    if matrix is None:
        return np.zeros(0, int)
    coo = matrix.tocoo()
    keep = coo.data != 0
    return np.concatenate([coo.row[keep], coo.col[keep]]) % n_rows


def _scatter_index(rows, position, width, P):
    """Where the memory rows δλ̃_t (P, n_g, 2, 3P) of a group go in the flattened 𝒥_LL (S²):
    (mask (P, n_g, 2, 3P) of the entries on loaded rows, flat indices (entries,), unique)."""
    harmonic = np.arange(P)
    row = harmonic[:, None, None] * width + position[rows[:, 1:]][None]        # (P, n_g, 2)
    row_ok = np.broadcast_to((position[rows[:, 1:]] >= 0)[None], row.shape)
    column = (harmonic[None, :, None] * width + position[rows][:, None, :]).reshape(
        rows.shape[0], 3 * P)                                                  # (n_g, 3P): h·3 + l
    column_ok = np.repeat((position[rows] >= 0)[:, None, :], P, axis=1).reshape(rows.shape[0],
                                                                                3 * P)
    mask = row_ok[..., None] & column_ok[None, :, None, :]
    flat = row[..., None] * (P * width) + column[None, :, None, :]
    index = flat[mask]
    return mask, index, np.unique(index).size == index.size
