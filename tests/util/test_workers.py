"""solver.workers: the per-point work after Newton on forked processes gives the serial results.

- sarfe.util.workers.map_points: the items' results in order, an item's exception raised in the parent,
  the items of a killed worker computed by the parent, one process when workers = 1.
- solve_case on the shipped lumped rattle case (a sweep through its contact resonance, rattle and
  friction, estimates on the stride subset): workers 1 and 2 give the same per-point fields of
  summary.json within 1e-12 relative and the same stability verdicts; a deferred stability that
  raises gives the serial path's result.
"""
from __future__ import annotations

import math
import os
import signal
import time
from pathlib import Path

import pytest

from sarfe.util import workers
from sarfe.case.read import load_case, read_yaml
from sarfe.case.errors import CaseError
from sarfe.pipeline.post import point_workers
from sarfe.pipeline import solve_case

CASES = Path(__file__).resolve().parents[2] / "cases"


def _square(x):
    return x * x


def _pid(_):
    return os.getpid()


def test_map_points_keeps_order_and_uses_other_processes():
    items = list(range(23))
    assert workers.map_points(_square, items, 2) == [x * x for x in items]
    assert os.getpid() not in workers.map_points(_pid, items, 2)
    assert set(workers.map_points(_pid, items, 1)) == {os.getpid()}     # serial: this process


def test_map_points_shares_items_without_pickling_them():
    """Items and function are inherited by fork: a closure over an unpicklable object works."""
    lock = __import__("threading").Lock()          # not picklable

    def uses_lock(x):
        return (x, lock is not None)
    assert workers.map_points(uses_lock, [1, 2, 3], 2) == [(1, True), (2, True), (3, True)]


def _fails_on_three(x):
    if x == 3:
        raise ValueError("item 3")
    return x


def test_an_items_exception_is_raised_in_the_parent():
    with pytest.raises(ValueError, match="item 3"):
        workers.map_points(_fails_on_three, range(8), 2)


def test_items_of_a_killed_worker_are_computed_by_the_parent():
    parent = os.getpid()

    def dies_in_a_worker(x):
        if x == 2 and os.getpid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
        return x + 100

    progress = []
    result = workers.map_points(dies_in_a_worker, range(6), 2, progress=progress.append)
    assert result == [x + 100 for x in range(6)]
    assert sorted(progress) == list(range(6))       # each item once, the parent's too


def test_worker_count_setting():
    assert 1 <= workers.worker_count("auto") <= workers.AUTO_LIMIT
    assert workers.worker_count("auto") <= workers.available_cpus()
    assert workers.worker_count(3) == 3
    assert workers.worker_count(1) == 1


def _lumped(workers_setting, band=(45.0, 60.0)):
    data, _ = read_yaml(CASES / "lumped_rattle.yaml")
    data["excitation"]["sweep"] = {"start_hz": band[0], "end_hz": band[1]}
    data["solver"]["workers"] = workers_setting
    return load_case(data, base_dir=CASES)


@pytest.mark.parametrize("value", [0, "two", 1.5])
def test_workers_setting_is_checked(value):
    with pytest.raises(CaseError, match="workers"):
        _lumped(value)


def _differences(a, b, path=""):
    """Paths where summary.json fragments differ beyond 1e-12 relative (timings skipped)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return [f"{path} keys"]
        return [d for k in a if k != "seconds" for d in _differences(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            return [f"{path} length"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _differences(x, y, f"{path}[{i}]")]
    if isinstance(a, float) and isinstance(b, float):
        same = (math.isnan(a) and math.isnan(b)) or a == b or \
            abs(a - b) <= 1e-12 * max(abs(a), abs(b))
        return [] if same else [f"{path}: {a!r} vs {b!r}"]
    if hasattr(a, "tolist") and hasattr(b, "tolist"):
        return _differences(a.tolist(), b.tolist(), path)
    return [] if a == b else [f"{path}: {a!r} vs {b!r}"]


@pytest.fixture(scope="module")
def serial():
    return solve_case(_lumped(1), write=False)


def test_two_workers_give_the_serial_points(serial):
    parallel = solve_case(_lumped(2), write=False)
    one, two = serial.summary["points"], parallel.summary["points"]
    assert len(one) > 2 * 8                      # the stride subset of the estimates is used
    assert any(p["contacts"][0]["max_penetration_m"] > 0 for p in one)     # it rattles
    assert [p["stable"] for p in one] == [p["stable"] for p in two]
    assert all(p["stable"] is not None or "not resolved" in p["stability_note"]   # computed
               for p in one if p["converged"])
    assert any(isinstance(p["error_estimate"], dict) and not p["error_estimate"].get(
        "interpolated") for p in two)
    assert _differences(one, two) == []
    assert "point_work_s" in parallel.summary["timings_s"]
    assert all(s.stability_job is None for s in parallel.solutions)


def test_a_failing_deferred_stability_gives_the_serial_result(serial, monkeypatch):
    def broken(job):
        raise RuntimeError("stability failed in a worker")

    monkeypatch.setattr(point_workers, "stability_of", broken)
    result = solve_case(_lumped(2), write=False)
    assert "point_work_s" in result.summary["timings_s"]
    assert "in place" in result.summary["workers"]["stability"]
    assert _differences(serial.summary["points"], result.summary["points"]) == []


def test_meshing_leaves_sigpipe_ignored():
    """gmsh's initialize resets SIGPIPE to its default action (kill); sarfe's gmsh start puts
    Python's ignore back, so a pool whose stopped workers close their pipes cannot kill the
    process (the suite once ended in `make: *** Broken pipe` right after a mesh was made)."""
    import ctypes

    from sarfe.mesh.gmsh_model import gmsh_session

    class SigAction(ctypes.Structure):
        _fields_ = [("handler", ctypes.c_void_p), ("mask", ctypes.c_ulong * 16),
                    ("flags", ctypes.c_int), ("restorer", ctypes.c_void_p)]

    def handler():
        action = SigAction()
        ctypes.CDLL(None).sigaction(signal.SIGPIPE, None, ctypes.byref(action))
        return action.handler or 0                  # 0 = SIG_DFL, 1 = SIG_IGN

    with gmsh_session():
        assert handler() == 1
    assert handler() == 1


def _slow_square(x):
    import time

    time.sleep(0.02)
    return x * x


def _settle(stream, count):
    """Poll ``stream`` until its worker has computed ``count`` items (at most 120 s)."""
    import time

    start = time.perf_counter()
    while len(stream.done) < count and time.perf_counter() - start < 120:
        stream.poll()
        time.sleep(0.02)


def test_a_stream_computes_items_while_they_arrive_on_one_other_process():
    """Stream: items submitted one by one while this process works; finish() returns what was
    computed (in another process), the rest is left to the caller; results as the function's."""
    import time

    with workers.Stream(_slow_square) as stream:
        for x in range(30):
            stream.submit(x, x)
            time.sleep(0.01)             # this process "solves the next point"
        _settle(stream, 30)
        done = stream.finish()
    assert done == {x: x * x for x in range(30)}
    assert 1 <= stream.forks <= 30       # a fork per batch of the items waiting
    with workers.Stream(_pid) as stream:
        for x in range(5):
            stream.submit(x, x)
        _settle(stream, 5)
        pids = stream.finish()
    assert len(pids) == 5 and os.getpid() not in pids.values()


def test_a_stream_stops_early_and_reports_exceptions_and_dead_workers():
    import time

    with workers.Stream(_fails_on_three) as stream:
        for x in range(6):
            stream.submit(x, x)
        _settle(stream, 6)
        done = stream.finish()
    assert isinstance(done[3], ValueError)
    assert {k: v for k, v in done.items() if k != 3} == {0: 0, 1: 1, 2: 2, 4: 4, 5: 5}

    def sleeps(x):
        time.sleep(0.2)
        return x

    with workers.Stream(sleeps) as stream:
        for x in range(50):                      # one batch of 50 × 0.2 s
            stream.submit(x, x)
        done = stream.finish()                   # stops after the current item
    assert len(done) < 50

    parent = os.getpid()

    def dies(x):
        if x == 2 and os.getpid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
        return x

    with workers.Stream(dies) as stream:
        for x in range(5):
            stream.submit(x, x)
        start = time.perf_counter()
        while (stream.pending or stream._process is not None) and time.perf_counter() - start < 120:
            stream.poll()                       # batches until every item was handed out
            time.sleep(0.02)
        done = stream.finish()
    assert 2 not in done and all(done[k] == k for k in done) and {0, 1} <= set(done)


def test_the_parallel_solve_computes_stability_during_the_sweep(serial):
    """workers 2: part of the Hill stability is computed while the sweep runs, and the points are
    the serial path's (same verdicts, same fields within 1e-12)."""
    parallel = solve_case(_lumped(2), write=False)
    record = parallel.summary["workers"]
    assert record["processes"] == 2
    assert record["stability_points"] == sum(p["converged"] for p in serial.summary["points"])
    assert 0 < record["stability_during_sweep"] <= record["stability_points"]
    assert record["stream_processes"] >= 1
    assert _differences(serial.summary["points"], parallel.summary["points"]) == []
    assert serial.summary["workers"] == {"processes": 1}


def test_an_error_in_a_worker_is_one_error_and_leaves_no_result_folder(tmp_path, monkeypatch):
    """A point record that raises on a worker ends the solve with that exception (the CLI's one
    line), and neither the result folder nor a temporary sibling is left behind."""
    from sarfe.pipeline.post import records as postprocess

    original, parent = postprocess.point_records, os.getpid()

    def fails_in_a_worker(config, stage, nl, points):      # the records of a chunk of points
        if any(index == 5 for index, _, _ in points) and os.getpid() != parent:
            raise RuntimeError("record of point 5 failed")
        return original(config, stage, nl, points)

    monkeypatch.setattr(postprocess, "point_records", fails_in_a_worker)
    target = tmp_path / "result"
    with pytest.raises(RuntimeError, match="record of point 5 failed"):
        solve_case(_lumped(2), output_dir=target)
    assert list(tmp_path.iterdir()) == []


def test_record_progress_counts_each_chunk_by_its_own_points(monkeypatch):
    """Records go to the workers in chunks of unequal size that finish in any order: the progress
    callback still ticks once per point, and the records come back in point order."""
    from sarfe.pipeline.post import records as postprocess

    def records(config, stage, nl, points):
        if points[0][0] == 0:                 # the first chunk finishes last
            time.sleep(0.3)
        return [index * 10 for index, _, _ in points]

    monkeypatch.setattr(postprocess, "record_chunks", lambda count: [[0, 1, 2, 3, 4], [5], [6, 7]])
    monkeypatch.setattr(postprocess, "point_records", records)
    ticks = []
    result = point_workers.point_records(None, None, None, list(range(8)), [None] * 8, 2,
                                         progress=lambda: ticks.append(1))
    assert result == [i * 10 for i in range(8)]
    assert len(ticks) == 8
