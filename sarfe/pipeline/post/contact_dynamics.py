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
    dissipated energy    Σ_rows ∮ λ ṙ dt = Σ_rows T (λ₀ ṙ₀ + ½ Σ_k λ_kc ṙ_kc + λ_ks ṙ_ks)   [J]
                         (Parseval, :func:`sarfe.hbm.time_integration.period_work`); penalty
                         rows give 0 on a periodic orbit, friction rows the Coulomb loss
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.harmonics import derivative_matrix, time_samples


def _row_work(solution) -> np.ndarray:
    """∮ λ ṙ dt per contact row (n_rows,) [J]."""
    R = np.asarray(solution.contact_displacement, dtype=float)
    L = np.asarray(solution.contact_force, dtype=float)
    H = (R.shape[0] - 1) // 2
    omega = float(solution.omega)
    weight = np.full(2 * H + 1, 0.5)
    weight[0] = 1.0
    Rdot = omega * derivative_matrix(H) @ R
    return 2.0 * np.pi / omega * np.sum(weight[:, None] * L[: 2 * H + 1] * Rdot, axis=0)


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
    work = _row_work(solution) if R.shape[1] else np.zeros(0)
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
        slip = float("nan")
        if valid.any():
            q = r[:, t] * valid
            stiffness = k_t[idx][None, :, None]
            slider = q - np.divide(lam_t, stiffness, out=np.zeros_like(lam_t),
                                   where=stiffness > 0)
            step = np.sqrt(((slider - np.roll(slider, 1, axis=0)) ** 2).sum(axis=2))  # (N, p)
            slip = float((step * slipping[:, idx]).sum(axis=0).max())
        rows = np.concatenate([nr, tr.ravel()])
        rows = rows[rows >= 0]
        out.append({"name": name,
                    "impacts_per_period": int(closing[:, idx].sum()),
                    "peak_force_N": float(np.sqrt(normal ** 2 + tangential ** 2).max()),
                    "slip_distance_m": slip,
                    "dissipated_energy_J": float(work[rows].sum()) if rows.size else 0.0})
    return out
