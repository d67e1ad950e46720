"""A case's ``accuracy`` target → H, N, mode count: moved below the study layer
(:mod:`sarfe.accuracy.resolve` on plain arrays, :mod:`sarfe.pipeline.accuracy` for a case);
re-exported here for ``sarfe study --accuracy``."""
from sarfe.accuracy.resolve import apply_resolution
from sarfe.pipeline.accuracy import resolve_case_accuracy

__all__ = ["resolve_case_accuracy", "apply_resolution"]
