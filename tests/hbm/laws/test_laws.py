"""The contact-law interface on the two original laws: registry, analytic Jacobians (AFT and the
time step) against central finite differences in every state, and the cold-start linearization."""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm import laws
from sarfe.hbm.contacts import make_contact_set

from law_checks import aft_errors, step_error


def harmonics_of(mean, first, second=0.0, H=3):
    """r̃ (2H+1, len(mean)) with a mean, a first and a second harmonic per row."""
    R = np.zeros((2 * H + 1, len(mean)))
    R[0], R[1], R[2], R[3], R[4] = mean, first, 0.3 * np.asarray(first), second, 0.1
    return R


def test_registry_declares_the_original_laws():
    assert {"rattle", "squeak"} <= set(laws.names())
    assert laws.law("squeak").tangent is not None and laws.law("rattle").tangent is None
    with pytest.raises(ValueError, match="contact law must be one of"):
        laws.law("glue")


@pytest.mark.parametrize("state, mean", [("open", -2.0), ("closed", 3.0), ("impacting", 0.2)])
def test_rattle_jacobian_in_every_state(state, mean):
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["rattle"], [0], [[-1, -1]], 0.0, 50.0)
    R = harmonics_of([mean], [1.0])
    jac, omega, _ = aft_errors(contacts, R, 256, 3.0)
    assert jac < 1e-6 and omega < 1e-9
    assert step_error(contacts, np.array([mean + 0.37]), np.array([mean]), np.array([0.1]),
                      np.zeros((0, 2)), 1e-3) < 1e-6


@pytest.mark.parametrize("state, amplitude", [("stick", 0.01), ("slip", 1.0)])
@pytest.mark.parametrize("directions", [1, 2])
def test_squeak_jacobian_in_stick_and_slip(state, amplitude, directions):
    G = sp.csr_matrix(np.eye(3))
    tangent = [[1, -1]] if directions == 1 else [[1, 2]]
    contacts = make_contact_set(G, ["squeak"], [0], tangent, -0.5, 4.0, 3.0, 0.4, 0.5)
    R = harmonics_of([0.2, 0.0, 0.0], [0.1, amplitude, 0.5 * amplitude])
    jac, omega, _ = aft_errors(contacts, R, 128, 2.0)
    assert jac < 1e-5 and omega < 1e-9
    stuck = state == "stick"
    slider = np.array([[0.0, 0.0]]) if stuck else np.array([[-3.0, 1.0]])
    r = np.array([0.6, 0.01, 0.005 if directions == 2 else 0.0])
    assert step_error(contacts, r, r, np.zeros(3), slider, 1e-3) < 1e-6


def test_linearization_of_the_original_laws():
    G = sp.csr_matrix(np.eye(3))
    contacts = make_contact_set(G, ["rattle", "squeak"], [0, 1], [[-1, -1], [2, -1]],
                                [-1e-3, 2e-3], [1e4, 2e4], [0.0, 5e3], [0.0, 0.3], [0.0, 4.0])
    normal, tangent = laws.linearization(contacts)
    assert normal.spring.tolist() == [1e4, 2e4] and normal.closed.tolist() == [True, False]
    assert normal.preload == pytest.approx([10.0, 4.0]) and tangent.tolist() == [0.0, 5e3]
