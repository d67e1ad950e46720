"""Third-octave band levels (IEC 61260-1 base-10 bands) of harmonic ERP spectra."""
import numpy as np
import pytest

from sarfe.erp.bands import band_frequencies, band_index, third_octave_levels
from sarfe.erp.weighting import a_weighting_db


def test_band_centres_and_edges_follow_iec_61260():
    mid, lo, hi = band_frequencies(np.array([0, -4, 3]))
    assert np.allclose(mid, [1000.0, 1000 * 10 ** -0.4, 1000 * 10 ** 0.3])
    assert np.allclose(hi / lo, 10 ** 0.1)          # one third of a decade-octave
    assert np.allclose(hi[:1], lo[:1] * 10 ** 0.1)
    # nominal 63 Hz band: 56.2 … 70.8 Hz; 1 kHz band: 891 … 1122 Hz
    assert band_index(63.0) == -12 and band_index(56.3) == -12 and band_index(70.7) == -12
    assert band_index(70.8) == -11 and band_index(1000.0) == 0 and band_index(1122.1) == 1
    # an exact edge belongs to the upper band
    edge = 1000.0 * 10 ** (0.5 / 10)
    assert band_index(edge) == 1


@pytest.mark.parametrize("frequency_hz, nominal", [(67.0, 63.0), (100.0, 100.0), (42.0, 40.0),
                                                   (1.9e3, 2000.0)])
def test_pure_tone_puts_all_its_power_in_its_band(frequency_hz, nominal):
    spectrum = third_octave_levels([frequency_hz], [3.2e-6])
    (loud,) = np.flatnonzero(spectrum.power_W > 0)
    assert spectrum.nominal_hz[loud] == nominal
    assert spectrum.lower_hz[loud] <= frequency_hz < spectrum.upper_hz[loud]
    assert spectrum.power_W[loud] == 3.2e-6
    assert spectrum.level_db[loud] == pytest.approx(10 * np.log10(3.2e-6 / 1e-12), abs=1e-12)
    assert spectrum.level_dba[loud] == pytest.approx(spectrum.level_db[loud]
                                                     + a_weighting_db(frequency_hz), abs=1e-9)


def test_band_powers_add_up_to_the_total():
    rng = np.random.default_rng(3)
    f = 37.0 * np.arange(1, 41)                    # 40 harmonics of 37 Hz: 37 Hz … 1.48 kHz
    power = rng.uniform(0, 1e-5, f.size)
    power[7] = 0.0
    spectrum = third_octave_levels(f, power)
    assert spectrum.power_W.sum() == pytest.approx(power.sum(), rel=1e-9)
    weighted = (power * 10 ** (a_weighting_db(f) / 10)).sum()
    assert spectrum.power_a_W.sum() == pytest.approx(weighted, rel=1e-9)
    # contiguous bands, each edge the next band's lower edge
    assert np.all(np.diff(spectrum.band) == 1)
    assert np.allclose(spectrum.upper_hz[:-1], spectrum.lower_hz[1:])
    # several harmonics share the upper bands; every harmonic lies inside its band
    n = band_index(f)
    assert np.all(spectrum.lower_hz[n - spectrum.band[0]] <= f)
    assert np.all(f < spectrum.upper_hz[n - spectrum.band[0]])
