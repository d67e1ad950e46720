"""The last retry of :func:`sarfe.pipeline.solve.points.solve_point`: a time-integration start guess at
``guess_steps(H)`` steps per period (not the AFT's N) started on the previous orbit, and, when
Newton fails from it, the integration continued from its end state with 8× the steps.

Near grazing impacts Newton at high H needs a very close start: on the rattle rig at 33.47 Hz,
H = 160, N = 8192 it fails from 512- and 1024-step orbits and converges from 4096 steps."""
import dataclasses

import numpy as np
import pytest

import sarfe.hbm
import sarfe.pipeline.solve.points as points
from sarfe.pipeline import load_case
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model


def test_guess_steps_cover_the_harmonics():
    for H in (1, 10, 40, 127, 128, 160, 400):
        steps = points.guess_steps(H)
        assert steps >= max(points.GUESS_STEPS, 2 * H + 1) and steps & (steps - 1) == 0


@pytest.mark.slow   # default suite under 10 min on 2 cores (682 s measured): a long study, run by make bench / make test-all
def test_failed_retry_refines_the_time_integration_from_its_end_state(monkeypatch):
    """Every Newton start fails except one from a guess of 8 × guess_steps(H): the point is that
    Newton's solution, and the refined integration started where the coarse one ended."""
    case = load_case("cases/lumped_rattle.yaml")
    nl = nonlinear_model(case, build_linear_model(case))
    options, _ = points.solver_options(case.config.solver)
    options = dataclasses.replace(options, stability=False)
    omega, H, N = 2 * np.pi * 50.0, case.config.solver.harmonics, 256
    real_solve, real_guess = sarfe.hbm.solve_frequency, points.time_integration_point
    previous = real_solve(nl.model, nl.contacts, nl.excitation, 2 * np.pi * 49.0, H, N,
                          options=options)
    assert previous.converged
    guesses = []

    def guess(*args, initial=None, **kwargs):
        result = real_guess(*args, initial=initial, **kwargs)
        guesses.append((args[5], initial, result))
        return result

    def only_from_fine_guess(*args, initial=None, **kwargs):
        solution = real_solve(*args, initial=initial, **kwargs)
        fine = len(guesses) == 2 and initial is guesses[1][2].displacement
        return solution if fine else dataclasses.replace(solution, converged=False,
                                                         reason="stalled (test)")

    monkeypatch.setattr(points, "solve_frequency", only_from_fine_guess)
    monkeypatch.setattr(points, "time_integration_point", guess)
    point = points.solve_point(nl, omega, H, N, options, previous)
    assert point.converged, point.reason
    steps = points.guess_steps(H)
    assert [g[0] for g in guesses] == [steps, points.GUESS_REFINEMENT_FACTOR * steps]
    assert guesses[0][1] is previous and guesses[1][1] is guesses[0][2]
    assert f"{points.GUESS_REFINEMENT_FACTOR * steps} steps/period" in point.reason
    exact = real_solve(nl.model, nl.contacts, nl.excitation, omega, H, N,
                       initial=guesses[1][2].displacement, options=options)
    assert np.abs(point.displacement - exact.displacement).max() \
        <= 1e-9 * np.abs(exact.displacement).max()


@pytest.mark.slow
def test_rattle_rig_grazing_point_at_high_harmonics_matches_time_integration():
    """Rattle rig 33.47 Hz, H = 160, N = 8192 from the 33.14 Hz orbit (a sweep's warm start fails
    there): the point converges and its contact-row first harmonic is within 0.2 % of a Newmark
    integration (4096 steps/period + Richardson) started on it and run to a steady state."""
    from sarfe.hbm.time_integration import integrate_time

    case = load_case("cases/rattle_rig.yaml")
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    H, N = 160, 8192
    F = np.zeros((2 * H + 1, nl.model.dof_count))
    F[:nl.excitation.shape[0]] = nl.excitation
    nl = dataclasses.replace(nl, excitation=F)
    options, _ = points.solver_options(case.config.solver)
    options = dataclasses.replace(options, stability=False)
    freqs = np.linspace(24.0, 40.0, 50)
    previous = None
    for f in freqs[26:29]:               # 32.49, 32.82, 33.14 Hz: the sweep up to the point
        previous = points.solve_point(nl, 2 * np.pi * f, H, N, options, previous)
        assert previous.converged
    omega = 2 * np.pi * freqs[29]
    point = points.solve_point(nl, omega, H, N, options, previous)
    assert point.converged, point.reason
    check = integrate_time(nl.model, nl.contacts, nl.excitation, omega, H, steps_per_period=4096,
                           max_periods=400, steady_tolerance=1e-10, initial=point,
                           richardson=True)
    assert check.steady
    G = nl.contacts.gap_map

    def first(U):
        return G @ U[1] - 1j * (G @ U[2])
    reference = first(check.displacement_harmonics)
    assert np.linalg.norm(first(point.displacement) - reference) <= 2e-3 * np.linalg.norm(reference)
