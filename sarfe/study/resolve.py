r"""Accuracy of a whole case as an input: ``solver: {accuracy: fast | balanced | fine | {erp_db: x} |
{amplitude_rel: x}}`` → H, N and the fixed-interface mode count.

1. a stepped solve over a coarse grid (``points`` frequencies) at the case's H, N (screening);
2. the grid point with the largest a-posteriori estimate (nonlinearity is strongest there) is refined
   by :func:`sarfe.study.accuracy.choose_resolution` (H up until the truncation estimate, then N up
   until the aliasing estimate are each within half the budget);
3. FE cases: the mode count from :func:`sarfe.study.accuracy.suggest_mode_count` (and doubled when
   the modal estimate — the re-solve on the coarser Craig–Bampton model, (4) there — exceeds half
   the budget).

The chosen values, the estimate that justified them and the history are returned; the pipeline can
apply them with :func:`apply_resolution` (see the integration notes in the report).
"""
from __future__ import annotations

import copy
import time

import numpy as np


def resolve_case_accuracy(case, target, points=8, start_harmonics=3, start_samples=64,
                          max_harmonics=64, max_samples=8192, max_points_tuned=3,
                          linear_stage=None) -> dict:
    """Choose H, N (and mode count) for ``target`` (see module docstring) → report dict with keys
    harmonics, samples_per_period, mode_count (None for matrices cases), estimate, met, reason,
    frequency_hz, tuned_hz, history, seconds, text, note. ``linear_stage``: reuse a built stage."""
    from sarfe.io.case import load_case
    from sarfe.pipeline import build_linear_model, nonlinear_model

    from .accuracy import (choose_resolution, parse_accuracy, resize_harmonics,
                           stage_modal_coordinates, suggest_mode_count)

    from .runner import attach_estimates, frequency_grid, solve_grid

    clock = time.perf_counter()
    target = parse_accuracy(target)
    case = load_case(case)
    stage = linear_stage if linear_stage is not None else build_linear_model(case)
    screen = case        # screening at the case's own H, N (a coarser pass can miss impacts)
    grid = frequency_grid(case, points)
    pts, _ = solve_grid(screen, stage, grid)
    attach_estimates(screen, stage, pts)
    converged = [p for p in pts if p["converged"]]
    if not converged:
        return {"harmonics": case.data["solver"]["harmonics"],
                "samples_per_period": case.data["solver"]["samples_per_period"],
                "mode_count": None, "estimate": None, "met": False,
                "reason": "no grid point converged in the screening pass", "frequency_hz": None,
                "history": [], "seconds": time.perf_counter() - clock,
                "text": f"accuracy {target.name}: no grid point converged; case settings kept"}
    active = [p for p in converged if p["peak_force_N"] > 0]
    if not active and any(not p["converged"] for p in pts):
        note = ("no converged screening point has an active contact (the others did not converge): "
                "tuned at a linear point, the choice may be too coarse for the impacts")
    else:
        note = ""
    candidates = sorted(active or converged,
                        key=lambda p: -np.nan_to_num(p.get("estimate_amplitude_rel", 0.0)))
    nl = nonlinear_model(case, stage)
    modal, residual = stage_modal_coordinates(stage)
    solver = case.data["solver"]

    def adapt(point, H0, N0):
        return choose_resolution(target, nl.model, nl.contacts, nl.excitation,
                                 2 * np.pi * point["frequency_hz"], harmonics=H0,
                                 samples_per_period=N0, max_harmonics=max_harmonics,
                                 max_samples=max_samples, erp_map=stage.erp_map,
                                 erp_areas=stage.erp_areas, modal_dofs=modal,
                                 residual_dofs=residual,
                                 initial=resize_harmonics(point["_solution"].displacement, H0))

    tuned = []
    for point in candidates[:max_points_tuned]:
        resolution = adapt(point, start_harmonics, start_samples)
        lost = (point["peak_force_N"] > 0 and resolution.solution is not None
                and not np.abs(resolution.solution.contact_force_time).max() > 0)
        if lost:   # contact vanished from the coarse start: adapt from the case's H, N instead
            resolution = adapt(point, int(solver["harmonics"]), int(solver["samples_per_period"]))
            note = (note + "; " if note else "") + (
                f"{point['frequency_hz']:.2f} Hz: no contact at H = {start_harmonics}, adapted "
                f"from the case's H = {solver['harmonics']}")
        tuned.append((point, resolution))
    # the most demanding tuned point decides
    worst, resolution = max(tuned, key=lambda t: (t[1].harmonics, t[1].samples_per_period))
    H_all = max(r.harmonics for _, r in tuned)
    N_all = max(r.samples_per_period for _, r in tuned)
    met_all = all(r.met for _, r in tuned)
    mode = None
    if stage.kind == "fe":
        exc = case.data["excitation"]
        f_max = max(exc["frequency_hz"]) if "frequency_hz" in exc else max(
            exc["sweep"]["start_hz"], exc["sweep"]["end_hz"])
        reduced = stage.reduced
        freqs = getattr(reduced, "mode_frequencies_hz", stage.mode_frequencies_hz)
        mode = suggest_mode_count(freqs, f_max, H_all, target,
                                  modal_rel=resolution.estimate.modal_rel,
                                  current=stage.info.get("modes"))
        if mode["mode_count"] >= len(freqs):
            mode["note"] = (f"all {len(freqs)} computed modes are below the cutoff: the linear stage "
                            "computes more when mode_count is set")
    e = resolution.estimate
    tuned_text = ", ".join(f"{p['frequency_hz']:.2f}" for p, _ in tuned)
    reason = resolution.reason if met_all else "; ".join(
        f"{p['frequency_hz']:.2f} Hz: {r.reason}" for p, r in tuned if not r.met)
    text = (f"accuracy {target.name or 'target'} (amplitude budget {target.amplitude_budget():.2g}):"
            f" H = {H_all}, N = {N_all}"
            + (f", mode_count = {mode['mode_count']} ({mode['reason']})" if mode else "")
            + f"\n  tuned at {tuned_text} Hz "
            f"(active contacts, largest screening estimates); at {worst['frequency_hz']:.2f} Hz: "
            f"amplitude {e.amplitude_rel:.2e} (H→{e.extended_harmonics}: {e.harmonics_rel:.2e}, "
            f"N→2N: {e.aliasing_rel:.2e}, modes: {e.modal_rel:.2e}), ERP {e.erp_db:.3f} dB"
            f"\n  {'met' if met_all else 'NOT met'}: {reason} "
            f"({len(resolution.history)} rounds, {time.perf_counter() - clock:.1f} s)"
            + (f"\n  note: {note}" if note else ""))
    return {"harmonics": H_all, "samples_per_period": N_all,
            "tuned_hz": [p["frequency_hz"] for p, _ in tuned],
            "mode_count": None if mode is None else mode["mode_count"], "mode": mode,
            "estimate": e.as_dict(), "met": met_all, "reason": reason,
            "frequency_hz": worst["frequency_hz"], "history": resolution.history, "note": note,
            "seconds": time.perf_counter() - clock, "text": text}


def apply_resolution(case_data: dict, report: dict) -> dict:
    """Case data (a copy) with solver.harmonics / samples_per_period and reduction.mode_count set."""
    data = copy.deepcopy(case_data)
    data.setdefault("solver", {})
    data["solver"]["harmonics"] = int(report["harmonics"])
    data["solver"]["samples_per_period"] = int(report["samples_per_period"])
    data["solver"].pop("accuracy", None)
    if report.get("mode_count"):
        red = data.setdefault("reduction", {})
        red.pop("cutoff_hz", None)
        red["mode_count"] = int(report["mode_count"])
    return data


__all__ = ["resolve_case_accuracy", "apply_resolution"]
