"""The `make demo` case (cases/door_trim.yaml): its mesh resolves H × f_max (no range warning at
validate), and (slow) its own error estimate is inside the 'balanced' budget at every frequency —
the reason its H was raised from 3 (±1.85 dB at 40 Hz) to 10 (see the case's comment) — and a
finer model agrees with it within those bounds."""
from pathlib import Path

import pytest

from sarfe.cli import main

DEMO = Path(__file__).resolve().parents[2] / "cases" / "door_trim.yaml"


def test_demo_validates_without_range_warnings(capsys):
    assert main(["validate", str(DEMO)]) == 0
    captured = capsys.readouterr()
    assert "valid" in captured.out and "warning" not in captured.err


@pytest.mark.slow
def test_demo_estimate_is_inside_the_balanced_budget(tmp_path):
    from sarfe.pipeline import load_case, solve_case

    summary = solve_case(load_case(DEMO), output_dir=tmp_path / "demo").summary
    check = summary["accuracy_check"]
    # the ± carries the 14 mm mesh's own error (issue 29 item 4: ±5.4 dB, the 19.8 / 28 mm re-solves
    # at 67 Hz): the demo is screening grade (its file says why); inside the budget but for it
    assert check["met"] is False and "mostly from mesh" in check["warning"]
    assert check["target"] == "balanced" and not check["unknown_points"]
    for point in summary["points"]:
        assert point["converged"]
        estimate = point["error_estimate"]
        assert estimate["erp_db"] - estimate["mesh_db"] <= 0.5 and \
            estimate["amplitude_rel"] <= 0.01, point["frequency_hz"]


@pytest.mark.slow
def test_demo_levels_agree_with_a_finer_model_within_their_bounds(tmp_path):
    """Not only the estimator's word: at 40 Hz (the largest estimate) and 67 Hz (the headline)
    the demo's dB(A) lies within its own error bound of a finer model of the same mesh (H = 15,
    N = 128, cutoff margin 1.5: 463 modes; measured 89.17 / 97.03 dB(A) vs the demo's
    89.10 ± 0.38 / 96.95 ± 0.24)."""
    from sarfe.pipeline import load_case, solve_case

    demo = load_case(DEMO).data          # as shipped (its cutoff follows its f_max = 80 Hz)
    demo["output"]["files"] = ["summary"]
    fine = load_case(DEMO).data
    fine["excitation"]["frequency_hz"] = [40.0, 67.0]
    fine["solver"].update(harmonics=15, samples_per_period=128, stability=False)
    fine["reduction"] = {"cutoff_margin": 1.5}
    fine["output"]["files"] = ["summary"]
    coarse = [p for p in solve_case(demo, output_dir=tmp_path / "demo").summary["points"]
              if p["frequency_hz"] in (40.0, 67.0)]
    finer = solve_case(fine, output_dir=tmp_path / "fine").summary["points"]
    for p, q in zip(coarse, finer, strict=True):
        assert p["converged"] and q["converged"]
        assert abs(q["error_estimate"]["erp_db"]) < 0.25                 # the reference is finer
        assert abs(p["erp"]["level_dba"] - q["erp"]["level_dba"]) <= abs(
            p["error_estimate"]["erp_db"]), p["frequency_hz"]
