"""A point whose harmonic-balance engine raises is kept, marked not converged, with the reason."""
import numpy as np
import yaml

from sarfe.pipeline import load_case
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
import sarfe.pipeline.solve.points as points
from sarfe.pipeline.solve.points import solve_point, solver_options
from small_cases import TINY


def test_engine_exception_gives_a_non_converged_point_with_the_reason(monkeypatch):
    """:data:`small_cases.TINY` (2 DOF, 1 mm rattle gap the 1 N drive never closes) with 3 %
    modal damping at 20 Hz. What is asserted is the engine-failure path of :func:`solve_point`:
    the exception's message and the time-integration stand-in in the point, finite values. The
    stand-in's own accuracy is asserted by the time-integration tests (tests/hbm). On
    cases/lumped_rattle.yaml, where the contacts act, its two 40-period integrations (256 and
    2048 steps a period) cost 17 s of the default suite; here the start (the scheme's linear
    periodic solution) is already periodic: 0.7 s."""
    data = yaml.safe_load(TINY)
    data["damping"] = {"modal_zeta": 0.03}
    case = load_case(data)
    nl = nonlinear_model(case, build_linear_model(case))
    options, _ = solver_options(case.config.solver)

    def failing(*args, **kwargs):
        raise RuntimeError("engine broke")

    monkeypatch.setattr(points, "solve_frequency", failing)
    point = solve_point(nl, 2 * np.pi * 20.0, 3, 64, options, None)
    assert point.converged is False
    assert "engine broke" in point.reason and "time-integration" in point.reason
    assert point.method == "time integration"
    assert np.all(np.isfinite(point.displacement))
