"""PNG figures of ``sarfe compare`` (matplotlib Agg, no pyplot state).

    plot_sweeps(path, results)                   L_A(f) of every variant overlaid [dB(A)]
    plot_contributions(path, results)            contribution levels [dB(A)] of every source,
                                                 variants' bars side by side, each at its
                                                 loudest point
    plot_map_difference(path, difference, title) ΔL = 10 log10(e_b/e_a) per node [dB] on the
                                                 mesh projected onto its two widest principal axes
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from sarfe.compare.map_difference import MapDifference

DYNAMIC_RANGE_DB = 60.0


def _save(fig: Figure, path) -> Path:
    FigureCanvasAgg(fig)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return Path(path)


def plot_sweeps(path, results) -> Path:
    """Overlaid A-weighted ERP sweeps L_A(f) [dB(A) re 1e-12 W] of all results."""
    fig = Figure(figsize=(7.0, 4.0))
    ax = fig.add_subplot()
    top = -np.inf
    for r in results:
        finite = np.isfinite(r.sweep_dba)
        ax.plot(r.sweep_hz[finite], r.sweep_dba[finite], marker="o" if r.sweep_hz.size < 40 else None,
                ms=4, label=r.label)
        top = max(top, float(r.sweep_dba[finite].max()) if finite.any() else top)
    if np.isfinite(top):
        ax.set_ylim(bottom=max(ax.get_ylim()[0], top - DYNAMIC_RANGE_DB))
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("ERP level [dB(A) re 1e-12 W]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def plot_contributions(path, results) -> Path:
    """Contribution levels [dB(A)] per source (contacts and the excitation's structure-borne part)
    at each variant's loudest point, one bar per variant side by side; a variant without a
    source draws no bar."""
    rows, labels = [], []
    for r in results:
        index = r.worst.get("index")
        point = r.points[int(index)] if index is not None else None
        rows.append(point.sources if point else {})
        labels.append(r.label + (f" ({point.frequency_hz:.4g} Hz)" if point else ""))
    names = list(dict.fromkeys(n for row in rows for n in row))
    fig = Figure(figsize=(7.0, 0.9 + 0.45 * max(1, len(names)) * max(1, len(results)) ** 0.5))
    ax = fig.add_subplot()
    height = 0.8 / max(1, len(results))
    y = np.arange(len(names))
    values = [[row.get(n, np.nan) for n in names] for row in rows]
    finite = np.array([v for vs in values for v in vs if np.isfinite(v)])
    floor = float(finite.max()) - DYNAMIC_RANGE_DB if finite.size else 0.0
    for k, (label, vs) in enumerate(zip(labels, values)):
        vs = np.array(vs, float)
        shown = np.where(np.isfinite(vs), np.maximum(vs, floor), np.nan)
        ax.barh(y + (k - (len(results) - 1) / 2) * height, shown - floor, height, left=floor,
                label=label)
    ax.set_yticks(y, names)
    ax.invert_yaxis()
    ax.set_xlabel("contribution level at the loudest point [dB(A) re 1e-12 W]")
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)


def plot_map_difference(path, difference: MapDifference, title: str) -> Path:
    """ΔL per node [dB], diverging colours centred on 0; non-radiating nodes grey (masked)."""
    xyz = difference.points_m
    centred = xyz - xyz.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2][:2]     # two widest principal axes
    uv = centred @ axes.T
    values = difference.delta_db.copy()
    finite = values[np.isfinite(values)]
    limit = max(float(np.abs(finite).max()) if finite.size else 0.0, 0.1)
    values = np.clip(values, -limit, limit)                       # ±inf (silent on one side) at the ends
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.add_subplot()
    tri = difference.triangles
    ax.triplot(uv[:, 0], uv[:, 1], tri, color="0.85", lw=0.3)
    corner = values[tri]                                          # (t, 3); NaN = not radiating
    count = np.count_nonzero(~np.isnan(corner), axis=1)
    face = np.where(count > 0, np.nansum(corner, axis=1) / np.maximum(count, 1), np.nan)
    keep = np.isfinite(face)
    art = ax.tripcolor(uv[:, 0], uv[:, 1], tri[keep], facecolors=face[keep], cmap="RdBu_r",
                       vmin=-limit, vmax=limit)
    fig.colorbar(art, ax=ax, label="ΔERP density [dB] (variant − reference)")
    ax.set_aspect("equal")
    ax.set_xlabel("principal axis 1 [m]")
    ax.set_ylabel("principal axis 2 [m]")
    ax.set_title(title, fontsize=9)
    return _save(fig, path)
