"""A point whose harmonic-balance engine raises is kept, marked not converged, with the reason."""
import numpy as np

from sarfe.pipeline import load_case
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
import sarfe.pipeline.solve.points as points
from sarfe.pipeline.solve.points import solve_point, solver_options


def test_engine_exception_gives_a_non_converged_point_with_the_reason(monkeypatch):
    case = load_case("cases/lumped_rattle.yaml")
    nl = nonlinear_model(case, build_linear_model(case))
    options, _ = solver_options(case.config.solver)

    def failing(*args, **kwargs):
        raise RuntimeError("engine broke")

    monkeypatch.setattr(points, "solve_frequency", failing)
    point = solve_point(nl, 2 * np.pi * 50.0, 3, 64, options, None)
    assert point.converged is False
    assert "engine broke" in point.reason and "time-integration" in point.reason
    assert point.method == "time integration"
    assert np.all(np.isfinite(point.displacement))
