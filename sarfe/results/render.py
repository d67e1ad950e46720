"""PNG renders of surface fields for the report: pyvista off-screen, matplotlib as the fallback.

    render_surface(path, points (n,3) [m], triangles (n_tri,3), values (n,), label, title=None,
                   warp=None (n,3) [m], clim=None, cmap="inferno") -> (path, renderer)

pyvista renders in a child process (``python -m sarfe.results.render DATA.npz OUT.png``) so that
a missing or broken OpenGL stack can never take the solve down with it; VTK picks its off-screen
context itself (here: no X display, it falls back to its EGL/OSMesa path, which renders). When the
child fails or times out, :func:`sarfe.results.plots.plot_surface_map` draws the field with
matplotlib's tripcolor seen along the panel's thickness axis, and ``renderer`` says so. The child
ends with the solve that started it, even one killed by SIGKILL
(:func:`sarfe.util.parent_watch.die_with_parent`).
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarfe.util.parent_watch import die_with_parent

__all__ = ["render_surface", "render_surfaces", "start_render", "finish_render", "cancel_render",
           "RenderRun"]

TIMEOUT_S = 120
PARENT_ENV = "SARFE_RENDER_PARENT_PID"    # the solve's PID: the child dies with it


def render_surface(path, points, triangles, values, label, title=None, warp=None, clim=None,
                   cmap="inferno", use_pyvista: bool = True, spots: bool = False, labels=None):
    """Render ``values`` on the surface (module docstring); returns (PNG path, 'pyvista' |
    'matplotlib (pyvista failed: …)' | 'matplotlib'). ``spots``: show the surface grey and the
    nodes with a nonzero value as coloured spheres (fields that live on a few nodes, e.g. contacts).
    ``labels``: [(xyz (3,) [m], text)] written next to those points (pyvista only).
    """
    job = dict(path=path, points=points, triangles=triangles, values=values, label=label,
               title=title, warp=warp, clim=clim, cmap=cmap, spots=spots, labels=labels)
    return render_surfaces([job], use_pyvista=use_pyvista)[0]


def render_surfaces(jobs, use_pyvista: bool = True) -> list:
    """Several :func:`render_surface` jobs (dicts of its arguments) in one child process (pyvista
    is imported once); returns [(path, renderer)] in order."""
    return finish_render(start_render(jobs, use_pyvista=use_pyvista))


@dataclass
class RenderRun:
    """A render child started by :func:`start_render` (its jobs, data files, process, stderr
    file and start time), read by :func:`finish_render`."""

    jobs: list
    data: list
    process: subprocess.Popen | None
    stderr: Path | None
    started: float
    reason: str
    use_pyvista: bool


def start_render(jobs, use_pyvista: bool = True) -> RenderRun:
    """Start the child that renders ``jobs`` (as :func:`render_surfaces`) and return at once, so
    the caller writes its other files meanwhile (the child imports VTK and renders on the other
    core: ≈ 2.7 s for the 5 mm door trim's three maps); :func:`finish_render` waits for it."""
    jobs = [dict(job, path=Path(job["path"])) for job in jobs]
    run = RenderRun(jobs, [], None, None, time.monotonic(), "not asked", use_pyvista)
    if not (use_pyvista and jobs):
        return run
    directory = jobs[0]["path"].parent
    directory.mkdir(parents=True, exist_ok=True)
    for i, job in enumerate(jobs):
        points = np.asarray(job["points"], dtype=float)
        warp = job.get("warp")
        clim = job.get("clim")
        name = directory / f".render-{i}.npz"
        np.savez(name, points=points, triangles=np.asarray(job["triangles"], dtype=np.int64),
                 values=np.asarray(job["values"], dtype=float),
                 warp=np.zeros_like(points) if warp is None else np.asarray(warp, float),
                 clim=np.asarray(clim if clim is not None else [np.nan, np.nan], float),
                 label=str(job["label"]), title=str(job.get("title") or ""),
                 cmap=str(job.get("cmap", "inferno")), spots=bool(job.get("spots", False)),
                 png=str(job["path"]),
                 label_points=np.asarray([p for p, _ in job.get("labels") or []],
                                         dtype=float).reshape(-1, 3),
                 label_texts=np.asarray([t for _, t in job.get("labels") or []], dtype=str))
        run.data.append(name)
    env = dict(os.environ, PYVISTA_OFF_SCREEN="true", **{PARENT_ENV: str(os.getpid())})
    run.stderr = directory / ".render-stderr.txt"    # a file, not a pipe: the child never blocks
    try:
        with open(run.stderr, "w") as stderr:
            run.process = subprocess.Popen([sys.executable, "-m", "sarfe.results.render",
                                            *map(str, run.data)], stdout=subprocess.DEVNULL,
                                           stderr=stderr, env=env)
    except OSError as error:
        run.reason = f"{type(error).__name__}: {error}"
    return run


def cancel_render(run: RenderRun) -> None:
    """Stop the child of :func:`start_render` (the caller failed before it needed the maps) and
    remove its data files."""
    if run.process is not None and run.process.poll() is None:
        run.process.kill()
        run.process.wait()
    for name in run.data + ([run.stderr] if run.stderr is not None else []):
        name.unlink(missing_ok=True)


def finish_render(run: RenderRun) -> list:
    """Wait for the child of :func:`start_render` (at most TIMEOUT_S per job from its start) and
    return [(path, renderer)]; where it failed, the matplotlib fallback draws the maps here."""
    jobs, reason = run.jobs, run.reason
    try:
        if run.process is not None:
            limit = TIMEOUT_S * len(jobs) - (time.monotonic() - run.started)
            try:
                code = run.process.wait(timeout=max(limit, 0.0))
            except subprocess.TimeoutExpired as error:
                run.process.kill()
                run.process.wait()
                code, reason = None, f"TimeoutExpired: {error}"
            if code == 0 and all(j["path"].exists() and j["path"].stat().st_size for j in jobs):
                return [(j["path"], "pyvista") for j in jobs]
            if code is not None:
                text = run.stderr.read_text(errors="replace") if run.stderr.exists() else ""
                lines = [x.strip() for x in text.splitlines() if "Error" in x]
                reason = (lines or [f"exit code {code}"])[-1]
    finally:
        for name in run.data + ([run.stderr] if run.stderr is not None else []):
            name.unlink(missing_ok=True)
    from sarfe.results.plots import plot_surface_map

    out = []
    for job in jobs:
        plot_surface_map(job["path"], job["points"], job["triangles"], job["values"],
                         job["label"], title=job.get("title"), clim=job.get("clim"),
                         cmap=job.get("cmap", "inferno"))
        out.append((job["path"], "matplotlib" if not run.use_pyvista
                    else f"matplotlib (pyvista failed: {reason})"))
    return out


def _render(data_path):
    import pyvista as pv

    pv.OFF_SCREEN = True
    d = np.load(data_path)
    png_path = str(d["png"])
    points, triangles = d["points"], d["triangles"]
    warp = d["warp"]
    grid = pv.PolyData(points + warp, np.hstack([np.full((triangles.shape[0], 1), 3),
                                                 triangles]).ravel())
    label = str(d["label"])
    grid.point_data[label] = d["values"]
    clim = d["clim"]
    plotter = pv.Plotter(off_screen=True, window_size=(900, 620))
    triangles = np.asarray(triangles)
    plotter.set_background("white")
    bar = {"title": label, "color": "black", "vertical": True, "position_x": 0.80,
           "position_y": 0.12, "height": 0.76, "width": 0.06, "fmt": "%.3g",
           "title_font_size": 20, "label_font_size": 18}
    if bool(d["spots"]):  # a field on a few nodes: grey surface, coloured spheres at those nodes
        plotter.add_mesh(grid, color="lightgray", smooth_shading=True)
        spots = d["values"] > 0
        cloud = pv.PolyData(points[spots] + warp[spots])
        cloud.point_data[label] = d["values"][spots]
        plotter.add_mesh(cloud, scalars=label, cmap=str(d["cmap"]), render_points_as_spheres=True,
                         point_size=18, scalar_bar_args=bar)
    else:
        plotter.add_mesh(grid, scalars=label, cmap=str(d["cmap"]),
                         clim=None if np.isnan(clim).any() else clim.tolist(),
                         show_edges=False, smooth_shading=True, scalar_bar_args=bar)
    if np.any(warp):  # the undeformed surface as a faint wireframe
        plotter.add_mesh(pv.PolyData(points, np.hstack([np.full((triangles.shape[0], 1), 3),
                                                        triangles]).ravel()),
                         style="wireframe", color="gray", opacity=0.15)
    if d["label_points"].shape[0]:  # names next to points (e.g. each contact)
        plotter.add_point_labels(d["label_points"], [str(t) for t in d["label_texts"]],
                                 font_size=14, point_size=1, shape_opacity=0.5,
                                 always_visible=True)
    title = str(d["title"])
    if title:
        plotter.add_text(title, font_size=12, color="black")
    extent = np.ptp(points, axis=0)
    normal = np.zeros(3)
    normal[int(np.argmin(extent))] = 1.0
    plotter.view_vector(normal + 0.35 * np.array([1.0, -1.0, 0.6]))
    plotter.screenshot(png_path)
    plotter.close()


if __name__ == "__main__":  # child process of render_surfaces: one .npz per image
    if os.environ.get(PARENT_ENV):      # ends with the solve, even a solve killed by SIGKILL
        die_with_parent(int(os.environ[PARENT_ENV]))
    for argument in sys.argv[1:]:
        _render(argument)
