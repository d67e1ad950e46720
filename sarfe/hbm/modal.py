r"""Modal representation of the linear model for the dynamic compliance (one eigen-solve per model).

With the undamped modes of (K, M) and a damping that is diagonal in them — modal ζ (d_j = 2ζ_jω_j),
Rayleigh α M + β K (d_j = α + β ω_j²), none — the complex dynamic stiffness of harmonic k,
Z_k(ω) = K − (kω)² M + i kω D, is diagonalized by the same modes for every k and ω:

    Z_k(ω)⁻¹ = Σ_j φ_j φ_jᵀ / (ω_j² − (kω)² + i kω d_j)         (φ_j M-orthonormal).

A Craig–Bampton model's modes span ω_max²/ω_1² ~ 10⁷…10¹⁰, so the modes are computed from the
flexibility form M v = μ K v (``eigh(M, K)``: accurate for the low modes, μ_j = 1/ω_j² [s²]), and
K-orthonormal, Vᵀ K V = I, Vᵀ M V = diag(μ), Vᵀ D V = diag(δ) [s] (δ_j = d_j/ω_j²). The static
flexibility K⁻¹ = V Vᵀ is taken exactly from one Cholesky factor of K and the modes carry only the
dynamic remainder (the mode-acceleration form):

    Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ,     q_kj = a_kj / (1 − a_kj),   a_kj = (kω)² μ_j − i kω δ_j,

in which a stiff mode's term is O((kω)² μ_j) → 0, so its inaccurate eigenvector does not matter.
Then G Z_k⁻¹ Gᵀ = G K⁻¹ Gᵀ + (GV) diag(q_k) (GV)ᵀ costs O(n_rows² n_modes) per harmonic and
frequency and Z_k⁻¹ f = K⁻¹ f + V (q_k ⊙ Vᵀ f) O(n n_modes), with no factorization per point: the
O(n³) eigen-solve and the Cholesky factor are paid once per model, at its second condensation
(:func:`cached_modal_basis`). V
is the complete basis of the (reduced) model, not a truncation: nothing is approximated except the
damping check below. Models with a singular K (rigid-body modes; Z_0 is singular anyway) keep the
factorization path.

When is D modal-diagonal? Dropping an off-diagonal Δ_ij = v_iᵀ D v_j perturbs Z_k in modal
coordinates by kω Δ_ij against diagonal terms |1 − a_kj| ≥ kω δ_j, i.e. relatively by at most
|Δ_ij| / √(δ_i δ_j) at any k and ω (first order). The basis is accepted when every
|Δ_ij| ≤ tolerance · √(δ_i δ_j) (+ 10⁻¹⁴ max δ for round-off of undamped modes), tolerance =
10⁻⁸: a modal ζ built on the modes of K φ = ω² M φ and projected on those of M v = μ K v keeps
off-diagonal round-off of ~10⁻¹⁰ √(δ_i δ_j) on Craig–Bampton models (9.2e-11 on the test plate,
1.1e-10 on the 15 mm instrument panel, which a 10⁻¹⁰ bound sent to the per-harmonic LU at 5× the
sweep's cost), and a relative perturbation of 10⁻⁸ of Z_k is far below every reported ±; otherwise
:func:`modal_basis` returns None and the caller keeps the per-harmonic factorization. Only models
with n ≤ ``max_dofs`` are decomposed (dense LAPACK).
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

MODAL_MAX_DOFS = 3000        # dense eigh above this costs more than it saves on a sweep
MODAL_DAMPING_TOLERANCE = 1e-8


@dataclass(frozen=True, eq=False)
class ModalBasis:
    """Undamped modes of a linear model, K-orthonormal, with the static flexibility.

    modes: V (n, n_modes), Vᵀ K V = I [1/√(N/m)]; flexibility: μ_j = v_jᵀ M v_j = 1/ω_j² (n_modes,)
    [s²], descending (lowest mode first); damping: δ_j = v_jᵀ D v_j = d_j/ω_j² (n_modes,) [s];
    stiffness_factor: Cholesky factor of K (``scipy.linalg.cho_factor``) for K⁻¹.
    """

    modes: np.ndarray
    flexibility: np.ndarray
    damping: np.ndarray
    stiffness_factor: tuple
    _projections: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def natural_frequencies(self) -> np.ndarray:
        """ω_j = 1/√μ_j (n_modes,) [rad/s]."""
        return 1.0 / np.sqrt(self.flexibility)

    def _a(self, orders, omega):
        kw = np.asarray(orders, dtype=float)[:, None] * omega
        return kw**2 * self.flexibility[None, :] - 1j * kw * self.damping[None, :]

    def dynamic_receptance(self, orders, omega: float) -> np.ndarray:
        """q_kj = a_kj / (1 − a_kj) (n_orders, n_modes) complex [-]: Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ."""
        a = self._a(orders, omega)
        return a / (1.0 - a)

    def receptance_slope(self, orders, omega: float) -> np.ndarray:
        """∂q_kj/∂ω = a'_kj / (1 − a_kj)², a'_kj = 2k²ω μ_j − i k δ_j (n_orders, n_modes) complex
        [s]: the ω-derivative of :meth:`dynamic_receptance`."""
        k = np.asarray(orders, dtype=float)[:, None]
        a = self._a(orders, omega)
        slope = 2.0 * k**2 * omega * self.flexibility[None, :] - 1j * k * self.damping[None, :]
        return slope / (1.0 - a) ** 2

    def static_solve(self, B: np.ndarray) -> np.ndarray:
        """K⁻¹ B for real or complex B (n, ...) [m per N]."""
        B = np.asarray(B)
        if np.iscomplexobj(B):
            return self.static_solve(B.real) + 1j * self.static_solve(B.imag)
        return sla.cho_solve(self.stiffness_factor, B)

    def _projection(self, kind, operand, build):
        """build(operand) cached for the last operand of each kind (compared by value: the points
        of a sweep project the same gap map and the same excitation)."""
        hit = self._projections.get(kind)
        if hit is not None and hit[0].shape == operand.shape and np.array_equal(hit[0], operand):
            return hit[1]
        value = build(operand)
        self._projections[kind] = (operand.copy(), value)
        return value

    def gap_projection(self, gap_map: np.ndarray):
        """(GV (n_rows, n_modes), K⁻¹Gᵀ (n, n_rows), G K⁻¹ Gᵀ (n_rows, n_rows)) of a dense gap map
        G (n_rows, n): the frequency-independent factors of G Z_k⁻¹ Gᵀ, computed once per G."""
        def build(G):
            static = self.static_solve(G.T)
            return G @ self.modes, static, G @ static
        return self._projection("gap", np.asarray(gap_map, dtype=float), build)

    def load_projection(self, loads: np.ndarray):
        """(K⁻¹ f_k (m, n), Vᵀ f_k (m, n_modes)) complex of load amplitudes f (m, n): the
        frequency-independent factors of Z_k⁻¹ f_k, computed once per load."""
        def build(f):
            return self.static_solve(f.T).T, real_product(f, self.modes)
        return self._projection("load", np.asarray(loads), build)

    def row_compliance(self, gap_map: np.ndarray, receptance: np.ndarray) -> np.ndarray:
        """C_k = G Z_k⁻¹ Gᵀ = G K⁻¹ Gᵀ + (GV) diag(q_k) (GV)ᵀ (m, n_rows, n_rows) complex [m/N] of
        a dense gap map G (n_rows, n) and the receptance q (m, n_modes) of
        :meth:`dynamic_receptance`: Σ_j (G v_j)_r q_kj (G v_j)_s as one real product over the
        orders and rows per part (Re q, Im q), the scaled rows formed real."""
        gap_modes, _, static_compliance = self.gap_projection(gap_map)
        q = np.asarray(receptance)

        def part(x):
            return (gap_modes[None] * x[:, None, :]).reshape(-1, q.shape[1]) @ gap_modes.T
        rows = gap_modes.shape[0]
        return static_compliance[None] + (part(q.real) + 1j * part(q.imag)).reshape(
            q.shape[0], rows, rows)

    def singular(self, orders, omega: float) -> bool:
        """True if some Z_k(ω) is singular to working precision, |1 − a_kj| ≤ 10⁻¹³ max(1, |a_kj|)
        (an undamped resonance (kω)² = ω_j²)."""
        a = self._a(orders, omega)
        return bool(np.any(np.abs(1.0 - a) <= 1e-13 * np.maximum(1.0, np.abs(a))))


def updated_solve(basis: ModalBasis, gap_map: np.ndarray, row_stiffness: np.ndarray,
                  row_damping: np.ndarray, orders, omega: float, loads: np.ndarray) -> np.ndarray:
    """z_k = (Z_k + Gᵀ A_k G)⁻¹ f_k for the orders k (m,) and complex loads f_k (m, n): the model
    with springs k_r and dashpots c_r on the rows of G (n_rows, n dense), A_k = diag(k_r + i kω c_r)
    (a linearized contact), by Woodbury on Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ:

        y_k = Z_k⁻¹ f_k,  C_k = G Z_k⁻¹ Gᵀ,  λ_k = (I + A_k C_k)⁻¹ A_k G y_k,  z_k = y_k − Z_k⁻¹ Gᵀ λ_k,

    O(n n_modes) per order instead of a dense O(n³) solve. Raises LinAlgError if I + A_k C_k is
    singular."""
    orders = np.asarray(orders, dtype=float)
    G = np.asarray(gap_map, dtype=float)
    gap_modes, static, _ = basis.gap_projection(G)
    q = basis.dynamic_receptance(orders, omega)                            # (m, n_modes)
    y = basis.static_solve(np.asarray(loads).T).T + real_product(
        q * real_product(loads, basis.modes), basis.modes.T)
    C = basis.row_compliance(G, q)                                         # (m, n_rows, n_rows)
    A = row_stiffness[None, :] + 1j * (orders * omega)[:, None] * row_damping[None, :]
    system = np.eye(G.shape[0])[None] + A[:, :, None] * C
    lam = np.linalg.solve(system, (A * (y @ G.T))[..., None])[..., 0]     # (m, n_rows)
    return y - (real_product(lam, static.T)
                + real_product(q * real_product(lam, gap_modes), basis.modes.T))


def real_product(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A B for a complex (or real) A and a real B, as two real products (no complex copy of B)."""
    if not np.iscomplexobj(A):
        return A @ B
    # contiguous copies of the parts: a strided .real view misses the BLAS path; the two products
    # written into the parts of the result (no complex temporary 1j·(Im A B) and no sum pass)
    real = np.ascontiguousarray(A.real) @ B
    out = np.empty(real.shape, dtype=np.result_type(A.dtype, B.dtype))
    out.real = real
    out.imag = np.ascontiguousarray(A.imag) @ B
    return out


def dense_matrix(matrix) -> np.ndarray:
    """A dense float array of a sparse or dense matrix (the modal basis and the checks that work
    on the small reduced model's M, D, K)."""
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix, dtype=float)


def modal_damping_is_diagonal(modal_damping: np.ndarray, tolerance=MODAL_DAMPING_TOLERANCE) -> bool:
    """|Δ_ij| ≤ tolerance √(|Δ_ii| |Δ_jj|) + 10⁻¹⁴ max|Δ_ii| for every i ≠ j (see module)."""
    d = np.abs(np.diag(modal_damping))
    off = np.abs(modal_damping - np.diag(np.diag(modal_damping)))
    bound = tolerance * np.sqrt(np.outer(d, d)) + 1e-14 * d.max(initial=0.0)
    return bool(np.all(off <= bound))


def modal_basis(model, max_dofs=MODAL_MAX_DOFS, tolerance=MODAL_DAMPING_TOLERANCE):
    """ModalBasis of ``model`` (dense or sparse M, D, K), or None when n > ``max_dofs``, K is not
    positive definite or D is not diagonal in the undamped modes (see the module docstring)."""
    n = model.dof_count
    if n == 0 or n > max_dofs:
        return None
    M, K, D = (dense_matrix(a) for a in (model.mass, model.stiffness, model.damping))
    K, M = 0.5 * (K + K.T), 0.5 * (M + M.T)
    try:
        factor = sla.cho_factor(K)                 # K positive definite (no rigid-body mode)
        flexibility, modes = sla.eigh(M, K)        # M v = μ K v, Vᵀ K V = I
    except (np.linalg.LinAlgError, ValueError):
        return None
    flexibility, modes = flexibility[::-1], modes[:, ::-1]
    modal_damping = modes.T @ D @ modes
    if not modal_damping_is_diagonal(modal_damping, tolerance):
        return None
    return ModalBasis(modes, flexibility, np.diag(modal_damping).copy(), factor)


_CACHE: dict = {}
_SEEN_ONCE = object()


def cached_modal_basis(model):
    """:func:`modal_basis` of a dense ``model`` from its second call on, cached per model object.

    Sparse models (unreduced FE, lumped chains) get None: their per-harmonic sparse LU costs less
    than the O(n²) dense modal products.

    The first call for a model returns None (the caller factorizes): a model condensed at a single
    frequency — a fixed-frequency Newton caches its condensation, the error estimate's coarser
    model is solved at one ω — never pays the eigen-solve; from the second call (a sweep, a
    continuation, several frequencies) the basis is computed once and reused. The cache is keyed
    on id(model) and the entry dropped when the model is garbage-collected; the model must not be
    mutated (LinearModel is frozen). None is also cached when the modal path does not apply.
    """
    if sp.issparse(model.stiffness):
        return None              # SuperLU of a sparse Z_k is cheaper than the O(n²) modal products
    key = id(model)
    entry = _CACHE.get(key)
    if entry is None and key not in _CACHE:
        try:
            weakref.finalize(model, _CACHE.pop, key, None)
        except TypeError:        # not weak-referenceable: no cache (ids could be reused)
            return modal_basis(model)
        _CACHE[key] = _SEEN_ONCE
        return None
    if entry is _SEEN_ONCE:
        entry = _CACHE[key] = modal_basis(model)
    return entry
