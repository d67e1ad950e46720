r"""The Craig–Bampton cutoff rule of an FE case: modes up to f_c are kept, with

    f_c = reduction.cutoff_hz                       when given,
          none (reduction.mode_count modes)         when a mode count is given,
          min(m · H · f_max, f_N)                   else (:func:`default_cutoff_hz`),

    f_N = max(f_floor, m' · H_dyn · f_max)          the Newton cutoff (:func:`newton_cutoff_hz`),

m = ``reduction.cutoff_margin`` (1.0 by default), m' = max(m, LADDER_FACTOR) (1.5), H the
harmonics, f_max the highest excitation frequency [Hz], f_floor = NEWTON_FLOOR_HZ (1 kHz),
H_dyn = NEWTON_HARMONICS (5). A cutoff for the Newton, not for the spectrum (issue 30): the
modes that respond dynamically at the contact rows are kept, the harmonics above f_N meet no
kept mode and are answered quasi-statically — the Craig–Bampton constraint modes give the exact
static response of the contact (boundary) DOFs, the residual vectors (on by default) that of the
loads — and the per-point error estimate's modal term measures what that costs (in the ±).
With ``resolution: auto`` the H search and the sweep run on f_N itself
(:func:`sarfe.pipeline.solve.case_accuracy.rule_cutoff_hz`). Shared by the mesh and the deck
path of the linear stage and by its key (the default cutoff follows H and f_max).

Measured (benchmarks/results/newton_cutoff.md): the door trim (10 mm, 67 Hz) and the instrument
panel (65.3 Hz, H = 18) move ≤ 0.002 dB(A) between f_N and 3 kHz. The capped default
(benchmarks/results/capped_cutoff.md) against 2–4× larger cutoffs: door_trim_p1's geometry at
10 mm, H = 15, 44–80 Hz (f_N = 1 kHz, harmonics to 1.2 kHz) ≤ 0.0052 dB(A) and 2.9e-4 in the
contact amplitudes (today's 1.2 kHz default: ≤ 0.0078 dB), 30–200 Hz (f_N = 1.5 kHz, harmonics
to 3 kHz, 457 modes instead of 1038) ≤ 0.0003 dB; the squeak rig (stick-slip, H = 32 to 150 Hz,
f_N = 1125 Hz instead of 4.8 kHz) ≤ 0.017 dB — each bracketed by the modal term plus its floor.
"""
from __future__ import annotations

from sarfe.accuracy.resolve import LADDER_FACTOR

NEWTON_FLOOR_HZ = 1000.0    # f_floor [Hz]: below it the door trim's H ladder climbed irregularly
NEWTON_HARMONICS = 5        # H_dyn (solver.harmonics' default)


def newton_margin(config) -> float:
    """m' = max(reduction.cutoff_margin, LADDER_FACTOR) of :func:`newton_cutoff_hz` (the H
    ladder's next rung over H_dyn). ``config``: the case's CaseConfig (or the Case)."""
    config = getattr(config, "config", config)
    return float(max(config.reduction.cutoff_margin, LADDER_FACTOR))


def newton_cutoff_hz(config) -> float:
    """f_N = max(f_floor, m' · H_dyn · f_max) [Hz] (module docstring): it does not grow with H.
    ``config``: the case's CaseConfig (or the Case)."""
    config = getattr(config, "config", config)
    return float(max(NEWTON_FLOOR_HZ, newton_margin(config) * NEWTON_HARMONICS
                     * config.excitation.max_frequency_hz))


def spectral_cutoff_hz(config) -> float:
    """m · H · f_max [Hz]: the highest excited harmonic times the margin (the rule before the cap).
    ``config``: the case's CaseConfig (or the Case)."""
    config = getattr(config, "config", config)
    return float(config.reduction.cutoff_margin * config.solver.harmonics
                 * config.excitation.max_frequency_hz)


def default_cutoff_hz(config) -> float:
    """Reduction cutoff [Hz] when none is given: min(m · H · f_max, f_N) (module docstring) —
    every kept harmonic below f_N has the modes up to its frequency (cutoff_margin 1.0: measured
    on the door trim, H = 15, against 2 H f_max: contact amplitudes ≤ 1.7e-4, ERP ≤ 0.012 dB(A),
    :class:`sarfe.case.config.ReductionConfig`), the harmonics above f_N answer quasi-statically.
    ``config``: the case's CaseConfig (or the Case)."""
    return min(spectral_cutoff_hz(config), newton_cutoff_hz(config))


def stage_cutoff_hz(config) -> float | None:
    """The cutoff [Hz] the reduction uses (module docstring): the given one, None with a given
    mode count, else :func:`default_cutoff_hz`. ``config``: the case's CaseConfig."""
    reduction = config.reduction
    if reduction.cutoff_hz is not None:
        return reduction.cutoff_hz
    return None if reduction.mode_count is not None else default_cutoff_hz(config)


__all__ = ["NEWTON_FLOOR_HZ", "NEWTON_HARMONICS", "newton_margin", "newton_cutoff_hz", "spectral_cutoff_hz",
           "default_cutoff_hz", "stage_cutoff_hz"]
