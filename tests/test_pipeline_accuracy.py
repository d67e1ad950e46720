"""Accuracy as an input (`solver.accuracy`): the resolution sarfe picks meets the target against a
converged fine reference, and every point carries its error estimate."""
import copy
from pathlib import Path

import numpy as np

from sarfe.io.case import load_case
from sarfe.pipeline import solve_case

CASE = Path(__file__).resolve().parents[1] / "cases" / "lumped_rattle.yaml"


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
