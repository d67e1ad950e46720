"""Linear risk baseline against hand-computed numbers."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.erp.risk import (
    linear_risk,
    linear_risk_from_contacts,
    tangential_peak_to_peak,
)


def test_hand_computed_normal_and_tangential():
    # contact 0: w = 3e-4 cos θ + 4e-4 sin θ → a_n = 5e-4; gap 1 mm, tolerance 0.3 mm → d = +0.2 mm
    # contact 1: w amplitude 1e-3 (pure sine) → d = 0.8e-3 - 0.1e-3 - 1e-3 = -0.3 mm → rattle
    W = np.zeros((3, 2))
    W[0] = [7.0, 7.0]  # static part ignored
    W[1, 0], W[2, 0] = 3e-4, 4e-4
    W[2, 1] = 1e-3
    T = np.zeros((3, 2, 2))
    # contact 0: q1 = 1e-4 cos θ, q2 = 1e-4 sin θ → circle of radius 1e-4 → s_pp = 2e-4
    T[1, 0, 0], T[2, 0, 1] = 1e-4, 1e-4
    # contact 1: q1 = 3e-5 cos θ, q2 = 4e-5 cos θ → line segment of half-length 5e-5 → s_pp = 1e-4
    T[1, 1, 0], T[1, 1, 1] = 3e-5, 4e-5
    risks = linear_risk(W, T, gap=[1e-3, 0.8e-3], tolerance=[0.3e-3, 0.1e-3], names=["a", "b"],
                        frequency_hz=50.0)
    a, b = risks
    assert a.name == "a" and a.frequency_hz == 50.0
    assert a.normal_amplitude_m == pytest.approx(5e-4)
    assert a.dynamic_tolerance_m == pytest.approx(2e-4)
    assert not a.rattle_risk
    assert a.tangential_peak_to_peak_m == pytest.approx(2e-4)
    assert b.normal_amplitude_m == pytest.approx(1e-3)
    assert b.dynamic_tolerance_m == pytest.approx(-3e-4)
    assert b.rattle_risk
    assert b.tangential_peak_to_peak_m == pytest.approx(1e-4)


def test_ellipse_major_axis_matches_sampling():
    rng = np.random.default_rng(3)
    T = rng.normal(size=(3, 50, 2))
    theta = np.linspace(0, 2 * np.pi, 20001)
    q = T[1][None] * np.cos(theta)[:, None, None] + T[2][None] * np.sin(theta)[:, None, None]
    sampled = 2 * np.linalg.norm(q, axis=2).max(axis=0)
    np.testing.assert_allclose(tangential_peak_to_peak(T), sampled, rtol=1e-6)
    # one direction: twice the amplitude
    T1 = np.zeros((3, 1, 2))
    T1[1, 0, 0], T1[2, 0, 0] = 6e-6, 8e-6
    assert tangential_peak_to_peak(T1)[0] == pytest.approx(2e-5)


def test_from_contact_set():
    # rows: 0 = w of rattle contact, 1 = q1 of squeak contact (no normal row, one tangent)
    G = sp.identity(2, format="csr")
    contacts = make_contact_set(G, ["rattle", "squeak"], [0, -1], [[-1, -1], [1, -1]],
                                gap=[2e-3, 0.0], normal_stiffness=[1e5, 0.0],
                                tangential_stiffness=[0.0, 1e4], friction_coefficient=[0, 0.4],
                                normal_load=[0, 5.0], names=["clip", "pad"])
    amp = 2.5e-3
    R = np.zeros((5, 2))
    R[1, 0] = amp
    R[2, 1] = amp / 10
    clip, pad = linear_risk_from_contacts(contacts, R, tolerance=0.5e-3, frequency_hz=20.0)
    assert clip.frequency_hz == 20.0 and clip.rattle_risk
    assert clip.dynamic_tolerance_m == pytest.approx(2e-3 - 0.5e-3 - 2.5e-3)
    assert np.isnan(clip.tangential_peak_to_peak_m)
    assert np.isnan(pad.normal_amplitude_m) and not pad.rattle_risk
    assert pad.tangential_peak_to_peak_m == pytest.approx(2 * 2.5e-4)
