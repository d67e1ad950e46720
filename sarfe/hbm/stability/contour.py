r"""The argument principle on the half-strip of the contact-row count: the number of zeros of
det F (:mod:`sarfe.hbm.stability.determinant`) right of −ε, from the change of its argument along
the boundary.

The verdict of the full method (:func:`sarfe.hbm.stability.hill.hill_stability`) is decided by the
exponents in the strip |Im s| ≤ 1.01 ω/2: unstable when one has Re s > tolerance·ω, uncertain
when the leading one is within ±``uncertain_band``·ω of 0. The number of zeros of det F in the
half-strip Ω = {−ε < Re s < X, |Im s| < 1.01 ω/2}, ε = uncertain_band·ω, is the winding number of
det F along its boundary (no pole inside: the poles are the structure's own exponents, all left
of −ε when every mode is damped, shifted by imω (:func:`shifted_exponents`); X bounds |s| of any
exponent, |s| ≤ ‖d‖ + √‖k‖ from pᴴT(s)p = 0 (:func:`exponent_bound`)). F is real for real s, so
det F(s̄) = conj det F(s) and the count is the change of arg det F along the upper half of the
boundary divided by π (:func:`winding_count`). The contour is sampled adaptively (every step's
change of arg below π/3) from nodes placed by the known poles of det F (:func:`upper_contour`).
"""
from __future__ import annotations

import numpy as np

PHASE_STEP = np.pi / 3       # largest change of arg det F between neighbouring contour samples
MAX_EVALUATIONS = 1500       # det F evaluations per point before giving up (→ Ritz method)


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
    """The poles of det F(s): the structure's exponents λ_j
    (:func:`sarfe.hbm.stability.determinant.structural_exponents`) shifted
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


def upper_contour(epsilon, X, top, poles):
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
