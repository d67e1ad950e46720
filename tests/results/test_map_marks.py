"""What an ERP map tells a user who opens it (issue 31, item 6): points off the ERP surface are
NaN in the dB map (ParaView's NaN colour), not the colour of silence, and flagged by
``radiating``; every triangle carries its part (cell data ``part_id``, names in ``part_names``);
the dB map is the active scalars; PVD times are rounded (30, not 29.999999999999996)."""
import re
import warnings

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from small_cases import coarse_rig

from sarfe.cli import main
from sarfe.erp import equivalent_radiated_power, nodal_areas, nodal_normals, normal_displacement
from sarfe.mesh.cache import cached_mesh
from sarfe.results.vtk import erp_point_data, part_ids, write_erp_vtu, write_pvd


def two_parts(nx=4, ny=3):
    """A 0.4 × 0.3 m plate (z = 0, element group part_plate) and a 0.4 m strip beside it at
    x = 0.5 … 0.9 (part_strip); the ERP surface is the plate."""
    x, y = np.meshgrid(np.linspace(0, 0.4, nx + 1), np.linspace(0, 0.3, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(points.shape[0]).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    plate = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    strip = points[:2 * (ny + 1)] + [0.5, 0.0, 0.0]
    s = np.arange(strip.shape[0]).reshape(2, ny + 1) + points.shape[0]
    sa, sb, sc, sd = s[0, :-1], s[1, :-1], s[1, 1:], s[0, 1:]
    strip_tri = np.concatenate([np.column_stack([sa, sb, sc]), np.column_stack([sa, sc, sd])])
    groups = {"part_plate": np.arange(len(plate)),
              "part_strip": len(plate) + np.arange(len(strip_tri)),
              "skin": np.arange(len(plate))}
    return np.vstack([points, strip]), np.vstack([plate, strip_tri]), groups, points.shape[0]


def plate_map(tmp_path):
    points, triangles, groups, n_plate = two_parts()
    plate_nodes = np.arange(n_plate)
    shape = np.sin(np.pi * points[plate_nodes, 0] / 0.4) * np.sin(np.pi * points[plate_nodes, 1] / 0.3)
    W = np.zeros((5, n_plate))
    W[1] = 2e-6 * shape                                   # cos θ, normal displacement [m]
    omega = 2 * np.pi * 120.0
    erp = equivalent_radiated_power(W, omega, nodal_areas(points, triangles)[plate_nodes])
    data = erp_point_data(points.shape[0], erp, W, omega, radiating_nodes=plate_nodes)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                    # the NaN off the surface is no slip
        path = write_erp_vtu(tmp_path / "erp.vtu", points, triangles, data,
                             parts=part_ids(len(triangles), groups))
    return path, erp, n_plate, points, triangles, groups


def test_points_off_the_surface_are_nan_not_silence(tmp_path):
    path, erp, n_plate, points, _, _ = plate_map(tmp_path)
    grid = pv.read(path)
    level = np.asarray(grid.point_data["erp_level_db_m2"])
    radiating = np.asarray(grid.point_data["radiating"])
    assert np.array_equal(radiating, np.arange(points.shape[0]) < n_plate)
    assert np.isnan(level[n_plate:]).all()                # the strip: no level at all
    on = level[:n_plate]
    assert np.isfinite(on).all()
    # 10 log10(e / 1 pW/m²), floored at max − 60 dB: the plate's still edges (sin · sin ≈ 0)
    # sit on the floor, coloured as silence — they are on the surface
    with np.errstate(divide="ignore"):
        exact = 10 * np.log10(np.asarray(erp.density_total) / 1e-12)
    np.testing.assert_allclose(on, np.maximum(exact, exact.max() - 60.0), rtol=0, atol=1e-9)
    assert np.count_nonzero(np.isclose(on, on.max() - 60.0)) > 0
    assert np.all(np.asarray(grid.point_data["erp_density_W_m2"])[n_plate:] == 0.0)


def test_the_db_map_is_the_active_scalars(tmp_path):
    path = plate_map(tmp_path)[0]
    assert pv.read(path).active_scalars_name == "erp_level_db_m2"
    header = path.read_bytes().split(b"<AppendedData", 1)[0].decode()
    assert re.search(r'<PointData[^>]*Scalars="erp_level_db_m2"', header), header[:400]


def test_every_triangle_carries_its_part(tmp_path):
    path, _, _, _, triangles, groups = plate_map(tmp_path)
    grid = pv.read(path)
    ids = np.asarray(grid.cell_data["part_id"])
    names = str(grid.field_data["part_names"][0]).split(",")
    assert names == ["part_plate", "part_strip"]          # skin is no part: part_* only
    for k, name in enumerate(names):
        assert np.array_equal(np.flatnonzero(ids == k + 1), groups[name])
    # decks name parts pid_<PSHELL id>; a mesh without either convention: every group
    ids, names = part_ids(4, {"pid_7": [0, 1], "pid_2": [2, 3], "set_5": [0]})
    assert names == ("pid_2", "pid_7") and ids.tolist() == [2, 2, 1, 1]
    ids, names = part_ids(3, {"wall": [0, 1], "lid": [2]})
    assert names == ("lid", "wall") and ids.tolist() == [2, 2, 1]
    assert part_ids(2, {})[0].tolist() == [0, 0]


def test_a_nan_on_the_surface_is_still_written_as_zero(tmp_path):
    points, triangles, _, n_plate = two_parts()
    data = {"erp_level_db_m2": np.where(np.arange(len(points)) == 0, np.nan, 50.0),
            "radiating": (np.arange(len(points)) < n_plate).astype(np.int8)}
    with pytest.warns(RuntimeWarning, match="1 non-finite values written as 0"):
        path = write_erp_vtu(tmp_path / "x.vtu", points, triangles, data)
    assert pv.read(path).point_data["erp_level_db_m2"][0] == 0.0


def test_pvd_times_are_rounded(tmp_path):
    """2π·30 / 2π in floating point is 29.999999999999996: written as 30. Times that 10 digits
    would merge keep the digits that tell them apart."""
    frequency = (2 * np.pi * 30.0) / (2 * np.pi)
    path = write_pvd(tmp_path / "a.pvd", [(frequency, "a.vtu"), (100 / 3, "b.vtu")])
    times = re.findall(r'timestep="([^"]+)"', path.read_text())
    assert times == ["30", "33.33333333"]
    close = write_pvd(tmp_path / "b.pvd", [(50.0, "a.vtu"), (50.0 + 1e-9, "b.vtu")])
    times = re.findall(r'timestep="([^"]+)"', close.read_text())
    assert len(set(times)) == 2 and float(times[1]) == pytest.approx(50.0 + 1e-9, abs=1e-12)


def test_a_solved_rig_maps_its_parts_and_marks_the_beam(tmp_path, monkeypatch):
    """`sarfe solve` of the coarse rattle rig (ERP surface: the plate, `skin`): the beam's points
    are NaN in the dB map, every triangle has part_beam or part_plate, the PVD times are the
    frequencies as given."""
    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path / "cache"))
    case = tmp_path / "rig.yaml"
    case.write_text(coarse_rig([30.0, 32.5], "{harmonics: 3, samples_per_period: 32, "
                               "stability: false, error_estimate: false, workers: 1}",
                               "output: {files: [summary, erp_vtu]}"))
    assert main(["solve", str(case), "--output", str(tmp_path / "out"), "--quiet"]) == 0
    pvd = (tmp_path / "out" / "erp" / "erp.pvd").read_text()
    assert re.findall(r'timestep="([^"]+)"', pvd) == ["30", "32.5"]
    grid = pv.read(tmp_path / "out" / "erp" / "erp_0000.vtu")
    mesh = cached_mesh("rattle_rig", 0.02, gap=0.5e-3)
    beam_only = np.setdiff1d(mesh.node_groups["part_beam"], mesh.node_groups["part_plate"])
    level = np.asarray(grid.point_data["erp_level_db_m2"])
    assert np.isnan(level[beam_only]).all()
    assert np.isfinite(level[mesh.node_groups["skin"]]).all()
    names = str(grid.field_data["part_names"][0]).split(",")
    assert names == ["part_beam", "part_plate"]
    ids = np.asarray(grid.cell_data["part_id"])
    assert np.array_equal(np.flatnonzero(ids == 1), np.sort(mesh.element_groups["part_beam"]))
    assert grid.active_scalars_name == "erp_level_db_m2"
