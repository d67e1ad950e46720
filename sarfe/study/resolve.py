r"""Accuracy of a whole case as an input: ``solver: {accuracy: fast | balanced | fine | {erp_db: x} |
{amplitude_rel: x}}`` → H, N and the fixed-interface mode count.

1. a stepped solve over a coarse grid (``points`` frequencies) at H = 3, N = 64 (cheap screening);
2. the grid point with the largest a-posteriori estimate (nonlinearity is strongest there) is refined
   by :func:`sarfe.study.accuracy.choose_resolution` (H up until the truncation estimate, then N up
   until the aliasing estimate are each within half the budget);
3. FE cases: the mode count from :func:`sarfe.study.accuracy.suggest_mode_count` (and doubled when
   the modal estimate of the highest kept modes exceeds half the budget).

The chosen values, the estimate that justified them and the history are returned; the pipeline can
apply them with :func:`apply_resolution` (see the integration notes in the report).
"""
from __future__ import annotations

import copy
import time

import numpy as np


def resolve_case_accuracy(case, target, points=8, start_harmonics=3, start_samples=64,
                          max_harmonics=64, max_samples=8192) -> dict:
    """Choose H, N (and mode count) for ``target`` (see module docstring) → report dict with keys
    harmonics, samples_per_period, mode_count (None for matrices cases), estimate, met, reason,
    frequency_hz, history, seconds, text."""
    from sarfe.io.case import load_case
    from sarfe.pipeline import build_linear_model, nonlinear_model

    from .accuracy import choose_resolution, parse_accuracy, resize_harmonics, suggest_mode_count
    from .runner import attach_estimates, frequency_grid, solve_grid

    clock = time.perf_counter()
    target = parse_accuracy(target)
    case = load_case(case)
    stage = build_linear_model(case)
    data = copy.deepcopy(case.data)
    data["solver"]["harmonics"] = int(start_harmonics)
    data["solver"]["samples_per_period"] = int(max(start_samples, 4 * start_harmonics + 1))
    screen = load_case(data, base_dir=case.base_dir)
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
    worst = max(converged, key=lambda p: np.nan_to_num(p.get("estimate_amplitude_rel", 0.0)))
    nl = nonlinear_model(case, stage)
    modal = (np.arange(int(stage.info.get("boundary_dofs", 0)), stage.dof_count)
             if stage.kind == "fe" else None)
    omega = 2 * np.pi * worst["frequency_hz"]
    resolution = choose_resolution(target, nl.model, nl.contacts, nl.excitation, omega,
                                   harmonics=start_harmonics, samples_per_period=start_samples,
                                   max_harmonics=max_harmonics, max_samples=max_samples,
                                   erp_map=stage.erp_map, erp_areas=stage.erp_areas,
                                   modal_dofs=modal,
                                   initial=resize_harmonics(worst["_solution"].displacement,
                                                            start_harmonics))
    mode = None
    if stage.kind == "fe":
        exc = case.data["excitation"]
        f_max = max(exc["frequency_hz"]) if "frequency_hz" in exc else max(
            exc["sweep"]["start_hz"], exc["sweep"]["end_hz"])
        reduced = stage.reduced
        freqs = getattr(reduced, "mode_frequencies_hz", stage.mode_frequencies_hz)
        mode = suggest_mode_count(freqs, f_max, resolution.harmonics, target,
                                  modal_rel=resolution.estimate.modal_rel,
                                  current=stage.info.get("modes"))
        if mode["mode_count"] >= len(freqs):
            mode["note"] = (f"all {len(freqs)} computed modes are below the cutoff: the linear stage "
                            "computes more when mode_count is set")
    e = resolution.estimate
    text = (f"accuracy {target.name or 'target'} (amplitude budget {target.amplitude_budget():.2g}):"
            f" H = {resolution.harmonics}, N = {resolution.samples_per_period}"
            + (f", mode_count = {mode['mode_count']} ({mode['reason']})" if mode else "")
            + f"\n  tuned at {worst['frequency_hz']:.2f} Hz (largest screening estimate); estimate: "
            f"amplitude {e.amplitude_rel:.2e} (H→{e.extended_harmonics}: {e.harmonics_rel:.2e}, "
            f"N→2N: {e.aliasing_rel:.2e}, modes: {e.modal_rel:.2e}), ERP {e.erp_db:.3f} dB"
            f"\n  {'met' if resolution.met else 'NOT met'}: {resolution.reason} "
            f"({len(resolution.history)} rounds, {time.perf_counter() - clock:.1f} s)")
    return {"harmonics": resolution.harmonics, "samples_per_period": resolution.samples_per_period,
            "mode_count": None if mode is None else mode["mode_count"], "mode": mode,
            "estimate": e.as_dict(), "met": resolution.met, "reason": resolution.reason,
            "frequency_hz": worst["frequency_hz"], "history": resolution.history,
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
