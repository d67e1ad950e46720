"""output.target_dba exceeded → exit code 4 (documented in sarfe.cli and docs/case-file.md); met →
0. A rattle contact's dissipated energy is never negative beyond round-off (it was −1e-7 J: the
Parseval sum of a conservative penalty force's truncation error)."""
import json

import h5py

from sarfe.case.errors import EXIT_TARGET_EXCEEDED
from sarfe.cli import main
from tests.small_cases import TINY


def _solve(tmp_path, target_dba, force_N=1.0):
    case = tmp_path / f"t{target_dba}.yaml"
    case.write_text(TINY.replace("output: {files: [summary, table]}",
                                 f"output: {{files: [summary, table], target_dba: {target_dba}}}")
                    .replace("force_N: 1.0", f"force_N: {force_N}"))
    out = tmp_path / f"out{target_dba}"
    return main(["solve", str(case), "--output", str(out), "--quiet"]), out


def test_an_exceeded_target_exits_4_and_a_met_one_0(tmp_path):
    code, out = _solve(tmp_path, -50.0)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["worst"]["erp_level_dba"] > -50.0
    assert code == EXIT_TARGET_EXCEEDED == 4
    code, _ = _solve(tmp_path, 300.0)
    assert code == 0


def test_dissipated_energy_is_never_negative(tmp_path):
    _, out = _solve(tmp_path, 300.0, force_N=60.0)      # static 3 mm > the 1 mm gap: impacts
    summary = json.loads((out / "summary.json").read_text())
    assert max(c["max_penetration_m"] for p in summary["points"] for c in p["contacts"]) > 0
    energies = [c["dissipated_energy_J"] for p in summary["points"] for c in p["contacts"]
                if "dissipated_energy_J" in c]
    assert energies and min(energies) >= -1e-15 * max(1.0, max(abs(e) for e in energies))


def test_margins_reach_response_h5(tmp_path):
    """Onset factor, dynamic tolerance and sensitivities per point and contact are in response.h5
    (/margins) as in summary.json (issue 31 item 4: report, console, VTU and HDF5)."""
    case = tmp_path / "case.yaml"
    case.write_text(TINY.replace("force_N: 1.0", "force_N: 60.0").replace(
        "output: {files: [summary, table]}", "output: {files: [summary, response]}"))
    assert main(["solve", str(case), "--output", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    contact = summary["points"][0]["contacts"][0]
    with h5py.File(tmp_path / "out" / "response.h5", "r") as f:
        margins = f["margins"]
        assert margins["onset_factor"][0, 0] == contact["onset"]["factor"]
        assert margins["dynamic_tolerance_m"][0, 0] == \
            summary["points"][0]["linear"]["contacts"][0]["dynamic_tolerance_m"]
        names = [k for k in margins if "gap_m" in k]
        assert names, list(margins)
