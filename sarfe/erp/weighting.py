r"""A-weighting (IEC 61672-1:2013, Annex E) and decibel arithmetic.

The A-weighting of a frequency f [Hz] is

    A(f) = 20 log10( f4² f⁴ / ( (f² + f1²) √((f² + f2²)(f² + f3²)) (f² + f4²) ) ) − A1000,

with the pole frequencies of IEC 61672-1 (E.2–E.6)

    f1 = 20.598997 Hz, f2 = 107.65265 Hz, f3 = 737.86223 Hz, f4 = 12194.217 Hz,

and the normalisation A1000 = −2.000 dB, so that A(1 kHz) = 0 dB. A(0) = −∞.

Levels add on a power basis: L_Σ = 10 log10 Σ_k 10^(L_k/10); an A-weighted total of harmonic
levels L_k at frequencies f_k is L_A = 10 log10 Σ_k 10^((L_k + A(f_k))/10).
"""
from __future__ import annotations

import numpy as np

__all__ = ["a_weighting_db", "db_sum", "a_weighted_levels_db", "a_weighted_total_db"]

F1_HZ = 20.598997
F2_HZ = 107.65265
F3_HZ = 737.86223
F4_HZ = 12194.217
A1000_DB = -2.000


def a_weighting_db(frequency_hz) -> np.ndarray:
    """A-weighting A(f) [dB] of IEC 61672-1 (see module docstring); any shape, f ≥ 0 [Hz].

    Returns an array of the input's shape (a 0-d array for a scalar); A(0) = −inf.
    """
    f = np.asarray(frequency_hz, dtype=float)
    if np.any(f < 0) or np.any(np.isnan(f)):
        raise ValueError("frequency_hz must be >= 0 and not NaN")
    f2 = f * f
    with np.errstate(divide="ignore"):
        gain = (F4_HZ**2 * f2 * f2) / (
            (f2 + F1_HZ**2) * np.sqrt((f2 + F2_HZ**2) * (f2 + F3_HZ**2)) * (f2 + F4_HZ**2)
        )
        return 20.0 * np.log10(gain) - A1000_DB


def db_sum(levels_db, axis=-1) -> np.ndarray:
    """Power sum of levels [dB]: 10 log10 Σ 10^(L/10) along ``axis``; −inf entries add nothing.

    All −inf (or an empty axis) gives −inf.
    """
    levels = np.asarray(levels_db, dtype=float)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.sum(10.0 ** (levels / 10.0), axis=axis))


def a_weighted_levels_db(levels_db, frequency_hz) -> np.ndarray:
    """L_k + A(f_k) [dB(A)] for levels ``levels_db`` at frequencies ``frequency_hz`` (broadcast)."""
    return np.asarray(levels_db, dtype=float) + a_weighting_db(frequency_hz)


def a_weighted_total_db(levels_db, frequency_hz, axis=-1) -> np.ndarray:
    """A-weighted total 10 log10 Σ_k 10^((L_k + A(f_k))/10) [dB(A)] along ``axis``."""
    return db_sum(a_weighted_levels_db(levels_db, frequency_hz), axis=axis)
