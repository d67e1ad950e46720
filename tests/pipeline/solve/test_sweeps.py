"""Honest sweeps: every reported point lies in the requested band, folds are passed by continuation
(a stall at a corner of the sampled branch is not reported as a fold), and a sweep that falls back
to point-by-point solving says so in summary.json, on the console and in the exit code."""
from __future__ import annotations

import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from sarfe.case.read import load_case
from sarfe.pipeline import solve_case
from sarfe.pipeline.solve.points import POINT_BY_POINT, sweep_status

CASES = Path(__file__).resolve().parents[3] / "cases"


def _sweep(name, start_hz=None, end_hz=None, **solver):
    data = load_case(CASES / f"{name}.yaml").data
    data["solver"].update(error_estimate=False, stability=False, **solver)
    if start_hz is not None:
        data["excitation"]["sweep"] = {"start_hz": start_hz, "end_hz": end_hz}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_case(data, write=False)


def _amplitude(result):
    return np.array([p["contacts"][0]["normal_amplitude_m"] for p in result.summary["points"]])


def _frequencies(result):
    return np.array([p["frequency_hz"] for p in result.summary["points"]])


def _assert_in_band(result, lo, hi):
    f = _frequencies(result)
    assert f.min() >= lo - 1e-9 and f.max() <= hi + 1e-9, (f.min(), f.max())


@pytest.mark.timeout(300)
def test_lumped_rattle_sweep_passes_its_fold_by_continuation():
    """cases/lumped_rattle.yaml (N = 256): one continuation over 30 → 90 Hz — no stop, no
    point-by-point fallback, no near-identical rows — whose hardening peak (the fold of the upper
    branch) matches a sweep with 8× the AFT samples (N = 2048) to 0.5 % in amplitude and 0.2 % in
    frequency."""
    result = _sweep("lumped_rattle")
    summary = result.summary
    _assert_in_band(result, 30.0, 90.0)
    assert summary["sweep_complete"] is True and summary["sweep_stop_reason"] is None
    assert result.exit_code == 0
    a, f = _amplitude(result), _frequencies(result)
    steps = np.hypot(np.diff(f) / 60.0, np.diff(a) / a.max())
    assert steps.min() > 1e-5                                 # no stalled near-duplicates
    reference = _sweep("lumped_rattle", samples_per_period=2048)
    a_ref, f_ref = _amplitude(reference), _frequencies(reference)
    assert a.max() == pytest.approx(a_ref.max(), rel=5e-3)
    assert f[np.argmax(a)] == pytest.approx(f_ref[np.argmax(a_ref)], rel=2e-3)
    assert a.max() > 1.5e-4          # gap 0.1 mm: a real rattle, the upper branch was followed


@pytest.mark.timeout(300)
def test_rattle_rig_sweep_stays_in_its_band():
    """cases/rattle_rig.yaml, 24 → 40 Hz (it used to turn back at 31.4 Hz and run down to 6.6 Hz):
    every reported point in the band, the sweep reaches 40 Hz by continuation, passing a fold
    (ω turns at least twice on the way)."""
    result = _sweep("rattle_rig")
    _assert_in_band(result, 24.0, 40.0)
    assert result.summary["sweep_complete"] is True and result.exit_code == 0
    f = _frequencies(result)
    assert f[-1] == pytest.approx(40.0)
    turns = np.count_nonzero(np.diff(np.sign(np.diff(f))) != 0)
    assert turns >= 2                                           # up to the fold, back, up again


@pytest.mark.timeout(300)
def test_branch_turning_back_past_the_start_stops_at_the_band_edge():
    """lumped_rattle swept down from 70 Hz: the branch turns at its lower fold and climbs back past
    70 Hz. The continuation stops at exactly 70 Hz (no point above it), the rest of the band is
    solved point by point and the summary says so; the band is still covered, so exit code 0."""
    result = _sweep("lumped_rattle", 70.0, 30.0)
    summary = result.summary
    _assert_in_band(result, 30.0, 70.0)
    edge = [p for p in summary["points"] if "turned back past the start" in p["reason"]]
    assert len(edge) == 1 and edge[0]["frequency_hz"] == pytest.approx(70.0)
    assert summary["sweep_complete"] is False and summary["sweep_covered"] is True
    assert "point by point" in summary["sweep_stop_reason"] and result.exit_code == 0


def test_sweep_status_exit_code_rule():
    """An incomplete sweep is covered when converged points reach both ends with no gap wider than
    the continuation's largest step; otherwise it is reported as not covered (exit code 3)."""
    case = load_case(CASES / "lumped_rattle.yaml")          # 30 → 90 Hz, max_step 0.1 → 6 Hz

    def point(f, reason="converged", converged=True):
        return SimpleNamespace(omega=2 * np.pi * f, reason=reason, converged=converged)

    fallback = f"converged ({POINT_BY_POINT})"
    stop = "converged; sweep stopped: step below min_step 1e-06 near ω = 400"
    covered = ([point(f) for f in (30, 35, 40)] + [point(45, stop)]
               + [point(f, fallback) for f in np.linspace(45, 90, 10)])
    status = sweep_status(case.config.excitation, case.config.solver.continuation, covered)
    assert status["complete"] is False and status["covered"] is True
    assert "45.00 Hz" in status["reason"] and "10 point(s)" in status["reason"]
    holed = covered[:4] + [point(f, fallback, converged=f < 60) for f in np.linspace(45, 90, 10)]
    status = sweep_status(case.config.excitation, case.config.solver.continuation, holed)
    assert status["complete"] is False and status["covered"] is False
    assert "exit code 3" in status["reason"]
    assert sweep_status(case.config.excitation, case.config.solver.continuation, [point(f) for f in np.linspace(30, 90, 20)])["complete"] is True


@pytest.mark.timeout(300)
def test_stopped_continuation_is_reported_on_the_console(tmp_path, capsys):
    """max_points 5 stops the continuation: the rest is solved point by point, summary.json says
    sweep_complete false with the reason, one console line says so, exit code 0 (covered)."""
    import yaml

    from sarfe.cli import main

    data = load_case(CASES / "lumped_rattle.yaml").data
    data.pop("case_data", None)
    data["solver"].update(error_estimate=False, stability=False)
    data["solver"]["continuation"]["max_points"] = 5
    data["output"] = {"directory": str(tmp_path / "out"), "files": ["summary"]}
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    code = main(["solve", str(path), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0
    lines = [line for line in err.splitlines() if "sweep not complete" in line]
    assert len(lines) == 1 and "max_points 5" in lines[0] and "covered" in lines[0]
