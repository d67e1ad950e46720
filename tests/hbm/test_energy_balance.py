"""The AFT's error in the work of a penalty contact (sarfe.hbm.energy_balance).

A penalty contact is conservative: over any closed period ∮ λ dw = 0 exactly. Sampled at N points
its work is not zero: the kink of λ(w) at the gap falls between samples, an error that shrinks as N
grows and is proportional to k_n X² at amplitudes X ≫ gap (the force is homogeneous there). Where
the damping is light this error is of the size of the damping's work, which sets the peak: the
measure :func:`energy_error` must show it at coarse N and not at fine N.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sarfe.hbm.aft import contact_forces
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.energy_balance import energy_error
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.time_integration import period_work

H = 7
GAP, K_N = 1e-4, 1e6


def rattle():
    """One grounded rattle row, gap 0.1 mm, k_n = 10⁶ N/m (as cases/lumped_rattle.yaml)."""
    return make_contact_set(sp.csr_matrix([[1.0]]), ["rattle"], [0], [[-1, -1]], gap=GAP,
                            normal_stiffness=K_N)


def orbit(X):
    """r(θ) = X cos θ + 0.3 X cos 2θ + 0.1 X sin 3θ (2H+1, 1) [m]: an orbit through the gap."""
    R = np.zeros((2 * H + 1, 1))
    R[1, 0], R[3, 0], R[6, 0] = X, 0.3 * X, 0.1 * X
    return R


def contact_work(R, N):
    force = contact_forces(rattle(), R, N, jacobian=False).force
    return float(np.sum(period_work(R, np.zeros((1, 1)), np.zeros((1, 1)), R, force, 1.0)[2])), \
        force


def test_sampled_penalty_work_vanishes_with_finer_sampling_and_scales_with_amplitude_squared():
    """The sampled ∮ λ dw falls from N = 256 to 16384 by more than 100× (0 in continuous time),
    and at X = 1, 10 m (≫ gap) it scales as X² within 1 % (homogeneous force)."""
    elastic = 0.5 * K_N * 1e-2**2               # the contact's peak elastic energy at X = 1 cm [J]
    coarse = abs(contact_work(orbit(1e-2), 256)[0])
    fine = abs(contact_work(orbit(1e-2), 16384)[0])
    assert coarse > 1e-5 * elastic              # an error a light damping notices (ζ ~ 1e-4)
    assert fine < 1e-2 * coarse
    w1, w10 = contact_work(orbit(1.0), 256)[0], contact_work(orbit(10.0), 256)[0]
    assert abs(w10 / w1 / 100.0 - 1.0) < 1e-2


def test_energy_error_flags_coarse_sampling_against_light_damping_only():
    """A 1-DOF oscillator (1 kg, 10⁴ N/m) on that contact, moving on the orbit at ω = 500 rad/s:
    with ζ = 10⁻⁴ the work error of N = 256 is a large share of the damping's work, with ζ = 0.03
    it is 300× smaller, and doubling 4096 → 8192 leaves a small share even with ζ = 10⁻⁴."""
    R = orbit(1e-2)
    shares = {}
    for zeta in (1e-4, 3e-2):
        model = make_linear_model([[1.0]], [[2 * zeta * 100.0]], [[1e4]])
        for N in (256, 4096):
            force, force_fine = contact_work(R, N)[1], contact_work(R, 2 * N)[1]
            shares[zeta, N] = energy_error(model, sp.csr_matrix([[1.0]]), R, 500.0, force,
                                           force_fine)
    assert shares[1e-4, 256] > 0.2
    assert shares[3e-2, 256] < shares[1e-4, 256] / 100
    assert shares[1e-4, 4096] < 0.05
