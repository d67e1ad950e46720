r"""The Craig–Bampton cutoff rule of an FE case: modes up to f_c are kept, with

    f_c = reduction.cutoff_hz                       when given,
          none (reduction.mode_count modes)         when a mode count is given,
          m · H · f_max                             else (:func:`default_cutoff_hz`),

m = ``reduction.cutoff_margin`` (1.0 by default), H the harmonics, f_max the highest excitation
frequency [Hz]. Shared by the mesh and the deck path of the linear stage and by its key (the
default cutoff follows H and f_max).
"""
from __future__ import annotations


def default_cutoff_hz(config) -> float:
    """Reduction cutoff [Hz] when none is given: margin · H · f_max (``reduction.cutoff_margin``,
    1.0 by default: every kept harmonic has the modes up to its frequency, the modes above answer
    quasi-statically through the residual vectors; measured on the door trim, H = 15, against
    2 H f_max: contact amplitudes ≤ 1.7e-4, ERP ≤ 0.012 dB(A), and the error estimate's modal part
    brackets it: :class:`sarfe.case.config.ReductionConfig`).
    ``config``: the case's CaseConfig (or the Case)."""
    config = getattr(config, "config", config)
    return (config.reduction.cutoff_margin * config.solver.harmonics
            * config.excitation.max_frequency_hz)


def stage_cutoff_hz(config) -> float | None:
    """The cutoff [Hz] the reduction uses (module docstring): the given one, None with a given
    mode count, else :func:`default_cutoff_hz`. ``config``: the case's CaseConfig."""
    reduction = config.reduction
    if reduction.cutoff_hz is not None:
        return reduction.cutoff_hz
    return None if reduction.mode_count is not None else default_cutoff_hz(config)


__all__ = ["default_cutoff_hz", "stage_cutoff_hz"]
