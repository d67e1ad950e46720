"""The impact-resolution indicator of the error estimate (sarfe.accuracy.contact_resolution) on a
1-DOF impact oscillator: 0.2 kg on 2·10⁴ N/m (50 Hz, ζ = 3 %), a wall 0.1 mm away, driven with
2 N at 60 Hz (its free amplitude 0.23 mm: it impacts).

Closed form: while the mass touches the wall it oscillates on k + k_n, so an impact lasts half
that period, τ = π √(m / (k + k_n)) (14 µs at k_n = 10¹⁰ N/m, 1.4 ms at 10⁶ N/m). The indicator
must find that duration from the structure's compliance at H' and the law's stiffness, and say
the change-based estimate bounds nothing when τ ≪ T / (2H'). Measured against the independent
Newmark integration (sub-stepped impacts) the H = 7 solution is then 12–16 % off (N = 256 with
Richardson, 30 periods; where a Newton solve at H = 60 from it does not even converge); at
10⁶ N/m the estimate covers the true error (H = 60)."""
from __future__ import annotations

import functools

import numpy as np
import pytest

from sarfe.accuracy.contact_resolution import RESOLUTION_LIMIT, contact_resolution
from sarfe.accuracy.estimate import estimate_errors
from sarfe.accuracy.measures import resize_harmonics
from sarfe.accuracy.time_check import time_integration_error
from sarfe.hbm import solve_frequency
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model

MASS, SPRING, GAP = 0.2, 2e4, 1e-4
OMEGA = 2 * np.pi * 60.0


def oscillator(normal_stiffness):
    """(model, contacts, excitation f̃_e (15, 1) [N]) of the impact oscillator (module docstring)."""
    model = make_linear_model(np.eye(1) * MASS, np.eye(1) * 0.06 * np.sqrt(SPRING * MASS),
                              np.eye(1) * SPRING)
    contacts = make_contact_set(np.eye(1), ["rattle"], [0], [[-1, -1]], gap=GAP,
                                normal_stiffness=normal_stiffness)
    F = np.zeros((15, 1))
    F[1, 0] = 2.0
    return model, contacts, F


@functools.cache
def solved(normal_stiffness):
    """(model, contacts, F, the converged H = 7, N = 256 solution at 60 Hz)."""
    model, contacts, F = oscillator(normal_stiffness)
    solution = solve_frequency(model, contacts, F, OMEGA, 7, 256)
    assert solution.converged
    return model, contacts, F, solution


def first_harmonic(U):
    return complex(U[1, 0], -U[2, 0])


@pytest.mark.parametrize("normal_stiffness", [1e6, 1e10])
def test_impact_duration_is_the_closed_form_half_period_on_the_contact_spring(normal_stiffness):
    """τ_c of the indicator = π √(m / (k + k_n)) within 1 % (the compliance at H' ω is the mass's
    to 0.4 %: k / (m (H'ω)²)); the verdict is ρ ≤ 4 ⇔ H'ω ≥ ω_c / 2 ⇔ τ_c ≥ T / (4H'): resolved
    at 10⁶ N/m (ρ = 0.18), not at 10¹⁰ N/m (ρ = 1.8·10³)."""
    model, contacts, F, solution = solved(normal_stiffness)
    assert np.max(solution.contact_force_time) > 0 and np.min(solution.contact_force_time) == 0
    r = contact_resolution(solution, model, contacts, F, 14)
    closed_form = np.pi * np.sqrt(MASS / (SPRING + normal_stiffness))
    assert r.impact_duration_s == pytest.approx(closed_form, rel=1e-2)
    assert r.ratio == pytest.approx(normal_stiffness / (MASS * (14 * OMEGA) ** 2), rel=1e-2)
    assert r.resolved == (normal_stiffness == 1e6)
    assert (r.ratio <= RESOLUTION_LIMIT) == r.resolved
    assert r.resolved_duration_s == pytest.approx(2 * np.pi / OMEGA / 28)
    assert (r.needed_harmonics() <= 14) == r.resolved        # H' ω ≥ ω_c / 2 where it would hold


def test_a_contact_that_never_opens_or_never_closes_has_no_impact():
    """A wall beyond the motion (never closed) or pressed into it (never open): no impact, ρ = 0,
    resolved — a linear spring or no force needs no resolution of a pulse."""
    for gap in (1e-2, -1e-2):
        model, contacts, F = oscillator(1e10)
        contacts = make_contact_set(np.eye(1), ["rattle"], [0], [[-1, -1]], gap=gap,
                                    normal_stiffness=1e10)
        solution = solve_frequency(model, contacts, F, OMEGA, 7, 256)
        assert solution.converged
        r = contact_resolution(solution, model, contacts, F, 14)
        assert r.ratio == 0.0 and r.resolved and r.contact is None


def test_hard_impact_gets_no_bound_and_is_far_off_the_time_integration():
    """k_n = 10¹⁰ N/m: the estimate withholds its bound (inf, with the impact's 14 µs against the
    595 µs H' = 14 resolves, in its note) — rightly: the H = 7 solution's first harmonic is
    > 10 % off the sub-stepped Newmark orbit (measured 12 %, the run's check at N = 256), while
    the change to H' is not even re-solvable (Newton at H' = 60 from it does not converge)."""
    model, contacts, F, solution = solved(1e10)
    estimate = estimate_errors(solution, model, contacts, F)
    assert estimate.amplitude_rel == np.inf and estimate.erp_db == np.inf
    assert estimate.contact_resolution["resolved"] is False
    assert "14 µs" in estimate.notes[0] and "595 µs" in estimate.notes[0]
    assert "contact_resolution" in estimate.as_dict()
    check = time_integration_error(solution, model, contacts, F, steps_per_period=256,
                                   periods=30)               # (the run's check, coarser here)
    assert check["amplitude_rel"] > 0.1 and check["harmonics"] == 32
    assert check["first_harmonic_rel"] == pytest.approx(check["contact_amplitude_rel"], rel=0.3)
    assert abs(check["contact_work_rel"][0]) < 1e-2          # the elastic impacts do no work


def test_soft_impact_keeps_its_bound_and_it_covers_the_true_error():
    """k_n = 10⁶ N/m (lumped_rattle's contact): resolved, the change-based estimate is kept
    (finite, no contact_resolution in its dict) and bounds the error of H = 7 against H = 60
    (measured 2.2 % against 1.1 %)."""
    model, contacts, F, solution = solved(1e6)
    estimate = estimate_errors(solution, model, contacts, F)
    assert np.isfinite(estimate.amplitude_rel) and "contact_resolution" not in estimate.as_dict()
    fine = solve_frequency(model, contacts, resize_harmonics(F, 60), OMEGA, 60, 4096,
                           initial=resize_harmonics(solution.displacement, 60))
    assert fine.converged
    a, b = first_harmonic(solution.displacement), first_harmonic(fine.displacement)
    assert abs(abs(a) - abs(b)) / abs(b) <= estimate.amplitude_rel
