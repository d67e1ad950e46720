r"""Sensitivity of the A-weighted ERP level of a converged periodic solution to the contact
parameters.

The level of the harmonics ũ (2H+1, n) of the reduced displacements, radiating-node normal
displacements W = ũ Nᵀ (N = the stage's ``erp_map`` (n_s, n), nodal areas A_i), is

    L_A = 10 log10( ½ρc·RLF Σ_k a_k p_k / P_ref ),    p_k = (kω)² Σ_i A_i (W_kc,i² + W_ks,i²),
    a_k = 10^(A(f_k)/10),  f_k = kω/2π                                  [dB(A)]

(the same number as :func:`sarfe.erp.erp.equivalent_radiated_power`'s ``level_total_a_db``). It is
a quadratic form in the harmonics, so its gradient is

    ∂L_A/∂W_kc,i = (10/ln 10) · 2 a_k (kω)² A_i W_kc,i / Σ_j a_j p_j    (sin rows alike, row 0: 0),
    ∂L_A/∂ũ = (∂L_A/∂W) N                                                [dB(A)/m],

independent of ρ, c, RLF and P_ref. The sensitivities dL_A/dp of each contact's gap, stiffnesses,
friction coefficient and normal load follow from one adjoint solve with the converged Jacobian
(:func:`sarfe.hbm.sensitivity.adjoint_sensitivities`).
"""
from __future__ import annotations

import numpy as np

from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED
from sarfe.erp.reduced import radiation_gram
from sarfe.erp.weighting import a_weighting_db
from sarfe.hbm.sensitivity import PARAMETERS, RELATIVE_STEP, adjoint_sensitivities

__all__ = ["a_weighted_level", "level_sensitivities"]


def a_weighted_level(displacement, omega, erp_map, areas, density=AIR_DENSITY,
                     sound_speed=SOUND_SPEED, radiation_loss_factor=1.0,
                     reference_power=REFERENCE_POWER):
    """(L_A [dB(A)], ∂L_A/∂ũ (2H+1, n) [dB(A)/m]) of displacement harmonics ũ (2H+1, n) [m] at
    ω [rad/s] (module docstring). erp_map N (n_s, n) dense or sparse; areas (n_s,) [m²]. A zero
    power gives (−inf, NaN gradient).

    Evaluated in the reduced coordinates with Q = Nᵀ diag(A) N (:func:`sarfe.erp.reduced.
    radiation_gram`, cached per map): p_k = (kω)² (ũ_kcᵀ Q ũ_kc + ũ_ksᵀ Q ũ_ks) and
    ∂L_A/∂ũ_kc = (10/ln 10) · 2 a_k (kω)² (Q ũ_kc) / Σ_j a_j p_j — the nodal sums above without
    forming W on every radiating node (two (2H+1)·n·n_s products per point on a fine mesh)."""
    U = np.asarray(displacement, dtype=float)
    H = (U.shape[0] - 1) // 2
    omega = float(omega)
    QU = U @ radiation_gram(erp_map, areas)                            # (2H+1, n), Q symmetric
    k_omega2 = (np.arange(1, H + 1) * omega) ** 2
    weight = 10.0 ** (a_weighting_db(np.arange(1, H + 1) * omega / (2.0 * np.pi)) / 10.0)
    rows = np.einsum("rn,rn->r", U[1:], QU[1:])
    power = k_omega2 * (rows[0::2] + rows[1::2])                       # p_k (H,)
    total = float(weight @ power)
    if not total > 0:
        return -np.inf, np.full(U.shape, np.nan)
    scale = 0.5 * density * sound_speed * radiation_loss_factor
    level = 10.0 * np.log10(scale * total / reference_power)
    coefficient = np.zeros(2 * H + 1)
    coefficient[1:] = np.repeat(10.0 / np.log(10.0) * 2.0 * weight * k_omega2 / total, 2)
    return level, coefficient[:, None] * QU


def level_sensitivities(model, contacts, excitation, solution, erp_map, areas,
                        names=PARAMETERS, condensed=True, relative_step=RELATIVE_STEP, **air):
    """(L_A [dB(A)], :class:`sarfe.hbm.sensitivity.Sensitivities` of L_A [dB(A) per unit of p]) of
    a converged HarmonicSolution of (``model``, ``contacts``, f̃_e = ``excitation``): one adjoint
    solve, no re-solve. erp_map (n_s, n), areas (n_s,) [m²] and ``air`` (density, sound_speed,
    radiation_loss_factor, reference_power: the level's value only) as for
    :func:`a_weighted_level`."""
    level, gradient = a_weighted_level(solution.displacement, solution.omega, erp_map, areas,
                                       **air)
    return level, adjoint_sensitivities(model, contacts, excitation, solution, gradient, names,
                                        condensed, relative_step)
