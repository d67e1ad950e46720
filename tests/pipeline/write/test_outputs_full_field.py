"""Full-field recovery for the VTU maps of a sweep stays bounded: beyond the cost budget only the
loudest point's map carries the nodal displacement (the others keep every ERP array), and that
map equals the one written with the budget unlimited."""
from pathlib import Path

import numpy as np
import pytest

from sarfe.pipeline import load_case, solve_case

CASES = Path(__file__).resolve().parents[3] / "cases"


def _maps(tmp_path, name, budget, monkeypatch):
    import pyvista

    import sarfe.pipeline.write.result_files as outputs

    monkeypatch.setattr(outputs, "FULL_FIELD_BUDGET", budget)
    data = load_case(CASES / "rattle_rig.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.02
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [31.0, 20.0, 26.0]
    data["solver"].update(error_estimate=False, stability=False)
    data["output"].update(files=["summary", "erp_vtu"], maps={"every": 1})   # a map per point
    result = solve_case(data, output_dir=tmp_path / name)
    files = sorted((tmp_path / name / "erp").glob("erp_*.vtu"))
    return result.summary["worst"]["index"], [pyvista.read(f).point_data for f in files]


def test_full_field_only_at_the_loudest_point_beyond_the_budget(tmp_path, monkeypatch):
    loudest, every = _maps(tmp_path, "all", 1e30, monkeypatch)
    _, bounded = _maps(tmp_path, "bounded", 0.0, monkeypatch)
    assert loudest is not None and len(every) == len(bounded) == 3
    for j, (a, b) in enumerate(zip(every, bounded)):
        np.testing.assert_allclose(b["erp_density_W_m2"], a["erp_density_W_m2"], rtol=1e-9,
                                   atol=1e-30)
        assert np.abs(a["displacement_amplitude_m"]).max() > 0
        if j == loudest:
            np.testing.assert_allclose(b["displacement_amplitude_m"], a["displacement_amplitude_m"],
                                       rtol=1e-12, atol=0)
        else:
            assert np.abs(b["displacement_amplitude_m"]).max() == 0.0
