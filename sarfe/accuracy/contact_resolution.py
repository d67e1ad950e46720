r"""Is an impact resolved by the harmonics at all? The premise of the truncation estimate (3) of
:mod:`sarfe.accuracy.harmonic_truncation` is that the error already decays like H^{−p} between H
and H'. An impact of a stiff contact breaks it: its force is a pulse as short as the contact's
own period, and its spectrum is flat far beyond H' — the change H → H' then says nothing about
the error at H (issue 29, k_n = 10¹⁰ N/m on lumped_rattle: the H = 7 branch is 17–39 % off the
resolved time integration on its impacting part where the change-based ± said 9 %, or did not
converge).

The indicator, per contact c that opens and closes within the period (an impact; a contact that
never opens is a linear spring, one that never closes carries no force):

    ρ_c(k) = k_c · |C_k,cc|,   C_k = G Z(kω)⁻¹ Gᵀ,  k_c = max_t ∂λ_n/∂w (t)             (6)

the contact's stiffest tangent (the law's, over the AFT samples) times the structure's condensed
dynamic compliance at its normal row at harmonic k. Above the structure's modes the compliance is
mass-like, |C_k| ≈ 1/(m_c (kω)²), so ρ_c(k) = (ω_c / kω)² with ω_c = √(k_c / m_c) the contact's
frequency: the impact lasts τ_c = π / ω_c (a half period of the mass on the contact spring) and
its force spectrum is flat up to kω ≈ ω_c / 2 and falls off beyond (a half-sine pulse:
|λ_k| ∝ |cos(kωτ_c/2)| / |1 − (kωτ_c/π)²|). The estimate's H' reaches the decay when

    ρ(H') = max_c ρ_c(H') ≤ RESOLUTION_LIMIT = 4   ⇔   H' ω ≥ ω_c / 2                 (7)

and otherwise the point has no trustworthy error bound (said, with τ_c and T / (2H'), the shortest
time H' resolves). Measured (benchmarks/results/hard_contact_error.md), the largest ρ at the
impacting points of the shipped cases: lumped_rattle (k_n = 10⁶ N/m) 0.45 (τ_c = 1.2 ms),
rattle_rig 0.64, door_trim 2.2 (squeak_rig: no impact) — none flagged; lumped_rattle at
k_n = 10⁷ 1.6 … 5.1 (19 of 196 points, near the first touch at 42 Hz), 10⁸ 16 … 51 (all; the
change-based ± there 2.1 % where the Newmark orbit is 5.9 % off, at 45 Hz), 10¹⁰ 1.6·10³ … 5·10³
(all; τ_c = 12 µs against T/(2H') ≈ 0.5 ms; the branch 17–47 % off the Newmark orbit).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.accuracy.measures import resize_harmonics
from sarfe.hbm import harmonics as hm
from sarfe.hbm import laws
from sarfe.hbm.dynamic_stiffness import condense

RESOLUTION_LIMIT = 4.0      # (7): ρ(H') above it — H' ω below half the contact frequency


@dataclass(frozen=True)
class ContactResolution:
    """(6)–(7) at a solution: ``ratio`` ρ(H') (0 without an impacting contact), ``harmonics`` H',
    ``contact`` the name of the contact with the largest ρ (None: none impacts),
    ``contact_frequency_hz`` ω_c / 2π = H' f √ρ, ``impact_duration_s`` τ_c = π / ω_c,
    ``resolved_duration_s`` T / (2H') (the shortest time H' resolves) and ``resolved`` ρ ≤
    RESOLUTION_LIMIT."""

    harmonics: int
    ratio: float
    contact: str | None
    contact_frequency_hz: float
    impact_duration_s: float
    resolved_duration_s: float
    resolved: bool

    def note(self) -> str:
        """One line saying why the point has no error bound (empty when resolved)."""
        if self.resolved:
            return ""
        return (f"no error bound: the impact of {self.contact} lasts ≈ "
                f"{1e6 * self.impact_duration_s:.3g} µs (contact frequency "
                f"{self.contact_frequency_hz:.3g} Hz), far shorter than the "
                f"{1e6 * self.resolved_duration_s:.3g} µs that H' = {self.harmonics} harmonics "
                f"resolve (ρ = {self.ratio:.3g} > {RESOLUTION_LIMIT:g}): the change to H' does "
                f"not bound the error; a bound needs H' ≥ {self.needed_harmonics()} (raise "
                "solver.harmonics) or a softer contact")

    def needed_harmonics(self) -> int:
        """The H' at which (7) would hold, ⌈H' √(ρ / RESOLUTION_LIMIT)⌉ (mass-like compliance)."""
        return int(np.ceil(self.harmonics * np.sqrt(max(self.ratio, 0.0) / RESOLUTION_LIMIT)))

    def as_dict(self) -> dict:
        return {"harmonics": self.harmonics, "ratio": self.ratio, "contact": self.contact,
                "contact_frequency_hz": self.contact_frequency_hz,
                "impact_duration_s": self.impact_duration_s,
                "resolved_duration_s": self.resolved_duration_s, "resolved": self.resolved,
                "needed_harmonics": self.needed_harmonics()}


def impact_stiffness(contacts, contact_displacement, samples_per_period, omega):
    """Per contact (n_c,): k_c = max over the N samples of the law's ∂λ_n/∂w [N/m] where the
    contact opens and closes within the period, 0 elsewhere (no normal row, always open, or
    always closed: a linear spring). contact_displacement r̃ (2H+1, n_rows) [m]."""
    R = np.asarray(contact_displacement, dtype=float)
    H = (R.shape[0] - 1) // 2
    r = hm.time_samples(R, int(samples_per_period))
    out = np.zeros(contacts.count)
    for law, idx, p in laws.groups(contacts):
        rows = np.asarray(contacts.normal_row)[idx]
        has = rows >= 0
        if not np.any(has):
            continue
        w = np.where(has, r[:, np.maximum(rows, 0)], np.asarray(contacts.gap)[idx])
        wdot = None
        if law.velocity_dependent:
            slope = hm.time_samples(hm.derivative_matrix(H) @ R, int(samples_per_period))
            wdot = np.where(has, float(omega) * slope[:, np.maximum(rows, 0)], 0.0)
        normal = law.normal(p, np.asarray(contacts.gap)[idx], w, wdot)
        closed = np.asarray(normal.closed, dtype=bool)
        impacts = has & closed.any(axis=0) & ~closed.all(axis=0)
        stiffness = np.max(np.abs(np.asarray(normal.stiffness, dtype=float)), axis=0)
        out[idx] = np.where(impacts, stiffness, 0.0)
    return out


def row_compliance(model, gap_map, excitation, omega, order):
    """|C_k,ii| = |(G Z(kω)⁻¹ Gᵀ)_ii| (n_rows,) [m/N] at harmonic ``order`` k (the engine's
    condensation, :func:`sarfe.hbm.dynamic_stiffness.condense`); None when Z(kω) is singular."""
    k = int(order)
    condensed = condense(model, gap_map, resize_harmonics(excitation, k), float(omega),
                         orders=np.array([k]))
    if condensed is None:
        return None
    n_rows = np.shape(gap_map)[0]
    C = condensed.compliance.reshape(2, n_rows, 2, n_rows)
    diagonal = np.arange(n_rows)
    return np.hypot(C[0, diagonal, 0, diagonal], C[0, diagonal, 1, diagonal])


def contact_resolution(solution, model, contacts, excitation, extended) -> ContactResolution:
    """(6)–(7) of a :class:`HarmonicSolution` for the estimate's H' = ``extended`` (Z(H'ω)
    singular: the next order is used). excitation f̃_e (2H_e+1, n) [N]."""
    omega = float(solution.omega)
    period = 2 * np.pi / omega
    H_ext = int(extended)
    stiffness = impact_stiffness(contacts, solution.contact_displacement,
                                 solution.samples_per_period, omega)
    none = ContactResolution(H_ext, 0.0, None, float("nan"), float("nan"), period / (2 * H_ext),
                             True)
    if not np.any(stiffness > 0):
        return none
    compliance = row_compliance(model, contacts.gap_map, excitation, omega, H_ext)
    if compliance is None:
        H_ext += 1
        compliance = row_compliance(model, contacts.gap_map, excitation, omega, H_ext)
    if compliance is None:
        return none
    rows = np.asarray(contacts.normal_row)
    ratio = np.where(rows >= 0, stiffness * compliance[np.maximum(rows, 0)], 0.0)
    c = int(np.argmax(ratio))
    rho = float(ratio[c])
    omega_c = H_ext * omega * np.sqrt(rho)
    names = contacts.names or tuple(f"contact_{i}" for i in range(contacts.count))
    return ContactResolution(H_ext, rho, str(names[c]), omega_c / (2 * np.pi), np.pi / omega_c,
                             period / (2 * H_ext), bool(rho <= RESOLUTION_LIMIT))


__all__ = ["RESOLUTION_LIMIT", "ContactResolution", "impact_stiffness", "row_compliance",
           "contact_resolution"]
