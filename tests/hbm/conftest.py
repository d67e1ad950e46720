"""Fixtures shared by the HBM tests."""
import numpy as np
import pytest


@pytest.fixture(scope="module")
def squeak_rig():
    """cases/squeak_rig.yaml's nonlinear model and its points at 50 and 150 Hz (H = 3, N = 128:
    the case's old setting, which these tests were written for; the case itself now runs H = 23)."""
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.solve.points import solve_point, solver_options
    data = load_case("cases/squeak_rig.yaml").data
    data["solver"].update(harmonics=3, samples_per_period=128)
    case = load_case(data)
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    options, _ = solver_options(case)
    return nl, [solve_point(nl, 2 * np.pi * f, 3, 128, options, None) for f in (50.0, 150.0)]
