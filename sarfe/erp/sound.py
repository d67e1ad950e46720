r"""Listen to a prediction: calibrated WAV files of the harmonic sound pressure at the occupant,
alone and mixed with a cabin background.

Harmonics (input convention). The periodic pressure at the occupant at one solved point, of
fundamental angular frequency ω [rad/s], is

    p(t) = Σ_k Re( p̂_k e^{i k ω t} ) = Σ_k |p̂_k| cos(k ω t + φ_k)                      [Pa]

with p̂_k the complex pressure amplitude (peak, not RMS) of harmonic k = 1 … H. In the HBM
Fourier convention [x0, x1c, x1s, …] (x(θ) = x0 + Σ x_kc cos kθ + x_ks sin kθ) a coefficient pair
maps to p̂_k = x_kc − i x_ks. Its RMS is |p̂_k|/√2, so the SPL is L_k = 20 lg(|p̂_k| / (√2 p_ref))
and :func:`pressure_amplitudes` builds p̂_k from (L_k, φ_k). The ERP gives power only: the caller
takes |p̂_k| from the cabin SPL (:mod:`sarfe.erp.cabin`) and φ_k from the panel: for a compact
baffled radiator the far pressure follows the normal acceleration, p(t) ∝ ẅ_n(t − r/c)
(Rayleigh), so φ_k = arg(ŵ_k) + π with ŵ_k = w_kc − i w_ks of the dominant radiating
contribution. A common delay (φ_k → φ_k − k ω τ) does not change the sound; relative phases do
(they shape the waveform of a rattle's impacts).

Background. Random-phase noise shaped to third-octave levels B_n: in the discrete spectrum of the
N-sample record every bin of band n gets the same magnitude and a uniform random phase (seeded
``numpy.random.default_rng``), so the mean-square pressure in band n is p_ref² 10^(B_n/10)
exactly (Parseval) and the record is periodic (loops without a click).

Both are faded in and out with raised-cosine ramps of ``fade_s``. Harmonics at or above the
Nyquist frequency fs/2 are left out (they cannot be represented).

Calibration. A sample value s (int16: s/32767; float32: s) is s · full_scale_pa pascal. The
value is returned (:class:`WavCalibration`) and stored in the file's LIST/INFO comment chunk
(``ICMT``: "sarfe full_scale_pa=<Pa> p_ref_pa=2e-05 …"), so :func:`read_wav` returns the
pressure in Pa whatever the file is named. Files are written with numpy and ``struct`` (RIFF
WAVE, mono, 16-bit PCM or 32-bit IEEE float); ``wave`` and ``scipy.io.wavfile`` read them.
"""
from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarfe.erp.bands import band_index
from sarfe.erp.cabin import REFERENCE_PRESSURE
from sarfe.erp.loudness import BAND_NUMBERS

__all__ = ["SAMPLE_RATE_HZ", "WavCalibration", "apply_fade", "background_noise",
           "pressure_amplitudes", "read_wav", "synthesize_harmonics", "write_sound_files",
           "write_wav"]

SAMPLE_RATE_HZ = 44100
_FORMATS = {"int16": (1, 16), "float32": (3, 32)}     # WAVE format tag, bits per sample
_INT16_FULL = 32767.0
_CHUNK_SAMPLES = 8192


@dataclass(frozen=True)
class WavCalibration:
    """How a WAV file's samples map to pressure: p = s / s_full · full_scale_pa."""

    full_scale_pa: float     # pressure [Pa] at digital full scale
    sample_rate_hz: int
    sample_format: str       # "int16" or "float32"
    peak_dbfs: float         # the signal's peak relative to full scale [dB]

    @property
    def full_scale_spl_db(self) -> float:
        """SPL [dB re 20 µPa] of a full-scale sine (RMS = full_scale_pa/√2)."""
        return float(20.0 * np.log10(self.full_scale_pa / (np.sqrt(2.0) * REFERENCE_PRESSURE)))


def pressure_amplitudes(spl_db, phase_rad=0.0) -> np.ndarray:
    """p̂_k = √2 p_ref 10^(L_k/20) e^{i φ_k} [Pa] (complex peak amplitudes) from SPL L_k
    [dB re 20 µPa] and phase φ_k [rad] (broadcast); −inf dB gives 0."""
    L = np.asarray(spl_db, dtype=float)
    return np.sqrt(2.0) * REFERENCE_PRESSURE * 10.0 ** (L / 20.0) * np.exp(1j * np.asarray(
        phase_rad, dtype=float))


def apply_fade(pressure_pa, fade_s: float, sample_rate_hz: int = SAMPLE_RATE_HZ) -> np.ndarray:
    """The signal with raised-cosine fade-in and fade-out of ``fade_s`` seconds each."""
    p = np.array(pressure_pa, dtype=float)
    n = min(int(round(fade_s * sample_rate_hz)), p.size // 2)
    if n > 0:
        ramp = 0.5 - 0.5 * np.cos(np.pi * (np.arange(n) + 0.5) / n)
        p[:n] *= ramp
        p[p.size - n:] *= ramp[::-1]
    return p


def synthesize_harmonics(omega_rad_s: float, amplitudes_pa, duration_s: float = 3.0,
                         sample_rate_hz: int = SAMPLE_RATE_HZ, fade_s: float = 0.05
                         ) -> np.ndarray:
    """p(t_j) = Σ_k Re(p̂_k e^{i k ω t_j}), t_j = j/fs, j = 0 … ⌊duration·fs⌋−1 [Pa], faded.

    amplitudes_pa (H,) complex p̂_k of harmonics k = 1 … H (module docstring); harmonics with
    k ω/2π ≥ fs/2 are omitted. Evaluated in blocks of samples (memory ∝ block × H).
    """
    amplitudes = np.asarray(amplitudes_pa, dtype=complex).ravel()
    if not (np.isfinite(omega_rad_s) and omega_rad_s > 0):
        raise ValueError(f"omega_rad_s must be > 0, not {omega_rad_s!r}")
    if not np.all(np.isfinite(amplitudes)):
        raise ValueError("amplitudes_pa must be finite")
    n_samples = int(np.floor(duration_s * sample_rate_hz))
    if n_samples < 1:
        raise ValueError(f"duration_s = {duration_s!r} gives no samples")
    harmonic_omega = omega_rad_s * np.arange(1, amplitudes.size + 1)
    keep = harmonic_omega / (2.0 * np.pi) < sample_rate_hz / 2.0
    harmonic_omega, amplitudes = harmonic_omega[keep], amplitudes[keep]
    magnitude, phase = np.abs(amplitudes), np.angle(amplitudes)
    p = np.empty(n_samples)
    for start in range(0, n_samples, _CHUNK_SAMPLES):
        t = np.arange(start, min(start + _CHUNK_SAMPLES, n_samples)) / sample_rate_hz
        p[start:start + t.size] = np.cos(np.outer(t, harmonic_omega) + phase) @ magnitude
    return apply_fade(p, fade_s, sample_rate_hz)


def background_noise(background_db, duration_s: float = 3.0,
                     sample_rate_hz: int = SAMPLE_RATE_HZ, seed: int = 0, fade_s: float = 0.05
                     ) -> np.ndarray:
    """Random-phase noise [Pa] with third-octave levels background_db (28,) [dB re 20 µPa] on the
    ISO 532-1 bands 25 Hz … 12.5 kHz (−inf: silent band); module docstring. Reproducible for a
    given seed. A band with no DFT bin (record too short) stays silent."""
    B = np.asarray(background_db, dtype=float)
    if B.shape != BAND_NUMBERS.shape or np.any(np.isnan(B)) or np.any(B == np.inf):
        raise ValueError("background_db must be 28 band levels (25 Hz … 12.5 kHz), no NaN/+inf")
    n_samples = int(np.floor(duration_s * sample_rate_hz))
    if n_samples < 2:
        raise ValueError(f"duration_s = {duration_s!r} is too short for a noise record")
    frequency = np.fft.rfftfreq(n_samples, 1.0 / sample_rate_hz)
    interior = (frequency > 0) & (frequency < sample_rate_hz / 2.0)   # bins of weight 2/N²
    slot = np.full(frequency.size, -1)
    slot[interior] = band_index(frequency[interior]) - BAND_NUMBERS[0]
    valid = interior & (slot >= 0) & (slot < BAND_NUMBERS.size)
    bins_per_band = np.bincount(slot[valid], minlength=BAND_NUMBERS.size)
    mean_square = REFERENCE_PRESSURE ** 2 * 10.0 ** (B / 10.0)        # p̃² per band [Pa²]
    magnitude = np.zeros(frequency.size)
    share = np.divide(mean_square, 2.0 * bins_per_band, out=np.zeros_like(mean_square),
                      where=bins_per_band > 0)
    magnitude[valid] = n_samples * np.sqrt(share[slot[valid]])
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, frequency.size)
    p = np.fft.irfft(magnitude * np.exp(1j * phase), n=n_samples)
    return apply_fade(p, fade_s, sample_rate_hz)


def _chunk(tag: bytes, payload: bytes) -> bytes:
    pad = b"\x00" if len(payload) % 2 else b""
    return tag + struct.pack("<I", len(payload)) + payload + pad


def write_wav(path, pressure_pa, sample_rate_hz: int = SAMPLE_RATE_HZ,
              full_scale_pa: float | None = None, sample_format: str = "int16",
              headroom_db: float = 1.0) -> WavCalibration:
    """Write a mono WAV of pressure_pa (n,) [Pa]; returns and stores its calibration.

    full_scale_pa: pressure at digital full scale; default: the peak |p| raised by
    ``headroom_db`` (peak at −1 dBFS), 1 Pa for a silent signal. Samples beyond full scale are
    clipped (int16) — pass a larger full_scale_pa to avoid that.
    """
    if sample_format not in _FORMATS:
        raise ValueError(f"sample_format must be one of {tuple(_FORMATS)}, not {sample_format!r}")
    p = np.asarray(pressure_pa, dtype=float).ravel()
    if not np.all(np.isfinite(p)):
        raise ValueError("pressure_pa must be finite")
    peak = float(np.max(np.abs(p))) if p.size else 0.0
    if full_scale_pa is None:
        full_scale_pa = peak * 10.0 ** (headroom_db / 20.0) if peak > 0 else 1.0
    if not (np.isfinite(full_scale_pa) and full_scale_pa > 0):
        raise ValueError(f"full_scale_pa must be > 0, not {full_scale_pa!r}")
    scaled = p / full_scale_pa
    if sample_format == "int16":
        data = np.clip(np.round(scaled * _INT16_FULL), -32768, 32767).astype("<i2").tobytes()
    else:
        data = scaled.astype("<f4").tobytes()
    tag, bits = _FORMATS[sample_format]
    block = bits // 8
    fmt = struct.pack("<HHIIHH", tag, 1, sample_rate_hz, sample_rate_hz * block, block, bits)
    chunks = _chunk(b"fmt ", fmt if tag == 1 else fmt + struct.pack("<H", 0))
    if tag == 3:
        chunks += _chunk(b"fact", struct.pack("<I", p.size))
    comment = (f"sarfe full_scale_pa={full_scale_pa!r} p_ref_pa={REFERENCE_PRESSURE!r} "
               f"sample_format={sample_format}").encode("ascii") + b"\x00"
    chunks += _chunk(b"LIST", b"INFO" + _chunk(b"ICMT", comment))
    chunks += _chunk(b"data", data)
    Path(path).write_bytes(b"RIFF" + struct.pack("<I", 4 + len(chunks)) + b"WAVE" + chunks)
    peak_dbfs = 20.0 * np.log10(peak / full_scale_pa) if peak > 0 else float("-inf")
    return WavCalibration(full_scale_pa=float(full_scale_pa), sample_rate_hz=int(sample_rate_hz),
                          sample_format=sample_format, peak_dbfs=float(peak_dbfs))


def read_wav(path):
    """(pressure [Pa] (n,), WavCalibration) of a mono WAV written by :func:`write_wav`.
    Raises ValueError naming the file if it is not such a WAV."""
    raw = Path(path).read_bytes()
    if raw[:4] != b"RIFF" or raw[8:12] != b"WAVE":
        raise ValueError(f"{path}: not a RIFF WAVE file")
    position, fmt, data, comment = 12, None, None, b""
    while position + 8 <= len(raw):
        tag = raw[position:position + 4]
        size = struct.unpack("<I", raw[position + 4:position + 8])[0]
        body = raw[position + 8:position + 8 + size]
        if tag == b"fmt ":
            fmt = struct.unpack("<HHIIHH", body[:16])
        elif tag == b"data":
            data = body
        elif tag == b"LIST" and body[:4] == b"INFO":
            comment += body
        position += 8 + size + (size % 2)
    match = re.search(rb"full_scale_pa=([0-9.eE+-]+)", comment)
    if fmt is None or data is None or match is None:
        raise ValueError(f"{path}: no fmt/data chunk or no sarfe calibration (full_scale_pa)")
    tag, channels, rate, _, _, bits = fmt
    formats = {value: name for name, value in _FORMATS.items()}
    if channels != 1 or (tag, bits) not in formats:
        raise ValueError(f"{path}: only mono 16-bit PCM or 32-bit float WAV files are read")
    sample_format = formats[(tag, bits)]
    full_scale_pa = float(match.group(1))
    if sample_format == "int16":
        samples = np.frombuffer(data, dtype="<i2").astype(float) / _INT16_FULL
    else:
        samples = np.frombuffer(data, dtype="<f4").astype(float)
    pressure = samples * full_scale_pa
    peak = float(np.max(np.abs(pressure))) if pressure.size else 0.0
    peak_dbfs = 20.0 * np.log10(peak / full_scale_pa) if peak > 0 else float("-inf")
    return pressure, WavCalibration(full_scale_pa, int(rate), sample_format, float(peak_dbfs))


def write_sound_files(directory, omega_rad_s: float, amplitudes_pa, background_db=None,
                      duration_s: float = 3.0, sample_rate_hz: int = SAMPLE_RATE_HZ,
                      seed: int = 0, sample_format: str = "int16") -> dict:
    """Write ``sound.wav`` (the prediction) and, with background_db (28,), also
    ``sound_with_background.wav`` (prediction + background noise) into ``directory``, on one
    common full scale (so their loudness relation is kept on playback). Returns
    {file name: WavCalibration}."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    prediction = synthesize_harmonics(omega_rad_s, amplitudes_pa, duration_s, sample_rate_hz)
    signals = {"sound.wav": prediction}
    if background_db is not None:
        signals["sound_with_background.wav"] = prediction + background_noise(
            background_db, duration_s, sample_rate_hz, seed)
    peak = max(float(np.max(np.abs(s))) for s in signals.values())
    full_scale = peak * 10.0 ** (1.0 / 20.0) if peak > 0 else 1.0
    return {name: write_wav(directory / name, signal, sample_rate_hz, full_scale, sample_format)
            for name, signal in signals.items()}
