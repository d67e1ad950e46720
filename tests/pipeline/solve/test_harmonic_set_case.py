"""solver.harmonic_set end to end on a lumped oscillator: two identical stops (odd-symmetric) give
the same ERP with the odd set as with all orders; one stop makes 'auto' fall back to all orders;
summary.json says which set each point used and the estimate η."""
from __future__ import annotations

import json

import pytest

from sarfe.case.errors import CaseError
from sarfe.pipeline import load_case, solve_case

FREQUENCIES = [30.0, 31.5, 33.0]       # around the 31.8 Hz mode: the stops close every period


def oscillator(harmonic_set, stops=2):
    """1-DOF m = 0.5 kg, k = 2e4 N/m, ζ = 3 %, 2 N at DOF 0, between two stops at ±0.5 mm
    (``stops`` = 2) or against one (``stops`` = 1), k_n = 1e6 N/m; DOF 1 a decoupled spare."""
    contacts = [{"name": "upper", "type": "rattle", "normal_dof": 0, "gap_m": 5e-4,
                 "normal_stiffness_N_m": 1.0e6, "tolerance_m": 0.0},
                {"name": "lower", "type": "rattle", "normal_dof": {"dof": 0, "sign": -1},
                 "gap_m": 5e-4, "normal_stiffness_N_m": 1.0e6, "tolerance_m": 0.0}][:stops]
    return {
        "name": "stops",
        "model": {"matrices": {"mass": [[0.5, 0.0], [0.0, 1.0]],
                               "stiffness": [[2.0e4, 0.0], [0.0, 1.0e4]]}},
        "damping": {"modal_zeta": 0.03},
        "contacts": contacts,
        "excitation": {"forces": [{"dof": 0, "force_N": 2.0}], "frequency_hz": FREQUENCIES},
        "solver": {"harmonics": 7, "samples_per_period": 256, "harmonic_set": harmonic_set,
                   "error_estimate": False},
        "erp": {"dofs": [0, 1], "areas_m2": [0.04, 0.04]},
    }


def run(tmp_path, harmonic_set, stops=2):
    out = tmp_path / f"{harmonic_set}{stops}"
    result = solve_case(oscillator(harmonic_set, stops), output_dir=out)
    return result, json.loads((out / "summary.json").read_text())


def test_symmetric_stops_odd_and_auto_match_all(tmp_path):
    _, full = run(tmp_path, "all")
    for harmonic_set in ("odd", "auto"):
        _, reduced = run(tmp_path, harmonic_set)
        for p, q in zip(full["points"], reduced["points"]):
            assert p["converged"] and q["converged"]
            assert p["contacts"][0]["peak_normal_force_N"] > 0          # the stops act
            assert q["erp"]["power_W"] == pytest.approx(p["erp"]["power_W"], rel=1e-8)
            assert q["harmonic_set"]["requested"] == harmonic_set
            assert q["harmonic_set"]["used"] == "odd"
            assert q["harmonic_set"]["orders"] == [1, 3, 5, 7]
            assert q["harmonic_set"]["dropped_content"] < 1e-8
        assert p["harmonic_set"] == {"requested": "all", "used": "all",
                                     "orders": list(range(8)),
                                     "dropped_content": pytest.approx(0, abs=1e-8)}


def test_one_stop_auto_falls_back_to_all_orders(tmp_path):
    _, full = run(tmp_path, "all", stops=1)
    _, auto = run(tmp_path, "auto", stops=1)
    for p, q in zip(full["points"], auto["points"]):
        assert q["converged"] and q["harmonic_set"]["used"] == "all"
        assert q["harmonic_set"]["dropped_content"] > 0.01
        assert q["erp"]["power_W"] == pytest.approx(p["erp"]["power_W"], rel=1e-6)


def test_harmonic_set_key_is_validated():
    case = load_case(oscillator("all"))
    assert case.data["solver"]["harmonic_set"] == "all"
    data = oscillator("all")
    del data["solver"]["harmonic_set"]
    assert load_case(data).data["solver"]["harmonic_set"] == "all"
    with pytest.raises(CaseError, match="harmonic_set"):
        load_case(oscillator("even"))
