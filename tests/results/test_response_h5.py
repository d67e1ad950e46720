"""response.h5 round trip: every dataset back with its shape, values, units and convention."""
import dataclasses
from types import SimpleNamespace

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.erp import equivalent_radiated_power
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.harmonics import time_samples
from sarfe.results import plot_erp_sweep, read_response_h5, write_response_h5

READ_FIELDS = {"omega", "harmonics", "samples_per_period", "displacement", "contact_displacement",
               "contact_force", "contact_force_time", "contact_state", "converged", "reason",
               "iterations", "residual_norm", "friction_passes", "stable", "floquet_exponent"}


def fake_sweep(n_f=4, H=3, N=32, n_dof=12, seed=0):
    rng = np.random.default_rng(seed)
    sols = []
    for j in range(n_f):
        force = rng.normal(size=(2 * H + 1, 3))
        sols.append(SimpleNamespace(
            omega=2 * np.pi * (50.0 + 10 * j), harmonics=H, samples_per_period=N,
            displacement=rng.normal(size=(2 * H + 1, n_dof)) * 1e-5,
            contact_displacement=rng.normal(size=(2 * H + 1, 3)) * 1e-5,
            contact_force=force, contact_force_time=time_samples(force, N),
            contact_state=rng.integers(0, 3, size=(N, 2)).astype(np.int8),
            converged=True, reason="converged", iterations=5 + j, residual_norm=1e-10,
            friction_passes=2, stable=[True, False, None, True][j % 4],
            floquet_exponent=[-1.0, 2.5, float("nan"), -0.5][j % 4]))
    return sols


def contact_set(n_dof=12):
    G = sp.csr_matrix((np.ones(3), ([0, 1, 2], [2, 3, 8])), shape=(3, n_dof))
    return make_contact_set(G, ["rattle", "squeak"], [0, -1], [[-1, -1], [1, 2]],
                            gap=[1e-3, 0.0], normal_stiffness=[1e5, 0.0],
                            tangential_stiffness=[0.0, 1e4], friction_coefficient=[0.0, 0.3],
                            normal_load=[0.0, 10.0], names=["clip_1", "felt_pad"])


def test_attributes_read_match_harmonic_solution_fields():
    solution = pytest.importorskip("sarfe.hbm.solution")
    fields = {f.name for f in dataclasses.fields(solution.HarmonicSolution)}
    assert READ_FIELDS <= fields


def test_round_trip(tmp_path):
    sols = fake_sweep()
    H, N = 3, 32
    excitation = np.zeros((2 * H + 1, 12))
    excitation[1, [4, 7]] = [1.0, -2.0]
    areas = np.full(5, 0.01)
    erps = [equivalent_radiated_power(s.displacement[:, :5], s.omega, areas) for s in sols]
    linear = np.stack([s.contact_displacement[:3] for s in sols])
    path = write_response_h5(
        tmp_path / "response.h5", sols, contacts=contact_set(), excitation=excitation,
        boundary_dofs=[2, 3, 8], mode_frequencies_hz=[101.0, 250.0], erp=erps,
        radiating_nodes=np.arange(5), store_displacement=True, store_erp_density_per_harmonic=True,
        extra_groups={"linear": {"contact_displacement_m": (linear, "m")}},
        attributes={"case": "unit", "model_key": "abc123"})
    data = read_response_h5(path)
    attrs = data["attrs"]
    assert attrs["format"] == "sarfe-response" and attrs["format_version"] == 3
    assert attrs["harmonics"] == H and attrs["samples_per_period"] == N
    assert "u0" in attrs["fourier_convention"] and attrs["case"] == "unit"
    np.testing.assert_allclose(data["frequency_hz"], [50, 60, 70, 80])
    np.testing.assert_allclose(data["omega_rad_s"], 2 * np.pi * data["frequency_hz"])
    np.testing.assert_array_equal(data["status"]["stable"], [1, 0, -1, 1])
    np.testing.assert_array_equal(data["status"]["iterations"], [5, 6, 7, 8])
    assert data["status"]["reason"][0] == "converged"
    c = data["contacts"]
    assert list(c["names"]) == ["clip_1", "felt_pad"] and list(c["kind"]) == ["rattle", "squeak"]
    np.testing.assert_array_equal(c["tangent_rows"], [[-1, -1], [1, 2]])
    assert c["displacement_m"].shape == (4, 2 * H + 1, 3)
    assert c["force_time_N"].shape == (4, N, 3) and c["state"].shape == (4, N, 2)
    for j, s in enumerate(sols):
        np.testing.assert_array_equal(c["force_N"][j], s.contact_force)
        np.testing.assert_array_equal(c["state"][j], s.contact_state)
        np.testing.assert_array_equal(data["displacement_m"][j], s.displacement)
        np.testing.assert_array_equal(data["excitation"]["displacement_m"][j],
                                      s.displacement[:, [4, 7]])
    np.testing.assert_array_equal(data["excitation"]["dofs"], [4, 7])
    np.testing.assert_array_equal(data["excitation"]["force_N"], excitation[:, [4, 7]])
    np.testing.assert_array_equal(data["reduction"]["boundary_dofs"], [2, 3, 8])
    e = data["erp"]
    assert e["power_W"].shape == (4, H) and e["density_W_m2"].shape == (4, H, 5)
    np.testing.assert_allclose(e["level_total_db"], [r.level_total_db for r in erps])
    np.testing.assert_allclose(e["power_total_W"], e["power_W"].sum(axis=1))
    np.testing.assert_array_equal(data["linear"]["contact_displacement_m"], linear)
    with h5py.File(path) as f:
        assert f["contacts/force_N"].attrs["units"] == "N"
        assert f["erp/level_db"].attrs["units"].startswith("dB")
    # re-plot from the file alone, no re-solve
    png = plot_erp_sweep(tmp_path / "replot.png", data["frequency_hz"], e["level_total_db"],
                         stable=[None if s < 0 else bool(s) for s in data["status"]["stable"]])
    assert png.stat().st_size > 1000


def test_minimal_and_validation(tmp_path):
    sols = fake_sweep(n_f=1)
    data = read_response_h5(write_response_h5(tmp_path / "r.h5", sols))
    assert data["contacts"]["force_N"].shape == (1, 7, 3)
    assert "erp" not in data
    with pytest.raises(ValueError, match="H and N"):
        write_response_h5(tmp_path / "bad.h5", fake_sweep(1) + fake_sweep(1, H=2))
    with pytest.raises(ValueError, match="empty"):
        write_response_h5(tmp_path / "bad.h5", [])
