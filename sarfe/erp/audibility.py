r"""Will the occupant hear it? Predicted harmonic SPL against the hearing threshold and a cabin
background, per third-octave band (the 28 bands 25 Hz … 12.5 kHz of ISO 532-1).

Input: harmonic frequencies f_k [Hz] and SPL L_k [dB re 20 µPa] at the occupant (from
:mod:`sarfe.erp.cabin`), and a background spectrum B_n [dB] (:mod:`sarfe.erp.backgrounds`).

1. Prediction band levels L_n = 10 lg Σ_{f_k ∈ band n} 10^(L_k/10) (ideal IEC 61260-1 bands:
   each harmonic's power in its own band, exactly).
2. Threshold in quiet T_q,n: ISO 226:2003 table 1 (free-field pure-tone threshold T_f, 18–25
   year-old otologically normal listeners; = ISO 389-7) at the band centre.
3. Masked threshold of a tone by the background (Zwicker & Fastl, *Psychoacoustics*, 3rd ed.,
   ch. 4 and 6.2): a tone is just masked when its level equals the background's level in the
   critical band around it plus the masking index a_v,

       T_m,n = L_CB,n + a_v(f_n),  a_v(f) = −2 − 2.05 atan(f/4 kHz) − 0.75 atan((f/1.6 kHz)²) dB,

   L_CB,n = 10 lg ∫ b(f) df over [f_n − Δf_G/2, f_n + Δf_G/2], b(f) the background's power
   density (band power spread evenly over its band), with the critical bandwidth
   Δf_G = 25 + 75 (1 + 1.4 (f/kHz)²)^0.69 Hz (Zwicker & Terhardt 1980). This reproduces the
   classic datum that tones in white noise of density level l are just masked ≈ 17 dB above l
   below 500 Hz, rising ≈ 10 dB per decade above (tests/erp/test_audibility.py). Masking spread
   from bands outside the critical band (upward spread of strong low-frequency road noise) is
   NOT modelled, so the margin errs on the audible side (conservative for squeak & rattle).
4. Band margin M_n = L_n − max(T_m,n, T_q,n) [dB]; ``margin_db`` = max_n M_n and
   ``audible`` = margin_db > 0: the prediction is audible when at least one band exceeds its
   threshold.
5. The industry's overall rule: the prediction counts as "above ambient" when its A-weighted level
   exceeds the background's by :data:`DBA_OVER_AMBIENT_DB` = 6 dB(A) (the 6 dB signal-to-
   background margin of ISO 3744-type measurements). It ignores spectral masking: a 3 kHz squeak
   can be plainly audible 20 dB(A) below a road-noise ambient, so the band margin is the verdict.
6. Loudness (ISO 532-1, :mod:`sarfe.erp.loudness`) of the prediction alone, of the background,
   and of both together (powers added per analyser band); the increase N(P+B) − N(B) [sone] is
   what the prediction adds to the cabin's own loudness. Loudness uses analyser band levels
   (Butterworth order-3 filters, the input ISO 532-1 expects), the margins the ideal bands.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.bands import band_frequencies
from sarfe.erp.loudness import (BAND_CENTRES_HZ, BAND_NUMBERS, line_spectrum_band_levels_db,
                                zwicker_loudness)
from sarfe.erp.weighting import a_weighted_total_db, db_sum

__all__ = ["DBA_OVER_AMBIENT_DB", "THRESHOLD_IN_QUIET_DB", "Audibility", "assess_audibility",
           "critical_bandwidth_hz", "masked_threshold_db", "masking_index_db"]

DBA_OVER_AMBIENT_DB = 6.0

# ISO 226:2003 table 1, T_f [dB] at the nominal centres 25 Hz … 12.5 kHz (BAND_CENTRES_HZ)
THRESHOLD_IN_QUIET_DB = np.array([68.7, 59.5, 51.1, 44.0, 37.5, 31.5, 26.5, 22.1, 17.9, 14.4,
                                  11.4, 8.6, 6.2, 4.4, 3.0, 2.2, 2.4, 3.5, 1.7, -1.3, -4.2, -6.0,
                                  -5.4, -1.5, 6.0, 12.6, 13.9, 12.3])

_CENTRE_HZ, _LOWER_HZ, _UPPER_HZ = band_frequencies(BAND_NUMBERS)   # exact mid-band and edges


def critical_bandwidth_hz(frequency_hz) -> np.ndarray:
    """Δf_G = 25 + 75 (1 + 1.4 (f/kHz)²)^0.69 [Hz] (Zwicker & Terhardt 1980); any shape."""
    f_khz = np.asarray(frequency_hz, dtype=float) / 1000.0
    return 25.0 + 75.0 * (1.0 + 1.4 * f_khz ** 2) ** 0.69


def masking_index_db(frequency_hz) -> np.ndarray:
    """a_v(f) = −2 − 2.05 atan(f/4 kHz) − 0.75 atan((f/1.6 kHz)²) [dB]: level of a just-masked
    tone relative to the masking noise's critical-band level (Zwicker & Fastl; the same threshold
    index as ITU-R BS.1387). −2.1 dB at 200 Hz, −2.8 dB at 1 kHz, −4.7 dB at 4 kHz."""
    f = np.asarray(frequency_hz, dtype=float)
    return -2.0 - 2.05 * np.arctan(f / 4000.0) - 0.75 * np.arctan((f / 1600.0) ** 2)


def masked_threshold_db(background_db) -> np.ndarray:
    """T_m,n = L_CB,n + a_v(f_n) [dB] of the 28 bands (module docstring, step 3).

    background_db (28,) band levels [dB] on BAND_CENTRES_HZ (−inf: no background there).
    The critical band [f_n − Δf_G/2, f_n + Δf_G/2] collects from each background band the share
    of its power that falls inside it (power density flat within a band); −inf if none.
    """
    B = np.asarray(background_db, dtype=float)
    if B.shape != BAND_CENTRES_HZ.shape:
        raise ValueError(f"background_db must have shape (28,), not {B.shape}")
    half = critical_bandwidth_hz(_CENTRE_HZ) / 2.0
    lo = np.maximum(_CENTRE_HZ - half, 0.0)[:, None]          # (n, 1) critical band of band n
    hi = (_CENTRE_HZ + half)[:, None]
    overlap = np.clip(np.minimum(hi, _UPPER_HZ) - np.maximum(lo, _LOWER_HZ), 0.0, None)  # (n, m)
    density = 10.0 ** (B / 10.0) / (_UPPER_HZ - _LOWER_HZ)    # (m,) [p_ref²/Hz]
    with np.errstate(divide="ignore"):
        critical_band_db = 10.0 * np.log10(overlap @ density)
    return critical_band_db + masking_index_db(_CENTRE_HZ)


@dataclass(frozen=True)
class Audibility:
    """Audibility of one predicted harmonic spectrum in one background (module docstring).
    Per-band arrays are (28,) on ``band_hz`` = BAND_CENTRES_HZ; levels in dB re 20 µPa."""

    band_hz: np.ndarray               # (28,) nominal band centres [Hz]
    spl_db: np.ndarray                # (28,) prediction band levels L_n (ideal bands)
    background_db: np.ndarray         # (28,) background B_n
    threshold_in_quiet_db: np.ndarray  # (28,) T_q,n
    masked_threshold_db: np.ndarray   # (28,) T_m,n
    margin_band_db: np.ndarray        # (28,) M_n = L_n − max(T_m,n, T_q,n); −inf: empty band
    spl_dba: float                    # prediction, A-weighted over all harmonics [dB(A)]
    background_dba: float             # background, A-weighted [dB(A)]
    dba_over_background_db: float     # spl_dba − background_dba [dB]
    above_ambient_dba_rule: bool      # dba_over_background_db ≥ DBA_OVER_AMBIENT_DB
    loudness_sone: float              # N of the prediction alone [sone]
    loudness_level_phon: float        # L_N of the prediction alone [phon]
    background_loudness_sone: float   # N of the background
    total_loudness_sone: float        # N of prediction + background
    loudness_increase_sone: float     # total − background
    audible: bool                     # margin_db > 0
    margin_db: float                  # max_n M_n [dB] (−inf: nothing in the bands)
    loudest_band_hz: float            # band of the largest margin (nan if none)
    harmonics_outside_bands: int      # harmonics below 22.4 Hz or above 14.1 kHz (not assessed)
    field: str                        # loudness field: "free" or "diffuse"

    def as_dict(self) -> dict:
        """JSON-ready: arrays as lists, −inf as None."""
        def clean(value):
            if isinstance(value, np.ndarray):
                return [clean(v) for v in value.tolist()]
            if isinstance(value, float) and not np.isfinite(value):
                return None
            return value
        return {name: clean(getattr(self, name)) for name in self.__dataclass_fields__}


def assess_audibility(frequencies_hz, spl_db, background_db, field: str = "diffuse"
                      ) -> Audibility:
    """Audibility of harmonics (f_k, L_k) at the occupant in a background (module docstring).

    frequencies_hz (H,) > 0 [Hz]; spl_db (H,) L_k [dB re 20 µPa] (−inf for a silent harmonic);
    background_db (28,) B_n on BAND_CENTRES_HZ (e.g. ``BackgroundSpectrum.iso_band_levels_db()``).
    field: ISO 532-1 sound field for the loudness; "diffuse" by default (the occupant hears the
    cabin's reverberant field from all directions).
    """
    f = np.asarray(frequencies_hz, dtype=float).ravel()
    L = np.asarray(spl_db, dtype=float).ravel()
    B = np.asarray(background_db, dtype=float)
    if f.shape != L.shape:
        raise ValueError(f"frequencies_hz {f.shape} and spl_db {L.shape} must match")
    if B.shape != BAND_CENTRES_HZ.shape or np.any(np.isnan(B)) or np.any(B == np.inf):
        raise ValueError("background_db must be 28 band levels (25 Hz … 12.5 kHz), no NaN/+inf")
    inside = (f >= _LOWER_HZ[0]) & (f < _UPPER_HZ[-1])
    band_spl = line_spectrum_band_levels_db(f[inside], L[inside], filter_order=None)
    masked = masked_threshold_db(B)
    threshold = np.maximum(masked, THRESHOLD_IN_QUIET_DB)
    margin = band_spl - threshold
    margin_db = float(np.max(margin))
    loudest = float(BAND_CENTRES_HZ[int(np.argmax(margin))]) if np.isfinite(margin_db) \
        else float("nan")

    analyser = line_spectrum_band_levels_db(f[inside], L[inside], filter_order=3)
    both = db_sum(np.stack([analyser, B]), axis=0)
    N = zwicker_loudness(np.stack([analyser, B, both]), field=field)
    spl_dba = float(a_weighted_total_db(L, f)) if f.size else float("-inf")
    background_dba = float(a_weighted_total_db(B, _CENTRE_HZ))
    over = spl_dba - background_dba
    return Audibility(
        band_hz=BAND_CENTRES_HZ.copy(), spl_db=band_spl, background_db=B.copy(),
        threshold_in_quiet_db=THRESHOLD_IN_QUIET_DB.copy(), masked_threshold_db=masked,
        margin_band_db=margin, spl_dba=spl_dba, background_dba=background_dba,
        dba_over_background_db=over, above_ambient_dba_rule=bool(over >= DBA_OVER_AMBIENT_DB),
        loudness_sone=float(N.loudness_sone[0]),
        loudness_level_phon=float(N.loudness_level_phon[0]),
        background_loudness_sone=float(N.loudness_sone[1]),
        total_loudness_sone=float(N.loudness_sone[2]),
        loudness_increase_sone=float(N.loudness_sone[2] - N.loudness_sone[1]),
        audible=bool(margin_db > 0.0), margin_db=margin_db, loudest_band_hz=loudest,
        harmonics_outside_bands=int(np.count_nonzero(~inside)), field=field)
