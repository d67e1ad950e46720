"""Calibrated WAV synthesis (sarfe.erp.sound): the files' spectra reproduce the harmonic SPL
(with phases) and the background's third-octave levels; the calibration travels in the file."""
import wave

import numpy as np
import pytest
from scipy.io import wavfile
from scipy.signal import butter, sosfilt

from sarfe.erp.backgrounds import load_background
from sarfe.erp.loudness import BAND_NUMBERS, line_spectrum_band_levels_db
from sarfe.erp.sound import (SAMPLE_RATE_HZ, background_noise, pressure_amplitudes, read_wav,
                             synthesize_harmonics, write_sound_files, write_wav)
from sarfe.erp.weighting import db_sum

P_REF = 20e-6
SPL_DB = np.array([62.0, 55.0, 48.0, 58.0, 40.0, 35.0, 30.0])
PHASE_RAD = np.array([0.3, -1.2, 2.0, 0.0, 2.9, -2.5, 1.1])


def fourier_spl_and_phase(p, start, samples_per_period, periods, harmonics):
    """SPL [dB] and phase [rad] of harmonics 1 … H from an FFT over whole periods."""
    n = samples_per_period * periods
    spectrum = np.fft.rfft(p[start:start + n]) / n
    coefficient = 2 * spectrum[periods * np.arange(1, harmonics + 1)]        # p̂_k e^{ikωt0}
    return 20 * np.log10(np.abs(coefficient) / (np.sqrt(2) * P_REF)), coefficient


def third_octave_levels(p, fs, skip):
    """Band levels [dB] measured with order-3 Butterworth third-octave filters (an analyser)."""
    levels = []
    for n in BAND_NUMBERS:
        centre = 1000.0 * 10 ** (n / 10)
        sos = butter(3, [centre * 10 ** -0.05, centre * 10 ** 0.05], btype="bandpass", fs=fs,
                     output="sos")
        y = sosfilt(sos, p)[skip:-skip]
        levels.append(10 * np.log10(np.mean(y ** 2) / P_REF ** 2))
    return np.array(levels)


def test_wav_spectrum_reproduces_harmonic_spl_and_phase(tmp_path):
    f0 = SAMPLE_RATE_HZ / 400.0                                  # 110.25 Hz: 400 samples/period
    amplitudes = pressure_amplitudes(SPL_DB, PHASE_RAD)
    p = synthesize_harmonics(2 * np.pi * f0, amplitudes, duration_s=2.0)
    calibration = write_wav(tmp_path / "sound.wav", p)
    rate, samples = wavfile.read(tmp_path / "sound.wav")             # an independent reader
    assert rate == SAMPLE_RATE_HZ and samples.dtype == np.int16
    pressure = samples / 32767.0 * calibration.full_scale_pa
    start = 8000                                                     # after the 50 ms fade-in
    spl, coefficient = fourier_spl_and_phase(pressure, start, 400, 100, SPL_DB.size)
    assert np.max(np.abs(spl - SPL_DB)) < 0.5                        # measured < 0.01 dB
    k = np.arange(1, SPL_DB.size + 1)
    phase = np.angle(coefficient * np.exp(-1j * k * 2 * np.pi * f0 * start / SAMPLE_RATE_HZ))
    assert np.max(np.abs(np.angle(np.exp(1j * (phase - PHASE_RAD))))) < 0.01
    assert calibration.peak_dbfs == pytest.approx(-1.0, abs=1e-9)


def test_any_fundamental_keeps_its_harmonic_levels():
    """A fundamental without a whole number of samples per period: the Fourier coefficients over
    250 whole periods (projection on e^{−ikωt}) still give the SPL within 0.5 dB."""
    omega = 2 * np.pi * 97.3
    p = synthesize_harmonics(omega, pressure_amplitudes(SPL_DB, PHASE_RAD), duration_s=3.0)
    t = np.arange(p.size) / SAMPLE_RATE_HZ
    window = (t >= 0.1) & (t < 0.1 + 250 * 2 * np.pi / omega)
    k = np.arange(1, SPL_DB.size + 1)[:, None]
    coefficient = 2 * np.mean(p[window] * np.exp(-1j * k * omega * t[window]), axis=1)
    spl = 20 * np.log10(np.abs(coefficient) / (np.sqrt(2) * P_REF))
    assert np.max(np.abs(spl - SPL_DB)) < 0.5


def test_background_noise_has_the_third_octave_spectrum(tmp_path):
    background = load_background("ev_80kmh").iso_band_levels_db()
    p = background_noise(background, duration_s=3.0, seed=7)
    assert 10 * np.log10(np.mean(p[5000:-5000] ** 2) / P_REF ** 2) == pytest.approx(
        db_sum(background), abs=0.2)
    measured = third_octave_levels(p, SAMPLE_RATE_HZ, skip=SAMPLE_RATE_HZ // 4)
    assert np.max(np.abs(measured - background)) < 1.0
    again = background_noise(background, duration_s=3.0, seed=7)
    other = background_noise(background, duration_s=3.0, seed=8)
    assert np.array_equal(p, again) and not np.allclose(p, other)


def test_sound_files_mix_prediction_and_background_on_one_scale(tmp_path):
    background = load_background("test_chamber_50dba").iso_band_levels_db()
    f0 = 173.0
    amplitudes = pressure_amplitudes(SPL_DB - 15.0, PHASE_RAD)
    calibrations = write_sound_files(tmp_path, 2 * np.pi * f0, amplitudes, background,
                                     duration_s=3.0, seed=1)
    assert set(calibrations) == {"sound.wav", "sound_with_background.wav"}
    assert calibrations["sound.wav"].full_scale_pa == calibrations[
        "sound_with_background.wav"].full_scale_pa
    mix, calibration = read_wav(tmp_path / "sound_with_background.wav")
    assert calibration.sample_rate_hz == SAMPLE_RATE_HZ and calibration.sample_format == "int16"
    with wave.open(str(tmp_path / "sound_with_background.wav")) as handle:   # the standard reader
        assert (handle.getnchannels(), handle.getsampwidth(), handle.getframerate()) == (
            1, 2, SAMPLE_RATE_HZ)
        assert handle.getnframes() == mix.size
    # the analyser sees each harmonic through its filters' skirts too (same order-3 filters)
    prediction_bands = line_spectrum_band_levels_db(f0 * np.arange(1, 8), SPL_DB - 15.0)
    expected = db_sum(np.stack([prediction_bands, background]), axis=0)
    measured = third_octave_levels(mix, SAMPLE_RATE_HZ, skip=SAMPLE_RATE_HZ // 4)
    assert np.max(np.abs(measured - expected)) < 1.0


def test_float32_format_and_calibration_round_trip(tmp_path):
    p = synthesize_harmonics(2 * np.pi * 300.0, pressure_amplitudes([20.0]), duration_s=0.5)
    calibration = write_wav(tmp_path / "quiet.wav", p, sample_format="float32", full_scale_pa=2.0)
    back, read_calibration = read_wav(tmp_path / "quiet.wav")
    assert (read_calibration.full_scale_pa, read_calibration.sample_format) == (2.0, "float32")
    assert read_calibration.peak_dbfs == pytest.approx(calibration.peak_dbfs, abs=1e-5)
    assert np.allclose(back, p, rtol=0, atol=2.0 * 2 ** -23)
    rate, samples = wavfile.read(tmp_path / "quiet.wav")
    assert samples.dtype == np.float32 and np.allclose(samples * 2.0, p, atol=1e-6)
    assert calibration.full_scale_spl_db == pytest.approx(20 * np.log10(2.0 / np.sqrt(2) / P_REF))


def test_fade_and_nyquist():
    amplitudes = pressure_amplitudes([60.0, 60.0])
    p = synthesize_harmonics(2 * np.pi * 15000.0, amplitudes, duration_s=0.2, fade_s=0.01)
    assert abs(p[0]) < 1e-3 * np.max(np.abs(p)) and abs(p[-1]) < 1e-3 * np.max(np.abs(p))
    t = np.arange(p.size) / SAMPLE_RATE_HZ
    middle = slice(p.size // 4, 3 * p.size // 4)
    only_first = np.abs(pressure_amplitudes(60.0)) * np.cos(2 * np.pi * 15000.0 * t)
    assert np.allclose(p[middle], only_first[middle])           # 30 kHz left out, no alias
    with pytest.raises(ValueError, match="omega"):
        synthesize_harmonics(0.0, amplitudes)
