r"""Will the occupant hear it: the sound pressure at the occupant of a point, per harmonic and per
third-octave band, its loudness and the verdict against the case's background noise — for the
whole sound and for each source alone (the structure-borne part and each contact).

Per harmonic k (:mod:`sarfe.erp.cabin`, the case's ``audibility.cabin``): the ERP P_k [W] at f_k
gives L_p,k = L_W,k + 10 lg(Q/(4π r²) + 4/R) + 10 lg(ρc/400) [dB re 20 µPa]; the verdict
(:func:`sarfe.erp.audibility.assess_audibility`): masked margin per band against the background,
threshold in quiet, the +6 dB(A)-over-ambient rule, ISO 532-1 loudness. A source alone (the
partial ERP P_s,k of :mod:`sarfe.pipeline.post.contribution_records`) is judged the same way:
would it be heard if it were the only sound.

Phase of the pressure (for sound.wav, :mod:`sarfe.erp.sound`): the pressure of a compact
baffled radiator follows its volume acceleration, p(t) ∝ Σ_i A_i ẅ_i(t − r/c) (Rayleigh), so

    φ_k = arg(V̂_k) + π,    V̂_k = Σ_i A_i ŵ_k,i,   ŵ_k,i = W_kc,i − i W_ks,i

(radiating-node normal displacements W, nodal areas A_i; the common delay r/c is dropped). Where
the panel's net volume displacement cancels (|V̂_k| < 10⁻⁶ Σ_i A_i |ŵ_k,i|: an antisymmetric
pattern), the phase of the node radiating most at that harmonic is taken instead.
"""
from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from sarfe.case.config import NO_BACKGROUND, AudibilityConfig, ErpConfig
from sarfe.erp.audibility import DBA_OVER_AMBIENT_DB, assess_audibility
from sarfe.erp.bands import band_frequencies
from sarfe.erp.backgrounds import load_background
from sarfe.erp.cabin import Cabin, occupant_spl_db
from sarfe.erp.loudness import BAND_CENTRES_HZ, BAND_NUMBERS, line_spectrum_band_levels_db
from sarfe.erp.weighting import a_weighted_total_db

# ISO 532-1 analyser band levels must stay ≤ 120 dB in 25–250 Hz: the caps tried for the loudness
LOUDNESS_CAPS_DB = np.arange(120.0, 100.0, -1.0)
_, _LOWER_HZ, _UPPER_HZ = band_frequencies(BAND_NUMBERS)
_EDGES_HZ = (float(_LOWER_HZ[0]), float(_UPPER_HZ[-1]))      # 22.4 Hz … 14.1 kHz
CANCELLED_VOLUME = 1e-6    # |V̂_k| / Σ A |ŵ_k| below which the phase comes from the loudest node

VERDICT_KEYS = ("spl_dba", "loudness_sone", "audible", "margin_db", "loudest_band_hz",
                "dba_over_background_db", "above_ambient_dba_rule", "background_dba",
                "loudness_level_phon", "background_loudness_sone", "total_loudness_sone",
                "loudness_increase_sone", "harmonics_outside_bands")
# loudness_capped (also in each verdict): the loudness of harmonics capped into ISO 532-1's range
BAND_KEYS = {"spl_db": "spl_db", "background_db": "background_db",
             "threshold_in_quiet_db": "threshold_in_quiet_db",
             "masked_threshold_db": "masked_threshold_db", "margin_db": "margin_band_db"}


def cabin_of(config: AudibilityConfig) -> Cabin:
    """The :class:`sarfe.erp.cabin.Cabin` of ``audibility.cabin``."""
    c = config.cabin
    return Cabin(volume_m3=c.volume_m3, surface_m2=c.surface_m2, absorption=c.absorption,
                 absorption_band_hz=c.absorption_band_hz, directivity=c.directivity,
                 distance_m=c.distance_m)


@functools.lru_cache(maxsize=8)
def _background(name: str):
    if name == NO_BACKGROUND:
        return np.full(BAND_CENTRES_HZ.shape, -np.inf), "none: the threshold in quiet only"
    spectrum = load_background(name)
    return spectrum.iso_band_levels_db(), spectrum.source.splitlines()[0] if spectrum.source \
        else spectrum.name


def background_levels(config: AudibilityConfig) -> np.ndarray:
    """(28,) band levels [dB re 20 µPa] of ``audibility.background`` on the ISO 532-1 bands
    (−inf everywhere for 'none')."""
    return _background(config.background)[0].copy()


def background_record(config: AudibilityConfig) -> dict:
    """summary.json ``audibility_model``: the background (name or file, first header line, band
    levels, A-weighted total), the cabin and the loudness field — what every verdict assumes."""
    levels, source = _background(config.background)
    cabin = cabin_of(config)
    finite = levels[np.isfinite(levels)]
    total = float("-inf")
    if finite.size:
        total = float(a_weighted_total_db(levels[np.isfinite(levels)],
                                          BAND_CENTRES_HZ[np.isfinite(levels)]))
    return {"background": config.background, "background_source": source,
            "background_dba": total,
            "background_band_hz": BAND_CENTRES_HZ, "background_db": levels,
            "cabin": {"distance_m": cabin.distance_m, "volume_m3": cabin.volume_m3,
                      "surface_m2": cabin.surface_m2, "absorption": list(cabin.absorption),
                      "absorption_band_hz": list(cabin.absorption_band_hz),
                      "directivity": cabin.directivity},
            "loudness_field": config.loudness_field,
            "criterion": "audible when a third-octave band of the prediction at the occupant "
                         "exceeds max(masked threshold of the background, threshold in quiet)"}


def pressure_phases(W, areas) -> np.ndarray:
    """φ_k (H,) [rad] of the occupant pressure per harmonic (module docstring) from the
    radiating-node normal displacements W (2H+1, n_s) [m] and areas (n_s,) [m²]."""
    W = np.asarray(W, dtype=float)
    A = np.asarray(areas, dtype=float)
    w = W[1::2] - 1j * W[2::2]                                   # (H, n_s) ŵ_k,i
    if not A.size:
        return np.zeros(w.shape[0])
    volume = w @ A                                               # V̂_k
    scale = np.abs(w) @ A
    loudest = w[np.arange(w.shape[0]), np.argmax(A * np.abs(w) ** 2, axis=1)]
    cancelled = np.abs(volume) < CANCELLED_VOLUME * scale
    return np.angle(np.where(cancelled, loudest, volume)) + np.pi


def occupant_spl(config: AudibilityConfig, erp: ErpConfig, power_W, frequencies_hz):
    """L_p,k [dB re 20 µPa] at the occupant of harmonic powers P_k [W] at f_k [Hz]."""
    return occupant_spl_db(np.asarray(power_W, dtype=float), np.asarray(frequencies_hz, float),
                           cabin_of(config), density=erp.rho_kg_m3, sound_speed=erp.c_m_s)


def _assess(config: AudibilityConfig, f, L):
    """(Audibility, loudness_capped) of harmonics (f_k, L_k) against the case's background. ISO
    532-1 is not defined for bands 25–250 Hz above 120 dB: then the loudness is taken of the
    harmonics capped so that every band stays within the standard (a lower bound,
    ``loudness_capped`` True) and everything else of the uncapped harmonics."""
    background = background_levels(config)
    try:
        return assess_audibility(f, L, background, field=config.loudness_field), False
    except ValueError as error:
        if "120 dB" not in str(error):
            raise
    for cap in LOUDNESS_CAPS_DB:
        try:
            capped = assess_audibility(f, np.minimum(L, cap), background,
                                       field=config.loudness_field)
            break
        except ValueError:
            continue
    else:
        raise ValueError("the occupant SPL is beyond ISO 532-1's range even when capped")
    inside = (f >= _EDGES_HZ[0]) & (f < _EDGES_HZ[1])
    band_spl = line_spectrum_band_levels_db(f[inside], L[inside], filter_order=None)
    margin = band_spl - np.maximum(capped.masked_threshold_db, capped.threshold_in_quiet_db)
    margin_db = float(np.max(margin))
    spl_dba = float(a_weighted_total_db(L, f))
    over = spl_dba - capped.background_dba
    return dataclasses.replace(
        capped, spl_db=band_spl, margin_band_db=margin, margin_db=margin_db,
        audible=bool(margin_db > 0.0), spl_dba=spl_dba, dba_over_background_db=over,
        above_ambient_dba_rule=bool(over >= DBA_OVER_AMBIENT_DB),
        loudest_band_hz=float(BAND_CENTRES_HZ[int(np.argmax(margin))]) if math.isfinite(
            margin_db) else float("nan")), True


def verdict(config: AudibilityConfig, frequencies_hz, spl_db, bands: bool = False) -> dict:
    """The verdict dict (:data:`VERDICT_KEYS`, ``loudness_capped``; with ``bands`` also the 28
    band arrays) of harmonics (f_k, L_p,k) against the case's background."""
    f = np.asarray(frequencies_hz, dtype=float)
    result, capped = _assess(config, f, np.asarray(spl_db, dtype=float))
    out = {key: getattr(result, key) for key in VERDICT_KEYS}
    out["loudness_capped"] = capped
    if bands:
        out["bands"] = {"band_hz": result.band_hz,
                        **{key: getattr(result, name) for key, name in BAND_KEYS.items()}}
    return out


def point_audibility(config, erp_result, W, areas, contributions) -> dict:
    """summary.json ``points[].audibility`` of one point: the verdict of the whole sound with its
    bands, the occupant SPL and pressure phase per harmonic, and per source (``contributions``
    available: the structure-borne part 'excitation' and each contact) the verdict of its sound
    alone. ``config``: the case's CaseConfig; ``erp_result``: the point's ErpResult; W (2H+1, n_s)
    radiating-node displacements, ``areas`` their nodal areas."""
    audibility = config.audibility
    f = np.asarray(erp_result.frequencies_hz, dtype=float)
    spl = occupant_spl(audibility, config.erp, erp_result.power, f)
    record = verdict(audibility, f, spl, bands=True)
    record["harmonics"] = {"frequency_hz": f, "spl_db": spl,
                           "phase_rad": pressure_phases(W, areas)}
    sources = []
    if contributions.get("available"):
        for source in contributions["sources"]:
            power = np.asarray(source["harmonics_power_W"], dtype=float)
            alone = verdict(audibility, f, occupant_spl(audibility, config.erp, power, f))
            sources.append({"name": source["name"],
                            **{k: alone[k] for k in ("spl_dba", "loudness_sone", "audible",
                                                     "margin_db")}})
    record["sources"] = sources
    return record
