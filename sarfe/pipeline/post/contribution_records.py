r"""Which contact makes the noise: the response of a point split into the excitation's part and one
part per named contact, and the ERP of each (:mod:`sarfe.erp.contributions`).

The structure is linear apart from the contact forces λ̃ (f_nl = Gᵀ λ), so per harmonic k the
reduced displacement is, exactly,

    ũ_k = Z_k⁻¹ f̃_k − Σ_c Z_k⁻¹ G_cᵀ λ̃_k,c = y_k − Σ_c Y_k[:, rows_c] λ̃_k,c,
    Z_k = K − (kω)² M + i kω D,

with y_k = Z_k⁻¹ f̃_k and Y_k = Z_k⁻¹ Gᵀ from :func:`sarfe.hbm.dynamic_stiffness.condense` (orders k = 1 … H:
the static term does not radiate) and rows_c the contact rows (normal and tangential) of the node
pairs of contact c. The excitation's part is the response of the structure with every contact
removed; a contact's part is the response to its own contact force alone. The radiating-surface
normal velocity of each part is v_k = i kω · erp_map · ũ_k [m/s], and the area-weighted products
of two parts the ERP needs are reduced quadratic forms,

    Σ_i A_i v̄_a,k,i v_b,k,i = (kω)² ũ_a,kᴴ Q ũ_b,k,     Q = erp_mapᵀ diag(A) erp_map   (n × n),

with Q built once per model: a point costs O(S H n²), whatever the size of the radiating surface.
"""
from __future__ import annotations

import numpy as np

from sarfe.case.config import ErpConfig
from sarfe.erp.contributions import contributions_from_gram, ranking_lines, superposition_stack
from sarfe.erp import reduced as reduced_erp
from sarfe.hbm.dynamic_stiffness import condense, to_complex

EXCITATION = "excitation"


def contact_rows(contacts, groups) -> np.ndarray:
    """(n_rows, n_groups) 0/1 matrix: row r of G belongs to named contact g (normal + tangents)."""
    member = np.zeros((contacts.row_count, len(groups)))
    for g, (_, _, idx) in enumerate(groups):
        rows = np.concatenate([np.asarray(contacts.normal_row)[idx],
                               np.asarray(contacts.tangent_rows)[idx].ravel()])
        member[rows[rows >= 0], g] = 1.0
    return member


def source_displacements(condensation, contact_force, member) -> np.ndarray:
    """ũ_s,k of the sources [excitation, contact 1, …] (1 + n_groups, H, n) complex [m].

    condensation: Condensation of orders 1 … H (forced y (H, n), admittance Y (H, n, n_rows),
    applied without forming it: :meth:`sarfe.hbm.dynamic_stiffness.Condensation.apply_admittance`);
    contact_force: λ̃ harmonics (2H+1, n_rows) [N] (sarfe convention); member: :func:`contact_rows`.
    """
    lam = to_complex(np.asarray(contact_force, dtype=float))[np.asarray(condensation.orders)]
    y = np.asarray(condensation.forced)                                     # (H, n)
    if not member.shape[1]:
        return y[None]
    loads = lam[None] * member.T[:, None, :]                                # (g, H, n_rows)
    return np.concatenate([y[None], -condensation.apply_admittance(loads)], axis=0)


def radiation_gram(stage) -> np.ndarray:
    """Q = Nᵀ diag(A) N (n, n) [m²], N = ``stage.erp_map`` (n_s, n) the radiating-node normal
    displacement per reduced coordinate, A the nodal areas: Σ_i A_i |w_i|² = uᴴ Q u for any
    complex reduced displacement u (:func:`sarfe.erp.reduced.radiation_gram`, once per stage)."""
    return reduced_erp.radiation_gram(stage.erp_map, stage.erp_areas)


def reduced_gram(Q, X, omega) -> np.ndarray:
    """Γ_k,ab = (kω)² X̄_a,k ᵀ Q X_b,k (H, A, A) complex [m⁴/s²]: the area-weighted inner products
    Σ_i A_i v̄_a,k,i v_b,k,i of the normal velocities v = i kω N x of reduced displacements
    X (A, H, n) complex [m] (harmonics k = 1 … H), without forming the nodal fields."""
    A, H, n = X.shape
    flat = X.reshape(A * H, n)
    QX = (flat.real @ Q + 1j * (flat.imag @ Q)).reshape(A, H, n)
    Xh, QXh = np.moveaxis(X, 1, 0), np.moveaxis(QX, 1, 0)                  # (H, A, n)
    k2 = ((np.arange(1, H + 1) * float(omega)) ** 2)[:, None, None]
    return k2 * (Xh.conj() @ np.swapaxes(QXh, 1, 2))


def point_condensation(nl, solution):
    """The condensation of orders 1 … H of the excitation at the point's ω
    (:func:`sarfe.hbm.dynamic_stiffness.condense`), or None when a Z_k is singular there."""
    U = np.asarray(solution.displacement, dtype=float)
    H = (U.shape[0] - 1) // 2
    excitation = np.zeros_like(U)
    F = np.asarray(nl.excitation, dtype=float)
    m = min(F.shape[0], U.shape[0])
    excitation[:m] = F[:m]
    return condense(nl.model, nl.contacts.gap_map, excitation, float(solution.omega),
                    orders=np.arange(1, H + 1))


def point_contributions(erp: ErpConfig, stage, nl, solution, condensation=False):
    """:class:`sarfe.erp.contributions.ErpContributions` of one solution (sources: the excitation
    then the named contacts), or (None, reason) when it cannot be computed (no contacts, no
    radiating surface, a singular Z_k). ``condensation``: :func:`point_condensation` when
    computed beforehand (False: computed here).

    The partial and coherent powers are quadratic forms of the reduced source displacements,
    Γ_k = (kω)² X_kᴴ Q X_k with Q = Nᵀ diag(A) N (:func:`radiation_gram`, once per model), equal to
    the nodal sums Σ_i A_i v̄ v of :func:`sarfe.erp.contributions.erp_contributions` without
    recovering the radiating-node field of every source at every point."""
    if not nl.contacts.count:
        return None, "no contacts"
    if stage.erp_map.shape[0] == 0:
        return None, "no radiating surface"
    if condensation is False:
        condensation = point_condensation(nl, solution)
    if condensation is None:
        return None, "a dynamic stiffness Z_k is singular at this frequency"
    omega = float(solution.omega)
    member = contact_rows(nl.contacts, nl.groups)
    parts = source_displacements(condensation, solution.contact_force, member)   # (S, H, n)
    total = to_complex(np.asarray(solution.displacement, dtype=float))[1:]      # (H, n)
    gram = reduced_gram(radiation_gram(stage), superposition_stack(parts, total), omega)
    names = [EXCITATION] + [name for name, _, _ in nl.groups]
    return contributions_from_gram(names, gram, omega, True, density=erp.rho_kg_m3,
                                   sound_speed=erp.c_m_s,
                                   radiation_loss_factor=erp.radiation_loss_factor,
                                   reference_power=erp.reference_power_W), None


def contributions_record(erp: ErpConfig, stage, nl, solution, condensation=False) -> dict:
    """summary.json record of :func:`point_contributions` (``available`` false with a reason when
    it was not computed; a failure is reported, never raised)."""
    try:
        result, reason = point_contributions(erp, stage, nl, solution, condensation)
    except Exception as error:  # a diagnostic must not break a solve
        result, reason = None, f"{type(error).__name__}: {error}"
    if result is None:
        return {"available": False, "reason": reason}
    record = {"available": True, **result.as_dict()}
    record["ranking"] = ranking_lines(result, float(solution.omega) / (2 * np.pi),
                                      skip=(EXCITATION,))
    return record
