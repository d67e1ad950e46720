r"""Stability of a harmonic-balance orbit checked by time integration: does a small perturbation decay?

Two Newmark runs (:mod:`sarfe.hbm.time_integration`) start at θ = 0 on the orbit ũ of a
:class:`HarmonicSolution` — one from the orbit's state (u₀, u̇₀, sliders), one from the same state
plus a perturbation δx₀ (random direction, ‖δu₀‖ = ε max|ũ|, ‖δu̇₀‖ = ε ω max|ũ|). Comparing the two
runs period by period cancels the scheme's own discretization error; the distance

    d_k = ‖x_pert(kT) − x_ref(kT)‖,   x = (u, u̇/ω)

decays like e^{Re s₁ kT} on a stable orbit and grows on an unstable one (s₁ the leading Floquet
exponent) until the nonlinearity saturates it (the run leaves for another attractor). The linear
regime is the periods with d_k ≤ 30 d_0; the measured rate σ = ln(d_K / d_{K₀}) / ((K − K₀) T)
[1/s] over its second half is an estimate of Re s₁ from time integration. The verdict is unstable
when d grew past 100 d_0 (the run stops there) or σ > ``tolerance`` · ω (a neutral direction — the
stuck slider of a friction contact, whose offset is a history constant — keeps d_k bounded: σ ≈ 0,
stable in Lyapunov's sense).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .time_integration import _ContactLaws, _run, _slider_from_initial, _state_at_zero
from .harmonics import time_samples


@dataclass(frozen=True)
class PerturbationCheck:
    """distance (periods+1,) d_k [m]; rate σ [1/s] (estimate of max Re s); stable (bool);
    periods integrated; steps_per_period."""

    distance: np.ndarray
    rate: float
    stable: bool
    periods: int
    steps_per_period: int


def perturbation_check(model, contacts, excitation, solution, periods=30, steps_per_period=512,
                       size=1e-4, tolerance=2e-3, seed=0) -> PerturbationCheck:
    """Integrate the orbit of ``solution`` and a perturbed copy for ``periods`` periods (see module
    docstring). excitation F̃ (2H+1, n) [N] at solution.omega; size ε [-] relative perturbation;
    tolerance: σ/ω above which the orbit is called unstable (σ/ω = 2e-3 ≈ growth by 1.3 % per
    period)."""
    omega = float(solution.omega)
    N = int(steps_per_period)
    U = np.asarray(solution.displacement, dtype=float)
    n = U.shape[1]
    u0, v0 = _state_at_zero(U, omega, N)
    law = _ContactLaws(contacts) if contacts is not None and contacts.count else None
    force0 = np.asarray(solution.contact_force_time)[0] if law is not None else None
    slider0 = _slider_from_initial(law, contacts.gap_map @ u0, force0) if law is not None \
        else np.zeros((0, 2))
    scale = max(np.abs(U).max(), 1e-300)
    rng = np.random.default_rng(seed)
    du, dv = rng.standard_normal(n), rng.standard_normal(n)
    du *= size * scale / np.linalg.norm(du)
    dv *= size * scale * omega / np.linalg.norm(dv)
    forcing = time_samples(np.asarray(excitation, dtype=float), N)
    states = [(u0, v0, slider0), (u0 + du, v0 + dv, slider0.copy())]
    distance = [np.sqrt(np.sum(du ** 2) + np.sum((dv / omega) ** 2))]
    for _ in range(int(periods)):
        states = [_run(model, contacts, forcing, omega, N, u, v, w, 1, 0.0, False, None, 0)["final"]
                  for u, v, w in states]
        (ua, va, _), (ub, vb, _) = states
        distance.append(np.sqrt(np.sum((ua - ub) ** 2) + np.sum(((va - vb) / omega) ** 2)))
        if distance[-1] > 100.0 * distance[0]:
            break
    d = np.maximum(np.asarray(distance), 1e-300)
    linear = np.flatnonzero(d > 30.0 * d[0])
    end = int(linear[0]) if linear.size else len(d) - 1
    end = max(end, 2)
    start = end // 2
    period = 2 * np.pi / omega
    rate = float(np.log(d[end] / d[start]) / ((end - start) * period))
    grew = bool(d.max() > 100.0 * d[0])
    stable = not grew and rate <= tolerance * omega
    return PerturbationCheck(d, rate, stable, len(d) - 1, N)
