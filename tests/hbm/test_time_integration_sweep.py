"""Time integrator as a sweep tool: Poincaré section (periodicity check) and the warm start from the
previous frequency's end state (a TimeResponse as ``initial``)."""
import numpy as np
import scipy.sparse as sp

from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.laws.jenkins import SLIP
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.time_integration import integrate_time, section_spread


def sdof(zeta=0.02, f_n=10.0):
    m, k = 1.0, (2 * np.pi * f_n) ** 2
    return make_linear_model([[m]], [[2 * zeta * np.sqrt(k * m)]], [[k]]), m, k


def warped(omega, steps):
    """Frequency the trapezoidal rule sees for ω at h = T/steps: (2/h) tan(ωh/2)."""
    h = 2 * np.pi / (omega * steps)
    return 2 / h * np.tan(omega * h / 2)


def test_section_of_a_linear_oscillator_decays_at_the_free_vibration_rate():
    """Started at rest, the period-start states approach the periodic orbit like the free vibration
    e^{−ζ ω_n t}: ‖x_p − x_∞‖ in the energy norm √(k u² + m u̇²) falls by e^{−ζ ω_n T} a period."""
    zeta, f_n, f = 0.02, 10.0, 6.5
    model, m, k = sdof(zeta, f_n)
    omega = 2 * np.pi * f
    F = np.zeros((3, 1))
    F[1] = 1.0
    r = integrate_time(model, None, F, omega, 1, steps_per_period=512, max_periods=40,
                       steady_tolerance=0.0, initial=np.zeros((3, 1)), accelerate=False)
    assert r.section.shape == (41, 2)
    # the periodic state at θ = 0 of the scheme: u = u_c, u̇ = ω' u_s (u̇/ω stored)
    u_hat = 1.0 / (k - m * warped(omega, 512) ** 2 + 1j * warped(omega, 512)
                   * 2 * zeta * np.sqrt(k * m))
    fixed = np.array([u_hat.real, warped(omega, 512) * -u_hat.imag / omega])
    d = r.section - fixed
    energy = np.sqrt(k * d[:, 0] ** 2 + m * (omega * d[:, 1]) ** 2)
    slope = np.polyfit(np.arange(len(energy)), np.log(energy), 1)[0]
    expected = -zeta * 2 * np.pi * f_n / f            # −ζ ω_n T
    assert abs(slope - expected) < 0.03 * abs(expected)
    assert section_spread(r.section, tail=5) > 1e-3        # still a transient at 40 periods
    periodic = integrate_time(model, None, F, omega, 1, steps_per_period=512, max_periods=5,
                              steady_tolerance=0.0, accelerate=False)  # from the orbit itself
    assert section_spread(periodic.section) < 1e-10


def test_section_spread_tells_period_two_from_period_one():
    a, b = np.array([1.0, 0.2]), np.array([0.6, -0.3])
    section = np.array([a, b] * 6)
    assert abs(section_spread(section, period=1) - 0.5) < 1e-12   # max ptp 0.5 / max |x| 1
    assert section_spread(section, period=2) == 0.0
    assert section_spread(section[:1]) == 0.0


def test_warm_started_sweep_is_the_closed_form_frf():
    """Each frequency started from the previous one's end state reaches the scheme's periodic
    response |Û| = 1/|k − m ω'² + i ω' c| (the exact FRF at the warped frequency ω')."""
    zeta, f_n = 0.05, 10.0
    model, m, k = sdof(zeta, f_n)
    c = 2 * zeta * np.sqrt(k * m)
    F = np.zeros((3, 1))
    F[1] = 1.0
    previous, steps = None, 256
    for f in np.linspace(6.0, 14.0, 9):
        omega = 2 * np.pi * f
        r = integrate_time(model, None, F, omega, 1, steps_per_period=steps,
                           steady_tolerance=1e-10, initial=previous)
        w = warped(omega, steps)
        exact = 1.0 / abs(k - m * w * w + 1j * w * c)
        assert r.steady
        assert abs(np.hypot(*r.displacement_harmonics[1:3, 0]) - exact) < 1e-7 * exact
        previous = r


def test_warm_start_from_a_steady_stick_slip_state_is_steady_at_once():
    """A friction contact: the end state (u, u̇, slider) of a steady run is the orbit's θ = 0 state,
    so a run started from it at the same ω is periodic in its first period and repeats it."""
    M = np.diag([1.0, 0.4])
    K = np.array([[2e4, -1e4], [-1e4, 1e4]])
    model = make_linear_model(M, 2e-4 * K + 4.0 * M, K)
    contacts = make_contact_set(sp.csr_matrix([[0.0, 1.0]]), ["squeak"], [-1], [[0, -1]], gap=0.0,
                                normal_stiffness=0.0, tangential_stiffness=3e4,
                                friction_coefficient=0.3, normal_load=10.0)
    F = np.zeros((3, 2))
    F[1, 0] = 30.0
    omega = 2 * np.pi * 11.0
    first = integrate_time(model, contacts, F, omega, 3, steps_per_period=256,
                           steady_tolerance=1e-11)
    again = integrate_time(model, contacts, F, omega, 3, steps_per_period=256,
                           steady_tolerance=1e-9, initial=first)
    assert first.steady and np.any(first.contact_state == SLIP)
    assert again.steady and again.periods == 1
    scale = np.abs(first.displacement_harmonics).max()
    assert np.abs(again.displacement_harmonics - first.displacement_harmonics).max() < 1e-8 * scale
