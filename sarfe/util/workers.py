r"""Worker processes for the per-point work of a run: an ordered map on a fork context.

    map_points(function, items, workers, progress=None) -> [function(item) for item in items]

computed by ``workers`` processes forked from this one. Fork shares the parent's memory
copy-on-write: ``function`` and ``items`` (a closure over the reduced model, the converged points)
are never pickled — a worker receives an item's index and pickles back only its result (a
StabilityResult, a record dict). ``workers`` ≤ 1, or a single item, is the plain loop in this
process. This module imports only :mod:`sarfe.util.parent_watch`, so every layer may use it.

- Threads: the pool is forked under ``threadpool_limits(1)`` and every worker keeps one BLAS /
  OpenMP thread (docs/performance.md: oversubscribed BLAS threads on 2 cores cost 75×).
- Memory: the parent's objects are frozen out of the garbage collector while the workers run
  (``gc.freeze``), so a worker's collections do not copy the pages they sit on.
- Errors: an exception raised by ``function`` in a worker is raised again in the parent, as in the
  loop. A worker that dies (killed, out of memory) leaves its items to the parent, which computes
  them itself: the results are the same, only later.
- Ctrl-C: the workers ignore SIGINT; the parent receives it, stops its workers and re-raises.
- A parent killed outright (SIGKILL, out of memory): every worker ends with it, within
  :data:`sarfe.util.parent_watch.POLL_S` at most (the kernel's parent-death signal on Linux, a
  watchdog thread elsewhere), instead of waiting on its task pipe for good.
  The workers write no result file, except the ERP map series (``sarfe.results.
  write_erp_sweep``: each map its own file, in the run's temporary directory, at the end).
- ``progress(item)``: called in the parent once per finished item, with that item (in finishing
  order), so a caller whose items are of different sizes can weigh them.

:func:`worker_count` turns the case's ``solver.workers`` (``auto`` | n) into a process count.
:class:`Stream` computes items that arrive one at a time on one worker; :class:`Background`
prepares a state on one worker forked at once (before this process builds its own large arrays)
and answers questions on it later (the mesh term's coarser models, built while the sweep runs).
Both fork their one worker by :func:`fork_worker`; :func:`release_memory` hands a waiting
worker's freed heap back to the system.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import gc
import multiprocessing
import os
import signal
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from sarfe.util.parent_watch import die_with_parent

AUTO_LIMIT = 2          # 'auto' uses at most 2 processes (the P1 machine has 2 cores)
WORKER_MEMORY_SHARE = 0.5   # 'auto': a worker may add up to half the parent's resident memory

_TASK = None            # (function, items) of the map in progress: inherited by the forked workers


def available_cpus() -> int:
    """The CPUs this process may run on (its affinity mask; the CPU count where there is none)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:       # (not Linux)
        return os.cpu_count() or 1


def _memory_kb(field) -> int | None:
    """A field of /proc/meminfo or /proc/self/status [kB] (None where unavailable)."""
    path = "/proc/meminfo" if field == "MemAvailable" else "/proc/self/status"
    try:
        with open(path) as stream:
            for line in stream:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def memory_workers() -> int | None:
    """How many workers the free memory allows: MemAvailable / (WORKER_MEMORY_SHARE × this
    process's resident set), a worker being assumed to add that much (its own arrays; the model is
    shared). None where /proc does not say."""
    available, resident = _memory_kb("MemAvailable"), _memory_kb("VmRSS")
    if not available or not resident:
        return None
    return int(available // (WORKER_MEMORY_SHARE * resident))


def worker_count(setting="auto") -> int:
    """Processes for the per-point work: ``auto`` = min(available CPUs, AUTO_LIMIT, what memory
    allows), an integer n ≥ 1 = n. 1 in a daemonic process (e.g. a Dask worker of ``sarfe batch``),
    which may not start processes of its own."""
    if multiprocessing.current_process().daemon:
        return 1
    if setting == "auto":
        limits = [available_cpus(), AUTO_LIMIT, memory_workers()]
        return max(1, min(n for n in limits if n is not None))
    return max(1, int(setting))


def _start_worker(parent_pid: int):
    """Initializer of a forked worker: it dies with the process ``parent_pid`` that forked it
    (SIGKILL included: :func:`sarfe.util.parent_watch.die_with_parent`), SIGINT goes to the
    parent only, one BLAS / OpenMP thread."""
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)


def _run(index):
    function, items = _TASK
    return function(items[index])


def map_points(function, items, workers, progress=None) -> list:
    """[function(item) for item in items] on ``workers`` forked processes (module docstring)."""
    return start_map(function, items, workers).result(progress)


class PendingMap:
    """A :func:`start_map` in progress: ``result(progress)`` waits for it and returns the results
    in order (``cancel()`` ends its workers). The items given to ``workers`` ≤ 1 are computed by
    ``result`` in this process."""

    def __init__(self, function, items, pool, pending):
        self.function, self.items = function, items
        self.pool, self.pending = pool, pending

    def result(self, progress=None) -> list:
        function, items = self.function, self.items
        results = [None] * len(items)
        if self.pool is None:
            for i, item in enumerate(items):
                results[i] = function(item)
                if progress is not None:
                    progress(item)
            return results
        done, pending, pool = set(), self.pending, self.pool
        try:
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    i = pending.pop(future)
                    try:
                        results[i] = future.result()
                    except BrokenProcessPool:     # a worker died: the parent computes what is left
                        continue
                    done.add(i)
                    if progress is not None:
                        progress(items[i])
        except BaseException:                     # Ctrl-C or an item's exception: stop the workers
            self.cancel()
            raise
        self._release()
        pool.shutdown(wait=True)
        for i in range(len(items)):               # items of a worker that died
            if i not in done:
                results[i] = function(items[i])
                if progress is not None:
                    progress(items[i])
        return results

    def cancel(self):
        _stop(self.pool)
        self._release()

    def _release(self):
        global _TASK
        if self.pool is not None and _TASK is not None:
            _TASK = None
            gc.unfreeze()


def start_map(function, items, workers) -> PendingMap:
    """Fork the workers of :func:`map_points` and hand them the items, without waiting: this
    process goes on with other work and collects the results with ``.result()`` (one map at a
    time: the next starts after this one's result)."""
    global _TASK
    items = list(items)
    if workers <= 1 or len(items) <= 1 or multiprocessing.current_process().daemon:
        return PendingMap(function, items, None, None)
    from threadpoolctl import threadpool_limits

    if _TASK is not None:
        raise RuntimeError("a map is already in progress")
    _TASK = (function, items)
    pool = None
    gc.freeze()     # the workers' garbage collector leaves the parent's objects (and pages) alone
    try:
        with threadpool_limits(limits=1):     # fork with one BLAS thread (no pool to inherit)
            pool = ProcessPoolExecutor(max_workers=min(int(workers), len(items)),
                                       mp_context=multiprocessing.get_context("fork"),
                                       initializer=_start_worker, initargs=(os.getpid(),))
            pending = {pool.submit(_run, i): i for i in range(len(items))}
    except BaseException:
        _stop(pool)
        _TASK = None
        gc.unfreeze()
        raise
    return PendingMap(function, items, pool, pending)


def _stop(pool):
    """Cancel what is queued and end the workers now (running items are abandoned)."""
    if pool is None:
        return
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=5)


class Stream:
    r"""``function(item)`` for items that arrive one at a time, on one forked process while this
    one goes on producing them (the Hill stability of the points of a sweep while Newton solves
    the next ones).

        stream = Stream(function)
        stream.submit(key, item)        # returns at once
        …
        done = stream.finish()          # {key: result} of the items computed so far

    There is never more than one worker. ``submit`` collects the finished results and, when no
    worker runs, forks one for the items submitted since the last fork (a fork inherits them:
    nothing is pickled on the way there, only the results come back). ``finish`` asks the worker
    to stop after its current item and returns what was computed; the caller computes the rest
    (:func:`map_points`), so the results do not depend on how far the stream got. An item whose
    function raised is in ``done`` as the exception (the caller decides), a worker that died
    leaves its items undone. ``forks`` counts the workers started. Use it as a context manager:
    leaving the block (Ctrl-C, an exception) ends the worker.
    """

    def __init__(self, function):
        self.function = function
        self.pending = []           # (key, item) submitted since the last fork
        self.done = {}              # key → result (or the exception an item raised)
        self.forks = 0
        self._process = self._connection = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._end(stop=True)
        return False

    def submit(self, key, item):
        self.pending.append((key, item))
        self.poll()

    def poll(self):
        """Collect the finished results; start a worker for the items waiting if none runs."""
        self._collect()
        if self._process is None and self.pending:
            self._start()

    def finish(self) -> dict:
        """Stop the worker after its current item; {key: result} of the items computed."""
        if self._process is not None:
            try:
                self._connection.send("stop")
            except OSError:
                pass
            self._collect(wait=True)
        self._end(stop=False)
        return self.done

    def _start(self):
        batch, self.pending = self.pending, []
        self._process, self._connection = fork_worker(_stream_worker, self.function, batch)
        self.forks += 1

    def _collect(self, wait=False):
        """Read the finished results; the worker's end (sentinel or death) clears it."""
        if self._process is None:
            return
        connection = self._connection
        try:
            while wait or connection.poll():
                message = connection.recv()
                if message is None:            # the worker finished its batch (or stopped)
                    break
                key, result = message
                self.done[key] = result
            else:
                return
        except (EOFError, OSError):            # it died: its undone items stay undone
            pass
        self._end(stop=False)

    def _end(self, stop):
        process, self._process = self._process, None
        if process is None:
            return
        if stop and process.is_alive():
            process.terminate()
        process.join(timeout=None if not stop else 5)
        self._connection.close()
        self._connection = None


def fork_worker(target, *args):
    """One worker process forked now (daemon, one BLAS / OpenMP thread at the fork) running
    ``target(*args, connection, parent_end, parent_pid)``: ``connection`` its end of a pipe,
    ``parent_end`` this process's end (inherited: the worker closes it first, so that the pipe
    closes when this process's copy does) → (process, this process's end of the pipe)."""
    from threadpoolctl import threadpool_limits

    context = multiprocessing.get_context("fork")
    parent, child = context.Pipe()
    with threadpool_limits(limits=1):
        process = context.Process(target=target, args=(*args, child, parent, os.getpid()),
                                  daemon=True)
        process.start()
    child.close()
    return process, parent


def release_memory():
    """Collect garbage and hand the heap's free pages back to the system (glibc ``malloc_trim``;
    nothing where there is none): for a worker that holds a small result of a large build while
    it waits."""
    gc.collect()
    try:
        ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def _stream_worker(function, batch, connection, parent_end, parent_pid):
    """Body of a :class:`Stream` worker: the batch in order, each result sent as soon as it is
    computed, until the parent says stop; then the sentinel None."""
    parent_end.close()
    _start_worker(parent_pid)
    gc.freeze()       # this process's collections leave the inherited objects (and pages) alone
    try:
        for key, item in batch:
            if connection.poll():
                break
            try:
                result = function(item)
            except Exception as error:       # the caller decides (e.g. solve serially)
                result = error
            connection.send((key, result))
        connection.send(None)
    except (BrokenPipeError, EOFError, OSError):
        pass
    finally:
        connection.close()


class Background:
    r"""``prepare()`` on one process forked now, then ``respond(state, message)`` there for each
    :meth:`ask`: work whose costly part does not depend on what this process is about to compute
    (the mesh term's coarser linear stages, :mod:`sarfe.pipeline.solve.mesh_error`, built while
    this process builds its own stage and sweeps).

        background = Background(prepare, respond)   # forks at once; prepare() runs there
        …
        answer = background.ask(message)            # respond(state, message), waited for
        background.close()

    Fork it early, before this process holds large arrays: the worker inherits the parent's pages
    copy-on-write, and only ``message`` and the answers are pickled. ``ask`` returns None where
    the worker died (killed, out of memory) or is closed: the caller then computes the answer
    itself. An exception raised by ``prepare`` or ``respond`` comes back as the answer (the caller
    decides). The worker keeps one BLAS / OpenMP thread and ignores SIGINT, dies with this process
    (SIGKILL included: :func:`sarfe.util.parent_watch.die_with_parent`), ends when its pipe closes
    (:meth:`close`, this object collected) and is a daemon (ended at this interpreter's exit).
    """

    def __init__(self, prepare, respond):
        self._process, self._connection = fork_worker(_background_worker, prepare, respond)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def alive(self) -> bool:
        return self._process is not None and self._process.is_alive()

    @property
    def pid(self) -> int | None:
        """The worker's process id (None once closed)."""
        return None if self._process is None else self._process.pid

    def ask(self, message):
        """``respond(state, message)`` computed by the worker (after ``prepare`` is done), or None
        where the worker is gone."""
        if self._process is None:
            return None
        try:
            self._connection.send(message)
            return self._connection.recv()
        except (EOFError, OSError):
            self.close()
            return None

    def close(self):
        """End the worker (it is told to stop; ended by force after 5 s)."""
        process, self._process = self._process, None
        if process is None:
            return
        try:
            self._connection.send(None)
        except OSError:
            pass
        process.join(timeout=5)
        if process.is_alive():
            process.terminate()
            process.join(timeout=5)
        self._connection.close()


def _background_worker(prepare, respond, connection, parent_end, parent_pid):
    """Body of a :class:`Background` worker: prepare, then answer each message until None (or
    until the parent's end of the pipe closes: this copy of it is closed first)."""
    parent_end.close()
    _start_worker(parent_pid)
    try:
        try:
            state, failed = prepare(), None
        except Exception as error:           # every answer is that error (the caller decides)
            state, failed = None, error
        while True:
            message = connection.recv()
            if message is None:
                break
            if failed is not None:
                answer = failed
            else:
                try:
                    answer = respond(state, message)
                except Exception as error:
                    answer = error
            connection.send(answer)
    except (BrokenPipeError, EOFError, OSError):
        pass
    finally:
        connection.close()
