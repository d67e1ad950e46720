"""Contribution of each contact to the radiated power: the structure is linear apart from the
contact forces, so ũ_k = Z_k⁻¹ f̃_k − Σ_c Z_k⁻¹ G_cᵀ λ̃_k,c exactly (sarfe.pipeline.post.contribution_records),
and the coherent shares of the sources add up to the total ERP (sarfe.erp.contributions)."""
from types import SimpleNamespace

import numpy as np
import pytest

from sarfe.erp.contributions import erp_contributions, ranking_lines
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.dynamic_stiffness import to_complex
from sarfe.hbm.model import make_linear_model
from sarfe.pipeline.post.contact_dynamics import contact_dynamics
from sarfe.case.config import ErpConfig
from sarfe.pipeline.post.contribution_records import point_contributions, source_displacements

H, N = 9, 256
ERP = {"rho_kg_m3": 1.204, "c_m_s": 343.2, "radiation_loss_factor": 1.0,
       "reference_power_W": 1e-12}


def _case_stage_nl(model, contacts, F, groups, erp_map, areas):
    case = ErpConfig(**ERP)            # the case's erp section (sarfe.case.config)
    stage = SimpleNamespace(erp_map=np.asarray(erp_map, dtype=float), erp_areas=np.asarray(areas))
    nl = SimpleNamespace(model=model, contacts=contacts, excitation=F, groups=groups)
    return case, stage, nl


def chain_with_two_contacts():
    """3-DOF chain (masses 1, 0.5, 0.8 kg), excited at DOF 0; 'stop' a rattle contact of DOF 1
    against ground with a 0.1 mm gap (it impacts), 'clip' a preloaded contact of DOF 2 against
    ground that never opens (closed, so linear: λ = k_n (w − g))."""
    M = np.diag([1.0, 0.5, 0.8])
    k = 4.0e4
    K = k * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1.5]])
    D = 2e-4 * K + 0.5 * M
    model = make_linear_model(M, D, K)
    G = np.array([[0, 1.0, 0], [0, 0, 1.0]])
    contacts = make_contact_set(G, ["rattle", "rattle"], [0, 1], [[-1, -1], [-1, -1]],
                                gap=[1e-4, -1e-2], normal_stiffness=[2e6, 1e4],
                                names=("stop", "clip"))
    F = np.zeros((2 * H + 1, 3))
    F[1, 0] = 60.0
    groups = [("stop", "rattle", np.array([0])), ("clip", "rattle", np.array([1]))]
    return model, contacts, F, groups


@pytest.fixture(scope="module")
def chain_solution():
    model, contacts, F, groups = chain_with_two_contacts()
    omega = 2 * np.pi * 20.0
    solution = solve_frequency(model, contacts, F, omega, H, N,
                               options=SolverOptions(tolerance=1e-12, max_iterations=200))
    assert solution.converged
    return model, contacts, F, groups, solution


def test_partial_responses_sum_to_the_total_velocity_field(chain_solution):
    model, contacts, F, groups, s = chain_solution
    state = np.asarray(s.contact_state)
    assert (state[:, 0] == 0).any() and (state[:, 0] == 1).any()   # the stop opens and closes
    assert (state[:, 1] == 1).all()                                # the clip never opens
    areas = np.array([0.02, 0.05, 0.03])
    case, stage, nl = _case_stage_nl(model, contacts, F, groups, np.eye(3), areas)
    result, reason = point_contributions(case, stage, nl, s)
    assert reason is None
    assert result.names == ("excitation", "stop", "clip")
    assert result.superposition_error < 1e-10
    # independently of the shares: Σ partial displacements = the solved ũ_k, DOF by DOF
    from sarfe.hbm.dynamic_stiffness import condense

    cond = condense(model, contacts.gap_map, F, s.omega, orders=np.arange(1, H + 1))
    member = np.eye(2)
    parts = source_displacements(cond, s.contact_force, member)
    total = to_complex(np.asarray(s.displacement))[1:]
    assert np.abs(parts.sum(axis=0) - total).max() < 1e-10 * np.abs(total).max()
    # the clip is closed-linear: its force is k_n (w − g), its part −Z⁻¹ Gᵀ k_n w_k for k ≥ 1
    w_clip = to_complex(np.asarray(s.contact_displacement))[1:, 1]
    lam_clip = to_complex(np.asarray(s.contact_force))[1:, 1]
    assert np.abs(lam_clip - 1e4 * w_clip).max() < 1e-8 * np.abs(lam_clip).max()
    # shares are coherent parts of the total: they add up to one, weighted or not
    assert result.share.sum() == pytest.approx(1.0, abs=1e-12)
    assert result.share_a.sum() == pytest.approx(1.0, abs=1e-12)
    assert result.total_power_W.sum() == pytest.approx(
        (result.coherent_power_W.sum(axis=0)).sum(), rel=1e-12)


def test_ranking_names_the_contact_that_drives_the_panel():
    """A panel (DOF 1) coupled to the excited mass (DOF 0) only through the 'link' contact, and a
    'stop' contact of the mass against ground: the panel, the only radiating DOF, moves by the
    link's force alone, so the link has 100 % of the sound and the stop and the excitation none."""
    M = np.diag([1.0, 0.3])
    K = np.diag([5.0e4, 2.0e4])
    D = 1e-4 * K
    model = make_linear_model(M, D, K)
    G = np.array([[1.0, -1.0], [1.0, 0.0]])
    contacts = make_contact_set(G, ["rattle", "rattle"], [0, 1], [[-1, -1], [-1, -1]],
                                gap=[-1e-3, 2e-4], normal_stiffness=[1e4, 1e6],
                                names=("link", "stop"))
    F = np.zeros((2 * H + 1, 2))
    F[1, 0] = 40.0
    omega = 2 * np.pi * 25.0
    s = solve_frequency(model, contacts, F, omega, H, N,
                        options=SolverOptions(tolerance=1e-12, max_iterations=200))
    assert s.converged
    groups = [("link", "rattle", np.array([0])), ("stop", "rattle", np.array([1]))]
    case, stage, nl = _case_stage_nl(model, contacts, F, groups, [[0.0, 1.0]], [0.1])
    result, _ = point_contributions(case, stage, nl, s)
    share = dict(zip(result.names, result.share_a))
    assert share["link"] == pytest.approx(1.0, abs=1e-9)
    assert abs(share["stop"]) < 1e-9 and abs(share["excitation"]) < 1e-9
    assert not np.isfinite(result.partial_level_db[result.names.index("stop")])
    lines = ranking_lines(result, 25.0, skip=("excitation",))
    link = result.names.index("link")
    assert lines[0] == (f"link: 100 % of the total = {result.part_level_dba[link]:.1f} dB(A) "
                        f"(alone {result.partial_level_dba[link]:.1f} dB(A)) at 25 Hz")
    # all of the sound: its part of the total is the whole, and equal to it alone
    assert result.part_level_dba[link] == pytest.approx(result.partial_level_dba[link], abs=1e-6)
    assert lines[1] == "stop: 0 % of the total (alone - dB(A)) at 25 Hz"


def test_shares_of_disjoint_fields_are_their_power_fractions():
    """Fields on disjoint nodes are orthogonal: share = partial power / total power, and the
    partial ERP is ½ρc Σ A |v|² (closed form)."""
    v = np.zeros((3, 1, 3), dtype=complex)
    v[0, 0, 0], v[1, 0, 1], v[2, 0, 2] = 10.0, 1j, 0.1
    areas = np.array([0.5, 1.0, 2.0])
    result = erp_contributions(["a", "b", "c"], v, areas, omega=2 * np.pi * 1000.0)
    power = 0.5 * 1.204 * 343.2 * np.array([100 * 0.5, 1.0, 0.01 * 2.0])
    assert np.allclose(result.partial_total_W, power, rtol=1e-12)
    assert np.allclose(result.share, power / power.sum(), rtol=1e-12)
    assert list(result.order()) == [0, 1, 2]
    # at 1 kHz A(f) = 0: the A-weighted levels equal the unweighted ones
    assert np.allclose(result.partial_level_dba, result.partial_level_db, atol=1e-9)


def test_friction_contact_dissipation_equals_input_minus_viscous_work():
    """contact_dynamics' dissipated energy of a Jenkins contact = the excitation's input work −
    viscous losses (periodic energy balance, from the solved harmonics), and its slip distance
    is bounded by the tangential motion's peak-to-peak path."""
    import importlib.util
    import pathlib

    from sarfe.hbm.time_integration import period_work

    path = pathlib.Path(__file__).parents[1] / "hbm" / "test_hbm_vs_time.py"
    spec = importlib.util.spec_from_file_location("hbm_vs_time_models", path)
    models = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(models)
    model, contacts, F, omega = models.squeak_model(15)
    s = solve_frequency(model, contacts, F, omega, 15, 2048)
    assert s.converged
    nl = SimpleNamespace(contacts=contacts, groups=[("pad", "squeak", np.array([0]))])
    (record,) = contact_dynamics(s, nl)
    input_work, viscous, _ = period_work(s.displacement, F, np.asarray(model.damping),
                                         s.contact_displacement, s.contact_force, omega)
    assert record["dissipated_energy_J"] == pytest.approx(input_work - viscous, rel=5e-3)
    # with the normal DOF not shaken the normal force is constant (the overclosure shared by the
    # penalty and the structure's spring) and the Coulomb work is μ λ_n × the slip path
    F[1, 2] = F[2, 2] = 0.0
    s = solve_frequency(model, contacts, F, omega, 15, 2048)
    assert s.converged
    (record,) = contact_dynamics(s, nl)
    assert record["slip_distance_m"] > 0 and record["impacts_per_period"] == 0
    normal = np.asarray(s.contact_force_time)[:, np.asarray(contacts.normal_row)[0]]
    assert np.ptp(normal) < 1e-9 * normal.max()
    assert record["dissipated_energy_J"] == pytest.approx(0.4 * normal[0] * record["slip_distance_m"],
                                                          rel=1e-3)


def test_reduced_quadratic_form_equals_the_nodal_erp_sums(chain_solution):
    """The contributions from the reduced Gram matrix Γ_k = (kω)² X_kᴴ Q X_k, Q = Nᵀ diag(A) N,
    equal those of the nodal velocities v = i kω N ũ summed over the radiating nodes (the
    definition, sarfe.erp.contributions.erp_contributions) to 1e-10 relative, on a radiating
    surface of 40 nodes seeing all three DOFs through a random map N."""
    from sarfe.erp.contributions import normal_velocity
    from sarfe.hbm.dynamic_stiffness import condense
    from sarfe.pipeline.post.contribution_records import contact_rows

    model, contacts, F, groups, s = chain_solution
    rng = np.random.default_rng(7)
    erp_map, areas = rng.normal(size=(40, 3)), rng.uniform(1e-4, 1e-2, 40)
    case, stage, nl = _case_stage_nl(model, contacts, F, groups, erp_map, areas)
    reduced, _ = point_contributions(case, stage, nl, s)
    cond = condense(model, contacts.gap_map, F, s.omega, orders=np.arange(1, H + 1))
    parts = source_displacements(cond, s.contact_force, contact_rows(contacts, groups))
    velocity = normal_velocity(np.moveaxis(parts @ erp_map.T, 1, 0), s.omega)      # (H, S, n_s)
    total = normal_velocity(to_complex(np.asarray(s.displacement))[1:] @ erp_map.T, s.omega)
    nodal = erp_contributions(reduced.names, np.moveaxis(velocity, 0, 1), areas, s.omega,
                              total_velocity=total)
    for name in ("partial_power_W", "coherent_power_W", "total_power_W"):
        a, b = getattr(reduced, name), getattr(nodal, name)
        assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max(), name
    assert np.allclose(reduced.share_a, nodal.share_a, rtol=1e-10, atol=1e-12)
    assert reduced.superposition_error < 1e-10 and nodal.superposition_error < 1e-10


def test_linear_baseline_by_the_condensation_equals_the_assembled_solve(chain_solution):
    """The linear baseline through the point's condensation (Woodbury on the contact rows) equals
    the direct solve of (K + Gᵀ diag(k) G − ω² M + iω D) Û = F̂ with the preloaded 'clip' as its
    spring and the open 'stop' removed, to 1e-10 relative."""
    from sarfe.pipeline.post.contribution_records import point_condensation
    from sarfe.pipeline.post.records import baseline_response

    model, contacts, F, groups, s = chain_solution
    nl = SimpleNamespace(model=model, contacts=contacts, excitation=F, groups=groups,
                         excitation_amplitude=F[1] - 1j * F[2])
    w = s.omega
    K = np.asarray(model.stiffness) + np.diag([0.0, 0.0, 1e4])        # the clip's spring
    direct = np.linalg.solve(K - w**2 * np.asarray(model.mass) + 1j * w * np.asarray(model.damping),
                             nl.excitation_amplitude)
    by_rows = baseline_response(nl, w, point_condensation(nl, s))
    assert np.abs(by_rows - direct).max() <= 1e-10 * np.abs(direct).max()
    assert np.abs(baseline_response(nl, w) - direct).max() <= 1e-10 * np.abs(direct).max()
