"""sarfe.util.workers.Background (the mesh term's coarser models built while the sweep runs,
issue 30): prepare() runs once on another process, each ask() is answered there from its state,
a dead or closed worker answers None (the caller computes it itself), an exception comes back as
the answer, and the worker is gone after close() or when the object is dropped. (Its death with
a killed parent: tests/util/test_parent_watch.py.)"""
from __future__ import annotations

import gc
import os
import signal
import time

import psutil

from sarfe.util import workers


def _gone(pid, timeout_s=10.0) -> bool:
    clock = time.monotonic()
    while time.monotonic() - clock < timeout_s:
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                return True
        except psutil.NoSuchProcess:
            return True
        time.sleep(0.05)
    return False


def test_background_prepares_once_elsewhere_and_answers_from_its_state():
    prepared = []

    def prepare():
        prepared.append(os.getpid())
        return {"pid": os.getpid(), "base": 10}

    with workers.Background(prepare, lambda state, x: (state["pid"], state["base"] + x)) as b:
        pid = b.pid
        answers = [b.ask(x) for x in range(3)]
    assert [a[1] for a in answers] == [10, 11, 12]
    assert {a[0] for a in answers} == {pid} and pid != os.getpid()
    assert prepared == []                       # prepare ran in the worker, not here
    assert _gone(pid) and b.ask(1) is None      # closed: no answer, the caller computes it


def test_background_errors_and_a_dead_worker():
    def respond(state, x):
        if x == 3:
            raise ValueError("three")
        return x

    with workers.Background(lambda: None, respond) as b:
        assert b.ask(1) == 1
        error = b.ask(3)
        assert isinstance(error, ValueError) and str(error) == "three"
        assert b.ask(2) == 2                    # still answering after an error
    with workers.Background(lambda: 1 / 0, respond) as b:
        assert isinstance(b.ask(1), ZeroDivisionError)    # prepare's error is every answer
    with workers.Background(lambda: None, respond) as b:
        os.kill(b.pid, signal.SIGKILL)
        assert b.ask(1) is None and not b.alive()


def test_a_dropped_background_ends_its_worker():
    """The parent's end of the pipe closed (the object collected, e.g. a solve that raised before
    the mesh term): the worker's recv ends and it exits."""
    b = workers.Background(lambda: None, lambda state, x: x)
    pid = b.pid
    del b
    gc.collect()
    assert _gone(pid)
