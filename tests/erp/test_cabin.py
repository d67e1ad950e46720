"""Diffuse-field cabin model: SPL at the occupant from radiated power (sarfe.erp.cabin)."""
import numpy as np
import pytest

from sarfe.erp.bands import band_index, third_octave_levels
from sarfe.erp.cabin import (PASSENGER_CAR, REFERENCE_PRESSURE, Cabin, absorption_at,
                             critical_distance_m, occupant_pressure_squared, occupant_spl_db,
                             reverberation_time_s, room_constant_m2)
from sarfe.erp.erp import AIR_DENSITY, SOUND_SPEED
from sarfe.erp.rayleigh import baffled_radiated_power


def test_anechoic_limit_is_the_rayleigh_field_of_a_baffled_piston():
    """ᾱ → 1 leaves the direct term: p̃² = ρcPQ/(4πr²), Q = 2 for a baffled source. Checked
    against a small square piston: P from the Rayleigh radiation impedance, the on-axis pressure
    from the Rayleigh integral p̂ = iωρ/(2π) Σ v̂ A e^{−iκR}/R, evaluated independently here."""
    side, n = 0.02, 12
    x = (np.arange(n) + 0.5) / n * side - side / 2
    X, Y = np.meshgrid(x, x)
    points = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    areas = np.full(X.size, (side / n) ** 2)
    v = np.full(X.size, 1e-3 + 0j)
    omega, r = 2 * np.pi * 500.0, 0.5
    kappa = omega / SOUND_SPEED
    power = baffled_radiated_power(points, areas, v, omega)
    R = np.linalg.norm(points - [0.0, 0.0, r], axis=1)
    p_hat = 1j * omega * AIR_DENSITY / (2 * np.pi) * np.sum(v * areas * np.exp(-1j * kappa * R) / R)
    anechoic = Cabin(absorption=1 - 1e-9, directivity=2.0, distance_m=r)
    assert occupant_pressure_squared(power, 500.0, anechoic) == pytest.approx(
        abs(p_hat) ** 2 / 2, rel=0.01)


def test_level_equation_and_reference_impedance():
    """L_p − L_W = 10 lg(Q/(4πr²) + 4/R) + 10 lg(ρc/400): +0.14 dB over the textbook form."""
    P = np.array([1e-9, 1e-6])
    f = np.array([200.0, 2000.0])
    cabin = PASSENGER_CAR
    R = cabin.surface_m2 * 0.41 / 0.59
    expected = (10 * np.log10(P / 1e-12) + 10 * np.log10(2 / (4 * np.pi * 0.25) + 4 / R)
                + 10 * np.log10(AIR_DENSITY * SOUND_SPEED / 400.0))
    assert occupant_spl_db(P, f, cabin) == pytest.approx(expected, abs=1e-12)
    assert 10 * np.log10(AIR_DENSITY * SOUND_SPEED / 400.0) == pytest.approx(0.14, abs=0.005)
    assert occupant_spl_db(0.0, 500.0) == -np.inf
    assert occupant_spl_db(1e-9, 500.0) == pytest.approx(
        10 * np.log10(occupant_pressure_squared(1e-9, 500.0) / REFERENCE_PRESSURE ** 2))


def test_reverberant_field_is_the_diffuse_energy_balance():
    """Far from the source p̃² → 4ρcP/R. With R = A/(1 − ᾱ) and the Sabine area A = Sᾱ
    = 24 ln10 V/(cT) this is the diffuse-field balance w = 4P(1 − ᾱ)/(cA) of the room."""
    far = Cabin(volume_m3=3.0, surface_m2=21.6, absorption=0.3, directivity=1e-9, distance_m=1.0)
    T = reverberation_time_s(far, 1000.0)
    sabine_area = 24 * np.log(10) * far.volume_m3 / (SOUND_SPEED * T)
    energy_balance = 4 * AIR_DENSITY * SOUND_SPEED * 1e-6 * (1 - 0.3) / sabine_area
    assert occupant_pressure_squared(1e-6, 1000.0, far) == pytest.approx(energy_balance, rel=1e-6)


def test_default_cabin_matches_its_sources():
    """Crolla (ed.) 2009, ch. 21.1 p. 699: ᾱ = 0.41, R = 14.98 m², T60(1 kHz) = 58 ms;
    Ono Sokki: a car compartment is about 3 m³."""
    assert room_constant_m2(PASSENGER_CAR, 1000.0) == pytest.approx(14.98, rel=0.01)
    assert reverberation_time_s(PASSENGER_CAR, 1000.0) == pytest.approx(0.058, rel=0.10)
    assert PASSENGER_CAR.volume_m3 == 3.0 and PASSENGER_CAR.directivity == 2.0


def test_critical_distance_splits_the_field_evenly():
    f = 800.0
    rc = float(critical_distance_m(PASSENGER_CAR, f))
    at_rc = Cabin(distance_m=rc)
    reverberant_only = 4 * AIR_DENSITY * SOUND_SPEED * 1e-7 / room_constant_m2(PASSENGER_CAR, f)
    assert occupant_pressure_squared(1e-7, f, at_rc) == pytest.approx(2 * reverberant_only)
    assert 0.5 < rc < 1.2                      # a car's occupant sits near r_c: both terms count


def test_absorption_per_band_interpolates_in_log_frequency():
    cabin = Cabin(absorption=(0.1, 0.3, 0.5), absorption_band_hz=(125.0, 500.0, 2000.0))
    assert absorption_at(cabin, [125.0, 250.0, 500.0, 50.0, 8000.0]) == pytest.approx(
        [0.1, 0.2, 0.3, 0.1, 0.5])
    spl = occupant_spl_db(np.full(3, 1e-8), [125.0, 500.0, 2000.0], cabin)
    assert spl[0] > spl[1] > spl[2]           # less absorption, more reverberant level
    assert cabin.absorption == (0.1, 0.3, 0.5) and hash(cabin)


@pytest.mark.parametrize("kwargs, message", [
    ({"absorption": 1.0}, "absorption"),
    ({"absorption": (0.2, 0.3)}, "absorption_band_hz"),
    ({"absorption": (0.2, 0.3), "absorption_band_hz": (500.0, 250.0)}, "increasing"),
    ({"distance_m": 0.0}, "distance_m"),
    ({"volume_m3": float("nan")}, "volume_m3"),
])
def test_bad_cabin_is_one_clear_error(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Cabin(**kwargs)
    with pytest.raises(ValueError, match="power_W"):
        occupant_spl_db(-1.0, 100.0)


def test_per_band_spl_is_the_power_sum_of_the_harmonics_spl():
    """p̃² is linear in P: with a flat ᾱ the band SPL from the ERP band power equals the power
    sum of the harmonics' SPL in that band."""
    f = 61.0 * np.arange(1, 31)
    power = 1e-8 / np.arange(1, 31) ** 1.5
    bands = third_octave_levels(f, power)
    band_spl = occupant_spl_db(bands.power_W, bands.center_hz)
    harmonic_spl = occupant_spl_db(power, f)
    slot = band_index(f) - bands.band[0]
    summed = np.bincount(slot, 10 ** (harmonic_spl / 10), bands.band.size)
    filled = summed > 0                       # bands between harmonics stay empty (−inf)
    assert band_spl[filled] == pytest.approx(10 * np.log10(summed[filled]), abs=1e-9)
    assert np.all(np.isneginf(band_spl[~filled]))
