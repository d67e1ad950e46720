r"""Squeak: Jenkins element — tangential spring k_t in series with a Coulomb slider (limit μ λ_n).

Slider position w (in the tangent plane, 1 or 2 directions), tangential relative displacement q:

    λ_t = k_t (q − w),     |λ_t| ≤ μ λ_n.

One time step (the return map) projects the previous slider position onto the disk of radius
ρ = μ λ_n / k_t around q:

    w_j = q_j + Proj_{|x| ≤ ρ_j}(w_{j−1} − q_j)

states: separation (λ_n = 0: ρ = 0, the slider follows, λ_t = 0), stick (w_j = w_{j−1}),
slip (the projection is active, |λ_t| = μ λ_n). In one tangential direction the projection is a
clamp, w_j = clip(w_{j−1}, q_j − ρ_j, q_j + ρ_j).
"""
from __future__ import annotations

import numpy as np

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
    Returns dict with slider w (N, n), state (N, n) int8, reset (N, n) bool (slip or separation:
    the history is erased there), sign (N, n) ∈ {+1, −1, 0} with λ_t = sign·μλ_n at a slip sample
    (+1: w clamped at q − ρ), slider_end (n,), passes = 2.
    """
    q = np.asarray(tangential_displacement, dtype=float)
    rho = np.maximum(np.asarray(slip_radius, dtype=float), 0.0)
    lower, upper = q - rho, q + rho
    A, B = compose_clamps(lower, upper)
    slider_end = np.clip(slider_start, A[-1], B[-1])
    slider = np.clip(slider_end, A, B)
    previous = np.concatenate([slider_end[None], slider[:-1]], axis=0)
    below, above = previous < lower, previous > upper
    separated = rho <= 0.0
    sign = np.where(separated, 0, np.where(below, 1, np.where(above, -1, 0))).astype(np.int8)
    reset = separated | below | above
    state = np.where(separated, SEPARATED, np.where(below | above, SLIP, STICK)).astype(np.int8)
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
