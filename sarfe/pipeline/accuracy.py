"""A case's point and sweep in the terms of :mod:`sarfe.accuracy`: the estimate problem of a linear
stage and nonlinear model (plain arrays), the per-point error estimate and a case's accuracy target
→ H, N and mode count (:func:`resolve_case_accuracy`)."""
from __future__ import annotations

import numpy as np

from sarfe.accuracy.estimates import (EstimateProblem, highest_natural_frequency_hz,
                                      problem_error_estimate)
from sarfe.accuracy.resolve import resolve_accuracy


def stage_modal_coordinates(stage):
    """(fixed-interface modes, residual modes) of an FE stage's reduced coordinates (after the
    Craig–Bampton boundary DOFs, each in increasing frequency); (None, None) for matrices."""
    if stage.kind != "fe":
        return None, None
    first = int(stage.info.get("boundary_dofs", 0))
    modes = int(stage.info.get("modes", stage.dof_count - first))
    return np.arange(first, first + modes), np.arange(first + modes, stage.dof_count)


def accuracy_problem(stage, nl) -> EstimateProblem:
    """The :class:`EstimateProblem` of a case: ``nl`` (:func:`sarfe.pipeline.nonlinear_model`) on
    the linear ``stage``, its ERP map and areas, the Craig–Bampton modal coordinates of FE stages
    and the highest natural frequency (FE: the highest kept mode; matrices: of M, K)."""
    modal, residual = stage_modal_coordinates(stage)
    if stage.kind == "fe":
        highest = float(np.max(stage.mode_frequencies_hz, initial=0.0)) or None
    else:
        highest = highest_natural_frequency_hz(nl.model)
    return EstimateProblem(nl.model, nl.contacts, nl.excitation, stage.erp_map, stage.erp_areas,
                           modal, residual, highest)


def stage_error_estimate(solution, stage, nl):
    """:func:`sarfe.accuracy.estimates.problem_error_estimate` of a case's point."""
    return problem_error_estimate(solution, accuracy_problem(stage, nl))


def sweep_grid_hz(case, points=8) -> np.ndarray:
    """[Hz]: the listed frequencies, or ``points`` evenly spaced over the sweep."""
    exc = case.data["excitation"]
    if "frequency_hz" in exc:
        return np.atleast_1d(np.asarray(exc["frequency_hz"], dtype=float))
    return np.linspace(exc["sweep"]["start_hz"], exc["sweep"]["end_hz"], int(points))


def resolve_case_accuracy(case, target, points=8, start_harmonics=3, start_samples=64,
                          max_harmonics=64, max_samples=8192, max_points_tuned=3,
                          linear_stage=None) -> dict:
    """A case's accuracy target → H, N (and mode count): :func:`sarfe.accuracy.resolve_accuracy`
    over ``points`` frequencies of the case solved at its own H, N. ``linear_stage``: reuse a built
    stage. Returns the report dict of resolve_accuracy."""
    from sarfe.hbm import SolverOptions
    from sarfe.io.case import load_case
    from sarfe.pipeline.linear import build_linear_model
    from sarfe.pipeline.nonlinear import nonlinear_model

    case = load_case(case)
    stage = linear_stage if linear_stage is not None else build_linear_model(case)
    nl = nonlinear_model(case, stage)
    solver = case.data["solver"]
    options = SolverOptions(tolerance=solver["tolerance"], max_iterations=solver["max_iterations"],
                            stability=False)
    modes = None
    f_max = None
    if stage.kind == "fe":
        exc = case.data["excitation"]
        f_max = max(exc["frequency_hz"]) if "frequency_hz" in exc else max(
            exc["sweep"]["start_hz"], exc["sweep"]["end_hz"])
        modes = getattr(stage.reduced, "mode_frequencies_hz", stage.mode_frequencies_hz)
    return resolve_accuracy(accuracy_problem(stage, nl), target, sweep_grid_hz(case, points),
                            solver["harmonics"], solver["samples_per_period"],
                            start_harmonics=start_harmonics, start_samples=start_samples,
                            max_harmonics=max_harmonics, max_samples=max_samples,
                            max_points_tuned=max_points_tuned, options=options,
                            mode_frequencies_hz=modes, max_frequency_hz=f_max,
                            current_modes=stage.info.get("modes"))


__all__ = ["stage_modal_coordinates", "accuracy_problem", "stage_error_estimate", "sweep_grid_hz",
           "resolve_case_accuracy"]
