"""``sarfe study`` end to end on a tiny matrices case (one knob at a time, files, accuracy choice)."""
import csv
import json

import numpy as np
import pytest
import yaml

from sarfe.cli import main
from sarfe.tradeoff.study import knob_levels, run_study, study_table, variant_case

CASE = {
    "name": "tiny_rattle",
    "model": {"matrices": {"mass": [[1.0, 0.0], [0.0, 1.0]],
                           "stiffness": [[1.1e5, -1.0e5], [-1.0e5, 1.1e5]]}},
    "damping": {"modal_zeta": 0.02},
    "contacts": [{"name": "stop", "type": "rattle", "normal_dof": {"dof": 0}, "gap_m": 1.0e-3,
                  "normal_stiffness_N_m": 1.0e5, "tolerance_m": 1.0e-4}],
    "excitation": {"forces": [{"dof": 0, "force_N": 10.0}], "frequency_hz": [12.0, 16.0]},
    "solver": {"harmonics": 4, "samples_per_period": 64},
    "erp": {"dofs": [0], "areas_m2": [0.05]},
}


@pytest.fixture()
def case_file(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(CASE))
    return path


def test_variant_case_changes_one_knob(case_file):
    from sarfe.pipeline import build_linear_model, load_case

    case = load_case(case_file)
    levels = knob_levels(case, build_linear_model(case))
    assert set(levels) == {"harmonics", "samples", "penalty"}     # matrices case: no modes / mesh
    assert [v for _, v in levels["harmonics"]] == [2, 4, 8, 16]
    v = variant_case(case, "harmonics", 16)
    assert v.data["solver"]["harmonics"] == 16 and v.data["solver"]["samples_per_period"] >= 65
    v = variant_case(case, "penalty", 3.0)
    assert v.data["contacts"][0]["normal_stiffness_N_m"] == pytest.approx(3.0e5)
    assert case.data["contacts"][0]["normal_stiffness_N_m"] == pytest.approx(1.0e5)


@pytest.mark.timeout(300)
def test_run_study_errors_and_files(tmp_path, case_file):
    result = run_study(case_file, knobs=["harmonics", "samples"], output_dir=tmp_path / "out")
    rows = result.rows
    assert len(rows) == 8
    for knob in ("harmonics", "samples"):
        sub = [r for r in rows if r["knob"] == knob]
        assert sub[-1]["amplitude_rel_error"] == 0.0 and sub[-1]["erp_db_error"] == 0.0
        assert all(r["converged_points"] == 2 for r in sub)
        assert sum(r["baseline"] for r in sub) == 1
        assert all(r["wall_s"] > 0 and r["peak_memory_MB"] > 0 for r in sub)
    h = [r for r in rows if r["knob"] == "harmonics"]
    # truncation error falls with H and the estimate bounds it
    assert h[0]["amplitude_rel_error"] > h[2]["amplitude_rel_error"]
    for r in h[:-1]:
        assert r["amplitude_rel_error"] <= r["estimate_amplitude_rel"] + 1e-12
    files = result.files
    with open(files["csv"]) as handle:
        assert len(list(csv.DictReader(handle))) == 8
    data = json.loads(open(files["json"]).read())
    assert data["case"] == "tiny_rattle" and len(data["rows"]) == 8
    assert open(files["pareto_png"], "rb").read(8).startswith(b"\x89PNG")
    text = study_table(rows)
    assert "harmonics" in text and "*H=4" in text


@pytest.mark.timeout(300)
def test_cli_study_and_accuracy(tmp_path, case_file, capsys):
    code = main(["study", str(case_file), "--knobs", "penalty", "-o", str(tmp_path / "s"),
                 "--quiet", "--no-estimate"])
    assert code == 0
    out = capsys.readouterr().out
    assert "k×10" in out and (tmp_path / "s" / "study_pareto.png").exists()
    code = main(["study", str(case_file), "--accuracy", "fast"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "H = " in out and "met" in out
    assert main(["study", str(case_file), "--knobs", "bogus"]) == 2
    assert main(["study", str(case_file), "--accuracy", "medium"]) == 2


@pytest.mark.timeout(300)
def test_resolve_case_accuracy_finer_target_needs_more(case_file):
    from sarfe.case.read import load_case
    from sarfe.pipeline.solve.case_accuracy import resolve_case_accuracy, resolved_case

    fast = resolve_case_accuracy(case_file, "fast", points=2)
    fine = resolve_case_accuracy(case_file, "fine", points=2)
    assert fast["met"] and fine["met"]
    assert fine["harmonics"] >= fast["harmonics"] and fine["harmonics"] > 3
    case = resolved_case(load_case(case_file), fine)
    assert case.config.solver.harmonics == fine["harmonics"]
    assert case.data["solver"]["harmonics"] == fine["harmonics"]
    assert np.isfinite(fine["estimate"]["amplitude_rel"])
