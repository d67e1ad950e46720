"""Typed configuration (sarfe/case/config.py): built once per Case from the normalized data, frozen,
and the single source of the case defaults (issue 12)."""
import copy
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from sarfe.erp.erp import AIR_DENSITY, REFERENCE_POWER, SOUND_SPEED
from sarfe.case.read import load_case, read_yaml
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
    assert config.contacts[0].gap_m == pytest.approx(1e-4)
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


def _reloaded(case, edit):
    """The old way of changing a setting: the normalized mapping copied, edited and loaded again."""
    data = copy.deepcopy(case.data)
    edit(data)
    return load_case(data, base_dir=case.base_dir)


def test_a_changed_setting_is_the_typed_section_replaced_not_a_reload():
    """with_solver / with_reduction / with_contact / with_generator give the config and the
    normalized mapping that editing the mapping and loading it again gives — without the reload
    (the file and its lines are kept), and the original case is left as it was."""
    case = load_case(CASE)
    changed = case.with_solver(harmonics=9, samples_per_period=256, resolution="fixed")
    again = _reloaded(case, lambda d: d["solver"].update(harmonics=9, samples_per_period=256,
                                                         resolution="fixed"))
    assert changed.config == again.config and changed.data == again.data
    assert changed.source == case.source and changed.lines == case.lines
    assert case.config.solver.harmonics == case.data["solver"]["harmonics"] == 7

    stiff = case.with_contact(0, normal_stiffness_N_m=3e6, gap_m=2e-4)
    again = _reloaded(case, lambda d: d["contacts"][0].update(normal_stiffness_N_m=3e6,
                                                              gap_m=2e-4))
    assert stiff.config == again.config and stiff.data == again.data
    assert stiff.config.contacts[0].gap_m == 2e-4

    fe = load_case(CASE.parent / "rattle_rig.yaml")
    cut = fe.with_reduction(cutoff_hz=400.0)
    again = _reloaded(fe, lambda d: d["reduction"].update(cutoff_hz=400.0))
    assert cut.config == again.config and cut.data == again.data
    modes = cut.with_reduction(cutoff_hz=None, mode_count=20, min_mode_count=0)
    assert modes.config.reduction.cutoff_hz is None and "cutoff_hz" not in modes.data["reduction"]
    assert modes.config == _reloaded(cut, lambda d: (d["reduction"].pop("cutoff_hz"), d[
        "reduction"].update(mode_count=20, min_mode_count=0))).config
    coarse = fe.with_generator(mesh_size_m=0.02)
    assert coarse.config.model.fe.generator.mesh_size_m == 0.02
    assert coarse.config == _reloaded(fe, lambda d: d["model"]["fe"]["generator"].update(
        mesh_size_m=0.02)).config
    with pytest.raises(ValueError, match="2H\\+1"):
        case.with_solver(harmonics=200)
    with pytest.raises(ValueError, match="not both"):
        cut.with_reduction(mode_count=20)


def test_every_default_the_normalized_case_holds_is_a_config_field_default():
    """A deck case and an FE case without the optional keys: what normalize wrote is the field
    default of the typed section (one source), and the typed fields read it back."""
    from sarfe.case.config import (BaseAccelerationConfig, ContactConfig, DeckConfig,
                                   ForceConfig, default_of)

    fe = load_case(CASE.parent / "rattle_rig.yaml")
    contact = fe.data["contacts"][0]
    assert contact["pairing_tolerance_m"] == ContactConfig.pairing_tolerance_m == \
        fe.config.contacts[0].pairing_tolerance_m
    assert contact["normal"] == ContactConfig.normal == fe.config.contacts[0].normal == "auto"
    assert fe.data["model"]["fe"]["mesh_units"] == fe.config.model.fe.mesh_units == "m"
    raw, _ = read_yaml(CASE.parent / "rattle_rig_deck.yaml")
    raw["model"]["fe"].pop("units")
    deck = load_case(raw, base_dir=CASE.parent)
    section = deck.data["model"]["fe"]
    for key in ("ignore_cards", "node_groups", "element_groups"):
        assert section[key] == default_of(DeckConfig, key)
    # units stays absent (the units check yields only to an explicit units:), typed default SI
    assert "units" not in section
    assert deck.config.model.fe.deck.units == DeckConfig.units == "SI"
    assert deck.config.model.fe.deck.node_groups == {} and deck.config.model.fe.fixed == ()
    force, typed = deck.data["excitation"]["forces"][0], deck.config.excitation.forces[0]
    assert force["phase_deg"] == ForceConfig.phase_deg == typed.phase_deg == 0.0
    assert tuple(force["direction"]) == typed.direction
    lumped = load_case(CASE)
    base = lumped.data["excitation"]["base_acceleration"]
    assert base["phase_deg"] == BaseAccelerationConfig.phase_deg == \
        lumped.config.excitation.base_acceleration.phase_deg
    assert lumped.config.excitation.base_acceleration.influence == (1.0, 0.2, 1.0)
    ref = lumped.config.contacts[0].normal_dof
    assert (ref.dof, ref.relative_to, ref.sign) == (0, 1, 1)
