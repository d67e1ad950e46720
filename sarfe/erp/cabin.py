r"""Sound pressure at the occupant from radiated sound power: a diffuse-field cabin model.

A source of sound power P [W] and directivity factor Q in a room of surface S [m²] and mean
(random-incidence) absorption coefficient ᾱ gives, at distance r [m] (Hopkins–Stryker; Kuttruff,
*Room Acoustics*, 5.4; Bies & Hansen, *Engineering Noise Control*, 7.4),

    p̃² = ρ c P ( Q / (4π r²) + 4 / R ),     R = S ᾱ / (1 − ᾱ)          [Pa², room constant m²]

    L_p = L_W + 10 lg( Q/(4π r²) + 4/R ) + 10 lg( ρ c / 400 Pa·s/m )    [dB re 20 µPa]

with L_W = 10 lg(P / 1 pW) and p̃ the RMS pressure. The last term (+0.14 dB for air at 20 °C,
ρc = 413 Pa·s/m) is the usual textbook formula's omission: p_ref²/P_ref = 400 Pa·s/m. The direct
term dominates within the critical distance r_c = √(Q R / 16π). ᾱ may depend on frequency
(given per third-octave band, interpolated linearly in lg f between band centres and held
constant beyond the first and last). For the ERP of a harmonic response each harmonic k has its
own P_k and f_k (harmonics are incoherent in power over a period), so L_p,k follows per harmonic,
``occupant_spl_db(erp.power, erp.frequencies_hz)``, and per third-octave band from the band
powers of :func:`sarfe.erp.bands.third_octave_levels`, ``occupant_spl_db(bands.power_W,
bands.center_hz)`` (ᾱ at the band centre; with a flat ᾱ both agree exactly).
The Sabine reverberation time T = 24 ln 10 · V / (c S ᾱ) is reported as a plausibility check of
the chosen absorption (the source below measured 58 ms at 1 kHz).

Default passenger-car cabin (:data:`PASSENGER_CAR`, every value stated with its source):

- ᾱ = 0.41 (one value for all bands) and R = 14.98 m²: the worked cabin example of
  *Automotive Engineering: Powertrain, Chassis System and Vehicle Body* (D. Crolla, ed.,
  Butterworth-Heinemann 2009), ch. 21.1 "Interior noise: assessment and control", p. 699:
  surface-average absorption of a saloon with cloth seats (unoccupied) at 1 kHz, room constant
  R_cloth = 14.98 m², average T60(1 kHz) = 58 ms.
- S = R (1 − ᾱ)/ᾱ = 21.6 m² (from those two numbers; trim, glass, seats and floor).
- V = 3.0 m³: "the car compartment has only approx. 3 m³" (A. Motojima et al., Ono Sokki
  technical note "Acoustic measurement trend in a car compartment"); with S and ᾱ above, Sabine
  gives T = 0.055 s, the book's 58 ms within 6 % (the book's value implies V = 3.2 m³).
- Q = 2: a trim panel radiates into the half space in front of it (baffled by the body).
- r = 0.5 m: an assumed door-trim/instrument-panel-to-ear distance (not from a source; set it
  per case).

A flat ᾱ over frequency is a simplification: trim absorbs less below ~500 Hz (Saha & Baker, SAE
870988: carpets have "significant absorption above 500 Hz"), so low-frequency reverberant levels
are under-estimated by this default; pass per-band values when known. The model also inherits
the ERP's assumptions (radiation efficiency 1, so P is an upper bound below coincidence).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.erp.erp import AIR_DENSITY, SOUND_SPEED

__all__ = ["Cabin", "PASSENGER_CAR", "REFERENCE_PRESSURE", "absorption_at", "critical_distance_m",
           "occupant_pressure_squared", "occupant_spl_db", "reverberation_time_s",
           "room_constant_m2"]

REFERENCE_PRESSURE = 20e-6   # [Pa] p_ref, levels in dB re 20 µPa


@dataclass(frozen=True)
class Cabin:
    """A cabin for the diffuse-field model (module docstring). SI units.

    absorption: mean absorption coefficient ᾱ ∈ (0, 1), one value or one per entry of
    absorption_band_hz (band centres [Hz], increasing; empty for a single value).
    """

    volume_m3: float = 3.0
    surface_m2: float = 21.6
    absorption: tuple = (0.41,)
    absorption_band_hz: tuple = ()
    directivity: float = 2.0
    distance_m: float = 0.5

    def __post_init__(self):
        alpha = np.atleast_1d(np.asarray(self.absorption, dtype=float))
        bands = np.asarray(self.absorption_band_hz, dtype=float)
        object.__setattr__(self, "absorption", tuple(float(a) for a in alpha))
        object.__setattr__(self, "absorption_band_hz", tuple(float(b) for b in bands))
        for name in ("volume_m3", "surface_m2", "directivity", "distance_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"Cabin.{name} must be a finite number > 0, not {value!r}")
        if alpha.size == 0 or np.any(~((alpha > 0) & (alpha < 1))):
            raise ValueError(f"Cabin.absorption must lie in (0, 1), not {self.absorption!r}")
        if alpha.size > 1 or bands.size:
            if bands.size != alpha.size:
                raise ValueError(f"Cabin.absorption_band_hz has {bands.size} entries for "
                                 f"{alpha.size} absorption values")
            if np.any(~(bands > 0)) or np.any(np.diff(bands) <= 0):
                raise ValueError("Cabin.absorption_band_hz must be > 0 and increasing")


PASSENGER_CAR = Cabin()


def absorption_at(cabin: Cabin, frequency_hz) -> np.ndarray:
    """ᾱ(f): the single value, or linear in lg f between band centres (constant outside)."""
    f = np.asarray(frequency_hz, dtype=float)
    if np.any(~(f > 0)):
        raise ValueError("frequency_hz must be > 0")
    if not cabin.absorption_band_hz:
        return np.full(f.shape, cabin.absorption[0])
    return np.interp(np.log10(f), np.log10(cabin.absorption_band_hz), cabin.absorption)


def room_constant_m2(cabin: Cabin, frequency_hz) -> np.ndarray:
    """R = S ᾱ / (1 − ᾱ) [m²] at the frequencies [Hz]."""
    alpha = absorption_at(cabin, frequency_hz)
    return cabin.surface_m2 * alpha / (1.0 - alpha)


def reverberation_time_s(cabin: Cabin, frequency_hz, sound_speed: float = SOUND_SPEED
                         ) -> np.ndarray:
    """Sabine T = 24 ln10 · V / (c S ᾱ) [s] (≈ 0.161 V/(S ᾱ))."""
    alpha = absorption_at(cabin, frequency_hz)
    return 24.0 * np.log(10.0) * cabin.volume_m3 / (sound_speed * cabin.surface_m2 * alpha)


def critical_distance_m(cabin: Cabin, frequency_hz) -> np.ndarray:
    """r_c = √(Q R / 16π) [m]: where the direct and reverberant terms are equal."""
    return np.sqrt(cabin.directivity * room_constant_m2(cabin, frequency_hz) / (16.0 * np.pi))


def occupant_pressure_squared(power_W, frequency_hz, cabin: Cabin = PASSENGER_CAR,
                              density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED
                              ) -> np.ndarray:
    """p̃² = ρ c P (Q/(4π r²) + 4/R(f)) [Pa²] at the occupant; power_W and frequency_hz
    broadcast (per harmonic (H,), per band (n_b,), or stacked)."""
    P = np.asarray(power_W, dtype=float)
    if np.any(P < 0) or np.any(~np.isfinite(P)):
        raise ValueError("power_W must be finite and >= 0")
    direct = cabin.directivity / (4.0 * np.pi * cabin.distance_m ** 2)
    return density * sound_speed * P * (direct + 4.0 / room_constant_m2(cabin, frequency_hz))


def occupant_spl_db(power_W, frequency_hz, cabin: Cabin = PASSENGER_CAR,
                    density: float = AIR_DENSITY, sound_speed: float = SOUND_SPEED
                    ) -> np.ndarray:
    """L_p = 10 lg(p̃² / p_ref²) [dB re 20 µPa] at the occupant (module docstring); zero power
    gives −inf. Same broadcasting as :func:`occupant_pressure_squared`."""
    p2 = occupant_pressure_squared(power_W, frequency_hz, cabin, density, sound_speed)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(p2 / REFERENCE_PRESSURE ** 2)
