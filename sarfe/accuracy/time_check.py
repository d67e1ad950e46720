r"""The error of one harmonic-balance point measured against the Newmark time integration, where
no change of H bounds it (an impact the harmonics do not resolve,
:mod:`sarfe.accuracy.contact_resolution`).

The model M ü + D u̇ + K u + Gᵀ λ(G u) = f_e(t) is integrated from the point's own state
(:func:`sarfe.hbm.time_integration.integrate_time`: N = STEPS_PER_PERIOD steps a period, the steps
in which a contact opens or closes sub-stepped to ω_c h ≤ 0.1, Richardson N / 2N) for at most
PERIODS periods, and the settled orbit's harmonics (up to H_ref = min(MAX_HARMONICS, N / 8)) are
compared with the point's on the estimate's measures (:func:`sarfe.accuracy.measures.
solution_change`: the first-harmonic contact amplitude and the ERP level, the larger of the dB and
dB(A) changes) and on the first harmonic of all DOFs:

    amplitude_rel = max(|Δa₁| / max a₁, ‖û₁ − û₁^TI‖∞ / ‖û₁^TI‖∞),  erp_db = |L − L^TI|      (8)

The integration's own error is small against what it measures here (lumped_rattle at k_n =
10¹⁰ N/m, 71.5 Hz: N = 2048 and 4096 agree to 0.08 %, sub-step resolutions 0.05 … 0.2 to 0.2 %,
the orbit's period-start jitter ~0.2 %; benchmarks/results/extremes.md). Where the orbit leaves
the point for another one (the point is no stable orbit of the model) the difference is that
distance, said in ``note``.
"""
from __future__ import annotations

import time

import numpy as np

from sarfe.accuracy.measures import first_harmonic_amplitude, resize_harmonics, solution_change
from sarfe.hbm.time_integration import integrate_time, section_spread

STEPS_PER_PERIOD = 2048     # N (Richardson with 2N): the k_n = 10¹⁰ orbit to 0.1 %
PERIODS = 40                # at most; the vibro-impact orbit keeps a ~0.2 % jitter
MAX_HARMONICS = 64          # H_ref: the orbit's harmonics compared (its impacts' ERP)
LEFT_ORBIT = 0.5            # first-harmonic contact amplitude change that means another orbit


def time_integration_error(solution, model, contacts, excitation, erp_map=None, erp_areas=None,
                           steps_per_period=STEPS_PER_PERIOD, periods=PERIODS) -> dict:
    """(8) for a :class:`HarmonicSolution` → {amplitude_rel, erp_db, first_harmonic_rel,
    contact_amplitude_rel, harmonics, steps_per_period, periods, steady, spread (of the last 10
    period starts), contact_work_rel (∮ λ dr / input work per contact: ≈ 0 for an elastic one,
    the check of the integration's impacts), seconds, note}. excitation f̃_e (2H_e+1, n) [N]; erp_map (n_s, n), erp_areas (n_s,) [m²]."""
    clock = time.perf_counter()
    N = int(steps_per_period)
    H = int(solution.harmonics)
    H_ref = int(max(H, min(MAX_HARMONICS, N // 8)))
    omega = float(solution.omega)
    reference = integrate_time(model, contacts, excitation, omega, H_ref, steps_per_period=N,
                               richardson=True, initial=solution, max_periods=int(periods))
    U = resize_harmonics(solution.displacement, H_ref)
    V = np.asarray(reference.displacement_harmonics, dtype=float)
    a_ref = np.max(first_harmonic_amplitude(contacts, V), initial=0.0) or None
    contact_rel, db = solution_change(contacts, V, U, omega, erp_map, erp_areas, a_ref)
    first = np.hypot(U[1] - V[1], U[2] - V[2]).max() / max(np.hypot(V[1], V[2]).max(), 1e-300)
    spread = float(section_spread(reference.section, tail=10)) \
        if reference.section is not None and len(reference.section) > 1 else float("nan")
    work = np.asarray(reference.contact_work, dtype=float) / max(abs(reference.input_work), 1e-300)
    note = ("the integration left the point for another orbit (the point is not a stable orbit "
            "of the model)" if contact_rel > LEFT_ORBIT else "")
    return {"amplitude_rel": float(max(contact_rel, first)), "erp_db": float(abs(db)),
            "first_harmonic_rel": float(first), "contact_amplitude_rel": float(contact_rel),
            "harmonics": H_ref, "steps_per_period": N, "periods": int(reference.periods),
            "steady": bool(reference.steady), "spread": spread, "contact_work_rel": [float(x) for x in work],
            "seconds": time.perf_counter() - clock, "note": note}


__all__ = ["STEPS_PER_PERIOD", "PERIODS", "MAX_HARMONICS", "time_integration_error"]
