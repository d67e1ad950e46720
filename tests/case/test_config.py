"""Typed configuration (sarfe/case/config.py): built once per Case from the normalized data, frozen,
and the single source of the case defaults (issue 12)."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED
from sarfe.case.read import load_case
from sarfe.case.config import CONTINUATION_MAX_STEP, ContinuationConfig, ErpConfig, SolverConfig

CASE = Path(__file__).resolve().parents[2] / "cases" / "lumped_rattle.yaml"


def test_config_mirrors_the_normalized_case_and_is_built_once():
    case = load_case(CASE)
    config = case.config
    assert case.config is config                         # built once per Case
    assert config.solver.harmonics == case.data["solver"]["harmonics"] == 7
    assert config.excitation.sweep.start_hz == 30.0 and config.excitation.max_frequency_hz == 90.0
    assert [c.name for c in config.contacts] == ["panel_bracket", "seal"]
    assert [c.kind for c in config.contacts] == ["rattle", "squeak"]
    assert config.contacts[0]["gap_m"] == pytest.approx(1e-4)
    assert config.damping.modal_zeta == pytest.approx(0.03)
    assert config.model.fe is None and config.model.matrices is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.solver.harmonics = 3


def test_defaults_come_from_the_config_dataclasses():
    """A case without solver.continuation / erp air keys gets the config's defaults: one source."""
    case = load_case(CASE)
    cont = case.data["solver"]["continuation"]
    assert cont["max_step"] == ContinuationConfig.max_step == CONTINUATION_MAX_STEP == 0.1
    assert cont["initial_step"] == ContinuationConfig.initial_step
    assert case.data["solver"]["tolerance"] == SolverConfig.tolerance
    erp = case.config.erp
    assert (erp.rho_kg_m3, erp.c_m_s, erp.reference_power_W) == \
        (AIR_DENSITY, SOUND_SPEED, REFERENCE_POWER) == \
        (ErpConfig.rho_kg_m3, ErpConfig.c_m_s, ErpConfig.reference_power_W)


def test_pipeline_passes_the_case_continuation_step_to_the_engine():
    from sarfe.pipeline.solve.points import solver_options

    case = load_case(CASE)
    _, continuation = solver_options(case.config.solver)
    assert continuation.max_step == 0.1                  # not the engine's library default 0.25


def test_time_integration_stand_in_is_a_harmonic_solution():
    """The pipeline's stand-in for a point whose engine call raised is a HarmonicSolution
    (method 'time integration'); its first harmonic matches the linear closed form when no
    contact closes (gap far away)."""
    from sarfe.hbm.solution import HarmonicSolution
    from sarfe.pipeline import build_linear_model, nonlinear_model
    from sarfe.pipeline.solve.points import TIME_INTEGRATION, linear_solution, time_integration_point

    data = load_case(CASE).data
    data["contacts"] = [dict(data["contacts"][0], gap_m=1.0)]       # never closes
    case = load_case(data, base_dir=CASE.parent)
    nl = nonlinear_model(case, build_linear_model(case))
    omega = 2 * np.pi * 40.0
    point = time_integration_point(nl.model, nl.contacts, nl.excitation, omega, 7, 256)
    assert isinstance(point, HarmonicSolution) and point.method == TIME_INTEGRATION
    exact = linear_solution(nl, omega, 7, 256)
    assert exact.method == "linear"
    assert point.converged
    np.testing.assert_allclose(point.displacement[1:3], exact.displacement[1:3], rtol=1e-3,
                               atol=1e-3 * np.abs(exact.displacement[1:3]).max())
