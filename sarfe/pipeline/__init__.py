"""sarfe.pipeline — one case from YAML to result files, by stage (imports run one way: checks and
solve use model; post uses solve; write uses post; run.py and verify.py sit on top):

    checks/   case_checks (check_case: every input check before the heavy work, warnings),
              mesh_checks (check_mesh, check_deck: groups, pairing, quality without assembly)
    model/    stage (LinearStage, linear_model_key), linear_stage (build_linear_model) over
              matrices_stage, fe_stage, deck_stage (+ deck_model, deck_checks, deck_springs);
              shared pieces: case_mesh, groups, contact_pairs, cutoff, erp_map;
              nonlinear_model (damping, ContactSet, excitation harmonics)
    solve/    points (HBM per frequency or continuation, fallbacks), pruned_points,
              case_accuracy (accuracy target → H, N, cutoff; per-point estimates)
    post/     records (ERP, contact indicators, linear baseline, bands), contribution_records,
              contact_dynamics, audibility_records (heard at the occupant), margin_records
              (onset factor, level sensitivities), review (loudest point's answers, target),
              result_data, point_workers (the per-point work on processes)
    write/    result_files (summary, response.h5, VTU, report; table.txt), figures, sound_files
    run.py    solve_case: check → model → solve → post → write
    verify.py verify_point: one point, harmonic balance against time integration

    load_case(path_or_dict) -> Case                         schema-validated, defaults filled
    linear_model_key(case) -> str                           SHA-256 of the linear stage's inputs
    build_linear_model(case, progress=False) -> LinearStage picklable reduced model + maps
    nonlinear_model(case, stage) -> NonlinearModel          damping, contacts, excitation
    solve_case(case, linear_stage=None, output_dir=None, progress=False) -> CaseResult
"""
from sarfe.case.errors import EXIT_CASE_ERROR, EXIT_NOT_CONVERGED, EXIT_TARGET_EXCEEDED, CaseError
from sarfe.case.read import Case, load_case
from sarfe.pipeline.checks.mesh_checks import check_mesh
from sarfe.pipeline.model.contact_pairs import ContactGeometry
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.model.stage import LinearStage, linear_model_key
from sarfe.pipeline.run import CaseResult, solve_case
from sarfe.pipeline.write.result_files import results_table

__all__ = ["Case", "CaseError", "CaseResult", "ContactGeometry", "LinearStage", "load_case",
           "linear_model_key", "build_linear_model", "check_mesh", "solve_case",
           "nonlinear_model", "results_table", "EXIT_CASE_ERROR", "EXIT_NOT_CONVERGED",
           "EXIT_TARGET_EXCEEDED"]
