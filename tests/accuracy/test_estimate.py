"""A-posteriori error estimates of one solution (sarfe.accuracy.estimate): zero on a linear
problem, the aliasing part equal to the N → 2N change, and the estimate bracketing the true error
(against a much finer H, N and, for FE, 3× the reduction cutoff) on a lumped rattle and the shipped
cases."""
import warnings

import numpy as np
import pytest

from sarfe.accuracy.estimate import estimate_errors
from sarfe.accuracy.measures import resize_harmonics
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.tradeoff.lumped import lumped_problem
from tests.accuracy.references import case_setting, raise_to, true_errors

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


def test_linear_problem_has_zero_estimate():
    """No contact ever closes: the harmonic balance is exact for any H, N."""
    p = lumped_problem(gap=1.0, harmonics=3)
    s = _solve(p, 90.0, 3, 64)
    e = estimate_errors(s, p.model, p.contacts, p.excitation)
    assert e.amplitude_rel < 1e-10 and abs(e.erp_db) < 1e-9


@pytest.mark.timeout(300)
def test_estimate_brackets_true_error():
    """Rattle with k_n = 10 k: the true error (against H = 40, N = 2048) is at most the estimate
    (Richardson factors included) and at least 1/30 of it."""
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
def test_estimate_brackets_lumped_rattle_case():
    """cases/lumped_rattle.yaml near its resonance at H = 3, 5: the estimate the pipeline reports
    is at least the true error against H = 40, N = 4096 (amplitude and ERP) and at most 5× it."""
    from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

    for H, N in ((3, 64), (5, 128)):
        stage, nl, sols = case_setting("lumped_rattle", [48.0, 55.0], H, N)
        for s in sols:
            assert s.converged and np.abs(s.contact_force_time).max() > 0   # it rattles
            ref = raise_to(nl, s, 40, 4096)
            e = stage_error_estimate(s, stage, nl)
            true_rel, true_db = true_errors(stage, s, stage, ref)
            assert true_rel <= e.amplitude_rel <= 5 * true_rel, (H, s.omega, true_rel, e)
            assert true_db <= e.erp_db <= 5 * true_db, (H, s.omega, true_db, e)


@pytest.mark.slow   # default suite under 10 min on 2 cores (682 s measured): a long study, run by make bench / make test-all
@pytest.mark.timeout(600)
def test_estimate_brackets_squeak_rig_at_low_harmonics():
    """FE squeak rig (stick–slip) at its 100 Hz point, H = 1 and 2: against a reference with
    H = 12, N = 512 and 3× the reduction cutoff (more modes), the estimate — harmonics, aliasing
    and the re-solved modal part — brackets the true amplitude and ERP errors, within a factor 5."""
    from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

    freqs = [100.0]
    ref_stage, ref_nl, ref_sols = case_setting("squeak_rig", freqs, 3, 128, cutoff_hz=2025.0)
    assert ref_stage.info["cutoff_hz"] == 2025.0        # 3 × the case's 1.5 · 3 · 150 Hz
    refs = [raise_to(ref_nl, s, 12, 512) for s in ref_sols]
    for H, N in ((1, 16), (2, 32)):
        stage, nl, sols = case_setting("squeak_rig", freqs, H, N)
        assert stage.info["cutoff_hz"] < ref_stage.info["cutoff_hz"]
        for s, ref in zip(sols, refs):
            assert s.converged
            e = stage_error_estimate(s, stage, nl)
            assert np.isfinite(e.modal_rel) and e.modal_rel > 0    # the contact rows see the modes
            true_rel, true_db = true_errors(stage, s, ref_stage, ref)
            assert true_rel <= e.amplitude_rel <= 5 * true_rel, (H, s.omega, true_rel, e)
            assert true_db <= e.erp_db <= 5 * true_db, (H, s.omega, true_db, e)
