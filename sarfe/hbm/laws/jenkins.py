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
on a solution with another mean and rejected it. The periodic state is therefore the one reached
by marching from the slider position at assembly, w_start = 0 (q is measured from the undeformed
state): in 1-D w_0 = clip(0, A, B) with [A, B] the interval of periodic starts. A contact that
never slips keeps the spring it was assembled with (λ_t = k_t q: it carries its share of any static
load, exactly what a start from rest gives when the contact never slips), and one whose interval
does not hold 0 rests on the nearest edge — dragged by slip just as far as needed. λ_t is then a
continuous, piecewise smooth function of q̃ and λ̃_n alone (the ``slider_start`` of a call is not
used), continuous through stick ↔ slip transitions, and the Jacobian is k_t I in stick (regular
even where the contact is the only restraint).

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

from .. import harmonics as hm
from .contract import Parameter

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
                    tolerance, pass_cap, kept_rows):
    r"""Periodic tangential forces of n Jenkins elements over one period, and their AFT Jacobian.

    p: parameters (tangential_stiffness k_t, friction_coefficient μ; (n,) each); q (N, n, 2) [m]
    tangential displacements, one_d (n,) bool: only the first direction exists; normal_force λ_n (N, n) [N], normal_stiffness ∂λ_n/∂w (N, n) [N/m]; slider_start (n, 2);
    kept_rows: coefficient rows of the Jacobian (P of them). slider_start is not used: the periodic
    state is fixed by the gauge (module docstring), so it is a function of q and λ_n alone.
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
            J[c1] = _jacobian_1d(res, mu[c1] * normal_stiffness[:, c1], k_t[c1], H, N, kept_rows)
    c2 = np.flatnonzero(~one_d)
    if c2.size:
        force_t, st, w_end, n_pass, J2 = _march_2d(
            q_all[:, c2], rho[:, c2], mu[c2] * normal_stiffness[:, c2] / k_t[c2], k_t[c2],
            np.zeros((c2.size, 2)), H, N, jacobian, tolerance, pass_cap, kept_rows)
        force[:, c2] = force_t
        state[:, c2] = st
        slider_end[c2] = w_end
        passes = max(passes, n_pass)
        if jacobian:
            J[c2] = J2
    return force, state, slider_end, passes, J


def _jacobian_1d(res, mu_dlam, k_t, H, N, kept_rows):
    """∂λ̃_t/∂(w̃, q̃) of 1-D Jenkins elements in the local (h·3 + l) layout (l = 0 n, 1 t),
    h over the kept coefficient rows.

    The slider forgets its past at every slip or separation sample j(i), so
    λ_t,i = k_t (q_i − q_j) + s_j μ λ_n,j and ∂λ_t,i/∂X = k_t (Φ_i − Φ_j) + s_j μ ∂λ_n,j/∂w Φ_j
    (s_j = ±1 the slip direction), pushed through one FFT of the gathered rows Φ_{j(i)}; a contact
    sticking the whole period keeps the gauge slider w0 = 0 (module docstring): λ_t = k_t q,
    ∂w0/∂X = 0."""
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
    return J


def _march_2d(q, rho, drho_dw, k_t, start, H, N, jacobian, tolerance, pass_cap, kept_rows):
    r"""2-D Jenkins elements marched sample by sample (compiled kernels over contacts × samples,
    :mod:`.jenkins_march`).

    The disk projection of the slider is not composable like the 1-D clamp, so the march over
    samples is inherent to 2-D hysteresis. Periods are marched from ``start`` until the slider
    state at θ_0 repeats to ``tolerance`` × (max|q| + max ρ) or ``pass_cap`` periods; between passes
    the start is updated by Newton on the periodicity, w_0 ← w_0 + (I − A)⁻¹ (w_N − w_0) with
    A = ∂w_N/∂w_0 (where I − A is regular, i.e. the contact slipped), so a few passes suffice even
    when slip is rare and the plain iteration contracts slowly; a final period
    propagates the consistent tangent: with X = local harmonics (h·3 + l),
        dw_j = (I − P_j) dq_j + n_j dρ_j + P_j dw_{j−1},
    and the periodicity w_N = w_0 gives ∂w_0/∂X = (I − A)⁻¹ B (A = ∂w_N/∂w_0, B = ∂w_N/∂X at
    fixed w_0) when the contact slipped or separated; 0 when it stuck (``start`` = 0, the gauge of
    the module docstring).
    Returns (λ_t (N, n, 2), state (N, n), w_end (n, 2), passes, J (n, 3P, 3P) or None).
    """
    from . import jenkins_march as march    # numba is imported (and the kernels loaded) on first use
    n = q.shape[1]
    P = kept_rows.size                                       # local harmonic rows (kept set)
    scale = np.abs(q).max() + rho.max() + 1e-300
    q = np.ascontiguousarray(q, dtype=float)
    rho = np.ascontiguousarray(rho, dtype=float)
    w_start, passes = march.periodic_start(q, rho, np.array(start, dtype=float),
                                           tolerance * scale, pass_cap)
    Phi = np.ascontiguousarray(_basis(H, N)[:, kept_rows])
    force, state, dforce, history, dw = march.final_pass(
        q, rho, np.ascontiguousarray(drho_dw, dtype=float), np.asarray(k_t, dtype=float),
        w_start, Phi, jacobian)
    passes += 1
    if not jacobian:
        return force, state, w_start, passes, None
    forgot = np.any(state != STICK, axis=0)
    dw0 = np.zeros((n, 2, 3 * P))                           # stuck: w_0 = 0, the gauge
    if np.any(forgot):
        system = np.eye(2) - history[-1, forgot]
        dw0[forgot] = np.linalg.solve(system, dw[forgot])
    dforce -= k_t[None, :, None, None] * np.einsum("jcab,cbx->jcax", history, dw0)
    coeff = hm.harmonic_coefficients(dforce, H)[kept_rows]  # (P, n, 2, 3P)
    J = np.zeros((n, 3 * P, 3 * P))
    J[:, 1::3, :] = np.moveaxis(coeff[:, :, 0, :], 0, 1)
    J[:, 2::3, :] = np.moveaxis(coeff[:, :, 1, :], 0, 1)
    return force, state, w_start, passes, J


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
