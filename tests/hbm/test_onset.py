"""Onset factors (sarfe.hbm.onset) against the nonlinear solution swept in excitation level.

Below its onset a contact stays in its rest state and the periodic solution is the linear one;
above it the contact closes, separates or slips. The measured onset is found by bisection on the
excitation level with the harmonic-balance solver (AFT with the laws, Newton; 12 halvings of
±5 %: resolution 2e-5) — the steady state, whose friction sliders have shaken down — and the
first slip from the rest state by one period of the Newmark time integrator started from the rest
state's periodic orbit (slider at its assembly position) at 0.99 and 1.01 × the predicted factor.
Measured (HBM: H = 7 or 5, N = 256 samples, 16 halvings; onset: 512 samples): rattle closing
+0.0008 %, seal slip +0.003 %, preloaded rattle separation +0.0001 %, damped impact +0.005 %,
squeak with a varying normal force (steady slip) +0.0007 %, 2-D friction (steady slip) +0.0001 %;
first slip by time-integration bisection −0.004 % (both friction cases).
"""
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from lumped_panel import RATTLE, SEAL, contacts as panel_contacts, excitation as panel_excitation
from lumped_panel import model as panel_model
from sarfe.erp.risk import linear_risk_from_contacts
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.onset import excitation_onset, onset_factors, rest_response
from sarfe.hbm.solution import SolverOptions
from sarfe.hbm.solve import solve_frequency
from sarfe.hbm.time_integration import integrate_time
from test_hbm_vs_time import squeak_model

OPTIONS = SolverOptions(stability=False)
CLOSED, SEPARATED, SLIP = 1, 0, 2       # contact_state codes of the events


def scaled(F, level):
    """The excitation with its periodic rows × level (the static row held)."""
    out = np.array(F, dtype=float)
    out[1:] *= level
    return out


def measured_onset(model, contacts, F, omega, predicted, contact, state, harmonics,
                   samples=256, halvings=12):
    """Excitation level at which the HBM solution first shows ``state`` at ``contact``: bisection
    in [0.95, 1.05] × predicted (the bracket itself asserted)."""
    def active(level):
        solution = solve_frequency(model, contacts, scaled(F, level), omega, harmonics, samples,
                                   options=OPTIONS)
        assert solution.converged, solution.reason
        return bool(np.any(solution.contact_state[:, contact] == state))
    low, high = 0.95 * predicted, 1.05 * predicted
    assert not active(low) and active(high)
    for _ in range(halvings):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if active(middle) else (middle, high)
    return 0.5 * (low + high)


def first_period_slips(model, contacts, F, omega, harmonics, tangential_stiffness):
    """Does the contact slip within one period of Newmark integration (512 steps) started on the
    rest state's periodic orbit with its slider where it was assembled (λ_t(0) = λ_t,0 +
    k_t q_dyn(0))? One contact, its tangent rows 1 (and 2)."""
    rest = rest_response(model, contacts, F, omega)
    U = rest.displacement
    q_dyn = contacts.gap_map @ U[1::2].sum(axis=0)
    force = tangential_stiffness * q_dyn
    rows = contacts.tangent_rows[0]
    force[rows[rows >= 0]] += rest.tangential_force[0][rows >= 0]
    start = SimpleNamespace(displacement=U, contact_force_time=force[None])
    run = integrate_time(model, contacts, F, omega, harmonics, steps_per_period=512,
                         max_periods=1, initial=start, accelerate=False)
    return bool(np.any(run.contact_state == SLIP))


def test_single_harmonic_closing_is_the_closed_form_and_the_linear_risk():
    """One harmonic: s* = (g − w0)/|ŵ1| (w0 = 0 here), and s* < 1 exactly where the linear risk
    index (tolerance 0) flags the contact; 20 log10 s* in dB."""
    model, contacts, H = panel_model(), panel_contacts(), 3
    for frequency in (40.0, 50.0, 65.0):
        omega = 2 * np.pi * frequency
        F = panel_excitation(H)
        onset = excitation_onset(model, contacts, F, omega)
        U = rest_response(model, contacts, F, omega).displacement
        R = np.asarray(contacts.gap_map @ U.T).T
        amplitude = np.hypot(R[1, 0], R[2, 0])
        assert abs(R[0, 0]) < 1e-15
        assert onset.factor[RATTLE] == pytest.approx(1e-4 / amplitude, rel=1e-7)
        assert onset.level_db[RATTLE] == pytest.approx(20 * np.log10(1e-4 / amplitude), abs=1e-6)
        risk = linear_risk_from_contacts(contacts, R, 0.0)[RATTLE]
        assert risk.rattle_risk == (onset.normal_factor[RATTLE] < 1)
        # the seal: one harmonic, constant N, no static load: first and steady slip agree
        k_t, mu, N0 = 1e5, 0.4, 1.0
        assert onset.slip_factor[SEAL] == pytest.approx(
            mu * N0 / (k_t * np.hypot(R[1, 1], R[2, 1])), rel=1e-7)
        assert onset.steady_slip_factor[SEAL] == pytest.approx(onset.slip_factor[SEAL], rel=1e-7)


@pytest.mark.parametrize("frequency, contact, state, mechanism", [
    (45.0, RATTLE, CLOSED, "closing"),      # rattle first: s* 0.69, seal 1.14
    (120.0, SEAL, SLIP, "slip"),            # seal first: s* 0.88, rattle 33
])
def test_lumped_panel_first_event_within_one_percent(frequency, contact, state, mechanism):
    model, contacts, H = panel_model(), panel_contacts(), 7
    omega = 2 * np.pi * frequency
    F = panel_excitation(H)
    onset = excitation_onset(model, contacts, F, omega)
    assert onset.mechanism[contact] == mechanism
    assert 1.1 * onset.factor[contact] < onset.factor[1 - contact]      # it is the first event
    measured = measured_onset(model, contacts, F, omega, onset.factor[contact], contact, state, H)
    assert measured / onset.factor[contact] - 1 == pytest.approx(0.0, abs=1e-2)


@pytest.mark.parametrize("law, parameters", [("rattle", {}),
                                             ("damped_impact", {"contact_damping": 30.0})])
def test_preloaded_contact_separation_within_one_percent(law, parameters):
    """A 2-DOF chain whose tip is pressed on ground (overclosure 0.2 mm, k_n = 2e4 N/m: 4 N): the
    static state (w0 − g = 5e-5 m, not the overclosure) and, for the dashpot law, the force
    k(w − g) + c ẇ reaching 0 before w = g set the separation."""
    H = 7
    M, K = np.diag([1.0, 0.5]), np.array([[3e4, -1e4], [-1e4, 1e4]])
    model = make_linear_model(M, 2e-4 * K + 5.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix([[0.0, 1.0]]), [law], [0], [[-1, -1]], gap=-2e-4,
                                normal_stiffness=2e4, parameters=parameters)
    F = np.zeros((2 * H + 1, 2))
    F[1, 0] = 40.0
    omega = 2 * np.pi * 10.0
    onset = excitation_onset(model, contacts, F, omega)
    assert onset.mechanism[0] == "separation"
    penetration = rest_response(model, contacts, F, omega).displacement[0, 1] + 2e-4   # w0 − g
    compliance = np.linalg.inv(K)[1, 1]                                     # 1.5e-4 m/N
    assert penetration == pytest.approx(2e-4 / (1 + 2e4 * compliance), rel=1e-9)
    measured = measured_onset(model, contacts, F, omega, onset.factor[0], 0, SEPARATED, H)
    assert measured / onset.factor[0] - 1 == pytest.approx(0.0, abs=1e-2)


def friction_onsets_hold(model, contacts, F, omega, harmonics, tangential_stiffness, margin):
    """The steady stick–slip factor exceeds the first-slip one by ``margin`` (the shakedown is
    real); the HBM sweep's first slip is within 1 % of the steady factor, and one period of time
    integration from the rest state slips at 1.01 × the first-slip factor, not at 0.99."""
    onset = excitation_onset(model, contacts, F, omega)
    assert onset.mechanism[0] == "slip"
    assert onset.steady_slip_factor[0] > margin * onset.slip_factor[0]
    measured = measured_onset(model, contacts, F, omega, onset.steady_factor[0], 0, SLIP,
                              harmonics)
    assert measured / onset.steady_factor[0] - 1 == pytest.approx(0.0, abs=1e-2)
    for level, slips in ((0.99, False), (1.01, True)):
        assert first_period_slips(model, contacts, scaled(F, level * onset.slip_factor[0]), omega,
                                  harmonics, tangential_stiffness) == slips
    return onset


def test_squeak_with_varying_normal_force():
    """The squeak model of test_hbm_vs_time (pressed on ground: 0.2 mm overclosure, k_n 4e4 + N0
    2 N; its normal DOF shaken): N(θ) = N0 + s N_dyn(θ) moves the slip limit, so the steady
    stick–slip comes > 5 % after the first slip from the rest state."""
    model, contacts, F, omega = squeak_model(7)
    onset = friction_onsets_hold(model, contacts, F, omega, 7, 3e4, 1.05)
    assert onset.normal_factor[0] > 4 * onset.slip_factor[0]


def test_two_direction_friction_with_static_load():
    """Friction in two tangent directions under a constant normal load, a static tangential load
    (0.2, 0.1) N and an elliptic orbit: the static load brings the first slip forward, the steady
    stick–slip needs the orbit's swing only (> 20 % later; the directional factor is exact for one
    harmonic and a constant normal force)."""
    H = 5
    M, K = np.diag([0.2, 0.3]), np.array([[4e4, -1e4], [-1e4, 3e4]])
    model = make_linear_model(M, 1e-4 * K + 2.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix(np.eye(2)), ["squeak"], [-1], [[0, 1]], gap=0.0,
                                tangential_stiffness=5e4, friction_coefficient=0.3,
                                normal_load=2.0)
    F = np.zeros((2 * H + 1, 2))
    F[0], F[1], F[2] = [0.2, 0.1], [1.0, 0.25], [0.0, -0.25 * np.sqrt(3)]
    friction_onsets_hold(model, contacts, F, 2 * np.pi * 60.0, H, 5e4, 1.2)


def test_events_at_rest_and_never():
    """s* = 0 where the rest state is already past the event (a static load closing the gap);
    s* = ∞ where nothing moves towards it (no excitation)."""
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["rattle"], [0], [[-1, -1]], gap=1e-4,
                                normal_stiffness=1e5)
    R = np.zeros((3, 1))
    R[0, 0] = 2e-4
    assert onset_factors(contacts, R, 10.0).factor[0] == 0.0
    R[0, 0] = 0.0
    still = onset_factors(contacts, R, 10.0)
    assert np.isinf(still.factor[0]) and still.mechanism[0] == ""


def test_pair_pushed_sideways_by_its_preload_slides_at_assembly():
    """An inclined pad (normal and tangential DOF coupled, K_01 = −8e3 N/m) pressed on ground
    (0.1 mm overclosure): stuck where it was assembled it would carry k_t q0 > μN0, so it slid.
    The rest state carries μN0 along that force and the periodic solution at a tiny excitation
    (1e-4 × the steady factor: its slider dragged as little as needed) has the same static normal
    and tangential force within 0.1 %; the first slip is at once (s* = 0)."""
    H = 5
    M, K = np.diag([0.1, 0.1]), np.array([[2e4, -8e3], [-8e3, 1e4]])
    model = make_linear_model(M, 1e-4 * K + 3.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix(np.eye(2)), ["squeak"], [0], [[1, -1]], gap=-1e-4,
                                normal_stiffness=5e4, tangential_stiffness=5e4,
                                friction_coefficient=0.3)
    F = np.zeros((2 * H + 1, 2))
    F[1] = [0.5, 1.0]
    omega = 2 * np.pi * 40.0
    rest = rest_response(model, contacts, F, omega)
    assert rest.slid[0]
    normal = 5e4 * (rest.displacement[0, 0] + 1e-4)
    assert np.linalg.norm(rest.tangential_force[0]) == pytest.approx(0.3 * normal, rel=1e-9)
    onset = excitation_onset(model, contacts, F, omega)
    assert onset.factor[0] == 0.0 and onset.mechanism[0] == "slip"
    tiny = solve_frequency(model, contacts, 1e-4 * onset.steady_factor[0] * F, omega, H, 256,
                           options=OPTIONS)
    assert tiny.converged and not np.any(tiny.contact_state == SLIP)
    assert tiny.contact_force[0, 0] == pytest.approx(normal, rel=1e-3)
    assert tiny.contact_force[0, 1] == pytest.approx(rest.tangential_force[0, 0], rel=1e-3)
