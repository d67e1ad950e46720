r"""Third-octave band levels of a harmonic ERP spectrum (IEC 61260-1, base-10 bands).

Band n has the exact mid-band frequency and edges (IEC 61260-1:2014, 5.2 and 5.4, G = 10^(3/10),
fractional-octave designator b = 3, so G^(1/2b) = 10^(1/20))

    f_m,n = 1000 · 10^(n/10) Hz,     f_lo,n = f_m,n · 10^(−1/20),     f_hi,n = f_m,n · 10^(+1/20),

n = −20 … +13 giving 10 Hz … 20 kHz (nominal labels 10, 12.5, 16, 20, 25, 31.5, 40 …). Adjacent
bands share an edge; a frequency on an edge belongs to the upper band (half-open [f_lo, f_hi)).

A periodic response radiates only at its harmonics f_k = k ω/2π, so the band power is the sum of
the harmonic powers that fall into the band, and its A-weighted counterpart weights each harmonic at
its own frequency (not at the band centre):

    P_n   = Σ_{k: f_k ∈ band n} P_k                               [W]
    P_A,n = Σ_{k: f_k ∈ band n} P_k · 10^(A(f_k)/10)              [W, A-weighted]
    L_n   = 10 log10(P_n / P_ref),  L_A,n = 10 log10(P_A,n / P_ref)   [dB re 1 pW], [dB(A)]

so Σ_n P_n = Σ_k P_k = P (the total) and Σ_n P_A,n = the A-weighted total, exactly: the bands run
from the lowest harmonic's band to the highest one's (outside 10 Hz–20 kHz too, exact labels).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.erp import REFERENCE_POWER, power_level_db
from sarfe.erp.weighting import a_weighting_db

__all__ = ["ThirdOctaveSpectrum", "band_index", "band_frequencies", "nominal_frequency",
           "third_octave_levels"]

# IEC 61260-1 nominal mid-band frequencies (Annex E), for labels; n = −20 … 13
_NOMINAL = (10, 12.5, 16, 20, 25, 31.5, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500,
            630, 800, 1000, 1250, 1600, 2000, 2500, 3150, 4000, 5000, 6300, 8000, 10000, 12500,
            16000, 20000)
_FIRST_NOMINAL = -20


def band_index(frequency_hz) -> np.ndarray:
    """Band number n (int) with f ∈ [f_m,n 10^(−1/20), f_m,n 10^(1/20)); f > 0 [Hz], any shape."""
    f = np.asarray(frequency_hz, dtype=float)
    if np.any(~(f > 0)):
        raise ValueError("frequency_hz must be > 0")
    # f ≥ f_lo,n  ⇔  10 log10(f/1000) ≥ n − 1/2; a tiny relative slack keeps exact edges upward
    return np.floor(10.0 * np.log10(f / 1000.0) + 0.5 + 1e-12).astype(int)


def band_frequencies(n):
    """(mid, lower edge, upper edge) [Hz] of band numbers n (exact base-10 values)."""
    n = np.asarray(n, dtype=float)
    mid = 1000.0 * 10.0 ** (n / 10.0)
    return mid, mid * 10.0 ** (-1.0 / 20.0), mid * 10.0 ** (1.0 / 20.0)


def nominal_frequency(n) -> float:
    """The nominal (label) mid-band frequency of band n [Hz]; the exact one outside 10 Hz–20 kHz."""
    i = int(n) - _FIRST_NOMINAL
    if 0 <= i < len(_NOMINAL):
        return float(_NOMINAL[i])
    return float(f"{1000.0 * 10.0 ** (int(n) / 10.0):.3g}")


@dataclass(frozen=True)
class ThirdOctaveSpectrum:
    """Band powers and levels of one harmonic spectrum; n_b contiguous bands from the lowest to the
    highest harmonic's band (empty bands included, with zero power and level −inf)."""

    band: np.ndarray             # (n_b,) int band numbers n
    nominal_hz: np.ndarray       # (n_b,) nominal mid-band frequencies [Hz] (labels)
    center_hz: np.ndarray        # (n_b,) exact mid-band frequencies [Hz]
    lower_hz: np.ndarray         # (n_b,) lower band edges [Hz]
    upper_hz: np.ndarray         # (n_b,) upper band edges [Hz]
    power_W: np.ndarray          # (n_b,) P_n [W]
    power_a_W: np.ndarray        # (n_b,) A-weighted P_A,n [W]
    level_db: np.ndarray         # (n_b,) L_n [dB re 1 pW]
    level_dba: np.ndarray        # (n_b,) L_A,n [dB(A) re 1 pW]

    def as_dict(self) -> dict:
        return {"band": self.band.tolist(), "nominal_hz": self.nominal_hz.tolist(),
                "center_hz": self.center_hz.tolist(), "lower_hz": self.lower_hz.tolist(),
                "upper_hz": self.upper_hz.tolist(), "power_W": self.power_W.tolist(),
                "power_a_W": self.power_a_W.tolist(), "level_db": self.level_db.tolist(),
                "level_dba": self.level_dba.tolist()}


def third_octave_levels(frequencies_hz, power_W,
                        reference_power: float = REFERENCE_POWER) -> ThirdOctaveSpectrum:
    """Third-octave band spectrum (module docstring) of harmonic powers.

    frequencies_hz : (H,) harmonic frequencies f_k > 0 [Hz]; power_W : (H,) P_k ≥ 0 [W].
    Returns a :class:`ThirdOctaveSpectrum` over the bands from min(n_k) to max(n_k).
    """
    f = np.asarray(frequencies_hz, dtype=float).ravel()
    P = np.asarray(power_W, dtype=float).ravel()
    if f.shape != P.shape:
        raise ValueError(f"frequencies_hz {f.shape} and power_W {P.shape} must match")
    if np.any(P < 0) or not np.all(np.isfinite(P)):
        raise ValueError("power_W must be finite and >= 0")
    if f.size == 0:
        empty = np.zeros(0)
        return ThirdOctaveSpectrum(np.zeros(0, dtype=int), empty, empty, empty, empty, empty,
                                   empty, empty, empty)
    n = band_index(f)
    bands = np.arange(n.min(), n.max() + 1)
    slot = n - bands[0]
    power = np.bincount(slot, weights=P, minlength=bands.size)
    power_a = np.bincount(slot, weights=P * 10.0 ** (a_weighting_db(f) / 10.0),
                          minlength=bands.size)
    mid, lower, upper = band_frequencies(bands)
    return ThirdOctaveSpectrum(
        band=bands, nominal_hz=np.array([nominal_frequency(b) for b in bands]), center_hz=mid,
        lower_hz=lower, upper_hz=upper, power_W=power, power_a_W=power_a,
        level_db=power_level_db(power, reference_power),
        level_dba=power_level_db(power_a, reference_power))
