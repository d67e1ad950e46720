"""PNG renders of surface fields for the report: pyvista off-screen, matplotlib as the fallback.

    render_surface(path, points (n,3) [m], triangles (n_tri,3), values (n,), label, title=None,
                   warp=None (n,3) [m], clim=None, cmap="inferno") -> (path, renderer)

pyvista renders in a child process (``python -m sarfe.io.outputs.render DATA.npz OUT.png``) so that
a missing or broken OpenGL stack can never take the solve down with it; VTK picks its off-screen
context itself (here: no X display, it falls back to its EGL/OSMesa path, which renders). When the
child fails or times out, :func:`sarfe.io.outputs.plots.plot_surface_map` draws the field with
matplotlib's tripcolor seen along the panel's thickness axis, and ``renderer`` says so.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

__all__ = ["render_surface", "render_surfaces"]

TIMEOUT_S = 120


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
    jobs = [dict(job, path=Path(job["path"])) for job in jobs]
    reason = "not asked"
    if use_pyvista and jobs:
        directory = jobs[0]["path"].parent
        directory.mkdir(parents=True, exist_ok=True)
        data = []
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
            data.append(name)
        env = dict(os.environ, PYVISTA_OFF_SCREEN="true")
        try:
            done = subprocess.run([sys.executable, "-m", "sarfe.io.outputs.render",
                                   *map(str, data)], capture_output=True, text=True,
                                  timeout=TIMEOUT_S * len(jobs), env=env)
            if done.returncode == 0 and all(j["path"].exists() and j["path"].stat().st_size
                                            for j in jobs):
                return [(j["path"], "pyvista") for j in jobs]
            lines = [x.strip() for x in done.stderr.splitlines() if "Error" in x]
            reason = (lines or [f"exit code {done.returncode}"])[-1]
        except (OSError, subprocess.SubprocessError) as error:
            reason = f"{type(error).__name__}: {error}"
        finally:
            for name in data:
                name.unlink(missing_ok=True)
    from sarfe.io.outputs.plots import plot_surface_map

    out = []
    for job in jobs:
        plot_surface_map(job["path"], job["points"], job["triangles"], job["values"],
                         job["label"], title=job.get("title"), clim=job.get("clim"),
                         cmap=job.get("cmap", "inferno"))
        out.append((job["path"], "matplotlib" if not use_pyvista
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
    for argument in sys.argv[1:]:
        _render(argument)
