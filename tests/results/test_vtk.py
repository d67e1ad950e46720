"""VTU/PVD files read back with pyvista: array names, shapes, values, no NaN, collections."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from sarfe.erp import equivalent_radiated_power, nodal_areas, nodal_normals, normal_displacement
from sarfe.results import (
    contact_markers,
    erp_point_data,
    write_deflection_animation,
    write_erp_sweep,
    write_erp_vtu,
    write_pvd,
)


def plate(nx=4, ny=3):
    x, y = np.meshgrid(np.linspace(0, 0.4, nx + 1), np.linspace(0, 0.3, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(points.shape[0]).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return points, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def harmonic_field(points, H=2):
    U = np.zeros((2 * H + 1, points.shape[0], 3))
    shape = np.sin(np.pi * points[:, 0] / 0.4) * np.sin(np.pi * points[:, 1] / 0.3)
    U[0, :, 2] = 1e-5                   # static sag (not part of the amplitude)
    U[1, :, 2] = 2e-6 * shape           # cos θ
    U[4, :, 2] = 1e-6 * shape           # sin 2θ
    U[2, :, 0] = 5e-7                   # in-plane sin θ
    return U


def test_erp_vtu_reads_back(tmp_path):
    points, triangles = plate()
    n = points.shape[0]
    U = harmonic_field(points)
    W = normal_displacement(U, nodal_normals(points, triangles))
    omega = 2 * np.pi * 120.0
    radiating = np.arange(n)
    erp = equivalent_radiated_power(W, omega, nodal_areas(points, triangles))
    data = erp_point_data(n, erp, W, omega, displacement=U, radiating_nodes=radiating,
                          contact_marker=contact_markers(n, [[0], [5, 6]]))
    path = write_erp_vtu(tmp_path / "erp.vtu", points, triangles, data)
    mesh = pv.read(path)
    assert mesh.n_points == n and mesh.n_cells == triangles.shape[0]
    np.testing.assert_allclose(mesh.points, points)
    expected = {"erp_density_W_m2", "erp_density_h1_W_m2", "erp_density_h2_W_m2",
                "normal_velocity_amplitude_m_s", "normal_displacement_amplitude_m",
                "displacement_amplitude_m", "contact_marker"}
    assert expected <= set(mesh.point_data.keys())
    for name in expected:
        assert not np.any(np.isnan(mesh.point_data[name]))
    assert mesh.point_data["displacement_amplitude_m"].shape == (n, 3)
    assert np.issubdtype(mesh.point_data["contact_marker"].dtype, np.integer)
    np.testing.assert_array_equal(np.flatnonzero(mesh.point_data["contact_marker"]), [0, 5, 6])
    assert mesh.point_data["contact_marker"][6] == 2
    np.testing.assert_allclose(mesh.point_data["erp_density_W_m2"], erp.density_total)
    np.testing.assert_allclose(mesh.point_data["erp_density_W_m2"],
                               mesh.point_data["erp_density_h1_W_m2"]
                               + mesh.point_data["erp_density_h2_W_m2"])
    # e = ½ρc v², v the root-sum-square velocity amplitude
    v = mesh.point_data["normal_velocity_amplitude_m_s"]
    np.testing.assert_allclose(mesh.point_data["erp_density_W_m2"], 0.5 * 1.204 * 343.2 * v**2)
    # amplitude of u_x = 5e-7 (pure sine), u_z: max over θ of |2 cos θ + sin 2θ|·1e-6·shape
    amp = mesh.point_data["displacement_amplitude_m"]
    np.testing.assert_allclose(amp[:, 0], 5e-7, rtol=1e-12)
    theta = np.linspace(0, 2 * np.pi, 100001)
    peak = np.abs(2 * np.cos(theta) + np.sin(2 * theta)).max()
    shape = U[1, :, 2] / 2e-6
    np.testing.assert_allclose(amp[:, 2], 1e-6 * peak * np.abs(shape), rtol=2e-3, atol=1e-15)
    # flat plate in z: normal amplitude = |u_z| amplitude
    np.testing.assert_allclose(mesh.point_data["normal_displacement_amplitude_m"], amp[:, 2],
                               rtol=2e-3, atol=1e-15)


def test_vtu_zeroes_nan_and_rejects_bad_shapes(tmp_path):
    points, triangles = plate(1, 1)
    with pytest.warns(RuntimeWarning, match="non-finite"):
        path = write_erp_vtu(tmp_path / "x.vtu", points, triangles,
                             {"a": np.array([np.nan, 1.0, np.inf, 2.0])})
    np.testing.assert_array_equal(pv.read(path).point_data["a"], [0.0, 1.0, 0.0, 2.0])
    with pytest.raises(ValueError, match="point_data"):
        write_erp_vtu(tmp_path / "x.vtu", points, triangles, {"a": np.zeros(3)})


def test_pvd_lists_files_and_sweep(tmp_path):
    points, triangles = plate(2, 2)
    n = points.shape[0]
    datasets = [{"erp_density_W_m2": np.full(n, float(j))} for j in range(3)]
    pvd = write_erp_sweep(tmp_path / "vtk", points, triangles, datasets, [100.0, 150.0, 200.0])
    entries = ET.parse(pvd).getroot().findall("./Collection/DataSet")
    assert [e.get("file") for e in entries] == ["erp_0000.vtu", "erp_0001.vtu", "erp_0002.vtu"]
    assert [float(e.get("timestep")) for e in entries] == [100.0, 150.0, 200.0]
    for e in entries:
        assert (pvd.parent / e.get("file")).is_file()
    reader = pv.get_reader(str(pvd))
    np.testing.assert_allclose(reader.time_values, [100.0, 150.0, 200.0])
    reader.set_active_time_value(150.0)
    mesh = reader.read()[0]
    np.testing.assert_allclose(mesh.point_data["erp_density_W_m2"], 1.0)
    assert mesh.field_data["frequency_hz"][0] == 150.0 and mesh.field_data["point_index"][0] == 1
    # a continuation through a fold visits 150 Hz twice: time = point index, frequency in field data
    fold = write_erp_sweep(tmp_path / "fold", points, triangles, datasets * 2,
                           [100.0, 150.0, 200.0, 180.0, 150.0, 220.0])
    reader = pv.get_reader(str(fold))
    np.testing.assert_allclose(reader.time_values, np.arange(6))
    reader.set_active_time_value(4)
    assert reader.read()[0].field_data["frequency_hz"][0] == 150.0
    # plain write_pvd with files in a subfolder stays relative
    other = write_pvd(tmp_path / "vtk" / "all.pvd", [(0.0, "sub/a.vtu")])
    assert 'file="sub/a.vtu"' in other.read_text()


def test_deflection_animation_over_one_period(tmp_path):
    points, triangles = plate()
    n = points.shape[0]
    U = harmonic_field(points)
    omega = 2 * np.pi * 50.0
    pvd = write_deflection_animation(tmp_path / "anim", points, triangles, U, n_frames=12,
                                     omega=omega, point_data={"contact_marker": np.zeros(n, int)})
    reader = pv.get_reader(str(pvd))
    times = np.asarray(reader.time_values)
    assert times.size == 12
    np.testing.assert_allclose(times, np.arange(12) / 12 / 50.0)
    for j in (0, 3, 7):
        reader.set_active_time_value(times[j])
        mesh = reader.read()[0]
        u = mesh.point_data["displacement_m"]
        assert u.shape == (n, 3) and not np.any(np.isnan(u))
        theta = 2 * np.pi * j / 12
        expected = U[0] + U[1] * np.cos(theta) + U[2] * np.sin(theta) \
            + U[3] * np.cos(2 * theta) + U[4] * np.sin(2 * theta)
        np.testing.assert_allclose(u, expected, atol=1e-18)
        np.testing.assert_allclose(mesh.point_data["displacement_magnitude_m"],
                                   np.linalg.norm(expected, axis=1), atol=1e-18)
        assert "contact_marker" in mesh.point_data
        assert mesh.point_data.active_vectors_name == "displacement_m"
        assert mesh.field_data["phase_rad"][0] == pytest.approx(2 * np.pi * j / 12)
    # without omega the "time" is the period fraction
    pvd2 = write_deflection_animation(tmp_path / "anim2", points, triangles, U, n_frames=4)
    np.testing.assert_allclose(pv.get_reader(str(pvd2)).time_values, [0, 0.25, 0.5, 0.75])
