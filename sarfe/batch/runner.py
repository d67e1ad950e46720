"""Run a batch of variants: the linear part once per distinct linear model, then every variant.

Flow (``run_study``):
  1. expand studies/case files into variants (``sarfe.batch.variants``), skip ids already finished in
     ``<output>/variants`` (resume);
  2. ``load_case`` every remaining variant and group by ``linear_model_key(case)`` — a variant whose
     case is rejected is recorded as failed right away;
  3. per group build the ``LinearStage`` once (on a worker, or read ``<output>/.cache/<key>.npz``),
     ``client.scatter(stage, broadcast=True)`` it and submit the group's variants with it;
  4. write each finished variant's record at once (``sarfe.batch.store``), then merge the table and
     write summary and plots (``sarfe.batch.batch_report``).

Workers: ``workers=0`` runs in this process without Dask; ``workers=N`` starts a loopback
``LocalCluster`` (processes, one thread each, no dashboard); ``scheduler=ADDRESS`` or ``client=``
uses an existing cluster (its workers need sarfe installed; ``output_dir`` is written by this
process only, except per-variant outputs with ``write_variant_outputs``).
"""
from __future__ import annotations

import importlib
import logging
import os
import pathlib
import sys
import time
import traceback
from dataclasses import dataclass, field

import pandas as pd

from sarfe.batch import batch_report, store
from sarfe.batch.variants import StudyError, Variant, collect_variants
from sarfe.pipeline.checks.case_inputs import named_files
from sarfe.results.folder import check_output_folder, claim_folder, marker_info

PIPELINE = "sarfe.pipeline"
_BLAS_ENV = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}


def _pipeline(name: str):
    return importlib.import_module(name)


def load_variant_case(pipeline, variant: Variant):
    """``load_case`` of the variant's case mapping (relative paths resolved from its case file)."""
    return pipeline.load_case(variant.case, base_dir=variant.case_dir)


def _error_text(error: BaseException) -> str:
    text = " ".join(str(error).split())
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def build_stage(variant: Variant, pipeline_name: str = PIPELINE):
    """Worker task: the linear stage of ``variant``'s case."""
    pipeline = _pipeline(pipeline_name)
    return pipeline.build_linear_model(load_variant_case(pipeline, variant), progress=False)


def _timed_build(variant: Variant, pipeline_name: str = PIPELINE):
    start = time.perf_counter()
    stage = build_stage(variant, pipeline_name)
    return stage, time.perf_counter() - start


def _converged(result) -> bool:
    summary = getattr(result, "summary", None) or {}
    if summary.get("all_converged", summary.get("converged")) is False:
        return False
    return all(row.get("converged", True) is not False for row in (result.rows or []))


def solve_variant(variant: Variant, linear_stage, pipeline_name: str = PIPELINE,
                  variant_output: str | None = None) -> dict:
    """Worker task: solve one variant with a shared linear stage; never raises.

    Returns the record stored in ``<output>/variants/<id>.json``: ``status`` 'ok' | 'nonconverged'
    | 'failed', ``error`` (one line), ``exit_code``, ``summary`` and ``rows`` of ``CaseResult``.
    """
    start = time.perf_counter()
    record = {"variant_id": variant.id, "variant_index": variant.index, "source": variant.source,
              "parameters": variant.parameters, "status": "failed", "error": "", "exit_code": None,
              "summary": {}, "rows": []}
    try:
        pipeline = _pipeline(pipeline_name)
        case = load_variant_case(pipeline, variant)
        result = pipeline.solve_case(case, linear_stage=linear_stage, output_dir=variant_output,
                                     progress=False,
                                     write=variant_output is not None)  # no files unless asked
        summary = {k: v for k, v in (getattr(result, "summary", None) or {}).items() if k != "points"}
        record.update(status="ok" if _converged(result) else "nonconverged",
                      exit_code=getattr(result, "exit_code", None), summary=summary,
                      rows=list(result.rows or []))
    except Exception as error:  # recorded, the batch goes on
        record.update(error=_error_text(error), traceback=traceback.format_exc(limit=8))
    record["elapsed_s"] = time.perf_counter() - start
    return record


def failed_record(variant: Variant, message: str, transient: bool = False) -> dict:
    """Record of a variant that produced no result. ``transient``: the cluster failed (workers
    killed), not the variant — a re-run solves it again instead of skipping it."""
    return {"variant_id": variant.id, "variant_index": variant.index, "source": variant.source,
            "parameters": variant.parameters, "status": "failed", "error": message, "exit_code": None,
            "summary": {}, "rows": [], "elapsed_s": 0.0, "transient": transient}


@dataclass
class RunStats:
    """What a run did (goes into summary.json under ``run``)."""
    variants: int = 0
    skipped: int = 0                 # finished in an earlier run
    solved: int = 0                  # finished in this run (ok, nonconverged or failed)
    failed: int = 0
    linear_models: int = 0           # distinct linear_model_key among variants run now
    linear_stages_built: int = 0
    linear_stages_from_cache: int = 0
    linear_build_s: float = 0.0      # summed wall time of the linear builds (on the workers)
    linear_model_keys: list = field(default_factory=list)
    mode: str = "in-process"
    workers: int = 0
    cluster_start_s: float = 0.0     # starting the LocalCluster / connecting to the scheduler
    solve_phase_s: float = 0.0       # linear builds + variants (wall), without start-up and report
    wall_time_s: float = 0.0


class _Progress:
    def __init__(self, total: int, done: int, enabled: bool):
        from tqdm import tqdm
        self.failures = 0
        self.bar = tqdm(total=total, initial=done, unit="variant", desc="sarfe batch",
                        disable=not (enabled and sys.stderr.isatty()), file=sys.stderr)

    def update(self, record: dict) -> None:
        if record["status"] != "ok":
            self.failures += 1
            self.bar.set_postfix(failed=self.failures, refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


def _group(pipeline, variants, finish):
    """{linear_model_key: [variants]} in batch order; rejected cases are finished as failed."""
    groups: dict[str, list[Variant]] = {}
    for variant in variants:
        try:
            key = str(pipeline.linear_model_key(load_variant_case(pipeline, variant)))
        except Exception as error:
            finish(failed_record(variant, _error_text(error)))
            continue
        groups.setdefault(key, []).append(variant)
    return groups


def _variant_output(output: pathlib.Path, variant: Variant, write: bool) -> str | None:
    return str(output / "variant_outputs" / variant.id) if write else None


def _run_in_process(groups, output, stats, finish, pipeline_name, write_outputs, cache):
    for key, members in groups.items():
        stage = store.load_stage(output, key, (pipeline_name,)) if cache else None
        if stage is not None:
            stats.linear_stages_from_cache += 1
        else:
            try:
                stage, seconds = _timed_build(members[0], pipeline_name)
            except Exception as error:
                for variant in members:
                    finish(failed_record(variant, f"linear model: {_error_text(error)}"))
                continue
            stats.linear_stages_built += 1
            stats.linear_build_s += seconds
            if cache:
                store.save_stage(output, key, stage)
        for variant in members:
            finish(solve_variant(variant, stage, pipeline_name, _variant_output(output, variant, write_outputs)))


def _run_dask(client, groups, output, stats, finish, pipeline_name, write_outputs, cache):
    from distributed import as_completed

    pending = as_completed()
    task_of = {}
    stages, resubmitted = {}, set()      # a group's stage, to scatter again for a lost variant

    def submit_group(key, stage, members=None):
        stages[key] = stage
        shared = client.scatter(stage, broadcast=True, hash=False)
        for variant in groups[key] if members is None else members:
            future = client.submit(solve_variant, variant, shared, pipeline_name,
                                   _variant_output(output, variant, write_outputs),
                                   retries=1, pure=False, key=f"sarfe-variant-{variant.id}-{time.time_ns()}")
            task_of[future.key] = ("variant", variant, key)
            pending.add(future)

    for key, members in groups.items():
        stage = store.load_stage(output, key, (pipeline_name,)) if cache else None
        if stage is not None:
            stats.linear_stages_from_cache += 1
            submit_group(key, stage)
            continue
        future = client.submit(_timed_build, members[0], pipeline_name, retries=1, pure=False,
                               key=f"sarfe-linear-{key[:16]}-{time.time_ns()}")
        task_of[future.key] = ("linear", key, key)
        pending.add(future)

    for future in pending:
        kind, item, group = task_of.pop(future.key)
        transient = False
        try:
            value = future.result()
        except Exception as error:  # exception raised twice, or workers lost (KilledWorker)
            value, message = None, _error_text(error)
            transient = _infrastructure_error(error)
        finally:
            future.release()
        if kind == "linear":
            if value is None:
                for variant in groups[item]:
                    finish(failed_record(variant, f"linear model: {message}", transient))
                continue
            value, seconds = value
            stats.linear_stages_built += 1
            stats.linear_build_s += seconds
            if cache:
                store.save_stage(output, item, value)
            submit_group(item, value)
        elif value is None and transient and item.id not in resubmitted:
            # a worker died holding the only copy of the scattered stage (a worker restarted
            # after the broadcast has none): scatter it again and run the variant once more
            resubmitted.add(item.id)
            submit_group(group, stages[group], [item])
        else:
            finish(value if value is not None else failed_record(item, f"worker: {message}", transient))


def _infrastructure_error(error: BaseException) -> bool:
    """Workers killed or connections lost — not the variant's fault: run it again next time."""
    from concurrent.futures import CancelledError

    from distributed import KilledWorker
    from distributed.comm.core import CommClosedError

    # CancelledError (distributed's FutureCancelledError): a scattered stage lost with the only
    # worker that held it (the scheduler forgets the tasks that depend on it)
    return isinstance(error, (KilledWorker, CommClosedError, TimeoutError, ConnectionError,
                              CancelledError))


def _local_client(workers: int):
    from distributed import Client, LocalCluster

    for name, value in _BLAS_ENV.items():  # spawned workers inherit this too
        os.environ.setdefault(name, value)
    # memory_limit=0: no per-worker share of the RAM. The default (RAM / N) let the nanny kill a
    # worker building the door trim's linear stage (12 GB peak) on 2 workers of a 24 GB machine.
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, memory_limit=0,
                           dashboard_address=None, host="127.0.0.1", silence_logs=logging.ERROR,
                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},  # metrics only, loopback
                           env=dict(_BLAS_ENV))
    return Client(cluster), cluster


def default_output_dir(variants: list[Variant]) -> pathlib.Path:
    sources = list(dict.fromkeys(v.source for v in variants))
    name = sources[0] if len(sources) == 1 and os.sep not in sources[0] else "batch"
    return pathlib.Path("results") / name


def claim_output(output, study_or_cases, variants, force=False) -> pathlib.Path:
    """Check the batch folder (module ``sarfe.results.folder``) and mark it as sarfe's."""
    inputs = study_or_cases if isinstance(study_or_cases, (list, tuple)) else [study_or_cases]
    protected = {item: "a study or case file" for item in inputs
                 if isinstance(item, (str, os.PathLike))}
    for variant in variants:      # the files the variants read (mesh, deck, matrices, curves …)
        if getattr(variant, "case_dir", None):
            protected.setdefault(str(pathlib.Path(variant.case_dir) / "case"), "the folder of a case")
            protected.update(named_files(variant.case, variant.case_dir))
    target = check_output_folder(output, force=force, protected=protected,
                                 what="batch output folder", write_inside=True)
    names = list(dict.fromkeys(v.source for v in variants))
    return claim_folder(target, marker_info("batch", names[0] if len(names) == 1 else None),
                        force=force)


def run_study(study_or_cases, workers: int = 2, scheduler: str | None = None, output_dir=None, *,
              client=None, write_variant_outputs: bool = False, retry_failed: bool = False,
              cache_linear_stages: bool = True, progress: bool = False,
              pipeline: str = PIPELINE, force: bool = False) -> pd.DataFrame:
    """Solve every variant of the study file(s) / case file(s) and return the merged table.

    ``study_or_cases``: a study or case file path, a ``Study``, a case mapping, or a list of these.
    ``workers``: 0 = in this process without Dask, N = a LocalCluster of N processes (ignored when
    ``scheduler`` (address) or ``client`` (a ``distributed.Client``) is given).
    ``output_dir``: default ``results/<study name>``. Finished variants found there are not run
    again (failed ones are, with ``retry_failed``). ``pipeline``: module providing ``load_case``,
    ``linear_model_key``, ``build_linear_model``, ``solve_case`` (tests pass a stand-in).
    The output folder follows the rules of :mod:`sarfe.results.folder`: absent, empty or a
    sarfe batch folder (marker ``.sarfe-result``), never the current folder or one holding an input
    file; anything else is a CaseError before any work unless ``force``.

    Returns the table (one row per variant x frequency point, see ``store.records_table``), with
    ``table.attrs['summary']`` = the dict written to ``summary.json``. Raises ``StudyError`` for an
    unusable study/case file before anything is run.
    """
    start = time.perf_counter()
    variants = collect_variants(study_or_cases)
    output = pathlib.Path(output_dir) if output_dir is not None else default_output_dir(variants)
    output = claim_output(output, study_or_cases, variants, force)

    done = store.read_records(output, [v.id for v in variants], include_transient=False)
    if retry_failed:
        done = {k: r for k, r in done.items() if r.get("status") != "failed"}
    todo = [v for v in variants if v.id not in done]
    stats = RunStats(variants=len(variants), skipped=len(variants) - len(todo))
    bar = _Progress(len(variants), stats.skipped, progress)

    def finish(record: dict) -> None:
        store.write_record(output, record)
        done[record["variant_id"]] = record
        stats.solved += 1
        stats.failed += record["status"] == "failed"
        bar.update(record)

    own_client = cluster = None
    try:
        if todo:
            module = _pipeline(pipeline)
            groups = _group(module, todo, finish)
            stats.linear_models = len(groups)
            stats.linear_model_keys = list(groups)
            if client is None and scheduler is None and workers == 0:
                clock = time.perf_counter()
                _run_in_process(groups, output, stats, finish, pipeline, write_variant_outputs, cache_linear_stages)
                stats.solve_phase_s = time.perf_counter() - clock
            else:
                clock = time.perf_counter()
                if client is None:
                    if scheduler is not None:
                        from distributed import Client
                        own_client = client = Client(scheduler)
                    else:
                        own_client, cluster = _local_client(workers)
                        client = own_client
                stats.mode = "dask"
                stats.workers = len(client.scheduler_info()["workers"])
                stats.cluster_start_s = time.perf_counter() - clock
                clock = time.perf_counter()
                _run_dask(client, groups, output, stats, finish, pipeline, write_variant_outputs, cache_linear_stages)
                stats.solve_phase_s = time.perf_counter() - clock
    finally:
        bar.close()
        if own_client is not None:
            own_client.close()
        if cluster is not None:
            cluster.close()

    table = store.records_table(variants, done)
    store.write_table(table, output)
    stats.wall_time_s = time.perf_counter() - start
    table.attrs["summary"] = batch_report.write_report(table, output, stats)
    return table


__all__ = ["run_study", "solve_variant", "build_stage", "RunStats", "StudyError"]
