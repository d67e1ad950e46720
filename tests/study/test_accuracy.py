"""A-posteriori error estimates and the adaptive choice of H, N (sarfe.study.accuracy)."""
import warnings

import numpy as np
import pytest

from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.study.accuracy import (AccuracyTarget, choose_resolution, estimate_errors,
                                  harmonic_energy, parse_accuracy, resize_harmonics,
                                  spectral_tail, suggest_mode_count)
from sarfe.study.lumped import lumped_problem

OPTIONS = SolverOptions(stability=False)


def _solve(p, omega, H, N, initial=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_frequency(p.model, p.contacts, resize_harmonics(p.excitation, H), omega, H, N,
                               initial=initial, options=OPTIONS)


def _amplitude_error(p, s, ref):
    G = p.contacts.gap_map
    a = np.hypot(G @ s.displacement[1], G @ s.displacement[2])
    b = np.hypot(G @ ref.displacement[1], G @ ref.displacement[2])
    return float(np.max(np.abs(a - b)) / b.max())


def test_parse_accuracy():
    assert parse_accuracy("fast").amplitude_rel == 5e-2
    assert parse_accuracy({"erp_db": 0.5}).erp_db == 0.5
    assert parse_accuracy("amplitude_rel=1e-3").amplitude_rel == 1e-3
    assert AccuracyTarget(erp_db=0.5).amplitude_budget() == pytest.approx(10 ** (0.5 / 20) - 1)
    for bad in ("medium", {"erp": 1}, {"erp_db": -1}, {"erp_db": float("nan")}, 3):
        with pytest.raises(ValueError):
            parse_accuracy(bad)


def test_spectral_tail_and_energy():
    X = np.zeros((2 * 4 + 1, 1))
    X[1], X[8] = 1.0, 0.1          # k = 1 cos, k = 4 sin
    assert spectral_tail(X) == pytest.approx(0.1 / np.hypot(1, 0.1))
    e = harmonic_energy(X)
    assert e.tolist() == pytest.approx([0, 1, 0, 0, 0.01])
    assert spectral_tail(np.zeros((5, 2))) == 0.0


def test_linear_problem_has_zero_estimate():
    """No contact ever closes: the harmonic balance is exact for any H, N."""
    p = lumped_problem(gap=1.0, harmonics=3)
    s = _solve(p, 90.0, 3, 64)
    e = estimate_errors(s, p.model, p.contacts, p.excitation)
    assert e.amplitude_rel < 1e-10 and abs(e.erp_db) < 1e-9


@pytest.mark.timeout(300)
def test_estimate_brackets_true_error():
    """Rattle with k_n = 10 k: the true error (against H = 40, N = 2048) is at most the estimate
    (SAFETY included) and at least 1/30 of it."""
    p = lumped_problem(gap=1e-3, penalty_ratio=10.0, harmonics=40)
    omega = 90.0
    ref = _solve(p, omega, 40, 2048)
    assert ref.converged
    for H, N in ((3, 64), (5, 128), (9, 256)):
        s = _solve(p, omega, H, N, initial=resize_harmonics(ref.displacement, H))
        assert s.converged
        e = estimate_errors(s, p.model, p.contacts, resize_harmonics(p.excitation, H))
        true = _amplitude_error(p, s, ref)
        assert true <= e.amplitude_rel, (H, N, true, e.amplitude_rel)
        assert true >= e.amplitude_rel / 30, (H, N, true, e.amplitude_rel)
        assert np.isfinite(e.erp_db) and e.seconds >= 0


@pytest.mark.timeout(300)
def test_aliasing_estimate_tracks_sample_doubling():
    p = lumped_problem(gap=1e-3, penalty_ratio=10.0, harmonics=7)
    s = _solve(p, 90.0, 7, 32)            # N < 4H+1: strong aliasing
    s2 = _solve(p, 90.0, 7, 64, initial=s)
    assert s.converged and s2.converged
    e = estimate_errors(s, p.model, p.contacts, p.excitation, truncation=False)
    change = _amplitude_error(p, s, s2)
    assert np.isnan(e.harmonics_rel)
    assert e.aliasing_rel == pytest.approx(change, rel=0.5, abs=1e-6)


@pytest.mark.timeout(300)
@pytest.mark.parametrize("target", ["fast", "balanced"])
def test_choose_resolution_meets_target(target):
    p = lumped_problem(gap=1e-3, penalty_ratio=10.0, harmonics=40)
    omega = 90.0
    res = choose_resolution(target, p.model, p.contacts, p.excitation, omega, harmonics=2,
                            samples_per_period=16, options=OPTIONS)
    assert res.met, res.reason
    assert res.history and res.history[-1]["harmonics"] == res.harmonics
    ref = _solve(p, omega, 40, 2048)
    true = _amplitude_error(p, res.solution, ref)
    assert true <= parse_accuracy(target).amplitude_budget()


def test_choose_resolution_reports_caps():
    p = lumped_problem(gap=1e-3, penalty_ratio=10.0, harmonics=3)
    res = choose_resolution({"amplitude_rel": 1e-12}, p.model, p.contacts, p.excitation, 90.0,
                            harmonics=2, samples_per_period=16, max_harmonics=4, options=OPTIONS)
    assert not res.met and "cap" in res.reason


def test_suggest_mode_count():
    freqs = np.array([50, 100, 200, 400, 800, 1600.0])
    fast = suggest_mode_count(freqs, 40.0, 3, "fast")
    fine = suggest_mode_count(freqs, 40.0, 3, "fine")
    assert fast["mode_count"] == 2 and fine["mode_count"] == 3     # 180 Hz, 360 Hz cutoffs
    doubled = suggest_mode_count(freqs, 40.0, 3, "fine", modal_rel=0.5, current=4)
    assert doubled["mode_count"] == 8
