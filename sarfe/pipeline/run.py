r"""Solve a case end to end: linear stage → nonlinear model → HBM points → ERP, contact
indicators, linear baseline → summary.json and the other result files (written into a temporary
directory next to the target and moved into place at the end).
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import functools
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sarfe import __version__
from sarfe.case.errors import EXIT_NOT_CONVERGED, EXIT_TARGET_EXCEEDED
from sarfe.case.read import load_case
from sarfe.hbm.stability.deferred import deferred_stability, pending
from sarfe.pipeline.checks.case_checks import check_case, reduced_model_warnings
from sarfe.pipeline.checks.run_cost import cost_lines, run_cost
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.model.stage import linear_model_key
from sarfe.pipeline.post.point_workers import (first_estimates, point_records, point_work,
                                               point_workers, serial_stability,
                                               stability_stream, stream_submit)
from sarfe.pipeline.post.audibility_records import background_record
from sarfe.pipeline.post.records import error_estimates, worst_of
from sarfe.pipeline.post.review import target_check
from sarfe.pipeline.post.stability_need import stability_stride
from sarfe.pipeline.solve.by_need import erp_measure, fallback_warning
from sarfe.pipeline.solve.case_accuracy import (accuracy_check, case_resolution, resolution_line,
                                                resolved_case)
from sarfe.pipeline.solve.impact_check import impact_check_point, impact_time_check
from sarfe.pipeline.solve.mesh_error import (mesh_checked, mesh_error_term, mesh_line,
                                             start_coarse_levels, with_mesh_term)
from sarfe.pipeline.solve.points import common_samples, sweep_status
from sarfe.pipeline.solve.pruned_points import solve_points_pruned
from sarfe.pipeline.write.result_files import write_outputs
from sarfe.results.folder import marker_info, write_result_folder
from sarfe.results.summary import write_summary_json
from sarfe.util.progress import bar as progress_bar


@dataclass
class CaseResult:
    """Result of :func:`solve_case`: ``summary`` (= summary.json), ``rows`` (one flat dict per
    frequency point), ``exit_code`` (0 all converged, 3 some point did not converge or an
    incomplete sweep left part of its band without converged points, 4 ``output.target_dba``
    exceeded at the loudest point — before 3, :data:`sarfe.case.errors.EXIT_TARGET_EXCEEDED`),
    ``solutions`` (HarmonicSolution per point), ``output_dir`` (None if nothing was written)."""

    summary: dict
    rows: list
    exit_code: int
    solutions: list = field(default_factory=list, repr=False)
    output_dir: Path | None = None


def solve_case(case, linear_stage=None, output_dir=None, progress=False, write=True,
               force=False, warn=None) -> CaseResult:
    """Solve a case end to end (module docstring). Returns :class:`CaseResult`.

    ``output_dir``: where the result files go (default ``output.directory`` of the case, relative to
    the current directory); ``write=False`` writes nothing. Every input check of ``sarfe validate``
    runs first (:func:`sarfe.pipeline.checks.case_checks.check_case`: mesh quality, held structure, output
    folder; ``force`` replaces a folder that is not a sarfe result); its warnings go to
    ``warn(line)`` as found and to summary.json ``warnings``. Files are
    written into a temporary directory next to the target and moved into place at the end, so a
    failed run leaves the previous result as it was.
    Raises CaseError for problems in the case; a non-converged point gives ``exit_code`` 3.
    """
    started = time.perf_counter()
    case = load_case(case)
    bar = progress_bar(progress and linear_stage is None, "checking the case: mesh, groups, quality", None,
               unit="step")
    try:
        checked = check_case(case, output_dir, force, write=write, mesh_checks=linear_stage is None,
                             assemble=False)   # the linear stage assembles (a deck) right after
    finally:
        if bar is not None:
            bar.close()
    target, warnings = checked.output, list(checked.warnings)
    for line in warnings:
        if warn is not None:
            warn(line)
    # the cost before it is paid (issue 30 item 4): H, N, cutoff, modes, CPU s, bytes written
    cost = None if checked.size is None else run_cost(case, checked.size)
    if cost is not None and progress:
        for i, line in enumerate(cost_lines(cost, width=80 - len("sarfe: "))):
            print(("sarfe: " if i == 0 else " " * len("sarfe: ")) + line, file=sys.stderr,
                  flush=True)
    timings = {}
    accuracy = None
    config = case.config
    if config.solver.resolution == "auto" and not config.contacts and warn is not None:
        warn("no contacts: the response is linear (one modal sum per point), so resolution "
             f"'auto' searches no H; solved at harmonics = {config.solver.harmonics}")
    if config.solver.resolution == "auto" and config.contacts:
        # accuracy as an input: choose H, N (the reduction cutoff follows H) by a cheap search
        clock = time.perf_counter()
        report, searched = case_resolution(case, config.solver.accuracy, progress=progress)
        if progress:       # the chosen resolution before the sweep pays for it (issue 30)
            print(f"sarfe: {resolution_line(report, searched)}", file=sys.stderr, flush=True)
        accuracy = {k: report.get(k) for k in ("harmonics", "samples_per_period", "mode_count",
                                               "estimate", "met", "reason", "tuned_hz",
                                               "search_stage_modes", "search_stage_seconds",
                                               "cutoff_hz", "history", "seconds")}
        accuracy["target"] = config.solver.accuracy
        case = resolved_case(case, report)
        config = case.config
        # a given stage, else the search's last one, is the sweep's when its key matches
        linear_stage = next((s for s in (linear_stage, searched)
                             if s is not None and s.key == linear_model_key(case)), None)
        timings["accuracy_s"] = time.perf_counter() - clock
    # the ± mesh term's coarser models, built on the other core from now on (this process small)
    coarse_levels = start_coarse_levels(case)
    if linear_stage is None:
        linear_stage = build_linear_model(case, progress=progress)
        timings.update(linear_stage.timings)
    elif linear_stage.key != linear_model_key(case):
        raise ValueError("linear_stage was built for a different linear model (key mismatch)")
    stage = linear_stage
    for line in reduced_model_warnings(case, stage):
        warnings.append(line)
        if warn is not None:
            warn(line)
    clock = time.perf_counter()
    nl = nonlinear_model(case, stage)
    timings["setup_s"] = time.perf_counter() - clock

    clock = time.perf_counter()
    workers = point_workers(config.solver)     # processes for the per-point work (1: serial)
    # Hill stability by need (sarfe.pipeline.post.stability_need): recorded during the sweep,
    # computed at the seeds (with workers: on the stream while the sweep goes on) and where a
    # verdict changes, inferred between equal verdicts — the same on both paths; after the sweep
    # the error estimates and records go to all workers at once (sarfe.pipeline.post.point_workers)
    deferring = bool(config.solver.stability)
    parallel, work = {"processes": workers}, None
    streaming = deferring and workers > 1
    stride = stability_stride(config.excitation)
    with stability_stream() if streaming else contextlib.nullcontext() as stream:
        with deferred_stability(enabled=deferring,
                                on_job=None if stream is None
                                else stream_submit(stream, stride)) as jobs:
            solutions, pruning = solve_points_pruned(config.solver, config.excitation, nl,
                                                     progress=progress, measure=erp_measure(stage))
        if workers == 1 and jobs is not None:
            solutions = serial_stability(solutions, jobs, stride)
        timings["hbm_s"] = time.perf_counter() - clock
        if workers > 1:
            # the first estimate in this process (it builds the caches the others share) while
            # the stream's worker goes on with the stability
            clock = time.perf_counter()
            first = first_estimates(config, stage, nl, solutions)
            timings["error_estimate_s"] = time.perf_counter() - clock
        done = stream.finish() if stream is not None else {}
    if workers > 1:
        if jobs is not None:
            used = set(pending(solutions))
            parallel.update(stability_points=len(used),
                            stability_during_sweep=sum(i in done for i in used),
                            stream_processes=stream.forks)
        clock = time.perf_counter()
        work = point_work(config, stage, nl, solutions, jobs, done, first, workers, progress)
        timings["point_work_s"] = time.perf_counter() - clock
        if work is None:      # a deferred stability raised: the serial path's sweep
            parallel = {"processes": workers, "stability": "in place: a deferred stability "
                        "raised, the sweep was solved again serially"}
            clock = time.perf_counter()
            with deferred_stability() as jobs:
                solutions, pruning = solve_points_pruned(config.solver, config.excitation, nl,
                                                         progress=progress,
                                                         measure=erp_measure(stage))
            solutions = serial_stability(solutions, jobs, stride)
            timings["hbm_s"] += time.perf_counter() - clock
    clock = time.perf_counter()
    if work is not None:
        solutions, records = work
    else:
        bar = progress_bar(progress, "ERP and error estimates" if config.solver.error_estimate else "ERP",
                   len(solutions), unit="point")
        try:
            # each at the N it was solved with
            estimates = error_estimates(config, stage, nl, solutions, workers=workers)
            timings["error_estimate_s"] = time.perf_counter() - clock
            solutions = common_samples(nl, solutions)                # one time grid for the files
            records = point_records(
                config, stage, nl, solutions, estimates, workers,
                progress=None if bar is None else functools.partial(bar.update, 1))
        finally:
            if bar is not None:
                bar.close()
        timings["postprocess_s"] = time.perf_counter() - clock
    points, rows, erps, map_fields = (list(column) for column in zip(*records)) if records \
        else ([], [], [], [])
    # the ± mesh term: the loudest point re-solved on a 2× coarser generated mesh (issue 29 item 4)
    clock = time.perf_counter()
    mesh_term = mesh_error_term(case, points, solutions, background=coarse_levels) \
        if config.solver.error_estimate \
        else {"estimated": False, "reason": "not estimated (solver.error_estimate: false)"}
    timings.update(mesh_term.pop("timings_s", {}))    # the coarser models' background seconds
    with_mesh_term(points, rows, mesh_term)
    mesh_term["line"] = mesh_line(mesh_term)
    timings["mesh_error_s"] = time.perf_counter() - clock
    # the headline's ± where H cannot give one (an unresolved impact): time integration, issue 29
    impact_check, loudest = None, impact_check_point(points)
    if loudest is not None:
        bar = progress_bar(progress, "the loudest point's error by time integration (its impact "
                                     "is not resolved by H)", None)
        try:
            clock = time.perf_counter()
            impact_check = impact_time_check(stage, nl, points, rows, solutions, loudest)
            timings["impact_check_s"] = time.perf_counter() - clock
        finally:
            if bar is not None:
                bar.close()
    fallback = fallback_warning(solutions)      # the sweep by need raised: said, not only in reasons
    if fallback is not None:
        warnings.append(fallback)
        if warn is not None:
            warn(fallback)
    not_converged = [p["index"] for p in points if not p["converged"]]
    # None entries without a sweep
    sweep = sweep_status(config.excitation, config.solver.continuation, solutions)
    # exit code 3: a point did not converge, or the sweep fell back to point-by-point solving
    # without the band still being covered by converged points (docs/hbm.md, exit codes)
    exit_code = EXIT_NOT_CONVERGED if (not_converged or not points or (
        sweep["complete"] is False and not sweep["covered"])) else 0
    worst = worst_of(points)
    target_verdict = target_check(config.output.target_dba, worst)
    if target_verdict is not None and target_verdict["exceeded"]:   # 4 before 3 (case.errors)
        exit_code = EXIT_TARGET_EXCEEDED
    summary = {
        "sarfe_version": __version__,
        "case": case.name,
        "case_file": case.source,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "exit_code": exit_code,
        "all_converged": not not_converged and bool(points),
        "non_converged_points": not_converged,
        "sweep_complete": sweep["complete"],     # None without a sweep; False: see the reason
        "sweep_stop_reason": sweep["reason"],
        "sweep_covered": sweep["covered"],       # False with an incomplete sweep → exit code 3
        "sweep_note": sweep["note"],             # closed loops the continuation left, or None
        "engine": "harmonic balance",
        "linear_model_key": stage.key,
        "model": dict(stage.info, kind=stage.kind, kept_dofs=int(stage.dof_count),
                      mode_frequencies_hz=np.asarray(stage.mode_frequencies_hz)[:50]),
        "solver": {k: v for k, v in case.data["solver"].items()},
        "contacts": [dict({"name": name, "type": kind, "pairs": int(len(idx))},
                          **_node_pairs(stage, name)) for name, kind, idx in nl.groups],
        "contact_pruning": pruning,              # per contact: open / closed / nonlinear
        "points": points,
        "worst": worst,
        "target": target_verdict,                # output.target_dba against the loudest point
        "audibility_model": background_record(config.audibility),   # cabin and background
        "accuracy": accuracy,                    # None unless solver.accuracy was given
        "accuracy_check": mesh_checked(accuracy_check(config.solver, points), mesh_term, case),
        "mesh_error": mesh_term,                 # the ± mesh term (sarfe.pipeline.solve.mesh_error)
        **({} if impact_check is None else {"impact_check": impact_check}),   # (impact_check.py)
        "warnings": warnings,                    # inputs far outside the model's range
        "timings_s": timings,
        "cost_estimate": None if cost is None else cost.as_dict(),   # said before the run
        "workers": parallel,      # processes; Hill points computed during the sweep (of all)
        "case_data": case.data,                  # the case with every default filled in
    }
    result = CaseResult(summary, rows, exit_code, solutions)
    if not write:
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        return result
    def write_files(folder):
        clock = time.perf_counter()
        summary["timings_s"]["outputs_s"] = 0.0
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        summary["files"] = write_outputs(config, stage, nl, summary, rows, solutions, erps,
                                         map_fields, folder)
        summary["timings_s"]["outputs_s"] = time.perf_counter() - clock
        summary["timings_s"]["total_s"] = time.perf_counter() - started
        write_summary_json(folder / "summary.json", summary)

    bar = progress_bar(progress, "writing results", None, unit="file")
    try:
        write_result_folder(target, write_files, marker_info("solve", case.name), force=force)
    finally:
        if bar is not None:
            bar.close()
    result.output_dir = target
    return result


def _node_pairs(stage, name) -> dict:
    """{"node_pairs": [[a, b], …]} of an FE contact: the deck's GRID ids (deck models) or mesh
    node indices; b is "ground" for a contact with ground."""
    geometry = stage.contacts.get(name) if stage.kind == "fe" else None
    if geometry is None:
        return {}
    ids = getattr(stage, "node_ids", None)
    name_of = (lambda n: int(ids[n])) if ids is not None else int   # noqa: E731
    return {"node_pairs": [[name_of(a), "ground" if b < 0 else name_of(b)]
                           for a, b in zip(geometry.nodes_a, geometry.nodes_b)],
            "node_numbering": "deck ids" if ids is not None else "mesh indices"}


__all__ = ["CaseResult", "solve_case"]
