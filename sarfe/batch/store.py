"""On-disk state of a batch run under ``<output>``: resumable and crash-safe.

    <output>/variants/<id>.json     one finished variant (written atomically: temp file + rename)
    <output>/.cache/<key>.npz       linear stages keyed by ``linear_model_key`` (reused on re-runs;
                                    arrays + manifest + content hash, no pickle: ``stage_file``)
    <output>/results.csv|.parquet   merged table, one row per variant x frequency point
    <output>/summary.json, *.png    statistics and plots (``sarfe.batch.batch_report``)

A killed run loses only the variants in flight: everything in ``variants/`` is complete, and a
re-run skips those ids.
"""
from __future__ import annotations

import json
import math
import os
import pathlib
import tempfile

import numpy as np
import pandas as pd

from sarfe.batch.stage_file import StageFileError, load_stage_file, stage_bytes
from sarfe.batch.variants import Variant, canonical_json

# Table columns that describe the variant; the varied inputs and CaseResult.rows keys follow.
VARIANT_COLUMNS = ["variant_index", "variant_id", "source", "status", "error", "exit_code"]


def atomic_write(path: pathlib.Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that readers see the old file or the whole new one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, path)
    except BaseException:
        pathlib.Path(temporary).unlink(missing_ok=True)
        raise


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, pathlib.PurePath):
        return str(value)
    return repr(value)


def to_json(value) -> str:
    """JSON text; floats round-trip exactly (NaN/inf written as NaN/Infinity)."""
    return json.dumps(value, default=_plain, indent=None, sort_keys=False)


def record_path(output: pathlib.Path, variant_id: str) -> pathlib.Path:
    return pathlib.Path(output) / "variants" / f"{variant_id}.json"


def write_record(output, record: dict) -> None:
    atomic_write(record_path(output, record["variant_id"]), to_json(record).encode())


def read_records(output, ids=None, include_transient: bool = True) -> dict[str, dict]:
    """Variant records in ``<output>/variants`` (optionally only ``ids``); ``include_transient=False``
    leaves out failures of the cluster (killed workers), which a re-run solves again."""
    folder = pathlib.Path(output) / "variants"
    records = {}
    if not folder.is_dir():
        return records
    wanted = None if ids is None else set(ids)
    for path in sorted(folder.glob("v*.json")):
        if wanted is not None and path.stem not in wanted:
            continue
        try:
            record = json.loads(path.read_text())
        except (OSError, ValueError):
            continue  # unreadable: treated as not finished, the variant is run again
        if include_transient or not record.get("transient"):
            records[path.stem] = record
    return records


def stage_cache_path(output, key: str) -> pathlib.Path:
    return pathlib.Path(output) / ".cache" / f"{key}.npz"


def load_stage(output, key: str, modules=()):
    """Cached linear stage for ``key`` or None (missing, damaged, edited, for another key or
    holding classes other than sarfe's / ``modules``': rebuilt). Never unpickles."""
    path = stage_cache_path(output, key)
    if not path.is_file():
        return None
    try:
        return load_stage_file(path, key, modules)
    except StageFileError:
        return None


def save_stage(output, key: str, stage) -> None:
    try:
        data = stage_bytes(stage, key)
    except TypeError:  # a stage holding something a data file cannot carry: not cached
        return
    atomic_write(stage_cache_path(output, key), data)


def _cell(value):
    if isinstance(value, (list, dict, tuple)):
        return canonical_json(value)
    return value


def records_table(variants: list[Variant], records: dict[str, dict]) -> pd.DataFrame:
    """One row per variant x frequency point, variants in batch order.

    Columns: ``VARIANT_COLUMNS``, the varied inputs (named by their parameter path), then the keys of
    ``CaseResult.rows`` (a key equal to an earlier column gets the prefix ``result_``). A failed
    variant has one row with its error and empty results.
    """
    parameter_names = list(dict.fromkeys(p for v in variants for p in v.parameters))
    rows = []
    for variant in variants:
        record = records.get(variant.id)
        if record is None:
            continue
        base = {"variant_index": variant.index, "variant_id": variant.id, "source": variant.source,
                "status": record["status"], "error": record.get("error") or "",
                "exit_code": record.get("exit_code")}
        base.update({name: _cell(variant.parameters.get(name, math.nan)) for name in parameter_names})
        for result_row in record.get("rows") or [{}]:
            row = dict(base)
            for key, value in result_row.items():
                row[f"result_{key}" if key in base else key] = _cell(value)
            rows.append(row)
    table = pd.DataFrame(rows)
    if table.empty:
        table = pd.DataFrame(columns=VARIANT_COLUMNS + parameter_names)
    table["exit_code"] = table["exit_code"].astype("Int64")
    table.attrs["parameters"] = parameter_names
    return table


def write_table(table: pd.DataFrame, output) -> dict[str, pathlib.Path]:
    """``results.csv`` and ``results.parquet`` in ``output`` (each written atomically)."""
    output = pathlib.Path(output)
    paths = {"csv": output / "results.csv", "parquet": output / "results.parquet"}
    atomic_write(paths["csv"], table.to_csv(index=False).encode())
    parquet = table.copy()
    for column in parquet.columns:  # Parquet needs one type per column
        if parquet[column].dtype == object:
            kinds = {type(v) for v in parquet[column] if v is not None and not (isinstance(v, float) and math.isnan(v))}
            if len(kinds) > 1:
                parquet[column] = parquet[column].map(lambda v: None if v is None else str(v))
    handle, temporary = tempfile.mkstemp(dir=output, prefix=".results.", suffix=".parquet.tmp")
    os.close(handle)
    try:
        parquet.to_parquet(temporary, index=False)
        os.replace(temporary, paths["parquet"])
    except BaseException:
        pathlib.Path(temporary).unlink(missing_ok=True)
        raise
    return paths
