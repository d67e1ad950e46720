r"""Locate the zeros of det F right of −ε that the contact-row count found: the exponents
themselves, without the Ritz-basis eigen-solve.

:func:`sarfe.hbm.stability.rows.contact_row_counts` counts the zeros of f(s) = det F(s)
(:mod:`sarfe.hbm.stability.determinant`) in the half-strip Ω = {−ε < Re s < X, |Im s| < top}
(top = 1.01 ω/2) by the change of arg f along its boundary (:mod:`sarfe.hbm.stability.contour`).

One zero (:func:`real_zero`): it is real (zeros off the real axis come in conjugate pairs) and
simple; det F, real for real s, changes sign across it, so a bracket by the sign of det F and
Brent's method locate it.

Two or more (:func:`located_zeros`): the verdict needs the leading one (max Re s), and the full
method's rule (:func:`sarfe.hbm.stability.hill.verdict`) needs its value. The zeros are found from
the values of log f the count has already sampled, in three steps:

1. A box B = {−ε < Re s < b, |Im s| < top}: the count's left and top edges up to a top-edge
   node b ≥ top (its nodes reused), closed by a new right edge at Re s = b
   (:func:`sarfe.hbm.stability.contour.winding_count`). When it counts the same n, B holds every
   zero of Ω (else the next top-edge node ×3 is tried, at most ``BOX_TRIES`` times).
2. Delves–Lyness: the power sums of the zeros z_k in B (w = (s − c)/r, c the box centre, r its
   half-diagonal, so |w| ≤ 1) are contour integrals of log f,

       p_j = Σ_k w_k^j = (1/2πi) ∮ w^j d log f,   j = 0 … n,

   taken on the upper half of ∂B only (f(s̄) = conj f(s): the lower half contributes −conj of the
   upper, so p_j = Im I_j / π), with log f linear in s on each sampled step,
   I_j = Σ Δlog f · (w_b^{j+1} − w_a^{j+1}) / ((j+1)(w_b − w_a)). Newton's identities turn
   p_1 … p_n into the monic polynomial whose roots are the start points.
3. Muller's method (:func:`muller`, quadratic interpolation of f through the last three iterates,
   one evaluation of det F per step and start, all starts at once) from the start points with
   Im ≥ 0, to |Δs| ≤ 10⁻¹⁰·max(|s|, r). A located zero z is kept when it lies in Ω and differs
   from every one kept before; it stands for z and z̄ (two zeros unless real). While fewer than n
   are located, steps 2–3 are repeated on the deflated function g(s) = f(s) / Π (s − z_k) (the
   same samples, log g by subtracting the principal log of each step's ratio (s_b − z)/(s_a − z):
   a zero near the contour, whose steep phase the trapezoid misses, no longer spoils the power
   sums of the others).

The result is trusted only when the located zeros (with conjugates) number exactly n: every zero
of Ω is then known and the leading one is max Re z. Otherwise None (the caller keeps its last
resort, the Ritz method). The count's box is exact (the argument principle), Muller's zeros are
zeros of det F to its tolerance; nothing is extrapolated.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.stability.contour import winding_count

BOX_TRIES = 3            # right edges b tried for the box before giving up
MAX_POWER_SUMS = 8       # zeros located from one set of power sums (Newton identities' degree)
ROUNDS = 6               # rounds of starts (deflated by the zeros located before)
MULLER_STEPS = 25        # Muller iterations per start
MULLER_TOLERANCE = 1e-10  # |Δs| ≤ tolerance · max(|s|, r) [relative]


def real_zero(log_det, lower, upper, relative=1e-9):
    """The zero of det F on the real segment (lower, upper) [1/s], lower < 0 < upper, where det F
    (real for real s) changes sign once — the count found one zero in Ω, so it is real and
    simple — or None (det F not finite there, or of the same sign at both ends).

    The sign of det F brackets it: on (lower, 0], on (0, −lower], or by geometric bisection of
    (−lower, upper] (a fold's exponent lies near 0 and ``upper`` is a crude bound: each evaluation
    halves the bracket's log-ratio) down to a ratio ≤ 2; then Brent's method on
    det F(s)/|det F(a)| to |Δs| ≤ ``relative``·|s| + 10⁻¹²|lower|. ≈ 15 evaluations in all (the
    grid search this replaces took 108). Returns s* [1/s]."""
    from scipy.optimize import brentq   # 0.6–0.9 s to import; only a point with one zero needs it

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


def located_zeros(log_det, samples, zeros, epsilon, top, X, poles=()):
    r"""The zeros of f = det F in Ω with Im s ≥ 0 ((m,) complex [1/s], real ones with Im = 0,
    each standing for itself and its conjugate) when exactly ``zeros`` = n are located, else
    None (module docstring).

    log_det: s (n_s,) complex ↦ log f(s) (n_s,) complex (log|f| + i arg f); samples: dict
    s ↦ log f(s) of the count's contour (read and extended: no node is evaluated twice);
    epsilon, top, X [1/s]: the half-strip Ω of the count; poles: the known poles of f (the
    structure's exponents shifted by imω, all left of −ε), of which those within top/16 of the
    box's left edge (the lightly damped ones beside the strip, the poles the count's contour
    steps around) are divided out of f wherever it is interpolated or iterated on: they lie
    outside the box, so its zeros are unchanged, and g is smoother there (a pole just left of −ε
    beside a zero just right of it otherwise throws Muller's parabola off; dividing out all poles
    of the region instead makes g vary like Π (s − p) over hundreds of them, and Muller stalls)."""
    values = samples

    def log_f(s):
        s = np.asarray(s, dtype=complex)
        keys = s.tolist()
        new = [k for k in dict.fromkeys(keys) if k not in values]
        if new:
            values.update(zip(new, np.asarray(log_det(np.array(new, dtype=complex))).tolist()))
        return np.array([values[k] for k in keys], dtype=complex)

    n = int(zeros)
    top_nodes = np.sort(np.array([k.real for k in values if k.imag == top]))
    right = top_nodes[top_nodes >= top]
    right = [float(right[0]) if right.size else float(X)]
    while len(right) < BOX_TRIES and right[-1] < X:
        later = top_nodes[top_nodes >= 3.0 * right[-1]]
        right.append(float(later[0]) if later.size else float(X))
    for b in right:
        nodes, _ = _upper_boundary(values, epsilon, top, b)
        count, _ = winding_count(log_f, np.concatenate([[b, b + 1j * top],
                                                        nodes[nodes.real != b]]))
        if np.isfinite(count) and round(count) == n and abs(count - n) < 0.1:
            break
    else:
        return None
    nodes, logs = _upper_boundary(values, epsilon, top, b)
    centre, radius = 0.5 * (b - epsilon), float(np.hypot(0.5 * (b + epsilon), top))
    poles = np.asarray(poles, dtype=complex).ravel()
    poles = poles[(-epsilon - poles.real <= top / 16) & (np.abs(poles.imag) <= 17 / 16 * top)]
    snap = 1e-9 * radius
    found, stalled = np.zeros(0, complex), False
    for _ in range(ROUNDS):
        known = np.concatenate([found, found[found.imag != 0].conj()])
        left = n - known.size
        if left <= 0 or left > MAX_POWER_SUMS:
            break
        if not stalled:           # the roots of the (deflated) power sums
            sums = power_sums(nodes, logs, known, centre, radius, left, poles)
            starts = centre + radius * roots_of_power_sums(sums)
        else:                     # they led to no new zero: start where arg g turns fastest
            starts = _steepest_steps(nodes, logs, known, left, poles)

        def log_g(s, known=known):
            s = np.asarray(s, dtype=complex)
            return log_f(s) - np.log(s[:, None] - known[None]).sum(axis=1) + np.log(
                s[:, None] - poles[None]).sum(axis=1)

        z, converged = muller(log_g, _distinct(starts, snap), radius, centre=centre)
        z = z[converged]
        z = np.where(np.abs(z.imag) <= snap, z.real + 0j, z)
        z = np.where(z.imag < 0, z.conj(), z)
        new = []
        for w in z[(z.real > -epsilon) & (z.real < b) & (z.imag < top)]:
            if all(abs(w - u) > 1e-6 * radius for u in [*found, *new]):
                new.append(w)
        if not new and stalled:
            break
        stalled = not new
        found = np.concatenate([found, new])
    if found.size + np.count_nonzero(found.imag != 0) != n:
        return None
    return found


def _distinct(starts, snap):
    """The start points mapped to Im s ≥ 0 (f(s̄) = conj f(s)), without repeats (to ``snap``)."""
    starts = np.where(starts.imag < -snap, starts.conj(), starts)
    keep = []
    for s in starts[np.isfinite(starts)]:
        if all(abs(s - t) > snap for t in keep):
            keep.append(s)
    return np.array(keep, dtype=complex)


def _steepest_steps(nodes, logs, known, count, poles=()):
    """The midpoints of the ``count`` sampled steps along which arg g (g = f Π (s − p) /
    Π_known (s − z)) turns fastest (|Δarg g| / |Δs|, local maxima along the contour): beside a
    zero close to the contour — a period-doubling pair near Im s = ω/2 lies just below the top
    edge — where the power sums, which take log f linear over a step, are least accurate."""
    rate = np.abs(_principal_steps(nodes, logs, known, poles).imag) / np.abs(np.diff(nodes))
    padded = np.concatenate([[-np.inf], rate, [-np.inf]])
    peaks = np.flatnonzero((rate >= padded[:-2]) & (rate >= padded[2:]))
    steep = peaks[np.argsort(-rate[peaks], kind="stable")[:count]]
    return 0.5 * (nodes[steep] + nodes[steep + 1])


def _upper_boundary(values, epsilon, top, right):
    """The sampled nodes on the upper half of the box's boundary, counter-clockwise from (b, 0):
    right edge Re s = b, top edge Im s = top, left edge Re s = −ε (nodes (k,), log f (k,))."""
    s = np.array(list(values.keys()), dtype=complex)
    v = np.array(list(values.values()), dtype=complex)
    on_right = (s.real == right) & (s.imag >= 0) & (s.imag <= top)
    on_top = (s.imag == top) & (s.real >= -epsilon) & (s.real < right)
    on_left = (s.real == -epsilon) & (s.imag >= 0) & (s.imag < top)
    position = np.where(on_right, s.imag, np.where(on_top, top + right - s.real,
                                                   2 * top + right + epsilon - s.imag))
    keep = np.flatnonzero(on_right | on_top | on_left)
    order = keep[np.argsort(position[keep], kind="stable")]
    return s[order], v[order]


def power_sums(nodes, logs, known, centre, radius, count, poles=()):
    r"""p_j = Σ_k w_k^j (j = 0 … count) of the zeros of g = f Π (s − p) / Π_known (s − z) (the
    ``poles`` outside the contour: they change nothing but the smoothness) inside the closed
    contour whose upper half is sampled at ``nodes`` (counter-clockwise, (k,) complex) with
    ``logs`` = log f there; w = (s − centre)/radius. Per step log g is taken linear in s, so
    ∫ w^j d log g = Δlog g (w_b^{j+1} − w_a^{j+1}) / ((j+1)(w_b − w_a)); Δarg f between
    neighbours is the principal one (the count's steps turn it by ≤ π/3), Δlog (s − z) the
    principal log of (s_b − z)/(s_a − z) (exact for a straight step). p_j = Im I_j / π (the
    lower half is the mirror image). Returns (count + 1,) real (p_0 = count when all is well)."""
    w = (nodes - centre) / radius
    step = _principal_steps(nodes, logs, known, poles)
    a, b = w[:-1], w[1:]
    j = np.arange(count + 1)[:, None] + 1
    integrals = (step * (b ** j - a ** j) / (j * (b - a))).sum(axis=1)
    return integrals.imag / np.pi


def _principal_steps(nodes, logs, known, poles):
    """Δ log g between neighbouring nodes, g = f Π (s − p) / Π (s − z): Δarg f the principal one
    (the count's steps turn it by ≤ π/3), Δ log (s − a) the principal log of
    (s_b − a)/(s_a − a) — exact for a straight step that does not pass through a."""
    step = np.diff(logs.real) + 1j * np.angle(np.exp(1j * np.diff(logs.imag)))
    for points, sign in ((np.asarray(known, complex), -1.0), (np.asarray(poles, complex), 1.0)):
        if points.size:
            step = step + sign * np.log((nodes[1:, None] - points[None]) /
                                        (nodes[:-1, None] - points[None])).sum(axis=1)
    return step


def roots_of_power_sums(sums):
    """The n numbers whose power sums are p_1 … p_n (``sums`` = p_0 … p_n): Newton's identities
    k e_k = Σ_{i=1..k} (−1)^{i−1} e_{k−i} p_i give the elementary symmetric e_k, and the roots of
    Σ (−1)^k e_k w^{n−k} (numpy.roots) are the numbers."""
    n = len(sums) - 1
    e = [1.0]
    for k in range(1, n + 1):
        e.append(sum((-1) ** (i - 1) * e[k - i] * sums[i] for i in range(1, k + 1)) / k)
    return np.roots([(-1) ** k * e[k] for k in range(n + 1)])


def muller(log_g, starts, scale, tolerance=MULLER_TOLERANCE, steps=MULLER_STEPS, centre=0.0):
    r"""Muller's method on g = exp(log_g) from every start at once → (s (m,), converged (m,)).

    Per start the parabola through the last three iterates (x₀, x₁, x₂; g scaled by the start's
    |g| so that it stays of order one), with divided differences d₁, d₂, a = (d₂ − d₁)/(x₂ − x₀),
    b = a (x₂ − x₁) + d₂, gives the next iterate x₃ = x₂ − 2 g₂ / (b ± √(b² − 4 g₂ a)) (the sign
    with the larger denominator). The first three iterates are x − 10⁻³ r, x + 10⁻³ i r, x
    (r = ``scale`` [1/s]). Converged when |x₃ − x₂| ≤ ``tolerance``·max(|x₃|, r); a start whose g
    is not finite, or whose iterate leaves the disc |s − ``centre``| ≤ 3r (a zero there is not
    one of the box), stops. One call of log_g per step for all starts still moving."""
    x = np.asarray(starts, dtype=complex)
    m = x.size
    h = 1e-3 * scale
    xs = np.stack([x - h, x + 1j * h, x], axis=1)                            # (m, 3)
    logs = np.asarray(log_g(xs.ravel())).reshape(m, 3)
    reference = logs[:, 2].real.copy()
    with np.errstate(all="ignore"):
        gs = np.exp(logs - reference[:, None])
    moving = np.isfinite(gs).all(axis=1)
    converged = np.zeros(m, bool)
    for _ in range(steps):
        index = np.flatnonzero(moving)
        if index.size == 0:
            break
        x0, x1, x2 = xs[index].T
        g0, g1, g2 = gs[index].T
        with np.errstate(all="ignore"):
            d1, d2 = (g1 - g0) / (x1 - x0), (g2 - g1) / (x2 - x1)
            a = (d2 - d1) / (x2 - x0)
            b = a * (x2 - x1) + d2
            root = np.sqrt(b * b - 4.0 * g2 * a)
            denominator = np.where(np.abs(b + root) >= np.abs(b - root), b + root, b - root)
            x3 = x2 - 2.0 * g2 / denominator
        finite = np.isfinite(x3) & (np.abs(x3 - centre) <= 3.0 * scale)
        g3 = np.full(index.size, np.nan, complex)
        if finite.any():
            with np.errstate(all="ignore"):
                g3[finite] = np.exp(np.asarray(log_g(x3[finite])) - reference[index[finite]])
        done = finite & (np.abs(x3 - x2) <= tolerance * np.maximum(np.abs(x3), scale))
        xs[index] = np.stack([x1, x2, x3], axis=1)
        gs[index] = np.stack([g1, g2, g3], axis=1)
        converged[index[done]] = True
        moving[index[done | ~np.isfinite(g3)]] = False
    return xs[:, 2], converged
