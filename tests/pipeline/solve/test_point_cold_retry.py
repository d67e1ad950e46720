"""A point whose warm start fails is re-solved from the engine's cold start (linearized guess and
homotopies) before the short time integration is tried; it then equals the cold-start solution."""
import dataclasses

import numpy as np

import sarfe.hbm
import sarfe.pipeline.solve.points as points
from sarfe.pipeline import load_case
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model


def test_failed_warm_start_retries_the_cold_start_not_the_time_integration(monkeypatch):
    case = load_case("cases/lumped_rattle.yaml")
    nl = nonlinear_model(case, build_linear_model(case))
    options, _ = points.solver_options(case.config.solver)
    options = dataclasses.replace(options, stability=False)
    omega, H, N = 2 * np.pi * 50.0, case.config.solver.harmonics, 256
    cold = sarfe.hbm.solve_frequency(nl.model, nl.contacts, nl.excitation, omega, H, N,
                                     options=options)
    assert cold.converged
    real = sarfe.hbm.solve_frequency

    def warm_start_fails(*args, initial=None, **kwargs):
        solution = real(*args, initial=initial, **kwargs)
        if initial is None:
            return solution
        return dataclasses.replace(solution, converged=False, reason="stalled (test)")

    def no_time_integration(*args, **kwargs):
        raise AssertionError("the time integration must not be needed")

    monkeypatch.setattr(points, "solve_frequency", warm_start_fails)
    monkeypatch.setattr(points, "time_integration_point", no_time_integration)
    point = points.solve_point(nl, omega, H, N, options, cold)
    assert point.converged and point.method != points.TIME_INTEGRATION
    assert "cold start after the warm start failed" in point.reason and "stalled" in point.reason
    scale = np.abs(cold.displacement).max()
    assert np.abs(point.displacement - cold.displacement).max() <= 1e-9 * scale
