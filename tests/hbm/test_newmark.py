"""The Newmark march (sarfe.hbm.newmark) on its own: the scheme's discrete periodic orbit of a
linear model is a fixed point of one period, and the slider start reproduces a given stuck force."""
import numpy as np
import pytest

from sarfe.hbm import newmark
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.laws.jenkins import STICK
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.newmark import (ContactLaws, initial_sliders, march_periods, state_at_zero,
                               warped_frequency)
from sarfe.hbm.time_integration import integrate_time


def two_dof():
    M = np.diag([1.0, 0.5])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    return make_linear_model(M, 2e-4 * K + 5.0 * M, K)


def discrete_orbit(model, F, omega, N):
    """Û_k = (K − ω'_k² M + iω'_k D)⁻¹ F̂_k at the bilinear-transform frequencies
    ω'_k = (2/h) tan(kωh/2), h = 2π/(ωN), written out here (not the package's solver)."""
    M, D, K = (np.asarray(x) for x in (model.mass, model.damping, model.stiffness))
    h = 2 * np.pi / (omega * N)
    U = np.zeros_like(F)
    U[0] = np.linalg.solve(K, F[0])
    for k in range(1, (F.shape[0] - 1) // 2 + 1):
        w = 2 / h * np.tan(k * omega * h / 2)
        Uk = np.linalg.solve(K - w * w * M + 1j * w * D, F[2 * k - 1] - 1j * F[2 * k])
        U[2 * k - 1], U[2 * k] = Uk.real, -Uk.imag
    return U


def test_warped_frequency_is_the_bilinear_transform():
    omega, N = 2 * np.pi * 9.0, 64
    h = 2 * np.pi / (omega * N)
    assert warped_frequency(3 * omega, omega, N) == pytest.approx(2 / h * np.tan(1.5 * omega * h),
                                                                  rel=1e-15)
    assert warped_frequency(3 * omega, omega, None) == 3 * omega
    assert warped_frequency(0.0, omega, N) == 0.0


@pytest.mark.parametrize("N", [32, 256])
def test_discrete_linear_orbit_is_a_fixed_point_of_one_period(N):
    """M ü + D u̇ + K u = f_e(t) with a static load and three harmonics: started from the discrete
    periodic orbit (state_at_zero), one period of the march returns to the start state and its
    samples are the orbit's, to round-off — at any N (the scheme is exact at ω'_k)."""
    model = two_dof()
    H = 3
    F = np.zeros((2 * H + 1, 2))
    F[0] = [5.0, -2.0]
    F[1, 0], F[2, 1], F[5, 0] = 10.0, 4.0, 3.0
    omega = 2 * np.pi * 9.0
    U = discrete_orbit(model, F, omega, N)
    u0, v0 = state_at_zero(U, omega, N)
    run = march_periods(model, None, time_samples(F, N), omega, N, u0, v0, np.zeros((0, 2)), 1,
                        0.0, False, None, 0)
    u_end, v_end, _ = run["final"]
    scale = np.abs(U).max()
    assert np.abs(u_end - u0).max() < 1e-10 * scale
    assert np.abs(v_end - v0).max() < 1e-10 * scale * omega
    assert np.abs(run["u"] - time_samples(U, N)).max() < 1e-10 * scale
    assert run["periods"] == 1


def test_initial_sliders_reproduce_a_stuck_tangential_force():
    """w = q − λ_t/k_t: the Jenkins element's force at the start state is the given force when it
    lies inside the Coulomb disk (|λ_t| < μ N0)."""
    k_t, mu, n0 = 3e4, 0.5, 100.0
    G = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    contacts = make_contact_set(G, ["squeak"], [-1], [[0, 1]], gap=0.0, normal_stiffness=0.0,
                                tangential_stiffness=k_t, friction_coefficient=mu, normal_load=n0)
    law = ContactLaws(contacts)
    r0 = np.array([2e-3, -1e-3])                   # tangential displacements q [m]
    force = np.array([12.0, -30.0])                # |λ_t| = 32.3 N < μ N0 = 50 N
    slider = initial_sliders(law, r0, force)
    assert slider.shape == (1, 2)
    assert np.allclose(slider[0], r0 - force / k_t, rtol=1e-14, atol=1e-18)
    lam, _, state = law.forces(r0, None, slider)
    assert np.allclose(lam, force, rtol=1e-12)
    assert state[0] == STICK
    unloaded = initial_sliders(law, r0, None)       # no force given: unloaded springs, w = q
    assert np.allclose(unloaded[0], r0)



def impact_oscillator():
    """0.2 kg on 2·10⁴ N/m (50 Hz, ζ = 3 %) against a wall 0.1 mm away, k_n = 10¹⁰ N/m: contact
    frequency ω_c = 2.2·10⁵ rad/s, an impact lasts π/ω_c = 14 µs (the lumped rattle's panel with
    the hard contact of issue 29)."""
    m, k = 0.2, 2e4
    model = make_linear_model(np.eye(1) * m, np.eye(1) * 0.06 * np.sqrt(k * m), np.eye(1) * k)
    contacts = make_contact_set(np.eye(1), ["rattle"], [0], [[-1, -1]], gap=1e-4,
                                normal_stiffness=1e10)
    return model, contacts


def test_stiff_impacts_do_no_net_work_and_converge_in_the_step(monkeypatch):
    """Driven at 60 Hz with 2 N, N = 256 steps per period (ω_c h = 14). An elastic contact does no
    net work over a period (∮ λ dr = 0), so input = viscous work: with the impact steps sub-stepped
    the contact's work is < 1 % of the input and the first harmonic agrees with N = 1024 to 0.5 %.
    The plain trapezoidal rule (no sub-steps) gains energy at every impact and grows without
    bound (measured: |u₁| ~ 10³⁵ m at N = 256, 0.24 mm at N = 1024 where it is 0.1 mm)."""
    model, contacts = impact_oscillator()
    F = np.zeros((3, 1))
    F[1, 0] = 2.0
    omega = 2 * np.pi * 60.0
    runs = {N: integrate_time(model, contacts, F, omega, 3, steps_per_period=N, max_periods=30)
            for N in (256, 1024)}
    first = {N: r.displacement_harmonics[1, 0] - 1j * r.displacement_harmonics[2, 0]
             for N, r in runs.items()}
    free = 2.0 / abs(2e4 - 0.2 * omega**2 + 1j * omega * 0.06 * np.sqrt(2e4 * 0.2))
    assert abs(first[1024]) < 0.5 * free                     # the wall holds it (free: 0.23 mm)
    assert abs(first[256] - first[1024]) < 5e-3 * abs(first[1024])
    for r in runs.values():
        assert abs(r.contact_work[0]) < 1e-2 * r.input_work
        assert r.substepped_steps >= 1                       # the impact's step(s)
    monkeypatch.setattr(newmark, "SUBSTEP_RESOLUTION", np.inf)   # the plain rule
    plain = integrate_time(model, contacts, F, omega, 3, steps_per_period=256, max_periods=30)
    assert abs(plain.contact_work[0]) > 0.1 * plain.input_work and plain.substepped_steps == 0
