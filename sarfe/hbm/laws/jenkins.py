r"""Jenkins friction element — tangential spring k_t in series with a Coulomb slider (limit μ λ_n):
the hysteretic tangent part of the laws with friction (squeak, tabulated with friction).

Slider position w (in the tangent plane, 1 or 2 directions), tangential relative displacement q:

    λ_t = k_t (q − w),     |λ_t| ≤ μ λ_n.

One time step (the return map) projects the previous slider position onto the disk of radius
ρ = μ λ_n / k_t around q:

    w_j = q_j + Proj_{|x| ≤ ρ_j}(w_{j−1} − q_j)

states: separation (λ_n = 0: ρ = 0, the slider follows, λ_t = 0), stick (w_j = w_{j−1}),
slip (the projection is active, |λ_t| = μ λ_n). In one tangential direction the projection is a
clamp, w_j = clip(w_{j−1}, q_j − ρ_j, q_j + ρ_j).

Gauge of the periodic state. Where the slider slips (or the contact separates) during the period,
its periodic state is fixed by q̃ and λ̃_n. A contact that sticks the whole period has a whole
interval (a convex set in 2-D) of periodic slider positions: its mean tangential force is a
history constant. Taking it from a warm start (the last evaluation's slider) made the residual
depend on the path of the iterations, not only on the unknowns — a continuation corrector landed
on a solution with another mean and rejected it. The periodic state is therefore fixed by the
slider position at assembly, w = 0 (q is measured from the undeformed state): where the contact
can stick the whole period, the slider is the point of the set of stick-periodic sliders
S = ∩_j {w : |w − q_j| ≤ ρ_j} nearest to 0. In 1-D S is the interval [A, B] of periodic starts and
w_0 = clip(0, A, B), which is also where a march from 0 ends. In 2-D a march from 0 also ends in S
(cyclic projections onto convex sets), but at a point that depends on the order in which the disks
are met, whose motion along the boundary of S no consistent tangent of the march can follow (the
mean tangential rows of the Jacobian were wrong by up to 37 %, and Newton on the 12-pair door trim
converged linearly, ×0.15 per iteration); the nearest point of S is a smooth function of q̃ and λ̃_n
with an exact derivative (:func:`_march_2d`). A contact that never slips with 0 ∈ S keeps the spring
it was assembled with (λ_t = k_t q: it carries its share of any static load, exactly what a start
from rest gives when the contact never slips), and one with 0 ∉ S rests on the boundary of S —
dragged as little as needed. λ_t is then a continuous, piecewise smooth function of q̃ and λ̃_n
alone (the ``slider_start`` of a call is not used), continuous through stick ↔ slip transitions,
and the Jacobian is k_t I in stick (regular even where the contact is the only restraint).

The element provides (vectorized over contacts, driven by the law's normal force λ_n(θ)):
- :func:`periodic_forces`: the periodic steady state over one period and its AFT Jacobian (1-D:
  exact clamp composition without a sample loop; 2-D: the march with its consistent tangent);
- :func:`step`: the one-step return map of the time integrator and ∂λ_t/∂q, ∂λ_t/∂λ_n;
- :func:`initial_slider`: the slider from a known tangential force.
The normal force driving it must be rate independent (∂λ_n/∂ẇ = 0; checked at registration).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from sarfe.hbm import harmonics as hm
from sarfe.hbm.laws.contract import Parameter

PARAMETERS = (
    Parameter("tangential_stiffness", "tangential_stiffness_N_m", "N/m",
              "tangential spring k_t in series with the slider", minimum=0.0, exclusive=True,
              required=True, split=True, scaled=True),
    Parameter("friction_coefficient", "friction_coefficient", "1",
              "Coulomb friction coefficient μ (slip limit μ λ_n)", minimum=0.0, required=True),
)
STATES = ("separated", "stick", "slip")

SEPARATED, STICK, SLIP = 0, 1, 2


def slider_update(slider_previous, tangential_displacement, slip_radius):
    """Return map of one step, broadcasting over leading axes; last axis = tangent directions.

    slider_previous, tangential_displacement: (..., n_t) [m]; slip_radius ρ = μ λ_n / k_t: (...) [m].
    Returns (slider (..., n_t) [m], state (...) int8 in {SEPARATED, STICK, SLIP}).
    """
    w_prev = np.asarray(slider_previous, dtype=float)
    q = np.asarray(tangential_displacement, dtype=float)
    rho = np.maximum(np.asarray(slip_radius, dtype=float), 0.0)
    trial = w_prev - q
    norm = np.sqrt(np.sum(trial * trial, axis=-1))
    slipping = norm > rho
    scale = np.where(slipping, rho / np.where(slipping, norm, 1.0), 1.0)
    slider = q + trial * scale[..., None]
    state = np.where(rho <= 0.0, SEPARATED, np.where(slipping, SLIP, STICK)).astype(np.int8)
    return slider, state


def compose_clamps(lower, upper):
    r"""Prefix compositions of the clamps c_j(x) = clip(x, a_j, b_j) along axis 0 (Hillis–Steele).

    The composition of two clamps is a clamp,

        clip(clip(x, a₁, b₁), a₂, b₂) = clip(x, clip(a₁, a₂, b₂), clip(b₁, a₂, b₂)),

    so C_j = c_j ∘ … ∘ c_0 = clip(·, A_j, B_j) for every j follows from log₂N doubling steps, each a
    vectorized numpy operation over (samples, contacts). lower, upper: (N, ...) with a ≤ b.
    Returns (A, B) of the same shape; x after sample j is clip(x_start, A_j, B_j).
    """
    A = np.array(lower, dtype=float)
    B = np.array(upper, dtype=float)
    shift = 1
    while shift < A.shape[0]:
        lo, hi = A[shift:], B[shift:]
        A_new = np.clip(A[:-shift], lo, hi)
        B_new = np.clip(B[:-shift], lo, hi)
        A[shift:], B[shift:] = A_new, B_new
        shift *= 2
    return A, B


def jenkins_periodic_1d(tangential_displacement, slip_radius, slider_start):
    r"""Periodic steady state of the 1-D Jenkins element over one period, without a sample loop.

    The return map w_j = clip(w_{j−1}, q_j − ρ_j, q_j + ρ_j) is a clamp; the whole period is the
    composed clamp clip(·, A_{N−1}, B_{N−1}) (:func:`compose_clamps`). A clamp is idempotent, so
    one period marched from any start w_start lands on the periodic state
    w_end = clip(w_start, A_{N−1}, B_{N−1}), and the second period w_j = clip(w_end, A_j, B_j) ends
    on w_end again (it only confirms): 2 passes.

    q: (N, n) [m], ρ = μ λ_n / k_t: (N, n) [m], slider_start: (n,) [m].
    Returns dict with slider w (N, n), state (N, n) int8, reset (N, n) bool (slip, separation or
    the slider resting on a slip bound: the history is erased there), sign (N, n) ∈ {+1, −1, 0}
    with λ_t = sign·μλ_n at a reset sample (+1: w at q − ρ), slider_end (n,), passes = 2.
    """
    q = np.asarray(tangential_displacement, dtype=float)
    rho = np.maximum(np.asarray(slip_radius, dtype=float), 0.0)
    lower, upper = q - rho, q + rho
    A, B = compose_clamps(lower, upper)
    slider_end = np.clip(slider_start, A[-1], B[-1])
    slider = np.clip(slider_end, A, B)
    previous = np.concatenate([slider_end[None], slider[:-1]], axis=0)
    # ≤: a slider resting exactly on a bound (a start clamped to the edge of the periodic
    # interval) follows that bound, like a slip sample
    below, above = previous <= lower, previous >= upper
    separated = rho <= 0.0
    sign = np.where(separated, 0, np.where(below, 1, np.where(above, -1, 0))).astype(np.int8)
    reset = separated | below | above
    slipping = (previous < lower) | (previous > upper)
    state = np.where(separated, SEPARATED, np.where(slipping, SLIP, STICK)).astype(np.int8)
    return {"slider": slider, "state": state, "reset": reset, "sign": sign,
            "slider_end": slider_end, "passes": 2}


def last_reset_index(reset):
    """Index j(i) ≤ i (cyclic) of the last reset sample before or at each sample, along axis 0.

    reset: (N, n) bool. Returns (j (N, n) int, has_reset (n,) bool); j is meaningless where a column
    never resets. Found by np.maximum.accumulate over two concatenated periods.
    """
    N = reset.shape[0]
    twice = np.concatenate([reset, reset], axis=0)
    index = np.where(twice, np.arange(2 * N).reshape((-1,) + (1,) * (reset.ndim - 1)), -1)
    last = np.maximum.accumulate(index, axis=0)[N:]
    return last % N, reset.any(axis=0)


def slider_update_derivatives(slider_previous, tangential_displacement, slip_radius):
    r"""Return map (as :func:`slider_update`) and its derivatives, vectorized over leading axes.

    Slip: w = q + ρ n, n = t/|t|, t = w_prev − q, so
        dw = dq + n dρ + (ρ/|t|)(I − n nᵀ)(dw_prev − dq);
    stick: dw = dw_prev; separation (ρ = 0): dw = dq.
    Returns (slider (..., m), state (...), P = ∂w/∂w_prev (..., m, m), n_rho = ∂w/∂ρ (..., m)),
    with ∂w/∂q = I − P. Fused and lean: it runs once per time sample in the 2-D march.
    """
    w_prev = np.asarray(slider_previous, dtype=float)
    q = np.asarray(tangential_displacement, dtype=float)
    rho = np.maximum(np.asarray(slip_radius, dtype=float), 0.0)
    trial = w_prev - q
    norm = np.sqrt(np.add.reduce(trial * trial, axis=-1))
    slipping = norm > rho
    separated = rho <= 0.0
    safe = np.where(norm > 0.0, norm, 1.0)
    ratio = np.where(slipping, rho / safe, 1.0)
    slider = q + trial * ratio[..., None]
    unit = trial / safe[..., None]
    slip_unit = unit * slipping[..., None]
    coefficient = np.where(separated, 0.0, ratio)
    P = (np.eye(trial.shape[-1]) - slip_unit[..., :, None] * unit[..., None, :]) * coefficient[..., None, None]
    state = np.where(separated, SEPARATED, np.where(slipping, SLIP, STICK)).astype(np.int8)
    return slider, state, P, slip_unit


@lru_cache(maxsize=32)
def _basis(H: int, N: int):
    return hm.fourier_matrices(H, N)[1]


def periodic_forces(p, q, one_d, normal_force, normal_stiffness, slider_start, H, N, jacobian,
                    tolerance, pass_cap, kept_rows, normal_slope_q=None):
    r"""Periodic tangential forces of n Jenkins elements over one period, and their AFT Jacobian.

    p: parameters (tangential_stiffness k_t, friction_coefficient μ; (n,) each); q (N, n, 2) [m]
    tangential displacements, one_d (n,) bool: only the first direction exists; normal_force λ_n (N, n) [N], normal_stiffness ∂λ_n/∂w (N, n) [N/m]; slider_start (n, 2);
    kept_rows: coefficient rows of the Jacobian (P of them). slider_start is not used: the periodic
    state is fixed by the gauge (module docstring), so it is a function of q and λ_n alone.
    normal_slope_q (N, n, 2) [N/m] or None: ∂λ_n/∂q where the normal force also depends on the
    slide (a curved partner, :mod:`.curvature`): the slip radius then moves with q as well.
    Returns (λ_t (N, n, 2), state (N, n) int8, slider_end (n, 2), passes, J (n, 3P, 3P) or None)
    with J in the local layout (h·3 + l), l = 0 normal, 1, 2 tangents; its tangential rows only.
    """
    q_all = q
    n = q_all.shape[1]
    P = kept_rows.size
    k_t, mu = p["tangential_stiffness"], p["friction_coefficient"]
    rho = mu * normal_force / k_t                              # (N, n) slip radius [m]
    force = np.zeros(q_all.shape)
    state = np.zeros((N, n), np.int8)
    slider_end = np.full((n, 2), np.nan)
    J = np.zeros((n, 3 * P, 3 * P)) if jacobian else None
    passes = 0
    c1 = np.flatnonzero(one_d)
    if c1.size:                      # 1-D: clamp scan, exact steady state
        qc = q_all[:, c1, 0]
        res = jenkins_periodic_1d(qc, rho[:, c1], np.zeros(c1.size))   # gauge w = 0: see above
        force[:, c1, 0] = k_t[c1] * (qc - res["slider"])
        state[:, c1] = res["state"]
        slider_end[c1, 0] = res["slider_end"]
        passes = max(passes, res["passes"])
        if jacobian:
            slope_q = None if normal_slope_q is None else mu[c1] * normal_slope_q[:, c1, 0]
            J[c1] = _jacobian_1d(res, mu[c1] * normal_stiffness[:, c1], k_t[c1], H, N, kept_rows,
                                 slope_q)
    c2 = np.flatnonzero(~one_d)
    if c2.size:
        drho_dq = np.zeros((N, c2.size, 2)) if normal_slope_q is None \
            else (mu[c2] / k_t[c2])[:, None] * normal_slope_q[:, c2]
        force_t, st, w_end, n_pass, J2 = _march_2d(
            q_all[:, c2], rho[:, c2], mu[c2] * normal_stiffness[:, c2] / k_t[c2], k_t[c2],
            np.zeros((c2.size, 2)), H, N, jacobian, tolerance, pass_cap, kept_rows, drho_dq)
        force[:, c2] = force_t
        state[:, c2] = st
        slider_end[c2] = w_end
        passes = max(passes, n_pass)
        if jacobian:
            J[c2] = J2
    return force, state, slider_end, passes, J


def _jacobian_1d(res, mu_dlam, k_t, H, N, kept_rows, mu_dlam_q=None):
    """∂λ̃_t/∂(w̃, q̃) of 1-D Jenkins elements in the local (h·3 + l) layout (l = 0 n, 1 t),
    h over the kept coefficient rows.

    The slider forgets its past at every slip or separation sample j(i), so
    λ_t,i = k_t (q_i − q_j) + s_j μ λ_n,j and ∂λ_t,i/∂X = k_t (Φ_i − Φ_j) + s_j μ ∂λ_n,j/∂w Φ_j
    (s_j = ±1 the slip direction), pushed through one FFT of the gathered rows Φ_{j(i)}; a contact
    sticking the whole period keeps the gauge slider w0 = 0 (module docstring): λ_t = k_t q,
    ∂w0/∂X = 0. ``mu_dlam_q`` (N, n): μ ∂λ_n/∂q where λ_n also depends on the slide (a curved
    partner): the term s_j μ ∂λ_n,j/∂q Φ_j then joins the tangential columns."""
    P = kept_rows.size
    n = k_t.size
    Phi = _basis(H, N)[:, kept_rows]
    j, has = last_reset_index(res["reset"])
    gathered = Phi[j]                                      # (N, n, P) rows Φ_{j(i)}
    weight = np.take_along_axis(res["sign"] * mu_dlam, j, axis=0)  # s_j μ ∂λ_n/∂w at j(i)
    memory = np.moveaxis(hm.harmonic_coefficients(gathered, H)[kept_rows], 0, 1)  # E P Φ (n, P, P)
    normal = np.moveaxis(hm.harmonic_coefficients(weight[..., None] * gathered, H)[kept_rows], 0, 1)
    J = np.zeros((n, 3 * P, 3 * P))
    eye = np.eye(P)
    J[:, 1::3, 1::3] = k_t[:, None, None] * (eye - np.where(has[:, None, None], memory, 0.0))
    J[:, 1::3, 0::3] = np.where(has[:, None, None], normal, 0.0)
    if mu_dlam_q is not None:
        weight_q = np.take_along_axis(res["sign"] * mu_dlam_q, j, axis=0)
        slide = np.moveaxis(hm.harmonic_coefficients(weight_q[..., None] * gathered, H)[kept_rows],
                            0, 1)
        J[:, 1::3, 1::3] += np.where(has[:, None, None], slide, 0.0)
    return J


def _march_2d(q, rho, drho_dw, k_t, start, H, N, jacobian, tolerance, pass_cap, kept_rows,
              drho_dq):
    r"""2-D Jenkins elements over one period (compiled kernels over contacts × samples,
    :mod:`.jenkins_march`).

    Stuck contacts first (:func:`.jenkins_march.stick_projection`): where the disks
    D_j = {w : |w − q_j| ≤ ρ_j} have a common point the contact can stick the whole period, and the
    gauge (module docstring) takes the point of S = ∩_j D_j nearest to w = 0: w₀ = 0 when 0 ∈ S
    (λ_t = k_t q), else w₀ on the boundary of one disk j (w₀ = q_j (1 − ρ_j/|q_j|)) or of two
    (a corner of S). λ_t = k_t (q − w₀) with, from those 0–2 active constraints,

        one:  dw₀ = (I − (ρ_j/|q_j|)(I − m mᵀ)) dq_j + m dρ_j,      m = (w₀ − q_j)/ρ_j,
        two:  (w₀ − q_i)ᵀ dw₀ = (w₀ − q_i)ᵀ dq_i + ρ_i dρ_i,   i ∈ {j, k},

    so the mean rows of the Jacobian are exact there too (the march's periodicity cannot fix a
    slider that never slips: its I − A is singular or nearly so at a touching sample).

    The others slip (or separate) every period: their periodic state is unique. The disk
    projection is not composable like the 1-D clamp, so the march over samples is inherent to 2-D
    hysteresis. Periods are marched from ``start`` until the slider state at θ_0 repeats to
    ``tolerance`` × (max|q| + max ρ) or ``pass_cap`` periods; between passes the start is updated
    by Newton on the periodicity, w_0 ← w_0 + (I − A)⁻¹ (w_N − w_0) with A = ∂w_N/∂w_0 (where
    I − A is regular), so a few passes suffice even when slip is rare and the plain iteration
    contracts slowly; a final period propagates the consistent tangent: with X = local harmonics
    (h·3 + l),
        dw_j = (I − P_j) dq_j + n_j dρ_j + P_j dw_{j−1},
    and the periodicity w_N = w_0 gives ∂w_0/∂X = (I − A)⁻¹ B (A = ∂w_N/∂w_0, B = ∂w_N/∂X at
    fixed w_0).
    drho_dq (N, n, 2): ∂ρ/∂q (0 unless a curved partner makes λ_n depend on the slide; then
    dρ_j = ∂ρ/∂w_n dw_n,j + ∂ρ/∂q · dq_j in the formulas above).
    Returns (λ_t (N, n, 2), state (N, n), w_start (n, 2), passes, J (n, 3P, 3P) or None).
    """
    from sarfe.hbm.laws import jenkins_march as march    # numba is imported (and the kernels loaded) on first use
    n = q.shape[1]
    P = kept_rows.size                                       # local harmonic rows (kept set)
    scale = np.abs(q).max() + rho.max() + 1e-300
    q = np.ascontiguousarray(q, dtype=float)
    rho = np.ascontiguousarray(rho, dtype=float)
    drho_dw = np.ascontiguousarray(drho_dw, dtype=float)
    k_t = np.asarray(k_t, dtype=float)
    Phi = np.ascontiguousarray(_basis(H, N)[:, kept_rows])
    w_start, active, stuck = march.stick_projection(q, rho, STUCK_TOLERANCE * scale,
                                                    STUCK_ITERATIONS)
    force = k_t[None, :, None] * (q - w_start[None])
    state = np.full((N, n), STICK, np.int8)
    dforce = np.zeros((N, n, 2, 3 * P)) if jacobian else None
    passes = 0
    slipping = np.flatnonzero(~stuck)
    if slipping.size:
        qs, rs = np.ascontiguousarray(q[:, slipping]), np.ascontiguousarray(rho[:, slipping])
        w0, passes = march.periodic_start(qs, rs, np.array(start, dtype=float)[slipping],
                                          tolerance * scale, pass_cap)
        f, st, df, history, dw = march.final_pass(qs, rs, np.ascontiguousarray(drho_dw[:, slipping]),
                                                  np.ascontiguousarray(drho_dq[:, slipping]),
                                                  k_t[slipping], w0, Phi, jacobian)
        passes += 1
        force[:, slipping], state[:, slipping], w_start[slipping] = f, st, w0
        if jacobian:
            system = np.eye(2) - history[-1]
            regular = np.abs(np.linalg.det(system)) > 1e-12
            dw0 = np.zeros_like(dw)             # never slipped (stuck test inconclusive): 0
            dw0[regular] = np.linalg.solve(system[regular], dw[regular])
            df -= k_t[None, slipping, None, None] * np.einsum("jcab,cbx->jcax", history, dw0)
            dforce[:, slipping] = df
    if not jacobian:
        return force, state, w_start, passes, None
    held = np.flatnonzero(stuck)
    if held.size:
        dq = np.zeros((N, held.size, 2, 3 * P))
        dq[:, :, 0, 1::3] = Phi[:, None, :]
        dq[:, :, 1, 2::3] = Phi[:, None, :]
        dw0 = _stuck_slider_derivative(q[:, held], rho[:, held], drho_dw[:, held], Phi,
                                       w_start[held], active[held], drho_dq[:, held])
        dforce[:, held] = k_t[None, held, None, None] * (dq - dw0[None])
    coeff = hm.harmonic_coefficients(dforce, H)[kept_rows]  # (P, n, 2, 3P)
    J = np.zeros((n, 3 * P, 3 * P))
    J[:, 1::3, :] = np.moveaxis(coeff[:, :, 0, :], 0, 1)
    J[:, 2::3, :] = np.moveaxis(coeff[:, :, 1, :], 0, 1)
    return force, state, w_start, passes, J


STUCK_TOLERANCE = 1e-10      # a stuck slider may lie outside a disk by this × (max|q| + max ρ)
STUCK_ITERATIONS = 64        # cutting-plane steps of the stuck test (more: treated as slipping)


def _stuck_slider_derivative(q, rho, drho_dw, Phi, w, active, drho_dq):
    r"""∂w₀/∂X (m, 2, 3P) of stuck sliders w₀ (m, 2) with active disks ``active`` (m, 2) (sample
    indices, −1 none): the formulas of :func:`_march_2d`. q (N, m, 2), ρ, ∂ρ/∂w_n (N, m),
    ∂ρ/∂q (N, m, 2)."""
    m, C = w.shape[0], 3 * Phi.shape[1]
    contacts = np.arange(m)

    def rows(j):              # dq_j (m, 2, C) and dρ_j (m, C) of the samples j (m,)
        dq = np.zeros((m, 2, C))
        dq[:, 0, 1::3] = Phi[j]
        dq[:, 1, 2::3] = Phi[j]
        drho = np.zeros((m, C))
        drho[:, 0::3] = drho_dw[j, contacts][:, None] * Phi[j]
        drho[:, 1::3] = drho_dq[j, contacts, 0][:, None] * Phi[j]
        drho[:, 2::3] = drho_dq[j, contacts, 1][:, None] * Phi[j]
        return dq, drho

    j, k = np.maximum(active[:, 0], 0), np.maximum(active[:, 1], 0)
    dq_j, drho_j = rows(j)
    q_j, rho_j = q[j, contacts], rho[j, contacts]
    unit = (w - q_j) / rho_j[:, None]
    ratio = rho_j / np.maximum(np.linalg.norm(q_j, axis=1), 1e-300)
    M = np.eye(2) - ratio[:, None, None] * (np.eye(2) - unit[:, :, None] * unit[:, None, :])
    one = M @ dq_j + unit[:, :, None] * drho_j[:, None, :]
    dq_k, drho_k = rows(k)
    n_j, n_k = w - q_j, w - q[k, contacts]
    normals = np.stack([n_j, n_k], axis=1)                              # (m, 2, 2)
    rhs = np.stack([np.einsum("ma,mac->mc", n_j, dq_j) + rho_j[:, None] * drho_j,
                    np.einsum("ma,mac->mc", n_k, dq_k) + rho[k, contacts][:, None] * drho_k], axis=1)
    two = active[:, 1] >= 0
    det = np.linalg.det(normals)
    corner = two & (np.abs(det) > 1e-12 * np.einsum("mab,mab->m", normals, normals))
    result = np.where((active[:, 0] >= 0)[:, None, None], one, 0.0)
    if np.any(corner):
        result[corner] = np.linalg.solve(normals[corner], rhs[corner])
    return result


def step(p, q, normal_force, slider_previous):
    r"""One time step of n elements (time integration): the return map and its derivatives.

    q (n, 2) [m] (0 in an absent direction), λ_n (n,) [N], slider_previous (n, 2) [m].
    Returns (λ_t (n, 2) [N], slider (n, 2), state (n,) int8, ∂λ_t/∂q (n, 2, 2) [N/m],
    ∂λ_t/∂λ_n (n, 2) [-]): stick k_t I; slip μλ_n (I − ŝŝᵀ)/|s| and μ ŝ (s = q − w_prev);
    separated 0.
    """
    k_t, mu = p["tangential_stiffness"], p["friction_coefficient"]
    slider, state = slider_update(slider_previous, q, mu * normal_force / k_t)
    force = k_t[:, None] * (q - slider)
    s_vec = q - slider_previous
    norm = np.sqrt(np.einsum("ij,ij->i", s_vec, s_vec))
    norm = np.where(norm > 0, norm, 1.0)
    unit = s_vec / norm[:, None]
    slip = state == SLIP
    stick_coef = k_t * (state == STICK)
    slip_coef = mu * normal_force / norm * slip
    d_tq = (stick_coef + slip_coef)[:, None, None] * np.eye(2) \
        - slip_coef[:, None, None] * unit[:, :, None] * unit[:, None, :]
    d_tn = (slip * mu)[:, None] * unit
    return force, slider, state, d_tq, d_tn


def initial_slider(p, q, force=None):
    """Slider w = q − λ_t/k_t from a known tangential force (n, 2), or w = q (unloaded spring)."""
    if force is None:
        return q.copy()
    return q - force / p["tangential_stiffness"][:, None]


def slip_length(p):
    """μ N0 / k_t (n,) [m]: the slider travel scale under the constant normal load."""
    return p["friction_coefficient"] * p.get("normal_load", 0.0) / np.maximum(
        p["tangential_stiffness"], 1e-300)
