"""Fixtures shared by the HBM tests."""
import numpy as np
import pytest


@pytest.fixture(scope="module")
def squeak_rig():
    """cases/squeak_rig.yaml's nonlinear model and its points at 50 and 150 Hz (H = 3, N = 128)."""
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.points import solve_point, solver_options
    case = load_case("cases/squeak_rig.yaml")
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    options, _ = solver_options(case)
    return nl, [solve_point(nl, 2 * np.pi * f, 3, 128, options, None) for f in (50.0, 150.0)]
