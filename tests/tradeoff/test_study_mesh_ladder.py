"""``sarfe study --knobs mesh``: the mesh ladder on a small generated case (the rattle rig at 20 mm,
one frequency): four rungs 2h, h, h/√2, h/2, each rung's Richardson estimate from the next coarser
one (sarfe.tradeoff.study.mesh_ladder) in the table, the CSV and the JSON."""
import csv
import json
from pathlib import Path

import pytest
import yaml

from sarfe.accuracy.mesh_refinement import mesh_richardson
from sarfe.cli import main
from sarfe.pipeline import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.mark.timeout(300)
def test_study_mesh_ladder_runs_and_estimates_each_rung(tmp_path, capsys):
    data = load_case(CASES / "rattle_rig.yaml").with_generator(mesh_size_m=0.02).data
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [31.0]
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["study", str(path), "--knobs", "mesh", "--no-estimate", "--quiet",
                 "--output", str(tmp_path / "study")]) == 0
    out = capsys.readouterr().out
    assert "mesh ladder (Richardson from the next coarser rung, p = 1 stated)" in out
    rows = json.loads((tmp_path / "study" / "study.json").read_text())["rows"]
    assert [r["level"] for r in rows] == ["h=40mm", "h=20mm", "h=14.1mm", "h=10mm"]
    assert all(r["converged_points"] == 1 for r in rows)
    assert rows[0]["mesh_estimate_db"] is None                       # nothing coarser
    for coarser, rung in zip(rows, rows[1:]):
        ratio = coarser["value"] / rung["value"]
        expected = max(mesh_richardson(rung[k], coarser[k], ratio=ratio) for k in ("erp_db", "erp_dba"))
        assert rung["mesh_estimate_db"] == pytest.approx(expected, rel=1e-9)
    assert rows[-1]["mesh_estimate_covers"] is None                  # the reference rung
    for rung in rows[1:-1]:                                          # covers its error to 10 mm
        assert rung["mesh_estimate_covers"] is (
            rung["mesh_estimate_db"] >= max(rung["erp_db_error"], rung["erp_dba_error"]))
    with open(tmp_path / "study" / "study.csv") as handle:
        assert "mesh_estimate_db" in next(csv.reader(handle))
