r"""Hill stability on the contact rows: count the Floquet exponents right of the imaginary axis
with the argument principle on det(I + C(s) 𝒥(s)), no eigen-solve of a Hill matrix.

Hill's operator (:mod:`sarfe.hbm.stability`) is T(s) = L(s) + (I⊗G)ᵀ 𝒥(s) (I⊗G) with the linear
structure L(s) = s² M̃ + s D̃ + S(ω) and the contact term 𝒥(s) on the (2H+1)·n_rows contact rows
(the AFT Jacobian, the Jenkins memory at s, s × the dashpots of rate-dependent laws;
:class:`sarfe.hbm.stability_contacts.ContactOperator`). Where L(s) is regular,

    det T(s) = det L(s) · det F(s),      F(s) = I + C(s) 𝒥(s),      C(s) = (I⊗G) L(s)⁻¹ (I⊗G)ᵀ,

so every exponent of T that is not a (damped) exponent of the linear structure is a zero of the
small matrix F(s) [(2H+1) n_rows square, only the rows the contacts load]. L(s) is block diagonal
over the harmonics; for harmonic k its (cos, sin) block acts on z± = a ∓ i b through Z(s ± ikω),
Z(λ) = K + λ D + λ² M, and the modal basis of the model (:mod:`sarfe.hbm.modal`, Vᵀ K V = I,
Vᵀ M V = diag μ, Vᵀ D V = diag δ) gives every G Z(λ)⁻¹ Gᵀ without a factorization:

    A(λ) = G K⁻¹ Gᵀ + (GV) diag(−a/(1+a)) (GV)ᵀ,   a_j = λ δ_j + λ² μ_j,
    C_k(s) = [[½(A₊ + A₋), ½i(A₋ − A₊)], [½i(A₊ − A₋), ½(A₊ + A₋)]],   A± = A(s ± ikω),

(C₀(s) = A(s) for the mean), which at s = 0 is the condensed compliance of the Newton solver.

The verdict of the full method (:func:`sarfe.hbm.stability.hill_stability`) is decided by the
exponents in the strip |Im s| ≤ 1.01 ω/2: unstable when one has Re s > tolerance·ω, uncertain
when the leading one is within ±``uncertain_band``·ω of 0. The number of zeros of det F in the
half-strip Ω = {−ε < Re s < X, |Im s| < 1.01 ω/2}, ε = uncertain_band·ω, is the winding number of
det F along its boundary (no pole inside: the poles are the structure's own exponents, all left
of −ε when every mode is damped; X bounds |s| of any exponent, |s| ≤ ‖d‖ + √‖k‖ from
pᴴT(s)p = 0). F is real for real s, so det F(s̄) = conj det F(s) and the count is the change of
arg det F along the upper half of the boundary divided by π. The contour is sampled adaptively
(every step's change of arg below π/3).

No zero in Ω: stable, and no exponent is within the uncertain band; the leading exponent reported
is the least damped exponent of the structure (max Re of μ s² + δ s + 1 = 0; the coupled
exponents left of −ε are not located). Some zero in Ω, a pole near the contour, a model without
a modal basis or a contour that does not close on a multiple of π: ``None`` — the caller then
locates the exponents by the Ritz-basis Hill method (:mod:`sarfe.hbm.stability_condensed`).
Measured against the full Hill method in tests/hbm/test_stability_rows.py and
benchmarks/bench_stability.py.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .aft import jacobian_matrix
from .modal import cached_modal_basis

PHASE_STEP = np.pi / 3       # largest change of arg det F between neighbouring contour samples
MAX_EVALUATIONS = 1500       # det F evaluations per point before giving up (→ Ritz method)


def structural_exponents(flexibility, damping):
    """Roots of μ_j s² + δ_j s + 1 = 0 per mode (2 n_modes,) complex [1/s]: the exponents of the
    structure without contacts (K-orthonormal modes: μ_j = 1/ω_j² [s²], δ_j [s])."""
    mu, delta = np.asarray(flexibility, float), np.asarray(damping, float)
    root = np.sqrt(delta.astype(complex) ** 2 - 4.0 * mu)
    return np.concatenate([(-delta + root) / (2 * mu), (-delta - root) / (2 * mu)])


class ContactRowDeterminant:
    """s ↦ det F(s) on the loaded contact rows (module docstring), for one periodic solution,
    evaluated at many s at once (the friction-memory march runs once for all of them).

    basis: :class:`sarfe.hbm.modal.ModalBasis` of the model; gap_map G (n_rows, n); omega [rad/s];
    harmonics H; jacobian: 𝒥_AFT (P n_rows square, harmonic-major); damping_jacobian: the
    dashpot part of rate-dependent laws or None; operator: ContactOperator (friction memory) or
    None."""

    def __init__(self, basis, gap_map, omega, harmonics, jacobian, damping_jacobian=None,
                 operator=None):
        G = gap_map.toarray() if sp.issparse(gap_map) else np.asarray(gap_map, float)
        self.n_rows, self.H, self.omega = G.shape[0], int(harmonics), float(omega)
        self.gap_modes = G @ basis.modes                              # GV (n_rows, n)
        self.static = G @ basis.static_solve(G.T)                     # G K⁻¹ Gᵀ
        self.mu, self.delta = basis.flexibility, basis.damping
        dense = (lambda a: a.toarray() if sp.issparse(a) else np.asarray(a))  # noqa: E731
        size = (2 * self.H + 1) * self.n_rows
        self.memory = operator if operator is not None and operator.has_memory else None
        # 𝒥(s) = 𝒥_AFT + (𝒥(s) − 𝒥_AFT): the pointwise part fixed, the memory blocks at s
        self.fixed = dense(jacobian).astype(complex)
        if operator is not None:
            self.fixed = self.fixed + dense(operator.pointwise_correction)
        self.damping = None if damping_jacobian is None else dense(damping_jacobian)
        self.scatter = []
        if self.memory is not None:
            for rows in (g["rows"] for g in self.memory.memory):
                P, m = 2 * self.H + 1, rows.shape[1]
                local = (np.arange(P)[:, None] * self.n_rows + rows[:, None, :]).reshape(
                    rows.shape[0], P * m)
                valid = np.repeat((rows >= 0)[:, None, :], P, axis=1).reshape(rows.shape[0], P * m)
                mask = valid[:, :, None] & valid[:, None, :]
                flat = (local[:, :, None] * size + local[:, None, :])
                index = flat[mask]
                self.scatter.append((mask, index, np.unique(index).size == index.size))
        pattern = np.abs(self.contact_terms(np.array([0.37 + 0.21j]) * self.omega)[0])
        loaded = pattern.sum(axis=0) + pattern.sum(axis=1) > 0
        self.loaded = np.flatnonzero(loaded)

    def contact_terms(self, s):
        """𝒥(s) (n_s, P n_rows, P n_rows) complex dense, for s (n_s,)."""
        s = np.asarray(s, dtype=complex)
        size = self.fixed.shape[0]
        J = np.broadcast_to(self.fixed, (s.size, size, size)).copy()
        if self.memory is not None:
            flat = J.reshape(s.size, -1)
            groups = self.memory.blocks_at_many(s)
            for (rows, blocks), (mask, index, unique) in zip(groups, self.scatter):
                values = blocks[:, mask]                              # (n_s, entries)
                if unique:
                    flat[:, index] += values
                    continue
                for i in range(s.size):      # indices repeat: accumulate
                    flat[i] += np.bincount(index, values[i].real, size * size) \
                        + 1j * np.bincount(index, values[i].imag, size * size)
            J = flat.reshape(s.size, size, size)
        if self.damping is not None:
            J = J + s[:, None, None] * self.damping[None]
        return J

    def compliance_blocks(self, s):
        """(C₀ (n_s, n_rows, n_rows), C_k (n_s, H, 2 n_rows, 2 n_rows)) complex: blocks of C(s)."""
        s = np.asarray(s, dtype=complex)
        k = np.arange(1, self.H + 1)
        lam = np.concatenate([s[:, None], s[:, None] + 1j * k * self.omega,
                              s[:, None] - 1j * k * self.omega], axis=1)       # (n_s, 2H+1)
        a = lam[..., None] * self.delta + lam[..., None] ** 2 * self.mu
        q = -a / (1.0 + a)                                                     # (n_s, 2H+1, n)
        A = self.static + np.matmul(q[..., None, :] * self.gap_modes, self.gap_modes.T)
        plus, minus = A[:, 1:self.H + 1], A[:, self.H + 1:]
        mean, half = 0.5 * (plus + minus), 0.5j * (minus - plus)
        nr = self.n_rows
        blocks = np.empty((s.size, self.H, 2 * nr, 2 * nr), complex)
        blocks[..., :nr, :nr], blocks[..., :nr, nr:] = mean, half
        blocks[..., nr:, :nr], blocks[..., nr:, nr:] = -half, mean
        return A[:, 0], blocks

    def matrices(self, s):
        """F(s) on the loaded rows (n_s, n_loaded, n_loaded) complex."""
        s = np.asarray(s, dtype=complex)
        J = self.contact_terms(s)[:, :, self.loaded]
        C0, Ck = self.compliance_blocks(s)
        nr, width = self.n_rows, J.shape[2]
        CJ = np.empty_like(J)
        CJ[:, :nr] = C0 @ J[:, :nr]
        CJ[:, nr:] = np.matmul(Ck, J[:, nr:].reshape(s.size, self.H, 2 * nr, width)).reshape(
            s.size, -1, width)
        F = CJ[:, self.loaded]
        F[:, np.arange(width), np.arange(width)] += 1.0
        return F

    def log_determinants(self, s):
        """log det F(s) (n_s,) complex: log|det| + i arg det (nan where det F = 0)."""
        sign, logabs = np.linalg.slogdet(self.matrices(s))
        bad = ~np.isfinite(logabs) | (sign == 0)
        out = logabs + 1j * np.angle(sign)
        out[bad] = np.nan
        return out


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


def _upper_contour(epsilon, X, top, pole_distance):
    """Samples of the upper half of the boundary of Ω, counter-clockwise: (X, 0) → (X, top) →
    (−ε, top) → (−ε, 0); geometric spacing along the top edge, steps of at most twice the
    distance of the nearest pole along the left edge (the poles lie left of −ε; a pole
    at distance d turns arg det F by at most 2 atan(1) = π/2 over such a step, and the refinement
    of :func:`winding_count` halves steps that turn it by more than π/3)."""
    right = X + 1j * top * np.linspace(0.0, 1.0, 3)
    depth = np.concatenate([np.geomspace(X + epsilon, 1e-2 * top, 12)[1:], [0.0]])
    count = int(np.clip(np.ceil(0.5 * top / pole_distance), 8, 64))
    left = 1j * top * np.linspace(1.0, 0.0, count + 1)[1:]
    return np.concatenate([right, depth - epsilon + 1j * top, left - epsilon])


def winding_count(log_det, points, step=PHASE_STEP, budget=MAX_EVALUATIONS):
    """Change of arg f along the polyline ``points`` / π, f = exp(log_det(s)) with log_det
    vectorized over s; a segment is halved while its change of arg exceeds ``step``. Returns
    (Δarg/π, evaluations), or (nan, evaluations) when f vanishes on the path or the budget runs
    out."""
    points = np.asarray(points, dtype=complex)
    values = log_det(points)
    evaluations = points.size
    while True:
        if np.any(np.isnan(values)):
            return float("nan"), evaluations
        change = np.diff(values)
        phase = np.angle(np.exp(1j * change.imag))
        coarse = np.flatnonzero(np.abs(phase) > step)
        if coarse.size == 0:
            return float(phase.sum() / np.pi), evaluations
        middle = 0.5 * (points[coarse] + points[coarse + 1])
        if evaluations + middle.size > budget or np.any(
                np.abs(points[coarse + 1] - points[coarse]) < 1e-9 * np.abs(middle).clip(1.0)):
            return float("nan"), evaluations
        points = np.insert(points, coarse + 1, middle)
        values = np.insert(values, coarse + 1, log_det(middle))
        evaluations += middle.size


def contact_row_stability(model, contacts, omega, harmonics, forces, operator=None,
                          uncertain_band=1e-4):
    """StabilityResult when the contact-row count decides it (no exponent right of −ε), else None.
    (No exponent right of −ε is 'stable' for every stability tolerance ≥ 0 of the full method.)

    forces: the AFT :class:`ContactForces` of the orbit (all harmonic rows, blocks computed);
    operator: the :class:`ContactOperator` (friction memory) or None. See the module docstring.
    """
    from .stability import StabilityResult

    basis = cached_modal_basis(model) or cached_modal_basis(model)
    if basis is None or model.dof_count == 0:
        return None
    omega, H = abs(float(omega)), int(harmonics)
    epsilon = uncertain_band * omega
    structure = structural_exponents(basis.flexibility, basis.damping)
    least_damped = float(structure.real.max())
    if not least_damped < -2.0 * epsilon:       # a pole on or right of the contour
        return None
    n_rows = contacts.row_count
    J = jacobian_matrix(forces.blocks, n_rows, H)
    Jd = jacobian_matrix(forces.damping_blocks, n_rows, H) if forces.damping_blocks else None
    det = ContactRowDeterminant(basis, contacts.gap_map, omega, H, J, Jd, operator)
    if det.loaded.size == 0:
        return StabilityResult(True, least_damped, "", structure)
    # ‖𝒥(s)‖ for Re s ≥ 0: twice its largest value at s = 0, ω, 10ω (the memory factors e^{−shd}
    # have modulus ≤ 1 there; the pointwise part does not depend on s)
    probes = det.contact_terms(np.array([0.0, omega, 10.0 * omega]))
    jacobian_norm = 2.0 * max(np.linalg.norm(p, 2) for p in probes)
    damping_norm = 0.0 if Jd is None else float(np.linalg.norm(Jd.toarray(), 2))
    X = exponent_bound(basis, det.gap_modes, omega, H, jacobian_norm, damping_norm)
    contour = _upper_contour(epsilon, X, 0.505 * omega, -least_damped)
    count, _ = winding_count(det.log_determinants, contour)
    if not np.isfinite(count) or abs(count - round(count)) > 0.1 or round(count) != 0:
        return None
    return StabilityResult(True, least_damped, "", structure)
