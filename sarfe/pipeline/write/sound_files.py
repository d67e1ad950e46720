r"""``sound.wav`` and ``sound_with_background.wav``: the predicted sound at the occupant at the
loudest point, to listen to (:mod:`sarfe.erp.sound`).

p(t) = Σ_k |p̂_k| cos(k ω t + φ_k) [Pa] with |p̂_k| = √2 · 20 µPa · 10^(L_p,k/20) from the point's
occupant SPL per harmonic and φ_k the phase of the panel's volume acceleration
(:mod:`sarfe.pipeline.post.audibility_records`: ``points[].audibility.harmonics``), mono, 44.1 kHz,
16-bit PCM, ``audibility.sound_duration_s`` long with 50 ms fades; the second file adds the
background's random-phase noise (its third-octave levels exact, seeded: the same file every run).
Both share one full scale (their loudness relation is kept on playback), stored in the file
(``read_wav`` returns pascals) and in summary.json ``sound``. Without a background ('none') only
sound.wav is written.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sarfe.case.config import NO_BACKGROUND
from sarfe.erp.sound import SAMPLE_RATE_HZ, pressure_amplitudes, write_sound_files
from sarfe.pipeline.post.audibility_records import background_levels

SOUND_FILES = ("sound.wav", "sound_with_background.wav")


def write_point_sound(config, point, directory) -> dict | None:
    """Write the sound files of ``point`` (a summary.json point with ``audibility``) into
    ``directory``; returns summary.json ``sound`` ({point index, frequency, duration, sample rate,
    files: {name: calibration}}) or None when the point has no occupant harmonics."""
    harmonics = (point.get("audibility") or {}).get("harmonics")
    if not harmonics:
        return None
    audibility = config.audibility
    spl = np.asarray(harmonics["spl_db"], dtype=float)
    amplitudes = pressure_amplitudes(np.where(np.isfinite(spl), spl, -np.inf),
                                     np.asarray(harmonics["phase_rad"], dtype=float))
    background = None if audibility.background == NO_BACKGROUND else background_levels(audibility)
    calibrations = write_sound_files(Path(directory), float(point["omega_rad_s"]), amplitudes,
                                     background, duration_s=audibility.sound_duration_s)
    return {"point_index": point["index"], "frequency_hz": point["frequency_hz"],
            "duration_s": audibility.sound_duration_s, "sample_rate_hz": SAMPLE_RATE_HZ,
            "background": audibility.background,
            "files": {name: {"full_scale_pa": c.full_scale_pa,
                             "full_scale_spl_db": c.full_scale_spl_db,
                             "peak_dbfs": c.peak_dbfs, "sample_format": c.sample_format}
                      for name, c in calibrations.items()}}
