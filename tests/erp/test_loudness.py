"""ISO 532-1 stationary loudness against the standard's own test cases (Annex B.2, B.3).

Reference values: ISO 532-1:2017 Annex B (test signal 1: third-octave levels given in B.2;
signals 2–4: pure tones of B.3), N = 83.296 / 14.655 / 4.019 / 1.549 sone and
L_N = 103.802 / 78.733 / 60.069 / 46.317 phon, as tabulated by the public validations of
MoSQITo (validations/sq_metrics/loudness_zwst) and SQAT (validation/Loudness_ISO532_1). The
specific loudness of signal 2 below is a subset of the standard's reference output file
(MoSQITo validations/.../ISO_532_1/test_signal_2.csv). Tolerance (ISO 532-1, 5.1): N' within
±5 % or ±0.1 sone/Bark; N within 5 %.
"""
import numpy as np
import pytest

from sarfe.erp.loudness import (BAND_CENTRES_HZ, band_filter_gain, line_spectrum_band_levels_db,
                                loudness_level_phon, zwicker_loudness)

SIGNAL_1_DB = [-60, -60, 78, 79, 89, 72, 80, 89, 75, 87, 85, 79, 86, 80, 71, 70, 72, 71, 72, 74,
               69, 65, 67, 77, 68, 58, 45, 30]


def tone_bands(frequency_hz, level_db, filter_order=3):
    """Third-octave levels of a pure tone as an analyser measures them."""
    return line_spectrum_band_levels_db([frequency_hz], [level_db], filter_order=filter_order)


def within_iso_tolerance(value, reference):
    return abs(value - reference) <= max(0.05 * abs(reference), 0.1)


def test_annex_b2_third_octave_spectrum():
    result = zwicker_loudness(SIGNAL_1_DB, field="free")
    assert result.loudness_sone == pytest.approx(83.296, abs=0.01)     # measured 83.295
    assert result.loudness_level_phon == pytest.approx(103.802, abs=0.01)
    assert result.specific_sone_per_bark.shape == (240,)
    # N is the integral of N'(z): the 0.1-Bark samples integrate to it within the grid error
    assert 0.1 * result.specific_sone_per_bark.sum() == pytest.approx(83.296, rel=0.02)


@pytest.mark.parametrize("frequency_hz, level_db, reference_sone, reference_phon", [
    (250.0, 80.0, 14.655, 78.733),        # test signal 2
    (1000.0, 60.0, 4.019, 60.069),        # test signal 3
    (4000.0, 40.0, 1.549, 46.317),        # test signal 4
    (1000.0, 40.0, 1.0, 40.0),            # the definition of the sone
])
def test_annex_b3_pure_tones(frequency_hz, level_db, reference_sone, reference_phon):
    result = zwicker_loudness(tone_bands(frequency_hz, level_db), field="free")
    assert within_iso_tolerance(result.loudness_sone, reference_sone)
    assert result.loudness_sone == pytest.approx(reference_sone, rel=0.025)   # measured ≤ 2.3 %
    assert result.loudness_level_phon == pytest.approx(reference_phon, abs=0.4)


def test_annex_b3_specific_loudness_of_the_250_hz_tone():
    reference = {1.0: 0.329, 1.8: 0.329, 1.9: 4.583, 2.8: 4.583, 2.9: 4.381, 3.1: 4.081,
                 3.6: 3.346, 5.1: 1.750, 8.1: 0.274, 10.1: 0.079, 15.0: 0.0}
    result = zwicker_loudness(tone_bands(250.0, 80.0))
    for z, value in reference.items():
        i = int(round(z * 10)) - 1
        assert result.bark[i] == pytest.approx(z)
        assert within_iso_tolerance(result.specific_sone_per_bark[i], value), z


def test_an_ideal_band_tone_misses_the_analyser_leakage():
    """Without the analyser filters' skirts a tone excites one band only and loses the lower
    flank of its pattern: 7 % less than the sone's definition at 1 kHz, 40 dB."""
    ideal = zwicker_loudness(tone_bands(1000.0, 40.0, filter_order=None)).loudness_sone
    assert ideal == pytest.approx(0.927, abs=0.005)


def test_ten_phon_more_doubles_the_loudness():
    """The sone scale: above 40 phon, +10 dB at 1 kHz doubles N (L_N = 40 + 10 log2 N)."""
    N = [zwicker_loudness(tone_bands(1000.0, L)).loudness_sone for L in (50.0, 60.0, 70.0, 80.0)]
    assert np.allclose(np.diff(np.log2(N)), 1.0, atol=0.1)


def test_loudness_level_formula():
    assert loudness_level_phon(1.0) == pytest.approx(40.0, abs=1e-12)
    assert loudness_level_phon(4.0) == pytest.approx(60.0)
    assert loudness_level_phon(0.5) == pytest.approx(40 * 0.5005 ** 0.35)
    assert loudness_level_phon(0.0) > 0


def test_diffuse_field_adds_the_tabulated_level_difference():
    """ISO 532-1 table A.5: at 1 kHz a diffuse field excites like a free field 3.0 dB louder."""
    band = np.full(28, -np.inf)
    band[16] = 55.0                                        # 1 kHz band alone
    louder = band.copy()
    louder[16] = 58.0
    diffuse = zwicker_loudness(band, field="diffuse").loudness_sone
    assert diffuse == pytest.approx(zwicker_loudness(louder, field="free").loudness_sone, rel=1e-12)


def test_vectorised_over_spectra_and_silence_is_zero():
    stack = np.stack([SIGNAL_1_DB, np.full(28, -np.inf), tone_bands(1000.0, 60.0)])
    result = zwicker_loudness(stack)
    assert result.loudness_sone.shape == (3,) and result.specific_sone_per_bark.shape == (3, 240)
    assert result.loudness_sone[0] == pytest.approx(zwicker_loudness(SIGNAL_1_DB).loudness_sone)
    assert result.loudness_sone[1] == 0.0


def test_analyser_filters_have_their_half_power_points_on_the_band_edges():
    edges = 1000.0 * 10.0 ** (np.array([-0.05, 0.05]))
    gain = band_filter_gain(np.r_[1000.0, edges], band_numbers=[0])[0]
    assert gain == pytest.approx([1.0, 0.5, 0.5])
    assert BAND_CENTRES_HZ.size == 28


@pytest.mark.parametrize("levels, message", [
    (np.zeros(27), "shape"),
    (np.r_[121.0, np.zeros(27)], "120 dB"),
    (np.r_[np.nan, np.zeros(27)], "NaN"),
])
def test_bad_input_is_one_clear_error(levels, message):
    with pytest.raises(ValueError, match=message):
        zwicker_loudness(levels)
    with pytest.raises(ValueError, match="field"):
        zwicker_loudness(np.zeros(28), field="reverberant")
