"""sarfe.study — the speed/accuracy trade of a case, accuracy as an input, and modelling only what a
scene requires.

Modules: accuracy, resolve (aliases of :mod:`sarfe.accuracy` and :mod:`sarfe.pipeline.accuracy`,
where the error estimates and accuracy resolution live), scene (contact screening/pruning, harmonic content),
runner (``sarfe study``: one knob at a time → table, CSV, JSON, Pareto PNG), lumped (small stand-in
problems), cli (``register(subparsers)``).
"""
from sarfe.accuracy import (AccuracyTarget, ErrorEstimate, Resolution, choose_resolution,
                       estimate_errors, parse_accuracy, suggest_mode_count)
from .scene import (harmonic_content, prune_contacts, screen_contacts, solve_frequency_pruned)

__all__ = ["AccuracyTarget", "ErrorEstimate", "Resolution", "choose_resolution", "estimate_errors",
           "parse_accuracy", "suggest_mode_count", "harmonic_content", "prune_contacts",
           "screen_contacts", "solve_frequency_pruned"]
