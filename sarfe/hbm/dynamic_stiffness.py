r"""Linear part of the harmonic balance: S(ω) per harmonic, dynamic compliance condensation, recovery.

Per harmonic k the linear operator acts on (u_kc, u_ks) as

    S_k(ω) = [[K − k²ω²M,  kωD],
              [−kωD,        K − k²ω²M]],        S_0 = K,

(from u = u_c cos kθ + u_s sin kθ, u̇ = kω(−u_c sin kθ + u_s cos kθ), ü = −k²ω² u). It is applied
harmonic by harmonic; the (2H+1)n Kronecker product is never formed densely. Equivalently, with the
complex amplitude z = u_c − i u_s (u = Re(z e^{ikθ})), S_k becomes the complex dynamic stiffness

    Z_k(ω) = K − k²ω²M + i kωD,      Z_k z = f_c − i f_s,

which halves the cost of each solve.

Condensation: the linear DOFs are eliminated exactly through the dynamic compliance at the
contact rows, C_k = G Z_k⁻¹ Gᵀ (n_rows × n_rows), so that r̃ = G ũ satisfies

    R_c(r̃) = r̃ − r̃_lin + C λ̃(r̃) = 0,    r̃_lin = G S⁻¹ f̃_e,

with (2H+1) n_rows unknowns instead of (2H+1) n. The DOFs are recovered afterwards from
ũ_k = Z_k⁻¹ (f̃_k − Gᵀ λ̃_k). For a dense (reduced) model with n ≤ 3000 whose damping is
diagonal in its undamped modes (modal ζ, Rayleigh, none), Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ with the
modes V and the Cholesky factor of K computed once per model (:mod:`sarfe.hbm.modal`), so a sweep
point costs no factorization; otherwise Z_k is factorized once per harmonic and frequency (dense
LU, or SuperLU when the model is sparse). A singular Z_k (undamped resonance, free-floating
structure at k = 0) makes :func:`condense` return None so that the caller falls back to the full
residual.

With a harmonic set (:mod:`sarfe.hbm.harmonic_set`) only the kept orders k are factorized and C,
r̃_lin, Y_k hold only their blocks (dropped orders: zero), so the cost falls with the kept count.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sarfe.hbm.harmonics import derivative_matrix
from sarfe.hbm.modal import ModalBasis, cached_modal_basis, real_product


def apply_dynamic_stiffness(model, omega: float, U: np.ndarray) -> np.ndarray:
    """S(ω) Ũ for Ũ (2H+1, n) [m] → (2H+1, n) [N], harmonic by harmonic (3 matrix products)."""
    U = np.asarray(U, dtype=float)
    H = (U.shape[0] - 1) // 2
    KU = np.asarray(model.stiffness @ U.T).T
    MU = np.asarray(model.mass @ U.T).T
    DU = np.asarray(model.damping @ U.T).T
    k = np.arange(1, H + 1)[:, None]
    out = KU.copy()
    out[1::2] += -(k * omega) ** 2 * MU[1::2] + k * omega * DU[2::2]
    out[2::2] += -(k * omega) ** 2 * MU[2::2] - k * omega * DU[1::2]
    return out


def apply_dynamic_stiffness_derivative(model, omega: float, U: np.ndarray) -> np.ndarray:
    """∂S/∂ω Ũ (2H+1, n): cos rows −2k²ωM u_c + kD u_s, sin rows −2k²ωM u_s − kD u_c."""
    U = np.asarray(U, dtype=float)
    H = (U.shape[0] - 1) // 2
    MU = np.asarray(model.mass @ U.T).T
    DU = np.asarray(model.damping @ U.T).T
    k = np.arange(1, H + 1)[:, None]
    out = np.zeros_like(U)
    out[1::2] = -2 * k**2 * omega * MU[1::2] + k * DU[2::2]
    out[2::2] = -2 * k**2 * omega * MU[2::2] - k * DU[1::2]
    return out


def dynamic_stiffness_matrix(model, omega: float, harmonics: int) -> sp.csr_matrix:
    """Sparse block-diagonal S(ω) of size (2H+1)n, harmonic-major (for the uncondensed Newton).

    S = I⊗K − ω² diag(k²)⊗M + ω ∇⊗D  (∇ = :func:`derivative_matrix`). The three Kronecker
    products are built once per (model, H) on one sparsity pattern (:func:`_dynamic_stiffness_parts`),
    so each call only forms the values a₀ + ω b₁ + ω² b₂.
    """
    pattern, a0, b1, b2 = _dynamic_stiffness_parts(model, int(harmonics))
    return sp.csr_matrix((a0 + omega * b1 + omega**2 * b2, pattern.indices.copy(),
                          pattern.indptr.copy()), shape=pattern.shape)


_STIFFNESS_PARTS: dict = {}


def _dynamic_stiffness_parts(model, harmonics):
    """(pattern, a₀, b₁, b₂): the union sparsity pattern of I⊗K, ∇⊗D, diag(k²)⊗M and the values of
    I⊗K, ∇⊗D and −diag(k²)⊗M on it; cached per model object (id, dropped when it is collected)."""
    per_model = _STIFFNESS_PARTS.get(id(model))
    if per_model is not None and harmonics in per_model:
        return per_model[harmonics]
    K, M, D = (sp.csr_matrix(a) for a in (model.stiffness, model.mass, model.damping))
    P = 2 * harmonics + 1
    orders = np.concatenate(([0], np.repeat(np.arange(1, harmonics + 1), 2)))
    terms = (sp.kron(sp.identity(P), K, format="csr"),
             sp.kron(sp.csr_matrix(derivative_matrix(harmonics)), D, format="csr"),
             -sp.kron(sp.diags(orders**2.0), M, format="csr"))
    pattern = sum(abs(t) for t in terms).tocsr()
    pattern.sort_indices()
    rows = np.repeat(np.arange(pattern.shape[0]), np.diff(pattern.indptr))
    values = [np.asarray(t[rows, pattern.indices]).ravel() for t in terms]
    parts = (pattern, *values)
    if per_model is None:
        try:
            weakref.finalize(model, _STIFFNESS_PARTS.pop, id(model), None)
        except TypeError:                  # not weak-referenceable: do not cache
            return parts
        per_model = _STIFFNESS_PARTS[id(model)] = {}
    per_model[harmonics] = parts
    return parts


def hill_matrices(model, omega: float, harmonics: int):
    """(M̃, D̃) of the Hill problem s² M̃ + s D̃ + ∂R/∂ũ: M̃ = I⊗M, D̃ = I⊗D + 2ω ∇⊗M (sparse)."""
    P = 2 * harmonics + 1
    M, D = sp.csr_matrix(model.mass), sp.csr_matrix(model.damping)
    Mt = sp.kron(sp.identity(P), M, format="csr")
    Dt = sp.kron(sp.identity(P), D, format="csr") + 2 * omega * sp.kron(
        sp.csr_matrix(derivative_matrix(harmonics)), M, format="csr")
    return Mt, Dt


def _factorize(Z):
    """solve(b) with a sparse LU of one complex Z_k, or None when it is singular."""
    try:
        lu = spla.splu(sp.csc_matrix(Z))
    except RuntimeError:
        return None
    diag = np.abs(lu.U.diagonal())
    if diag.min() <= 1e-13 * diag.max():
        return None
    return lu.solve


def to_complex(F):
    """Complex amplitudes (H+1, ...) f_c − i f_s of harmonic arrays F (2H+1, ...) (row 0: mean)."""
    return np.concatenate([F[:1].astype(complex), F[1::2] - 1j * F[2::2]], axis=0)


def from_complex(Z):
    """Inverse of :func:`to_complex`: (H+1, ...) complex → (2H+1, ...) real."""
    out = np.empty((2 * Z.shape[0] - 1,) + Z.shape[1:])
    out[0] = Z[0].real
    out[1::2], out[2::2] = Z[1:].real, -Z[1:].imag
    return out


@dataclass(frozen=True)
class Condensation:
    """Dynamic compliance of the contact rows at one ω (see module docstring).

    compliance: C (P, P) real, P = (2H+1) n_rows, harmonic-major, block diagonal over harmonics
    [m/N]; linear_response: r̃_lin (2H+1, n_rows) [m]; forced: y_k = Z_k⁻¹ f_k (m, n) complex
    (stored on the factorization path, ``solved_forced``; formed on first use on the modal path,
    where Newton needs only G y_k = r̃_lin);
    orders: the m kept orders k (all 0 … H, or a harmonic set: then P counts the kept rows only
    and r̃_lin is zero in the dropped rows); admittance: Y_k = Z_k⁻¹ Gᵀ (m, n, n_rows) complex —
    stored on the factorization path (``solved_admittance``), formed on first use on the modal path
    (``modal``: Y_k = K⁻¹Gᵀ + V diag(q_k) (GV)ᵀ). Use :meth:`apply_admittance` /
    :meth:`apply_admittance_transpose` to act with Y without forming it.
    """

    omega: float
    compliance: np.ndarray
    linear_response: np.ndarray
    solved_forced: np.ndarray = None
    orders: np.ndarray = None
    solved_admittance: np.ndarray = None
    modal: ModalCompliance = None

    @cached_property
    def forced(self) -> np.ndarray:
        """y_k = Z_k⁻¹ f_k (m, n) complex; modal: K⁻¹ f_k + V (q_k ⊙ Vᵀ f_k)."""
        if self.solved_forced is not None:
            return self.solved_forced
        m = self.modal
        y = m.static_load.copy()
        loaded = np.flatnonzero(np.any(m.modal_load != 0, axis=1))    # (usually order 1 only)
        y[loaded] += real_product(m.receptance[loaded] * m.modal_load[loaded], m.basis.modes.T)
        return y

    @cached_property
    def admittance(self) -> np.ndarray:
        if self.solved_admittance is not None:
            return self.solved_admittance
        m = self.modal
        return m.static_admittance[None] + (m.basis.modes[None] * m.receptance[:, None, :]) \
            @ m.gap_modes.T

    @cached_property
    def _compliance_blocks(self):
        """(mean block (n_rows, n_rows) or None, (cos, sin) blocks (m', 2 n_rows, 2 n_rows)) of C."""
        n_rows = self.linear_response.shape[1]
        orders = np.arange((self.linear_response.shape[0] + 1) // 2) if self.orders is None \
            else np.asarray(self.orders)
        first = n_rows if orders.size and orders[0] == 0 else 0
        C = self.compliance
        pairs = (C.shape[0] - first) // (2 * n_rows)
        blocks = C[first:, first:].reshape(pairs, 2 * n_rows, pairs, 2 * n_rows)
        index = np.arange(pairs)
        return (C[:first, :first] if first else None), blocks[index, :, index, :]

    def apply_compliance(self, B) -> np.ndarray:
        """C B (P, q) dense for a dense or sparse B (P, q): C is block diagonal over the kept orders
        (the mean block, then one (cos, sin) block of 2 n_rows per order), applied block by block."""
        mean, pairs = self._compliance_blocks
        first = 0 if mean is None else mean.shape[0]
        if sp.issparse(B):
            B = sp.csr_matrix(B)
            out = np.empty(B.shape)
            if first:
                out[:first] = (B[:first].T @ mean.T).T
            width = pairs.shape[1] if pairs.shape[0] else 0
            for j in range(pairs.shape[0]):
                block = slice(first + j * width, first + (j + 1) * width)
                out[block] = (B[block].T @ pairs[j].T).T
            return out
        out = np.empty(B.shape, dtype=np.result_type(B, float))
        if first:
            np.matmul(mean, B[:first], out=out[:first])
        if pairs.shape[0]:      # the products written in place (no (P, q) temporary to copy)
            width = pairs.shape[1]
            np.matmul(pairs, B[first:].reshape(pairs.shape[0], width, -1),
                      out=out[first:].reshape(pairs.shape[0], width, -1))
        return out

    def apply_admittance(self, L: np.ndarray) -> np.ndarray:
        """Y_k λ_k (..., m, n) complex for complex λ (..., m, n_rows) of the kept orders (leading
        axes: several load cases at once)."""
        if self.modal is None:
            return np.einsum("knm,...km->...kn", self.solved_admittance, L)
        m = self.modal
        shape = L.shape[:-1]
        flat = L.reshape(-1, L.shape[-1])
        modal = (m.receptance * real_product(flat, m.gap_modes).reshape(shape + (-1,)))
        return (real_product(flat, m.static_admittance.T).reshape(shape + (-1,))
                + real_product(modal.reshape(flat.shape[0], -1), m.basis.modes.T).reshape(
                    shape + (-1,)))

    def apply_admittance_transpose(self, V: np.ndarray) -> np.ndarray:
        """Y_kᵀ v_k = G Z_k⁻¹ v_k (m, n_rows) complex for complex v (m, n) (Z_k symmetric)."""
        if self.modal is None:
            return np.einsum("knm,kn->km", self.solved_admittance, V)
        m = self.modal
        return real_product(V, m.static_admittance) + real_product(
            m.receptance * real_product(V, m.basis.modes), m.gap_modes.T)


@dataclass(frozen=True)
class ModalCompliance:
    """The modal factors of one condensation, Y_k = K⁻¹Gᵀ + V diag(q_k) (GV)ᵀ: basis
    (:class:`ModalBasis`), receptance q_kj (m, n_modes) complex (dynamic part, at the kept orders
    and ω), gap_modes GV (n_rows, n_modes), static_admittance K⁻¹Gᵀ (n, n_rows); static_load
    K⁻¹ f_k (m, n) and modal_load Vᵀ f_k (m, n_modes) complex of the kept orders' excitation."""

    basis: ModalBasis
    receptance: np.ndarray
    gap_modes: np.ndarray
    static_admittance: np.ndarray
    static_load: np.ndarray = None
    modal_load: np.ndarray = None


def _solve_factorized(model, Gd, forces, k, omega):
    """(Y, y) = Z_k⁻¹ [Gᵀ, f_k] by one factorization per kept order, or None if a Z_k is singular."""
    n_rows, n = Gd.shape
    rhs = np.empty((k.size, n, n_rows + 1), dtype=complex)
    rhs[:, :, :n_rows] = Gd.T
    rhs[:, :, n_rows] = forces
    if sp.issparse(model.stiffness):
        solution = np.empty_like(rhs)
        K, M, D = (sp.csc_matrix(a, dtype=complex)
                   for a in (model.stiffness, model.mass, model.damping))
        for i, order in enumerate(k):
            Z = K - (order * omega) ** 2 * M + 1j * order * omega * D
            solve = _factorize(Z)
            if solve is None:
                return None
            solution[i] = solve(rhs[i])
    else:
        K, M, D = (np.asarray(a, dtype=float) for a in (model.stiffness, model.mass, model.damping))
        Z = K - ((k * omega) ** 2)[:, None, None] * M + 1j * (k * omega)[:, None, None] * D
        try:
            solution = np.linalg.solve(Z, rhs)
        except np.linalg.LinAlgError:
            return None
        # near-singular Z_k: ‖Z_k⁻¹ b‖ ‖Z_k‖ ≫ ‖b‖ (cheap bound on the condition number)
        size = np.abs(Z).max(axis=(1, 2)) * np.abs(solution).max(axis=(1, 2))
        if np.any(size > 1e13 * np.abs(rhs).max(axis=(1, 2)).clip(1e-300)):
            return None
    if not np.all(np.isfinite(solution)):
        return None
    return solution[:, :, :n_rows], solution[:, :, n_rows]


def _modal_basis_for(model, modal):
    if modal is None or modal is False:
        return None
    if isinstance(modal, ModalBasis):
        return modal
    if modal in ("auto", True):
        return cached_modal_basis(model)
    raise ValueError(f"modal must be 'auto', a ModalBasis, True, False or None, got {modal!r}")


def condense(model, gap_map, excitation: np.ndarray, omega: float,
             orders=None, modal="auto") -> Condensation | None:
    """C = G Z_k⁻¹ Gᵀ (kept rows only), r̃_lin and y_k = Z_k⁻¹ f_k for the kept orders k (``orders``,
    default 0…H); None if a Z_k is singular.

    Modal path (``modal`` = 'auto' and :func:`sarfe.hbm.modal.cached_modal_basis` applies — a
    dense model (e.g. Craig–Bampton), n ≤ 3000, K positive definite and D diagonal in the undamped
    modes — or ``modal`` = a ModalBasis of this model): C_k = G K⁻¹ Gᵀ + (GV) diag(q_k) (GV)ᵀ, y_k = K⁻¹ f_k + V (q_k ⊙ Vᵀ f_k), no
    factorization per point (the eigen-solve and the Cholesky factor of K are computed once per
    model, at its second condensation, and cached: the first one is factorized). Otherwise (``modal`` = False / None, or the basis does not apply):
    dense models, one batched LAPACK solve of Z_k [Gᵀ, f_k] over the kept harmonics (singular when
    LAPACK says so or when ‖Z_k‖ max|Z_k⁻¹ b| > 10¹³ max|b|); sparse models, one SuperLU per kept
    harmonic.
    """
    F = np.asarray(excitation, dtype=float)
    H = (F.shape[0] - 1) // 2
    G = sp.csr_matrix(gap_map)
    n_rows, n = G.shape
    k = np.arange(H + 1) if orders is None else np.asarray(orders, dtype=int)
    Gd = G.toarray()
    forces = to_complex(F)[k]                               # (m, n)
    basis = _modal_basis_for(model, modal)
    if basis is not None:
        if basis.singular(k, omega):
            return None
        g = basis.dynamic_receptance(k, omega)              # (m, n_modes)
        # GV, K⁻¹Gᵀ, G K⁻¹ Gᵀ, K⁻¹ f_k and Vᵀ f_k do not depend on ω: once per sweep
        gap_modes, static, _ = basis.gap_projection(Gd)
        static_forced, modal_forced = basis.load_projection(forces)
        # G y_k = G K⁻¹ f_k + (GV)(q_k ⊙ Vᵀ f_k): O(n_rows n_modes), y_k itself only on demand
        gy = real_product(static_forced, Gd.T) + real_product(g * modal_forced, gap_modes.T)
        Ck = basis.row_compliance(Gd, g)                    # (m, n_rows, n_rows)
        factors = dict(modal=ModalCompliance(basis, g, gap_modes, static, static_forced,
                                             modal_forced))
    else:
        solved = _solve_factorized(model, Gd, forces, k, omega)
        if solved is None:
            return None
        Y, y = solved
        Ck = Gd @ Y                                         # (m, n_rows, n_rows)
        gy = y @ Gd.T
        factors = dict(solved_admittance=Y, solved_forced=y)
    if not (np.all(np.isfinite(Ck)) and np.all(np.isfinite(gy))):
        return None
    # kept rows (orders sorted) in harmonic-major order: the mean if kept, then (cos, sin) per k
    mean = k == 0
    first = int(mean.any())
    P_k = first + 2 * int((~mean).sum())
    C = np.zeros((P_k, n_rows, P_k, n_rows))
    if first:
        C[0, :, 0, :] = Ck[mean][0].real
    c = np.arange(first, P_k, 2)
    s = c + 1
    C[c, :, c, :], C[c, :, s, :] = Ck[~mean].real, Ck[~mean].imag
    C[s, :, c, :], C[s, :, s, :] = -Ck[~mean].imag, Ck[~mean].real
    lin = np.zeros((H + 1, n_rows), dtype=complex)
    lin[k] = gy
    r_lin = from_complex(lin)
    return Condensation(float(omega), C.reshape(P_k * n_rows, P_k * n_rows), r_lin, orders=k,
                        **factors)


def _kept_orders(condensation, H):
    return np.arange(H + 1) if condensation.orders is None else condensation.orders


def recover_displacement(condensation: Condensation, contact_force: np.ndarray) -> np.ndarray:
    """ũ (2H+1, n) from λ̃ (2H+1, n_rows): ũ_k = Z_k⁻¹ (f̃_k − Gᵀ λ̃_k) = y_k − Y_k λ̃_k (kept k;
    dropped orders zero)."""
    H = (np.asarray(contact_force).shape[0] - 1) // 2
    k = _kept_orders(condensation, H)
    L = to_complex(np.asarray(contact_force, dtype=float))[k]
    z = np.zeros((H + 1, condensation.forced.shape[1]), dtype=complex)
    z[k] = condensation.forced - condensation.apply_admittance(L)
    return from_complex(z)


def modal_omega_derivative(condensation: Condensation, contact_force: np.ndarray) -> np.ndarray:
    """∂R_c/∂ω (2H+1, n_rows) of a modal condensation from λ̃ alone (no ũ): with
    Z_k⁻¹ = K⁻¹ + V diag(q_k) Vᵀ and ũ_k = Z_k⁻¹ (f_k − Gᵀ λ_k),

        ∂R_c/∂ω = −G (∂Z_k⁻¹/∂ω) (f_k − Gᵀ λ_k) = −(GV) [q'_k ⊙ (Vᵀ f_k − (GV)ᵀ λ_k)],
        q'_kj = ∂q_kj/∂ω = a'_kj / (1 − a_kj)²,   a'_kj = 2k²ω μ_j − i k δ_j   [s],

    O(n_rows n_modes) per order where :func:`condensed_omega_derivative` is O(n n_modes) (dropped
    orders zero). Same value (the modal form of G Z⁻¹ Z' ũ)."""
    m = condensation.modal
    H = (np.asarray(contact_force).shape[0] - 1) // 2
    orders = _kept_orders(condensation, H)
    slope = m.basis.receptance_slope(orders, condensation.omega)             # q'_k (m, n_modes)
    L = to_complex(np.asarray(contact_force, dtype=float))[orders]          # (m, n_rows)
    modal = m.modal_load - real_product(L, m.gap_modes)                     # Vᵀ(f − Gᵀλ)
    out = np.zeros((H + 1, m.gap_modes.shape[0]), dtype=complex)
    out[orders] = -real_product(slope * modal, m.gap_modes.T)
    return from_complex(out)


def condensed_omega_derivative(model, condensation: Condensation, U: np.ndarray) -> np.ndarray:
    """∂R_c/∂ω = G Z⁻¹ (∂Z/∂ω) ũ = Yᵀ Z' ũ (Z symmetric), Z'_k = −2k²ωM + i kD; (2H+1, n_rows)
    (dropped orders zero)."""
    H = (U.shape[0] - 1) // 2
    orders = _kept_orders(condensation, H)
    k = orders[:, None]
    z = to_complex(U)[orders]
    Z = np.concatenate([z.real, z.imag])                # real products (M, D real: no complex copy)
    MZ, DZ = np.asarray(model.mass @ Z.T).T, np.asarray(model.damping @ Z.T).T
    m = orders.size
    dz = (-2 * k**2 * condensation.omega * (MZ[:m] + 1j * MZ[m:])
          + 1j * k * (DZ[:m] + 1j * DZ[m:]))
    out = np.zeros((H + 1, condensation.linear_response.shape[1]), dtype=complex)
    out[orders] = condensation.apply_admittance_transpose(dz)
    return from_complex(out)
