r"""What each named contact does over one period of a periodic solution: impacts, peak force, slip
distance and the energy it dissipates.

With the contact state s_j (0 open, 1 closed/stick, 2 slip) at θ_j = 2πj/N, the relative
displacements r(θ_j) = G u and forces λ(θ_j) of the contact rows:

    impacts per period   Σ_pairs #{j : s_{j−1} = 0 and s_j ≠ 0}          (cyclic; closings)
    peak force           max_j √(λ_n,j² + |λ_t,j|²) of the contact's summed pair forces   [N]
    slip distance        max_pairs Σ_{j : s_j = 2 or s_{j−1} = 2} |p_j − p_{j−1}|           [m]
                         with the slider position p = q − λ_t / k_t (Jenkins element; the
                         tangential relative displacement q itself when k_t = 0), so stick
                         (p constant) and separation (s = 0 at both ends) add nothing
    dissipated energy    D = D_n + D_t ≥ 0 per period [J], only the law's dissipative parts:
                         D_n = (T/N) Σ_j [λ_n(w_j, ẇ_j) − λ_n(w_j, 0)] ẇ_j   (a rate-dependent
                               normal law: the dashpot and its no-pulling cut-off; each term ≥ 0
                               for a force non-decreasing in ẇ; 0 for a rate-independent law),
                         D_t = Σ_{j : s_j = slip} λ_t,j · (p_j − p_{j−1})   (Coulomb slip work of
                               the Jenkins slider; the return map moves p along λ_t, so each
                               term is ≥ 0 exactly; on a curved partner λ_t is the tangent
                               rows' force less the normal force's components −κ q λ_n,
                               :mod:`sarfe.hbm.laws.curvature`).
                         The elastic parts (penalty spring λ_n(w, 0) and the tangential spring
                         k_t (q − p)) are conservative: their work over a closed period is
                         exactly 0 and is not summed. (Before: Σ_rows ∮ λ ṙ dt by Parseval of
                         the H-harmonic r̃ and the AFT's λ̃ — for a pure penalty contact that is
                         the truncation/aliasing error of a conservative force's zero work, of
                         either sign: −2.1 µJ on the P1 door trim's upper_1, −0.4 µJ on the
                         instrument panel's end_left.)
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm import laws
from sarfe.hbm.harmonics import derivative_matrix, time_samples
from sarfe.hbm.laws.curvature import friction_rows


def normal_dissipation(nl, r, rate, omega) -> np.ndarray:
    """D_n (n_c,) [J] (module docstring) from the contact-row samples r(θ_j), ṙ(θ_j) (N, n_rows)
    [m, m/s]: (T/N) Σ_j [λ_n(w_j, ẇ_j) − λ_n(w_j, 0)] ẇ_j for the rate-dependent normal laws,
    0 for the others (their normal force is a function of w: no work over a period)."""
    cs = nl.contacts
    out = np.zeros(cs.count)
    N = r.shape[0]
    for contact_law, idx, p in laws.groups(cs):
        rows = np.asarray(cs.normal_row)[idx]
        idx, rows = idx[rows >= 0], rows[rows >= 0]
        if not contact_law.velocity_dependent or not idx.size:
            continue
        p = cs.law_parameters(contact_law, idx)
        w, wdot, gap = r[:, rows], rate[:, rows], cs.gap[idx]
        viscous = contact_law.normal(p, gap, w, wdot).force \
            - contact_law.normal(p, gap, w, np.zeros_like(wdot)).force
        out[idx] = 2.0 * np.pi / omega / N * np.sum(viscous * wdot, axis=0)
    return out


def contact_dynamics(solution, nl) -> list[dict]:
    """Per named contact (``nl.groups`` order): impacts_per_period, peak_force_N,
    slip_distance_m (squeak contacts; NaN otherwise), dissipated_energy_J (module docstring)."""
    cs = nl.contacts
    if not cs.count:
        return []
    state = np.asarray(solution.contact_state)
    force = np.asarray(solution.contact_force_time, dtype=float)               # (N, n_rows)
    N = force.shape[0]
    R = np.asarray(solution.contact_displacement, dtype=float)
    r = time_samples(R, N) if R.shape[1] else np.zeros((N, 0))
    omega = float(solution.omega)
    H = (R.shape[0] - 1) // 2
    rate = omega * time_samples(derivative_matrix(H) @ R, N) if R.shape[1] else r
    normal_loss = normal_dissipation(nl, r, rate, omega) if R.shape[1] else np.zeros(cs.count)
    friction = friction_rows(cs, r, force) if R.shape[1] else force   # curved: less −κ q λ_n
    if state.shape[0] != N:  # states sampled differently from the forces: resample by phase
        state = state[(np.arange(N) * state.shape[0]) // N]
    closing = (state != 0) & (np.roll(state, 1, axis=0) == 0)                  # (N, n_c)
    slipping = (state == 2) | (np.roll(state, 1, axis=0) == 2)
    normal_row = np.asarray(cs.normal_row)
    tangent_rows = np.asarray(cs.tangent_rows)
    k_t = np.asarray(cs.tangential_stiffness, dtype=float)
    out = []
    for name, kind, idx in nl.groups:
        nr = normal_row[idx]
        normal = force[:, nr[nr >= 0]].sum(axis=1) + np.asarray(cs.normal_load)[idx].sum()
        tr = tangent_rows[idx]                                                 # (p, 2)
        t = np.where(tr >= 0, tr, 0)
        valid = (tr >= 0)[None]                                                # (1, p, 2)
        lam_t = force[:, t] * valid                                            # (N, p, 2)
        tangential = np.sqrt((lam_t.sum(axis=1) ** 2).sum(axis=1))
        slip, slip_work = float("nan"), 0.0
        if valid.any():
            q = r[:, t] * valid
            lam_t = friction[:, t] * valid
            stiffness = k_t[idx][None, :, None]
            slider = q - np.divide(lam_t, stiffness, out=np.zeros_like(lam_t),
                                   where=stiffness > 0)
            moved = slider - np.roll(slider, 1, axis=0)                         # (N, p, 2)
            step = np.sqrt((moved ** 2).sum(axis=2))                           # (N, p)
            slip = float((step * slipping[:, idx]).sum(axis=0).max())
            slip_work = float(((lam_t * moved).sum(axis=2) * (state[:, idx] == 2)).sum())
        out.append({"name": name,
                    "impacts_per_period": int(closing[:, idx].sum()),
                    "peak_force_N": float(np.sqrt(normal ** 2 + tangential ** 2).max()),
                    "slip_distance_m": slip,
                    "dissipated_energy_J": float(normal_loss[idx].sum()) + slip_work})
    return out
