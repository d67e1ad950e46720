"""Shipped cases: every file validates; the FE rigs run end to end (coarse meshes)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from sarfe.cli import main
from sarfe.pipeline import load_case, solve_case

CASES = Path(__file__).resolve().parents[1] / "cases"
SHIPPED = ["lumped_rattle", "rattle_rig", "squeak_rig", "door_trim", "instrument_panel"]


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_case_passes_schema(name):
    case = load_case(CASES / f"{name}.yaml")
    assert case.name == name
    assert case.data["output"]["directory"] == f"results/{name}"


@pytest.mark.parametrize("name", ["rattle_rig", "squeak_rig"])
def test_rig_validates_with_mesh(name, capsys):
    assert main(["validate", str(CASES / f"{name}.yaml")]) == 0
    assert "valid" in capsys.readouterr().out


def test_rattle_rig_end_to_end(tmp_path):
    """Coarse rattle rig at two frequencies: the striker closes its gap near the strip resonance,
    and only through the contact does the plate (the radiating skin) move."""
    data = load_case(CASES / "rattle_rig.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.02
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [31.0, 20.0]
    data["output"]["files"] = ["summary", "response", "erp_vtu", "table"]
    result = solve_case(data, output_dir=tmp_path / "rig")
    summary = json.loads((tmp_path / "rig" / "summary.json").read_text())
    assert summary["model"]["kind"] == "fe" and summary["model"]["modes"] >= 10
    assert summary["model"]["boundary_dofs"] == 9            # striker, plate node, load point
    assert (tmp_path / "rig" / "erp" / "erp.pvd").is_file()
    # full-field recovery (Craig–Bampton basis) agrees with the ERP normal-velocity basis: on the
    # flat plate (normal z) the z amplitude of the displacement is the normal amplitude
    import pyvista

    vtu = pyvista.read(sorted((tmp_path / "rig" / "erp").glob("erp_*.vtu"))[0])
    radiating = vtu.point_data["erp_density_W_m2"] > 0
    assert radiating.sum() > 10
    np.testing.assert_allclose(vtu.point_data["displacement_amplitude_m"][radiating, 2],
                               vtu.point_data["normal_displacement_amplitude_m"][radiating],
                               rtol=1e-6, atol=1e-12)
    assert (tmp_path / "rig" / "response.h5").is_file()
    near, far = summary["points"]
    tip_near, tip_far = near["contacts"][0], far["contacts"][0]
    if near["converged"]:
        assert tip_near["open_fraction"] < 1.0 and tip_near["peak_normal_force_N"] > 0
        # linear baseline: no contact → the plate hardly moves; with contact it radiates
        assert near["erp"]["level_db"] > near["linear"]["erp_level_db"] + 40
        assert near["linear"]["contacts"][0]["rattle_risk"] is True
    if far["converged"]:
        assert tip_far["open_fraction"] == 1.0 and tip_far["peak_normal_force_N"] == 0.0
    assert result.exit_code == (0 if summary["all_converged"] else 3)
    gap = 0.5e-3
    assert near["linear"]["contacts"][0]["dynamic_tolerance_m"] == pytest.approx(
        gap - 1e-4 - near["linear"]["contacts"][0]["normal_amplitude_m"], rel=1e-3)


def test_verify_lumped_linear_limit(tmp_path, capsys):
    path = tmp_path / "osc.yaml"
    path.write_text("""\
name: osc
model:
  matrices: {mass: [[0.5]], stiffness: [[2.0e4]]}
damping: {modal_zeta: 0.05}
contacts:
  - {name: stop, type: rattle, normal_dof: 0, gap_m: 1.0, normal_stiffness_N_m: 1.0e5}
excitation:
  forces: [{dof: 0, force_N: 1.0}]
  frequency_hz: 25.0
solver: {harmonics: 3, samples_per_period: 64}
""")
    code = main(["verify", str(path), "--frequency-hz", "25", "--quiet"])
    out = capsys.readouterr().out
    assert "HBM" in out and "time int." in out
    assert code == 0, out
    w = 2 * math.pi * 25.0
    X = 1.0 / abs(2.0e4 - 0.5 * w * w + 2j * 0.05 * math.sqrt(2.0e4 * 0.5) * w)
    assert f"{X:11.4e}".strip() in out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["door_trim", "squeak_rig", "instrument_panel"])
def test_shipped_fe_case_runs(name, tmp_path):
    result = solve_case(load_case(CASES / f"{name}.yaml"), output_dir=tmp_path / name)
    assert result.exit_code in (0, 3)
    summary = result.summary
    assert len(summary["points"]) >= 1
    assert all(np.isfinite(p["erp"]["power_W"]) for p in summary["points"])


def test_fe_contact_geometry_pairs_ground_and_normal():
    """Nearest-node pairing: normal from striker to plate (−z), default gap = geometric 0.5 mm;
    a grounded contact with an explicit normal; explicit node pairs give the same rows."""
    from sarfe.pipeline import build_linear_model, nonlinear_model

    data = load_case(CASES / "rattle_rig.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.03
    data["reduction"] = {"mode_count": 4}
    stage = build_linear_model(data)
    tip = stage.contacts["tip"]
    assert tip.frames[0, 0] == pytest.approx([0.0, 0.0, -1.0], abs=1e-9)
    nl = nonlinear_model(data, stage)
    assert nl.contacts.gap[0] == pytest.approx(0.5e-3, rel=1e-9)

    grounded = dict(data["contacts"][0], name="tip_ground", between=["contact_tip_a", "ground"],
                    normal=[0, 0, -2], gap_m=1e-3)
    explicit = dict(data["contacts"][0], name="tip_pairs",
                    pairs=[[int(tip.nodes_a[0]), int(tip.nodes_b[0])]])
    del explicit["between"]
    data["contacts"] += [grounded, explicit]
    stage = build_linear_model(data)
    nl = nonlinear_model(data, stage)
    G = nl.contacts.gap_map.toarray()
    assert np.all(stage.contacts["tip_ground"].coords_b == -1)
    np.testing.assert_allclose(G[2], G[0])                  # explicit pair = nearest-node pair
    assert nl.contacts.gap.tolist() == pytest.approx([0.5e-3, 1e-3, 0.5e-3])
    # the grounded row measures only the striker: w = −u_z(striker)
    assert np.count_nonzero(G[1]) == 1 and G[1].min() == pytest.approx(-1.0)
