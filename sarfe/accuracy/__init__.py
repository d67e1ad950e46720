"""sarfe.accuracy — error bounds of harmonic-balance solutions and accuracy as an input, below the
case layer (plain arrays in, numbers out).

Modules: estimates (a-posteriori error estimates of one solution, the adaptive choice of H, N at
one frequency, the mode-count rule), resolve (a sweep's accuracy target → H, N, mode count).
"""
from .estimates import (PRESETS, AccuracyTarget, ErrorEstimate, EstimateProblem, Resolution,
                        choose_resolution, estimate_errors, parse_accuracy, problem_error_estimate,
                        resize_harmonics, suggest_mode_count)
from .resolve import apply_resolution, resolve_accuracy

__all__ = ["PRESETS", "AccuracyTarget", "ErrorEstimate", "EstimateProblem", "Resolution",
           "choose_resolution", "estimate_errors", "parse_accuracy", "problem_error_estimate",
           "resize_harmonics", "suggest_mode_count", "apply_resolution", "resolve_accuracy"]
