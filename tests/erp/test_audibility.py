"""Audibility of a predicted harmonic spectrum: thresholds, masking, dB(A) rule, loudness, and the
shipped background spectra with their loader (sarfe.erp.audibility, sarfe.erp.backgrounds)."""
import json

import numpy as np
import pytest

from sarfe.erp.audibility import (THRESHOLD_IN_QUIET_DB, assess_audibility, critical_bandwidth_hz,
                                  masked_threshold_db, masking_index_db)
from sarfe.erp.backgrounds import (BackgroundFileError, background_names, load_background,
                                   neutral_spectrum_db)
from sarfe.erp.bands import band_frequencies
from sarfe.erp.loudness import (BAND_CENTRES_HZ, BAND_NUMBERS, line_spectrum_band_levels_db,
                                zwicker_loudness)
from sarfe.erp.weighting import a_weighting_db

SILENCE = np.full(28, -np.inf)
PUBLISHED_DBA = {"ev_80kmh": 61.0, "diesel_130kmh": 68.0, "test_chamber_50dba": 50.0}


@pytest.mark.parametrize("frequency_hz, threshold_db", [(1000.0, 2.4), (4000.0, -5.4),
                                                        (100.0, 26.5), (12500.0, 12.3)])
def test_threshold_in_quiet_is_iso_226(frequency_hz, threshold_db):
    """ISO 226:2003 table 1 (T_f): a tone 1 dB above is audible in silence, 1 dB below is not."""
    above = assess_audibility([frequency_hz], [threshold_db + 1.0], SILENCE)
    below = assess_audibility([frequency_hz], [threshold_db - 1.0], SILENCE)
    assert above.audible and above.margin_db == pytest.approx(1.0)
    assert not below.audible and below.margin_db == pytest.approx(-1.0)
    assert above.loudest_band_hz == frequency_hz


def test_white_noise_masks_tones_17_db_above_its_density_level():
    """Zwicker & Fastl, Psychoacoustics, fig. 4.1: tones in white noise of density level l are
    just masked ≈ 17 dB above l up to 500 Hz, the threshold rising 10 dB per decade above.
    The model (critical-band level + masking index) within 3 dB from 63 Hz to 12.5 kHz."""
    centre, lower, upper = band_frequencies(BAND_NUMBERS)
    density_level = 30.0
    white = density_level + 10 * np.log10(upper - lower)
    over_density = masked_threshold_db(white) - density_level
    datum = 17.0 + 10 * np.log10(np.maximum(BAND_CENTRES_HZ, 500.0) / 500.0)
    assessed = BAND_CENTRES_HZ >= 63
    assert np.max(np.abs(over_density - datum)[assessed]) < 3.0


def test_masking_ingredients():
    assert critical_bandwidth_hz(1000.0) == pytest.approx(162.2, abs=0.5)   # Zwicker & Terhardt
    assert critical_bandwidth_hz(100.0) == pytest.approx(100.8, abs=0.5)
    assert masking_index_db([200.0, 1000.0, 4000.0]) == pytest.approx([-2.11, -2.78, -4.67],
                                                                      abs=0.01)


def test_a_tone_just_above_the_masked_threshold_is_audible_where_the_dba_rule_says_no():
    """A 3.15 kHz squeak 3 dB above its masked threshold in the diesel cabin at 130 km/h is
    audible although its A-weighted level lies far below the ambient's (the overall dB(A) rule
    ignores masking per band); 3 dB below the threshold it is masked."""
    background = load_background("diesel_130kmh").iso_band_levels_db()
    band = int(np.flatnonzero(BAND_CENTRES_HZ == 3150.0)[0])
    threshold = masked_threshold_db(background)[band]
    assert threshold > THRESHOLD_IN_QUIET_DB[band]
    heard = assess_audibility([3150.0], [threshold + 3.0], background)
    masked = assess_audibility([3150.0], [threshold - 3.0], background)
    assert heard.audible and heard.margin_db == pytest.approx(3.0)
    assert not masked.audible and masked.margin_db == pytest.approx(-3.0)
    assert heard.dba_over_background_db < -15.0 and not heard.above_ambient_dba_rule
    assert heard.loudness_increase_sone > 0.0


def test_dba_rule_and_loudness_of_a_loud_prediction():
    background = load_background("test_chamber_50dba").iso_band_levels_db()
    f = 200.0 * np.arange(1, 21)
    spl = 70.0 - 20 * np.log10(np.arange(1, 21))
    result = assess_audibility(f, spl, background, field="free")
    expected_dba = 10 * np.log10(np.sum(10 ** ((spl + a_weighting_db(f)) / 10)))
    assert result.spl_dba == pytest.approx(expected_dba)
    assert result.background_dba == pytest.approx(50.0, abs=0.05)
    assert result.above_ambient_dba_rule and result.audible
    alone = zwicker_loudness(line_spectrum_band_levels_db(f, spl), field="free").loudness_sone
    assert result.loudness_sone == pytest.approx(alone)
    # adding a sound never makes the cabin quieter, and loudness is not additive (masking)
    assert result.background_loudness_sone < result.total_loudness_sone
    assert result.total_loudness_sone < result.loudness_sone + result.background_loudness_sone
    json.dumps(result.as_dict())


def test_bands_receive_each_harmonic_power_exactly():
    f = np.array([100.0, 105.0, 1000.0, 20000.0, 10.0])
    spl = np.array([40.0, 40.0, 30.0, 80.0, 90.0])
    result = assess_audibility(f, spl, SILENCE)
    assert result.spl_db[BAND_CENTRES_HZ == 100.0][0] == pytest.approx(40 + 10 * np.log10(2))
    assert result.spl_db[BAND_CENTRES_HZ == 1000.0][0] == pytest.approx(30.0)
    assert result.harmonics_outside_bands == 2
    assert np.isneginf(result.margin_band_db[BAND_CENTRES_HZ == 500.0][0])


@pytest.mark.parametrize("name", sorted(PUBLISHED_DBA))
def test_shipped_backgrounds_have_their_published_overall_level(name):
    spectrum = load_background(name)
    assert spectrum.total_dba() == pytest.approx(PUBLISHED_DBA[name], abs=0.05)
    assert np.allclose(spectrum.iso_band_levels_db(), neutral_spectrum_db(PUBLISHED_DBA[name]),
                       atol=0.05)
    assert np.allclose(np.diff(spectrum.level_db), -5.0 / 3.0, atol=0.11)   # −5 dB/octave
    assert "Overall level" in spectrum.source and "Construction" in spectrum.source
    assert set(background_names()) >= set(PUBLISHED_DBA)


@pytest.mark.parametrize("content, message", [
    ("100,50\n100,40\n", "listed twice"),
    ("110,50\n", "not a third-octave band centre"),
    ("100;50\n", "expected 'band_hz, level_db'"),
    ("100,loud\n", "not two numbers"),
    ("100,inf\n", "must be finite"),
    ("# only a header\n", "no band levels"),
])
def test_bad_background_file_is_one_line_naming_file_and_line(tmp_path, content, message):
    path = tmp_path / "cabin.csv"
    path.write_text("# a source line\nband_hz,level_db\n" + content)
    with pytest.raises(BackgroundFileError, match=message) as error:
        load_background(path)
    text = str(error.value)
    assert "\n" not in text and str(path) in text


def test_user_background_with_few_bands_and_exact_centres(tmp_path):
    path = tmp_path / "measured.csv"
    path.write_text("# measured somewhere\n1000 45.0\n501.19 50\n16000 20\n")
    spectrum = load_background(path)
    levels = spectrum.iso_band_levels_db()
    assert levels[BAND_CENTRES_HZ == 500.0][0] == 50.0
    assert levels[BAND_CENTRES_HZ == 1000.0][0] == 45.0
    assert np.isneginf(levels[BAND_CENTRES_HZ == 100.0][0])
    assert spectrum.source == "measured somewhere" and spectrum.band.tolist() == [-3, 0, 12]
    with pytest.raises(BackgroundFileError, match="no such background"):
        load_background("no_such_cabin")
