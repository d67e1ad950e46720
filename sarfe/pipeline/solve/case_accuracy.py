"""A case's point and sweep in the terms of :mod:`sarfe.accuracy`: the estimate problem of a linear
stage and nonlinear model (plain arrays), the per-point error estimate and a case's accuracy target
→ H, N and mode count (:func:`resolve_case_accuracy`)."""
from __future__ import annotations

import numpy as np

from sarfe.accuracy.estimate import (EstimateProblem, basis_limited_extension,
                                     highest_natural_frequency_hz, problem_error_estimate)
from sarfe.accuracy.harmonic_truncation import RICHARDSON, harmonics_richardson
from sarfe.accuracy.resolve import resolve_accuracy
from sarfe.accuracy.target import parse_accuracy
from sarfe.case.config import ExcitationConfig, SolverConfig
from sarfe.case.read import load_case
from sarfe.hbm import SolverOptions
from sarfe.pipeline.model.cutoff import (NEWTON_FLOOR_HZ, NEWTON_HARMONICS, newton_cutoff_hz,
                                         newton_margin)
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.util.progress import bar as progress_bar


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
    """:func:`sarfe.accuracy.estimate.problem_error_estimate` of a case's point."""
    return problem_error_estimate(solution, accuracy_problem(stage, nl))


def sweep_grid_hz(excitation: ExcitationConfig, points=8) -> np.ndarray:
    """[Hz]: the listed frequencies, or ``points`` evenly spaced over the sweep."""
    if excitation.frequency_hz is not None:
        return np.atleast_1d(np.asarray(excitation.frequency_hz, dtype=float))
    return np.linspace(excitation.sweep.start_hz, excitation.sweep.end_hz, int(points))


def rule_cutoff_hz(case) -> float | None:
    """The accuracy search's (and so the sweep's) Craig–Bampton cutoff: the Newton cutoff
    :func:`sarfe.pipeline.model.cutoff.newton_cutoff_hz`, max(1 kHz, max(cutoff_margin, 1.5) · 5 ·
    f_max), for an FE case whose reduction gives neither cutoff_hz nor mode_count; None otherwise
    (a matrices model, or the user's reduction, which the search keeps). It does not grow with
    the H the search chooses: the harmonics above it meet no kept mode and are answered
    quasi-statically, and the error of that is measured per point by the estimate's modal term
    (:mod:`sarfe.accuracy.modal_truncation`, in the ±).

    The floor, measured: door trim 10 mm, 67 Hz (benchmarks/results/audible.md), the dB(A) on a
    1005 Hz stage is within 0.011 dB of the 4020 Hz stage for every H from 3 to 60, on 2010 Hz
    within 0.001 dB; on 502 Hz it is 0.04–0.09 dB off and the H ladder climbed irregularly
    (to H = 27) — the search needs the modes up to a few harmonics of the loudest contact
    response, not up to H f_max. Door trim 14 mm at 67 Hz and the instrument panel at its loudest
    point (65.3 Hz, H = 18) at 1, 1.5, 2, 3 kHz: benchmarks/results/newton_cutoff.md. The rule it
    replaces, m · H · f_max, took the instrument panel sweep (H = 18, f_max = 200 Hz) to 5.4 kHz,
    1361 modes, and rebuilt the stage as the search's H grew."""
    reduction = case.config.reduction
    if reduction is None or reduction.cutoff_hz is not None or reduction.mode_count is not None:
        return None
    return newton_cutoff_hz(case)


def with_cutoff(case, cutoff_hz):
    """The case with reduction.cutoff_hz set (unchanged for None)."""
    return case if cutoff_hz is None else case.with_reduction(cutoff_hz=float(cutoff_hz))


def resolved_case(case, report):
    """The case with the resolution :func:`case_resolution` chose (``report``): solver.harmonics,
    samples_per_period, ``resolution: fixed`` (``accuracy`` stays the run's error budget), and the
    search's reduction cutoff (or mode count) when it reports one."""
    case = case.with_solver(harmonics=int(report["harmonics"]),
                            samples_per_period=int(report["samples_per_period"]),
                            resolution="fixed")
    if report.get("cutoff_hz"):      # the search's reduction cutoff (FE; none given by the user)
        return case.with_reduction(cutoff_hz=float(report["cutoff_hz"]))
    if report.get("mode_count"):
        return case.with_reduction(cutoff_hz=None, mode_count=int(report["mode_count"]))
    return case


def case_resolution(case, target, points=8, start_harmonics=3, start_samples=64,
                    max_harmonics=64, max_samples=8192, max_points_tuned=3, progress=False):
    """A case's accuracy target → (report, linear stage): :func:`sarfe.accuracy.resolve_accuracy`
    over ``points`` frequencies of the case (screened at ``start_harmonics``, then an H ladder at
    the loudest point), with the case's Newton tolerance and no stability.

    FE cases whose reduction gives neither cutoff_hz nor mode_count: the search runs on one
    linear stage, that of the Newton cutoff :func:`rule_cutoff_hz` (max(1 kHz, 1.5 · 5 · f_max)),
    which does not follow the H it chooses — no stage is rebuilt when H grows; the harmonics above
    the cutoff are answered quasi-statically (constraint modes and residual vectors) and the
    per-point estimate's modal term measures what that costs. The cutoff is reported as
    ``cutoff_hz`` and set explicitly by :func:`resolved_case`; the stage is returned: the sweep
    reuses it (same key as the chosen case). ``progress``: the stage's build and the H ladder on
    it are shown (the search can take minutes)."""
    case = load_case(case)
    solver = case.config.solver
    options = SolverOptions(tolerance=solver.tolerance, max_iterations=solver.max_iterations,
                            stability=False)
    cutoff = rule_cutoff_hz(case)
    searched = with_cutoff(case, cutoff)
    grid = sweep_grid_hz(case.config.excitation, points)
    where = "" if cutoff is None else f", Newton cutoff {cutoff:.0f} Hz"
    bar = progress_bar(progress, f"H search ({target}): linear stage{where}")
    if bar is not None:
        bar.close()
    stage = build_linear_model(searched, progress=progress)
    bar = progress_bar(progress, f"H search: the H, N ladder on {stage.info.get('modes')} "
                                 f"modes at {len(grid)} frequencies")
    if bar is not None:
        bar.close()
    report = resolve_accuracy(accuracy_problem(stage, nonlinear_model(searched, stage)),
                              target, grid, solver.harmonics, solver.samples_per_period,
                              max_harmonics=max_harmonics, max_samples=max_samples,
                              options=options, start_harmonics=start_harmonics,
                              start_samples=start_samples, max_points_tuned=max_points_tuned)
    modes = stage.info.get("modes")
    report.update(search_stage_modes=[modes], cutoff_hz=cutoff,
                  search_stage_seconds=[float(stage.timings.get("linear_stage_s", 0.0))])
    report["text"] += (f"\n  searched on one linear stage ({modes} modes)" + (
        "" if cutoff is None else
        f"; Newton cutoff {cutoff:.0f} Hz = max({NEWTON_FLOOR_HZ:.0f} Hz, "
        f"{newton_margin(case):g} · {NEWTON_HARMONICS} · f_max), not H f_max "
        f"({report['harmonics'] * case.config.excitation.max_frequency_hz:.0f} Hz at "
        f"H = {report['harmonics']}): harmonics above it answer quasi-statically"))
    return report, stage


def resolution_line(report, stage) -> str:
    """One line of what ``resolution: auto`` chose (:func:`case_resolution`'s ``report`` and the
    linear ``stage`` the sweep uses): H, N, the reduction cutoff [Hz] and modes, the search's
    time [s]."""
    modes = (getattr(stage, "info", None) or {}).get("modes") if stage is not None else None
    cutoff = report.get("cutoff_hz")
    return (f"resolution auto: H = {report['harmonics']}, N = {report['samples_per_period']}"
            + ("" if cutoff is None else f", reduction cutoff {cutoff:.0f} Hz")
            + ("" if modes is None else f", {modes} modes")
            + f" (search {report.get('seconds', 0.0):.0f} s)")


def resolve_case_accuracy(case, target, points=8, start_harmonics=3, start_samples=64,
                          max_harmonics=64, max_samples=8192, max_points_tuned=3) -> dict:
    """The report of :func:`case_resolution` (the report dict of
    :func:`sarfe.accuracy.resolve_accuracy` with the search's stages and cutoff)."""
    return case_resolution(case, target, points, start_harmonics, start_samples, max_harmonics,
                           max_samples, max_points_tuned)[0]


RELEVANT_DB = 30.0     # points quieter than the loudest by more than this do not count (dB(A))

KNOBS = {"harmonics": "solver.harmonics", "aliasing": "solver.samples_per_period",
         "modal": "reduction.cutoff_hz (or mode_count)", "mesh": "the mesh resolution (a smaller model.fe.generator.mesh_size_m)"}


def accuracy_check(solver: SolverConfig, points) -> dict | None:
    """The run's error estimates against its accuracy budget (``solver.accuracy``, default
    'balanced': 1 % first-harmonic amplitude, 0.5 dB ERP) → {'met', 'target', 'point',
    'frequency_hz', 'amplitude_rel', 'erp_db', 'knob', 'warning'} or None without estimates.

    Counted: converged points with an estimate whose ERP is within RELEVANT_DB of the loudest
    (a 5 dB error 60 dB below the headline changes nothing a user reads). The knob to raise is the
    one whose part (Richardson factors included) is largest at the worst point: harmonics →
    solver.harmonics, aliasing → solver.samples_per_period, modal → the reduction cutoff, mesh
    (``mesh_db``, :mod:`sarfe.pipeline.solve.mesh_error`) → the generator's mesh size."""
    target = parse_accuracy(solver.accuracy_or_default)
    rated = [p for p in points if p["converged"] and p.get("error_estimate")
             and "failed" not in p["error_estimate"]]
    if not rated:
        return None
    loudest = max((p["erp"]["level_dba"] for p in rated if np.isfinite(p["erp"]["level_dba"])),
                  default=float("nan"))
    if np.isfinite(loudest):
        rated = [p for p in rated if not p["erp"]["level_dba"] < loudest - RELEVANT_DB] or rated
    budget = target.amplitude_budget()

    def badness(p):
        e = p["error_estimate"]
        ratios = [np.nan_to_num(e["amplitude_rel"], posinf=np.inf) / budget]
        if target.erp_db is not None:
            ratios.append(np.nan_to_num(abs(e["erp_db"]), posinf=np.inf) / target.erp_db)
        return max(ratios)

    unknown = [p for p in rated if not np.isfinite(badness(p))]
    rated = [p for p in rated if np.isfinite(badness(p))] or rated
    worst = max(rated, key=badness)
    e = worst["error_estimate"]
    met = bool(badness(worst) <= 1.0)
    factor = harmonics_richardson(int(e["harmonics"]), int(e["extended_harmonics"]))
    parts = {"harmonics": factor * np.nan_to_num(e["harmonics_rel"]),
             "aliasing": RICHARDSON * np.nan_to_num(e["aliasing_rel"]),
             "modal": np.nan_to_num(e["modal_rel"])}
    parts_db = {"harmonics": factor * abs(np.nan_to_num(e["harmonics_db"])),
                "aliasing": RICHARDSON * abs(np.nan_to_num(e["aliasing_db"])),
                "modal": abs(np.nan_to_num(e["modal_db"])),
                "mesh": abs(np.nan_to_num(e.get("mesh_db", 0.0)))}      # sarfe.pipeline.solve.mesh_error
    parts["mesh"] = 0.0
    share = {k: max(parts[k] / budget, parts_db[k] / (target.erp_db or 1e300)) for k in parts}
    knob = max(share, key=share.get)
    warning = None
    if not met:
        warning = (f"accuracy: the error estimate exceeds the '{target.name}' budget at "
                   f"{worst['frequency_hz']:.2f} Hz (amplitude ±{100 * e['amplitude_rel']:.2g} %, "
                   f"ERP ±{abs(e['erp_db']):.2g} dB); mostly from {knob}: raise {KNOBS[knob]}")
        if knob == "harmonics" and basis_limited_extension(e, worst["frequency_hz"]):
            warning += (f" (its re-solve at H' = {int(e['extended_harmonics'])} reaches "
                        f"{int(e['extended_harmonics']) * worst['frequency_hz']:.0f} Hz, above "
                        f"the reduced basis' top mode at {e['basis_top_hz']:.0f} Hz, where the "
                        "reduced model's own error enters the change: if a higher "
                        "reduction.cutoff_margin lowers it, it was the basis')")
    if unknown:     # no bound (re-solve not converged, impact not resolved): said, not hidden
        met = False
        warning = (warning + "; " if warning else "accuracy: ") + unknown_text(unknown)
    return {"met": bool(met), "target": target.name, "point": worst["index"],
            "unknown_points": [p["index"] for p in unknown],
            "frequency_hz": worst["frequency_hz"], "amplitude_rel": float(e["amplitude_rel"]),
            "erp_db": float(e["erp_db"]), "knob": KNOBS[knob], "warning": warning}


def unknown_text(points) -> str:
    """What the run says of its points without an error bound (summary.json points with an
    ``error_estimate`` whose amplitude_rel is inf): where the harmonics do not resolve a contact's
    impact (``contact_resolution``, :mod:`sarfe.accuracy.contact_resolution`) the count, the
    frequency range and why; the others' re-solve did not converge."""
    def where(group):
        shown = ", ".join(f"{p['frequency_hz']:.2f}" for p in group[:3])
        return shown + (f" and {len(group) - 3} more" if len(group) > 3 else "") + " Hz"

    impacts = [p for p in points if (p["error_estimate"].get("contact_resolution") or {})
               .get("resolved") is False]
    failed = [p for p in points if p not in impacts]
    parts = []
    if impacts:
        r = max((p["error_estimate"]["contact_resolution"] for p in impacts),
                key=lambda r: r["ratio"])
        f = [p["frequency_hz"] for p in impacts]
        parts.append(
            f"no error bound at {len(impacts)} points ({min(f):.2f}–{max(f):.2f} Hz): the impact "
            f"of {r['contact']} lasts ≈ {1e6 * r['impact_duration_s']:.3g} µs, far shorter than "
            f"the {1e6 * r['resolved_duration_s']:.3g} µs H' = {r['harmonics']} resolves, so no "
            f"change of H bounds the error there (a bound needs H' ≥ {r['needed_harmonics']}: "
            "raise solver.harmonics, or soften the contact)")
    if failed:
        parts.append(f"no error estimate at {where(failed)} (its re-solve at more harmonics or "
                     "samples did not converge)")
    return "; ".join(parts)


__all__ = ["unknown_text", "accuracy_check", "resolved_case", "with_cutoff", "stage_modal_coordinates", "accuracy_problem", "stage_error_estimate", "sweep_grid_hz",
           "resolve_case_accuracy", "case_resolution", "resolution_line", "rule_cutoff_hz"]
