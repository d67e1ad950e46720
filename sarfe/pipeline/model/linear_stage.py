r"""The linear stage of a case, built: model → (reduced) M, K on the kept DOFs, contact geometry in
those DOFs, unit excitation vectors and the ERP recovery map (:class:`sarfe.pipeline.model.stage.
LinearStage`), by the path of the case's model:

    model.matrices            :mod:`sarfe.pipeline.model.matrices_stage`  (M, K, D as given)
    model.fe.mesh / generator :mod:`sarfe.pipeline.model.fe_stage`        (shells → Craig–Bampton)
    model.fe.deck             :mod:`sarfe.pipeline.model.deck_stage`      (a Nastran/Abaqus deck)
"""
from __future__ import annotations

import time

from sarfe.case.read import load_case
from sarfe.pipeline.model.deck_stage import build_deck_stage
from sarfe.pipeline.model.fe_stage import build_fe_stage
from sarfe.pipeline.model.matrices_stage import build_matrices_stage
from sarfe.pipeline.model.stage import LinearStage, linear_model_key


def build_linear_model(case, progress=False) -> LinearStage:
    """Linear stage of a case (module docstring); raises CaseError for mesh/group/file problems."""
    case = load_case(case)
    clock = time.perf_counter()
    if case.is_fe and case.config.model.fe.is_deck:
        parts = build_deck_stage(case, progress)
    else:
        parts = build_fe_stage(case, progress) if case.is_fe else build_matrices_stage(case)
    timings = dict(parts.pop("timings", {}))
    timings["linear_stage_s"] = time.perf_counter() - clock
    return LinearStage(key=linear_model_key(case), timings=timings, **parts)


__all__ = ["build_linear_model"]
