"""Continuation at the extremes (issue 29 item 5): cases/lumped_rattle.yaml with one parameter
pushed — a hard contact (k_n = 10⁹, 10¹⁰ N/m), a tiny gap (10⁻⁷ m), light damping (ζ = 10⁻⁴), a
stiff stick spring on the seal (k_t = 10⁹ N/m) — is swept 30 → 90 Hz by continuation to the end
of the band (``sweep_complete``), or stops with one line naming the knob to turn.

The continued branch is checked against the independent Newmark time integration
(:func:`sarfe.hbm.time_integration.integrate_time`) at k_n = 10¹⁰ N/m: a few points of the sweep,
each integrated from its HBM solution until periodic, must keep their first harmonic (the physics,
not the code's own earlier output).

The full sweeps take 1-3 min each (``@pytest.mark.slow``; times and points in
benchmarks/results/extremes.md, benchmarks/engine/bench_extremes.py).
"""
from __future__ import annotations

import importlib
import warnings
from pathlib import Path

import numpy as np
import pytest

from sarfe.case.read import load_case
from sarfe.hbm.time_integration import integrate_time, section_spread
from sarfe.pipeline import solve_case
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.solve.points import solver_options

continuation_module = importlib.import_module("sarfe.hbm.continuation")   # the package re-exports
CASE = Path(__file__).resolve().parents[2] / "cases" / "lumped_rattle.yaml"   # the function

EXTREMES = {        # one parameter of lumped_rattle changed: (where, key, value)
    "k_n = 1e9 N/m": ("contacts", 0, "normal_stiffness_N_m", 1e9),
    "k_n = 1e10 N/m": ("contacts", 0, "normal_stiffness_N_m", 1e10),
    "gap = 1e-7 m": ("contacts", 0, "gap_m", 1e-7),
    "zeta = 1e-4": ("damping", None, "modal_zeta", 1e-4),
    "k_t = 1e9 N/m": ("contacts", 1, "tangential_stiffness_N_m", 1e9),
}


def extreme_case(name, **solver):
    """The case data of lumped_rattle with the extreme ``name`` (a key of EXTREMES, or None)."""
    data = load_case(CASE).data
    if name is not None:
        section, index, key, value = EXTREMES[name]
        (data[section][index] if index is not None else data[section])[key] = value
    data["solver"].update(solver)
    return data


def _solve(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_case(data, write=False)


def _continue(data, start_hz, end_hz, **keywords):
    """The continuation of the case's nonlinear model alone (no point-by-point fallback, no
    post-processing; ``keywords`` to it) → list of HarmonicSolution."""
    case = load_case(data, base_dir=CASE.parent)
    model = nonlinear_model(case, build_linear_model(case))
    _, options = solver_options(case.config.solver)
    return continuation_module.continuation(
        model.model, model.contacts, model.excitation, 2 * np.pi * start_hz, 2 * np.pi * end_hz,
        case.config.solver.harmonics, case.config.solver.samples_per_period, options=options,
        **keywords)


@pytest.mark.timeout(300)
def test_a_corner_it_may_not_pass_stops_with_one_line_naming_the_knob(monkeypatch):
    """k_n = 10⁹ N/m: where the panel first touches the bracket (42.4 Hz) the branch turns by ~110°
    within a length no N resolves; the sweep steps past such corners with a sphere step, but a
    sweep that meets more than CORNER_LIMIT of them within FOLD_DISTANCE crawls and must stop
    there, saying which knob to turn. With CORNER_LIMIT = 0 the first corner is one too many."""
    monkeypatch.setattr(continuation_module, "CORNER_LIMIT", 0)
    points = _continue(extreme_case("k_n = 1e9 N/m", stability=False), 30.0, 44.0)
    reason = points[-1].reason
    assert "sweep stopped" in reason and "corners of the branch" in reason
    assert "raise solver.samples_per_period" in reason and "\n" not in reason
    assert 42.0 < points[-1].omega / (2 * np.pi) < 43.0


def test_a_closed_loop_of_solutions_is_left_past_its_farthest_frequency(monkeypatch):
    """Gap 10⁻⁷ m: at H = 7 the branch from 30 Hz runs into a loop near 31.2 Hz that it would
    circle for ever (measured; the time integration has no periodic response at 30-31 Hz). The
    sweep of the band leaves it by a new start past the loop's farthest frequency, says so in
    that point's reason and goes on (here ended past 33 Hz by ``stop_when``); with LOOP_LIMIT = 0
    it stops there naming solver.harmonics."""
    data = extreme_case("gap = 1e-7 m", stability=False)
    points = _continue(data, 30.0, 90.0, stop_when=lambda p: p.omega > 2 * np.pi * 33.0)
    left = [p for p in points if continuation_module.LEFT_LOOP in p.reason]
    assert left and all(p.converged for p in points)
    assert points[-1].omega / (2 * np.pi) > 33.0
    loop_end = max(p.omega for p in points[:points.index(left[0])])
    assert left[0].omega > loop_end          # the new start lies past the loop
    monkeypatch.setattr(continuation_module, "LOOP_LIMIT", 0)
    reason = _continue(data, 30.0, 90.0)[-1].reason
    assert "came back onto itself" in reason and "raise solver.harmonics" in reason


PASSING = ("k_n = 1e9 N/m", "k_n = 1e10 N/m", "k_t = 1e9 N/m", "gap = 1e-7 m",   # complete, H = 7
           "zeta = 1e-4")


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("name", sorted(EXTREMES))
def test_extreme_sweeps_complete_or_stop_naming_the_knob(name):
    """Each extreme of lumped_rattle swept 30 → 90 Hz at the case's H = 7 (before: k_n = 10⁹ and
    10¹⁰ N/m stopped at 42.4 Hz, ζ = 10⁻⁴ at 55 Hz, gap 10⁻⁷ m and k_t = 10⁹ N/m turned back past
    30 Hz). The hard contacts, the stiff stick spring and the tiny gap complete by continuation
    (``sweep_complete``, every point in the band, the last at 90 Hz; the gap leaves closed loops
    of H = 7 solutions, 2 in this sweep, said in ``sweep_note``). The light damping completes too
    (measured, bare continuation: 656 points, 358 CPU s at load 5-7): near 54-57 Hz the bracket's
    2ω resonance (its second harmonic 0.2-0.5 mm, Q ≈ 5000) and at 79 Hz the panel's impacting
    resonance (1.6 cm) zig-zag with the AFT sampling at any N tried (a turn of ω at 55.22 Hz,
    N = 2048, is a second solution 2.5 % off the branch that N = 8192 does not have); the sweep
    steps over 9 such sampled folds (sarfe.hbm.sampled_folds) and leaves 3 loops, both said in
    ``sweep_note`` (before: it stopped at 56.59 Hz after leaving 3 loops)."""
    result = _solve(extreme_case(name, error_estimate=False, stability=False))
    summary = result.summary
    f = np.array([p["frequency_hz"] for p in summary["points"]])
    assert f.min() >= 30.0 - 1e-9 and f.max() <= 90.0 + 1e-9
    if name in PASSING or summary["sweep_complete"]:
        assert summary["sweep_complete"] is True, summary["sweep_stop_reason"]
        assert summary["sweep_stop_reason"] is None
        assert (summary["sweep_note"] is not None) == (name in ("gap = 1e-7 m", "zeta = 1e-4"))
        return
    reason = summary["sweep_stop_reason"]
    assert "\n" not in reason and "raise solver." in reason


@pytest.mark.slow
@pytest.mark.timeout(3600)   # measured 1243 s wall, 658 CPU s at load 5-8
def test_stiffest_contact_sweep_completes_with_more_samples():
    """k_n = 10¹¹ N/m (beyond the item's 10¹⁰) completes 30 → 90 Hz by continuation at the
    defaults. Past the first impact the contact force is a ~1 kN pulse of a few µs: at 66.3 Hz
    it was carried by 27 of 16384 samples, and each sample entering turned the branch by ~92°;
    with N capped at 64 × 256 = 16384 the sweep crawled from corner to corner and stopped at
    68.7 Hz. The cap is now the AFT's cost (N × contact rows ≤ SAMPLE_BUDGET: 65536 for this
    case's 2 rows); the sweep goes on at N = 32768 from ~66 Hz past its fold (75.8 Hz) and the
    jump down (57.4 Hz) to 90 Hz (measured, bare continuation: 1280 points, 389 CPU s).
    Against the Newmark integration: benchmarks/results/extremes.md."""
    data = extreme_case(None, error_estimate=False, stability=False)
    data["contacts"][0]["normal_stiffness_N_m"] = 1e11
    summary = _solve(data).summary
    assert summary["sweep_complete"] is True, summary["sweep_stop_reason"]
    assert summary["sweep_stop_reason"] is None
    f = np.array([p["frequency_hz"] for p in summary["points"]])
    assert f.min() >= 30.0 - 1e-9 and f.max() == pytest.approx(90.0)
    raised = [p["reason"] for p in summary["points"] if "N raised to" in (p["reason"] or "")]
    assert any(f"N raised to {2 * 64 * 256}" in r for r in raised), raised   # beyond 64 × N


def test_the_sample_cap_follows_the_contact_rows():
    """The most samples a sweep raises N to (:func:`most_samples`): a lumped model's few contact
    rows may go to N × rows = SAMPLE_BUDGET (lumped_rattle: 2 rows, 2¹⁶ samples; an evaluation
    with its Jacobian costs ∝ N × rows), a case with many contact rows keeps 64 × N."""
    most = continuation_module.most_samples
    budget = continuation_module.SAMPLE_BUDGET
    assert most(256, 2) == budget // 2 == 65536
    assert most(256, 60) == 64 * 256 and most(1024, 2) == 64 * 1024
    assert most(256, 1) * 1 <= budget < 2 * most(256, 1)


def _swept(name):
    """The extreme ``name`` continued 30 → 90 Hz (asserted to reach 90 Hz) → (points, its
    NonlinearModel, frequencies [Hz])."""
    data = extreme_case(name, stability=False)
    points = _continue(data, 30.0, 90.0)
    assert points[-1].omega / (2 * np.pi) == pytest.approx(90.0)
    case = load_case(data, base_dir=CASE.parent)
    model = nonlinear_model(case, build_linear_model(case))
    f = np.array([p.omega / (2 * np.pi) for p in points])
    return points, model, f


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.xfail(strict=True, reason="issue 29, measured 2026-11-28: the H = 7 branch of the "
                   "k_n = 1e10 contact is 17 % (71.5 Hz) and 39 % (75.6 Hz) off the sub-stepped "
                   "Newmark orbit on its impacting part (0.02 % past the jump); the run reports "
                   "no bound there (its impact is not resolved by H': sarfe.accuracy."
                   "contact_resolution; before: ± 9 %). Higher-H Newton does not converge "
                   "from either orbit (benchmarks/results/extremes.md)")
def test_hard_contact_branch_matches_time_integration():
    """k_n = 10¹⁰ N/m, the continued branch at three frequencies on its upper (impacting) part and
    past the jump: each point's first harmonic on all DOFs agrees with an independent Newmark
    integration (2048 steps per period, Richardson) started from it within 2 %.

    The impacts last 12 µs (1/1200 of a period): the integration sub-steps the steps in which the
    contact opens or closes (:data:`sarfe.hbm.newmark.SUBSTEP_RESOLUTION`), checked by the energy
    balance — the elastic contact does no net work over a period (< 1 % of the input; the plain
    trapezoidal rule: −36 % at 71.5 Hz, an orbit that never settles: the cause of this test's
    former > 25 min). The impacting orbit keeps a residual jitter of ~0.2 % from period to
    period (vibro-impact), so 40 periods per run and the spread of the last 10 period-start
    states (< 0.5 %) stand for ``steady``. Measured (2026-11-28, benchmarks/results/extremes.md):
    71.5 Hz 17 %, 75.6 Hz 39 %, 90 Hz 0.02 %; N = 2048 vs 4096 agree to 0.08 % and the
    sub-step resolution 0.05/0.1/0.2 to 0.2 %: the H = 7 branch (its impact a 54 µs, 0.7 kN
    pulse against the integration's 12 µs, 3 kN) misses the 2 % on the impacting part."""
    points, model, f = _swept("k_n = 1e10 N/m")
    amplitude = np.array([np.hypot(*p.displacement[1:3, 0]) for p in points])
    impacting = np.flatnonzero(amplitude > 1e-4)           # closes the 0.1 mm gap
    chosen = [impacting[len(impacting) // 4], impacting[len(impacting) // 2], len(points) - 1]
    errors = {}
    for k in chosen:
        point = points[k]
        H = point.displacement.shape[0] // 2
        reference = integrate_time(model.model, model.contacts, model.excitation, point.omega, H,
                                   steps_per_period=2048, richardson=True, initial=point,
                                   max_periods=40)
        assert reference.steady or section_spread(reference.section, tail=10) < 5e-3, f[k]
        rattle = reference.contact_work[0]                   # panel_bracket: elastic, ∮ λ dr = 0
        assert abs(rattle) < 1e-2 * reference.input_work, (f[k], rattle, reference.input_work)
        a = point.displacement[1] - 1j * point.displacement[2]
        b = reference.displacement_harmonics[1] - 1j * reference.displacement_harmonics[2]
        errors[round(float(f[k]), 2)] = float(np.abs(a - b).max() / np.abs(b).max())
    assert max(errors.values()) < 2e-2, errors


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_tiny_gap_branch_past_its_loops_matches_time_integration():
    """Gap 10⁻⁷ m: the continued branch (past the closed loops it left) against an independent
    Newmark integration (1024 steps per period, from rest-like linear start) at 50, 80 and 88 Hz,
    where the integration reaches a periodic state (at 30, 31, 40, 60 and 70 Hz it does not:
    measured, no periodic response to compare). The branch's first harmonic, interpolated where
    it crosses the frequency, agrees within the H = 7 truncation error measured there (4.6 %,
    4.6 %, 0.3 %; a Newton solve at H = 15 from the integration's state agrees to 0.2 %, 0.03 %,
    0.005 %)."""
    points, model, f = _swept("gap = 1e-7 m")
    first = np.array([p.displacement[1] - 1j * p.displacement[2] for p in points])
    for frequency, bound in ((50.0, 0.06), (80.0, 0.06), (88.0, 0.01)):
        reference = integrate_time(model.model, model.contacts, model.excitation,
                                   2 * np.pi * frequency, 15, steps_per_period=1024,
                                   max_periods=400)
        assert reference.steady
        b = reference.displacement_harmonics[1] - 1j * reference.displacement_harmonics[2]
        errors = [np.abs(first[i] + (frequency - f[i]) / (f[i + 1] - f[i])
                         * (first[i + 1] - first[i]) - b).max() / np.abs(b).max()
                  for i in range(len(f) - 1) if (f[i] - frequency) * (f[i + 1] - frequency) <= 0
                  and f[i] != f[i + 1]]
        assert errors and min(errors) < bound, (frequency, errors)

