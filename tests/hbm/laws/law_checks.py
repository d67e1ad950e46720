"""Finite-difference checks of a contact law through the one interface (AFT and time step).

Used by the per-law tests: central differences of λ̃(r̃, ω) against the analytic ∂λ̃/∂r̃ (with its
velocity part ω E diag(∂λ/∂ṙ) Φ ∇), ∂λ̃/∂ω and Hill's damping blocks, and of the time integrator's
λ(r₊, ṙ₊(r₊)) against ∂λ/∂r + (2/h) ∂λ/∂ṙ.
"""
import numpy as np

from sarfe.hbm import harmonics as hm
from sarfe.hbm.aft import contact_forces, jacobian_matrix
from sarfe.hbm.newmark import ContactLaws


def aft_errors(contacts, R, N, omega, slider_start=None, step=1e-7):
    """(relative error of ∂λ̃/∂r̃, of ∂λ̃/∂ω, of the damping blocks ⋅ ∇r̃ vs ∂λ̃/∂ω) by central
    differences; R (2H+1, n_rows) [m]."""
    H = (R.shape[0] - 1) // 2
    n_rows = R.shape[1]
    if slider_start is None:
        slider_start = contact_forces(contacts, R, N, omega=omega).slider_end

    def force(X, w=omega):
        return contact_forces(contacts, X.reshape(R.shape), N, slider_start, jacobian=False,
                              omega=w).force.ravel()

    ev = contact_forces(contacts, R, N, slider_start, omega=omega)
    J = jacobian_matrix(ev.blocks, n_rows, H, dense=True)
    x = R.ravel()
    scale = step * max(np.abs(x).max(), 1e-12)
    fd = np.empty_like(J)
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = scale
        fd[:, i] = (force(x + e) - force(x - e)) / (2 * scale)
    jac_error = np.abs(J - fd).max() / max(np.abs(fd).max(), 1e-300)
    d_omega = (force(x, omega * (1 + step)) - force(x, omega * (1 - step))) / (2 * omega * step)
    analytic = np.zeros(x.size) if ev.omega_derivative is None else ev.omega_derivative.ravel()
    omega_error = np.abs(analytic - d_omega).max() / max(np.abs(d_omega).max(), np.abs(J).max()
                                                          * np.abs(x).max(), 1e-300)
    damping_error = 0.0
    if ev.damping_blocks:
        D = jacobian_matrix(ev.damping_blocks, n_rows, H, dense=True)
        slope = (hm.derivative_matrix(H) @ R).ravel()
        damping_error = np.abs(D @ slope - analytic).max() / max(np.abs(analytic).max(), 1e-300)
    return jac_error, omega_error, damping_error


def step_error(contacts, r, r_start, rdot_start, slider_previous, h, step=1e-7):
    """Relative error of the time step's ∂λ/∂r₊ + (2/h)∂λ/∂ṙ₊ against central differences of
    λ(r₊, ṙ₊(r₊)), ṙ₊ = (2/h)(r₊ − r) − ṙ."""
    laws = ContactLaws(contacts)
    rate = 2.0 / h

    def force(x):
        rdot = rate * (x - r_start) - rdot_start if laws.velocity else None
        return laws.forces(x, rdot, slider_previous)[0]

    force(r)
    J = laws.jacobian(rate)
    scale = step * max(np.abs(r).max(), 1e-12)
    fd = np.empty_like(J)
    for i in range(r.size):
        e = np.zeros_like(r)
        e[i] = scale
        fd[:, i] = (force(r + e) - force(r - e)) / (2 * scale)
    return np.abs(J - fd).max() / max(np.abs(fd).max(), 1e-300)
