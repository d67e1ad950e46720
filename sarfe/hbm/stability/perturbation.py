r"""Stability of a harmonic-balance orbit checked by time integration: do perturbations of the
orbit decay or grow over a period?

The period map P of the Newmark integrator (:mod:`sarfe.hbm.newmark`) takes the state
x = (u, u̇/ω, sliders) at θ = 0 to the state one period later. Starting from the HBM orbit's state,
Newton shooting finds the integrator's own periodic state x* = P(x*) (a few steps: the two orbits
differ only by the truncation and time-step errors), with the Jacobian Φ = ∂P/∂x by finite
differences (one perturbed period per state component). Φ is the monodromy matrix: a perturbation
δx of the orbit becomes Φ δx after one period, so the multipliers μ (eigenvalues of Φ) say whether
it returns to the orbit; the rate

    σ = max ln|μ| / T   [1/s]

is the time-integration estimate of the leading Floquet exponent (Re s₁). The verdict is stable when
σ ≤ ``tolerance`` · ω; a neutral direction — the stuck slider of a friction contact, whose offset
is a history constant — has |μ| = 1, σ = 0: stable in Lyapunov's sense. (Comparing two runs that
both start near the orbit is not enough: from an unstable orbit both leave for the same attractor
and their distance then decays.)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.hbm.harmonics import time_samples
from sarfe.hbm.newmark import ContactLaws, initial_sliders, march_periods, state_at_zero


@dataclass(frozen=True)
class PerturbationCheck:
    """multipliers μ (eigenvalues of the monodromy matrix, complex); rate σ [1/s] (estimate of
    max Re s); stable (bool); periods integrated; steps_per_period; periodicity: ‖P(x*) − x*‖
    relative to the orbit's amplitude after shooting."""

    multipliers: np.ndarray
    rate: float
    stable: bool
    periods: int
    steps_per_period: int
    periodicity: float


def perturbation_check(model, contacts, excitation, solution, steps_per_period=512,
                       newton_steps=3, size=1e-6, tolerance=2e-3, **_) -> PerturbationCheck:
    """Monodromy of the time integrator around the orbit of ``solution`` (module docstring).

    excitation F̃ (2H+1, n) [N] at solution.omega; size: relative finite-difference step;
    tolerance: σ/ω above which the orbit is called unstable."""
    omega = float(solution.omega)
    N = int(steps_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    n = U.shape[1]
    u0, v0 = state_at_zero(U, omega, N)
    law = ContactLaws(contacts) if contacts is not None and contacts.count else None
    force0 = np.asarray(solution.contact_force_time)[0] if law is not None else None
    slider0 = initial_sliders(law, contacts.gap_map @ u0, force0) if law is not None \
        else np.zeros((0, 2))
    forcing = time_samples(np.asarray(excitation, dtype=float), N)
    shape = slider0.shape
    runs = [0]

    def period(x):
        runs[0] += 1
        u, v, w = march_periods(model, contacts, forcing, omega, N, x[:n], omega * x[n:2 * n],
                                x[2 * n:].reshape(shape), 1, 0.0, False, None, 0)["final"]
        return np.concatenate((u, v / omega, w.ravel()))

    x = np.concatenate((u0, v0 / omega, slider0.ravel()))
    scale = max(np.abs(U).max(), 1e-300)
    step = size * scale
    for it in range(newton_steps + 1):
        image = period(x)
        Phi = np.empty((x.size, x.size))
        for j in range(x.size):
            e = x.copy()
            e[j] += step
            Phi[:, j] = (period(e) - image) / step
        defect = image - x
        if it == newton_steps or np.abs(defect).max() <= 1e-9 * scale:
            break
        x = x - np.linalg.lstsq(Phi - np.eye(x.size), defect, rcond=1e-10)[0]
    multipliers = np.linalg.eigvals(Phi)
    rate = float(np.log(np.maximum(np.abs(multipliers), 1e-300)).max() * omega / (2 * np.pi))
    return PerturbationCheck(multipliers, rate, bool(rate <= tolerance * omega), runs[0], N,
                             float(np.abs(defect).max() / scale))
