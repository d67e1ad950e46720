r"""Alternating frequency–time (AFT) scheme: contact force harmonics and their analytic Jacobian.

For the contact displacement harmonics r̃ (2H+1, n_rows) (r = G u, rows of all contacts):

    r(θ_j) = Φ r̃, ṙ(θ_j) = ω Φ ∇ r̃ (inverse real FFT, N samples) → λ(θ_j) by the laws → λ̃ = E λ

and f̃_nl = Gᵀ λ̃ harmonic by harmonic. The laws are reached only through :mod:`sarfe.hbm.laws`,
group by group (all contacts of one law at once, vectorized over contacts × samples). The
Jacobian ∂λ̃/∂r̃ is block diagonal over contacts (each contact couples its own normal/tangent rows
over all harmonics); it is assembled analytically:

* the pointwise normal part: E diag(∂λ/∂w) Φ + ω E diag(∂λ/∂ẇ) Φ ∇, built from the discrete
  Fourier coefficients of ∂λ/∂w (∂λ/∂ẇ) up to order 2H with product-to-sum identities (O(H²) per
  contact, :func:`pointwise_jacobian`);
* a hysteretic tangent element (Jenkins): its own periodic march and Jacobian
  (:func:`sarfe.hbm.laws.jenkins.periodic_forces`);
* a curved partner (:mod:`sarfe.hbm.laws.curvature`): the law sees the penetration
  w − g − ½ Σ κ_i q_i², the tangent rows get −κ_i q_i λ_n, and the pointwise couplings
  ∂λ/∂(w, q) enter as further E diag(·) Φ blocks (:func:`curvature_blocks`).

Rate-dependent laws also give ∂λ̃/∂ω = E diag(∂λ/∂ẇ) Φ ∇ r̃ (``omega_derivative``) and the blocks
E diag(∂λ/∂ẇ) Φ of Hill's damping term (``damping_blocks``); for rate-independent laws both are
absent (∂f̃_nl/∂ω = 0).

With ``kept_rows`` (a harmonic set, :mod:`sarfe.hbm.harmonic_set`) the forces are still computed on
all 2H+1 rows, but the Jacobian blocks hold only the kept rows and columns (the Fourier basis Φ is
restricted to the kept columns before the pushes through the FFT, so that work falls with the set).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import harmonics as hm
from sarfe.hbm import laws
from sarfe.hbm.laws import curvature


@lru_cache(maxsize=32)
def _product_tables(H: int):
    """Index/sign tables of E diag(d) Φ in terms of T = [a_0..a_2H, b_0..b_2H] (see pointwise_jacobian)."""
    orders = hm.harmonic_orders(H)
    is_sin = np.zeros(2 * H + 1, bool)
    is_sin[2::2] = True
    k, l = orders[:, None], orders[None, :]
    rs, cs = is_sin[:, None], is_sin[None, :]
    diff, total = np.abs(k - l), k + l
    b_off = 2 * H + 1
    # cos k cos l = ½[cos(k−l) + cos(k+l)]; sin k sin l = ½[cos(k−l) − cos(k+l)]
    # cos k sin l = ½[sin(l−k) + sin(l+k)]; sin k cos l = ½[sin(k−l) + sin(k+l)]
    idx1 = np.where(rs == cs, diff, b_off + diff)
    idx2 = np.where(rs == cs, total, b_off + total)
    sign1 = np.where(rs == cs, 1.0, np.where(cs, np.sign(l - k), np.sign(k - l)))
    sign2 = np.where(rs & cs, -1.0, 1.0)
    weight = np.where(orders == 0, 0.5, 1.0)[:, None]
    return idx1, idx2, sign1 * weight, sign2 * weight


def pointwise_jacobian(derivative_time: np.ndarray, harmonics: int, kept_rows=None) -> np.ndarray:
    r"""E diag(d) Φ for each column d of ``derivative_time`` (N, n) → (n, 2H+1, 2H+1), or only the
    ``kept_rows`` rows and columns (n, P_k, P_k).

    With a_m = (1/N) Σ_j d_j cos mθ_j and b_m = (1/N) Σ_j d_j sin mθ_j (m = 0 … 2H, one real FFT),
    the entries follow from product-to-sum identities, e.g.
    (2/N) Σ d cos kθ cos lθ = a_{|k−l|} + a_{k+l},  (2/N) Σ d sin kθ sin lθ = a_{|k−l|} − a_{k+l}.
    Exact for the sampled law (N ≥ 2H+1), O(n H²) work.
    """
    d = np.asarray(derivative_time, dtype=float)
    N, H = d.shape[0], int(harmonics)
    spectrum = hm._fft.rfft(d.reshape(N, -1), axis=0).reshape((N // 2 + 1,) + d.shape[1:])
    m = np.arange(2 * H + 1)
    mirrored = m > N // 2
    coeff = spectrum[np.where(mirrored, N - m, m)]
    coeff[mirrored] = coeff[mirrored].conj()
    table = np.concatenate([coeff.real, -coeff.imag], axis=0).T / N  # (n, 4H+2) = [a | b]
    idx1, idx2, s1, s2 = _product_tables(H)
    if kept_rows is not None:
        keep = np.ix_(kept_rows, kept_rows)
        idx1, idx2, s1, s2 = idx1[keep], idx2[keep], s1[keep], s2[keep]
    return s1 * table[:, idx1] + s2 * table[:, idx2]


def tangential_samples(contacts, idx, r):
    """q (N, n_g, 2) [m] of the contacts ``idx`` at the samples r (N, n_rows); 0 where a contact
    has no such tangent row."""
    rows = contacts.tangent_rows[idx]
    return np.where((rows >= 0)[None], r[:, np.maximum(rows, 0)], 0.0)


def curvature_blocks(kappa, q, force, stiffness, harmonics, kept_rows=None):
    r"""The pointwise curved-partner terms of n contacts in the local layout (h·3 + l; l = 0
    normal, 1, 2 tangents): E diag(∂λ_n/∂q_i) Φ in the normal rows' tangent columns, the same
    (symmetric) in the tangent rows' normal columns, E diag(∂λ_q,i/∂q_k) Φ in the tangent rows'
    tangent columns (:func:`sarfe.hbm.laws.curvature.coupling`). q (N, n, 2), λ_n and ∂λ_n/∂δ
    (N, n). Returns (n, 3P, 3P) [N/m]; the friction's own terms are not included."""
    _, slope, hessian = curvature.coupling(kappa, q, force, stiffness)
    n = force.shape[1]
    P = 2 * int(harmonics) + 1 if kept_rows is None else len(kept_rows)
    J = np.zeros((n, 3 * P, 3 * P))
    for i in range(2):
        coupled = pointwise_jacobian(slope[..., i], harmonics, kept_rows)
        J[:, 0::3, i + 1::3] = coupled
        J[:, i + 1::3, 0::3] = coupled
        for k in range(2):
            J[:, i + 1::3, k + 1::3] = pointwise_jacobian(hessian[..., i, k], harmonics, kept_rows)
    return J


@dataclass(frozen=True)
class ContactForces:
    """Result of one AFT evaluation.

    force (2H+1, n_rows) [N] λ̃; force_time (N, n_rows) [N]; state (N, n_c) int8;
    blocks: list of (rows (n_g, m) int with −1 = absent, J (n_g, (2H+1)m, (2H+1)m)) with local
    ordering harmonic-major (index h·m + l), ∂λ̃/∂r̃ of each contact group [N/m];
    slider_end (n_c, 2) [m] periodic slider state at θ_0 (nan without a tangent element);
    friction_passes int; omega_derivative: ∂λ̃/∂ω (2H+1, n_rows) [N s] or None (rate independent);
    damping_blocks: like ``blocks``, E diag(∂λ/∂ṙ) Φ [N s/m] of the rate-dependent laws (Hill).
    """

    force: np.ndarray
    force_time: np.ndarray
    state: np.ndarray
    blocks: list
    slider_end: np.ndarray
    friction_passes: int
    omega_derivative: np.ndarray = None
    damping_blocks: list = ()


def default_slider_start(contacts, displacement_time):
    """Slider start w(θ_0⁻) = q(θ_0): the tangential spring relaxed before the first sample."""
    rows = contacts.tangent_rows
    start = np.full((contacts.count, 2), np.nan)
    present = rows >= 0
    start[present] = displacement_time[0, rows[present]]
    return start


def contact_forces(contacts, contact_displacement, samples_per_period, slider_start=None,
                   jacobian=True, friction_tolerance=1e-12, friction_pass_cap=50,
                   kept_rows=None, omega=None) -> ContactForces:
    r"""λ̃(r̃, ω) for all contacts by AFT, and ∂λ̃/∂r̃ blocks when ``jacobian``.

    contact_displacement r̃ (2H+1, n_rows) [m]; N = samples_per_period; slider_start (n_c, 2) [m]
    (default: q(θ_0), see :func:`default_slider_start`); omega [rad/s] (needed only by
    rate-dependent laws). Laws as registered in :mod:`sarfe.hbm.laws`.
    kept_rows: coefficient rows of a harmonic set; the blocks then hold only those (P_k of them).
    """
    R = np.asarray(contact_displacement, dtype=float)
    H, N = (R.shape[0] - 1) // 2, int(samples_per_period)
    r = hm.time_samples(R, N)                              # (N, n_rows)
    n_rows, n_c = R.shape[1], contacts.count
    if slider_start is None:
        slider_start = default_slider_start(contacts, r)
    slider_start = np.where(np.isnan(slider_start), default_slider_start(contacts, r), slider_start)
    lam = np.zeros((N, n_rows))
    state = np.zeros((N, n_c), np.int8)
    slider_end = np.full((n_c, 2), np.nan)
    blocks, damping_blocks, passes = [], [], 0
    omega_derivative = None
    rows_k = np.arange(2 * H + 1) if kept_rows is None else np.asarray(kept_rows)
    P = rows_k.size
    velocity = None

    for law, idx, p in laws.groups(contacts):
        normal_rows = contacts.normal_row[idx]
        has_normal = normal_rows >= 0
        gap = contacts.gap[idx]
        safe = np.maximum(normal_rows, 0)
        w = np.where(has_normal, r[:, safe], gap) if not np.all(has_normal) else r[:, normal_rows]
        kappa = curvature.curvatures(p)
        if kappa is not None:                  # a curved partner: the slide moves the surface
            q_all = tangential_samples(contacts, idx, r)
            w = curvature.effective_normal(kappa, w, q_all)
        wdot = None
        if law.velocity_dependent:
            if omega is None:
                raise ValueError(f"the {law.name} law depends on velocity: give omega")
            if velocity is None:       # ṙ(θ_j) = ω Φ ∇ r̃, and ∇ r̃ for ∂λ̃/∂ω
                slope = hm.derivative_matrix(H) @ R
                velocity = (slope, omega * hm.time_samples(slope, N))
            wdot = np.where(has_normal, velocity[1][:, safe], 0.0)
        out = law.normal(p, gap, w, wdot)
        if np.all(has_normal):
            np.add.at(lam, (slice(None), normal_rows), out.force)
            stiffness = out.stiffness
        else:
            if np.any(has_normal):
                np.add.at(lam, (slice(None), normal_rows[has_normal]), out.force[:, has_normal])
            stiffness = np.where(has_normal, out.stiffness, 0.0)
        state[:, idx] = out.closed
        damping = None
        if out.damping is not None:
            damping = np.where(has_normal, out.damping, 0.0)
            if omega_derivative is None:
                omega_derivative = np.zeros((2 * H + 1, n_rows))
            rate = hm.harmonic_coefficients(damping * hm.time_samples(velocity[0][:, safe], N), H)
            np.add.at(omega_derivative, (slice(None), normal_rows[has_normal]),
                      rate[:, has_normal])
        slope_q = None
        if kappa is not None:
            geometric, slope_q, _ = curvature.coupling(kappa, q_all, out.force, stiffness)
            t_all = contacts.tangent_rows[idx]
            for col in range(2):
                on = t_all[:, col] >= 0
                np.add.at(lam, (slice(None), t_all[on, col]), geometric[:, on, col])
        normal_jacobian = None
        if jacobian:
            normal_jacobian = pointwise_jacobian(stiffness, H, kept_rows)
            if damping is not None:
                viscous = pointwise_jacobian(damping, H, kept_rows)
                nabla = hm.derivative_matrix(H)[np.ix_(rows_k, rows_k)]
                normal_jacobian = normal_jacobian + omega * viscous @ nabla
                damping_blocks.append((np.where(has_normal, normal_rows, -1)[:, None], viscous))
        # a tangent element acts on the contacts with tangent rows (optional for some laws)
        with_tangent = contacts.tangent_rows[idx, 0] >= 0 if law.tangent is not None \
            else np.zeros(idx.size, bool)
        if not np.all(with_tangent):
            if jacobian:
                alone = ~with_tangent
                blocks.append((np.where(has_normal, normal_rows, -1)[alone, None],
                               normal_jacobian[alone] if np.any(with_tangent)
                               else normal_jacobian))
            if not np.any(with_tangent):
                continue
        sel = np.flatnonzero(with_tangent) if not np.all(with_tangent) else slice(None)
        t_idx = idx[sel]
        t_rows = contacts.tangent_rows[t_idx]
        present = t_rows >= 0
        q = np.where(present[None], r[:, np.maximum(t_rows, 0)], 0.0)       # (N, n_t, 2)
        p_t = p if isinstance(sel, slice) else {k: v[sel] for k, v in p.items()}
        force_t, st, w_end, n_pass, J_t = law.tangent.periodic_forces(
            p_t, q, ~present[:, 1], out.force[:, sel], stiffness[:, sel], slider_start[t_idx], H,
            N, jacobian, friction_tolerance, friction_pass_cap, rows_k,
            None if slope_q is None else slope_q[:, sel])
        for col in range(2):
            on = present[:, col]
            if np.any(on):
                np.add.at(lam, (slice(None), t_rows[on, col]), force_t[:, on, col])
        state[:, t_idx] = st
        slider_end[t_idx] = w_end
        passes = max(passes, n_pass)
        if jacobian:
            J_t[:, 0::3, 0::3] = normal_jacobian[sel]
            if kappa is not None:
                J_t += curvature_blocks(kappa[sel], q, out.force[:, sel], stiffness[:, sel], H,
                                        kept_rows)
            normal_t = np.where(has_normal, normal_rows, -1)[sel]
            blocks.append((np.column_stack([normal_t, t_rows]), J_t))
    return ContactForces(hm.harmonic_coefficients(lam, H), lam, state, blocks, slider_end, passes,
                         omega_derivative, damping_blocks)


def jacobian_matrix(blocks, n_rows: int, harmonics: int, dense: bool = False, kept_rows=None):
    """Assemble ∂λ̃/∂r̃ blocks into a (P n_rows)² matrix, harmonic-major ordering; P = 2H+1, or the
    number of ``kept_rows`` for blocks of a harmonic set.

    Sparse CSR by default; a dense ndarray when ``dense`` (small condensed systems).
    """
    P = 2 * int(harmonics) + 1 if kept_rows is None else len(kept_rows)
    size = P * n_rows
    I, Jc, V = [], [], []
    for rows, block in blocks:
        m = rows.shape[1]
        local = (np.arange(P)[:, None] * n_rows + rows[:, None, :]).reshape(rows.shape[0], P * m)
        valid = np.repeat((rows >= 0)[:, None, :], P, axis=1).reshape(rows.shape[0], P * m)
        mask = valid[:, :, None] & valid[:, None, :]
        I.append(np.broadcast_to(local[:, :, None], block.shape)[mask])
        Jc.append(np.broadcast_to(local[:, None, :], block.shape)[mask])
        V.append(block[mask])
    if dense:
        out = np.zeros((size, size))
        rows_used = np.concatenate([rows[rows >= 0] for rows, _ in blocks]) if blocks else ()
        distinct = np.unique(rows_used).size == len(rows_used)
        for i, j, v in zip(I, Jc, V):
            if distinct:            # each row in one block: no (i, j) twice, plain assignment
                out[i, j] = v
            else:
                np.add.at(out, (i, j), v)
        return out
    if not I:
        return sp.csr_matrix((size, size))
    return sp.csr_matrix((np.concatenate(V), (np.concatenate(I), np.concatenate(Jc))),
                         shape=(size, size))
