"""Contact pruning in `sarfe solve` (solver.prune_contacts): contacts that never switch are solved
linearly, and the result is the one of the full contact set.

The scene: the 3-DOF panel/bracket model of cases/lumped_rattle.yaml (panel 50 Hz, bracket 100 Hz,
in-plane DOF 80 Hz) with three rattle contacts — the panel hits the bracket across 0.1 mm
(nonlinear), the in-plane DOF has a 5 mm stop it never reaches (open), and a clip between bracket
and in-plane DOF is preloaded by 50 N while the motion unloads it by at most a few N (closed).
"""
import copy
import warnings

import numpy as np
import pytest

from sarfe.pipeline import load_case, solve_case
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.model.linear_stage import build_linear_model
from state_checks import assert_states_equal_away_from_ties

FREQUENCIES_HZ = [40.0, 48.0, 50.0, 55.0, 70.0]


def scene(frequencies=FREQUENCIES_HZ, sweep=None, prune=True, back_gap=None):
    contacts = [
        {"name": "panel_bracket", "type": "rattle", "normal_dof": {"dof": 0, "relative_to": 1},
         "gap_m": 1.0e-4, "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5},
        {"name": "far_stop", "type": "rattle", "normal_dof": {"dof": 2}, "gap_m": 5.0e-3,
         "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5},
        {"name": "clip", "type": "rattle", "normal_dof": {"dof": 1, "relative_to": 2},
         "preload_N": 50.0, "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5},
    ]
    if back_gap is not None:     # a stop behind the panel: w = −u0
        contacts.append({"name": "back_stop", "type": "rattle",
                         "normal_dof": {"dof": 0, "sign": -1}, "gap_m": back_gap,
                         "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5})
    excitation = {"base_acceleration": {"amplitude_m_s2": 3.0, "influence": [1.0, 0.2, 1.0]}}
    if sweep is not None:
        excitation["sweep"] = {"start_hz": sweep[0], "end_hz": sweep[1]}
    else:
        excitation["frequency_hz"] = list(frequencies)
    return {"name": "pruning_scene",
            "model": {"matrices": {"mass": [[0.2, 0, 0], [0, 0.5, 0], [0, 0, 0.2]],
                                   "stiffness": [[2e4, 0, 0], [0, 2e5, 0], [0, 0, 5e4]]}},
            "damping": {"modal_zeta": 0.03}, "contacts": contacts, "excitation": excitation,
            "solver": {"harmonics": 7, "samples_per_period": 256, "prune_contacts": prune,
                       "stability": False},
            "erp": {"dofs": [0], "areas_m2": [0.06]}}


def solve(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_case(copy.deepcopy(data), write=False)


def assert_same_solutions(pruned, full):
    """Displacements, contact forces (harmonics and samples) and states agree to 1e-6 of the peak."""
    assert len(pruned.solutions) == len(full.solutions)
    for a, b in zip(pruned.solutions, full.solutions):
        assert a.omega == b.omega and a.converged and b.converged
        for field in ("displacement", "contact_displacement", "contact_force",
                      "contact_force_time"):
            x, y = getattr(a, field), getattr(b, field)
            assert x.shape == y.shape
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-6 * np.abs(y).max(), err_msg=field)
        assert_states_equal_away_from_ties(a.contact_state, b.contact_state)
        assert a.residual_norm < 1e-8
    for p, q in zip(pruned.summary["points"], full.summary["points"]):
        assert p["erp"]["power_W"] == pytest.approx(q["erp"]["power_W"], rel=1e-6)
        assert p["erp"]["level_db"] == pytest.approx(q["erp"]["level_db"], abs=1e-5)


def decisions(result):
    return {c["name"]: c["decision"] for c in result.summary["contact_pruning"]["contacts"]}


@pytest.mark.timeout(300)
def test_pruned_points_identical_to_full_contact_set():
    pruned, full = solve(scene()), solve(scene(prune=False))
    report = pruned.summary["contact_pruning"]
    assert report["enabled"] and report["applied"] and not report["fallback"]
    assert decisions(pruned) == {"panel_bracket": "nonlinear", "far_stop": "open",
                                 "clip": "closed"}
    assert report["pairs"] == 3 and report["nonlinear_pairs"] == 1
    assert all(c["reason"] for c in report["contacts"])
    assert full.summary["contact_pruning"] == {**full.summary["contact_pruning"],
                                               "enabled": False, "applied": False}
    assert_same_solutions(pruned, full)
    # the closed clip carries its preload in the restored contact forces: mean λ = k_n (w0 − g) ≈ 50 N
    clip = pruned.solutions[0].contact_force[0, 2]
    assert clip == pytest.approx(50.0, rel=0.05)


@pytest.mark.timeout(300)
def test_screen_too_optimistic_falls_back_and_stays_identical():
    """A stop behind the panel that the linear response stays clear of (clearance ≈ 0.33 at
    40 Hz) but the impacts on the bracket push the panel onto: with a small margin it is screened
    open, the check on the nonlinear solution catches it, and the case is solved with all contacts."""
    data = scene(frequencies=[40.0, 70.0], back_gap=1.2e-4)
    data["solver"]["prune_contacts"] = {"margin": 0.1}
    pruned, full = solve(data), solve(scene(frequencies=[40.0, 70.0], back_gap=1.2e-4,
                                            prune=False))
    report = pruned.summary["contact_pruning"]
    assert decisions(pruned)["back_stop"] == "open" and report["fallback"]
    assert not report["applied"] and report["violations"][0]["contact"] == "back_stop"
    assert "closes" in report["violations"][0]["what"]
    assert_same_solutions(pruned, full)
    stop = full.solutions[0].contact_force_time[:, 3]
    assert stop.max() > 0                              # it does carry load in the full solution
    # the default margin (0.5) keeps it nonlinear and still prunes the other two
    default = solve(scene(frequencies=[40.0, 70.0], back_gap=1.2e-4))
    assert decisions(default)["back_stop"] == "nonlinear"
    assert default.summary["contact_pruning"]["applied"]
    assert_same_solutions(default, full)


@pytest.mark.timeout(300)
def test_pruned_sweep_points_solve_the_full_equations():
    """A continuation on the pruned model follows the same curve (its adaptive points may sit at
    other ω): every restored point satisfies the full equations, evaluated independently."""
    from sarfe.hbm.residual import full_residual
    from sarfe.hbm.solve import make_problem

    data = scene(sweep=(35.0, 65.0))
    pruned = solve(data)
    report = pruned.summary["contact_pruning"]
    assert report["applied"] and decisions(pruned)["far_stop"] == "open"
    assert report["screened_frequencies"] > 200
    case = load_case(copy.deepcopy(data))
    nl = nonlinear_model(case, build_linear_model(case))
    problem = make_problem(nl.model, nl.contacts, nl.excitation, 7, 256)
    converged = [s for s in pruned.solutions if s.converged]
    assert len(converged) >= 0.9 * len(pruned.solutions) > 10
    for s in converged:
        ev = full_residual(problem, s.displacement.ravel(), s.omega, None, jacobian=False)
        assert np.linalg.norm(ev.residual) / ev.reference < 1e-6
        np.testing.assert_allclose(s.contact_force, ev.forces.force, rtol=0,
                                   atol=1e-6 * np.abs(ev.forces.force).max())
    # the first point (same ω in both) is identical
    full = solve(scene(sweep=(35.0, 65.0), prune=False))
    first, reference = pruned.solutions[0], full.solutions[0]
    assert first.omega == reference.omega
    np.testing.assert_allclose(first.displacement, reference.displacement, rtol=0,
                               atol=1e-6 * np.abs(reference.displacement).max())


def test_prune_contacts_key():
    from sarfe.case.errors import CaseError

    assert load_case(scene()).data["solver"]["prune_contacts"] is True
    data = scene()
    del data["solver"]["prune_contacts"]
    assert load_case(data).data["solver"]["prune_contacts"] is True
    for bad in ({"margin": 1.5}, {"margin": 0.5, "extra": 1}, "yes"):
        data["solver"]["prune_contacts"] = bad
        with pytest.raises(CaseError, match="prune_contacts"):
            load_case(copy.deepcopy(data))


def test_pruning_line():
    from sarfe.results.summary import pruning_line

    report = solve(scene(frequencies=[40.0])).summary["contact_pruning"]
    assert pruning_line(report) == "contacts: 2 of 3 solved linearly (far_stop open; clip closed)"
    assert pruning_line({"enabled": False, "contacts": []}) is None


def test_pruned_case_writes_all_outputs(tmp_path):
    """The restored solutions go through every writer; summary.json reports the decisions."""
    import json

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = solve_case(scene(frequencies=[50.0]), output_dir=tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["contact_pruning"]["applied"]
    assert [c["decision"] for c in summary["contact_pruning"]["contacts"]] == [
        "nonlinear", "open", "closed"]
    assert [c["name"] for c in summary["points"][0]["contacts"]] == ["panel_bracket", "far_stop",
                                                                      "clip"]
    assert result.exit_code == 0 and (tmp_path / "out" / "response.h5").exists()
