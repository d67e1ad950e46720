"""Harmonic balance vs the independent time integrator on lumped rattle and squeak models.

The time-integration reference is Newmark with 1024 steps per period, Richardson-extrapolated
with 2048 (first-harmonic error ≲ 1e-6), started from the H = 30 HBM solution (the run still has to
settle on its own attractor: only decaying transients are extrapolated). The HBM error of the
first harmonic (complex amplitude, all DOFs) must fall below 0.5 % at H = 15 and keep falling to
H = 30 (AFT with N = 2048 samples so sampling error stays below the truncation error).
"""
import numpy as np
import pytest
import scipy.sparse as sp

import sarfe.hbm
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.time_integration import integrate_time

needs_engine = pytest.mark.skipif(not hasattr(sarfe.hbm, "solve_frequency"),
                                  reason="HBM engine (sarfe.hbm.solve_frequency) not available")


def rattle_model(harmonics):
    """2-DOF chain (1 kg – 0.5 kg; 10.5 / 34 Hz) whose tip hits ground across a 1 mm gap.

    k_n = 2e4 N/m, 40 N at 10 Hz on the first mass: the contact closes ~23 % of the period, the
    periodic solution is stable (Hill). Returns (model, contacts, excitation, omega).
    """
    M = np.diag([1.0, 0.5])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    model = make_linear_model(M, 2e-4 * K + 5.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix([[0.0, 1.0]]), ["rattle"], [0], [[-1, -1]],
                                gap=1e-3, normal_stiffness=2e4)
    F = np.zeros((2 * harmonics + 1, 2))
    F[1, 0] = 40.0
    return model, contacts, F, 2 * np.pi * 10.0


def squeak_model(harmonics):
    """3 DOF: driven mass x0 – spring – part with tangential DOF x1 and normal DOF x2.

    The part rubs on ground: Jenkins element k_t = 3e4 N/m, μ = 0.4, normal penalty k_n = 4e4 N/m
    with 0.2 mm overclosure plus N0 = 2 N; the normal DOF is shaken too (1st and 2nd harmonic), so
    the slip limit μ λ_n varies over the period. 12 Hz: stick–slip, stable.
    """
    M = np.diag([1.0, 0.3, 0.3])
    K = np.array([[2e4, -1e4, 0.0], [-1e4, 1e4, 0.0], [0.0, 0.0, 2e4]])
    model = make_linear_model(M, 2e-4 * K + 2.0 * M, K)
    G = sp.csr_matrix([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
    contacts = make_contact_set(G, ["squeak"], [0], [[1, -1]], gap=-2e-4, normal_stiffness=4e4,
                                tangential_stiffness=3e4, friction_coefficient=0.4,
                                normal_load=2.0)
    F = np.zeros((2 * harmonics + 1, 3))
    F[1, 0], F[1, 2], F[2, 2] = 15.0, 3.0, 1.0
    return model, contacts, F, 2 * np.pi * 12.0


MODELS = {"rattle": rattle_model, "squeak": squeak_model}
HBM_SAMPLES = 2048


def first_harmonic(U):
    """Complex first-harmonic amplitude per DOF, u_1c − i u_1s."""
    return U[1] - 1j * U[2]


def relative_error(U, reference):
    a, b = first_harmonic(U), first_harmonic(reference)
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.fixture(scope="module", params=sorted(MODELS))
def study(request):
    build = MODELS[request.param]
    solutions = {}
    for H in (5, 15, 30):
        model, contacts, F, omega = build(H)
        solutions[H] = sarfe.hbm.solve_frequency(model, contacts, F, omega, H, HBM_SAMPLES)
    model, contacts, F, omega = build(30)
    reference = integrate_time(model, contacts, F, omega, 30, steps_per_period=1024,
                               richardson=True, initial=solutions[30])
    return request.param, solutions, reference


@needs_engine
def test_first_harmonic_converges_with_harmonics(study):
    name, solutions, reference = study
    assert reference.steady, name
    assert all(s.converged for s in solutions.values())
    assert solutions[30].stable is not False          # a stable orbit is what time integration sees
    errors = {H: relative_error(s.displacement, reference.displacement_harmonics)
              for H, s in solutions.items()}
    assert errors[15] < 5e-3, errors                   # the 0.5 % requirement …
    assert errors[15] < 1e-4, errors                   # … is met with a wide margin
    assert errors[15] < 0.1 * errors[5], errors
    assert errors[30] < 0.5 * errors[15], errors


@needs_engine
def test_contact_states_and_forces_agree(study):
    name, solutions, reference = study
    hbm = solutions[30]
    # fraction of the period closed (rattle) / slipping (squeak)
    for state in (1, 2):
        assert np.mean(hbm.contact_state == state) == pytest.approx(
            np.mean(reference.contact_state == state), abs=0.01)
    L_hbm, L_ref = np.asarray(hbm.contact_force), reference.contact_force_harmonics
    assert np.abs(L_hbm[:3] - L_ref[:3]).max() < 1e-3 * np.abs(L_ref[:3]).max()


def test_time_integration_from_rest_finds_the_same_orbit():
    """Without the HBM start (linear periodic start), the integrator settles on the same orbit."""
    model, contacts, F, omega = rattle_model(15)
    coarse = integrate_time(model, contacts, F, omega, 15, steps_per_period=256)
    fine = integrate_time(model, contacts, F, omega, 15, steps_per_period=512,
                          initial=coarse.displacement_harmonics)
    assert coarse.steady and fine.steady
    # O(h²): the 256 → 512 change is ~4/3 of the 256-step error, well below 0.1 %
    assert relative_error(coarse.displacement_harmonics, fine.displacement_harmonics) < 1e-3


def chain_model(harmonics, n=8):
    """n-DOF spring–mass chain (fixed–free) with 3 rattle stops and 2 friction contacts (one with
    two tangential directions via a pair of DOFs), shaken at the first mass near mode 1."""
    mass = np.full(n, 0.2)
    k = 4e4
    K = np.diag(np.full(n, 2 * k)) - np.diag(np.full(n - 1, k), 1) - np.diag(np.full(n - 1, k), -1)
    K[-1, -1] = k
    M = np.diag(mass)
    model = make_linear_model(M, 1e-4 * K + 6.0 * M, K)
    rows = []
    for dof in (n - 1, n - 4, n // 2):                     # rattle stops
        rows.append(np.eye(n)[dof])
    rows += [np.eye(n)[n - 2], np.eye(n)[3], np.eye(n)[5] - 0.5 * np.eye(n)[6]]
    G = sp.csr_matrix(np.array(rows))
    contacts = make_contact_set(
        G, ["rattle", "rattle", "rattle", "squeak", "squeak"], [0, 1, 2, -1, -1],
        [[-1, -1], [-1, -1], [-1, -1], [3, -1], [4, 5]], gap=[2e-3, 1.5e-3, 1e-3, 0, 0],
        normal_stiffness=[5e4, 5e4, 5e4, 0, 0], tangential_stiffness=[0, 0, 0, 2e4, 2e4],
        friction_coefficient=[0, 0, 0, 0.5, 0.5], normal_load=[0, 0, 0, 4.0, 3.0])
    F = np.zeros((2 * harmonics + 1, n))
    F[1, 0] = 60.0
    omega = 2 * np.pi * 0.9 * np.sqrt(np.linalg.eigvalsh(np.linalg.solve(M, K))[0]) / (2 * np.pi)
    return model, contacts, F, omega


@needs_engine
@pytest.mark.slow
def test_chain_with_several_contacts():
    """8-DOF chain, 3 rattle stops + 1-D and 2-D friction: H = 15 within 0.1 %, H = 30 closer."""
    solutions = {}
    for H in (15, 30):
        model, contacts, F, omega = chain_model(H)
        solutions[H] = sarfe.hbm.solve_frequency(model, contacts, F, omega, H, 1024)
        assert solutions[H].converged
    reference = integrate_time(model, contacts, F, omega, 30, steps_per_period=1024,
                               richardson=True, initial=solutions[30])
    assert reference.steady
    errors = {H: relative_error(s.displacement, reference.displacement_harmonics)
              for H, s in solutions.items()}
    assert errors[15] < 1e-3 and errors[30] < 0.5 * errors[15], errors
    assert np.all(reference.contact_work[3:] > 0)           # both friction contacts dissipate
