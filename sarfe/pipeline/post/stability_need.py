r"""Hill stability by need over a sweep (issue 30 item 2): computed where the verdict can change,
inferred where it cannot.

A periodic orbit's stability changes only where a Floquet multiplier crosses the unit circle: at a
fold of the branch (ω turns), a period doubling or a Neimark–Sacker point. Along a sweep the
verdict is therefore piecewise constant, and it is computed (:func:`sarfe.hbm.stability.deferred.
stability_of`, the same Hill computation as every point had before) at

1. the seeds: every ``stride``-th recorded point in sweep order, the first and the last, and the
   three points around each fold (where ω reverses);
2. every point between two computed neighbours whose verdicts differ, or where either is
   unknown (None, failed): the crossing is located to one point, as if every point were computed.

A point between two computed points with the same verdict takes it, with ``leading`` NaN and the
note :data:`INFERRED` (summary.json ``stability_note``). What this can miss: an unstable window
narrower than ``stride`` points that both its computed neighbours miss (a bubble of instability
between two folds is always seen: folds are seeds). ``stride`` = 1 computes every point.

The serial and the parallel path call the same functions (``compute``: map the jobs, in this
process or on workers), so their verdicts are the same.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.stability.hill import StabilityResult

STABILITY_STRIDE = 4       # a computed verdict every this many points (and at folds, crossings)
INFERRED = ("inferred: computed neighbours in the sweep have this verdict (stability by need, "
            "every {stride}th point, folds and changes computed)")


def stability_stride(excitation) -> int:
    """STABILITY_STRIDE for a sweep (``excitation.sweep``: its points follow one branch), 1 for a
    list of frequencies (separate points: every verdict computed)."""
    return STABILITY_STRIDE if getattr(excitation, "sweep", None) is not None else 1


def ordered_jobs(solutions) -> tuple[list, np.ndarray]:
    """(job indices in sweep order, their ω [rad/s]) of the solutions with a deferred stability."""
    pairs = [(s.stability_job, s.omega) for s in solutions if s.stability_job is not None]
    jobs = list(dict.fromkeys(j for j, _ in pairs))
    omega = {j: w for j, w in pairs}
    return jobs, np.array([omega[j] for j in jobs], dtype=float)


def seed_jobs(solutions, stride: int = STABILITY_STRIDE) -> list:
    """Job indices to compute first (module docstring, 1.), in sweep order."""
    jobs, omega = ordered_jobs(solutions)
    if not jobs:
        return []
    chosen = set(range(0, len(jobs), max(int(stride), 1))) | {len(jobs) - 1}
    turn = np.sign(np.diff(omega))
    for k in np.flatnonzero(turn[:-1] * turn[1:] < 0):          # ω turns at point k + 1
        chosen |= {k, k + 1, k + 2}
    return [jobs[k] for k in sorted(chosen)]


def _verdict(result):
    return None if isinstance(result, Exception) else result.stable


def crossing_jobs(solutions, verdicts: dict) -> list:
    """Job indices between two computed neighbours whose verdicts differ or are unknown (module
    docstring, 2.), not computed yet; ``verdicts``: {job: StabilityResult or exception}."""
    jobs, _ = ordered_jobs(solutions)
    known = [k for k, j in enumerate(jobs) if j in verdicts]
    out = []
    for a, b in zip(known, known[1:]):
        first, second = _verdict(verdicts[jobs[a]]), _verdict(verdicts[jobs[b]])
        if b > a + 1 and (first is None or first != second):
            out += jobs[a + 1:b]
    return out


def inferred_verdicts(solutions, verdicts: dict, stride: int = STABILITY_STRIDE) -> dict:
    """{job: StabilityResult} for the jobs not computed, each between two computed neighbours with
    the same verdict (after :func:`crossing_jobs` has been computed there is no other kind)."""
    jobs, _ = ordered_jobs(solutions)
    known = [k for k, j in enumerate(jobs) if j in verdicts]
    note = INFERRED.format(stride=stride)
    out = {}
    for a, b in zip(known, known[1:]):
        verdict = _verdict(verdicts[jobs[a]])
        for j in jobs[a + 1:b]:
            out[j] = StabilityResult(verdict, float("nan"), note, np.zeros(0, complex))
    return out


def stability_by_need(solutions, jobs, compute, done=None, stride: int = STABILITY_STRIDE):
    """{job: StabilityResult or exception} for every deferred job of ``solutions``: the seeds and
    the crossings computed by ``compute(list of jobs) → list of results`` (exceptions returned,
    not raised), the rest inferred; ``done``: verdicts already computed (the sweep's stream)."""
    verdicts = dict(done or {})
    for chosen in (lambda: seed_jobs(solutions, stride),
                   lambda: crossing_jobs(solutions, verdicts)):
        todo = [j for j in chosen() if j not in verdicts]
        verdicts.update(zip(todo, compute([jobs[j] for j in todo]) if todo else []))
    verdicts.update(inferred_verdicts(solutions, verdicts, stride))
    return verdicts
