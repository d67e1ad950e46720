r"""The H and N parts of a solution's error estimate: harmonic truncation (H → H') and AFT
aliasing (N → N' = 2N), each the change of the solution re-solved there by Newton from ũ
(:mod:`sarfe.accuracy.correction`, (1)), measured on the contact amplitude and the ERP level
(:func:`sarfe.accuracy.measures.solution_change`).

H' is one doubling, 2H, at least H + 4 (two more odd orders: a friction contact that does not lift
off is nearly odd-symmetric; :func:`extended_harmonics`) and, when the model's natural frequencies
are known, at least the order past its highest mode (:func:`reach_harmonics`): an impact's
harmonic k that excites a plate mode at k f carries most of the ERP, and only above the highest
mode is the response mass-controlled and the decay regular. H is raised to H' in one Newton solve,
or in steps of ×1.5 when that does not converge (impacts, whose active set a large step
changes); when a raise does not converge, the change up to the last converged H'' is used (noted).

With an error that decays like e(H) ≈ C H^{−p}, the change to H' is
d = e(H) − e(H') = (1 − (H/H')^p) e(H), so

    e(H) ≈ d / (1 − (H/H')^p) ≤ max(2, 1 / (1 − H/H')) d   for p ≥ 1           (3)

(Richardson; :func:`harmonics_richardson` — an extension beyond the doubling does not lower the
factor below 2, as the decay below the highest mode is not yet the asymptotic one). p ≥ 1 holds for
the contact laws here: the penalty (rattle) force is continuous with a kink at contact onset and the
Jenkins (squeak) force is continuous with kinks at stick/slip, so its Fourier coefficients decay like
k⁻² and the displacements faster. The factor RICHARDSON = 2 multiplies the N → 2N change too
(aliasing errors of kinked forces decay like N⁻², 1/(1 − 2⁻²) < 2).
"""
from __future__ import annotations

import math

import numpy as np

from sarfe.accuracy.correction import newton_correction, newton_step, samples_for
from sarfe.accuracy.measures import resize_harmonics, solution_change

RICHARDSON = 2.0   # 1 / (1 − 2^{−p}) for an error ∝ H^{−p}, p = 1, and one doubling (3)
MAX_EXTENSION = 64      # cap of H' in :func:`reach_harmonics`


def extended_harmonics(harmonics: int) -> int:
    """H' used for the truncation estimate: 2H (one doubling, (3)) and at least H + 4, so that the
    next two odd orders are in (a friction contact that does not lift off is nearly odd-symmetric:
    its even harmonics vanish, and a step to H + 1 or 2H = 2 would add none)."""
    return int(max(2 * harmonics, harmonics + 4))


def reach_harmonics(harmonics: int, omega: float, highest_mode_hz=None) -> int:
    """H' for a model with natural frequencies up to ``highest_mode_hz``: :func:`extended_harmonics`
    and at least the order ⌈f_top / f⌉ + 1 that passes the highest mode (capped at MAX_EXTENSION).
    Harmonics below a mode can be resonant — an impact's harmonic k exciting a plate mode at k f
    carries most of the ERP — so an estimate that stops short of them misses them; above the
    highest mode the response is mass-controlled (G S_k⁻¹ Gᵀ ∝ (kω)⁻², w_k ≈ λ_k / (k ω)²) and the
    decay that (3) assumes holds."""
    H_ext = extended_harmonics(harmonics)
    if highest_mode_hz is None or not np.isfinite(highest_mode_hz) or omega <= 0:
        return H_ext
    reach = int(math.ceil(2 * np.pi * float(highest_mode_hz) / float(omega))) + 1
    return int(max(H_ext, min(MAX_EXTENSION, reach)))


def harmonics_richardson(harmonics: int, extended: int) -> float:
    """(3) with p = 1 for a change H → H'': 1 / (1 − H/H''), at least RICHARDSON (a doubling's) —
    an extension past the doubling reaches resonant harmonics, below which the decay is not yet
    the asymptotic one, so it does not lower the factor."""
    if extended <= harmonics:
        return RICHARDSON
    return float(max(RICHARDSON, 1.0 / (1.0 - harmonics / extended)))


def truncation_change(solution, model, contacts, excitation, extended, erp_map=None,
                      erp_areas=None, options=None, ref_amplitude=None, steps=None):
    """H → H' = ``extended``: the change of ``solution`` re-solved at H' (N ≥ 4H' + 1), one Newton
    solve, else the ×1.5 climb (:func:`sarfe.accuracy.correction.newton_correction`), else the
    climb by the engine's solver → (relative amplitude change, ERP level change [dB], H'' reached,
    notes). The changes are inf (unknown, not small) when no raise converged; H'' < H' when the
    climb stopped early. excitation f̃_e (2H_e+1, n) [N] (resized)."""
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    omega = float(solution.omega)
    notes = []
    H_ext = int(extended)
    U_new = newton_step(model, contacts, resize_harmonics(excitation, H_ext),
                        resize_harmonics(U, H_ext), omega, H_ext, samples_for(H_ext, N),
                        options, steps)
    for robust in (False, True):  # a large raise changed the active set: climb ×1.5 a step
        if U_new is None:
            U_new = newton_correction(model, contacts, excitation, solution, H_ext,
                                      samples_for(H_ext, N), options, robust)
            notes.append("truncation estimate: H raised in steps (one Newton solve at H' did "
                         "not converge)" + (", by the engine's solver" if robust else ""))
    if U_new is None:   # unknown, not small
        notes.append("truncation estimate: no re-solve with more harmonics converged")
        return float("inf"), float("inf"), H_ext, tuple(notes)
    if (U_new.shape[0] - 1) // 2 < H_ext:
        notes.append(f"truncation estimate: H raised to {(U_new.shape[0] - 1) // 2} of "
                     f"{H_ext} (the next raise did not converge)")
        H_ext = (U_new.shape[0] - 1) // 2
    rel, db = solution_change(contacts, resize_harmonics(U, H_ext), U_new, omega, erp_map,
                              erp_areas, ref_amplitude)
    return rel, db, H_ext, tuple(notes)


def aliasing_change(solution, model, contacts, excitation, erp_map=None, erp_areas=None,
                    options=None, ref_amplitude=None, steps=None):
    """N → 2N at the solution's H: the change of ``solution`` re-solved with twice the AFT samples
    (one Newton solve, else the engine's solver) → (relative amplitude change, ERP level change
    [dB], notes); inf (unknown, not small) when no re-solve converged."""
    H, N = int(solution.harmonics), int(solution.samples_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    omega = float(solution.omega)
    U_new = newton_step(model, contacts, resize_harmonics(excitation, H), U, omega, H, 2 * N,
                        options, steps)
    if U_new is None:   # (the cheap climb at the same H would repeat the step above exactly)
        U_new = newton_correction(model, contacts, excitation, solution, H, 2 * N, options,
                                  robust=True)
    if U_new is None:   # unknown, not small
        return float("inf"), float("inf"), ("aliasing estimate: no re-solve with 2N converged",)
    rel, db = solution_change(contacts, U, U_new, omega, erp_map, erp_areas, ref_amplitude)
    return rel, db, ()


__all__ = ["RICHARDSON", "MAX_EXTENSION", "extended_harmonics", "reach_harmonics",
           "harmonics_richardson", "truncation_change", "aliasing_change"]
