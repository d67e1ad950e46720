r"""Partial ERP of the sources of a surface velocity field, and their coherent shares.

The structure is linear apart from the contact forces, so per harmonic k the radiating-surface
normal velocity is a sum over sources s (the excitation and one term per contact, see
:mod:`sarfe.pipeline.post.contribution_records`):

    v_k,i = Σ_s v_s,k,i                                                    [m/s], complex

(complex amplitudes v = v_c − i v_s of node i). With the ERP constant κ = ½ ρ c · RLF [kg/(m² s)]
and nodal areas A_i [m²]:

    partial ERP of s        P_s,k = κ Σ_i A_i |v_s,k,i|²                              [W]
    coherent part of s      Q_s,k = κ Σ_i A_i Re(v_s,k,i* · v_k,i)                   [W]
    total                   P_k   = κ Σ_i A_i |v_k,i|² = Σ_s Q_s,k                   [W]

The partial ERP is what the surface would radiate if source s acted alone; the coherent part
splits the actual total among the sources (it is the projection of v_s on the total field in the
area-weighted inner product) and may be negative: a source that cancels part of the others' field.
Shares over the period's harmonics, unweighted and A-weighted (α_k = 10^(A(f_k)/10)):

    share_s   = Σ_k Q_s,k / Σ_k P_k,          share_A,s = Σ_k α_k Q_s,k / Σ_k α_k P_k,

so Σ_s share_s = Σ_s share_A,s = 1 exactly. The ranking orders the sources by share_A (the total is
judged in dB(A)). Two levels go with a source, and the ranking prints both, named:

    its part of the total   L_part,A = 10 lg(Σ_k α_k Q_s,k / P_ref) = L_A,total + 10 lg share_A,s
                            (only for share_A > 0: a source with a negative share cancels sound),
                            monotone with the share printed beside it;
    alone                   L_A,s = 10 lg(Σ_k α_k P_s,k / P_ref), what s radiates by itself —
                            not monotone with the share: a source in phase with the total may have
                            a large share and a small level alone, one out of phase the reverse. A motionless surface (total below ``MOTIONLESS_LEVEL_DB`` = −100 dB re 1 pW,
round-off radiates about −180 dB) has no sound to split: its shares and its superposition error
are NaN.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED, power_level_db
from sarfe.erp.weighting import a_weighting_db

__all__ = ["ErpContributions", "erp_contributions", "contributions_from_gram",
           "superposition_stack", "ranking_lines", "ranking_line", "share_text", "normal_velocity", "MOTIONLESS_LEVEL_DB"]

MOTIONLESS_LEVEL_DB = -100.0  # [dB re P_ref] below this total the surface counts as motionless


def normal_velocity(normal_displacement, omega: float) -> np.ndarray:
    """v_k = i k ω w_k [m/s] of complex normal-displacement amplitudes w (H, ...) for k = 1 … H."""
    w = np.asarray(normal_displacement)
    k = np.arange(1, w.shape[0] + 1).reshape((-1,) + (1,) * (w.ndim - 1))
    return 1j * k * float(omega) * w


@dataclass(frozen=True)
class ErpContributions:
    """Partial ERP and coherent shares of S sources over H harmonics (module docstring)."""

    names: tuple                 # (S,) source names (e.g. "excitation", contact names)
    frequencies_hz: np.ndarray   # (H,) f_k = k ω/2π [Hz]
    partial_power_W: np.ndarray  # (S, H) P_s,k [W]
    coherent_power_W: np.ndarray  # (S, H) Q_s,k [W] (signed)
    total_power_W: np.ndarray    # (H,) P_k [W]
    partial_total_W: np.ndarray  # (S,) Σ_k P_s,k [W]
    partial_level_db: np.ndarray  # (S,) [dB re 1 pW]
    partial_level_dba: np.ndarray  # (S,) A-weighted [dB(A)]
    share: np.ndarray            # (S,) Σ_k Q_s,k / Σ_k P_k [-]
    share_a: np.ndarray          # (S,) A-weighted share [-]
    part_level_db: np.ndarray    # (S,) 10 lg(Σ_k Q_s,k / P_ref) [dB re 1 pW], NaN where ≤ 0
    part_level_dba: np.ndarray   # (S,) its part of the A-weighted total [dB(A)], NaN where ≤ 0
    superposition_error: float   # ‖Σ_s v_s − v‖ / ‖v‖ (area-weighted), or NaN without a given total

    def order(self) -> np.ndarray:
        """Source indices by decreasing A-weighted share (NaN shares last)."""
        key = np.where(np.isfinite(self.share_a), -self.share_a, np.inf)
        return np.argsort(key, kind="stable")

    def as_dict(self) -> dict:
        return {"frequencies_hz": self.frequencies_hz.tolist(),
                "superposition_error": float(self.superposition_error),
                "sources": [{"name": str(name), "power_W": float(self.partial_total_W[s]),
                             "level_db": float(self.partial_level_db[s]),
                             "level_dba": float(self.partial_level_dba[s]),
                             "share": float(self.share[s]), "share_a": float(self.share_a[s]),
                             "part_level_db": float(self.part_level_db[s]),
                             "part_level_dba": float(self.part_level_dba[s]),
                             "harmonics_power_W": self.partial_power_W[s].tolist(),
                             "harmonics_coherent_power_W": self.coherent_power_W[s].tolist()}
                            for s, name in enumerate(self.names)]}


def erp_contributions(names, source_velocity, nodal_areas, omega: float, total_velocity=None,
                      density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED,
                      radiation_loss_factor: float = 1.0,
                      reference_power: float = REFERENCE_POWER) -> ErpContributions:
    """Partial ERP and coherent shares (module docstring) of full-field velocities.

    names : S source names; source_velocity : (S, H, n) complex normal velocities v_s,k,i [m/s] of
    harmonics k = 1 … H at n radiating nodes; nodal_areas : (n,) [m²]; omega : [rad/s];
    total_velocity : optional (H, n) complex v_k,i [m/s] of the solved response — the shares are
    taken against Σ_s v_s and ``superposition_error`` says how far that is from the given total.
    Forms the area-weighted Gram matrices of the sources (:func:`velocity_gram`) and hands them
    to :func:`contributions_from_gram`.
    """
    V = np.asarray(source_velocity, dtype=complex)
    if V.ndim != 3 or V.shape[0] != len(names):
        raise ValueError(f"source_velocity must be (S={len(names)}, H, n), got {V.shape}")
    areas = np.asarray(nodal_areas, dtype=float)
    if areas.shape != (V.shape[2],):
        raise ValueError(f"nodal_areas must be ({V.shape[2]},), got {areas.shape}")
    stacked = superposition_stack(V, total_velocity)
    gram = np.einsum("ahn,n,bhn->hab", stacked.conj(), areas, stacked)
    return contributions_from_gram(names, gram, omega, total_velocity is not None, density,
                                   sound_speed, radiation_loss_factor, reference_power)


def superposition_stack(sources, total=None):
    """(S + 2, H, ...) complex: the S sources x_s, their superposition defect d = Σ_s x_s − x and
    the given total x (zeros when ``total`` is None) — the vectors whose Gram matrix
    :func:`contributions_from_gram` takes. d is formed here, before any inner product, so a
    superposition error near round-off is not lost to cancellation."""
    X = np.asarray(sources, dtype=complex)
    given = np.zeros(X.shape[1:], dtype=complex) if total is None else \
        np.asarray(total, dtype=complex)
    return np.concatenate([X, (X.sum(axis=0) - given)[None], given[None]], axis=0)


def contributions_from_gram(names, gram, omega: float, has_total: bool = True,
                            density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED,
                            radiation_loss_factor: float = 1.0,
                            reference_power: float = REFERENCE_POWER) -> ErpContributions:
    """Partial ERP and coherent shares from the area-weighted velocity Gram matrices

        Γ_k,ab = Σ_i A_i v̄_a,k,i v_b,k,i      [m⁴/s²],  (H, S + 2, S + 2) complex Hermitian,

    of the vectors of :func:`superposition_stack` (S sources, the defect d, the given total):
    P_s,k = κ Γ_k,ss, Q_s,k = κ Re Σ_b≤S Γ_k,sb, P_k = κ Σ_a,b≤S Γ_k,ab, superposition error
    √(Σ_k Γ_k,dd / Σ_k Γ_k,tt) (NaN without a total). The Gram matrices may come from the nodal
    velocities or from a reduced quadratic form Γ_k = (kω)² X_kᴴ Q X_k (X reduced coordinates,
    Q = Nᵀ diag(A) N, :mod:`sarfe.pipeline.post.contribution_records`): the results are the same.
    """
    gram = np.asarray(gram, dtype=complex)
    S = len(names)
    if gram.ndim != 3 or gram.shape[1:] != (S + 2, S + 2):
        raise ValueError(f"gram must be (H, S + 2 = {S + 2}, S + 2), got {gram.shape}")
    kappa = 0.5 * density * sound_speed * radiation_loss_factor
    sources = gram[:, :S, :S]                                             # (H, S, S)
    error = float("nan")
    if has_total:
        norm = np.sqrt(max(float(gram[:, -1, -1].real.sum()), 0.0))
        diff = np.sqrt(max(float(gram[:, -2, -2].real.sum()), 0.0))
        error = float(diff / norm) if norm > 0 else float(diff)
    partial = kappa * np.einsum("hss->sh", sources).real.clip(min=0.0)   # (S, H)
    coherent = kappa * sources.sum(axis=2).real.T                        # (S, H)
    P = (kappa * sources.sum(axis=(1, 2)).real).clip(min=0.0)            # (H,)
    H = gram.shape[0]
    f = np.arange(1, H + 1) * float(omega) / (2.0 * np.pi)
    alpha = 10.0 ** (a_weighting_db(f) / 10.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = coherent.sum(axis=1) / P.sum()
        share_a = (coherent @ alpha) / (P @ alpha)
    if not P.sum() >= reference_power * 10.0 ** (MOTIONLESS_LEVEL_DB / 10.0):
        share, share_a = np.full(S, np.nan), np.full(S, np.nan)
        error = float("nan")
    part, part_a = coherent.sum(axis=1), coherent @ alpha
    with np.errstate(invalid="ignore", divide="ignore"):
        part_db = np.where(share > 0, power_level_db(np.clip(part, 0.0, None), reference_power),
                           np.nan)
        part_dba = np.where(share_a > 0, power_level_db(np.clip(part_a, 0.0, None),
                                                        reference_power), np.nan)
    return ErpContributions(
        names=tuple(str(n) for n in names), frequencies_hz=f, partial_power_W=partial,
        coherent_power_W=coherent, total_power_W=P, partial_total_W=partial.sum(axis=1),
        partial_level_db=power_level_db(partial.sum(axis=1), reference_power),
        partial_level_dba=power_level_db(partial @ alpha, reference_power),
        share=share, share_a=share_a, part_level_db=part_db, part_level_dba=part_dba,
        superposition_error=error)


def share_text(share) -> str:
    """'24 %' of a share (0…1); a share that rounds to 0 % reads '0 %' (never '-0 %'), a negative
    one '-3 %', NaN '- %'."""
    if share is None or not np.isfinite(share):
        return "- %"
    percent = int(round(100.0 * float(share)))
    return f"{percent} %"


def ranking_line(name, share_a, part_level_dba, level_dba, frequency_hz=None) -> str:
    """One ranking line, the share with the level it is monotone with and the level alone named:
    'upper_1: 24 % of the total = 90.7 dB(A) (alone 90.2 dB(A)) at 67 Hz'; a source that
    rounds to 0 % or cancels sound has no part level: 'lower_1: 0 % of the total (alone 57.8
    dB(A))', 'x: -3 % of the total (cancels) (alone 80.1 dB(A))'."""
    def level(value):
        return f"{value:.1f} dB(A)" if value is not None and np.isfinite(value) else "- dB(A)"
    percent = round(100 * share_a) if share_a is not None and np.isfinite(share_a) else 0
    part = f" = {level(part_level_dba)}" if percent > 0 and part_level_dba is not None \
        and np.isfinite(part_level_dba) else ""
    cancels = " (cancels)" if percent < 0 else ""
    at = "" if frequency_hz is None else f" at {frequency_hz:.4g} Hz"
    return (f"{name}: {share_text(share_a)} of the total{part}{cancels} (alone "
            f"{level(level_dba)}){at}")


def ranking_lines(contributions: ErpContributions, frequency_hz: float, count: int | None = None,
                  skip=()) -> list[str]:
    """:func:`ranking_line` per source, by decreasing A-weighted share (the first ``count``;
    sources named in ``skip`` left out)."""
    lines = []
    for s in contributions.order():
        name = contributions.names[s]
        if name in skip:
            continue
        lines.append(ranking_line(name, contributions.share_a[s], contributions.part_level_dba[s],
                                  contributions.partial_level_dba[s], frequency_hz))
    return lines if count is None else lines[:count]
