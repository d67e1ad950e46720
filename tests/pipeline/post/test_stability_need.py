"""Hill stability by need: along a sweep the verdict changes only where a Floquet multiplier
crosses the unit circle, so it is computed at every 4th point, at folds and between differing
verdicts, and inferred between equal ones — every verdict equals the every-point computation on
a branch with a fold pair (an unstable middle branch) and an isolated unstable window."""
from types import SimpleNamespace

import numpy as np

from sarfe.hbm.stability.hill import StabilityResult
from sarfe.pipeline.post.stability_need import (INFERRED, crossing_jobs, seed_jobs,
                                                 stability_by_need)


def _branch():
    """ω along an S-shaped branch (up, back over a middle branch, up again) and the true
    verdict per point: unstable between the two folds and in a window of 2 points later."""
    omega = np.r_[np.linspace(10, 20, 21), np.linspace(19.5, 15, 10), np.linspace(15.5, 30, 30)]
    truth = np.ones(omega.size, bool)
    truth[21:31] = False                 # the middle branch, between the folds at 20 and 31
    truth[45:49] = False                 # a Neimark–Sacker window of four points
    points = [SimpleNamespace(omega=w, stability_job=i) for i, w in enumerate(omega)]
    return points, truth


def test_verdicts_by_need_equal_every_point_with_fewer_computations():
    points, truth = _branch()
    jobs = list(range(len(points)))
    computed = []

    def compute(todo):
        computed.extend(todo)
        return [StabilityResult(bool(truth[j]), -1.0 if truth[j] else 1.0, "", np.zeros(0))
                for j in todo]

    verdicts = stability_by_need(points, jobs, compute)
    assert [verdicts[j].stable for j in jobs] == truth.tolist()
    assert len(set(computed)) == len(computed) < 0.6 * len(points)
    inferred = [j for j in jobs if j not in computed]
    assert inferred and all(INFERRED.format(stride=4) == verdicts[j].note for j in inferred)
    assert all(np.isnan(verdicts[j].leading) for j in inferred)


def test_folds_are_seeds_and_unknown_verdicts_are_bracketed():
    points, _ = _branch()
    seeds = seed_jobs(points)
    assert {19, 20, 21} <= set(seeds) and {29, 30, 31} <= set(seeds)    # ω turns at 20 and 30
    assert seeds[0] == 0 and seeds[-1] == len(points) - 1
    none = StabilityResult(None, float("nan"), "not resolved", np.zeros(0))
    yes = StabilityResult(True, -1.0, "", np.zeros(0))
    assert crossing_jobs(points, {0: yes, 4: none, 8: yes}) == [1, 2, 3, 5, 6, 7]
    assert crossing_jobs(points, {0: yes, 4: yes}) == []


def test_a_window_narrower_than_the_stride_between_seeds_is_missed_as_documented():
    points, truth = _branch()
    truth[45:49] = True
    truth[45:47] = False                 # two unstable points between the seeds 44 and 48
    verdicts = stability_by_need(points, list(range(len(points))), lambda todo: [
        StabilityResult(bool(truth[j]), 0.0, "", np.zeros(0)) for j in todo])
    assert verdicts[45].stable is True and verdicts[45].note.startswith("inferred")


def test_a_list_of_frequencies_computes_every_verdict():
    """Separate frequencies are not one branch: stride 1, every point a seed."""
    from sarfe.pipeline.post.stability_need import stability_stride

    assert stability_stride(SimpleNamespace(sweep=None, frequency_hz=(50.0, 100.0))) == 1
    assert stability_stride(SimpleNamespace(sweep=object())) == 4
    points = [SimpleNamespace(omega=w, stability_job=i) for i, w in enumerate((50.0, 100.0, 150.0))]
    assert seed_jobs(points, 1) == [0, 1, 2]
