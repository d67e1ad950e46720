"""Continuation through stick ↔ slip of a Jenkins friction element (issue 13 item 1).

The 1-DOF oscillator m ü + c u̇ + k u + λ_t = F cos Ωt with a Jenkins element to ground (k_t in
series with a Coulomb slider μ N0): m = k = k_t = μ = N0 = 1, c = 0.02, F = 0.5. The contact
sticks the whole period away from resonance (|λ_t| < μ N0) and slips near it. A stuck slider has
a continuum of periodic states; with the gauge of :mod:`sarfe.hbm.laws.jenkins` the forces are a
function of the unknowns and the continuation passes the whole band in both directions.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.continuation import continuation
from sarfe.hbm.laws.jenkins import SLIP, STICK
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.solution import ContinuationOptions, SolverOptions
from sarfe.hbm.solve import solve_frequency
from sarfe.hbm.time_integration import integrate_time

H, N = 7, 256
OPTIONS = SolverOptions(stability=False)


def oscillator(directions=1):
    """The Jenkins oscillator (1 direction), or a mass moving in a plane on the same contact
    (2 directions, stiffness 1 and 1.5, forces 0.5 cos Ωt and 0.4 sin Ωt: an elliptic orbit)."""
    if directions == 1:
        model = make_linear_model([[1.0]], [[0.02]], [[1.0]])
        rows = [0, -1]
    else:
        model = make_linear_model(np.eye(2), 0.02 * np.eye(2), np.diag([1.0, 1.5]))
        rows = [0, 1]
    contacts = make_contact_set(sp.csr_matrix(np.eye(directions)), ["squeak"], [-1], [rows],
                                gap=0.0, normal_stiffness=0.0, tangential_stiffness=1.0,
                                friction_coefficient=1.0, normal_load=1.0)
    return model, contacts


def excitation(harmonics, directions=1):
    F = np.zeros((2 * harmonics + 1, directions))
    F[1, 0] = 0.5
    if directions == 2:
        F[2, 1] = 0.4
    return F


def amplitude(U, dof=0):
    return float(np.hypot(U[1, dof], U[2, dof]))


def sweep(start, end, directions=1, harmonics=H, samples=N):
    model, contacts = oscillator(directions)
    return continuation(model, contacts, excitation(harmonics, directions), start, end, harmonics,
                        samples, ContinuationOptions(solver=OPTIONS))


def assert_whole_band(points, start, end):
    assert all(p.converged for p in points)
    assert not any("stopped" in p.reason or "min_step" in p.reason for p in points)
    omega = np.array([p.omega for p in points])
    assert omega[0] == start and omega[-1] == pytest.approx(end, rel=1e-12)
    low, high = min(start, end), max(start, end)
    assert np.all((omega >= low - 1e-12) & (omega <= high + 1e-12))
    states = np.concatenate([np.unique(p.contact_state) for p in points])
    assert STICK in states and SLIP in states            # the sweep crossed stick ↔ slip


@pytest.fixture(scope="module")
def up_and_down():
    return sweep(0.5, 2.0), sweep(2.0, 0.5)


def test_jenkins_continuation_passes_stick_both_ways(up_and_down):
    """One continuation each way, no fallback; every 8th point of either sweep is the periodic
    solution a point-by-point Newton finds at its Ω (first-harmonic amplitude to 1e-6)."""
    up, down = up_and_down
    assert_whole_band(up, 0.5, 2.0)
    assert_whole_band(down, 2.0, 0.5)
    assert len(up) < 150 and len(down) < 150
    model, contacts = oscillator()
    for p in up[::8] + down[::8]:
        alone = solve_frequency(model, contacts, excitation(H), p.omega, H, N, options=OPTIONS)
        assert alone.converged
        assert amplitude(p.displacement) == pytest.approx(amplitude(alone.displacement), rel=1e-6)


def test_jenkins_peak_matches_converged_reference(up_and_down):
    """The largest amplitude of the sweep within 0.1 % of the peak at H = 40, N = 2048 (found by a
    bounded scalar search on point-by-point solutions)."""
    from scipy.optimize import minimize_scalar
    up, _ = up_and_down
    peak = max(amplitude(p.displacement) for p in up)
    model, contacts = oscillator()
    F = excitation(40)

    def negative_amplitude(omega):
        s = solve_frequency(model, contacts, F, omega, 40, 2048, options=OPTIONS)
        assert s.converged
        return -amplitude(s.displacement)

    reference = -minimize_scalar(negative_amplitude, bounds=(1.27, 1.32), method="bounded",
                                 options={"xatol": 1e-4}).fun
    assert peak == pytest.approx(reference, rel=1e-3)


def test_jenkins_sweep_points_confirmed_by_time_integration(up_and_down):
    """Stick-dominated (Ω = 0.5: stuck the whole period), slip (Ω ≈ 1.25) and peak points: the
    first harmonic of an independent Newmark integration to its periodic steady state (started
    from the HBM orbit) within 0.5 %."""
    up, _ = up_and_down
    model, contacts = oscillator()
    amp = [amplitude(p.displacement) for p in up]
    slip = min(up, key=lambda p: abs(p.omega - 1.25))
    chosen = {"stick": up[0], "slip": slip, "peak": up[int(np.argmax(amp))]}
    assert np.all(chosen["stick"].contact_state == STICK)
    assert np.any(chosen["slip"].contact_state == SLIP)
    for label, point in chosen.items():
        r = integrate_time(model, contacts, excitation(H), point.omega, H, steps_per_period=1024,
                           initial=point)
        assert r.steady, label
        assert amplitude(point.displacement) == pytest.approx(
            amplitude(r.displacement_harmonics), rel=5e-3), label


@pytest.mark.parametrize("start, end", [(1.3, 2.0), (1.3, 0.5)])
def test_jenkins_sweep_starting_in_slip_is_short(start, end):
    """Sweeps that start near resonance (slipping) pass into stick with few points."""
    points = sweep(start, end)
    assert np.any(points[0].contact_state == SLIP)
    assert_whole_band(points, start, end)
    assert len(points) < 60


def test_two_direction_friction_continuation_passes_stick():
    """A mass in a plane on a 2-D Jenkins contact (elliptic orbit, disk slip limit): the
    continuation passes stick → slip → stick; the peak point agrees with time integration."""
    points = sweep(0.5, 2.0, directions=2, harmonics=5, samples=128)
    assert_whole_band(points, 0.5, 2.0)
    peak = max(points, key=lambda p: amplitude(p.displacement))
    model, contacts = oscillator(2)
    r = integrate_time(model, contacts, excitation(5, 2), peak.omega, 5, steps_per_period=1024,
                       initial=peak)
    assert r.steady
    for dof in (0, 1):
        assert amplitude(peak.displacement, dof) == pytest.approx(
            amplitude(r.displacement_harmonics, dof), rel=1e-2)
