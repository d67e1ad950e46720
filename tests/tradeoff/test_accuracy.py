"""A-posteriori error estimates (sarfe.accuracy)."""
import warnings
from pathlib import Path

import numpy as np
import pytest

from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.accuracy.estimate import estimate_errors
from sarfe.accuracy.measures import harmonic_energy, resize_harmonics, spectral_tail
from sarfe.accuracy.target import AccuracyTarget, parse_accuracy
from sarfe.tradeoff.lumped import lumped_problem

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


# ------------------------------------------------------------- shipped cases against a reference
def _case_setting(name, frequencies_hz, H, N, cutoff_hz=None):
    """Stage, nonlinear model and stepped solutions of cases/<name>.yaml at H, N (FE: cutoff)."""
    from pathlib import Path

    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.solve.points import solve_points

    data = load_case(Path(__file__).resolve().parents[2] / "cases" / f"{name}.yaml").data
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = list(frequencies_hz)
    data["solver"].update(harmonics=H, samples_per_period=N, prune_contacts=False,
                          error_estimate=False, stability=False)
    if cutoff_hz is not None:
        data["reduction"] = dict(data.get("reduction", {}), cutoff_hz=cutoff_hz)
    case = load_case(data)
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return stage, nl, solve_points(case.config.solver, case.config.excitation, nl)


def _raise_to(nl, solution, H, N):
    """Reference: H raised in steps of ×1.5 from a converged solution (warm starts)."""
    current = solution
    while current.harmonics < H:
        h = min(H, max(current.harmonics + 2, int(round(1.5 * current.harmonics))))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            current = solve_frequency(nl.model, nl.contacts, resize_harmonics(nl.excitation, h),
                                      solution.omega, h, N,
                                      initial=resize_harmonics(current.displacement, h),
                                      options=SolverOptions(stability=False, max_iterations=100))
        assert current.converged, (h, current.reason)
    return current


def _true_errors(stage, s, ref_stage, ref):
    """(max |Δa₁| / max a₁ over the contact rows, the larger of |ΔL_ERP| and |ΔL_ERP,A| [dB]);
    each with its own ERP map."""
    from sarfe.accuracy.measures import erp_proxy

    a = np.hypot(*np.asarray(s.contact_displacement)[1:3])
    b = np.hypot(*np.asarray(ref.contact_displacement)[1:3])
    db = []
    for weighted in (False, True):      # the estimate bounds the larger of dB and dB(A)
        p = erp_proxy(s.displacement, s.omega, stage.erp_map, stage.erp_areas, weighted)
        q = erp_proxy(ref.displacement, ref.omega, ref_stage.erp_map, ref_stage.erp_areas,
                       weighted)
        db.append(abs(10 * np.log10(p / q)))
    return float(np.max(np.abs(a - b)) / b.max()), float(max(db))


@pytest.mark.timeout(300)
def test_estimate_brackets_lumped_rattle_case():
    """cases/lumped_rattle.yaml near its resonance at H = 3, 5: the estimate the pipeline reports
    is at least the true error against H = 40, N = 4096 (amplitude and ERP) and at most 5× it."""
    from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

    for H, N in ((3, 64), (5, 128)):
        stage, nl, sols = _case_setting("lumped_rattle", [48.0, 55.0], H, N)
        for s in sols:
            assert s.converged and np.abs(s.contact_force_time).max() > 0   # it rattles
            ref = _raise_to(nl, s, 40, 4096)
            e = stage_error_estimate(s, stage, nl)
            true_rel, true_db = _true_errors(stage, s, stage, ref)
            assert true_rel <= e.amplitude_rel <= 5 * true_rel, (H, s.omega, true_rel, e)
            assert true_db <= e.erp_db <= 5 * true_db, (H, s.omega, true_db, e)


@pytest.mark.timeout(600)
def test_estimate_brackets_squeak_rig_at_low_harmonics():
    """FE squeak rig (stick–slip) at its 100 Hz point, H = 1 and 2: against a reference with
    H = 12, N = 512 and 3× the reduction cutoff (more modes), the estimate — harmonics, aliasing
    and the re-solved modal part — brackets the true amplitude and ERP errors, within a factor 5."""
    from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

    freqs = [100.0]
    ref_stage, ref_nl, ref_sols = _case_setting("squeak_rig", freqs, 3, 128, cutoff_hz=2025.0)
    assert ref_stage.info["cutoff_hz"] == 2025.0        # 3 × the case's 1.5 · 3 · 150 Hz
    refs = [_raise_to(ref_nl, s, 12, 512) for s in ref_sols]
    for H, N in ((1, 16), (2, 32)):
        stage, nl, sols = _case_setting("squeak_rig", freqs, H, N)
        assert stage.info["cutoff_hz"] < ref_stage.info["cutoff_hz"]
        for s, ref in zip(sols, refs):
            assert s.converged
            e = stage_error_estimate(s, stage, nl)
            assert np.isfinite(e.modal_rel) and e.modal_rel > 0    # the contact rows see the modes
            true_rel, true_db = _true_errors(stage, s, ref_stage, ref)
            assert true_rel <= e.amplitude_rel <= 5 * true_rel, (H, s.omega, true_rel, e)
            assert true_db <= e.erp_db <= 5 * true_db, (H, s.omega, true_db, e)


@pytest.mark.timeout(300)
def test_coarser_model_is_the_reduction_with_fewer_modes():
    """The modal estimate's coarser model (top fifth of the modes out, residual modes and modal
    damping rebuilt) is the case's own Craig–Bampton reduction with that many fewer modes: the
    change it reports equals the difference of the two solved cases (door trim on a coarse mesh,
    12 and 10 modes, 67 Hz)."""
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.solve.points import solve_points
    from sarfe.accuracy.modal_truncation import modal_truncation_change
    from sarfe.pipeline.solve.case_accuracy import stage_modal_coordinates

    def solved(mode_count):
        data = load_case(Path(__file__).resolve().parents[2] / "cases" / "door_trim.yaml").data
        data["model"]["fe"]["generator"]["mesh_size_m"] = 0.04
        data["excitation"]["frequency_hz"] = [67.0]
        data["solver"].update(prune_contacts=False, error_estimate=False, stability=False)
        data["reduction"] = {"mode_count": mode_count}
        case = load_case(data)
        stage = build_linear_model(case)
        nl = nonlinear_model(case, stage)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return stage, nl, solve_points(case.config.solver, case.config.excitation, nl)[0]

    stage, nl, s = solved(12)
    small_stage, small_nl, small = solved(10)
    assert s.converged and small.converged and stage.info["residual_vectors"] > 0
    modal, residual = stage_modal_coordinates(stage)
    rel, db, removed = modal_truncation_change(s, nl.model, nl.contacts, nl.excitation, modal,
                                               residual, stage.erp_map, stage.erp_areas)
    assert removed == 2
    a = np.hypot(*np.asarray(s.contact_displacement)[1:3])
    b = np.hypot(*np.asarray(small.contact_displacement)[1:3])
    true_rel = float(np.max(np.abs(a - b)) / a.max())
    _, true_db = _true_errors(small_stage, small, stage, s)
    assert rel > 1e-6 and rel == pytest.approx(true_rel, rel=1e-3)
    assert db == pytest.approx(true_db, rel=1e-3)
