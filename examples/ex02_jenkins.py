r"""Example 2 — the 1-DOF Jenkins oscillator: a mass held by a spring and a stick-slip friction element.

Physics (SI units):

    m ü + c u̇ + k u + λ(t) = F cos Ωt,   m = k = 1,  c = 0.02,  F = 0.5,
    λ: a Jenkins element — a spring k_t = 1 in series with a Coulomb slider of limit μN₀ = 1:
       λ = k_t (u − s), the slider s moves only while |λ| = μN₀ (stick ⇄ slip).

Without friction the oscillator resonates at Ω = 1 (k = 1); while the element sticks it adds k_t,
so small motion resonates at Ω = √2; once the force exceeds μN₀ the slider slips, the stiffness
falls back towards k and the slip dissipates energy. The resonance peak lies between: Ω ≈ 1.29.
Harmonic balance with H = 7, N = 256 traced from Ω = 0.5 to 2.0 (the slider's exact periodic
march inside the alternating frequency/time evaluation).

The number: the peak first-harmonic amplitude |û₁| [m] and the Ω [rad/s] where the sweep passes it;
the peer code pyHarm (pyharm-os 1.2.2, its Jenkins element, same H and N) gives 1.57224 at
Ω = 1.29366. An independent check: Newmark time integration of the same equation at that Ω
(:func:`sarfe.hbm.time_integration.integrate_time`, run to its periodic steady state), whose first
harmonic is compared with the harmonic-balance point at the same Ω.
"""
import numpy as np
import scipy.sparse as sp

from sarfe.hbm import (ContinuationOptions, SolverOptions, continuation, make_contact_set,
                       make_linear_model, solve_frequency)
from sarfe.hbm.time_integration import integrate_time

H, N = 7, 256


def oscillator():
    """(model, contacts, force harmonics (2H+1, 1)) of the Jenkins oscillator."""
    model = make_linear_model([[1.0]], [[0.02]], [[1.0]])
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["squeak"], [-1], [[0, -1]], gap=0.0,
                                normal_stiffness=0.0, tangential_stiffness=1.0,
                                friction_coefficient=1.0, normal_load=1.0)   # μN₀ = 1, no normal row
    force = np.zeros((2 * H + 1, 1))
    force[1, 0] = 0.5
    return model, contacts, force


def peak() -> tuple[float, float]:
    """(peak |û₁| [m], Ω at the peak [rad/s]) of the sweep Ω 0.5 → 2.0."""
    model, contacts, force = oscillator()
    points = continuation(model, contacts, force, 0.5, 2.0, H, N,
                          options=ContinuationOptions(solver=SolverOptions(stability=False)))
    amplitude = np.array([p.amplitude(0) for p in points])
    top = int(np.argmax(amplitude))
    return float(amplitude[top]), float(points[top].omega)


def against_time_integration(omega: float, steps_per_period=1024) -> tuple[float, float]:
    """(|û₁| by harmonic balance, |û₁| by time integration) at Ω = omega [rad/s]."""
    model, contacts, force = oscillator()
    hbm = solve_frequency(model, contacts, force, omega, H, N, options=SolverOptions(stability=False))
    time = integrate_time(model, contacts, force, omega, H, steps_per_period=steps_per_period)
    u = np.asarray(time.displacement_harmonics)
    return hbm.amplitude(0), float(np.hypot(u[1, 0], u[2, 0]))


if __name__ == "__main__":
    a, omega = peak()
    print(f"peak |û₁| = {a:.5f} at Ω = {omega:.5f} (pyHarm 1.57224 at 1.29366)")
    hbm, time = against_time_integration(omega)
    print(f"at that Ω: harmonic balance {hbm:.5f}, time integration {time:.5f}")
