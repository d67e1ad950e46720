"""PNG plots of a run (matplotlib, Agg; no pyplot state, safe in worker processes).

    plot_erp_sweep       ERP level [dB re 1 pW] (and dB(A)) vs excitation frequency; stable branches
                         solid, unstable dashed with × markers, not-assessed dotted
    plot_contact_forces  contact force λ(t) over one period, one line per contact row
    plot_erp_spectrum    ERP level per harmonic as bars, dB and dB(A) side by side
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["plot_erp_sweep", "plot_contact_forces", "plot_erp_spectrum"]

_STYLE = {  # stability category → line style
    1: dict(linestyle="-", marker=None, label="stable"),
    0: dict(linestyle="--", marker="x", markersize=4, label="unstable"),
    -1: dict(linestyle=":", marker=".", markersize=3, label="stability not assessed"),
}


def _figure(width=6.4, height=4.0):
    fig = Figure(figsize=(width, height), dpi=120)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, format="png")
    return path


def _categories(stable, n):
    if stable is None:
        return np.full(n, -1)
    return np.array([-1 if s is None or (isinstance(s, float) and np.isnan(s)) else int(bool(s))
                     for s in stable])


def _plot_branches(ax, x, y, category, color, label_prefix=""):
    """Plot y(x) in sweep order as runs of equal stability, each run joined to the next point."""
    labelled = set()
    start = 0
    n = len(x)
    while start < n:
        stop = start
        while stop + 1 < n and category[stop + 1] == category[start]:
            stop += 1
        end = min(stop + 2, n)  # include the next point so branches connect
        style = dict(_STYLE[int(category[start])])
        label = style.pop("label")
        if category[start] not in labelled:
            labelled.add(category[start])
            style["label"] = f"{label_prefix}{label}"
        ax.plot(x[start:end], y[start:end], color=color, **style)
        start = stop + 1


def plot_erp_sweep(path, frequencies_hz, level_db, stable=None, level_a_db=None, title=None,
                   linear_level_db=None, dynamic_range_db: float = 80.0) -> Path:
    """ERP level vs excitation frequency for a sweep, in sweep (continuation) order.

    frequencies_hz : (n_f,) [Hz]; level_db : (n_f,) total ERP level [dB re 1 pW];
    stable : (n_f,) True/False/None per point (None = not assessed); level_a_db : optional
    (n_f,) A-weighted total [dB(A)]; linear_level_db : optional (n_f,) linear baseline (thin grey).
    The y axis shows at most ``dynamic_range_db`` below the highest level (a panel that barely
    moves has levels of −200 dB that would squash the plot). Non-finite levels are left out.
    Returns the PNG path.
    """
    x = np.asarray(frequencies_hz, dtype=float)
    category = _categories(stable, x.size)
    fig = _figure()
    ax = fig.add_subplot()
    _plot_branches(ax, x, np.asarray(level_db, dtype=float), category, "C0", "ERP, ")
    if level_a_db is not None:
        _plot_branches(ax, x, np.asarray(level_a_db, dtype=float), category, "C1", "ERP(A), ")
    if linear_level_db is not None:
        ax.plot(x, np.asarray(linear_level_db, dtype=float), color="0.5", linewidth=0.8,
                label="linear (no contact)")
    shown = [np.asarray(v, dtype=float) for v in (level_db, level_a_db, linear_level_db)
             if v is not None]
    finite = np.concatenate([v[np.isfinite(v)] for v in shown])
    if finite.size:
        top, low = float(finite.max()), float(finite.min())
        margin = 0.05 * max(min(top - low, dynamic_range_db), 1.0)
        ax.set_ylim(max(low, top - dynamic_range_db) - margin, top + margin)
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("ERP level [dB re 1 pW]" + (" / [dB(A)]" if level_a_db is not None else ""))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return _save(fig, path)


def plot_contact_forces(path, force_time, names=None, omega=None, title=None) -> Path:
    """Contact force λ(θ_j) [N] over one period, θ_j = 2πj/N; ``force_time`` (N, n) [N].

    The x axis is time [ms] when ``omega`` [rad/s] is given, else the period fraction θ/2π.
    The period is closed (first sample repeated at the end). ``names`` labels the n lines.
    """
    F = np.asarray(force_time, dtype=float)
    if F.ndim == 1:
        F = F[:, None]
    N, n = F.shape
    phase = np.arange(N + 1) / N
    x = phase * 2 * np.pi / omega * 1e3 if omega else phase
    F = np.concatenate([F, F[:1]])
    names = list(names) if names is not None else [f"row {i}" for i in range(n)]
    fig = _figure()
    ax = fig.add_subplot()
    for i in range(n):
        ax.plot(x, F[:, i], label=str(names[i]))
    ax.set_xlabel("time [ms]" if omega else "phase θ/2π [-]")
    ax.set_ylabel("contact force [N]")
    ax.grid(True, alpha=0.3)
    if n <= 12:
        ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return _save(fig, path)


def plot_erp_spectrum(path, frequencies_hz, level_db, level_a_db=None, title=None) -> Path:
    """ERP level per harmonic as a bar chart: dB re 1 pW, and dB(A) beside it if given.

    frequencies_hz : (H,) harmonic frequencies kω/2π [Hz]; level_db, level_a_db : (H,).
    Bars start at a floor 10 dB below the lowest finite level; −inf levels get no bar.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    levels = [np.asarray(level_db, dtype=float)]
    labels = ["dB re 1 pW"]
    if level_a_db is not None:
        levels.append(np.asarray(level_a_db, dtype=float))
        labels.append("dB(A)")
    finite = np.concatenate([lv[np.isfinite(lv)] for lv in levels])
    floor = float(np.floor((finite.min() if finite.size else 0.0) / 10.0) * 10.0 - 10.0)
    top = float(finite.max()) + 5.0 if finite.size else floor + 10.0
    H = f.size
    width = 0.8 / len(levels)
    fig = _figure()
    ax = fig.add_subplot()
    positions = np.arange(H)
    for j, (lv, label) in enumerate(zip(levels, labels)):
        heights = np.where(np.isfinite(lv), lv - floor, 0.0)
        ax.bar(positions + (j - (len(levels) - 1) / 2) * width, heights, width, bottom=floor,
               label=label)
    ax.set_xticks(positions)
    ax.set_xticklabels([f"{k + 1}\n{fk:.4g} Hz" for k, fk in enumerate(f)], fontsize="small")
    ax.set_xlabel("harmonic k, frequency")
    ax.set_ylabel("ERP level")
    ax.set_ylim(floor, top)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return _save(fig, path)
