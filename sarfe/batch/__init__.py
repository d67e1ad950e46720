"""Batch runs: many cases or a study's variants, the linear part once per linear model, via Dask.

``run_study(study_or_cases, workers=2, scheduler=None, output_dir=None) -> pandas.DataFrame``
(``sarfe.batch.runner``); study files and variants: ``sarfe.batch.variants``; parameter paths:
``sarfe.batch.paths``; resumable on-disk state: ``sarfe.batch.store``; statistics, plots and the CI
gate: ``sarfe.batch.batch_report``; the ``sarfe batch`` subcommand: ``sarfe.batch.cli``. Exports load on
first use (:mod:`sarfe.util.lazy`: pandas and dask only when a batch runs).
"""
from sarfe.util.lazy import lazy_exports

_EXPORTS = {"GATE_EXIT_CODE": ".batch_report", "evaluate_gate": ".batch_report", "run_study": ".runner",
            "default_output_dir": ".runner",
            "StudyError": ".variants", "Variant": ".variants", "collect_variants": ".variants",
            "load_study": ".variants"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = ["run_study", "default_output_dir", "load_study", "collect_variants", "evaluate_gate",
           "Variant", "StudyError", "GATE_EXIT_CODE"]
