"""sarfe.pipeline — one case from YAML to results: the case layer's public functions.

    load_case(path_or_dict) -> Case                         schema-validated, defaults filled
    linear_model_key(case) -> str                           SHA-256 of the linear stage's inputs
    build_linear_model(case, progress=False) -> LinearStage picklable reduced model + maps
    solve_case(case, linear_stage=None, output_dir=None, progress=False) -> CaseResult
"""
from sarfe.io.case import Case, load_case
from sarfe.io.errors import EXIT_CASE_ERROR, EXIT_NOT_CONVERGED, CaseError
from sarfe.pipeline.linear import (
    ContactGeometry,
    LinearStage,
    build_linear_model,
    check_mesh,
    linear_model_key,
)
from sarfe.pipeline.solve import CaseResult, nonlinear_model, results_table, solve_case

__all__ = ["Case", "CaseError", "CaseResult", "ContactGeometry", "LinearStage", "load_case",
           "linear_model_key", "build_linear_model", "check_mesh", "solve_case",
           "nonlinear_model", "results_table", "EXIT_CASE_ERROR", "EXIT_NOT_CONVERGED"]
