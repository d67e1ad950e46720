"""The ERP map series read back (VTK's XML reader, ParaView's) equal the fields the writer was
given, whichever way they are written (a list, a function j → arrays, on worker processes); the
fast period excursion equals dense sampling; and on a solved FE case the power integrated from
each VTU's density over its own triangles is summary.json's ERP.

(meshio 5 cannot read these files: it knows the zlib and LZMA compressors of VTK XML, not LZ4,
which the maps use since they are written 20× faster with it — docs/outputs.md names ParaView,
VTK and pyvista as the readers.)"""
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from sarfe.results import write_erp_sweep  # noqa: E402
from sarfe.results.vtk import EXCURSION_BLOCK, excursion_amplitude  # noqa: E402

CASES = Path(__file__).resolve().parents[2] / "cases"


def strip(nx=7, ny=3):
    x, y = np.meshgrid(np.linspace(0, 0.7, nx + 1), np.linspace(0, 0.2, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), 0.01 * x.ravel() ** 2])
    idx = np.arange(points.shape[0]).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return points, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def fields(n, j):
    rng = np.random.default_rng(j)
    return {"erp_density_W_m2": rng.random(n) * 10.0 ** -j,
            "displacement_amplitude_m": rng.standard_normal((n, 3)),
            "contact_marker": rng.integers(0, 3, n).astype(np.int32)}


@pytest.mark.parametrize("how", ["list", "function", "workers"])
def test_series_reads_back_equal_and_pvd_lists_the_frequencies(tmp_path, how):
    points, triangles = strip()
    n = points.shape[0]
    frequencies = [41.0, 40.5, 43.25, 47.0, 52.5]
    data = [fields(n, j) for j in range(len(frequencies))]
    source = {"list": data, "function": data.__getitem__, "workers": data.__getitem__}[how]
    pvd = write_erp_sweep(tmp_path / "erp", points, triangles, source, frequencies,
                          workers=2 if how == "workers" else 1)
    entries = ET.parse(pvd).getroot().findall("./Collection/DataSet")
    assert [float(e.get("timestep")) for e in entries] == frequencies
    assert [e.get("file") for e in entries] == [f"erp_{j:04d}.vtu" for j in range(5)]
    for j, entry in enumerate(entries):
        back = pv.read(pvd.parent / entry.get("file"))
        np.testing.assert_array_equal(back.points, points)
        np.testing.assert_array_equal(back.cells_dict[pv.CellType.TRIANGLE], triangles)
        for name, values in data[j].items():          # written as float64 / int32: bit-equal
            np.testing.assert_array_equal(back.point_data[name], values)
            assert back.point_data[name].dtype == values.dtype


def test_a_started_series_is_written_while_this_process_writes_other_files(tmp_path):
    """start_erp_sweep: the maps on 2 forked workers while this process goes on; finish() gives
    the same files as write_erp_sweep; a cancelled series leaves no map in progress."""
    from sarfe.util import workers
    from sarfe.results import start_erp_sweep

    points, triangles = strip()
    n = points.shape[0]
    frequencies = [40.0, 45.0, 50.0, 55.0]
    data = [fields(n, j) for j in range(len(frequencies))]
    writer = start_erp_sweep(tmp_path / "erp", points, triangles, data.__getitem__, frequencies,
                             workers=2)
    (tmp_path / "other.txt").write_text("written meanwhile")      # this process works on
    pvd = writer.finish()
    serial = write_erp_sweep(tmp_path / "serial", points, triangles, data, frequencies)
    for j in range(len(frequencies)):
        a = pv.read(pvd.parent / f"erp_{j:04d}.vtu")
        b = pv.read(serial.parent / f"erp_{j:04d}.vtu")
        for name in data[j]:
            np.testing.assert_array_equal(a.point_data[name], b.point_data[name])
    writer = start_erp_sweep(tmp_path / "cancelled", points, triangles, data.__getitem__,
                             frequencies, workers=2)
    writer.cancel()
    assert workers._TASK is None
    assert workers.map_points(abs, [-1, -2, -3], 2) == [1, 2, 3]   # the next map starts


def test_excursion_equals_dense_sampling_across_blocks():
    """max_j |u(θ_j) − U0| block by block equals the whole-field sampling (period_samples), for a
    field longer than a block and not a multiple of it, and a closed form for one harmonic."""
    from sarfe.results.vtk import period_samples

    rng = np.random.default_rng(3)
    U = rng.standard_normal((11, 2 * EXCURSION_BLOCK + 37, 3))
    whole = np.abs(period_samples(U, 80) - U[0]).max(axis=0)
    np.testing.assert_allclose(excursion_amplitude(U, 80), whole, rtol=1e-13, atol=0)
    # a single harmonic a cos 2θ + b sin 2θ: the excursion is √(a² + b²) when the samples hit it
    W = np.zeros((5, 4))
    W[0], W[3], W[4] = 7.0, [3.0, 0.0, 1.0, 0.0], [4.0, 2.0, 0.0, 0.0]
    np.testing.assert_allclose(excursion_amplitude(W, 4096)[:3], [5.0, 2.0, 1.0], rtol=1e-6)
    assert excursion_amplitude(W, 64)[3] == 0.0
    np.testing.assert_array_equal(excursion_amplitude(np.ones((1, 4, 3)), 64), np.zeros((4, 3)))


def _lumped_power(vtu):
    """P = Σ_i e_i A_i with A_i a third of each radiating triangle's area (triangles touching a
    node of positive density) — from the file alone."""
    mesh = pv.read(vtu)
    x, tri = np.asarray(mesh.points), mesh.cells_dict[pv.CellType.TRIANGLE]
    density = mesh.point_data["erp_density_W_m2"]
    radiating = tri[(density[tri] > 0).any(axis=1)]
    area = 0.5 * np.linalg.norm(np.cross(x[radiating[:, 1]] - x[radiating[:, 0]],
                                         x[radiating[:, 2]] - x[radiating[:, 0]]), axis=1)
    nodal = np.zeros(x.shape[0])
    np.add.at(nodal, radiating, np.repeat(area[:, None] / 3.0, 3, axis=1))
    harmonics = sorted((k for k in mesh.point_data if k.startswith("erp_density_h")),
                       key=lambda k: int(k[len("erp_density_h"):-len("_W_m2")]))
    per_harmonic = np.array([mesh.point_data[k] @ nodal for k in harmonics])
    return density @ nodal, per_harmonic, mesh


@pytest.mark.parametrize("frequencies", [[31.0, 20.0, 26.0], [31.0]], ids=["sweep", "single"])
def test_solved_maps_integrate_to_summary_power(tmp_path, monkeypatch, frequencies):
    """Rattle rig, written on 2 worker processes (the series threshold lowered to 0): every map
    integrates to its point's ERP in summary.json, per harmonic too; the PVD lists the points'
    frequencies; the loudest map carries its recovered displacement."""
    import sarfe.pipeline.write.result_files as pipeline_outputs
    from sarfe.pipeline import load_case, solve_case

    monkeypatch.setattr(pipeline_outputs, "PARALLEL_MAP_VALUES", 0)
    data = load_case(CASES / "rattle_rig.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.02
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = frequencies if len(frequencies) > 1 else frequencies[0]
    data["solver"].update(error_estimate=False, stability=False, workers=2)
    data["output"].update(files=["summary", "erp_vtu"], maps={"every": 1})   # a map per point
    out = tmp_path / "run"
    solve_case(data, output_dir=out)
    summary = json.loads((out / "summary.json").read_text())
    points = summary["points"]
    if len(frequencies) == 1:
        files = [out / "erp.vtu"]
    else:
        pvd = out / "erp" / "erp.pvd"
        entries = ET.parse(pvd).getroot().findall("./Collection/DataSet")
        np.testing.assert_allclose([float(e.get("timestep")) for e in entries],
                                   [p["frequency_hz"] for p in points], rtol=1e-12)
        files = [pvd.parent / e.get("file") for e in entries]
    assert len(files) == len(points)
    for j, (vtu, point) in enumerate(zip(files, points)):
        power, per_harmonic, mesh = _lumped_power(vtu)
        assert point["erp"]["power_W"] > 0
        np.testing.assert_allclose(power, point["erp"]["power_W"], rtol=1e-9)
        np.testing.assert_allclose(per_harmonic, point["erp"]["harmonics"]["power_W"], rtol=1e-9,
                                   atol=1e-12 * power)
        if j == summary["worst"]["index"]:
            assert np.abs(mesh.point_data["displacement_amplitude_m"]).max() > 0
