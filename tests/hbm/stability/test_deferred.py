"""Deferred Hill stability (sarfe.hbm.stability.deferred): a sweep with the stability recorded instead of
computed is the same sweep (stability feeds nothing back into the continuation), and each recorded
job computed afterwards gives the in-place verdict and leading exponent — on both sides of a fold of
a damped-impact chain, where the middle branch is unstable."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm import continuation, make_contact_set, make_linear_model
from sarfe.hbm.stability.deferred import deferred_stability, pending, stability_of, with_stability


def chain(harmonics):
    """2-DOF chain (1 kg – 0.5 kg, 10.5 / 34 Hz), its tip against a damped stop 1 mm away
    (k = 2e4 N/m, e = 0.8), 60 N on the first mass: the resonance folds over near 9.7 Hz."""
    M = np.diag([1.0, 0.5])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    model = make_linear_model(M, 2e-4 * K + 5.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix([[0.0, 1.0]]), ["damped_impact"], [0],
                                [[-1, -1]], 1e-3, parameters=dict(
                                    normal_stiffness=2e4, restitution=0.8, effective_mass=0.5))
    F = np.zeros((2 * harmonics + 1, 2))
    F[1, 0] = 60.0
    return model, contacts, F


def test_deferred_stability_is_the_in_place_stability():
    H, N = 5, 256
    model, contacts, F = chain(H)
    band = (2 * np.pi * 9.3, 2 * np.pi * 10.2)
    in_place = continuation(model, contacts, F, *band, H, N)
    with deferred_stability() as jobs:
        deferred = continuation(model, contacts, F, *band, H, N)
    assert len(deferred) == len(in_place) > 5
    assert all(s.stable is None and s.stability_job is not None for s in deferred if s.converged)
    indices = pending(deferred)
    filled = with_stability(deferred, indices, [stability_of(jobs[i]) for i in indices])
    verdicts = [s.stable for s in in_place]
    assert True in verdicts and False in verdicts          # both sides of the fold and the middle
    for a, b in zip(in_place, filled):
        assert a.omega == pytest.approx(b.omega, rel=1e-12)
        np.testing.assert_allclose(b.displacement, a.displacement, rtol=1e-12, atol=0)
        assert b.stable == a.stable and b.stability_note == a.stability_note
        assert b.stability_job is None
        if np.isfinite(a.floquet_exponent):
            assert b.floquet_exponent == pytest.approx(a.floquet_exponent, rel=1e-12)


def test_outside_a_block_nothing_is_deferred():
    H, N = 3, 128
    model, contacts, F = chain(H)
    with deferred_stability(enabled=False) as jobs:
        points = continuation(model, contacts, F, 2 * np.pi * 8.0, 2 * np.pi * 8.5, H, N)
    assert jobs is None
    assert all(s.stability_job is None and s.stable is not None for s in points if s.converged)


def assert_same_point_fields(a, b):
    """The fields finalize evaluates for a point — contact forces (harmonics and samples), states,
    the full residual, the slider's friction passes — the same in place and deferred (a deferred
    point's evaluation skips the contact Jacobian, which they do not depend on): floats to 1e-12 of
    their largest magnitude (the same arithmetic: equal in practice), states and passes exactly.
    Both sweeps run after a first one, so both find the model's cached modal basis
    (sarfe.hbm.modal)."""
    for got, want in ((b.contact_force, a.contact_force),
                      (b.contact_force_time, a.contact_force_time)):
        np.testing.assert_allclose(got, want, rtol=0.0, atol=1e-12 * np.abs(want).max(initial=1.0))
    assert b.residual_norm == pytest.approx(a.residual_norm, rel=1e-12, abs=1e-300)
    np.testing.assert_array_equal(b.contact_state, a.contact_state)
    assert b.friction_passes == a.friction_passes


def test_deferred_points_have_the_in_place_contact_fields():
    """Damped impacts (rate-dependent law) over the fold, and a 2-D Jenkins element slipping on an
    elliptic orbit near resonance: each point of the deferred sweep carries the in-place fields."""
    from sarfe.hbm.laws.jenkins import SLIP

    H, N = 3, 128
    model, contacts, F = chain(H)
    band = (2 * np.pi * 9.5, 2 * np.pi * 9.9)
    continuation(model, contacts, F, *band, H, N)
    in_place = continuation(model, contacts, F, *band, H, N)
    with deferred_stability():
        deferred = continuation(model, contacts, F, *band, H, N)
    assert len(deferred) == len(in_place) > 5
    for a, b in zip(in_place, deferred):
        assert_same_point_fields(a, b)

    model = make_linear_model(np.eye(2), 0.02 * np.eye(2), np.diag([1.0, 1.5]))
    contacts = make_contact_set(sp.csr_matrix(np.eye(2)), ["squeak"], [-1], [[0, 1]], gap=0.0,
                                normal_stiffness=0.0, tangential_stiffness=1.0,
                                friction_coefficient=1.0, normal_load=1.0)
    F = np.zeros((2 * H + 1, 2))
    F[1, 0], F[2, 1] = 0.5, 0.4
    band = (0.9, 1.3)
    continuation(model, contacts, F, *band, H, N)
    in_place = continuation(model, contacts, F, *band, H, N)
    with deferred_stability():
        deferred = continuation(model, contacts, F, *band, H, N)
    assert len(deferred) == len(in_place) > 5
    assert any(np.any(s.contact_state == SLIP) for s in in_place)
    for a, b in zip(in_place, deferred):
        assert_same_point_fields(a, b)
