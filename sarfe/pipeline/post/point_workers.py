r"""The per-point work that does not feed the sweep, on ``solver.workers`` processes.

Newton and the continuation stay in the solving process: each point starts from the previous
one. The rest of a point's work reads the converged point only, and runs on worker processes
forked from the solve (:func:`sarfe.util.workers.map_points`: the reduced model and the points are
shared copy-on-write, only the results come back):

1. Hill stability by need (:mod:`sarfe.pipeline.post.stability_need`) — deferred during the
   sweep (:mod:`sarfe.hbm.stability.deferred`: ``finalize`` records a job per converged point),
   the seeds computed on one worker while the sweep goes on (:func:`stability_stream`,
   :func:`stream_submit`: the sweep holds one core, the stream the other), then the seeds left
   and the points between differing verdicts; the rest inferred;
2. the error estimates (:func:`sarfe.pipeline.post.records.error_estimates`; the first in the
   solving process, :func:`first_estimates`);
3. the point records: ERP, contact indicators, contributions, linear baseline
   (:func:`sarfe.pipeline.post.records.point_records`, by chunks of points).

After the sweep 1–3 go to the workers in two pools (:func:`point_work`): the seeds left and the
estimates, longest first, then the records on freshly forked workers (memory).

``workers`` = 1 is the serial path (the same stability by need in this process,
:func:`serial_stability`; plain loops). The results do not depend on ``workers``: every point is
computed by the same function from the same inputs. An exception of a deferred stability on a
worker makes the caller solve the sweep again serially, whose :func:`serial_stability` gives such
a point verdict None with the error in its note.
"""
from __future__ import annotations

import numpy as np

from sarfe.case.config import CaseConfig, SolverConfig
from sarfe.hbm.stability import deferred
from sarfe.hbm.stability.hill import StabilityResult
from sarfe.hbm.stability.deferred import pending, stability_of, with_stability
from sarfe.pipeline.post import records
from sarfe.pipeline.post.stability_need import seed_jobs, stability_by_need, stability_stride
from sarfe.pipeline.solve.points import common_samples
from sarfe.util.progress import bar as progress_bar
from sarfe.util.workers import Stream, map_points, worker_count


def _stability_or_error(job, compute=None):
    """:func:`stability_of` (or ``compute``) of a job, or the exception it raised (returned)."""
    try:
        return (compute or stability_of)(job)
    except Exception as error:      # the caller solves the sweep again serially
        return error


def point_workers(solver: SolverConfig) -> int:
    """Processes for the per-point work of a run: ``solver.workers`` (:func:`sarfe.util.workers.
    worker_count`; 'auto' = the CPUs this process may use, at most 2, as memory allows)."""
    return worker_count(solver.workers)


def stability_stream() -> Stream:
    """The Hill stability of the sweep's points on one worker while the sweep goes on (the jobs
    of :func:`sarfe.hbm.stability.deferred.deferred_stability` submitted as they are recorded,
    :func:`stream_submit`)."""
    return Stream(stability_of)


def stream_submit(stream: Stream, stride: int):
    """on_job(index, job) for :func:`sarfe.hbm.stability.deferred.deferred_stability`: every
    ``stride``-th recorded job goes to the stream (the seeds of the stability by need; the others
    are computed after the sweep where a verdict changes)."""
    def submit(index, job):
        if index % stride == 0:
            stream.submit(index, job)
    return submit


def serial_stability(solutions, jobs, stride: int) -> list:
    """The solutions of a serial sweep (``workers`` = 1) with their deferred stability by need
    (:mod:`sarfe.pipeline.post.stability_need`) computed in this process; a failing computation
    gives verdict None with its error in the note."""
    indices = pending(solutions)
    if not indices:
        return solutions
    verdicts = stability_by_need(solutions, jobs,
                                 lambda todo: [_stability_or_error(j, deferred.stability_of)
                                               for j in todo], stride=stride)
    results = [StabilityResult(None, float("nan"), f"stability failed: {type(r).__name__}: {r}",
                               np.zeros(0, complex)) if isinstance(r, Exception) else r
               for r in (verdicts[i] for i in indices)]
    return with_stability(solutions, indices, results)


def first_estimates(config: CaseConfig, stage, nl, solutions) -> dict:
    """{index: estimate} of the first point to estimate (:func:`sarfe.pipeline.post.records.
    estimated_points`), computed in this process: the caches it builds (the coarser Craig–Bampton
    model, the modal bases) are inherited by the workers forked after it, as the serial loop's
    later estimates find them, so every estimate has the serial path's round-off."""
    return {i: records.point_estimate(config, stage, nl, solutions[i])
            for i in records.estimated_points(config, nl, solutions)[:1]}


def point_work(config: CaseConfig, stage, nl, solutions, jobs, done, first, workers,
               progress=False):
    """Everything per point after a sweep, on ``workers`` processes at once: the Hill stability
    of the reported points the stream did not compute (``jobs`` of the :func:`sarfe.hbm.stability.deferred.
    deferred_stability` block around the sweep, None without stability; ``done``: {job index:
    StabilityResult or the exception it raised} of the stream, :func:`stability_stream`), the
    error estimates left (``first``: those computed in this process, :func:`first_estimates`) and
    every point's record (ERP, contact
    indicators, contributions, linear baseline; :func:`sarfe.pipeline.post.records.point_records`,
    with the points at one time grid, :func:`sarfe.pipeline.solve.points.common_samples`). Two pools: the
    Hill points and estimates, longest first (a Hill point ≈ 5× an estimate), so the workers
    finish together, then the records (≈ 1/5 of an estimate each) on freshly forked workers
    (memory: see the code).

    Returns (solutions with their verdicts at one time grid, [(point dict, row, ErpResult, map
    fields)]), or None when a deferred stability raised (the caller solves the sweep again
    serially). The records are filled with the verdicts and estimates afterwards
    (:func:`sarfe.pipeline.post.records.with_verdict`, ``with_estimate``): the same records as the
    serial path's."""
    indices = pending(solutions) if jobs is not None else []
    # the seeds of the stability by need first (sarfe.pipeline.post.stability_need), with the
    # estimates; the crossings between differing verdicts after them. Of the stream's verdicts
    # only the seeds' are kept: it computed every stride-th job as recorded, and where the sweep
    # dropped or re-recorded points those are not all seeds — which of them it reached depends on
    # timing, and a kept extra verdict would turn an inferred neighbour into a computed one from
    # run to run (measured on lumped_rattle, point 162)
    stride = stability_stride(config.excitation)
    seeds = seed_jobs(solutions, stride) if indices else []
    seed_set = set(seeds)
    done = {i: r for i, r in (done or {}).items() if i in seed_set}
    if any(isinstance(done.get(i), Exception) for i in indices):
        return None
    hill = [i for i in seeds if i not in done]
    estimates = [i for i in records.estimated_points(config, nl, solutions) if i not in first]
    gridded = common_samples(nl, solutions)      # records at one N; estimates at each point's own
    # two pools: the Hill and estimate items first, then the records on freshly forked workers
    # (a worker's heap keeps its high-water mark: Hill's working arrays beside the records sent
    # back to this process put P1's tree PSS at 4.1–4.3 GB in one pool, over its 4 GB budget)
    first_pool = [("stability", i) for i in hill] + [("estimate", i) for i in estimates]
    # records by chunks of points: one product with the ERP map per chunk (postprocess)
    second_pool = [("records", tuple(chunk)) for chunk in records.record_chunks(len(gridded))]
    tasks = first_pool + second_pool

    def run(task):
        kind, i = task
        if kind == "stability":
            return _stability_or_error(jobs[i])
        if kind == "estimate":
            return records.point_estimate(config, stage, nl, solutions[i])
        return records.point_records(config, stage, nl, [(j, gridded[j], None) for j in i])

    n = len(gridded)
    what = (f"{'ERP and error estimates' if config.solver.error_estimate else 'ERP'} "
            f"({n} point{'s' if n != 1 else ''})"
            + (f", Hill stability of the {len(hill)} left" if hill else "")
            + (f" on {workers} processes" if len(tasks) > 1 else ""))
    bar = progress_bar(progress, what, len(tasks), "item")
    tick = None if bar is None else (lambda item: bar.update(1))
    try:
        results = (map_points(run, first_pool, workers, progress=tick)
                   + map_points(run, second_pool, workers, progress=tick))
    finally:
        if bar is not None:
            bar.close()
    by_task = dict(zip(tasks, results))
    verdicts = {**done, **{i: by_task["stability", i] for i in hill}}
    if indices:
        verdicts = stability_by_need(
            solutions, jobs, lambda todo: map_points(_stability_or_error, todo, workers),
            done=verdicts, stride=stride)
    if any(isinstance(verdicts[i], Exception) for i in indices):
        return None
    if indices:
        gridded = with_stability(gridded, indices, [verdicts[i] for i in indices])
    computed = {**first, **{i: by_task["estimate", i] for i in estimates}}
    per_point = records.error_estimates(config, stage, nl, solutions, computed=computed)
    done_records = [record for _, chunk in second_pool for record in by_task["records", chunk]]
    for (point, row, _, _), solution, estimate in zip(done_records, gridded, per_point):
        records.with_verdict(point, row, solution)
        records.with_estimate(point, row, estimate)
    return gridded, done_records


def point_records(config: CaseConfig, stage, nl, solutions, estimates, workers,
                  progress=None) -> list:
    """[(point dict, table row, ErpResult, map fields)] per solution (:func:`sarfe.pipeline.
    post.records.point_records`, by chunks of points), on ``workers`` processes; ``progress()``
    once per point (a chunk's points when it finishes)."""
    chunks = records.record_chunks(len(solutions))

    def record(chunk):
        return records.point_records(config, stage, nl,
                                     [(i, solutions[i], estimates[i]) for i in chunk])

    def tick(chunk):
        for _ in chunk:
            progress()

    results = map_points(record, chunks, workers, progress=None if progress is None else tick)
    return [r for chunk in results for r in chunk]
