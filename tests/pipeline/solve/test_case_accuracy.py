"""Accuracy as an input (`solver.accuracy`): the resolution sarfe picks meets the target against a
converged fine reference, and every point carries its error estimate."""
import copy
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.read import load_case
from sarfe.pipeline import solve_case

CASE = Path(__file__).resolve().parents[3] / "cases" / "lumped_rattle.yaml"


def _panel_amplitude(result):
    """First-harmonic amplitude of the rattle gap closure [m] at each point."""
    return np.array([p["contacts"][0]["normal_amplitude_m"] for p in result.summary["points"]])


def test_balanced_accuracy_meets_target_against_fine_reference():
    data = load_case(CASE).data
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [48.0, 55.0]
    data["solver"] = {"accuracy": "balanced"}
    chosen = solve_case(copy.deepcopy(data), write=False)
    report = chosen.summary["accuracy"]
    assert report["target"] == "balanced" and report["harmonics"] >= 1
    assert all(p["converged"] for p in chosen.summary["points"])
    for point in chosen.summary["points"]:
        assert point["error_estimate"] is not None and "amplitude_rel" in point["error_estimate"]

    data["solver"] = {"harmonics": 40, "samples_per_period": 2048, "error_estimate": False}
    reference = solve_case(data, write=False)
    assert all(p["converged"] for p in reference.summary["points"])
    a, a_ref = _panel_amplitude(chosen), _panel_amplitude(reference)
    assert a_ref.max() > 1e-4                        # the gap (0.1 mm) closes: a real rattle case
    assert np.max(np.abs(a / a_ref - 1)) < 0.01      # 'balanced' = 1 % amplitude


def _damped_matrices_case():
    """A 2-DOF matrices model with its own damping matrix (no damping section) and a rattle stop."""
    return {
        "name": "own_damping",
        "model": {"matrices": {"mass": [[0.5, 0.0], [0.0, 1.0]],
                               "stiffness": [[2.0e4, 0.0], [0.0, 1.0e4]],
                               "damping": [[6.0, 0.0], [0.0, 6.0]]}},
        "contacts": [{"name": "stop", "type": "rattle", "normal_dof": 0, "gap_m": 5e-5,
                      "normal_stiffness_N_m": 1.0e6, "tolerance_m": 0.0}],
        "excitation": {"forces": [{"dof": 0, "force_N": 2.0}], "frequency_hz": [31.8]},
        "erp": {"dofs": [0], "areas_m2": [0.04]},
    }


def test_accuracy_on_a_matrices_model_with_its_own_damping():
    """solver.accuracy re-loads the case with the chosen H, N: a model with its own damping
    matrix (normalized to an empty damping section) must load again — no false 'give either
    model.matrices.damping or a damping section' — and keep its damping: the linear limit (stop far
    away) equals |F / (k − m ω² + i c ω)|."""
    data = _damped_matrices_case()
    data["solver"] = {"accuracy": "fast"}
    result = solve_case(copy.deepcopy(data), write=False)
    assert result.summary["accuracy"]["harmonics"] >= 1
    assert result.summary["points"][0]["converged"]
    data["contacts"][0]["gap_m"] = 1.0                      # never closes: linear
    linear = solve_case(copy.deepcopy(data), write=False)
    w = 2 * np.pi * 31.8
    exact = 2.0 / abs(2.0e4 - 0.5 * w * w + 6.0j * w)
    U = np.asarray(linear.solutions[0].displacement)
    assert np.hypot(U[1, 0], U[2, 0]) == pytest.approx(exact, rel=1e-6)


def test_study_runs_on_a_matrices_model_with_its_own_damping(tmp_path):
    """`sarfe study` builds its variants from the normalized case: same bug, same fix."""
    from sarfe.tradeoff.study import run_study

    data = _damped_matrices_case()
    data["solver"] = {"harmonics": 3, "samples_per_period": 64}
    result = run_study(data, knobs=["harmonics"], points=2, output_dir=tmp_path / "study",
                       estimate=False)
    assert result.rows


@pytest.mark.timeout(300)
def test_error_bound_is_shown_and_warned_about():
    """lumped_rattle at 48 and 55 Hz (it rattles) at H = 3: each point's ERP error estimate is in
    summary.json and in the table's ±dB column, it brackets the true ERP level error (the larger of
    dB and dB(A)) against
    H = 40, N = 4096, and the run warns in one line that the 'balanced' budget is exceeded,
    naming solver.harmonics. At H = 15 the budget is met and there is no warning."""
    from sarfe.pipeline import results_table

    data = load_case(CASE).data
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [48.0, 55.0]
    data["solver"].update(harmonics=3, samples_per_period=64, stability=False)
    coarse = solve_case(copy.deepcopy(data), write=False)
    data["solver"].update(harmonics=40, samples_per_period=4096, error_estimate=False)
    reference = solve_case(copy.deepcopy(data), write=False)
    for point, ref in zip(coarse.summary["points"], reference.summary["points"]):
        true_db = max(abs(point["erp"][k] - ref["erp"][k]) for k in ("level_db", "level_dba"))
        assert true_db > 0.05                                   # a real error to bound
        assert true_db <= abs(point["error_estimate"]["erp_db"]) <= 5 * true_db
    table = results_table(coarse.rows)
    assert "±dB" in table.splitlines()[0]
    check = coarse.summary["accuracy_check"]
    assert check["met"] is False and "raise solver.harmonics" in check["warning"]
    assert len(check["warning"].splitlines()) == 1
    data["solver"].update(harmonics=15, samples_per_period=512, error_estimate=True)
    fine = solve_case(copy.deepcopy(data), write=False)
    assert fine.summary["accuracy_check"]["met"] is True
    assert fine.summary["accuracy_check"]["warning"] is None


def test_newton_cutoff_does_not_follow_H():
    """The search's Craig–Bampton cutoff (rule_cutoff_hz) is max(1 kHz, m · 5 · f_max), the same
    for every H (issue 30: m · H · f_max took the instrument panel, H = 18, to 5.4 kHz), follows
    f_max and the margin, and leaves a cutoff or mode count the user gave alone."""
    from sarfe.pipeline.model.cutoff import NEWTON_FLOOR_HZ, newton_margin
    from sarfe.pipeline.solve.case_accuracy import rule_cutoff_hz

    case = load_case(Path(CASE).parent / "instrument_panel_sweep.yaml")
    assert case.config.excitation.max_frequency_hz == pytest.approx(200.0)
    rule = rule_cutoff_hz(case)
    assert rule == pytest.approx(1.5 * 5 * 200.0)
    for H in (3, 18, 40):            # the chosen H moves nothing
        assert rule_cutoff_hz(case.with_solver(harmonics=H, samples_per_period=256)) == pytest.approx(rule)
    assert rule_cutoff_hz(case.with_reduction(cutoff_margin=2.0)) == pytest.approx(2.0 * 5 * 200.0)
    low = load_case(Path(CASE).parent / "rattle_rig.yaml")      # f_max = 40 Hz: the floor
    assert newton_margin(low) * 5 * 40.0 < NEWTON_FLOOR_HZ
    assert rule_cutoff_hz(low) == pytest.approx(NEWTON_FLOOR_HZ)
    assert rule_cutoff_hz(case.with_reduction(cutoff_hz=700.0)) is None
    assert rule_cutoff_hz(load_case(CASE)) is None              # a matrices model
