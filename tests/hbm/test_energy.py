"""Energy balance per period of a friction (squeak) contact, from HBM harmonics and time samples.

Periodic steady state:   ∮ f_eᵀ u̇ dt  =  ∮ u̇ᵀ D u̇ dt  +  ∮ λ_t dq  (+ ∮ λ_n dw = 0, elastic),
input work of the excitation = viscous losses + work dissipated by the Jenkins slider.
"""
import importlib.util
import pathlib

import numpy as np
import pytest

import sarfe.hbm
from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.time_integration import integrate_time, period_work

_spec = importlib.util.spec_from_file_location(
    "hbm_vs_time_models", pathlib.Path(__file__).with_name("test_hbm_vs_time.py"))
_models = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_models)
squeak_model = _models.squeak_model

needs_engine = pytest.mark.skipif(not hasattr(sarfe.hbm, "solve_frequency"),
                                  reason="HBM engine (sarfe.hbm.solve_frequency) not available")
H = 15
NORMAL_ROW, TANGENT_ROW = 0, 1


def loop_area(force, displacement):
    """∮ λ dq over one sampled period by the trapezoid rule on the closed hysteresis loop."""
    dq = np.roll(displacement, -1) - displacement
    return float(np.sum(0.5 * (force + np.roll(force, -1)) * dq))


@pytest.fixture(scope="module")
def hbm_solution():
    model, contacts, F, omega = squeak_model(H)
    solution = sarfe.hbm.solve_frequency(model, contacts, F, omega, H, 2048)
    assert solution.converged
    return model, contacts, F, omega, solution


@pytest.fixture(scope="module")
def time_response():
    model, contacts, F, omega = squeak_model(H)
    response = integrate_time(model, contacts, F, omega, H, steps_per_period=256)
    assert response.steady
    return model, contacts, F, omega, response


@needs_engine
def test_hbm_friction_dissipation_balances_input_minus_viscous(hbm_solution):
    model, contacts, F, omega, s = hbm_solution
    D = np.asarray(model.damping)
    input_work, viscous, contact = period_work(s.displacement, F, D, s.contact_displacement,
                                               s.contact_force, omega)
    friction = contact[TANGENT_ROW]
    assert input_work > 0 and viscous > 0 and friction > 0
    assert friction == pytest.approx(input_work - viscous, rel=5e-3)
    assert abs(contact[NORMAL_ROW]) < 1e-3 * input_work       # the penalty spring is elastic
    # the same dissipation as the area of the sampled hysteresis loop λ_t(q)
    q = time_samples(np.asarray(s.contact_displacement)[:, TANGENT_ROW], s.samples_per_period)
    area = loop_area(np.asarray(s.contact_force_time)[:, TANGENT_ROW], q)
    assert area == pytest.approx(friction, rel=5e-3)
    # friction takes a real share of the input here (not a trivially small term)
    assert friction > 0.2 * input_work


def test_time_integration_energy_balance_from_samples(time_response):
    model, contacts, F, omega, r = time_response
    N = r.steps_per_period
    h = 2 * np.pi / omega / N
    D = np.asarray(model.damping)
    velocity = r.velocity                               # all DOFs kept (output_dofs default)
    force = time_samples(F, N)
    input_work = h * np.sum(force * velocity)
    viscous = h * np.einsum("ji,ik,jk->", velocity, D, velocity)
    friction = loop_area(r.contact_force[:, TANGENT_ROW], r.contact_displacement[:, TANGENT_ROW])
    normal = loop_area(r.contact_force[:, NORMAL_ROW], r.contact_displacement[:, NORMAL_ROW])
    assert friction == pytest.approx(input_work - viscous, rel=5e-3)
    assert abs(normal) < 1e-3 * input_work
    # the integrator's own (discrete-identity) works agree with the sample integrals
    assert r.input_work == pytest.approx(input_work, rel=5e-3)
    assert r.damping_work == pytest.approx(viscous, rel=5e-3)
    assert r.contact_work[0] == pytest.approx(friction + normal, rel=5e-3)
    assert r.input_work - r.damping_work - r.contact_work.sum() == pytest.approx(
        0.0, abs=1e-5 * r.input_work)


@needs_engine
def test_hbm_and_time_integration_dissipate_the_same(hbm_solution, time_response):
    *_, s = hbm_solution
    *_, r = time_response
    q = time_samples(np.asarray(s.contact_displacement)[:, TANGENT_ROW], s.samples_per_period)
    hbm = loop_area(np.asarray(s.contact_force_time)[:, TANGENT_ROW], q)
    tim = loop_area(r.contact_force[:, TANGENT_ROW], r.contact_displacement[:, TANGENT_ROW])
    assert hbm == pytest.approx(tim, rel=5e-3)
