r"""Cabin background noise spectra: third-octave levels read from CSV files.

File format (``sarfe/erp/data/backgrounds/*.csv``): lines starting with ``#`` are the header
(the spectrum's source and construction, kept as ``source``); an optional column-name line
``band_hz,level_db``; then one band per line, ``centre frequency [Hz], level [dB re 20 µPa]``,
comma- or whitespace-separated. A centre must be an IEC 61260-1 third-octave centre (nominal or
exact, within 2 %); each band at most once. Bands of the 25 Hz … 12.5 kHz grid of ISO 532-1 that
the file does not list carry no background (level −inf); bands outside it are kept in the
spectrum but play no part in the audibility assessment.

The shipped spectra are constructed, not measured (no measured interior third-octave spectrum was
at hand): each is the Room-Criterion "neutral" shape of ANSI/ASA S12.2, a straight line of
−5 dB per octave, over 25 Hz … 12.5 kHz, shifted so that its A-weighted total equals a published
overall level (:func:`neutral_spectrum_db`; each file's header names the level and its source).
Real interior spectra fall faster above ~1 kHz than −5 dB/octave, so these spectra rather
over-state high-frequency masking: treat a "masked" verdict above 2 kHz with care.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarfe.erp.bands import band_frequencies
from sarfe.erp.loudness import BAND_CENTRES_HZ, BAND_NUMBERS
from sarfe.erp.weighting import a_weighted_total_db

__all__ = ["BACKGROUNDS_DIR", "BackgroundFileError", "BackgroundSpectrum", "background_names",
           "load_background", "neutral_spectrum_db"]

BACKGROUNDS_DIR = Path(__file__).resolve().parent / "data" / "backgrounds"


class BackgroundFileError(ValueError):
    """A background file that cannot be read; the message is one line naming file and line."""


@dataclass(frozen=True)
class BackgroundSpectrum:
    """Third-octave band levels of a background noise."""

    name: str                 # file stem
    band: np.ndarray          # (n,) IEC 61260-1 band numbers (f_m = 1000·10^(n/10) Hz)
    band_hz: np.ndarray       # (n,) centre frequencies as written in the file [Hz]
    level_db: np.ndarray      # (n,) band levels [dB re 20 µPa]
    source: str               # the file's '#' header

    def iso_band_levels_db(self) -> np.ndarray:
        """(28,) levels on the ISO 532-1 bands 25 Hz … 12.5 kHz; −inf where the file has none."""
        levels = np.full(BAND_NUMBERS.shape, -np.inf)
        on_grid = (self.band >= BAND_NUMBERS[0]) & (self.band <= BAND_NUMBERS[-1])
        levels[self.band[on_grid] - BAND_NUMBERS[0]] = self.level_db[on_grid]
        return levels

    def total_dba(self) -> float:
        """A-weighted total [dB(A)], each band weighted at its exact centre."""
        return float(a_weighted_total_db(self.level_db, band_frequencies(self.band)[0]))


def neutral_spectrum_db(total_dba: float, slope_db_per_octave: float = -5.0) -> np.ndarray:
    """(28,) band levels on BAND_CENTRES_HZ falling by ``slope_db_per_octave`` (the RC neutral
    shape for −5), L_n = L_1k + slope · log₂(f_n / 1 kHz), with L_1k set so that the A-weighted
    total is ``total_dba`` [dB(A)]. Used to build the shipped background files."""
    centres = band_frequencies(BAND_NUMBERS)[0]
    shape = slope_db_per_octave * np.log2(centres / 1000.0)
    return shape + (total_dba - float(a_weighted_total_db(shape, centres)))


def background_names() -> list:
    """Names (file stems) of the shipped background spectra."""
    return sorted(p.stem for p in BACKGROUNDS_DIR.glob("*.csv"))


def _band_of(frequency_hz: float):
    """IEC 61260-1 band number whose nominal or exact centre is within 2 % of f, else None."""
    n = int(np.round(10.0 * np.log10(frequency_hz / 1000.0)))
    exact = 1000.0 * 10.0 ** (n / 10.0)
    nominal = BAND_CENTRES_HZ[n - BAND_NUMBERS[0]] if BAND_NUMBERS[0] <= n <= BAND_NUMBERS[-1] \
        else exact
    if min(abs(frequency_hz / exact - 1.0), abs(frequency_hz / nominal - 1.0)) <= 0.02:
        return n
    return None


def load_background(name_or_path) -> BackgroundSpectrum:
    """Read a background CSV (module docstring): a shipped name (:func:`background_names`) or a
    path. Raises :class:`BackgroundFileError` with one line "<file>:<line>: <problem>"."""
    path = Path(name_or_path)
    if not path.suffix and not path.exists():
        shipped = BACKGROUNDS_DIR / f"{path.name}.csv"
        if not shipped.exists():
            raise BackgroundFileError(f"{name_or_path}: no such background file or shipped name "
                                      f"(shipped: {', '.join(background_names())})")
        path = shipped
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as error:
        raise BackgroundFileError(f"{path}: cannot read: {error}") from None
    header, bands, centres, levels = [], [], [], []
    for number, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            header.append(line[1:].strip())
            continue
        fields = line.replace(",", " ").split()
        if not bands and [f.lower() for f in fields] == ["band_hz", "level_db"]:
            continue
        where = f"{path}:{number}"
        if len(fields) != 2:
            raise BackgroundFileError(f"{where}: expected 'band_hz, level_db', got {raw.strip()!r}")
        try:
            frequency, level = float(fields[0]), float(fields[1])
        except ValueError:
            raise BackgroundFileError(f"{where}: not two numbers: {raw.strip()!r}") from None
        if not (np.isfinite(frequency) and frequency > 0):
            raise BackgroundFileError(f"{where}: band centre {fields[0]} Hz must be > 0")
        if not np.isfinite(level):
            raise BackgroundFileError(f"{where}: level {fields[1]} dB must be finite")
        band = _band_of(frequency)
        if band is None:
            raise BackgroundFileError(f"{where}: {frequency:g} Hz is not a third-octave band "
                                      "centre")
        if band in bands:
            raise BackgroundFileError(f"{where}: band {frequency:g} Hz is listed twice")
        bands.append(band)
        centres.append(frequency)
        levels.append(level)
    if not bands:
        raise BackgroundFileError(f"{path}: no band levels found")
    order = np.argsort(bands)
    return BackgroundSpectrum(name=path.stem, band=np.array(bands)[order],
                              band_hz=np.array(centres)[order], level_db=np.array(levels)[order],
                              source="\n".join(header))
