"""The modal part of the per-point error estimate, (4)–(5) of sarfe.accuracy.modal_truncation: two
probes (the top 1/20 and 1/5 of the modes left out) and the decay p of an error ∝ m^{−p} fitted
from both.
Closed forms: for a truncation error e(m) = C m^{−p} the probes change by d_i = e(m'_i) − e(m) and
the extrapolation returns e(m) exactly while 1 ≤ p ≤ 2.5, more than e(m) (never less) for faster
decays, and p = 1 (the slowest plate-like decay: the earlier single probe, top fifth × 4, which it
never exceeds) when the changes do not decay."""
import warnings

import numpy as np
import pytest

from sarfe.accuracy.modal_truncation import (MODE_DECAY, MODE_PROBES, CoarserModels, coarser_models,
                                             modal_extrapolation, modal_truncation_change,
                                             mode_decay, mode_richardson)
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
from sarfe.pipeline.solve.case_accuracy import stage_modal_coordinates
from sarfe.pipeline.solve.points import solve_points
from tests.accuracy.references import CASES, true_errors

MODES = 317          # door trim, 15 mm, cutoff H f_max (benchmarks/results/cutoff.md)


def _probes(p, scale=1e-3):
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    error = (lambda m: scale * (m / MODES) ** (-p))
    return coarser, [error(m) - error(MODES) for m in coarser], error(MODES)


@pytest.mark.parametrize("p", [1.0, 1.5, 2.0, 2.5])
def test_extrapolation_recovers_a_power_law_error(p):
    coarser, changes, error = _probes(p)
    assert mode_decay(MODES, coarser, changes) == pytest.approx(p, abs=1e-9)
    estimate, fitted = modal_extrapolation(MODES, coarser, changes)
    assert estimate == pytest.approx(error, rel=1e-8) and fitted == pytest.approx(p, abs=1e-9)


@pytest.mark.parametrize("p", [3.0, 5.0, 8.0])
def test_faster_decay_is_over_reported_never_under(p):
    coarser, changes, error = _probes(p)
    estimate, fitted = modal_extrapolation(MODES, coarser, changes)
    assert fitted == MODE_DECAY[1]
    # the cap's price: 1.3× at p = 3, 2.7× at 5, 6.6× at 8 (≈ the decay measured from 0.75 to 1.0 H f_max)
    assert error < estimate < 7.0 * error


def test_changes_that_do_not_decay_use_the_slowest_decay():
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    # the smaller probe changed more than the larger (a resonance near the cutoff): p = 1 on the
    # larger probe, the top fifth × m'/(m − m') ≈ 4
    estimate, fitted = modal_extrapolation(MODES, coarser, [2e-4, 1e-4])
    assert fitted == 1.0
    assert estimate == pytest.approx(1e-4 * coarser[1] / (MODES - coarser[1]))     # m'/(m − m')
    assert mode_richardson(MODES, coarser[1]) == pytest.approx(coarser[1] / (MODES - coarser[1]))


@pytest.mark.parametrize("changes", [[1e-4, 1e-3], [1e-4, 2e-4], [3e-4, 1e-4], [1e-9, 1e-3]])
def test_never_above_the_single_top_fifth_probe(changes):
    coarser = [MODES - max(1, int(MODES * q)) for q in MODE_PROBES]
    estimate, _ = modal_extrapolation(MODES, coarser, changes)
    assert estimate <= changes[1] * mode_richardson(MODES, coarser[1], 1.0) * (1 + 1e-12)


def test_one_probe_or_equal_probes_fall_back_to_p_1():
    estimate, fitted = modal_extrapolation(10, [9], [1e-3])
    assert fitted == 1.0 and estimate == pytest.approx(9e-3)
    estimate, fitted = modal_extrapolation(8, [7, 7], [1e-3, 1e-3])    # few modes: same probe twice
    assert fitted == 1.0 and estimate == pytest.approx(7e-3)
    assert np.isfinite(estimate)


def _door_trim(mode_count):
    """Door trim on a coarse mesh (4 cm) with ``mode_count`` modes at 67 Hz: stage, nl, solution."""
    data = load_case(CASES / "door_trim.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.04
    data["excitation"]["frequency_hz"] = [67.0]
    data["solver"].update(prune_contacts=False, error_estimate=False, stability=False)
    data["reduction"] = {"mode_count": mode_count}
    case = load_case(data)
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return stage, nl, solve_points(case.config.solver, case.config.excitation, nl)[0]


@pytest.mark.timeout(300)
def test_coarser_model_is_the_reduction_with_fewer_modes():
    """The modal estimate's coarser model (top fifth of the modes out, residual modes and modal
    damping rebuilt) is the case's own Craig–Bampton reduction with that many fewer modes: the
    change it reports equals the difference of the two solved cases (door trim on a coarse mesh,
    12 and 10 modes, 67 Hz). The coarser model is built once per model: a caller-owned
    :class:`CoarserModels` and the model's own give the same change."""
    stage, nl, s = _door_trim(12)
    small_stage, small_nl, small = _door_trim(10)
    assert s.converged and small.converged and stage.info["residual_vectors"] > 0
    modal, residual = stage_modal_coordinates(stage)
    rel, db, removed = modal_truncation_change(s, nl.model, nl.contacts, nl.excitation, modal,
                                               residual, stage.erp_map, stage.erp_areas)
    assert removed == 2
    a = np.hypot(*np.asarray(s.contact_displacement)[1:3])
    b = np.hypot(*np.asarray(small.contact_displacement)[1:3])
    true_rel = float(np.max(np.abs(a - b)) / a.max())
    _, true_db = true_errors(small_stage, small, stage, s)
    assert rel > 1e-6 and rel == pytest.approx(true_rel, rel=1e-3)
    assert db == pytest.approx(true_db, rel=1e-3)

    own = CoarserModels()
    again = modal_truncation_change(s, nl.model, nl.contacts, nl.excitation, modal, residual,
                                    stage.erp_map, stage.erp_areas, coarser=own)
    assert again[0] == pytest.approx(rel, rel=1e-9) and again[1] == pytest.approx(db, rel=1e-9)
    built = own.get(nl.model, nl.contacts, nl.excitation, modal, residual, 0.2)
    assert own.get(nl.model, nl.contacts, nl.excitation, modal, residual, 0.2) is built
    assert coarser_models(nl.model).get(nl.model, nl.contacts, nl.excitation, modal, residual,
                                        0.2) is not built     # each owner builds its own
