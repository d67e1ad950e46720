"""sarfe.accuracy — error bounds of harmonic-balance solutions and accuracy as an input, below the
case layer (plain arrays in, numbers out).

Modules: estimates (a-posteriori error estimates of one solution), resolve (a sweep's accuracy target → H, N, mode count).
Exports load on first use (:mod:`sarfe.util.lazy`).
"""
from sarfe.util.lazy import lazy_exports

_EXPORTS = {name: ".estimates" for name in (
    "PRESETS", "AccuracyTarget", "ErrorEstimate", "EstimateProblem", "estimate_errors",
    "parse_accuracy", "problem_error_estimate", "resize_harmonics")}
_EXPORTS.update({"apply_resolution": ".resolve", "resolve_accuracy": ".resolve"})
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = list(_EXPORTS)
