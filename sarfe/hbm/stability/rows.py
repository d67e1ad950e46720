r"""Hill stability on the contact rows: count the Floquet exponents right of the imaginary axis
with the argument principle on det(I + C(s) 𝒥(s)), no eigen-solve of a Hill matrix.

Hill's operator (:mod:`sarfe.hbm.stability.hill`) is T(s) = L(s) + (I⊗G)ᵀ 𝒥(s) (I⊗G) with the linear
structure L(s) = s² M̃ + s D̃ + S(ω) and the contact term 𝒥(s) on the (2H+1)·n_rows contact rows
(the AFT Jacobian, the Jenkins memory at s, s × the dashpots of rate-dependent laws;
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
(:mod:`sarfe.hbm.stability.march`).

The verdict of the full method (:func:`sarfe.hbm.stability.hill.hill_stability`) is decided by the
exponents in the strip |Im s| ≤ 1.01 ω/2: unstable when one has Re s > tolerance·ω, uncertain
when the leading one is within ±``uncertain_band``·ω of 0. The number of zeros of det F in the
half-strip Ω = {−ε < Re s < X, |Im s| < 1.01 ω/2}, ε = uncertain_band·ω, is the winding number of
det F along its boundary (no pole inside: the poles are the structure's own exponents, all left
of −ε when every mode is damped; X bounds |s| of any exponent, |s| ≤ ‖d‖ + √‖k‖ from
pᴴT(s)p = 0). F is real for real s, so det F(s̄) = conj det F(s) and the count is the change of
arg det F along the upper half of the boundary divided by π. The contour is sampled adaptively
(every step's change of arg below π/3) from nodes placed by the known poles of det F
(:func:`_upper_contour`).

No zero in Ω: stable, and no exponent is within the uncertain band; the leading exponent reported
is the least damped exponent of the structure (max Re of μ s² + δ s + 1 = 0; the coupled
exponents left of −ε are not located). One zero in Ω: it is real (a fold's exponent), located on
the real axis by the sign of det F, and decides the verdict (:func:`contact_row_stability`). Two
or more: all of them are located from the count's samples (:mod:`sarfe.hbm.stability.zeros`) and
the leading one decides. A pole near the contour, a model without a modal basis, a contour that
does not close on a multiple of π, or zeros that are not all located: ``None`` — the caller then
locates the exponents by the Ritz-basis Hill method (:mod:`sarfe.hbm.stability.condensed`). The check of :mod:`sarfe.hbm.stability.trust` (the contact
coupling cut to H' < H) is counted along the same contour from the same LU
(:func:`contact_row_counts`, :meth:`ContactRowDeterminant.log_determinants`).
Measured against the full Hill method in tests/hbm/stability/test_stability_rows.py and
benchmarks/bench_stability.py.
"""
from __future__ import annotations

import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg import get_lapack_funcs

from sarfe.hbm.aft import jacobian_matrix
from sarfe.hbm.modal import cached_modal_basis, modal_basis

STABILITY_DAMPING_TOLERANCE = 1e-6   # modal-diagonal damping check of the count's basis (see below)
PHASE_STEP = np.pi / 3       # largest change of arg det F between neighbouring contour samples
MAX_EVALUATIONS = 1500       # det F evaluations per point before giving up (→ Ritz method)
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
    forms I + C𝒥). ``probes`` [0, ω, 10ω, (0.37 + 0.21i)ω]: the
    exponents at which the memory rows are first evaluated — their union of non-zero rows is R,
    the first three serve the norm of :func:`contact_row_stability`'s exponent bound
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
        pairs = q.real @ self._pairs.T + 1j * (q.imag @ self._pairs.T)         # (…, n_pairs)
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

    def log_determinants(self, s, chunk=8, coarse=None):
        """log det F(s) (n_s,) complex: log|det| + i arg det (nan where det F = 0); the memory
        rows for all s in one march, ``chunk`` exponents at a time.

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


def exponent_bound(basis, gap_modes, omega, harmonics, jacobian_norm, damping_norm):
    r"""X [1/s] with |s| < X for every exponent of T(s): from pᴴ T(s) p = 0 (p M̃-normalized),
    s² + d s + k = 0 with |d| ≤ max δ_j/μ_j + 2Hω + ‖G M⁻¹ Gᵀ‖ ‖𝒥_d‖ and
    |k| ≤ max 1/μ_j + Hω max δ_j/μ_j + (Hω)² + ‖G M⁻¹ Gᵀ‖ ‖𝒥‖, so |s| ≤ |d| + √|k|."""
    mu, delta = basis.flexibility, basis.damping
    reach = np.linalg.norm((gap_modes / np.sqrt(mu)[None]) @ (gap_modes / np.sqrt(mu)[None]).T, 2)
    top = float(np.max(delta / mu))
    Hw = harmonics * abs(omega)
    d = top + 2 * Hw + reach * damping_norm
    k = float(np.max(1.0 / mu)) + Hw * top + Hw ** 2 + reach * jacobian_norm
    return 1.1 * (d + np.sqrt(k))


def shifted_exponents(structure, omega, harmonics):
    """The poles of det F(s): the structure's exponents λ_j (:func:`structural_exponents`) shifted
    to s = λ_j − imω, m = −H…H, where A(s + imω) has its poles ((2H+1)·2 n_modes,) complex [1/s]."""
    m = np.arange(-int(harmonics), int(harmonics) + 1)
    return (np.asarray(structure)[:, None] - 1j * omega * m[None]).ravel()


def _left_step(y, epsilon, poles):
    r"""Largest L [1/s] with L ≤ 2 dist(p, [−ε + i(y − L), −ε + iy]) for every pole p (min over
    the poles): the vertical step down from −ε + iy whose every pole stays at least L/2 away. A
    pole p = −ε − a + ib (a > 0, every pole lies left of −ε) with c = y − b: above the start
    (c ≤ 0) its distance √(a² + c²) is that of the start; below, the distance falls with L to a
    once the step passes b, so L_p = 2a where c ≤ √3 a, else the first root of
    L = 2√(a² + (c − L)²), L_p = (4c − 2√(c² − 3a²))/3 (< c)."""
    a = -epsilon - poles.real
    c = y - poles.imag
    below = c > np.sqrt(3.0) * a
    step = np.where(c <= 0.0, 2.0 * np.hypot(a, c), 2.0 * a)
    cb, ab = c[below], a[below]
    step[below] = (4.0 * cb - 2.0 * np.sqrt(cb ** 2 - 3.0 * ab ** 2)) / 3.0
    return float(step.min(initial=np.inf))


def _upper_contour(epsilon, X, top, poles):
    """Samples of the upper half of the boundary of Ω, counter-clockwise: (X, 0) → (X, top) →
    (−ε, top) → (−ε, 0). The right edge by its ends (every zero and pole is ≥ X/11 away from it
    and X ≫ top: it turns arg det F by nothing measurable). Along the top and left edges every
    step L keeps each pole p of det F (``poles``, :func:`shifted_exponents`; all left of −ε) at
    least L/2 from the step, so a pole turns arg det F by at most 2 atan(1) = π/2 over it: on the
    top edge (the poles lie left of its start) L = 2 min_p |p − a| from a, steps that grow about
    threefold with the depth; on the left edge L from :func:`_left_step`, within [top/64, top/8].
    (The refinement of :func:`winding_count` halves steps that turn arg det F by more than π/3.)
    Before, the left edge was sampled uniformly at twice the distance of the nearest pole to the
    line and the top edge geometrically (12 depths down to 10⁻²·top): the same bound per pole,
    ≈ 4 more evaluations per point on the P1 door trim (benchmarks/results/stability.md)."""
    poles = np.asarray(poles, dtype=complex)
    depth = [0.0]                                       # top edge, from the corner rightwards
    while depth[-1] < X + epsilon:
        corner = depth[-1] - epsilon + 1j * top
        depth.append(depth[-1] + max(2.0 * float(np.abs(poles - corner).min(initial=np.inf)),
                                     1e-2 * top))
    depth[-1] = X + epsilon
    # left edge, downwards; a pole farther than top/16 from it never shortens a step below top/8
    margin = top / 16
    near = poles[(-epsilon - poles.real <= margin) & (poles.imag >= -margin)
                 & (poles.imag <= top + margin)]
    height = [top]
    while height[-1] > 0.0:
        step = float(np.clip(_left_step(height[-1], epsilon, near), top / 64, top / 8))
        height.append(max(height[-1] - step, 0.0))
    right = X + 1j * top * np.array([0.0, 1.0])
    return np.concatenate([right, np.array(depth[-2::-1]) - epsilon + 1j * top,
                           1j * np.array(height[1:]) - epsilon])


def winding_count(log_det, points, step=PHASE_STEP, budget=MAX_EVALUATIONS):
    """Change of arg f along the polyline ``points`` / π, f = exp(log_det(s)) with log_det
    vectorized over s; a segment is halved while its change of arg exceeds ``step``. Returns
    (Δarg/π, evaluations), or (nan, evaluations) when f vanishes on the path or the budget runs
    out."""
    counts, evaluations = winding_counts(log_det, points, step, budget)
    return float(counts[0]), evaluations


def winding_counts(log_det, points, step=PHASE_STEP, budget=MAX_EVALUATIONS):
    """:func:`winding_count` of several functions f_c = exp(log_det(s)[:, c]) on one node set:
    log_det returns (n_s,) or (n_s, n_f); a segment is halved while the arg of any f_c that is
    still counted changes by more than ``step`` along it, so every f_c is sampled at least as
    finely as alone. Returns (Δarg/π per function (n_f,), evaluations). A function that vanishes
    on a node, or needs a segment shorter than 10⁻⁹|s|, gets nan and stops steering the
    refinement; when the budget runs out the last function still counted is dropped first (the
    first is the primary count: it is refined alone as long as the budget allows)."""
    points = np.asarray(points, dtype=complex)
    values = np.asarray(log_det(points))
    values = values.reshape(points.size, -1)
    evaluations = points.size
    counts = np.full(values.shape[1], np.nan)
    active = np.ones(values.shape[1], bool)
    while True:
        active &= ~np.any(np.isnan(values), axis=0)
        phase = np.angle(np.exp(1j * np.diff(values.imag, axis=0)))           # (n − 1, n_f)
        wide = np.abs(phase) > step
        done = active & ~wide.any(axis=0)
        counts[done] = phase[:, done].sum(axis=0) / np.pi
        active &= ~done
        while active.any():
            coarse = np.flatnonzero(wide[:, active].any(axis=1))
            middle = 0.5 * (points[coarse] + points[coarse + 1])
            tiny = np.abs(points[coarse + 1] - points[coarse]) < 1e-9 * np.abs(middle).clip(1.0)
            failed = active & wide[coarse[tiny]].any(axis=0)
            if evaluations + middle.size > budget and not failed.any():
                failed[np.flatnonzero(active)[-1]] = True
            if not failed.any():
                break
            active &= ~failed
        if not active.any():
            return counts, evaluations
        points = np.insert(points, coarse + 1, middle)
        values = np.insert(values, coarse + 1, np.asarray(log_det(middle)).reshape(
            middle.size, -1), axis=0)
        evaluations += middle.size


def real_zero(log_det, lower, upper, relative=1e-9):
    """The zero of det F on the real segment (lower, upper) [1/s], lower < 0 < upper, where det F
    (real for real s) changes sign once — the count found one zero in Ω, so it is real and
    simple — or None (det F not finite there, or of the same sign at both ends).

    The sign of det F brackets it: on (lower, 0], on (0, −lower], or by geometric bisection of
    (−lower, upper] (a fold's exponent lies near 0 and ``upper`` is a crude bound: each evaluation
    halves the bracket's log-ratio) down to a ratio ≤ 2; then Brent's method on
    det F(s)/|det F(a)| to |Δs| ≤ ``relative``·|s| + 10⁻¹²|lower|. ≈ 15 evaluations in all (the
    grid search this replaces took 108). Returns s* [1/s]."""
    from scipy.optimize import brentq

    def value(s):
        v = log_det(np.array([s], dtype=complex))[0]
        if not np.isfinite(v):
            raise FloatingPointError(f"det F not finite at s = {s}")
        return v

    def sign(v):
        return np.sign(np.cos(v.imag))

    def scaled(s):          # det F(s)/|det F(a)|: continuous, of order one across the bracket
        v = log_det(np.array([s], dtype=complex))[0]
        if v.real == -np.inf:                        # det F = 0 exactly: s is the zero
            return 0.0
        if not np.isfinite(v):
            raise FloatingPointError(f"det F not finite at s = {s}")
        return np.cos(v.imag) * np.exp(np.clip(v.real - reference.real, -700.0, 700.0))

    try:
        low, zero, high = value(lower), value(0.0), value(upper)
        if sign(low) == sign(high):
            return None
        if sign(low) != sign(zero):
            a, b, reference = lower, 0.0, low
        else:
            a, b, reference = -lower, upper, value(-lower)
            if sign(reference) != sign(zero):
                a, b, reference = 0.0, -lower, zero
            while b > 2.0 * a > 0.0:
                middle = np.sqrt(a * b)
                v = value(middle)
                if sign(v) == sign(reference):
                    a, reference = middle, v
                else:
                    b = middle

        return float(brentq(scaled, a, b, xtol=1e-12 * abs(lower), rtol=relative))
    except (FloatingPointError, ValueError):
        return None


def contact_row_stability(model, contacts, omega, harmonics, forces, operator=None,
                          uncertain_band=1e-4, tolerance=1e-6):
    """StabilityResult when the contact-row count decides it, else None (see
    :func:`contact_row_count`, which also returns the count)."""
    return contact_row_count(model, contacts, omega, harmonics, forces, operator, uncertain_band,
                             tolerance)[0]


def contact_row_count(model, contacts, omega, harmonics, forces, operator=None,
                      uncertain_band=1e-4, tolerance=1e-6):
    """(StabilityResult or None, zeros) of :func:`contact_row_counts` without the coarse count."""
    return contact_row_counts(model, contacts, omega, harmonics, forces, operator, uncertain_band,
                              tolerance)[:2]


def contact_row_counts(model, contacts, omega, harmonics, forces, operator=None,
                       uncertain_band=1e-4, tolerance=1e-6, check_harmonics=0):
    """(StabilityResult or None, zeros, coarse): zeros = the number of Floquet exponents right of
    −ε (None where the count did not close); coarse = the same count with the contact coupling
    cut to ``check_harmonics`` = H' (1 ≤ H' < H; else None), on the same contour and nodes
    (:meth:`ContactRowDeterminant.log_determinants`, :func:`winding_counts`: X of the coupling at
    H bounds every exponent at H' too, ‖𝒥'‖ ≤ ‖𝒥‖ being a leading block). The result when the
    count decides it, else None.

    No zero of det F right of −ε: stable (for every stability tolerance ≥ 0 of the full method).
    Exactly one: it is real (zeros off the real axis come in conjugate pairs) and it is the leading
    exponent s*; :func:`real_zero` locates it and the verdict is the full method's rule: uncertain
    (None, with a note) when |s*| ≤ ``uncertain_band``·ω, else stable iff s* ≤ ``tolerance``·ω —
    the middle branch of a fold is unstable here without an eigen-solve. (The Ritz basis of
    :mod:`sarfe.hbm.stability.condensed`, which these points went to before, reported 'stable'
    with a leading exponent near −7 1/s at three points of such a branch of the 12-pair door trim
    at 46.2 Hz, where det F changes sign at s* ≈ 1.2–3.5 1/s.) Two or more: every zero in the
    half-strip is located from the count's samples (:func:`leading_zeros`: Delves–Lyness power
    sums on a box, Muller's method, deflation) and the leading one decides by the same rule; None
    (the caller's Ritz method) only where fewer than the counted number are located.

    forces: the AFT :class:`ContactForces` of the orbit (all harmonic rows, blocks computed);
    operator: the :class:`ContactOperator` (friction memory) or None. See the module docstring.
    """
    from sarfe.hbm.stability.hill import StabilityResult, verdict

    basis = stability_basis(model)
    if basis is None or model.dof_count == 0:
        return None, None, None
    omega, H = abs(float(omega)), int(harmonics)
    coarse = int(check_harmonics) if 1 <= int(check_harmonics) < H else None
    epsilon = uncertain_band * omega
    structure = structural_exponents(basis.flexibility, basis.damping)
    least_damped = float(structure.real.max())
    if not least_damped < -2.0 * epsilon:       # a pole on or right of the contour
        return None, None, None
    n_rows = contacts.row_count
    J = jacobian_matrix(forces.blocks, n_rows, H)
    Jd = jacobian_matrix(forces.damping_blocks, n_rows, H) if forces.damping_blocks else None
    det = ContactRowDeterminant(basis, contacts.gap_map, omega, H, J, Jd, operator)
    stable = StabilityResult(True, least_damped, "", structure)
    if det.loaded.size == 0:
        return stable, 0, None if coarse is None else 0
    # ‖𝒥(s)‖₂ for Re s ≥ 0: twice its largest value at s = 0, ω, 10ω (the memory factors e^{−shd}
    # have modulus ≤ 1 there; the pointwise part does not depend on s), each bounded above by the
    # Frobenius norm (‖·‖₂ ≤ ‖·‖_F: X only grows, the contour still encloses every exponent)
    jacobian_norm = 2.0 * float(np.linalg.norm(det.probe_terms, axis=(1, 2)).max())
    damping_norm = 0.0 if Jd is None else float(spla.norm(Jd))
    X = exponent_bound(basis, det.gap_modes, omega, H, jacobian_norm, damping_norm)
    top = 0.505 * omega                                   # the strip |Im s| ≤ 1.01 ω/2
    poles = shifted_exponents(structure, omega, H)
    contour = _upper_contour(epsilon, X, top, poles)
    samples = {}                # log det F at the contour's nodes, for locating ≥ 2 zeros

    def sampled(s):
        values = det.log_determinants(s, coarse=coarse)
        samples.update(zip(np.asarray(s).tolist(),
                           (values if coarse is None else values[:, 0]).tolist()))
        return values

    counts, _ = winding_counts(sampled, contour)
    closed = [None if not np.isfinite(c) or abs(c - round(c)) > 0.1 else int(round(c))
              for c in counts]
    zeros, coarse_zeros = closed[0], (closed[1] if coarse is not None else None)
    if zeros is None:
        return None, None, coarse_zeros
    if zeros == 0:
        return stable, 0, coarse_zeros
    if zeros == 1:
        lead = real_zero(det.log_determinants, -epsilon, X)
        exponents = None if lead is None else np.array([lead])
    else:
        exponents = leading_zeros(det.log_determinants, samples, zeros, epsilon, top, X, poles)
    if exponents is None:
        return None, zeros, coarse_zeros
    lead = float(exponents.real.max())
    return verdict(lead, np.concatenate([exponents, structure]), omega, tolerance,
                   uncertain_band), zeros, coarse_zeros


def leading_zeros(log_det, samples, zeros, epsilon, top, X, poles=()):
    """Every zero of det F in the half-strip Ω of the count (``zeros`` ≥ 2 of them), conjugates
    included ((zeros,) complex [1/s]), located from the count's ``samples`` (dict s ↦ log det F)
    by :func:`sarfe.hbm.stability.zeros.located_zeros` (``poles``: those of det F,
    :func:`shifted_exponents`); None when not all are located."""
    from sarfe.hbm.stability.zeros import located_zeros

    found = located_zeros(log_det, samples, zeros, epsilon, top, X, poles)
    if found is None:
        return None
    return np.concatenate([found, found[found.imag != 0].conj()])
