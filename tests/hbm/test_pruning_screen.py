"""The contact screen's linear pass on the contact rows (sarfe.hbm.pruning.contact_row_responses):
the modal compliance with the contacts' springs and dashpots as a Woodbury update equals a 1-DOF
closed form and the engine's own full linearized solve, never solves a system of model size, and
leaves the screen's decisions and clearances as the direct per-ω solves give them."""
import numpy as np
import pytest
import scipy.sparse as sp

import sarfe.hbm.modal as modal
import sarfe.hbm.pruning as pruning
from sarfe.hbm import make_contact_set, make_linear_model
from sarfe.hbm.pruning import contact_row_responses, screen_contacts
from sarfe.tradeoff.lumped import lumped_problem


def direct_rows(model, contacts, excitation, omegas):
    """G ũ of the engine's linearized start guess: one real system of all harmonics and all DOFs
    per ω (sarfe.hbm.solve.linearized_guess), independent of the screen's code."""
    from sarfe.hbm.solve import linearized_guess, make_problem

    H = (np.asarray(excitation).shape[0] - 1) // 2
    problem = make_problem(model, contacts, excitation, H, 64)
    return np.stack([np.asarray(contacts.gap_map @ linearized_guess(problem, w).T).T
                     for w in omegas])


def no_model_solve(*args, **kwargs):
    raise AssertionError("the modal path solved a system of model size")


def one_dof_with_preloaded_damped_stop(mass=2.0, stiffness=8e3, damping=4.0, stop=2e4,
                                       dashpot=6.0, gap=-1e-3, force=5.0):
    model = make_linear_model(np.array([[mass]]), np.array([[damping]]), np.array([[stiffness]]))
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), np.array(["damped_impact"], dtype=object),
                                [0], [[-1, -1]], [gap],
                                parameters={"normal_stiffness": stop, "contact_damping": dashpot})
    F = np.zeros((3, 1))
    F[1, 0] = force
    return model, contacts, F


def test_one_dof_closed_form(monkeypatch):
    """m ẍ + c ẋ + k x + λ = F cos ωt with a preloaded stop λ = k_n (x − g) + c_n ẋ (g < 0):
    x₀ = k_n g / (k + k_n), X = F / (k + k_n − ω² m + iω (c + c_n)), x = Re(X e^{iωt})."""
    m, k, c, kn, cn, g, F0 = 2.0, 8e3, 4.0, 2e4, 6.0, -1e-3, 5.0
    model, contacts, F = one_dof_with_preloaded_damped_stop(m, k, c, kn, cn, g, F0)
    omegas = np.linspace(60.0, 180.0, 25)            # through √((k + k_n)/m) = 118 rad/s
    monkeypatch.setattr(pruning, "linear_responses", no_model_solve)
    R = contact_row_responses(model, contacts, F, omegas)[:, :, 0]
    X = F0 / (k + kn - omegas**2 * m + 1j * omegas * (c + cn))
    np.testing.assert_allclose(R[:, 0], kn * g / (k + kn), rtol=1e-12)
    np.testing.assert_allclose(R[:, 1] - 1j * R[:, 2], X, rtol=1e-10)


def mixed_contacts(zeta=0.05):
    """3 masses: a rattle with a 1 mm gap, one with a 1 m gap, one preloaded 1 kN into its stop, a
    friction contact (stuck tangent k_t) and a preloaded damped stop between masses 1 and 2."""
    p = lumped_problem(3, rattle_dofs=(0, 1, 2), gap=[1e-3, 1.0, -1e-2], zeta=zeta, force=10.0,
                       squeak_dofs=(1,), harmonics=5)
    c = p.contacts
    G = sp.vstack([c.gap_map, sp.csr_matrix([[0.0, 1.0, -1.0]])]).tocsr()
    kind = np.array(list(c.kind) + ["damped_impact"], dtype=object)
    parameters = {name: np.append(value, value[0]) for name, value in c.parameters.items()}
    parameters["contact_damping"] = np.append(np.zeros(c.count), 30.0)
    contacts = make_contact_set(G, kind, np.append(c.normal_row, G.shape[0] - 1),
                                np.vstack([c.tangent_rows, [[-1, -1]]]), np.append(c.gap, -2e-3),
                                names=c.names + ("stop",), parameters=parameters)
    return p, contacts


@pytest.mark.parametrize("zeta", [0.05, 0.0])
def test_rows_equal_the_full_linearized_solve(monkeypatch, zeta):
    """Open, preloaded, stuck-friction and damped contacts at once, through the resonances of the
    chain with and without its contacts; ζ = 0: the chain's own undamped resonances are on the
    grid (Z_k singular there: those ω are solved directly, the rest modally)."""
    p, contacts = mixed_contacts(zeta)
    w = p.natural_frequencies_rad_s
    omegas = np.concatenate([np.linspace(0.5 * w[0], 3.0 * w[-1], 40), w])
    reference = direct_rows(p.model, contacts, p.excitation, omegas)
    modal._CACHE.pop(id(p.model), None)
    if zeta:
        monkeypatch.setattr(pruning, "linear_responses", no_model_solve)
    R = contact_row_responses(p.model, contacts, p.excitation, omegas)
    assert modal.cached_modal_basis(p.model) is not None
    scale = np.abs(reference).max(axis=(0, 1))          # per contact row
    assert np.all(np.abs(R - reference) <= 1e-10 * scale)


def test_screen_decisions_as_direct_solves():
    """Same decisions and clearances (to round-off) as the direct solve per ω."""
    p, contacts = mixed_contacts()
    w = p.natural_frequencies_rad_s
    omegas = np.concatenate([np.linspace(0.5 * w[0], 1.5 * w[-1], 60), w])
    modal_path = screen_contacts(p.model, contacts, p.excitation, omegas)
    direct = screen_contacts(p.model, contacts, p.excitation, omegas, modal=False)
    assert [d.decision for d in modal_path] == [d.decision for d in direct]
    assert [d.decision for d in modal_path] == ["nonlinear", "open", "closed", "nonlinear",
                                                "nonlinear"]
    np.testing.assert_allclose([d.clearance for d in modal_path], [d.clearance for d in direct],
                               rtol=1e-9, atol=1e-12)


def test_few_frequencies_leave_the_model_cache_alone(monkeypatch):
    """A screen of a few listed frequencies solves directly and does not request the basis (the
    points' first condensation still finds the model unseen)."""
    p, contacts = mixed_contacts()
    calls = []
    monkeypatch.setattr(pruning, "cached_modal_basis", lambda model: calls.append(model))
    decisions = screen_contacts(p.model, contacts, p.excitation, [60.0, 90.0])
    assert not calls and len(decisions) == contacts.count


def test_frequency_blocks_do_not_change_the_rows(monkeypatch):
    """The frequencies are processed in blocks bounded in memory; one ω per block gives the same."""
    p, contacts = mixed_contacts()
    omegas = np.linspace(50.0, 300.0, 30)
    whole = contact_row_responses(p.model, contacts, p.excitation, omegas)
    monkeypatch.setattr(pruning, "_BLOCK_ENTRIES", 1)
    np.testing.assert_allclose(contact_row_responses(p.model, contacts, p.excitation, omegas),
                               whole, rtol=1e-13, atol=1e-13 * np.abs(whole).max())
