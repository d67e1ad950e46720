r"""Hill stability deferred out of the solve: recorded by :func:`sarfe.hbm.solve.finalize`, computed
later — on worker processes (:mod:`sarfe.util.workers`) — for the points that are kept.

Stability feeds nothing back into Newton or the continuation (step size, corners, harmonic set and
the repairs of a sweep read ``converged``, ``residual_norm`` and η only), so a sweep may run
without it and the verdicts be computed afterwards over the reported points:

    with deferred_stability() as jobs:          # finalize records a StabilityJob per point
        solutions = continuation(...)           # stable None, stability_job = index into jobs
    results = map_points(stability_of, [jobs[i] for i in pending(solutions)], workers)
    solutions = with_stability(solutions, jobs, results)

:func:`stability_of` evaluates the converged point exactly as ``finalize`` does in place (the full
residual with the slider start of the solve, then :func:`sarfe.hbm.stability.select.stability`):
same inputs, same arithmetic, so the verdicts and exponents are those of the serial path. Jobs may
also be computed while the sweep goes on (``on_job``: :class:`sarfe.util.workers.Stream`); the
verdicts of points the sweep then drops (backed-up corners, replaced near-duplicates) are simply
not used.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from sarfe.hbm.residual import full_residual
from sarfe.hbm.stability.select import stability, stability_method

_JOBS = None     # the StabilityJob list of the active deferred_stability() block (None: in place)
_ON_JOB = None   # its callback on_job(index, job), or None


@dataclass(frozen=True)
class StabilityJob:
    """What ``finalize`` needs for the Hill stability of a converged point: the problem with all
    harmonic rows, ω [rad/s], ũ (2H+1, n_dof) [m], the slider start of its final evaluation (or
    None) and the SolverOptions (method, tolerance)."""

    problem: object
    omega: float
    displacement: np.ndarray
    slider: object
    options: object


@contextmanager
def deferred_stability(enabled=True, on_job=None):
    """Inside the block ``finalize`` records a :class:`StabilityJob` instead of computing stability
    (yields the job list; ``enabled=False``: yields None and nothing is deferred). ``on_job(index,
    job)`` is called as each job is recorded (e.g. :meth:`sarfe.util.workers.Stream.submit`: the job
    computed on another process while the sweep goes on)."""
    global _JOBS, _ON_JOB
    if not enabled:
        yield None
        return
    outer, _JOBS = (_JOBS, _ON_JOB), []
    _ON_JOB = on_job
    try:
        yield _JOBS
    finally:
        _JOBS, _ON_JOB = outer


def deferring() -> bool:
    """True inside a :func:`deferred_stability` block: :func:`defer` will record the job, so the
    caller's own evaluation needs no contact Jacobian for the stability."""
    return _JOBS is not None


def defer(problem, omega, U, slider, options) -> int | None:
    """Record the stability of a converged point: its job index, or None outside a
    :func:`deferred_stability` block (compute it in place)."""
    if _JOBS is None:
        return None
    job = StabilityJob(problem, float(omega), U, slider, options)
    _JOBS.append(job)
    if _ON_JOB is not None:
        _ON_JOB(len(_JOBS) - 1, job)
    return len(_JOBS) - 1


def stability_of(job: StabilityJob):
    """StabilityResult of a recorded point, computed as ``finalize`` computes it in place."""
    with np.errstate(all="ignore"):
        ev = full_residual(job.problem, job.displacement.ravel(), job.omega, job.slider,
                           jacobian=True,
                           assemble=stability_method(job.problem, job.options) == "full")
    return stability(job.problem, job.omega, job.displacement, ev, job.options)


def pending(solutions) -> list:
    """Job indices of the solutions whose stability is deferred (each once, in point order)."""
    return list(dict.fromkeys(s.stability_job for s in solutions if s.stability_job is not None))


def with_stability(solutions, indices, results) -> list:
    """The solutions with the verdicts of their jobs filled in (``results[k]`` is the
    StabilityResult of job ``indices[k]``)."""
    by_job = dict(zip(indices, results))
    out = []
    for s in solutions:
        if s.stability_job is None:
            out.append(s)
            continue
        r = by_job[s.stability_job]
        out.append(replace(s, stable=r.stable, floquet_exponent=r.leading,
                           stability_note=r.note, stability_job=None))
    return out
