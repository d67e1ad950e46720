r"""Which contact makes the noise: the response of a point split into the excitation's part and one
part per named contact, and the ERP of each (:mod:`sarfe.erp.contributions`).

The structure is linear apart from the contact forces λ̃ (f_nl = Gᵀ λ), so per harmonic k the
reduced displacement is, exactly,

    ũ_k = Z_k⁻¹ f̃_k − Σ_c Z_k⁻¹ G_cᵀ λ̃_k,c = y_k − Σ_c Y_k[:, rows_c] λ̃_k,c,
    Z_k = K − (kω)² M + i kω D,

with y_k = Z_k⁻¹ f̃_k and Y_k = Z_k⁻¹ Gᵀ from :func:`sarfe.hbm.linear.condense` (orders k = 1 … H:
the static term does not radiate) and rows_c the contact rows (normal and tangential) of the node
pairs of contact c. The excitation's part is the response of the structure with every contact
removed; a contact's part is the response to its own contact force alone. The radiating-surface
normal velocity of each part is v_k = i kω · erp_map · ũ_k [m/s].
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from sarfe.io.config import ErpConfig

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

    condensation: Condensation of orders 1 … H (forced y (H, n), admittance Y (H, n, n_rows));
    contact_force: λ̃ harmonics (2H+1, n_rows) [N] (sarfe convention); member: :func:`contact_rows`.
    """
    from sarfe.hbm.linear import to_complex

    lam = to_complex(np.asarray(contact_force, dtype=float))[np.asarray(condensation.orders)]
    y = np.asarray(condensation.forced)                                     # (H, n)
    Y = np.asarray(condensation.admittance)                                 # (H, n, n_rows)
    parts = -np.einsum("knm,km,mg->gkn", Y, lam, member) if member.shape[1] else \
        np.zeros((0,) + y.shape, dtype=complex)
    return np.concatenate([y[None], parts], axis=0)


def _radiating(erp_map, U):
    """erp_map · ũ over the last axis: (..., n) → (..., n_s)."""
    shape = U.shape
    flat = U.reshape(-1, shape[-1])
    W = (erp_map @ flat.T).T if sp.issparse(erp_map) else flat @ np.asarray(erp_map).T
    return np.asarray(W).reshape(shape[:-1] + (W.shape[-1],))


def point_contributions(erp: ErpConfig, stage, nl, solution):
    """:class:`sarfe.erp.contributions.ErpContributions` of one solution (sources: the excitation
    then the named contacts), or (None, reason) when it cannot be computed (no contacts, no
    radiating surface, a singular Z_k)."""
    from sarfe.erp.contributions import erp_contributions, normal_velocity
    from sarfe.hbm.linear import condense, to_complex

    if not nl.contacts.count:
        return None, "no contacts"
    if stage.erp_map.shape[0] == 0:
        return None, "no radiating surface"
    U = np.asarray(solution.displacement, dtype=float)
    H = (U.shape[0] - 1) // 2
    omega = float(solution.omega)
    excitation = np.zeros_like(U)
    F = np.asarray(nl.excitation, dtype=float)
    m = min(F.shape[0], U.shape[0])
    excitation[:m] = F[:m]
    condensation = condense(nl.model, nl.contacts.gap_map, excitation, omega,
                            orders=np.arange(1, H + 1))
    if condensation is None:
        return None, "a dynamic stiffness Z_k is singular at this frequency"
    member = contact_rows(nl.contacts, nl.groups)
    parts = source_displacements(condensation, solution.contact_force, member)   # (S, H, n)
    W = _radiating(stage.erp_map, parts)                                          # (S, H, n_s)
    velocity = np.moveaxis(normal_velocity(np.moveaxis(W, 1, 0), omega), 0, 1)   # (S, H, n_s)
    total = normal_velocity(_radiating(stage.erp_map, to_complex(U)[1:]), omega)
    names = [EXCITATION] + [name for name, _, _ in nl.groups]
    return erp_contributions(names, velocity, stage.erp_areas, omega, total_velocity=total,
                             density=erp.rho_kg_m3, sound_speed=erp.c_m_s,
                             radiation_loss_factor=erp.radiation_loss_factor,
                             reference_power=erp.reference_power_W), None


def contributions_record(erp: ErpConfig, stage, nl, solution) -> dict:
    """summary.json record of :func:`point_contributions` (``available`` false with a reason when
    it was not computed; a failure is reported, never raised)."""
    try:
        result, reason = point_contributions(erp, stage, nl, solution)
    except Exception as error:  # a diagnostic must not break a solve
        result, reason = None, f"{type(error).__name__}: {error}"
    if result is None:
        return {"available": False, "reason": reason}
    from sarfe.erp.contributions import ranking_lines

    record = {"available": True, **result.as_dict()}
    record["ranking"] = ranking_lines(result, float(solution.omega) / (2 * np.pi),
                                      skip=(EXCITATION,))
    return record
