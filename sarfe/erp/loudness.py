r"""Stationary loudness (ISO 532-1:2017, Zwicker method, section 5) from third-octave levels.

Input: the 28 third-octave band levels L_i [dB re 20 µPa] with nominal centres 25 Hz … 12.5 kHz
(IEC 61260-1 bands n = −16 … 11, :data:`BAND_CENTRES_HZ`), free (frontal) or diffuse field.
Output: total loudness N [sone], loudness level L_N [phon] and the specific loudness N'(z)
[sone/Bark] on the standard's 0.1 Bark grid z = 0.1 … 24.0 Bark. The steps (ISO 532-1 A.2–A.4;
Zwicker & Fastl, *Psychoacoustics*, 8.7), with the standard's tables below:

1. Bands 25–250 Hz are reduced along the equal-loudness contours: X_i = L_i + ΔL(j, i), j the
   first level range with X_i ≤ RAP_j (table DLL, ranges RAP = 45 … 120 dB), and summed on an
   intensity basis into three low critical bands:
   L_CB,1 = 10 lg Σ_{25–80 Hz} 10^(X/10),  L_CB,2 (100–160 Hz),  L_CB,3 (200–250 Hz).
2. The 20 band levels (L_CB,1..3 and the bands 315 Hz … 12.5 kHz) become excitation levels
   L_E = L − a0 (+ ΔL_diffuse for a diffuse field), and above the threshold L_TQ the core
   loudness is
       N_c = 0.0635 · 10^(0.025 L_TQ) · [(1 − s + s·10^((L_E − ΔL_CB − L_TQ)/10))^0.25 − 1],
   s = 0.25, N_c ≥ 0 (ΔL_CB: third-octave to critical-band level); the lowest band is scaled by
   min(1, 0.4 + 0.32 N_c^0.2). A 21st band (23.6–24 Bark) has N_c = 0.
3. The specific loudness N'(z) is N_c,i flat over band i (upper edges ZUP), and where it falls
   from one band to the next it decays with the upper masking slopes USL (sone/Bark per Bark,
   depending on N' in the ranges RNS and on the band); N = ∫₀²⁴ N'(z) dz, integrated exactly on
   the piecewise-linear pattern (the standard's program rounds N to 3 or 2 decimals; we do not).
4. L_N = 40 + 10 log₂ N for N ≥ 1 sone, L_N = 40 (N + 0.0005)^0.35 for N < 1 sone.

Calibration: a 1 kHz tone at 40 dB in a free field gives N = 1 sone (40 phon).

Why not MoSQITo (1.2.1, Apache-2.0): its public stationary functions take a 48 kHz time signal
or a fine spectrum and derive the third-octave levels themselves with 3rd-order Butterworth filters
(≈ 18 dB rejection at the neighbouring band's centre), so a given third-octave spectrum can only
be fed through its private ``_main_loudness``/``_calc_slopes``. The tables here are the standard's
(ISO 532-1:2017 Annex A, identical to DIN 45631:1991); the code is our own, vectorised over
spectra for steps 1–2 and 4.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.bands import band_index

__all__ = ["BAND_CENTRES_HZ", "BAND_NUMBERS", "FIELDS", "Loudness", "band_filter_gain",
           "line_spectrum_band_levels_db", "loudness_level_phon", "zwicker_loudness"]

FIELDS = ("free", "diffuse")

# IEC 61260-1 band numbers n (f_m = 1000·10^(n/10) Hz) and nominal centres of the 28 input bands
BAND_NUMBERS = np.arange(-16, 12)
BAND_CENTRES_HZ = np.array([25, 31.5, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500,
                            630, 800, 1000, 1250, 1600, 2000, 2500, 3150, 4000, 5000, 6300, 8000,
                            10000, 12500], dtype=float)

# ---- ISO 532-1:2017 Annex A tables ------------------------------------------------------------
# upper limits RAP [dB] of the level ranges for the low-frequency correction (table A.1)
_RANGE_LIMITS_DB = np.array([45.0, 55.0, 65.0, 71.0, 80.0, 90.0, 100.0, 120.0])
# reductions DLL [dB] of the bands 25 … 250 Hz (columns) in each level range (rows) (table A.2)
_LOW_BAND_REDUCTION_DB = np.array([
    [-32, -24, -16, -10, -5, 0, -7, -3, 0, -2, 0],
    [-29, -22, -15, -10, -4, 0, -7, -2, 0, -2, 0],
    [-27, -19, -14, -9, -4, 0, -6, -2, 0, -2, 0],
    [-25, -17, -12, -9, -3, 0, -5, -2, 0, -2, 0],
    [-23, -16, -11, -7, -3, 0, -4, -1, 0, -1, 0],
    [-20, -14, -10, -6, -3, 0, -4, -1, 0, -1, 0],
    [-18, -12, -9, -6, -2, 0, -3, -1, 0, -1, 0],
    [-15, -10, -8, -4, -2, 0, -3, -1, 0, -1, 0]], dtype=float)
# critical-band level LTQ [dB] at the threshold in quiet, 20 bands (table A.3)
_THRESHOLD_DB = np.array([30, 18, 12, 8, 7, 6, 5, 4, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3],
                         dtype=float)
# transmission through the outer ear a0 [dB] (table A.4)
_EAR_TRANSMISSION_DB = np.array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -0.5, -1.6, -3.2, -5.4, -5.6, -4.0,
                                 -1.5, 2.0, 5.0, 12.0])
# diffuse minus free field level difference DDF [dB] (table A.5)
_DIFFUSE_DB = np.array([0, 0, 0.5, 0.9, 1.2, 1.6, 2.3, 2.8, 3.0, 2.0, 0, -1.4, -2.0, -1.9, -1.0,
                        0.5, 3.0, 4.0, 4.3, 4.0])
# third-octave to critical-band level adaptation DCB [dB] (table A.6)
_CRITICAL_BAND_DB = np.array([-0.25, -0.6, -0.8, -0.8, -0.5, 0, 0.5, 1.1, 1.5, 1.7, 1.8, 1.8,
                              1.7, 1.6, 1.4, 1.2, 0.8, 0.5, 0, -0.5])
# upper edges ZUP [Bark] of the 21 approximated critical bands (table A.7)
_BAND_UPPER_BARK = np.array([0.9, 1.8, 2.8, 3.5, 4.4, 5.4, 6.6, 7.9, 9.2, 10.6, 12.3, 13.8,
                             15.2, 16.7, 18.1, 19.3, 20.6, 21.8, 22.7, 23.6, 24.0])
# specific-loudness ranges RNS [sone/Bark] for the upper slopes (table A.8)
_SLOPE_RANGES = np.array([21.5, 18.0, 15.1, 11.5, 9.0, 6.1, 4.4, 3.1, 2.13, 1.36, 0.82, 0.42,
                          0.30, 0.22, 0.15, 0.10, 0.035, 0.0])
# upper slopes USL [sone/Bark per Bark]: rows = RNS ranges, columns = band group (table A.8)
_UPPER_SLOPES = np.array([
    [13.0, 8.2, 6.3, 5.5, 5.5, 5.5, 5.5, 5.5],
    [9.0, 7.5, 6.0, 5.1, 4.5, 4.5, 4.5, 4.5],
    [7.8, 6.7, 5.6, 4.9, 4.4, 3.9, 3.9, 3.9],
    [6.2, 5.4, 4.6, 4.0, 3.5, 3.2, 3.2, 3.2],
    [4.5, 3.8, 3.6, 3.2, 2.9, 2.7, 2.7, 2.7],
    [3.7, 3.0, 2.8, 2.35, 2.2, 2.2, 2.2, 2.2],
    [2.9, 2.3, 2.1, 1.9, 1.8, 1.7, 1.7, 1.7],
    [2.4, 1.7, 1.5, 1.35, 1.3, 1.3, 1.3, 1.3],
    [1.95, 1.45, 1.3, 1.15, 1.1, 1.1, 1.1, 1.1],
    [1.5, 1.2, 0.94, 0.86, 0.82, 0.82, 0.82, 0.82],
    [0.72, 0.67, 0.64, 0.63, 0.62, 0.62, 0.62, 0.62],
    [0.59, 0.53, 0.51, 0.50, 0.42, 0.42, 0.42, 0.42],
    [0.40, 0.33, 0.26, 0.24, 0.24, 0.22, 0.22, 0.22],
    [0.27, 0.21, 0.20, 0.18, 0.17, 0.17, 0.17, 0.17],
    [0.16, 0.15, 0.14, 0.12, 0.11, 0.11, 0.11, 0.11],
    [0.12, 0.11, 0.10, 0.08, 0.08, 0.08, 0.08, 0.08],
    [0.09, 0.08, 0.07, 0.06, 0.06, 0.06, 0.06, 0.05],
    [0.06, 0.05, 0.03, 0.02, 0.02, 0.02, 0.02, 0.02]])
_MAX_LOW_BAND_DB = 120.0        # table A.2 ends at 120 dB: the method is not defined above
_SPECIFIC_GRID_BARK = 0.1 * np.arange(1, 241)   # z = 0.1 … 24.0 Bark (the standard's output grid)


@dataclass(frozen=True)
class Loudness:
    """ISO 532-1 stationary loudness of m spectra (m = 1 for one spectrum: scalars squeezed)."""

    loudness_sone: np.ndarray        # (m,) or () N [sone]
    loudness_level_phon: np.ndarray  # (m,) or () L_N [phon]
    specific_sone_per_bark: np.ndarray  # (m, 240) or (240,) N'(z) at z = 0.1 … 24.0 Bark
    core_sone_per_bark: np.ndarray   # (m, 21) or (21,) core loudness N_c of the 21 bands
    bark: np.ndarray                 # (240,) z grid [Bark]
    field: str                       # "free" or "diffuse"


def loudness_level_phon(loudness_sone) -> np.ndarray:
    """L_N [phon] of N [sone] (ISO 532-1, 5.2): 40 + 10 log₂ N for N ≥ 1 sone,
    40 (N + 0.0005)^0.35 below; any shape."""
    N = np.asarray(loudness_sone, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(N >= 1.0, 40.0 + 10.0 * np.log2(np.maximum(N, 1.0)),
                        40.0 * (np.maximum(N, 0.0) + 0.0005) ** 0.35)


def _core_loudness(levels_db: np.ndarray, field: str) -> np.ndarray:
    """Steps 1–2 (module docstring): core loudness N_c (m, 21) of levels (m, 28) [dB]."""
    low = levels_db[:, :11]                                          # 25 … 250 Hz
    limit = _RANGE_LIMITS_DB[:, None] - _LOW_BAND_REDUCTION_DB       # (8, 11): X ≤ RAP ⇔ L ≤ this
    within = low[:, None, :] <= limit[None]                          # (m, 8, 11)
    rng = np.where(within.any(axis=1), within.argmax(axis=1), limit.shape[0] - 1)
    reduced = low + _LOW_BAND_REDUCTION_DB[rng, np.arange(11)]
    intensity = 10.0 ** (reduced / 10.0)
    grouped = np.stack([intensity[:, :6].sum(axis=1), intensity[:, 6:9].sum(axis=1),
                        intensity[:, 9:11].sum(axis=1)], axis=1)
    with np.errstate(divide="ignore"):
        low_cb = 10.0 * np.log10(grouped)
    excitation = np.concatenate([low_cb, levels_db[:, 11:]], axis=1) - _EAR_TRANSMISSION_DB
    if field == "diffuse":
        excitation = excitation + _DIFFUSE_DB
    active = excitation > _THRESHOLD_DB
    over = np.where(active, excitation - _CRITICAL_BAND_DB - _THRESHOLD_DB, 0.0)
    s = 0.25
    core = (0.0635 * 10.0 ** (0.025 * _THRESHOLD_DB)
            * ((1.0 - s + s * 10.0 ** (over / 10.0)) ** 0.25 - 1.0))
    core = np.where(active, np.maximum(core, 0.0), 0.0)
    core[:, 0] *= np.minimum(1.0, 0.4 + 0.32 * core[:, 0] ** 0.2)
    return np.concatenate([core, np.zeros((core.shape[0], 1))], axis=1)


def _slope_range(n: float) -> int:
    """Index j of the RNS range holding specific loudness n > 0: RNS[j] < n ≤ RNS[j−1]."""
    return int(np.count_nonzero(_SLOPE_RANGES >= n))


def _specific_pattern(core: np.ndarray):
    """Step 3 for one spectrum: total N [sone] and the pattern's linear pieces
    (z_start, z_end, n_start, slope) [Bark, Bark, sone/Bark, sone/Bark²] over 0 … 24 Bark.

    A band whose core loudness lies below the pattern arriving from the band before it receives
    the upper slope of that pattern (falling by USL until it meets N_c of the band, or the band's
    upper edge); otherwise the pattern steps to N_c and stays flat to the band's upper edge.
    """
    total, z1, n1 = 0.0, 0.0, 0.0
    pieces = []
    for i, z_upper in enumerate(_BAND_UPPER_BARK):
        target = core[i]
        group = min(i - 1, 7)            # only used when n1 > target, impossible for i = 0
        while z1 < z_upper:
            if n1 > target:
                j = _slope_range(n1)
                slope = _UPPER_SLOPES[j, group]
                n2 = max(_SLOPE_RANGES[j], target)
                z2 = z1 + (n1 - n2) / slope
                if z2 > z_upper:
                    z2 = z_upper
                    n2 = n1 - (z2 - z1) * slope
                total += (z2 - z1) * (n1 + n2) / 2.0
                pieces.append((z1, z2, n1, -slope))
            else:
                z2, n2 = z_upper, target
                total += n2 * (z2 - z1)
                pieces.append((z1, z2, n2, 0.0))
            z1, n1 = z2, n2
    return total, np.array(pieces)


def _sample_pattern(pieces: np.ndarray, z: np.ndarray) -> np.ndarray:
    """N'(z) of the piecewise-linear pattern; a grid point on a piece's end belongs to it."""
    start, end, value, slope = pieces.T
    piece = np.minimum(np.searchsorted(end + 1e-9, z, side="left"), len(end) - 1)
    return np.maximum(value[piece] + slope[piece] * (z - start[piece]), 0.0)


def zwicker_loudness(third_octave_db, field: str = "free") -> Loudness:
    """ISO 532-1 stationary loudness of third-octave spectra (module docstring).

    third_octave_db : (28,) or (m, 28) levels L_i [dB re 20 µPa] of the bands 25 Hz … 12.5 kHz
        (:data:`BAND_CENTRES_HZ`); −inf for an empty band. field : "free" (frontal) or "diffuse".
    Raises ValueError for a wrong shape, NaN or +inf levels, an unknown field, or a band
    25–250 Hz above 120 dB (outside the standard's tables).
    """
    if field not in FIELDS:
        raise ValueError(f"field must be one of {FIELDS}, not {field!r}")
    levels = np.asarray(third_octave_db, dtype=float)
    single = levels.ndim == 1
    levels = np.atleast_2d(levels)
    if levels.ndim != 2 or levels.shape[1] != BAND_CENTRES_HZ.size:
        raise ValueError(f"third_octave_db must have shape (28,) or (m, 28), not "
                         f"{np.shape(third_octave_db)} (bands 25 Hz … 12.5 kHz)")
    if np.any(np.isnan(levels)) or np.any(levels == np.inf):
        raise ValueError("third_octave_db must not be NaN or +inf (−inf marks an empty band)")
    if np.any(levels[:, :11] > _MAX_LOW_BAND_DB):
        raise ValueError("a band 25–250 Hz exceeds 120 dB: ISO 532-1 is not defined there")
    core = _core_loudness(levels, field)
    totals, specific = [], []
    for row in core:                     # the slope pattern is sequential in z, per spectrum
        total, pieces = _specific_pattern(row)
        totals.append(total)
        specific.append(_sample_pattern(pieces, _SPECIFIC_GRID_BARK))
    N = np.maximum(np.array(totals), 0.0)
    specific = np.array(specific)
    if single:
        N, specific, core = N[0], specific[0], core[0]
    return Loudness(loudness_sone=N, loudness_level_phon=loudness_level_phon(N),
                    specific_sone_per_bark=specific, core_sone_per_bark=core,
                    bark=_SPECIFIC_GRID_BARK.copy(), field=field)


def band_filter_gain(frequency_hz, band_numbers=BAND_NUMBERS, order: int = 3) -> np.ndarray:
    r"""Power gain |H_n(f)|² of third-octave analyser filters: Butterworth band-passes of the
    given prototype order around each exact centre f_m,n = 1000·10^(n/10) Hz,

        |H_n(f)|² = 1 / (1 + Ω^(2·order)),  Ω = (f/f_m − f_m/f) / (G^(1/6) − G^(−1/6)),

    with G = 10^0.3, so the −3 dB points are the IEC 61260-1 band edges. Order 3 (a 6th-order
    band-pass, a common IEC 61260 class-1 realisation) stands in for the analyser behind the
    standard's reference values: with it the pure-tone test signals of ISO 532-1 Annex B.3 are
    reproduced within 2.3 % (tests/erp/test_loudness.py). frequency_hz (H,) [Hz] > 0 →
    (n_bands, H).
    """
    f = np.asarray(frequency_hz, dtype=float)[None, :]
    centre = 1000.0 * 10.0 ** (np.asarray(band_numbers, dtype=float)[:, None] / 10.0)
    half = 10.0 ** (1.0 / 20.0)
    omega = (f / centre - centre / f) / (half - 1.0 / half)
    return 1.0 / (1.0 + omega ** (2 * order))


def line_spectrum_band_levels_db(frequencies_hz, levels_db, filter_order: int | None = 3
                                 ) -> np.ndarray:
    r"""Third-octave levels [dB] of the 28 ISO 532-1 bands (25 Hz … 12.5 kHz) of a line spectrum.

    frequencies_hz (H,) > 0 [Hz] with levels L_k (H,) [dB re 20 µPa] (−inf for a silent line):

        L_n = 10 lg Σ_k 10^(L_k/10) · g_n(f_k),

    with g_n = |H_n|² of :func:`band_filter_gain` (``filter_order``: as an analyser measures it,
    the input ISO 532-1 expects) or, for ``filter_order=None``, the ideal band g_n = 1 for
    f_k ∈ [f_lo,n, f_hi,n) and 0 elsewhere (each line's power in its own band, exactly).
    Returns (28,), −inf for a band without power.
    """
    f = np.asarray(frequencies_hz, dtype=float).ravel()
    L = np.asarray(levels_db, dtype=float).ravel()
    if f.shape != L.shape:
        raise ValueError(f"frequencies_hz {f.shape} and levels_db {L.shape} must match")
    if np.any(~(f > 0)) or np.any(np.isnan(L)):
        raise ValueError("frequencies_hz must be > 0 and levels_db not NaN")
    if filter_order is None:
        gain = (band_index(f)[None, :] == BAND_NUMBERS[:, None]).astype(float)
    else:
        gain = band_filter_gain(f, BAND_NUMBERS, filter_order)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(gain @ 10.0 ** (L / 10.0))
