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

__all__ = ["render_surface"]

TIMEOUT_S = 120


def render_surface(path, points, triangles, values, label, title=None, warp=None, clim=None,
                   cmap="inferno", use_pyvista: bool = True):
    """Render ``values`` on the surface (module docstring); returns (PNG path, 'pyvista' |
    'matplotlib (pyvista failed: …)' | 'matplotlib')."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    points = np.asarray(points, dtype=float)
    reason = "not asked"
    if use_pyvista:
        data = path.with_suffix(".render.npz")
        np.savez(data, points=points, triangles=np.asarray(triangles, dtype=np.int64),
                 values=np.asarray(values, dtype=float),
                 warp=np.zeros_like(points) if warp is None else np.asarray(warp, dtype=float),
                 clim=np.asarray(clim if clim is not None else [np.nan, np.nan], dtype=float),
                 label=str(label), title=str(title or ""), cmap=str(cmap))
        env = dict(os.environ, PYVISTA_OFF_SCREEN="true")
        try:
            done = subprocess.run([sys.executable, "-m", "sarfe.io.outputs.render", str(data),
                                   str(path)], capture_output=True, text=True, timeout=TIMEOUT_S,
                                  env=env)
            if done.returncode == 0 and path.exists() and path.stat().st_size > 0:
                return path, "pyvista"
            lines = [x.strip() for x in done.stderr.splitlines() if "Error" in x]
            reason = (lines or [f"exit code {done.returncode}"])[-1]
        except (OSError, subprocess.SubprocessError) as error:
            reason = f"{type(error).__name__}: {error}"
        finally:
            data.unlink(missing_ok=True)
    from sarfe.io.outputs.plots import plot_surface_map

    plot_surface_map(path, points, triangles, values, label, title=title, clim=clim, cmap=cmap)
    return path, "matplotlib" if not use_pyvista else f"matplotlib (pyvista failed: {reason})"


def _render(data_path, png_path):
    import pyvista as pv

    pv.OFF_SCREEN = True
    d = np.load(data_path)
    points, triangles = d["points"], d["triangles"]
    warp = d["warp"]
    grid = pv.PolyData(points + warp, np.hstack([np.full((triangles.shape[0], 1), 3),
                                                 triangles]).ravel())
    label = str(d["label"])
    grid.point_data[label] = d["values"]
    clim = d["clim"]
    plotter = pv.Plotter(off_screen=True, window_size=(900, 620))
    plotter.set_background("white")
    plotter.add_mesh(grid, scalars=label, cmap=str(d["cmap"]),
                     clim=None if np.isnan(clim).any() else clim.tolist(),
                     show_edges=False, smooth_shading=True,
                     scalar_bar_args={"title": label, "color": "black", "vertical": True,
                                      "position_x": 0.80, "position_y": 0.12, "height": 0.76,
                                      "width": 0.06, "fmt": "%.3g", "title_font_size": 14,
                                      "label_font_size": 12})
    if np.any(warp):  # the undeformed surface as a faint wireframe
        plotter.add_mesh(pv.PolyData(points, np.hstack([np.full((triangles.shape[0], 1), 3),
                                                        triangles]).ravel()),
                         style="wireframe", color="gray", opacity=0.15)
    title = str(d["title"])
    if title:
        plotter.add_text(title, font_size=10, color="black")
    extent = np.ptp(points, axis=0)
    normal = np.zeros(3)
    normal[int(np.argmin(extent))] = 1.0
    plotter.view_vector(normal + 0.35 * np.array([1.0, -1.0, 0.6]))
    plotter.screenshot(png_path)
    plotter.close()


if __name__ == "__main__":  # child process of render_surface
    _render(sys.argv[1], sys.argv[2])
