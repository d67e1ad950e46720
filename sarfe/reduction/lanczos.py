r"""Block Lanczos in the M inner product: the Krylov engine of every fixed-interface mode search.

The generalized problem K φ = λ M φ (K, M symmetric, M positive definite; λ = ω² [rad²/s²]) is
solved by shift-invert: with a shift σ and the factor of K − σM,

    A = (K − σM)⁻¹ M,   A φ = θ φ,   λ = σ + 1/θ,

whose largest |θ| — the eigenvalues nearest σ — converge first. A is M-symmetric, so a block
Lanczos run in the M inner product builds Q (n, m) with Qᵀ M Q = I and the projected matrix
T = Qᵀ M A Q (m, m); T's eigenpairs (θ, y) give Ritz pairs (σ + 1/θ, Q y) with M-norm residual
‖A Q y − θ Q y‖_M = ‖B_k y_last‖ (B_k the last block's coupling). Every step is ONE multi-RHS
solve with ``block_size`` columns (cheaper per column than single solves).

σ = 0 (A = K⁻¹ M, K positive definite): the lowest modes, used by Craig–Bampton both for a whole
search and for run 0 of spectrum slicing (:mod:`sarfe.reduction.fixed_interface_modes`). σ > 0:
the shifted runs of :mod:`sarfe.reduction.spectrum_slicing`.

A Ritz pair is converged when ‖A φ − θ φ‖_M ≤ tol·|θ|, relative to its own θ: a value next to
the shift, with a huge θ, must not loosen the test for the others. At σ = 0 a test relative to
the largest θ (the former uncapped search's) is looser for the higher modes by (ω/ω_1)², and
its eigenvalue error ~ (tol θ_max)²/gap grows with it: 4.3e-11 relative against a dense
reference on the 40 mm door trim (279 modes to 1.2 kHz; 5e-13 with the per-value test), for
8–9 % fewer solves and ≈ 12 % less CPU (15 mm door trim, 317 modes; demo, 212 modes). One test
for every run keeps the uncapped search and run 0 the same computation
(benchmarks/results/lanczos_unified.md). Every run re-orthogonalizes a new block against the
whole stored basis only when Simon's recurrence estimates its M-orthogonality to an older block
above 1e-10 (partial re-orthogonalization, :func:`shifted_block_lanczos`): about every second step
on the door trim, 15–17 % less CPU per run, the same Ritz values to ~1e-14. Blocks of 12 columns:
on the door trim a shifted window converges in 10 % fewer columns than with 16 for 6 % less CPU
(the multi-RHS solves cost a little more per column); 24 and 32 took 24 % and 42 % more CPU. At
σ = 0 (15 mm door trim, 317 modes) 12 columns take 877 solves against 937 with 16, for the same
CPU within the noise.

Units: whatever K and M carry (Craig–Bampton: K_ii [N/m], M_ii [kg], λ [rad²/s²]).
"""
from __future__ import annotations

import numpy as np

# partial re-orthogonalization: the estimated |Q_jᵀ M q| of the new block against the older ones
# that triggers a full pass (semi-orthogonality is √ε ≈ 1.5e-8; kept lower so that the Ritz
# vectors stay M-orthonormal to ~1e-10)
_ORTHOGONALITY = 1e-10
_EPS = np.finfo(float).eps
# the Ritz pairs (a dense eigh of T, O(m³)) once the basis has grown by this share since the last
# time: at m ≈ 800 columns the eigh costs 10× a block step, and checking every step took 13 of the
# 30 s of the instrument panel's two Craig–Bampton runs; a run then stops at most this share of
# columns (a few blocks) after the step that first satisfied it, with the same modes selected
RITZ_CHECK_GROWTH = 0.05


def m_orthonormal(block, mass, mass_block=None):
    """Q, MQ with Qᵀ M Q = I spanning ``block`` (Gram-matrix eigendecomposition, twice; rank-deficient
    columns dropped). One sparse product M·block (none when ``mass_block`` = M·block is given):
    the second pass reuses M Q = (M block) T."""
    mass_block = mass @ block if mass_block is None else mass_block
    for _ in range(2):
        gram = block.T @ mass_block
        values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
        keep = values > 1e-12 * max(values.max(initial=0.0), 1e-300)
        transform = vectors[:, keep] / np.sqrt(values[keep])
        block, mass_block = (transform.T @ block.T).T, (transform.T @ mass_block.T).T  # column-major
    return block, mass_block


def shifted_block_lanczos(mass, operator, shift, satisfied, max_columns, block_size=12, tol=1e-8,
                          seed=0, stats=None, partial=True, capacity=None):
    r"""Block Lanczos on A = (K − σM)⁻¹ M (``operator(Y)`` = (K − σM)⁻¹ Y, σ = ``shift``) in the
    M inner product; Q (n, m) is stored, M Q only for the last two blocks (the three-term part).

    Re-orthogonalization against all of Q (a full pass, n·m·b per step) only when needed
    (``partial``, Simon's partial re-orthogonalization for blocks): the orthogonality
    W_{j,k} = Q_jᵀ M Q_k of each older block j to the newest one is estimated by the recurrence
    that A's M-symmetry gives from the block three-term relation
    A Q_k = Q_{k−1} B_{k−1}ᵀ + Q_k A_k + Q_{k+1} B_k,

        W_{·,k+1} B_k = T W_{·,k} − W_{·,k} A_k − W_{·,k−1} B_{k−1}ᵀ + O(ε ‖A‖)

    (T the projected matrix, the rounding term taken with the sign that makes it grow; the last
    two blocks' rows are the three-term part's ε ‖A‖ / σ_min(B_k)); a new block whose estimate
    max_j ‖W_{j,k+1}‖ exceeds _ORTHOGONALITY gets a full pass (C = Qᵀ M w, w ← w − Q C, its
    estimate reset to ε; T keeps the three-term part, the pass's older-block coefficients are
    discarded) before it is stored, so Q stays M-orthonormal to ~1e-10 and the Ritz
    pairs are those of a fully re-orthogonalized run to round-off (semi-orthogonality suffices,
    Simon 1984). The estimate tracks the measured Q_jᵀ M q within a factor 2.5 (twin plate); in
    shift-invert it grows ~1e2–1e3 per step, so about every second step needs the full pass.
    ``partial=False``: a full pass at every step. A step costs one sparse product M·(n, b) (M w
    for the three-term part's w; a second one after a full pass).

    After a block step (every step while the basis is small, then once it has grown by
    RITZ_CHECK_GROWTH) ``satisfied(lam, converged)`` gets the Ritz eigenvalues λ = σ + 1/θ
    (m,) and their convergence flags (residual ≤ tol·|θ|) and returns True to stop. Returns
    (λ (m,), converged (m,), vectors(selection) → M-normalized eigenvectors (n, k)); stops at
    ``max_columns`` columns or when the Krylov space is exhausted. Q is stored column-major (a
    block of columns is contiguous, which the sparse solvers want) in room for ``capacity``
    columns (default ``max_columns``), doubled when full, never beyond ``max_columns``: an
    uncapped run (max_columns = n) must not hold an n × n array up front. ``stats`` (a dict,
    optional) counts "steps", "full_passes" and "mass_products".
    mass: (n, n) sparse M; operator: (n, b) → (n, b); shift σ in λ's units ([rad²/s²] for
    Craig–Bampton).
    """
    n = mass.shape[0]
    stats = {} if stats is None else stats
    for key in ("steps", "full_passes", "mass_products"):
        stats.setdefault(key, 0)
    rng = np.random.default_rng(seed)
    q, mq = m_orthonormal(operator(mass @ rng.standard_normal((n, block_size))), mass)
    stats["mass_products"] += 2
    limit = min(max_columns, n)
    room = limit if capacity is None else min(max(capacity, 2 * block_size), limit)
    store = np.empty((n, max(room, q.shape[1])), order="F")
    m_new = q.shape[1]
    store[:, :m_new] = q
    recent = [mq]                # M Q of the previous and the current block
    projected = np.zeros((0, 0))
    previous_start = 0
    # estimated W_{·,k} = Q_{1..k}ᵀ M Q_k and W_{·,k−1}, and ‖A‖ ≈ max |θ| so far
    omega, omega_previous = np.eye(m_new), np.zeros((0, 0))
    theta_max = 0.0
    next_check = 0                 # the Ritz pairs are computed once the basis reaches this
    while True:
        m_old = projected.shape[0]
        basis = store[:, :m_new]
        mass_recent = recent[0] if len(recent) == 1 else np.hstack(recent)
        local = slice(previous_start, m_new)
        w = operator(mq)
        coefficients = np.zeros((m_new, w.shape[1]))
        coefficients[local] = mass_recent.T @ w            # the three-term part
        w = w - (coefficients[local].T @ basis[:, local].T).T
        mw = mass @ w
        stats["steps"] += 1
        stats["mass_products"] += 1
        projected = _grown(projected, coefficients)
        full = not partial or previous_start == 0
        if not full:
            growth, theta_max, level = _orthogonality_growth(projected, omega, omega_previous,
                                                             coefficients, m_old, theta_max)
            full = _lost(growth, w, mw, previous_start)
        if full:
            stats["full_passes"] += 1
            correction = basis.T @ mw                        # C = Qᵀ M w, then a fresh M w
            w = w - (correction.T @ basis.T).T
            mw = mass @ w
            stats["mass_products"] += 1
            # partial: T keeps the three-term part only; the older blocks' coefficients are
            # the orthogonality lost since the last pass (up to ~1e-8 once it jumps), and in T
            # (symmetrized) they made the Ritz vectors' residuals 100× larger (P1: 4e-10
            # instead of 4e-12); discarded, as in Simon's scheme, they are main's
            if partial:
                correction[:previous_start] = 0.0
            projected = _grown(projected[:m_old, :m_old], coefficients + correction)
        q, mq = m_orthonormal(w, mass, mw)
        coupling = mq.T @ w                                  # B_k: w = Q_{k+1} B_k
        if full or q.shape[1] != w.shape[1]:
            next_omega = np.full((m_new, q.shape[1]), _EPS)      # just re-orthogonalized
        else:
            next_omega = np.linalg.solve(coupling.T, growth.T).T     # W_{·,k+1} = G B_k⁻¹
            next_omega[previous_start:] = level / np.linalg.svd(coupling, compute_uv=False).min()
        omega_previous, omega = omega, np.vstack([next_omega, np.eye(q.shape[1])])
        previous_start = m_old
        exhausted = q.shape[1] == 0 or m_new + q.shape[1] > min(max_columns, n - 1)
        if m_new < next_check and not exhausted:     # the Ritz pairs: not at every step
            store = _stored(store, q, m_new, limit)
            recent = [recent[-1], mq]
            m_new += q.shape[1]
            continue
        next_check = int(m_new * (1 + RITZ_CHECK_GROWTH))
        theta, vectors = np.linalg.eigh(projected)
        theta_max = max(theta_max, np.abs(theta).max(initial=0.0))
        residual = np.linalg.norm(coupling @ vectors[m_old:], axis=0)
        converged = residual <= tol * np.abs(theta)     # relative to each Ritz value
        with np.errstate(divide="ignore"):
            lam = shift + 1.0 / theta
        if satisfied(lam, converged) or exhausted:
            break
        store = _stored(store, q, m_new, limit)
        recent = [recent[-1], mq]
        m_new += q.shape[1]

    def eigenvectors(selection):
        return basis @ vectors[:, selection]

    return lam, converged, eigenvectors


def _stored(store, q, m, limit):
    """The Lanczos store (n, room) with block q written at columns m…: doubled when full (never
    beyond ``limit`` columns), column-major (a block of columns contiguous)."""
    if m + q.shape[1] > store.shape[1]:
        grown = np.empty((store.shape[0], min(max(2 * store.shape[1], m + q.shape[1]), limit)),
                         order="F")
        grown[:, :m] = store[:, :m]
        store = grown
    store[:, m:m + q.shape[1]] = q
    return store


def _grown(projected, coefficients):
    """T (m, m) from T_old (m_old, m_old) and the new block's column C (m, b) = Qᵀ M A q_k,
    symmetrized."""
    m_new, m_old = coefficients.shape[0], projected.shape[0]
    grown = np.zeros((m_new, m_new))
    grown[:m_old, :m_old] = projected
    grown[:, m_old:] = coefficients
    grown[m_old:, :] = coefficients.T
    return 0.5 * (grown + grown.T)


def _orthogonality_growth(projected, omega, omega_previous, coefficients, start, theta_max):
    """G = W_{·,k+1} B_k (m, b) of :func:`shifted_block_lanczos`'s recurrence, the updated ‖A‖
    estimate and the orthogonality level the three-term part leaves (ε ‖A‖). ``omega`` (m, b_k)
    = W_{·,k} (block k's rows the identity), ``omega_previous`` (start, b_{k−1}) = W_{·,k−1};
    ``start``: the first column of block k; ``coefficients`` (m, b_k): T's new column."""
    diagonal = coefficients[start:]                         # A_k
    theta_max = max(theta_max, np.abs(diagonal).max(initial=0.0))
    growth = projected @ omega - omega @ diagonal
    b_previous = omega_previous.shape[1]
    if b_previous:                                           # − W_{·,k−1} B_{k−1}ᵀ
        growth[:start] -= omega_previous @ coefficients[start - b_previous:start]
    growth += _EPS * theta_max * np.where(growth < 0, -1.0, 1.0)     # rounding, made to grow
    return growth, theta_max, _EPS * theta_max


def _lost(growth, w, mw, previous_start):
    """Whether the new block w (n, b) (z = M w) would be more than _ORTHOGONALITY from
    M-orthogonal to a block older than the last two: max_j ‖W_{j,k+1}‖ = ‖G_j B_k⁻¹‖ with B_k from
    wᵀ M w = B_kᵀ B_k (row norms do not depend on the rotation the orthonormalization picks);
    True when w is (nearly) rank-deficient."""
    gram = w.T @ mw
    values, vectors = np.linalg.eigh(0.5 * (gram + gram.T))
    if values.min() <= 1e-20 * max(values.max(), 1e-300):
        return True
    estimate = growth[:previous_start] @ (vectors / np.sqrt(values))
    return bool(np.linalg.norm(estimate, axis=1).max(initial=0.0) > _ORTHOGONALITY)
