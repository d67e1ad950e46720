"""A-weighting against the IEC 61672-1 Table 3 values and dB arithmetic."""
import numpy as np
import pytest

from sarfe.erp.weighting import a_weighted_total_db, a_weighting_db, db_sum

# IEC 61672-1:2013 Table 3: nominal frequency [Hz] and A-weighting [dB]; the standard evaluates
# the weighting at the exact base-10 frequencies f = 1000 · 10^(n/10).
IEC_TABLE = [
    (31.5, -15, -39.4), (63, -12, -26.2), (125, -9, -16.1), (250, -6, -8.6), (500, -3, -3.2),
    (1000, 0, 0.0), (2000, 3, 1.2), (4000, 6, 1.0), (8000, 9, -1.1), (16000, 12, -6.6),
    (20, -17, -50.5), (100, -10, -19.1), (10000, 10, -2.5),
]


@pytest.mark.parametrize("nominal, n, expected", IEC_TABLE)
def test_a_weighting_matches_iec_table(nominal, n, expected):
    f_exact = 1000.0 * 10.0 ** (n / 10.0)
    assert abs(float(a_weighting_db(f_exact)) - expected) <= 0.1


def test_a_weighting_normalised_at_1khz_and_vectorised():
    assert abs(float(a_weighting_db(1000.0))) < 1e-3
    f = np.array([[0.0, 1000.0], [63.0, 8000.0]])
    a = a_weighting_db(f)
    assert a.shape == (2, 2)
    assert a[0, 0] == -np.inf
    with pytest.raises(ValueError):
        a_weighting_db(-1.0)


def test_db_sum_arithmetic():
    assert db_sum([90.0, 90.0]) == pytest.approx(90.0 + 10 * np.log10(2))
    assert db_sum([80.0, 80.0, 80.0, 80.0]) == pytest.approx(86.0206, abs=1e-4)
    assert db_sum([70.0, -np.inf]) == pytest.approx(70.0)
    assert db_sum([-np.inf, -np.inf]) == -np.inf
    # power sum, not an arithmetic mean: 100 dB + 90 dB = 100.414 dB
    assert db_sum([100.0, 90.0]) == pytest.approx(100.4139, abs=1e-4)


def test_a_weighted_total():
    levels = np.array([80.0, 80.0])
    freqs = np.array([1000.0, 1000.0 * 10 ** 0.3])
    a = a_weighting_db(freqs)
    expected = 10 * np.log10(10 ** ((80 + a[0]) / 10) + 10 ** ((80 + a[1]) / 10))
    assert a_weighted_total_db(levels, freqs) == pytest.approx(expected)
