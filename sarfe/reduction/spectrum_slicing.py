r"""Many fixed-interface modes at bounded memory: shift-invert block Lanczos in slices of the
spectrum, each slice certified complete by Sylvester's inertia.

One Lanczos run from σ = 0 finds the lowest modes cheaply, but for hundreds of modes its Krylov
space grows to ~5 columns per mode (the wanted ν = 1/ω² crowd towards 0 next to the unwanted
ones) and full re-orthogonalization costs n·m² (m columns): the door trim at 5 mm, 471 modes up to
1.5 kHz, took 200 s and 6.5 GB that way. Here the spectrum (0, λ_c] (λ = ω², λ_c the cutoff) is
cut at shifts 0 = σ_0 < σ_1 < … < σ_s = λ_c. Run j factorizes K − σ_j M (symmetric indefinite,
LDLᵀ) and iterates on

    A_j = (K − σ_j M)⁻¹ M,   A_j φ = θ φ,   λ = σ_j + 1/θ,

whose largest |θ| — the eigenvalues nearest σ_j, on both sides — converge first. The factor's
negative pivots count the eigenvalues below σ_j (Sylvester), so each gap (σ_{j−1}, σ_j] has a known
count c_j = n_j − n_{j−1}; it is filled by run j−1's converged values above σ_{j−1} (up to a
boundary r_{j−1} placed in a spectral gap) and run j's converged values in (r_{j−1}, σ_j], and run
j iterates until the two add up to c_j (or run j alone finds all c_j). Shifts are placed from the
eigenvalue count so far, N(λ) ≈ a √λ (a plate's modal density), so that a run's window holds
about ``slice_modes`` eigenvalues; each run's Krylov space is bounded by ``max_columns``.

Run 0 is the caller's σ = 0 block Lanczos stopped at its column cap; its converged prefix and the
next Ritz value enter here as (eigenvalues, modes, boundary). All runs use the M inner product; a Ritz pair is
converged when ‖A φ − θ φ‖_M ≤ tol·|θ| (relative to its own θ: a value next to the shift, with a
huge θ, must not loosen the test for the others).
"""
from __future__ import annotations

import numpy as np

from sarfe.fe.linear_solvers import factorize
from sarfe.reduction.craig_bampton import _m_orthonormal, lanczos_extend


class SlicingFailed(RuntimeError):
    """A gap's eigenvalue count was not reached within the column cap (the caller falls back)."""


def shifted_block_lanczos(mass, operator, shift, satisfied, max_columns, block_size=16, tol=1e-8,
                          seed=0):
    """Block Lanczos on A = (K − σM)⁻¹ M (``operator(Y)`` = (K − σM)⁻¹ Y, σ = ``shift``) in the
    M inner product with full re-orthogonalization; only Q (n, m) is stored, M Q is recomputed.

    After each block step ``satisfied(lam, converged)`` gets the Ritz eigenvalues λ = σ + 1/θ
    (m,) and their convergence flags (residual ≤ tol·|θ|) and returns True to stop. Returns
    (λ (m,), converged (m,), vectors(selection) → M-normalized eigenvectors (n, k)); stops at
    ``max_columns`` columns or when the Krylov space is exhausted.
    """
    n = mass.shape[0]
    rng = np.random.default_rng(seed)
    q, mq = _m_orthonormal(operator(mass @ rng.standard_normal((n, block_size))), mass)
    store = np.empty((n, max(max_columns, q.shape[1])), order="F")
    m_new = q.shape[1]
    store[:, :m_new] = q
    projected = np.zeros((0, 0))
    previous_start = 0
    while True:
        m_old = projected.shape[0]
        w = operator(mq)                       # A q_block = (K − σM)⁻¹ M q_block
        basis = store[:, :m_new]
        w, projected = lanczos_extend(basis, lambda cols, y: basis[:, cols].T @ (mass @ y), w,
                                      projected, previous_start)
        previous_start = m_old
        q, mq = _m_orthonormal(w, mass)
        coupling = mq.T @ w
        theta, vectors = np.linalg.eigh(projected)
        residual = np.linalg.norm(coupling @ vectors[m_old:], axis=0)
        converged = residual <= tol * np.abs(theta)     # relative to each Ritz value
        with np.errstate(divide="ignore"):
            lam = shift + 1.0 / theta
        exhausted = q.shape[1] == 0 or m_new + q.shape[1] > min(max_columns, n - 1)
        if satisfied(lam, converged) or exhausted:
            break
        store[:, m_new:m_new + q.shape[1]] = q
        m_new += q.shape[1]

    def eigenvectors(selection):
        return basis @ vectors[:, selection]

    return lam, converged, eigenvectors


def _place_shift(stiffness, mass, right_edge, known, wanted, cutoff_omega2, total, rate, solver,
                 record):
    """The next shift σ > right_edge with about ``wanted`` eigenvalues in (right_edge, σ] and its
    factor of K − σM; the cutoff itself once at most 1.25 ``wanted`` remain below it (``total``
    eigenvalues ≤ cutoff, ``known`` ≤ right_edge). First guess ω = √right_edge + wanted / rate
    (``rate``: eigenvalues per rad/s the last run saw; None: N(ω) linear up to the cutoff); a
    factor whose inertia shows more than 1.5× or fewer than 0.5× ``wanted`` is replaced (three
    times at most) by the interpolation through that probe."""
    omega, top = np.sqrt(right_edge), np.sqrt(cutoff_omega2)
    if total - known <= 1.25 * wanted:
        factor = factorize(stiffness - cutoff_omega2 * mass, solver=solver, structure="symmetric")
        record["factorizations"] += 1
        return cutoff_omega2, factor
    guess = omega + wanted / rate if rate else omega + (top - omega) * wanted / (total - known)
    for attempt in range(4):
        shift = min(guess, top) ** 2
        factor = factorize(stiffness - shift * mass, solver=solver, structure="symmetric")
        record["factorizations"] += 1
        inside = factor.negative_pivots - known
        if 0.5 * wanted <= inside <= 1.5 * wanted or attempt == 3 or (shift >= cutoff_omega2
                                                                      and inside <= 1.5 * wanted):
            return shift, factor
        del factor
        guess = omega + (np.sqrt(shift) - omega) * wanted / max(inside, 1)
    return shift, factor


def _slice_run(mass, factor, shift, lower, counted, right_edge, pending, max_columns, last):
    """One shifted Lanczos run for the gap (lower, shift] (module docstring). Returns (λ,
    converged, eigenvectors, take: the run's values kept for the gap, use_pending: whether the
    previous run's values ≤ shift complete it) or raises SlicingFailed."""
    gap_count = factor.negative_pivots - counted           # eigenvalues in (lower, shift]
    need_left = gap_count - sum(1 for v in pending if v <= shift)
    half_width = shift - right_edge
    state = {}

    def satisfied(lam, converged):
        left = converged & (lam > right_edge) & (lam <= shift)
        alone = converged & (lam > lower) & (lam <= shift)
        state["alone"] = np.count_nonzero(alone) == gap_count
        state["left"] = np.count_nonzero(left) == need_left
        if not (state["left"] or state["alone"]):
            return False
        if last:
            return True
        # the right side: every Ritz value within the mirrored window has converged
        open_right = (lam > shift) & ~converged & (lam <= shift + half_width)
        return not open_right.any()

    lam, converged, eigenvectors = shifted_block_lanczos(mass, factor.solve, shift, satisfied,
                                                         max_columns)
    if state.get("left"):
        return lam, converged, eigenvectors, converged & (lam > right_edge) & (lam <= shift), True
    if state.get("alone"):
        return lam, converged, eigenvectors, converged & (lam > lower) & (lam <= shift), False
    raise SlicingFailed(f"shift {np.sqrt(shift) / (2 * np.pi):.1f} Hz: "
                        f"{np.count_nonzero(converged & (lam > lower) & (lam <= shift))} of "
                        f"{gap_count} eigenvalues converged in {len(lam)} columns")


def sliced_modes(stiffness, mass, cutoff_omega2, found_omega2, found_modes, boundary,
                 slice_modes=80, max_columns=400, progress=None, solver="auto"):
    """All eigenpairs of K φ = λ M φ with λ ≤ ``cutoff_omega2`` (module docstring).

    found_omega2 (k,), found_modes (n, k): run 0's converged eigenpairs, all λ ≤ ``boundary``
    (a value between them and run 0's next Ritz value). Returns λ (ascending), Φ (Φᵀ M Φ = I) as
    a list of column blocks in that order (no stacked copy of n × n_m), and a record {"shifts",
    "columns", "negative_pivots", "factorizations", "modes_below_cutoff"}. Raises SlicingFailed
    when a gap's count is not reached within ``max_columns`` even at a quarter of the width.
    """
    pending = list(np.asarray(found_omega2, dtype=float))   # found above the last shift,
    pending_modes = np.asarray(found_modes)                  # not yet certified by a count
    values, modes = [], []
    lower, counted = 0.0, 0            # last shift and the eigenvalue count below it
    right_edge = float(boundary)       # r: the previous run's values cover (lower, r]
    record = {"shifts": [], "columns": [], "negative_pivots": [], "factorizations": 1}
    factor = factorize(stiffness - cutoff_omega2 * mass, solver=solver, structure="symmetric")
    if factor.negative_pivots is None:
        raise SlicingFailed(f"backend {factor.name} reports no inertia")
    total = factor.negative_pivots                     # eigenvalues below the cutoff
    record["modes_below_cutoff"] = int(total)
    del factor
    rate = None
    while True:
        known = counted + len(pending)                 # ≈ N(right_edge)
        for retry in range(3):     # a gap the column cap cannot fill: again with half the width
            shift, factor = _place_shift(stiffness, mass, right_edge, known,
                                         max(4, slice_modes // 2 >> retry), cutoff_omega2, total,
                                         rate, solver, record)
            try:
                lam, converged, eigenvectors, take, use_pending = _slice_run(
                    mass, factor, shift, lower, counted, right_edge, pending, max_columns,
                    shift >= cutoff_omega2)
                break
            except SlicingFailed:
                if retry == 2:
                    raise
            finally:
                record["shifts"].append(float(shift))
                record["negative_pivots"].append(int(factor.negative_pivots))
                del factor
        record["columns"].append(int(len(lam)))
        last = shift >= cutoff_omega2
        if use_pending:
            keep_pending = np.asarray(pending) <= shift
            values.append(np.asarray(pending)[keep_pending])
            modes.append(pending_modes if keep_pending.all() else pending_modes[:, keep_pending])
        order = np.flatnonzero(take)
        order = order[np.argsort(lam[order])]
        values.append(lam[order])
        modes.append(eigenvectors(order))
        counted = record["negative_pivots"][-1]
        lower = shift
        if progress is not None:
            progress(counted, None)
        if last:
            break
        # run j's converged prefix above the shift carries into the next gap; its edge r_j lies
        # halfway to the first unconverged Ritz value above the shift
        above = np.flatnonzero(lam > shift)
        above = above[np.argsort(lam[above])]
        prefix = np.argmin(converged[above]) if not converged[above].all() else len(above)
        chosen = above[:prefix]
        if prefix < len(above):
            right_edge = 0.5 * (lam[above[prefix - 1]] + lam[above[prefix]]) if prefix else shift
        else:
            right_edge = float(lam[above[-1]]) if len(above) else shift
        pending = list(lam[chosen])
        pending_modes = eigenvectors(chosen)
        del eigenvectors             # the run's Krylov store goes before the next one's
        # eigenvalues per rad/s over this run's coverage: the next shift's first guess
        start = np.sqrt(max(values[-1][0], 0.0)) if len(values[-1]) else np.sqrt(shift)
        seen, span = len(values[-1]) + len(pending), np.sqrt(right_edge) - start
        rate = seen / span if span > 0 and seen else None
        if right_edge >= cutoff_omega2:
            right_edge = cutoff_omega2
    omega2 = np.concatenate(values)
    if np.any(np.diff(omega2) < 0):       # blocks are sorted and follow each other; make sure
        order = np.argsort(omega2)
        return omega2[order], [np.hstack(modes)[:, order]], record
    return omega2, modes, record
