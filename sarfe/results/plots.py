"""PNG plots of a run (matplotlib, Agg; no pyplot state, safe in worker processes).

    plot_erp_sweep       ERP level [dB re 1 pW] (and dB(A)) vs excitation frequency; stable branches
                         solid, unstable dashed with × markers, not-assessed dotted
    plot_contact_forces  contact force λ(t) over one period, one line per contact row
    plot_erp_spectrum    ERP level per harmonic as bars, dB and dB(A) side by side
    plot_friction        friction force and stick/slip/open state over one period (squeak contacts)
    plot_third_octave    ERP per third-octave band [dB(A)] with the linear baseline and a target
    plot_contributions   partial ERP [dB(A)] and coherent share of each source (contact ranking)
    plot_surface_map     a scalar on the surface triangles (matplotlib fallback of the 3-D renders)
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

__all__ = ["plot_erp_sweep", "plot_contact_forces", "plot_erp_spectrum", "plot_friction",
           "plot_third_octave", "plot_contributions", "plot_surface_map", "branch_ids"]

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


def _runs(values):
    """(start, stop) index ranges [start, stop) of equal consecutive values."""
    values = np.asarray(values)
    if values.size == 0:
        return []
    cut = np.flatnonzero(values[1:] != values[:-1]) + 1
    edges = np.concatenate(([0], cut, [values.size]))
    return list(zip(edges[:-1], edges[1:]))


def branch_ids(x) -> np.ndarray:
    """Branch number per point of a sweep in continuation order: a new branch starts where the
    frequency turns back (a fold), so each branch is monotone in x; the fold point ends one branch
    and starts the next."""
    x = np.asarray(x, dtype=float)
    if x.size < 3:
        return np.zeros(x.size, dtype=int)
    direction = np.sign(np.diff(x))
    for i in range(1, direction.size):  # a zero step keeps the running direction
        if direction[i] == 0:
            direction[i] = direction[i - 1]
    turns = np.concatenate(([0], np.cumsum(direction[1:] * direction[:-1] < 0)))
    return np.concatenate((turns[:1], turns))


def jump_starts(y, factor: float = 5.0, minimum_db: float = 6.0) -> np.ndarray:
    """(n,) bool: True where a point jumps from the previous one by more than
    max(``minimum_db``, ``factor`` × the median step) — a point-by-point sweep landing on another
    branch, not a continuous curve, so no line is drawn across it."""
    y = np.asarray(y, dtype=float)
    with np.errstate(invalid="ignore"):      # −inf dB (zero power) − −inf dB: no step (NaN)
        step = np.abs(np.diff(y))
    out = np.zeros(y.size, dtype=bool)
    finite = step[np.isfinite(step)]
    if finite.size:
        limit = max(minimum_db, factor * float(np.median(finite)))
        out[1:] = np.isfinite(step) & (step > limit)
    return out


def _plot_branches(ax, x, y, category, color, label_prefix="", labelled=None, width=1.5,
                   jumps=None):
    """y(x) in sweep order, one line per branch (:func:`branch_ids`; a new line also at each
    ``jumps`` point) and per run of equal stability inside it (each run joined to the next point
    so the curve is unbroken); points with NaN y break the line."""
    labelled = set() if labelled is None else labelled
    branch = branch_ids(x)
    if jumps is not None:
        branch = branch + np.cumsum(np.asarray(jumps, dtype=int)) * (branch.max(initial=0) + 1)
    starts = np.zeros(branch.size, dtype=bool) if jumps is None else np.asarray(jumps, bool)
    for b0, b1 in _runs(branch):
        # the fold point belongs to both branches (not a jump: nothing joins across it)
        lo = b0 - 1 if b0 > 0 and not starts[b0] else b0
        for r0, r1 in _runs(category[lo:b1]):
            r0, r1 = r0 + lo, r1 + lo
            end = min(r1 + 1, b1)
            if not np.isfinite(y[r0:end]).any():
                continue
            style = dict(_STYLE[int(category[r0])])
            label = style.pop("label")
            if category[r0] not in labelled:
                labelled.add(category[r0])
                style["label"] = f"{label_prefix}{label}"
            ax.plot(x[r0:end], y[r0:end], color=color, linewidth=width, **style)
    return labelled


def plot_erp_sweep(path, frequencies_hz, level_db, stable=None, level_a_db=None, title=None,
                   linear_level_db=None, dynamic_range_db: float = 80.0, converged=None,
                   target_dba=None, loudest_index=None) -> Path:
    """ERP level vs excitation frequency for a sweep, in sweep (continuation) order.

    frequencies_hz : (n_f,) [Hz]; level_db : (n_f,) total ERP level [dB re 1 pW];
    stable : (n_f,) True/False/None per point (None = not assessed); level_a_db : optional
    (n_f,) A-weighted total [dB(A)]; linear_level_db : optional (n_f,) linear baseline (thin grey);
    converged : optional (n_f,) bool — points that did not converge are drawn as red circles and
    not joined; target_dba : optional target level [dB(A)] (red dashed line); loudest_index :
    optional point marked with a star (the run's loudest point).
    Each branch between folds is its own line, unstable parts dashed; a jump between two
    consecutive points (:func:`jump_starts`, e.g. a point-by-point sweep falling onto another
    branch) is left open rather than drawn as a vertical line. The y axis shows at most
    ``dynamic_range_db`` below the highest level: lower levels (e.g. a motionless surface at
    −190 dB) leave a gap and a grey ▼ on the axis instead of a line to the floor.
    Returns the PNG path.
    """
    x = np.asarray(frequencies_hz, dtype=float)
    n = x.size
    category = _categories(stable, n)
    good = np.ones(n, bool) if converged is None else np.asarray(converged, dtype=bool)
    series = {"db": np.asarray(level_db, dtype=float)}
    if level_a_db is not None:
        series["dba"] = np.asarray(level_a_db, dtype=float)
    linear = None if linear_level_db is None else np.asarray(linear_level_db, dtype=float)
    shown = [v[good] for v in series.values()] + ([linear] if linear is not None else [])
    finite = np.concatenate([v[np.isfinite(v)] for v in shown]) if shown else np.zeros(0)
    if target_dba is not None:
        finite = np.append(finite, float(target_dba))
    top = float(finite.max()) if finite.size else 0.0
    floor = top - dynamic_range_db
    primary = np.where(good, series["db"], np.nan)
    jumps = jump_starts(primary[good]) if good.any() else np.zeros(0, bool)
    jumps_all = np.zeros(n, dtype=bool)
    jumps_all[np.flatnonzero(good)] = jumps
    jumps = jumps_all
    fig = _figure(9.0, 4.2)
    ax = fig.add_subplot()
    labelled = set()
    for key, color, prefix in (("db", "C0", "ERP [dB], "), ("dba", "C1", "ERP [dB(A)], ")):
        if key not in series:
            continue
        y = np.where(good & np.isfinite(series[key]) & (series[key] >= floor), series[key], np.nan)
        _plot_branches(ax, x, y, category, color, prefix, labelled=set(), jumps=jumps)
        low = good & ~(np.isfinite(series[key]) & (series[key] >= floor))
        if low.any() and "low" not in labelled:  # a rug on the lower edge, whatever the limits
            ax.plot(x[low], np.full(low.sum(), 0.015), linestyle="none", marker="v", color="0.5",
                    markersize=3, alpha=0.7, transform=ax.get_xaxis_transform(), clip_on=False,
                    label=f"below the plotted range ({int(low.sum())} points; silent)")
            labelled.add("low")
    if linear is not None:
        y = np.where(np.isfinite(linear) & (linear >= floor), linear, np.nan)
        order = np.argsort(x, kind="stable")
        if np.isfinite(y).any():
            ax.plot(x[order], y[order], color="0.5", linewidth=0.8, label="linear baseline [dB]")
    if not good.all():
        y = series.get("dba", series["db"])
        y = np.where(np.isfinite(y) & (y >= floor), y, floor)
        ax.plot(x[~good], y[~good], linestyle="none", marker="o", markerfacecolor="none",
                color="red", label="not converged (not a result)")
    if target_dba is not None:
        ax.axhline(float(target_dba), color="red", linestyle="--", linewidth=1.0,
                   label=f"target {float(target_dba):.1f} dB(A)")
    if loudest_index is not None and 0 <= int(loudest_index) < n:
        j = int(loudest_index)
        y = series.get("dba", series["db"])[j]
        if np.isfinite(y):
            ax.plot([x[j]], [y], marker="*", markersize=11, color="k", linestyle="none",
                    label=f"loudest point {x[j]:.4g} Hz")
    if finite.size:
        low = float(finite[finite >= floor].min())
        margin = 0.05 * max(top - low, 1.0)
        ax.set_ylim(low - margin, top + margin)
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("ERP level [dB re 1 pW]" + (" / [dB(A)]" if level_a_db is not None else ""))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="x-small", loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
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
    step = max(1, int(np.ceil(H / 10)))           # at most ~10 labels: they never run together
    ax.set_xticks(positions[::step])
    ax.set_xticklabels([f"{k + 1}\n{fk:.4g}" for k, fk in enumerate(f)][::step], fontsize="small")
    ax.set_xlabel("harmonic k / frequency [Hz]")
    ax.set_ylabel("ERP level")
    ax.set_ylim(floor, top)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return _save(fig, path)


_STATE_COLORS = ("#d9d9d9", "#4c9be8", "#e8804c")   # open, closed/stick, slip


def plot_friction(path, friction_time, state, names=None, omega=None, title=None) -> Path:
    """Friction force |λ_t|(θ_j) [N] (top) and the contact state (bottom: open grey, stick blue,
    slip orange) over one period, one row per squeak contact.

    friction_time : (N, n) [N]; state : (N, n) int (0 open, 1 stick, 2 slip); x axis as in
    :func:`plot_contact_forces`.
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    F = np.asarray(friction_time, dtype=float).reshape(len(friction_time), -1)
    S = np.asarray(state).reshape(len(state), -1)
    N, n = F.shape
    phase = np.arange(N + 1) / N
    x = phase * 2 * np.pi / omega * 1e3 if omega else phase
    names = list(names) if names is not None else [f"contact {i}" for i in range(n)]
    fig = _figure(7.0, 3.0 + 0.35 * n)
    top, bottom = fig.subplots(2, 1, sharex=True,
                               gridspec_kw={"height_ratios": [3, max(1.0, 0.45 * n)]})
    for i in range(n):
        top.plot(x, np.concatenate([F[:, i], F[:1, i]]), label=str(names[i]))
    top.set_ylabel("friction force [N]")
    top.grid(True, alpha=0.3)
    handles = top.get_lines()[:12] + [Patch(color=c, label=t) for c, t in zip(
        _STATE_COLORS, ("state: open", "stick", "slip"))]
    top.legend(handles=handles, fontsize="x-small", ncol=2)
    bottom.pcolormesh(x, np.arange(n + 1), S.T.astype(float), cmap=ListedColormap(_STATE_COLORS),
                      vmin=-0.5, vmax=2.5, shading="flat")
    bottom.set_yticks(np.arange(n) + 0.5)
    bottom.set_yticklabels([str(v) for v in names], fontsize="x-small")
    bottom.set_xlabel("time [ms]" if omega else "phase θ/2π [-]")
    if title:
        top.set_title(title)
    return _save(fig, path)


def plot_third_octave(path, nominal_hz, level_dba, linear_level_dba=None, linear_nominal_hz=None,
                      target_dba=None, title=None) -> Path:
    """ERP per third-octave band [dB(A)] as bars (nominal mid-band labels), the linear baseline's
    bands as grey diamonds and an optional target line; empty bands (−inf) get no bar."""
    f = [float(v) for v in nominal_hz]
    level = np.asarray(level_dba, dtype=float)
    labels = [f"{v:g}" for v in f]
    if linear_nominal_hz is not None:
        labels += [f"{float(v):g}" for v in linear_nominal_hz if f"{float(v):g}" not in labels]
    order = sorted(set(labels), key=float)
    pos = {lab: i for i, lab in enumerate(order)}
    values = [v for v in level if np.isfinite(v)]
    if linear_level_dba is not None:
        values += [v for v in np.asarray(linear_level_dba, dtype=float) if np.isfinite(v)]
    if target_dba is not None:
        values.append(float(target_dba))
    floor = float(np.floor((min(values) if values else 0.0) / 10.0) * 10.0 - 10.0)
    top = (max(values) if values else floor) + 5.0
    floor = max(floor, top - 90.0)
    fig = _figure(7.0, 3.8)
    ax = fig.add_subplot()
    xs = [pos[f"{v:g}"] for v in f]
    heights = np.where(np.isfinite(level), level - floor, 0.0).clip(0.0)
    ax.bar(xs, heights, 0.7, bottom=floor, color="C1", label="nonlinear [dB(A)]")
    if linear_level_dba is not None:
        lx = [pos[f"{float(v):g}"] for v in linear_nominal_hz]
        ly = np.asarray(linear_level_dba, dtype=float)
        keep = np.isfinite(ly) & (ly >= floor)
        ax.plot(np.asarray(lx)[keep], ly[keep], "D", color="0.4", label="linear baseline [dB(A)]")
    if target_dba is not None:
        ax.axhline(float(target_dba), color="red", linestyle="--", linewidth=1.0,
                   label=f"target {float(target_dba):.1f} dB(A)")
    step = max(1, int(np.ceil(len(order) / 14)))
    ax.set_xticks(range(len(order))[::step])
    ax.set_xticklabels(order[::step], rotation=45, fontsize="small")
    ax.set_xlabel("third-octave band, nominal mid-band frequency [Hz]")
    ax.set_ylabel("ERP level [dB(A) re 1 pW]")
    ax.set_ylim(floor, top)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize="x-small")
    if title:
        ax.set_title(title)
    return _save(fig, path)


def plot_contributions(path, names, level_dba, share_a, title=None, part_level_dba=None) -> Path:
    """Horizontal bars of the coherent A-weighted share [%] of each source (ranked as given),
    annotated with the level of its part of the total (``part_level_dba``, monotone with the
    bar) and its level alone (``level_dba``: what it radiates by itself; '-' for no sound)."""
    names = [str(v) for v in names]
    share = 100.0 * np.nan_to_num(np.asarray(share_a, dtype=float))
    level = np.asarray(level_dba, dtype=float)
    part = np.full(len(names), np.nan) if part_level_dba is None \
        else np.array([np.nan if v is None else v for v in part_level_dba], dtype=float)
    fig = _figure(7.0, 1.2 + 0.35 * len(names))
    ax = fig.add_subplot()
    y = np.arange(len(names))[::-1]
    colors = ["C3" if v >= 0 else "C0" for v in share]
    ax.barh(y, share, color=colors)
    for yi, s_, lv, pv in zip(y, share, level, part):
        alone = f"{lv:.1f}" if np.isfinite(lv) else "-"
        percent = int(round(s_))
        text = f" {percent} %" + (f" = {pv:.1f} dB(A)" if np.isfinite(pv) and percent > 0
                                  else "") + f" (alone {alone})"
        ax.annotate(text, (max(s_, 0.0), yi), va="center", fontsize="x-small")
    ax.set_yticks(y)
    ax.set_yticklabels(names, fontsize="small")
    ax.set_xlabel("coherent share of the A-weighted ERP [%]")
    ax.axvline(0.0, color="k", linewidth=0.6)
    ax.set_xlim(min(0.0, share.min(initial=0.0)) - 5, max(100.0, share.max(initial=0.0)) + 55)
    ax.grid(True, axis="x", alpha=0.3)
    if title:
        ax.set_title(title)
    return _save(fig, path)


def plot_audibility(path, band_hz, spl_db, background_db, threshold_in_quiet_db,
                    masked_threshold_db, title=None) -> Path:
    """Third-octave SPL at the occupant [dB re 20 µPa] as bars (ISO 532-1 bands 25 Hz … 12.5 kHz)
    against the background bands, the masked threshold and the threshold in quiet: a bar above
    both thresholds is audible (its margin annotated)."""
    f = np.asarray(band_hz, dtype=float)
    spl, back = np.asarray(spl_db, dtype=float), np.asarray(background_db, dtype=float)
    quiet = np.asarray(threshold_in_quiet_db, dtype=float)
    masked = np.asarray(masked_threshold_db, dtype=float)
    threshold = np.fmax(quiet, np.where(np.isfinite(masked), masked, -np.inf))
    x = np.arange(f.size)
    values = np.concatenate([v[np.isfinite(v)] for v in (spl, back, threshold)])
    floor = float(np.floor(min(values.min(initial=0.0), 0.0) / 10.0) * 10.0)
    top = float(values.max(initial=60.0)) + 8.0
    fig = _figure(7.0, 3.8)
    ax = fig.add_subplot()
    ax.bar(x, np.where(np.isfinite(spl), spl - floor, 0.0).clip(0.0), 0.7, bottom=floor,
           color="C1", label="prediction at the occupant")
    if np.isfinite(back).any():
        ax.plot(x, np.where(np.isfinite(back), back, np.nan), "s", color="0.55", markersize=3,
                label="background")
        ax.plot(x, np.where(np.isfinite(masked), masked, np.nan), "-", color="C0",
                label="masked threshold")
    ax.plot(x, quiet, "--", color="k", linewidth=1.0, label="threshold in quiet (ISO 226)")
    for xi, level, limit in zip(x, spl, threshold):
        if np.isfinite(level) and level > limit:
            ax.annotate(f"+{level - limit:.0f}", (xi, level), ha="center", va="bottom",
                        fontsize="xx-small", color="C3")
    step = 2
    ax.set_xticks(x[::step])
    ax.set_xticklabels([f"{v:g}" for v in f[::step]], rotation=45, fontsize="small")
    ax.set_xlabel("third-octave band, nominal mid-band frequency [Hz]")
    ax.set_ylabel("SPL [dB re 20 µPa]")
    ax.set_ylim(floor, top)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize="x-small", loc="upper right")
    if title:
        ax.set_title(title)
    return _save(fig, path)


def plot_surface_map(path, points, triangles, values, label, title=None, clim=None,
                     cmap="inferno") -> Path:
    """A nodal scalar on the surface triangles, seen along the axis of least extent (the panel's
    thickness direction), with matplotlib's tripcolor — the fallback of the 3-D renders."""
    P = np.asarray(points, dtype=float)
    T = np.asarray(triangles, dtype=int)
    axis = int(np.argmin(np.ptp(P, axis=0)))
    a, b = [i for i in range(3) if i != axis]
    fig = _figure(6.4, 4.4)
    ax = fig.add_subplot()
    v = np.asarray(values, dtype=float)
    off = np.isnan(v[T]).any(axis=1)       # NaN: off the map's surface, drawn grey, not coloured
    if off.any():
        ax.tripcolor(P[:, a], P[:, b], T[off], facecolors=np.ones(int(off.sum())), cmap="Greys",
                     vmin=0.0, vmax=3.0)
    image = ax.tripcolor(Triangulation(P[:, a], P[:, b], T, mask=off), np.nan_to_num(v),
                         shading="gouraud", cmap=cmap,
                         vmin=None if clim is None else clim[0],
                         vmax=None if clim is None else clim[1])
    fig.colorbar(image, ax=ax, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    if title:
        ax.set_title(title)
    return _save(fig, path)
