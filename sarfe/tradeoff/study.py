r"""``sarfe study``: vary one knob at a time around a case's settings and measure the speed/accuracy trade.

Knobs (levels around the case value v; the finest level of each knob is that knob's reference):

    harmonics          H ∈ {⌈v/2⌉, v, 2v, 4v}            (N raised to ≥ 4H+1 where needed)
    samples            N ∈ {v/2, v, 2v, 8v}              (each ≥ 4H+1)
    modes              fixed-interface modes {v/2, v, 2v, 4v}  (FE cases; linear stage rebuilt)
    mesh               element size {2v, v, v/√2, v/2}   (generated meshes; linear stage rebuilt;
                       the ladder's own Richardson estimate per rung: :func:`mesh_ladder`)
    penalty            k_n, k_t × {0.3, 1, 3, 10}        (contact model sensitivity, not a discretization)

Each variant solves the same frequency grid (``points`` frequencies over the sweep, or the listed
frequencies) by stepping in frequency with warm starts, as ``sarfe solve`` does for listed points.
Per variant: ERP level (max over the grid) [dB re 1 pW] and [dB(A)], peak normal contact force [N],
largest first-harmonic normal amplitude at the contacts [m]; errors against the knob's reference at
every grid point converged in both (max over points): |ΔL| [dB], |ΔL_A| [dB], relative force and
amplitude errors; cost: wall time [s] (linear stage included when rebuilt), Newton iterations,
peak traced memory [MB] (tracemalloc, numpy buffers included); the a-posteriori estimate
(:func:`sarfe.accuracy.estimates.estimate_errors`, max over the grid, not timed).
The linear stage is built once and reused for harmonics / samples / penalty variants.
"""
from __future__ import annotations

import csv
import json
import math
import time
import tracemalloc
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sarfe.accuracy import resize_harmonics
from sarfe.accuracy.mesh_refinement import MESH_ORDER, mesh_richardson
from sarfe.erp import equivalent_radiated_power
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.time_integration import linear_harmonic_response
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

KNOBS = ("harmonics", "samples", "modes", "mesh", "penalty")


@dataclass
class StudyResult:
    case: str
    rows: list                       # one dict per variant
    frequencies_hz: np.ndarray
    summary: dict = field(default_factory=dict)
    output_dir: Path | None = None
    files: dict = field(default_factory=dict)


# ------------------------------------------------------------------------------------ variants
def knob_levels(case, stage, knobs=None) -> dict:
    """{knob: [(label, value), …]} for the applicable knobs (module docstring), finest last."""
    config = case.config
    H, N = config.solver.harmonics, config.solver.samples_per_period
    out = {}
    knobs = KNOBS if knobs is None else tuple(knobs)
    unknown = set(knobs) - set(KNOBS)
    if unknown:
        raise ValueError(f"unknown knob(s) {sorted(unknown)}; choose from {', '.join(KNOBS)}")
    if "harmonics" in knobs:
        values = sorted({max(1, math.ceil(H / 2)), H, min(200, 2 * H), min(200, 4 * H)})
        out["harmonics"] = [(f"H={v}", v) for v in values]
    if "samples" in knobs:
        values = sorted({max(4 * H + 1, N // 2), N, 2 * N, 8 * N})
        out["samples"] = [(f"N={v}", v) for v in values]
    if "penalty" in knobs and config.contacts:
        out["penalty"] = [(f"k×{v:g}", v) for v in (0.3, 1.0, 3.0, 10.0)]
    if case.is_fe and "modes" in knobs:
        m = int(stage.info.get("modes", len(stage.mode_frequencies_hz)) or 0)
        if m:
            values = sorted({max(1, m // 2), m, 2 * m, 4 * m})
            out["modes"] = [(f"modes={v}", v) for v in values]
    fe = config.model.fe
    if "mesh" in knobs and fe is not None and fe.source == "generator":
        h = float(fe.generator.mesh_size_m or 0)
        if h > 0:
            out["mesh"] = [(f"h={v * 1e3:.3g}mm", v) for v in (2 * h, h, h / math.sqrt(2), h / 2)]
    return out


def variant_case(case, knob, value):
    """A new Case with one knob changed (see module docstring), through the typed case API
    (:meth:`sarfe.case.read.Case.with_solver` …): harmonics (N doubled to at least 4H + 1),
    samples, penalty (every contact's normal and tangential stiffness × value), modes (a mode
    count instead of a cutoff, no minimum) or mesh (the generator's mesh size)."""
    if knob == "harmonics":
        N = int(case.config.solver.samples_per_period)
        while N < 4 * value + 1:
            N *= 2
        return case.with_solver(harmonics=int(value), samples_per_period=N)
    if knob == "samples":
        return case.with_solver(samples_per_period=int(value))
    if knob == "penalty":
        for index, contact in enumerate(case.config.contacts):
            changes = {key: contact.params[key] * value
                       for key in ("normal_stiffness_N_m", "tangential_stiffness_N_m")
                       if key in contact.params}
            if changes:
                case = case.with_contact(index, **changes)
        return case
    if knob == "modes":
        return case.with_reduction(cutoff_hz=None, mode_count=int(value), min_mode_count=0)
    if knob == "mesh":
        return case.with_generator(mesh_size_m=float(value))
    return case


def frequency_grid(case, points=16) -> np.ndarray:
    """[Hz]: the listed frequencies, or ``points`` evenly spaced over the sweep."""
    exc = case.config.excitation
    if exc.frequency_hz is not None:
        return np.atleast_1d(np.asarray(exc.frequency_hz, dtype=float))
    return np.linspace(exc.sweep.start_hz, exc.sweep.end_hz, int(points))


# --------------------------------------------------------------------------------------- solve
def solve_grid(case, stage, frequencies_hz, options=None, guesses=None):
    """Solve the grid. Without ``guesses``: stepped in frequency (warm start from the previous point;
    a failed point is retried once from the linear guess) — a cold sweep. With ``guesses`` (one ũ
    (2H+1, n) or None per point): each point starts from its guess (branch matching).
    Returns (points, cost): one dict per frequency (converged, ERP dB / dB(A), peak normal force,
    first-harmonic normal amplitude, the HarmonicSolution under ``_solution``) and
    {'solve_s', 'iterations'}."""
    nl = nonlinear_model(case, stage)
    solver = case.config.solver
    H, N = solver.harmonics, solver.samples_per_period
    options = options or SolverOptions(tolerance=solver.tolerance,
                                       max_iterations=solver.max_iterations, stability=False)
    solutions, iterations, previous = [], 0, None
    clock = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i, f in enumerate(frequencies_hz):
            omega = 2 * np.pi * float(f)
            start = previous if guesses is None else guesses[i]
            s = solve_frequency(nl.model, nl.contacts, nl.excitation, omega, H, N,
                                initial=start, options=options)
            if not s.converged and start is not None:
                iterations += s.iterations
                retry = solve_frequency(nl.model, nl.contacts, nl.excitation, omega, H, N,
                                        options=options)
                s = retry if retry.converged else s
            iterations += s.iterations
            solutions.append(s)
            previous = s if s.converged else None
    seconds = time.perf_counter() - clock
    points = []
    for s in solutions:
        level, level_a = erp_levels(case, stage, s.displacement, s.omega)
        force, amplitude = contact_measures(s, nl)
        points.append({"frequency_hz": s.omega / (2 * np.pi), "converged": bool(s.converged),
                       "iterations": int(s.iterations), "erp_db": level, "erp_dba": level_a,
                       "peak_force_N": force, "amplitude_m": amplitude, "_solution": s})
    return points, {"solve_s": seconds, "iterations": iterations}


def erp_levels(case, stage, displacement, omega):
    """(L_W, L_WA) [dB re reference power] of displacement harmonics (2H+1, n) at ω (−inf if silent)."""
    erp = case.config.erp
    W = np.asarray(displacement) @ np.asarray(stage.erp_map).T
    if W.shape[1] == 0:
        return float("-inf"), float("-inf")
    with np.errstate(divide="ignore"):
        r = equivalent_radiated_power(W, omega, stage.erp_areas, density=erp.rho_kg_m3,
                                      sound_speed=erp.c_m_s,
                                      radiation_loss_factor=erp.radiation_loss_factor,
                                      reference_power=erp.reference_power_W)
    return float(r.level_total_db), float(r.level_total_a_db)


def contact_measures(solution, nl):
    """(peak normal contact force [N], largest first-harmonic normal amplitude [m]) over the named
    contacts; the force of a named contact is the sum over its node pairs (+ constant normal loads)."""
    c = nl.contacts
    if not c.count:
        return 0.0, 0.0
    force_time = np.asarray(solution.contact_force_time)
    R = np.asarray(solution.contact_displacement)
    peak, amplitude = 0.0, 0.0
    for _, _, idx in nl.groups:
        rows = c.normal_row[idx]
        rows = rows[rows >= 0]
        total = force_time[:, rows].sum(axis=1) if rows.size else np.zeros(force_time.shape[0])
        peak = max(peak, float((total + c.normal_load[idx].sum()).max()))
        if rows.size:
            amplitude = max(amplitude, float(np.hypot(R[1, rows], R[2, rows]).max()))
    return peak, amplitude


def branch_guesses(case, stage, baseline_points):
    """Starting guesses ũ (2H+1, n) of a variant from the case-setting solutions at the same
    frequencies: the displacement resized to the variant's H when the DOFs match, else (same contact
    rows, e.g. another mode count) the linear response to f̃_e − Gᵀλ̃ of the baseline contact forces;
    None where neither applies."""
    nl = nonlinear_model(case, stage)
    H = case.config.solver.harmonics
    guesses = []
    for p in baseline_points:
        s = p.get("_solution")
        if s is None or not s.converged:
            guesses.append(None)
            continue
        U = np.asarray(s.displacement)
        if U.shape[1] == stage.dof_count:
            guesses.append(resize_harmonics(U, H))
        elif np.asarray(s.contact_force).shape[1] == nl.contacts.row_count:
            lam = resize_harmonics(s.contact_force, H)
            F = nl.excitation - np.asarray(nl.contacts.gap_map.T @ lam.T).T
            guesses.append(linear_harmonic_response(nl.model, F, s.omega))
        else:
            guesses.append(None)
    return guesses


def attach_estimates(case, stage, points):
    """estimate_errors at every converged grid point (adds estimate_amplitude_rel / _erp_db)."""
    nl = nonlinear_model(case, stage)
    for p in points:
        s = p.get("_solution")
        if s is None or not s.converged:
            continue
        e = stage_error_estimate(s, stage, nl)
        p["estimate_amplitude_rel"] = e.amplitude_rel
        p["estimate_erp_db"] = e.erp_db
        p["estimate_harmonics_rel"] = e.harmonics_rel
        p["estimate_aliasing_rel"] = e.aliasing_rel
        p["estimate_modal_rel"] = e.modal_rel


DYNAMIC_RANGE_DB = 60.0


def _errors(points, reference, dynamic_range_db=DYNAMIC_RANGE_DB):
    """Max over grid points converged in both: |ΔL|, |ΔL_A| [dB] with both levels floored at the
    reference's loudest level − ``dynamic_range_db`` (silent points, e.g. −230 dB when no impact
    excites the radiating part, would otherwise dominate), relative force and amplitude errors."""
    pairs = [(p, r) for p, r in zip(points, reference) if p["converged"] and r["converged"]]
    nan = float("nan")
    if not pairs:
        return {"erp_db_error": nan, "erp_dba_error": nan, "force_rel_error": nan,
                "amplitude_rel_error": nan, "compared_points": 0}
    f_ref = max(r["peak_force_N"] for _, r in pairs) or 1.0
    a_ref = max(r["amplitude_m"] for _, r in pairs) or 1.0

    def level_error(key):
        top = max((r[key] for _, r in pairs if np.isfinite(r[key])), default=nan)
        if not np.isfinite(top):
            return nan
        floor = top - dynamic_range_db
        values = [abs(max(p[key], floor) - max(r[key], floor)) for p, r in pairs
                  if not (np.isnan(p[key]) or np.isnan(r[key]))]
        return max(values) if values else nan

    return {
        "erp_db_error": level_error("erp_db"),
        "erp_dba_error": level_error("erp_dba"),
        "force_rel_error": max(abs(p["peak_force_N"] - r["peak_force_N"]) for p, r in pairs) / f_ref,
        "amplitude_rel_error": max(abs(p["amplitude_m"] - r["amplitude_m"]) for p, r in pairs) / a_ref,
        "compared_points": len(pairs),
    }


def _max(values):
    values = [v for v in values if v is not None and np.isfinite(v)]
    return max(values) if values else float("nan")


def run_variant(case, stage, knob, label, value, frequencies_hz, estimate=True,
                baseline_points=None):
    """One variant → (row, points, stage). Cost: a cold stepped sweep of the grid (linear stage
    included when the knob rebuilds it), timed with tracemalloc on. Values and errors: the grid
    re-solved from the case-setting solutions (:func:`branch_guesses`), so every variant is compared
    on the same solution branch (folds make cold sweeps jump at slightly different frequencies)."""
    variant = variant_case(case, knob, value) if knob != "baseline" else case
    tracemalloc.start()
    clock = time.perf_counter()
    linear_s = 0.0
    try:
        if knob in ("modes", "mesh"):
            stage = build_linear_model(variant)
            linear_s = time.perf_counter() - clock
        cold, cost = solve_grid(variant, stage, frequencies_hz)
        wall = time.perf_counter() - clock
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    points = cold
    if baseline_points is not None:
        guesses = branch_guesses(variant, stage, baseline_points)
        if any(g is not None for g in guesses):
            points, _ = solve_grid(variant, stage, frequencies_hz, guesses=guesses)
    if estimate:
        attach_estimates(variant, stage, points)
    converged = [p for p in points if p["converged"]]
    solver = variant.config.solver
    row = {
        "knob": knob, "level": label, "value": value,
        "harmonics": int(solver.harmonics), "samples_per_period": int(solver.samples_per_period),
        "reduced_dofs": int(stage.dof_count),
        "erp_db": _max(p["erp_db"] for p in converged),
        "erp_dba": _max(p["erp_dba"] for p in converged),
        "peak_force_N": _max(p["peak_force_N"] for p in converged),
        "amplitude_m": _max(p["amplitude_m"] for p in converged),
        "cold_sweep_erp_db": _max(p["erp_db"] for p in cold if p["converged"]),
        "wall_s": wall, "linear_stage_s": linear_s, "solve_s": cost["solve_s"],
        "newton_iterations": cost["iterations"], "peak_memory_MB": peak / 1e6,
        "converged_points": len(converged), "points": len(points),
        "cold_converged_points": sum(p["converged"] for p in cold),
        "estimate_amplitude_rel": _max(p.get("estimate_amplitude_rel") for p in points),
        "estimate_erp_db": _max(p.get("estimate_erp_db") for p in points),
    }
    return row, points, stage


def run_study(case, knobs=None, points=12, frequencies_hz=None, output_dir=None, write=True,
              estimate=True, progress=None) -> StudyResult:
    """One-knob-at-a-time study of a case (module docstring). ``progress(text)`` is called per variant.

    Writes study.csv, study.json and study_pareto.png into ``output_dir`` (default
    ``<output.directory>/study``) unless ``write`` is False.
    """
    case = load_case(case)
    clock = time.perf_counter()
    stage = build_linear_model(case)
    base_linear_s = time.perf_counter() - clock
    grid = np.asarray(frequencies_hz if frequencies_hz is not None else frequency_grid(case, points),
                      dtype=float)
    levels = knob_levels(case, stage, knobs)
    if progress:
        progress("baseline (case settings): cold sweep")
    baseline, _ = solve_grid(case, stage, grid)
    rows, all_points = [], {}
    for knob, values in levels.items():
        knob_rows, knob_points = [], []
        for label, value in values:
            if progress:
                progress(f"{knob}: {label}")
            row, pts, _ = run_variant(case, stage, knob, label, value, grid, estimate, baseline)
            row["baseline"] = _is_baseline(case, stage, knob, value)
            knob_rows.append(row)
            knob_points.append(pts)
        reference = knob_points[-1]
        for row, pts in zip(knob_rows, knob_points):
            row.update(_errors(pts, reference))
            row["reference"] = values[-1][0]
        if knob == "mesh":
            mesh_ladder(knob_rows, knob_points)
        rows += knob_rows
        all_points[knob] = [[{k: v for k, v in p.items() if not k.startswith("_")} for p in pts]
                            for pts in knob_points]
    summary = {
        "case": case.name, "case_file": case.source, "frequencies_hz": grid.tolist(),
        "linear_stage_s": base_linear_s,
        "knobs": {k: [label for label, _ in v] for k, v in levels.items()},
        "reference": "per knob: its finest level, the other knobs at the case values",
        "method": "values/errors branch-matched (each point started from the case-setting solution);"
                  " cost = cold stepped sweep over the grid",
        "baseline_converged_points": int(sum(p["converged"] for p in baseline)),
        "rows": rows, "points": all_points,
    }
    result = StudyResult(case.name, rows, grid, summary)
    if write:
        target = Path(output_dir) if output_dir is not None else (
            Path(case.config.output.directory) / "study")
        result.files = write_study(result, target)
        result.output_dir = target
    return result


def mesh_ladder(rows, points, order=MESH_ORDER):
    """The mesh ladder's own error estimate (:mod:`sarfe.accuracy.mesh_refinement`, (1)): each
    rung but the coarsest against the next coarser one, r = h_coarser / h, at every grid point
    converged in both (max over points, dB(A) and dB alike) → ``mesh_estimate_db``, and
    ``mesh_estimate_covers``: whether it is at least the rung's error against the finest rung
    (``erp_db_error``/``erp_dba_error``, the larger); the finest rung has no error to cover."""
    for k, row in enumerate(rows):
        row["mesh_estimate_db"], row["mesh_estimate_covers"] = float("nan"), None
        if k == 0:
            continue
        ratio = float(rows[k - 1]["value"]) / float(row["value"])
        estimates = [mesh_richardson(p[key], c[key], order, ratio)
                     for p, c in zip(points[k], points[k - 1]) if p["converged"] and c["converged"]
                     for key in ("erp_db", "erp_dba")]
        estimates = [e for e in estimates if np.isfinite(e)]
        if not estimates:
            continue
        row["mesh_estimate_db"] = max(estimates)
        if k < len(rows) - 1:
            error = _max([row.get("erp_db_error"), row.get("erp_dba_error")])
            row["mesh_estimate_covers"] = bool(row["mesh_estimate_db"] >= error) \
                if np.isfinite(error) else None


def _is_baseline(case, stage, knob, value):
    config = case.config
    if knob == "harmonics":
        return value == config.solver.harmonics
    if knob == "samples":
        return value == config.solver.samples_per_period
    if knob == "penalty":
        return value == 1.0
    if knob == "modes":
        return value == stage.info.get("modes")
    if knob == "mesh":
        return value == config.model.fe.generator.mesh_size_m
    return False


# -------------------------------------------------------------------------------------- output
COLUMNS = ("knob", "level", "harmonics", "samples_per_period", "reduced_dofs", "erp_db", "erp_dba",
           "peak_force_N", "amplitude_m", "erp_db_error", "erp_dba_error", "force_rel_error",
           "amplitude_rel_error", "estimate_amplitude_rel", "estimate_erp_db", "wall_s",
           "linear_stage_s", "newton_iterations", "cold_sweep_erp_db", "cold_converged_points", "peak_memory_MB", "converged_points", "points",
           "baseline", "reference", "mesh_estimate_db", "mesh_estimate_covers")


def study_table(rows) -> str:
    """Console table, one line per variant (the case's own setting marked *)."""
    head = (f"{'knob':<10} {'level':<14} {'ERP dB':>7} {'dB(A)':>7} {'F_peak N':>9} {'a1 m':>9} "
            f"{'|ΔdB|':>7} {'ΔF rel':>8} {'Δa1 rel':>8} {'est rel':>8} {'time s':>7} {'iter':>5} "
            f"{'MB':>6} {'conv':>5}")
    lines = [head, "-" * len(head)]
    for r in rows:
        mark = "*" if r.get("baseline") else " "
        lines.append(
            f"{r['knob']:<10} {mark}{r['level']:<13} {r['erp_db']:7.2f} {r['erp_dba']:7.2f} "
            f"{r['peak_force_N']:9.3g} {r['amplitude_m']:9.3g} {r['erp_db_error']:7.3f} "
            f"{r['force_rel_error']:8.2e} {r['amplitude_rel_error']:8.2e} "
            f"{r.get('estimate_amplitude_rel', float('nan')):8.2e} {r['wall_s']:7.2f} "
            f"{r['newton_iterations']:5d} {r['peak_memory_MB']:6.1f} "
            f"{r['converged_points']:>2}/{r['points']:<2}")
    mesh = [r for r in rows if r["knob"] == "mesh" and np.isfinite(r.get("mesh_estimate_db",
                                                                             float("nan")))]
    if mesh:   # the mesh ladder's Richardson estimates (mesh_ladder)
        lines.append(f"mesh ladder (Richardson from the next coarser rung, p = {MESH_ORDER:g} "
                     "stated): " + "; ".join(
                         f"{r['level']} ±{r['mesh_estimate_db']:.2f} dB" + (
                             "" if r["mesh_estimate_covers"] is None else
                             f" ({'covers' if r['mesh_estimate_covers'] else 'does NOT cover'} "
                             f"|ΔdB| {_max([r['erp_db_error'], r['erp_dba_error']]):.2f})")
                         for r in mesh))
    lines.append("errors: against the finest level of the same knob (reference column); "
                 "* = the case's setting; est rel = a-posteriori estimate (max over points)")
    return "\n".join(lines)


def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.bool_):
        return bool(value)
    return str(value)


def _clean(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def write_study(result: StudyResult, directory) -> dict:
    """study.csv, study.json (NaN → null), study_pareto.png → {kind: path}."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    files = {}
    path = directory / "study.csv"
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for row in result.rows:
            writer.writerow(row)
    files["csv"] = str(path)
    path = directory / "study.json"
    path.write_text(json.dumps(_clean(result.summary), indent=1, default=_json_default))
    files["json"] = str(path)
    files["pareto_png"] = str(plot_pareto(result.rows, directory / "study_pareto.png",
                                          title=result.case))
    return files


def plot_pareto(rows, path, title=""):
    """Error vs wall time per knob (log-log); the Pareto front of all variants dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, label in ((axes[0], "amplitude_rel_error", "first-harmonic amplitude error [-]"),
                           (axes[1], "erp_db_error", "ERP level error [dB]")):
        floor = 1e-16 if key == "amplitude_rel_error" else 1e-12
        pts = []
        for knob in dict.fromkeys(r["knob"] for r in rows):
            sub = [r for r in rows if r["knob"] == knob and r["level"] != r.get("reference")]
            x = [r["wall_s"] for r in sub]
            y = [max(r[key], floor) if np.isfinite(r[key]) else np.nan for r in sub]
            ax.loglog(x, y, "o-", label=knob)
            for r, xi, yi in zip(sub, x, y):
                ax.annotate(r["level"], (xi, yi), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
                if np.isfinite(yi):
                    pts.append((xi, yi))
        front, best = [], np.inf
        for xi, yi in sorted(pts):
            if yi < best:
                front.append((xi, yi))
                best = yi
        if front:
            ax.loglog(*zip(*front), "k--", lw=0.8, label="Pareto front")
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{title}: error vs cost (each knob against its finest level)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


__all__ = ["KNOBS", "StudyResult", "knob_levels", "variant_case", "frequency_grid", "solve_grid",
           "attach_estimates", "mesh_ladder", "erp_levels", "contact_measures", "branch_guesses", "run_variant", "run_study", "study_table", "write_study",
           "plot_pareto"]
