"""The new arrays of the result files: contributions, contact dynamics and bands in response.h5
(consistent with summary.json), and the dB map / contact arrays of the VTU."""
import json

import numpy as np
import pytest

from sarfe.results import read_response_h5
from sarfe.results.vtk import contact_point_values, erp_level_db_m2
from sarfe.pipeline import solve_case


def test_response_h5_holds_contributions_dynamics_and_bands(lumped_case, tmp_path):
    solve_case(lumped_case, output_dir=tmp_path / "out")
    data = read_response_h5(tmp_path / "out" / "response.h5")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    c = data["contributions"]
    assert list(c["source_names"]) == ["excitation", "panel_bracket", "seal"]
    assert np.allclose(np.nansum(c["share_a"], axis=1), 1.0, atol=1e-9)
    assert np.all(c["superposition_error"] < 1e-8)
    for i, p in enumerate(summary["points"]):
        sources = p["contributions"]["sources"]
        assert c["share_a"][i] == pytest.approx([s["share_a"] for s in sources])
        # band powers of each point add up to its total ERP, linear baseline to its own
        assert data["bands"]["nonlinear_power_W"][i].sum() == pytest.approx(p["erp"]["power_W"],
                                                                            rel=1e-9)
        assert data["bands"]["linear_power_W"][i].sum() == pytest.approx(
            p["linear"]["erp_power_W"], rel=1e-9)
    # names and units: A-weighted band levels say dB(A); the ERP levels in dB(A) also under names
    # ending in their unit (the *_a_db names kept for existing scripts, the same data)
    import h5py

    with h5py.File(tmp_path / "out" / "response.h5", "r") as f:
        assert f["bands/nonlinear_level_dba"].attrs["units"] == "dB(A) re 1e-12 W"
        assert f["bands/linear_level_dba"].attrs["units"] == "dB(A) re 1e-12 W"
        assert f["bands/nonlinear_level_db"].attrs["units"] == "dB re 1e-12 W"
        assert f["erp/level_total_dba"].attrs["units"] == "dB(A) re 1e-12 W"
    assert np.array_equal(data["erp"]["level_total_dba"], data["erp"]["level_total_a_db"])
    assert np.array_equal(data["erp"]["level_dba"], data["erp"]["level_a_db"])
    assert data["erp"]["level_total_dba"] == pytest.approx(
        [p["erp"]["level_dba"] for p in summary["points"]])
    d = data["contact_dynamics"]
    assert list(d["contact_names"]) == ["panel_bracket", "seal"]
    assert d["impacts_per_period"].shape == (5, 2)
    assert np.all(d["impacts_per_period"][:, 1] == 0)                  # the seal never lifts off
    assert np.all(d["slip_distance_m"][:, 1] >= 0)


def test_vtu_level_array_and_contact_fields():
    density = np.array([0.0, 1e-12, 1e-6, 1e-3])
    level = erp_level_db_m2(density)
    assert level[3] == pytest.approx(90.0) and level[2] == pytest.approx(60.0)
    assert level[1] == pytest.approx(90.0 - 60.0) and level[0] == pytest.approx(30.0)  # floored
    assert np.all(erp_level_db_m2(np.zeros(3)) == 0.0)
    values = contact_point_values(6, [0, 2], [5, -1], [3.0, 4.0])
    assert list(values) == [3.0, 0.0, 4.0, 0.0, 0.0, 3.0]
