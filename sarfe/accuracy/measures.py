r"""The measures of a change of a harmonic-balance solution ũ (2H+1, n) at ω, on the quantities
users read (every estimate of :mod:`sarfe.accuracy` is a change of these between two solutions):

- relative first-harmonic contact amplitude: max over contact rows of |Δ a₁| / max a₁, a₁ the
  first-harmonic amplitude of r = G ũ (:func:`first_harmonic_amplitude`);
- ERP level [dB]: 10 log₁₀(P(ũ')/P(ũ)), P = Σ_k p_k, p_k = (kω)² Σ_s a_s |w_{s,k}|² (ERP ∝ normal
  velocity², w = E ũ the radiating normal displacements, a_s their areas; all DOFs with unit areas
  when no E; :func:`harmonic_powers`, :func:`erp_proxy`), or the same change of the A-weighted
  P_A (harmonic k weighted by 10^{A(kf)/10}) when larger: on impacts the high harmonics carry the
  dB(A) level, which converges more slowly in H (:func:`solution_change`).

Cheaper still and model-free (no solve at all) are the spectral tails

    tail(X) = ‖X_{k > H − m}‖ / ‖X_{k ≥ 1}‖,  m = max(1, ⌊H/4⌋)                   (2)

of the contact displacements and forces (energy in the highest kept harmonics), reported only.
"""
from __future__ import annotations

import numpy as np

from sarfe.erp.reduced import harmonic_power_proxy, radiation_gram
from sarfe.erp.weighting import a_weighting_db


def resize_harmonics(U, harmonics: int) -> np.ndarray:
    """Coefficients (2H+1, ...) → (2H'+1, ...): truncate or pad with zeros."""
    U = np.asarray(U, dtype=float)
    rows = 2 * int(harmonics) + 1
    out = np.zeros((rows,) + U.shape[1:])
    m = min(rows, U.shape[0])
    out[:m] = U[:m]
    return out


def spectral_tail(X, top=None) -> float:
    """(2): share of the energy of harmonics k ≥ 1 in the top ``top`` harmonics (default ⌊H/4⌋, ≥ 1)."""
    X = np.asarray(X, dtype=float)
    H = (X.shape[0] - 1) // 2
    if H < 1:
        return 0.0
    top = max(1, H // 4) if top is None else int(top)
    energy = (X[1:].reshape(H, 2, -1) ** 2).sum(axis=(1, 2))
    total = energy.sum()
    if not total > 0:
        return 0.0
    return float(np.sqrt(energy[H - top:].sum() / total))


def harmonic_energy(X) -> np.ndarray:
    """Energy per harmonic order k = 0…H of coefficients (2H+1, ...): (H+1,) (k = 0: the mean²)."""
    X = np.asarray(X, dtype=float)
    H = (X.shape[0] - 1) // 2
    out = np.empty(H + 1)
    out[0] = (X[0] ** 2).sum()
    out[1:] = (X[1:].reshape(H, 2, -1) ** 2).sum(axis=(1, 2))
    return out


def first_harmonic_amplitude(contacts, U) -> np.ndarray:
    """a₁ = |(G ũ)₁| per contact row (n_rows,) [m]: the first-harmonic amplitude of r = G ũ."""
    G = contacts.gap_map
    if G.shape[0] == 0:
        return np.zeros(0)
    return np.hypot(G @ U[1], G @ U[2])


def harmonic_powers(U, omega, erp_map=None, erp_areas=None) -> np.ndarray:
    """p_k = (kω)² Σ_s a_s |w_{s,k}|² (H,) (the ERP of harmonic k up to ½ρc): by the reduced
    quadratic form Q = Nᵀ diag(a) N (:mod:`sarfe.erp.reduced`, built once per map) when a
    radiating map N is given, else over all DOFs with unit areas."""
    U = np.asarray(U, dtype=float)
    if erp_map is None:
        areas = np.ones(U.shape[1]) if erp_areas is None else np.asarray(erp_areas, dtype=float)
        rows = (U[1:] ** 2) @ areas
        return (np.arange(1, rows.size // 2 + 1) * omega) ** 2 * (rows[0::2] + rows[1::2])
    areas = np.ones(erp_map.shape[0]) if erp_areas is None else erp_areas
    return harmonic_power_proxy(U, omega, radiation_gram(erp_map, areas))


def erp_proxy(U, omega, erp_map=None, erp_areas=None, a_weighted=False, powers=None) -> float:
    """P = Σ_k (kω)² Σ_s a_s |w_{s,k}|² (proportional to the ERP of all harmonics); with
    ``a_weighted`` each harmonic k weighted by 10^{A(k f)/10}, A the A-weighting [dB] at k f,
    f = ω / 2π (proportional to the A-weighted ERP, which on impacts the high harmonics carry).
    ``powers``: :func:`harmonic_powers` of U when computed already."""
    p = harmonic_powers(U, omega, erp_map, erp_areas) if powers is None else powers
    if a_weighted:
        k = np.arange(1, p.size + 1)
        p = p * 10.0 ** (np.asarray(a_weighting_db(k * omega / (2 * np.pi))) / 10.0)
    return float(p.sum())


def solution_change(contacts, U, U_new, omega, erp_map, erp_areas, ref_amplitude=None):
    """ũ → ũ' (both (2H+1, n) [m], at ω [rad/s]) → (relative first-harmonic amplitude change at
    the contacts, ERP level change [dB], the larger of the dB and dB(A) changes; module
    docstring). ``ref_amplitude``: the max a₁ to divide by (default ũ's); without contact rows
    the largest first-harmonic DOF amplitude is used."""
    a0 = first_harmonic_amplitude(contacts, U)
    a1 = first_harmonic_amplitude(contacts, U_new)
    scale = np.max(a0, initial=0.0) if ref_amplitude is None else ref_amplitude
    if a0.size and scale > 0:
        rel = float(np.max(np.abs(a1 - a0)) / scale)
    else:  # no contact rows: use the largest DOF
        d0 = np.hypot(U[1], U[2])
        d1 = np.hypot(U_new[1], U_new[2])
        rel = float(np.max(np.abs(d1 - d0)) / max(d0.max(initial=0.0), 1e-300))
    q0 = harmonic_powers(U, omega, erp_map, erp_areas)
    q1 = harmonic_powers(U_new, omega, erp_map, erp_areas)
    p0, p1 = float(q0.sum()), float(q1.sum())
    if erp_map is not None:
        # a radiating surface that is silent compared with the structure (power ratio < 1e-24,
        # amplitude < 1e-12: round-off) has no meaningful level change
        whole = erp_proxy(U, omega) * (np.sum(erp_areas) if erp_areas is not None else 1.0)
        if max(p0, p1) <= 1e-24 * whole:
            return rel, 0.0

    def level_change(p0, p1):
        return float(10 * np.log10(p1 / p0)) if p0 > 0 and p1 > 0 else (
            0.0 if p0 == p1 else float("inf"))

    db = level_change(p0, p1)
    db_a = level_change(erp_proxy(U, omega, a_weighted=True, powers=q0),
                        erp_proxy(U_new, omega, a_weighted=True, powers=q1))
    return rel, (db_a if abs(db_a) > abs(db) else db)      # the larger of dB and dB(A)


__all__ = ["resize_harmonics", "spectral_tail", "harmonic_energy", "first_harmonic_amplitude",
           "harmonic_powers", "erp_proxy", "solution_change"]
