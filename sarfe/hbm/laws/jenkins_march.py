r"""Compiled march of 2-D Jenkins elements over one period (numba): the kernels of
:func:`sarfe.hbm.laws.jenkins._march_2d`.

The return map of one sample projects the slider onto the disk of radius ρ_j around q_j,

    t = w_{j−1} − q_j,  w_j = q_j + t · min(1, ρ_j / |t|)   (ρ_j = 0: w_j = q_j, separated),

with the derivative P_j = ∂w_j/∂w_{j−1} = (ρ_j/|t|)(I − n nᵀ) in slip (n = t/|t|), I in stick,
0 in separation, and ∂w_j/∂ρ_j = n in slip. The disk projection does not compose in closed form
(the 1-D clamp does), so the march is sequential in the samples; these kernels run it compiled,
over all contacts, in one call (no Python loop over samples). Compiled on first use and cached on
disk (``cache=True``): the first call of a fresh install compiles for a few seconds, later
processes load the cache.

Array shapes: N samples, n contacts, C = 3P local harmonic columns (h·3 + l; l = 0 normal,
1, 2 tangents) of the P kept coefficient rows.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def return_map_step(w0, w1, q0, q1, rho):
    """One return-map step of one contact (module docstring): the slider (w0, w1) [m] projected on
    the disk of radius ρ = ``rho`` [m] around q = (q0, q1) [m] → (w0, w1, ratio, slipping, u0, u1,
    separated), the new slider and what :func:`return_map_derivative` needs.

    ratio = ρ/|t| in slip, 1 otherwise; (u0, u1) = t/|t| (0 for t = 0); separated: ρ ≤ 0."""
    r = rho if rho > 0.0 else 0.0
    t0, t1 = w0 - q0, w1 - q1
    norm = np.sqrt(t0 * t0 + t1 * t1)
    slipping = norm > r
    safe = norm if norm > 0.0 else 1.0
    ratio = r / safe if slipping else 1.0
    return q0 + t0 * ratio, q1 + t1 * ratio, ratio, slipping, t0 / safe, t1 / safe, r <= 0.0


@njit(cache=True, inline="always")
def return_map_derivative(ratio, slipping, u0, u1, separated):
    """P_j = ∂w_j/∂w_{j−1} of one :func:`return_map_step` (from its outputs) → (p00, p01, p10, p11,
    s0, s1): (ρ/|t|)(I − n nᵀ) in slip, I in stick, 0 separated; (s0, s1) = ∂w_j/∂ρ_j = n in
    slip, 0 otherwise."""
    coefficient = 0.0 if separated else ratio
    s0 = u0 if slipping else 0.0
    s1 = u1 if slipping else 0.0
    return ((1.0 - s0 * u0) * coefficient, (0.0 - s0 * u1) * coefficient,
            (0.0 - s1 * u0) * coefficient, (1.0 - s1 * u1) * coefficient, s0, s1)


@njit(cache=True)
def periodic_start(q, rho, start, tolerance, pass_cap):
    r"""Slider at θ_0 of the periodic state, marched from ``start`` (n, 2) [m].

    Periods are marched until the slider at θ_0 repeats to ``tolerance`` [m] (every contact) or
    ``pass_cap`` periods; between passes w_0 ← w_0 + (I − A)⁻¹ (w_N − w_0), A = ∂w_N/∂w_0, where
    |det(I − A)| > 10⁻⁶ (the contact slipped). q (N, n, 2) [m], ρ (N, n) [m].
    Returns (w_0 (n, 2), passes).
    """
    N, n = rho.shape
    w = start.copy()
    passes = 0
    while True:
        w0 = w.copy()
        A = np.zeros((n, 2, 2))
        largest = 0.0
        for c in range(n):
            a00, a01, a10, a11 = 1.0, 0.0, 0.0, 1.0
            x0, x1 = w[c, 0], w[c, 1]
            for j in range(N):
                x0, x1, ratio, slipping, u0, u1, separated = return_map_step(
                    x0, x1, q[j, c, 0], q[j, c, 1], rho[j, c])
                p00, p01, p10, p11, s0, s1 = return_map_derivative(ratio, slipping, u0, u1, separated)
                a00, a01, a10, a11 = (p00 * a00 + p01 * a10, p00 * a01 + p01 * a11,
                                      p10 * a00 + p11 * a10, p10 * a01 + p11 * a11)
            w[c, 0], w[c, 1] = x0, x1
            A[c, 0, 0], A[c, 0, 1], A[c, 1, 0], A[c, 1, 1] = a00, a01, a10, a11
            largest = max(largest, abs(x0 - w0[c, 0]), abs(x1 - w0[c, 1]))
        passes += 1
        if largest <= tolerance:
            return w0, passes
        if passes >= pass_cap:
            return w, passes
        for c in range(n):      # Newton on the periodicity where I − A is regular (slip)
            m00, m01 = 1.0 - A[c, 0, 0], -A[c, 0, 1]
            m10, m11 = -A[c, 1, 0], 1.0 - A[c, 1, 1]
            det = m00 * m11 - m01 * m10
            if abs(det) > 1e-6:
                r0, r1 = w[c, 0] - w0[c, 0], w[c, 1] - w0[c, 1]
                w[c, 0] = w0[c, 0] + (m11 * r0 - m01 * r1) / det
                w[c, 1] = w0[c, 1] + (m00 * r1 - m10 * r0) / det


@njit(cache=True)
def final_pass(q, rho, drho_dw, drho_dq, k_t, start, Phi, jacobian):
    r"""One period from the periodic start (n, 2): forces, states and the consistent tangent.

    λ_t,j = k_t (q_j − w_j); with X the local harmonics (C = 3P columns, Φ (N, P) the kept basis)
        dw_j = P_j (dw_{j−1} − dq_j) + dq_j + n_j dρ_j,   dρ_j = (∂ρ/∂w) dw_n,j + (∂ρ/∂q) · dq_j
    (∂ρ/∂w = drho_dw (N, n); ∂ρ/∂q = drho_dq (N, n, 2), 0 unless a curved partner makes the normal
    force depend on the slide)
    at fixed w_0, and the history ∂w_j/∂w_0 = P_j ⋯ P_1.
    Returns (λ_t (N, n, 2) [N], state (N, n) int8 (0 separated, 1 stick, 2 slip),
    ∂λ_t,j/∂X at fixed w_0 (N, n, 2, C) [N/m], history (N, n, 2, 2), ∂w_N/∂X (n, 2, C)) — the
    last three zero-sized when not ``jacobian``.
    """
    N, n = rho.shape
    P = Phi.shape[1]
    C = 3 * P
    force = np.empty((N, n, 2))
    state = np.empty((N, n), np.int8)
    size = N if jacobian else 0
    dforce = np.zeros((size, n, 2, C))
    history = np.zeros((size, n, 2, 2))
    dw_end = np.zeros((n if jacobian else 0, 2, C))
    dw = np.zeros((2, C))
    for c in range(n):
        x0, x1 = start[c, 0], start[c, 1]
        h00, h01, h10, h11 = 1.0, 0.0, 0.0, 1.0
        dw[:, :] = 0.0
        for j in range(N):
            x0, x1, ratio, slipping, u0, u1, separated = return_map_step(
                x0, x1, q[j, c, 0], q[j, c, 1], rho[j, c])
            force[j, c, 0] = k_t[c] * (q[j, c, 0] - x0)
            force[j, c, 1] = k_t[c] * (q[j, c, 1] - x1)
            state[j, c] = 0 if separated else (2 if slipping else 1)
            if not jacobian:
                continue
            p00, p01, p10, p11, s0, s1 = return_map_derivative(ratio, slipping, u0, u1, separated)
            weight = drho_dw[j, c]
            slope0, slope1 = drho_dq[j, c, 0], drho_dq[j, c, 1]
            for h in range(P):
                phi = Phi[j, h]
                for l in range(3):
                    col = 3 * h + l
                    dq0 = phi if l == 1 else 0.0
                    dq1 = phi if l == 2 else 0.0
                    dn = phi if l == 0 else 0.0
                    e0, e1 = dw[0, col] - dq0, dw[1, col] - dq1
                    drho = weight * dn + slope0 * dq0 + slope1 * dq1
                    v0 = p00 * e0 + p01 * e1 + dq0 + s0 * drho
                    v1 = p10 * e0 + p11 * e1 + dq1 + s1 * drho
                    dw[0, col], dw[1, col] = v0, v1
                    dforce[j, c, 0, col] = k_t[c] * (dq0 - v0)
                    dforce[j, c, 1, col] = k_t[c] * (dq1 - v1)
            h00, h01, h10, h11 = (p00 * h00 + p01 * h10, p00 * h01 + p01 * h11,
                                  p10 * h00 + p11 * h10, p10 * h01 + p11 * h11)
            history[j, c, 0, 0], history[j, c, 0, 1] = h00, h01
            history[j, c, 1, 0], history[j, c, 1, 1] = h10, h11
        if jacobian:
            dw_end[c] = dw
    return force, state, dforce, history, dw_end


@njit(cache=True, inline="always")
def _disk_projection(q0, q1, rho):
    """Point of the disk |w − q| ≤ ρ nearest to the origin → (w0, w1, active)."""
    d = np.sqrt(q0 * q0 + q1 * q1)
    if d <= rho:
        return 0.0, 0.0, False
    s = 1.0 - rho / d
    return q0 * s, q1 * s, True


@njit(cache=True)
def _nearest_in_disks(q, rho, c, members, tolerance):
    r"""min |w| over the intersection of the disks ``members`` (indices of samples, ≤ 3, −1 unused)
    of contact c, by enumeration: the minimizer is the origin, the projection of the origin onto
    one disk, or an intersection point of two circles. Returns (w0, w1, a0, a1, found)."""
    best, b0, b1, ba0, ba1, found = np.inf, 0.0, 0.0, -1, -1, False
    m = members.size
    for x in range(m):
        s = members[x]
        if s < 0:
            continue
        for y in range(x, m):
            t = members[y]
            if t < 0:
                continue
            points = np.empty((2, 2))
            count = 0
            if y == x:
                p0, p1, active = _disk_projection(q[s, c, 0], q[s, c, 1], rho[s, c])
                points[0, 0], points[0, 1] = p0, p1
                count = 1
                a0, a1 = (s if active else -1), -1
            else:
                d0, d1 = q[t, c, 0] - q[s, c, 0], q[t, c, 1] - q[s, c, 1]
                d = np.sqrt(d0 * d0 + d1 * d1)
                r1, r2 = rho[s, c], rho[t, c]
                if d <= 0.0 or d > r1 + r2 or d < abs(r1 - r2):
                    continue
                a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
                h = np.sqrt(max(r1 * r1 - a * a, 0.0))
                for sign in range(2):
                    g = h if sign == 0 else -h
                    points[sign, 0] = q[s, c, 0] + (a * d0 - g * d1) / d
                    points[sign, 1] = q[s, c, 1] + (a * d1 + g * d0) / d
                count = 2
                a0, a1 = s, t
            for i in range(count):
                w0, w1 = points[i, 0], points[i, 1]
                norm = np.sqrt(w0 * w0 + w1 * w1)
                if norm >= best:
                    continue
                inside = True
                for z in range(m):
                    u = members[z]
                    if u < 0 or u == a0 or u == a1:
                        continue
                    e0, e1 = w0 - q[u, c, 0], w1 - q[u, c, 1]
                    if np.sqrt(e0 * e0 + e1 * e1) - rho[u, c] > tolerance:
                        inside = False
                        break
                if inside:
                    best, b0, b1, ba0, ba1, found = norm, w0, w1, a0, a1, True
    return b0, b1, ba0, ba1, found


@njit(cache=True)
def stick_projection(q, rho, tolerance, max_iterations):
    r"""Gauge slider of contacts that can stick the whole period: the point nearest to the
    assembly position w = 0 of S = ∩_j {w : |w − q_j| ≤ ρ_j} (the constant sliders that never slip).

    Cutting planes on the disks: from the working set (the active disks and the most violated
    one, ≤ 3) the exact minimizer of |w| over their intersection (:func:`_nearest_in_disks`); |w|
    grows at every step, so the active set never repeats. Stops when no disk is violated by more
    than ``tolerance`` [m] (stuck), when the working set has an empty intersection (S = ∅: the
    contact slips every period) or after ``max_iterations`` (treated as slipping). A contact that
    separates anywhere (ρ_j ≤ 0) forgets its slider: not stuck.
    q (N, n, 2) [m], ρ (N, n) [m]. Returns (w (n, 2) [m], active (n, 2) sample indices of the disks
    whose boundary holds w (−1: none), stuck (n,) bool).
    """
    N, n = rho.shape
    w = np.zeros((n, 2))
    active = np.full((n, 2), -1, np.int64)
    stuck = np.zeros(n, np.bool_)
    members = np.full(3, -1, np.int64)
    for c in range(n):
        separates = False
        for j in range(N):
            if rho[j, c] <= 0.0:
                separates = True
                break
        if separates:
            continue
        w0, w1, a0, a1 = 0.0, 0.0, -1, -1
        for _ in range(max_iterations):
            worst, k = tolerance, -1
            for j in range(N):
                e0, e1 = w0 - q[j, c, 0], w1 - q[j, c, 1]
                violation = np.sqrt(e0 * e0 + e1 * e1) - rho[j, c]
                if violation > worst:
                    worst, k = violation, j
            if k < 0:
                stuck[c] = True
                w[c, 0], w[c, 1] = w0, w1
                active[c, 0], active[c, 1] = a0, a1
                break
            members[0], members[1], members[2] = a0, a1, k
            w0, w1, a0, a1, found = _nearest_in_disks(q, rho, c, members, tolerance)
            if not found:
                break
    return w, active, stuck
