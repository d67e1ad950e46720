"""A sweep by need (sarfe.pipeline.solve.by_need) on the lumped panel (tests/hbm/lumped_panel):
where no contact ever closes it is the linear FRF (a closed-form complex solve) to 1e-10; a mixed
sweep's nonlinear points are roots of the full harmonic-balance equations that Newton, started off
them, returns within its tolerance, and its peak is the whole-band continuation's."""
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from small_cases import TINY

from sarfe.hbm import continuation, solve_frequency
from sarfe.hbm.solution import ContinuationOptions, SolverOptions
from sarfe.pipeline import solve_case
from sarfe.pipeline.solve import by_need
from sarfe.pipeline.solve.by_need import sweep_by_need
from sarfe.pipeline.solve.pruned_points import linearized_natural_frequencies

from tests.hbm import lumped_panel as panel
from tests.hbm.test_linear_points import _frf

H, N = 7, 256
OPTIONS = SolverOptions(stability=False)
CONTINUATION = ContinuationOptions(max_step=0.1, solver=OPTIONS)
START, END = 2 * np.pi * 30.0, 2 * np.pi * 90.0


def _by_need(level, start=START, end=END):
    model, contacts = panel.model(), panel.contacts()
    nl = SimpleNamespace(model=model, contacts=contacts, excitation=panel.excitation(H, level))
    return sweep_by_need(nl, start, end, H, N, OPTIONS, CONTINUATION,
                         np.linspace(start, end, 201), 0.5,
                         linearized_natural_frequencies(model, contacts))


def test_a_sweep_whose_contacts_never_close_is_the_linear_frf():
    points = _by_need(0.02)                            # 0.06 m/s²: the gap is never used up
    assert points and all(p.method == "linear" and p.converged for p in points)
    omegas = np.array([p.omega for p in points])
    assert omegas[0] == pytest.approx(START) and omegas[-1] == pytest.approx(END)
    assert np.all(np.diff(omegas) > 0)
    # the linear peak (≈ 50.3 Hz) is a point, located by the golden section
    amplitude = np.array([np.abs(p.displacement[1:3, 0]).max() for p in points])
    assert abs(omegas[np.argmax(amplitude)] / (2 * np.pi) - 50.3) < 1.0
    for p in points:
        frf = _frf(p.omega, 0.02)
        assert np.abs(p.displacement - frf).max() <= 1e-10 * np.abs(frf).max()


def test_mixed_sweep_nonlinear_points_are_newtons():
    points = _by_need(1.0, 2 * np.pi * 25.0, 2 * np.pi * 45.0)   # the rattle closes from 32 Hz
    methods = [p.method for p in points]
    assert "linear" in methods and "harmonic balance" in methods
    model, contacts, F = panel.model(), panel.contacts(), panel.excitation(H, 1.0)
    for p in points[::3]:
        if p.method == "linear":
            assert not np.any(p.contact_state[:, 0])          # the rattle open all period
            continue
        start = p.displacement * (1.0 + 1e-3)
        newton = solve_frequency(model, contacts, F, p.omega, H, N, initial=start,
                                 options=OPTIONS)
        assert newton.converged
        scale = np.abs(p.displacement).max()
        assert np.abs(newton.displacement - p.displacement).max() <= 1e-5 * scale


def test_a_branch_that_runs_past_the_next_stretch_covers_it():
    """1.65 × 3 m/s², 30 → 90 Hz: the linearized screen sees a linear window at 72.9–74.1 Hz
    between the rattle's stretch and the seal's, but the rattle's hardening branch is still closed
    there and runs on to the band's end. The walk takes that branch for the second stretch too (it
    raised before — a continuation from 90 Hz to 90 Hz — and the run fell back to the whole-band
    continuation: the shipped door_trim_p1 did so on every run). The band is covered to 90 Hz, the
    window's points are closed harmonic-balance points, and the nonlinear points are roots that
    Newton, started off them, returns."""
    level = 1.65
    points = _by_need(level, START, END)
    assert points is not None
    omegas = np.array([p.omega for p in points])
    assert omegas[0] == pytest.approx(START) and omegas[-1] == pytest.approx(END)
    window = [p for p in points if 2 * np.pi * 72.9 <= p.omega <= 2 * np.pi * 74.1]
    assert window and all(p.method == "harmonic balance" and np.any(p.contact_state[:, 0])
                          for p in window)
    model, contacts, F = panel.model(), panel.contacts(), panel.excitation(H, level)
    nonlinear = [p for p in points if p.method == "harmonic balance"]
    for p in nonlinear[::10]:
        newton = solve_frequency(model, contacts, F, p.omega, H, p.samples_per_period,
                                 initial=p.displacement * (1.0 + 1e-3), options=OPTIONS)
        assert newton.converged
        scale = np.abs(p.displacement).max()
        assert np.abs(newton.displacement - p.displacement).max() <= 1e-5 * scale


@pytest.mark.slow
def test_mixed_sweep_keeps_the_continuations_peak():
    """30 → 90 Hz, 1.0 × 3 m/s²: the hardening peak (a fold) within 0.1 % in amplitude and
    frequency of one whole-band continuation (measured: 3e-5 and 6e-4)."""
    need = _by_need(1.0)
    plain = continuation(panel.model(), panel.contacts(), panel.excitation(H, 1.0), START, END,
                         H, N, options=CONTINUATION)
    amp = [np.array([np.abs(p.contact_displacement[:, 0]).max() for p in s]) for s in (need, plain)]
    freq = [np.array([p.omega for p in s]) for s in (need, plain)]
    assert amp[0].max() == pytest.approx(amp[1].max(), rel=1e-3)
    assert freq[0][amp[0].argmax()] == pytest.approx(freq[1][amp[1].argmax()], rel=1e-3)


def test_a_failed_walk_is_said_in_the_warnings(monkeypatch):
    """Where the sweep by need raises, the run solves the band as one continuation and says so
    in one warning line (it was only in the points' reasons, and door_trim_p1 fell back unseen on
    every run): :data:`small_cases.TINY` swept 15 → 25 Hz with the walk made to raise."""
    def broken(*args, **kwargs):
        raise RuntimeError("walk broke")

    monkeypatch.setattr(by_need, "sweep_by_need", broken)
    data = yaml.safe_load(TINY)
    data["excitation"].pop("frequency_hz")
    data["excitation"]["sweep"] = {"start_hz": 15.0, "end_hz": 25.0}
    said = []
    result = solve_case(data, write=False, warn=said.append)
    points = result.summary["points"]
    assert points and all(p["converged"] for p in points)
    assert all("sweep by need failed (RuntimeError: walk broke)" in p["reason"] for p in points)
    lines = [w for w in result.summary["warnings"] if "sweep by need failed" in w]
    assert lines == ["sweep by need failed (RuntimeError: walk broke): the band was solved as one "
                     "whole-band continuation instead (the same equations, without the linear "
                     "stretches: slower); please report it"]
    assert lines[0] in said
