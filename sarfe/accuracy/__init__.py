"""sarfe.accuracy — error bounds of harmonic-balance solutions and accuracy as an input, below the
case layer (plain arrays in, numbers out).

Modules:

- target: the accuracy a user asks for (``fast | balanced | fine | {erp_db: x} |
  {amplitude_rel: x}``) → :class:`AccuracyTarget`;
- measures: what a change of a solution is measured on (first-harmonic contact amplitude, ERP
  level with dB(A), spectral tails), resizing coefficients to another H;
- correction: the Newton re-solve of a solution on another discretization or model, the building
  block of every estimate (engine entry point :func:`sarfe.hbm.solve.newton_from`);
- harmonic_truncation: the H → H' and N → 2N parts of an estimate, Richardson factors;
- modal_truncation: the Craig–Bampton mode-truncation part (coarser models, two probes, decay);
- contact_resolution: whether H' resolves a contact's impacts at all (ρ = k_c |C_{H'}|, the
  impact's duration against T/(2H')); where not, the point has no bound;
- estimate: the per-point estimate combining them (:func:`estimate_errors`,
  :class:`EstimateProblem`, :func:`problem_error_estimate`);
- resolve: a sweep's accuracy target → H, N (:func:`resolve_accuracy`);
- mesh_refinement: the mesh term's Richardson extrapolation of a level on h and 2h (stated order).
"""
from sarfe.accuracy.estimate import (ErrorEstimate, EstimateProblem, estimate_errors,
                                     problem_error_estimate)
from sarfe.accuracy.measures import resize_harmonics
from sarfe.accuracy.resolve import resolve_accuracy
from sarfe.accuracy.target import PRESETS, AccuracyTarget, parse_accuracy

__all__ = ["PRESETS", "AccuracyTarget", "parse_accuracy", "ErrorEstimate", "EstimateProblem",
           "estimate_errors", "problem_error_estimate", "resize_harmonics", "resolve_accuracy"]
