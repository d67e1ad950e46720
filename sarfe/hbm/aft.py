r"""Alternating frequency–time (AFT) scheme: contact force harmonics and their analytic Jacobian.

For the contact displacement harmonics r̃ (2H+1, n_rows) (r = G u, rows of all contacts):

    r(θ_j) = Φ r̃  (inverse real FFT, N samples)  →  λ(θ_j) by the laws  →  λ̃ = E λ  (real FFT)

and f̃_nl = Gᵀ λ̃ harmonic by harmonic. The Jacobian ∂λ̃/∂r̃ is block diagonal over contacts (each
contact couples its own normal/tangent rows over all harmonics); it is assembled analytically:

* pointwise laws (rattle, the normal part of squeak): E diag(∂λ/∂w) Φ, built from the discrete
  Fourier coefficients of ∂λ/∂w up to order 2H with product-to-sum identities (O(H²) per contact,
  :func:`pointwise_jacobian`);
* 1-D Jenkins: the slider forgets its past at every slip or separation sample j(i), so
  λ_t,i = k_t (q_i − q_j) + s_j μ λ_n,j and ∂λ_t,i/∂X = k_t (Φ_i − Φ_j) + s_j μ ∂λ_n,j/∂w Φ_j
  (s_j = ±1 the slip direction), pushed through one FFT of the gathered rows Φ_{j(i)};
  a contact sticking the whole period gives λ_t = k_t (q − w0) with w0 a history constant,
  ∂w0/∂X = 0 (w0 = the periodic slider state reached from ``slider_start``);
* 2-D Jenkins: the consistent tangent of the sample-by-sample march (see :mod:`sarfe.hbm.friction`),
  with the periodicity condition w_N = w_0 solved for ∂w_0/∂X (zero when the contact sticks).

The laws are displacement-only and rate-independent: ∂f̃_nl/∂ω = 0.

With ``kept_rows`` (a harmonic set, :mod:`sarfe.hbm.harmonic_set`) the forces are still computed on
all 2H+1 rows, but the Jacobian blocks hold only the kept rows and columns (the Fourier basis Φ is
restricted to the kept columns before the pushes through the FFT, so that work falls with the set).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from . import harmonics as hm
from .friction import (STICK, jenkins_periodic_1d, last_reset_index, slider_update,
                       slider_update_derivatives)
from .unilateral import normal_force


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


@lru_cache(maxsize=32)
def _basis(H: int, N: int):
    E, Phi = hm.fourier_matrices(H, N)
    return Phi


@dataclass(frozen=True)
class ContactForces:
    """Result of one AFT evaluation.

    force (2H+1, n_rows) [N] λ̃; force_time (N, n_rows) [N]; state (N, n_c) int8;
    blocks: list of (rows (n_g, m) int with −1 = absent, J (n_g, (2H+1)m, (2H+1)m)) with local
    ordering harmonic-major (index h·m + l), ∂λ̃/∂r̃ of each contact group [N/m];
    slider_end (n_c, 2) [m] periodic slider state at θ_0 (nan for rattle); friction_passes int.
    """

    force: np.ndarray
    force_time: np.ndarray
    state: np.ndarray
    blocks: list
    slider_end: np.ndarray
    friction_passes: int


def default_slider_start(contacts, displacement_time):
    """Slider start w(θ_0⁻) = q(θ_0): the tangential spring relaxed before the first sample."""
    rows = contacts.tangent_rows
    start = np.full((contacts.count, 2), np.nan)
    present = rows >= 0
    start[present] = displacement_time[0, rows[present]]
    return start


def contact_forces(contacts, contact_displacement, samples_per_period, slider_start=None,
                   jacobian=True, friction_tolerance=1e-12, friction_pass_cap=50,
                   kept_rows=None) -> ContactForces:
    r"""λ̃(r̃) for all contacts by AFT, and ∂λ̃/∂r̃ blocks when ``jacobian``.

    contact_displacement r̃ (2H+1, n_rows) [m]; N = samples_per_period; slider_start (n_c, 2) [m]
    (default: q(θ_0), see :func:`default_slider_start`). Laws as in :mod:`sarfe.hbm.contacts`.
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
    blocks, passes = [], 0
    kinds = np.asarray(contacts.kind)
    rows_k = np.arange(2 * H + 1) if kept_rows is None else np.asarray(kept_rows)

    # --- rattle: λ_n = k_n max(0, w − g) -------------------------------------------------------
    rattle = np.flatnonzero(kinds == "rattle")
    if rattle.size:
        rows = contacts.normal_row[rattle]
        force, stiffness = normal_force(r[:, rows], contacts.gap[rattle],
                                        contacts.normal_stiffness[rattle])
        np.add.at(lam, (slice(None), rows), force)
        state[:, rattle] = stiffness > 0
        if jacobian:
            blocks.append((rows[:, None], pointwise_jacobian(stiffness, H, kept_rows)))

    # --- squeak: normal penalty + N0, Jenkins element tangentially -----------------------------
    squeak = np.flatnonzero(kinds == "squeak")
    if squeak.size:
        P = rows_k.size
        n_rows_c = contacts.normal_row[squeak]
        t_rows = contacts.tangent_rows[squeak]
        has_normal = n_rows_c >= 0
        w = np.where(has_normal, r[:, np.maximum(n_rows_c, 0)], 0.0)
        force_n, stiff_n = normal_force(w, contacts.gap[squeak], contacts.normal_stiffness[squeak])
        force_n = np.where(has_normal, force_n, 0.0) + contacts.normal_load[squeak]
        stiff_n = np.where(has_normal, stiff_n, 0.0)
        if np.any(has_normal):
            np.add.at(lam, (slice(None), n_rows_c[has_normal]), force_n[:, has_normal])
        mu, k_t = contacts.friction_coefficient[squeak], contacts.tangential_stiffness[squeak]
        rho = mu * force_n / k_t                            # (N, n_s) slip radius [m]
        J = np.zeros((squeak.size, 3 * P, 3 * P)) if jacobian else None
        if jacobian:
            J[:, 0::3, 0::3] = pointwise_jacobian(stiff_n, H, kept_rows)
        one_d = t_rows[:, 1] < 0
        # 1-D contacts: clamp scan, exact steady state in one pass
        c1 = np.flatnonzero(one_d)
        if c1.size:
            rows_t = t_rows[c1, 0]
            q = r[:, rows_t]
            res = jenkins_periodic_1d(q, rho[:, c1], slider_start[squeak[c1], 0])
            force_t = k_t[c1] * (q - res["slider"])
            np.add.at(lam, (slice(None), rows_t), force_t)
            state[:, squeak[c1]] = res["state"]
            slider_end[squeak[c1], 0] = res["slider_end"]
            passes = max(passes, res["passes"])
            if jacobian:
                J[c1] += _jenkins_1d_jacobian(res, mu[c1] * stiff_n[:, c1], k_t[c1], H, N, rows_k)
        c2 = np.flatnonzero(~one_d)
        if c2.size:
            rows_t = t_rows[c2]
            q = r[:, rows_t]                                # (N, n2, 2)
            force_t, st, w_end, n_pass, J2 = _jenkins_2d(
                q, rho[:, c2], mu[c2] * stiff_n[:, c2] / k_t[c2], k_t[c2],
                slider_start[squeak[c2]], H, N, jacobian, friction_tolerance, friction_pass_cap,
                rows_k)
            np.add.at(lam, (slice(None), rows_t[:, 0]), force_t[:, :, 0])
            np.add.at(lam, (slice(None), rows_t[:, 1]), force_t[:, :, 1])
            state[:, squeak[c2]] = st
            slider_end[squeak[c2]] = w_end
            passes = max(passes, n_pass)
            if jacobian:
                J[c2] += J2
        if jacobian:
            rows = np.column_stack([np.where(has_normal, n_rows_c, -1), t_rows])
            blocks.append((rows, J))
    return ContactForces(hm.harmonic_coefficients(lam, H), lam, state, blocks, slider_end, passes)


def _jenkins_1d_jacobian(res, mu_dlam, k_t, H, N, kept_rows):
    """∂λ̃_(n,t)/∂(w̃, q̃) of 1-D Jenkins contacts in the local (h·3 + l) layout (l = 0 n, 1 t),
    h over the kept coefficient rows."""
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


def _jenkins_2d(q, rho, drho_dw, k_t, start, H, N, jacobian, tolerance, pass_cap, kept_rows):
    r"""2-D Jenkins elements marched sample by sample (vectorized over contacts).

    The disk projection of the slider is not composable like the 1-D clamp, so the march over
    samples is inherent to 2-D hysteresis. Periods are marched from ``start`` until the slider
    state at θ_0 repeats to ``tolerance`` × (max|q| + max ρ) or ``pass_cap`` periods; between passes
    the start is updated by Newton on the periodicity, w_0 ← w_0 + (I − A)⁻¹ (w_N − w_0) with
    A = ∂w_N/∂w_0 (where I − A is regular, i.e. the contact slipped), so a few passes suffice even
    when slip is rare and the plain iteration contracts slowly; a final period
    propagates the consistent tangent: with X = local harmonics (h·3 + l),
        dw_j = (I − P_j) dq_j + n_j dρ_j + P_j dw_{j−1},
    and the periodicity w_N = w_0 gives ∂w_0/∂X = (I − A)⁻¹ B (A = ∂w_N/∂w_0, B = ∂w_N/∂X at
    fixed w_0) when the contact slipped or separated; 0 (history constant) when it stuck.
    Returns (λ_t (N, n, 2), state (N, n), w_end (n, 2), passes, J (n, 3P, 3P) or None).
    """
    n = q.shape[1]
    P = kept_rows.size                                       # local harmonic rows (kept set)
    scale = np.abs(q).max() + rho.max() + 1e-300
    w = np.array(start, dtype=float)
    passes = 0
    eye = np.eye(2)
    while True:
        w0 = w.copy()
        A = np.broadcast_to(eye, (n, 2, 2)).copy()        # ∂w_N/∂w_0 over the pass
        for j in range(N):
            w, _, Pj, _ = slider_update_derivatives(w, q[j], rho[j])
            A = Pj @ A
        passes += 1
        residual = w - w0
        if np.abs(residual).max() <= tolerance * scale or passes >= pass_cap:
            w = w0 if np.abs(residual).max() <= tolerance * scale else w
            break
        # Newton on the periodicity w_N(w_0) = w_0 where it is well posed (slip: I − A regular)
        system = eye - A
        det = np.linalg.det(system)
        ok = np.abs(det) > 1e-6
        if np.any(ok):
            w[ok] = w0[ok] + np.linalg.solve(system[ok], residual[ok][..., None])[..., 0]
    Phi = _basis(H, N)[:, kept_rows]
    force = np.empty((N, n, 2))
    state = np.empty((N, n), np.int8)
    if jacobian:
        dw = np.zeros((n, 2, 3 * P))                        # ∂w/∂X at fixed w_0
        dw_dw0 = np.broadcast_to(np.eye(2), (n, 2, 2)).copy()
        dforce = np.empty((N, n, 2, 3 * P))
        history = np.empty((N, n, 2, 2))
        dq = np.zeros((N, 2, 3 * P))                       # ∂q_j/∂X templates
        dq[:, 0, 1::3], dq[:, 1, 2::3] = Phi, Phi
        dn = np.zeros((N, 3 * P))                          # ∂w_j/∂X (normal) template
        dn[:, 0::3] = Phi
    w_start = w.copy()
    for j in range(N):
        w, st, Pj, n_rho = slider_update_derivatives(w, q[j], rho[j])
        force[j] = k_t[:, None] * (q[j] - w)
        state[j] = st
        if jacobian:      # dw_j = P_j (dw_{j−1} − dq_j) + dq_j + n_j dρ_j
            dw = Pj @ (dw - dq[j]) + dq[j] + n_rho[:, :, None] * (drho_dw[j][:, None, None]
                                                                  * dn[j][None, None, :])
            dw_dw0 = Pj @ dw_dw0
            dforce[j] = k_t[:, None, None] * (dq[j] - dw)
            history[j] = dw_dw0
    passes += 1
    if not jacobian:
        return force, state, w, passes, None
    forgot = np.any(state != STICK, axis=0)
    dw0 = np.zeros((n, 2, 3 * P))
    if np.any(forgot):
        system = np.eye(2) - dw_dw0[forgot]
        dw0[forgot] = np.linalg.solve(system, dw[forgot])
    dforce -= k_t[None, :, None, None] * np.einsum("jcab,cbx->jcax", history, dw0)
    coeff = hm.harmonic_coefficients(dforce, H)[kept_rows]  # (P, n, 2, 3P)
    J = np.zeros((n, 3 * P, 3 * P))
    J[:, 1::3, :] = np.moveaxis(coeff[:, :, 0, :], 0, 1)
    J[:, 2::3, :] = np.moveaxis(coeff[:, :, 1, :], 0, 1)
    return force, state, w_start, passes, J


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
        for i, j, v in zip(I, Jc, V):
            np.add.at(out, (i, j), v)
        return out
    if not I:
        return sp.csr_matrix((size, size))
    return sp.csr_matrix((np.concatenate(V), (np.concatenate(I), np.concatenate(Jc))),
                         shape=(size, size))
