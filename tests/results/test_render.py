"""The report's surface renders started in a child process and collected later: PNGs from
pyvista, the matplotlib fallback (with the reason) when the child fails, and a child stopped and
its data removed when the caller gives up."""
import stat
import time

import numpy as np
import pytest

from sarfe.results import render


def plate_job(path):
    x, y = np.meshgrid(np.linspace(0, 0.3, 7), np.linspace(0, 0.2, 5), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(points.shape[0]).reshape(7, 5)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    values = np.sin(np.pi * points[:, 0] / 0.3) * np.sin(np.pi * points[:, 1] / 0.2)
    return dict(path=path, points=points, triangles=triangles, values=values, label="v [1]",
                title="plate")


def _png(path):
    return path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_started_render_is_collected_as_pyvista_pngs(tmp_path):
    pytest.importorskip("pyvista")
    jobs = [plate_job(tmp_path / "a.png"), dict(plate_job(tmp_path / "b.png"), spots=True)]
    run = render.start_render(jobs)
    assert run.process is not None                     # started, not waited for
    rendered = render.finish_render(run)
    if rendered[0][1] != "pyvista":
        pytest.skip(f"no off-screen VTK here: {rendered[0][1]}")
    assert [r for _, r in rendered] == ["pyvista", "pyvista"]
    assert all(_png(p) for p, _ in rendered)
    assert not list(tmp_path.glob(".render-*"))        # its data and stderr files are gone


def test_failed_child_falls_back_to_matplotlib_with_the_reason(tmp_path, monkeypatch):
    monkeypatch.setattr(render.sys, "executable", "/bin/false")
    rendered = render.finish_render(render.start_render([plate_job(tmp_path / "a.png")]))
    path, renderer = rendered[0]
    assert renderer == "matplotlib (pyvista failed: exit code 1)"
    assert _png(path)
    assert not list(tmp_path.glob(".render-*"))


def test_cancel_stops_the_child_and_removes_its_data(tmp_path, monkeypatch):
    slow = tmp_path / "slow.sh"
    slow.write_text("#!/bin/sh\nsleep 60\n")
    slow.chmod(slow.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setattr(render.sys, "executable", str(slow))
    run = render.start_render([plate_job(tmp_path / "a.png")])
    assert run.process.poll() is None and run.data[0].is_file()
    clock = time.monotonic()
    render.cancel_render(run)
    assert time.monotonic() - clock < 10
    assert run.process.poll() is not None
    assert not list(tmp_path.glob(".render-*"))


def test_a_failing_writer_stops_the_report_render(tmp_path, monkeypatch):
    """write_outputs starts the render before the ERP maps; when a later writer raises, the child
    is stopped and its data removed, and the error reaches the caller."""
    from pathlib import Path

    import sarfe.pipeline.write.result_files as pipeline_outputs
    from sarfe.pipeline import load_case, solve_case

    started = []
    start = render.start_render

    def recording_start(jobs, use_pyvista=True):
        started.append(start(jobs, use_pyvista=use_pyvista))
        return started[-1]

    def failing_map_workers(*args):
        raise RuntimeError("disk full (test)")

    monkeypatch.setattr(render, "start_render", recording_start)
    monkeypatch.setattr(pipeline_outputs, "map_workers", failing_map_workers)
    data = load_case(Path(__file__).resolve().parents[2] / "cases" / "rattle_rig.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.02
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [31.0, 26.0]
    data["solver"].update(error_estimate=False, stability=False, workers=1)
    data["output"]["files"] = ["summary", "erp_vtu", "report"]
    data["output"]["maps"] = {"every": 1}     # a series of maps: written on the map workers
    with pytest.raises(RuntimeError, match="disk full"):
        solve_case(data, output_dir=tmp_path / "run")
    assert len(started) == 1
    assert started[0].process.poll() is not None
    assert not any(path.exists() for path in started[0].data)
