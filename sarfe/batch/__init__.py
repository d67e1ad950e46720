"""Batch runs: many cases or a study's variants, the linear part once per linear model, via Dask.

``run_study(study_or_cases, workers=2, scheduler=None, output_dir=None) -> pandas.DataFrame``
(``sarfe.batch.runner``); study files and variants: ``sarfe.batch.study``; parameter paths:
``sarfe.batch.paths``; resumable on-disk state: ``sarfe.batch.store``; statistics, plots and the CI
gate: ``sarfe.batch.report``; the ``sarfe batch`` subcommand: ``sarfe.batch.cli``.
"""
from sarfe.batch.report import GATE_EXIT_CODE, evaluate_gate
from sarfe.batch.runner import run_study
from sarfe.batch.study import StudyError, Variant, collect_variants, load_study

__all__ = ["run_study", "load_study", "collect_variants", "evaluate_gate", "Variant", "StudyError",
           "GATE_EXIT_CODE"]
