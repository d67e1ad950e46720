"""Lumped (matrices) cases end to end: closed forms in the linear limit, ERP bookkeeping, exit codes."""
from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest

from sarfe.cli import main
from sarfe.case.errors import CaseError
from sarfe.pipeline import build_linear_model, linear_model_key, load_case, solve_case

M, K, ZETA, F, GAP = 0.5, 2.0e4, 0.03, 2.0, 0.05
AREA, RHO, C = 0.04, 1.204, 343.2


def oscillator(frequencies, gap=GAP, **solver):
    """1-DOF m, k, modal ζ, force F at DOF 0; a rattle stop at `gap` (never reached if large)."""
    return {
        "name": "oscillator",
        "model": {"matrices": {"mass": [[M, 0.0], [0.0, 1.0]], "stiffness": [[K, 0.0], [0.0, 1.0e4]]}},
        "damping": {"modal_zeta": ZETA},
        "contacts": [{"name": "stop", "type": "rattle", "normal_dof": 0, "gap_m": gap,
                      "normal_stiffness_N_m": 1.0e6, "tolerance_m": 0.0}],
        "excitation": {"forces": [{"dof": 0, "force_N": F, "phase_deg": 30.0}],
                       "frequency_hz": frequencies},
        "solver": dict({"harmonics": 3, "samples_per_period": 64}, **solver),
        "erp": {"dofs": [0, 1], "areas_m2": [AREA, AREA]},
    }


def closed_form_amplitude(f):
    w = 2 * math.pi * f
    c = 2 * ZETA * math.sqrt(K * M)
    return F / abs(K - M * w * w + 1j * c * w)


def test_linear_limit_matches_closed_form(tmp_path):
    frequencies = [20.0, 31.8, 45.0]
    result = solve_case(oscillator(frequencies), output_dir=tmp_path / "out")
    assert result.exit_code == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["all_converged"] and summary["non_converged_points"] == []
    assert [p["frequency_hz"] for p in summary["points"]] == pytest.approx(frequencies)
    for point, solution in zip(summary["points"], result.solutions):
        f = point["frequency_hz"]
        X = closed_form_amplitude(f)
        U = np.asarray(solution.displacement)
        assert math.hypot(U[1, 0], U[2, 0]) == pytest.approx(X, rel=1e-6)
        assert np.abs(U[3:]).max() <= 1e-12 * X          # no higher harmonics: contact open
        stop = point["contacts"][0]
        assert stop["open_fraction"] == 1.0 and stop["peak_normal_force_N"] == 0.0
        assert stop["max_penetration_m"] == 0.0
        # ERP: ½ ρ c A (ω X)², only harmonic 1; DOF 1 is not excited so it adds nothing
        w = 2 * math.pi * f
        power = 0.5 * RHO * C * AREA * (w * X) ** 2
        assert point["erp"]["power_W"] == pytest.approx(power, rel=1e-6)
        assert point["erp"]["level_db"] == pytest.approx(10 * math.log10(power / 1e-12), rel=1e-9)
        assert point["erp"]["harmonics"]["power_W"][0] == pytest.approx(power, rel=1e-6)
        assert all(p <= 1e-20 * power for p in point["erp"]["harmonics"]["power_W"][1:])
        # the linear baseline is the same solution here
        assert point["linear"]["erp_power_W"] == pytest.approx(power, rel=1e-6)
        lin = point["linear"]["contacts"][0]
        assert lin["normal_amplitude_m"] == pytest.approx(X, rel=1e-6)
        assert lin["dynamic_tolerance_m"] == pytest.approx(GAP - X, rel=1e-6)
        assert lin["rattle_risk"] is False
    assert summary["sarfe_version"]
    assert set(summary["timings_s"]) >= {"linear_stage_s", "hbm_s", "outputs_s", "total_s"}
    assert (tmp_path / "out" / "response.h5").is_file()
    assert len(result.rows) == 3 and result.rows[0]["frequency_hz"] == pytest.approx(20.0)


def test_closing_gap_limits_amplitude_and_flags_risk():
    at_resonance = math.sqrt(K / M) / (2 * math.pi)
    gap = 0.2 * closed_form_amplitude(at_resonance)
    result = solve_case(oscillator([at_resonance], gap=gap), write=False)
    point = result.summary["points"][0]
    assert point["converged"]
    stop = point["contacts"][0]
    assert 0 < stop["open_fraction"] < 1 and stop["peak_normal_force_N"] > 0
    assert point["linear"]["contacts"][0]["rattle_risk"] is True
    # the stop (10^6 N/m ≫ k) caps the closing motion near the gap
    U = np.asarray(result.solutions[0].displacement)
    assert np.abs(U[1:, 0]).max() < closed_form_amplitude(at_resonance)
    assert stop["max_penetration_m"] < gap


def test_non_converged_point_gives_exit_code_3(tmp_path, capsys):
    import yaml
    at_resonance = math.sqrt(K / M) / (2 * math.pi)
    case = oscillator([at_resonance], gap=0.1 * closed_form_amplitude(at_resonance),
                      max_iterations=1, tolerance=1e-15)
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(case))
    code = main(["solve", str(path), "--output", str(tmp_path / "out"), "--quiet"])
    assert code == 3
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["exit_code"] == 3 and summary["non_converged_points"] == [0]
    assert summary["points"][0]["converged"] is False
    assert "did not converge" in capsys.readouterr().err


def test_linear_stage_key_and_pickle():
    case = load_case(oscillator([20.0]))
    stage = build_linear_model(case)
    assert pickle.loads(pickle.dumps(stage)).key == stage.key == linear_model_key(case)
    changed = oscillator([25.0])
    changed["contacts"][0]["gap_m"] = 0.07
    changed["excitation"]["forces"][0]["force_N"] = 5.0
    assert linear_model_key(changed) == stage.key         # law, amplitude, frequency: same stage
    changed["model"]["matrices"]["stiffness"][0][0] = 3.0e4
    assert linear_model_key(changed) != stage.key
    result = solve_case(oscillator([20.0]), linear_stage=stage, write=False)
    assert result.exit_code == 0


def test_shipped_lumped_case_cli(tmp_path, capsys):
    from pathlib import Path

    source = Path(__file__).resolve().parents[2] / "cases" / "lumped_rattle.yaml"
    text = source.read_text().replace("sweep: {start_hz: 30.0, end_hz: 90.0}",
                                      "frequency_hz: [50.0]")
    path = tmp_path / "lumped.yaml"
    path.write_text(text)
    assert main(["validate", str(source)]) == 0
    code = main(["solve", str(path), "--output", str(tmp_path / "res")])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "ERP [dB(A)]" in out and "results:" in out
    summary = json.loads((tmp_path / "res" / "summary.json").read_text())
    assert [c["name"] for c in summary["contacts"]] == ["panel_bracket", "seal"]
    seal = summary["points"][0]["contacts"][1]
    assert seal["peak_normal_force_N"] == pytest.approx(1.0)   # constant normal load
    assert seal["open_fraction"] == 0.0


def test_sweep_linear_limit_matches_closed_form():
    case = oscillator(20.0)
    del case["excitation"]["frequency_hz"]
    case["excitation"]["sweep"] = {"start_hz": 20.0, "end_hz": 40.0}
    result = solve_case(case, write=False)
    summary = result.summary
    assert summary["sweep_complete"] is True and result.exit_code == 0
    f = [p["frequency_hz"] for p in summary["points"]]
    assert f[0] == pytest.approx(20.0) and f[-1] == pytest.approx(40.0, abs=0.02)
    assert len(f) >= 5
    for point, solution in zip(summary["points"], result.solutions):
        U = np.asarray(solution.displacement)
        assert math.hypot(U[1, 0], U[2, 0]) == pytest.approx(
            closed_form_amplitude(point["frequency_hz"]), rel=1e-5)


def test_matrix_files_npz_mtx_npy(tmp_path):
    import scipy.io
    import scipy.sparse as sp

    np.savez(tmp_path / "model.npz", mass=np.diag([M, 1.0]), stiffness=np.diag([K, 1.0e4]))
    scipy.io.mmwrite(str(tmp_path / "k.mtx"), sp.csr_matrix(np.diag([K, 1.0e4])))
    sp.save_npz(tmp_path / "m_sparse.npz", sp.csr_matrix(np.diag([M, 1.0])))
    np.save(tmp_path / "k.npy", np.diag([K, 1.0e4]))
    reference = solve_case(oscillator([25.0]), write=False).summary["points"][0]["erp"]["power_W"]
    for mass, stiffness in (("model.npz", "model.npz"), ("m_sparse.npz", "k.mtx"),
                            ("model.npz", "k.npy")):
        case = oscillator([25.0])
        case["model"]["matrices"] = {"mass": mass, "stiffness": stiffness}
        case = load_case(case, base_dir=tmp_path)
        power = solve_case(case, write=False).summary["points"][0]["erp"]["power_W"]
        assert power == pytest.approx(reference, rel=1e-9)
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    case = oscillator([25.0])
    case["model"]["matrices"]["mass"] = "bad.npz"
    from sarfe.case.errors import CaseError
    with pytest.raises(CaseError, match=r"model.matrices.mass: cannot read matrix file"):
        build_linear_model(load_case(case, base_dir=tmp_path))


def test_rerun_replaces_results_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "res"
    solve_case(oscillator([20.0]), output_dir=target)
    (target / "notes.txt").write_text("the user's")      # not sarfe's: the re-run refuses
    with pytest.raises(CaseError, match="notes.txt"):
        solve_case(oscillator([21.0]), output_dir=target)
    assert (target / "notes.txt").read_text() == "the user's"
    (target / "notes.txt").unlink()
    solve_case(oscillator([21.0]), output_dir=target)
    assert json.loads((target / "summary.json").read_text())["points"][0]["frequency_hz"] == 21.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res"]
