r"""Is the energy balance of a periodic solution resolved by its AFT sampling?

Over one period T = 2π/ω a harmonic balance solution satisfies (Galerkin: the residual is
orthogonal to u̇; :func:`sarfe.hbm.time_integration.period_work`)

    W_in = W_d + W_c,   W_d = ∮ u̇ᵀ D u̇ dt ≥ 0,   W_c = ∮ λᵀ ṙ dt   [J]

In continuous time a penalty contact is conservative (W_c = 0) and a friction contact dissipates
(W_c > 0). The AFT samples λ(r(θ_j)) at N points, and its W_c carries an error that grows like
k_n ‖r̃‖² / N² (the kink of the force falls between samples). Where the damping is light this error
can outweigh W_d and set the response: with modal ζ = 10⁻⁴ on cases/lumped_rattle.yaml at
N = 256 the sampled rattle contact put in −W_c = 30.3 J per period at 0.83 m (79.476 Hz), balancing
W_d = 30.4 J, so the branch climbed a resonance of metres that finer sampling does not have
(W_c = −5.2, +2.6, −0.11, +0.016 J at N = 512, 1024, 4096, 16384). :func:`energy_error` measures
it; :mod:`sarfe.hbm.continuation` raises N by it.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.time_integration import period_work


def energy_error(model, gap_map, U, omega, force, force_fine):
    """|W_c(N) − W_c(2N)| / (W_d + |W_c(2N)|): the change of the contacts' work per period when
    the AFT sampling is doubled, as a share of what the damping and the (finer) contacts dissipate,
    the energy balance that sets a lightly damped peak. model: LinearModel (its D); U (2H+1, n) [m]
    on all DOFs; ω [rad/s]; force, force_fine: λ̃ (2H+1, n_rows) [N] with N and 2N samples;
    gap_map G (n_rows, n). 0 where nothing dissipates."""
    U = np.asarray(U, dtype=float)
    R = np.asarray(gap_map @ U.T).T
    none = np.zeros((1, U.shape[1]))
    _, viscous, coarse = period_work(U, none, model.damping, R, force, omega)
    _, _, fine = period_work(U, none, model.damping, R, force_fine, omega)
    coarse, fine = float(np.sum(coarse)), float(np.sum(fine))
    dissipated = viscous + abs(fine)
    return abs(coarse - fine) / dissipated if dissipated > 0 else 0.0
