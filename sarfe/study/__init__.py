"""sarfe.study — the speed/accuracy trade of a case, accuracy as an input, and modelling only what a
scene requires.

Modules: accuracy, resolve (aliases of :mod:`sarfe.accuracy` and :mod:`sarfe.pipeline.accuracy`,
where the error estimates and accuracy resolution live), scene (contact screening/pruning),
runner (``sarfe study``: one knob at a time → table, CSV, JSON, Pareto PNG), lumped (small stand-in
problems), cli (``register(subparsers)``). Exports load on first use (:mod:`sarfe.lazy`).
"""
from sarfe.lazy import lazy_exports

_EXPORTS = {name: "sarfe.accuracy" for name in (
    "AccuracyTarget", "ErrorEstimate", "Resolution", "choose_resolution", "estimate_errors",
    "parse_accuracy", "suggest_mode_count")}
_EXPORTS.update({name: ".scene" for name in (
    "prune_contacts", "screen_contacts", "solve_frequency_pruned")})
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = list(_EXPORTS)
