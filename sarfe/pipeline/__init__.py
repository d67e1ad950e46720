"""sarfe.pipeline — one case from YAML to results: the case layer's public functions.

Modules: linear (mesh → reduced model, contact geometry, load and ERP maps; the reusable linear
stage), nonlinear (damping, ContactSet, excitation harmonics), points (HBM per frequency or
continuation, with fallbacks), postprocess (ERP, contact indicators, linear risk baseline),
outputs (result files, console table), solve (solve_case).

    load_case(path_or_dict) -> Case                         schema-validated, defaults filled
    linear_model_key(case) -> str                           SHA-256 of the linear stage's inputs
    build_linear_model(case, progress=False) -> LinearStage picklable reduced model + maps
    solve_case(case, linear_stage=None, output_dir=None, progress=False) -> CaseResult
"""
from sarfe.case.read import Case, load_case
from sarfe.case.errors import EXIT_CASE_ERROR, EXIT_NOT_CONVERGED, CaseError
from sarfe.pipeline.checks.mesh_checks import check_mesh
from sarfe.pipeline.model.contact_pairs import ContactGeometry
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.stage import LinearStage, linear_model_key
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.write.result_files import results_table
from sarfe.pipeline.run import CaseResult, solve_case

__all__ = ["Case", "CaseError", "CaseResult", "ContactGeometry", "LinearStage", "load_case",
           "linear_model_key", "build_linear_model", "check_mesh", "solve_case",
           "nonlinear_model", "results_table", "EXIT_CASE_ERROR", "EXIT_NOT_CONVERGED"]
