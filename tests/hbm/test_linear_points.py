"""Linear points (sarfe.hbm.linear_points): where every contact stays open or stuck the
harmonic-balance solution is the linearized model's response — checked against the closed-form
FRF of that linear model and against Newton on the full nonlinear equations."""
import numpy as np
import scipy.sparse as sp

from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.linear_points import (linear_displacements, linear_point, linearized_states,
                                     screen_linear)
from sarfe.hbm.pruning import linear_responses

from tests.hbm import lumped_panel as panel

H, N = 7, 256
OPTIONS = SolverOptions(stability=False)


def _frf(omega, level):
    """ũ of the lumped panel with the rattle open and the seal stuck (its spring k_t on DOF 2):
    one complex solve of (K + k_t e₂e₂ᵀ − ω²M + iωD) Û = F̂ — the linear FRF, written out."""
    K = panel.STIFFNESS.copy()
    K[2, 2] += panel.NOMINAL["tangential_stiffness"]
    D = np.asarray(panel.model().damping.toarray() if sp.issparse(panel.model().damping)
                   else panel.model().damping)
    F = panel.excitation(H, level)
    U = np.zeros((2 * H + 1, 3))
    Uc = np.linalg.solve(K - omega**2 * panel.MASS + 1j * omega * D, F[1] - 1j * F[2])
    U[1], U[2] = Uc.real, -Uc.imag
    return U


def test_states_of_the_linearization():
    # the rattle is open at u = 0, the seal (normal load 1 N) stuck
    np.testing.assert_array_equal(linearized_states(panel.contacts()), [0, 1])


def test_linear_point_is_the_linear_frf_and_newtons_solution():
    model, contacts = panel.model(), panel.contacts()
    level = 0.02                                # 0.06 m/s²: the gap is never used up
    F = panel.excitation(H, level)
    for hz in (30.0, 49.0, 50.3, 70.0, 90.0):
        omega = 2 * np.pi * hz
        point = linear_point(model, contacts, F, omega, H, N, options=OPTIONS)
        assert point is not None and point.method == "linear" and point.converged
        frf = _frf(omega, level)
        scale = np.abs(frf).max()
        assert np.abs(point.displacement - frf).max() <= 1e-10 * scale
        newton = solve_frequency(model, contacts, F, omega, H, N, options=OPTIONS)
        assert newton.converged
        assert np.abs(point.displacement - newton.displacement).max() <= 1e-10 * scale
        # forces: the stuck seal carries k_t q, the open rattle nothing
        assert np.all(point.contact_state[:, 0] == 0) and np.all(point.contact_state[:, 1] == 1)
        q = point.contact_displacement[:, 1]
        k_t = panel.NOMINAL["tangential_stiffness"]
        np.testing.assert_allclose(point.contact_force[:, 1], k_t * q, rtol=1e-10,
                                   atol=1e-12 * k_t * np.abs(q).max())   # AFT round-off [N]


def test_linear_point_refuses_where_a_contact_acts():
    model, contacts = panel.model(), panel.contacts()
    F = panel.excitation(H, 1.0)                  # 3 m/s²: the rattle closes near 50 Hz
    omega = 2 * np.pi * 50.0
    assert linear_point(model, contacts, F, omega, H, N, options=OPTIONS) is None
    newton = solve_frequency(model, contacts, F, omega, H, N, options=OPTIONS)
    assert newton.converged and np.any(newton.contact_state[:, 0] == 1)
    # the screen (dynamic part doubled, margin 0.5) is conservative: nonlinear at 50 Hz, and
    # wherever it says linear the exact check holds and Newton keeps the rattle open
    omegas = 2 * np.pi * np.linspace(30.0, 90.0, 13)
    screened = screen_linear(model, contacts, F, omegas, 64, 0.5)
    assert not screened[np.argmin(np.abs(omegas - omega))] and screened.any()
    for w in omegas[screened]:
        assert linear_point(model, contacts, F, w, H, N, options=OPTIONS) is not None
    assert screen_linear(model, contacts, panel.excitation(H, 0.02), omegas, 64, 0.5).all()


def test_modal_and_direct_linear_displacements_agree():
    model, contacts = panel.model(), panel.contacts()
    F = panel.excitation(H, 0.5)
    omegas = 2 * np.pi * np.linspace(30.0, 90.0, 13)
    modal = linear_displacements(model, contacts, F, omegas)     # the model's modal basis
    direct = np.stack(list(linear_responses(model, contacts, F[:3], omegas)))
    scale = np.abs(direct).max()
    assert np.abs(modal[:, :3] - direct).max() <= 1e-12 * scale
    assert not np.any(modal[:, 3:])              # orders without excitation are zero
