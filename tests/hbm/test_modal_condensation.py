"""Modal condensation: G Z_k⁻¹ Gᵀ from the undamped modes equals the per-harmonic factorization
(and a 1-DOF closed form) on lumped and Craig–Bampton models with modal ζ, Rayleigh and no damping;
a damping that the modes do not diagonalize falls back to the factorization; solutions unchanged."""
import numpy as np
import pytest
import scipy.sparse as sp

import sarfe.hbm.dynamic_stiffness as linear
from sarfe.hbm import (ContinuationOptions, SolverOptions, continuation, make_contact_set,
                       make_linear_model, solve_frequency)
from sarfe.hbm.dynamic_stiffness import (condense, condensed_omega_derivative, modal_omega_derivative,
                              recover_displacement)
from sarfe.hbm.harmonic_set import coefficient_rows
from sarfe.hbm.modal import MODAL_DAMPING_TOLERANCE, cached_modal_basis, modal_basis
from sarfe.fe.damping import modal_damping
from sarfe.reduction import craig_bampton, free_dofs_system

H = 5


def relative(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(b).max(), 1e-300)


def chain(n=6, damping="modal"):
    """Spring-mass chain fixed at one end (masses 0.5…1 kg, springs 1e3…2e3 N/m)."""
    m = np.linspace(0.5, 1.0, n)
    k = np.linspace(1e3, 2e3, n)
    K = np.diag(k + np.r_[k[1:], 0.0]) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    M = np.diag(m)
    if damping == "modal":
        D = modal_damping(M, K, np.linspace(0.01, 0.05, n))
    elif damping == "rayleigh":
        D = 0.8 * M + 2e-4 * K
    elif damping == "dashpot":          # one discrete dashpot: not diagonal in the modes
        D = np.zeros((n, n))
        D[0, 0] = 3.0
    else:
        D = None
    return make_linear_model(M, D, K)


def plate_reduced(damping):
    """Craig–Bampton model (with residual modes) of a small clamped shell plate, 3 boundary nodes."""
    from sarfe.fe import shell_matrices
    nx, ny = 8, 6
    x, y = np.meshgrid(np.linspace(0, 0.3, nx + 1), np.linspace(0, 0.2, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    index = np.arange(len(points)).reshape(nx + 1, ny + 1)
    a, b, c, d = (index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(),
                  index[:-1, 1:].ravel())
    triangles = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    K, M = shell_matrices(points, triangles, 2.5e-3, 2.2e9, 0.35, 1050.0)
    clamped = np.flatnonzero(np.isclose(points[:, 0], 0.0))
    k_ff, m_ff, free = free_dofs_system(K, M, (6 * clamped[:, None] + np.arange(6)).ravel())
    nodes = index[[nx, nx, nx // 2], [0, ny, ny // 2]]
    position = {dof: i for i, dof in enumerate(free)}
    boundary = np.array([position[6 * node + 2] for node in nodes])       # z translations
    reduced = craig_bampton(k_ff, m_ff, boundary, cutoff_hz=2000.0, residual_vectors=True)
    Kr, Mr = reduced.stiffness, reduced.mass
    D = {"modal": modal_damping(Mr, Kr, 0.03), "rayleigh": 5.0 * Mr + 1e-5 * Kr,
         "none": None}[damping]
    return make_linear_model(Mr, D, Kr)


def excitation(n, seed=0):
    F = np.random.default_rng(seed).normal(size=(2 * H + 1, n))
    return F


def compare_paths(model, G, omega, orders=None):
    F = excitation(model.dof_count)
    basis = modal_basis(model)
    assert basis is not None
    modal = condense(model, G, F, omega, orders, modal=basis)
    direct = condense(model, G, F, omega, orders, modal=False)
    assert modal.modal is not None and direct.modal is None
    assert relative(modal.compliance, direct.compliance) < 1e-10
    assert relative(modal.linear_response, direct.linear_response) < 1e-10
    assert relative(modal.forced, direct.forced) < 1e-10
    assert relative(modal.admittance, direct.admittance) < 1e-10
    force = np.random.default_rng(1).normal(size=(2 * H + 1, G.shape[0]))
    U = recover_displacement(direct, force)
    assert relative(recover_displacement(modal, force), U) < 1e-10
    assert relative(condensed_omega_derivative(model, modal, U),
                    condensed_omega_derivative(model, direct, U)) < 1e-10
    # ∂R_c/∂ω from λ̃ in modal coordinates = G Z⁻¹ Z' ũ of the factorization, and = the central
    # difference of R_c(r̃, ω) = r̃ − r̃_lin(ω) + C(ω) λ̃ at fixed r̃, λ̃
    derivative = modal_omega_derivative(modal, force)
    assert relative(derivative, condensed_omega_derivative(model, direct, U)) < 1e-10
    h = 1e-6 * omega
    plus, minus = (condense(model, G, F, omega + s, orders, modal=False) for s in (h, -h))
    rows = np.arange(2 * H + 1) if orders is None else coefficient_rows(orders)
    fd = ((plus.compliance - minus.compliance) @ force[rows].ravel()
          - (plus.linear_response - minus.linear_response)[rows].ravel()) / (2 * h)
    assert relative(derivative[rows].ravel(), fd) < 1e-5
    # C applied block by block (block diagonal over the kept orders) = the dense product
    B = np.random.default_rng(2).normal(size=(direct.compliance.shape[0], 7))
    for cond in (modal, direct):
        assert relative(cond.apply_compliance(B), cond.compliance @ B) < 1e-13
        assert relative(cond.apply_compliance(sp.csr_matrix(B)), cond.compliance @ B) < 1e-13


@pytest.mark.parametrize("damping", ["modal", "rayleigh", "none"])
def test_lumped_modal_path_equals_factorization(damping):
    model = chain(damping=damping)
    G = sp.csr_matrix(np.array([[1.0, -1.0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1.0]]))
    omega = 17.3     # between resonances (undamped case must stay regular)
    compare_paths(model, G, omega)
    compare_paths(model, G, omega, orders=np.array([1, 3, 5]))
    sparse = make_linear_model(*(sp.csr_matrix(a) for a in (model.mass, model.damping,
                                                            model.stiffness)))
    compare_paths(sparse, G, omega)
    for _ in range(2):      # 'auto' keeps the sparse LU for sparse models
        assert condense(sparse, G, excitation(6), omega).modal is None


@pytest.mark.parametrize("damping", ["modal", "rayleigh", "none"])
def test_reduced_fe_modal_path_equals_factorization(damping):
    model = plate_reduced(damping)
    G = sp.csr_matrix(np.eye(3, model.dof_count))           # the three boundary z translations
    for omega in (2 * np.pi * 37.0, 2 * np.pi * 151.0):
        compare_paths(model, G, omega)


def test_mode_range_damping_takes_the_modal_path():
    """ζ per mode range (the instrument panel's 0.03 for modes 1–10, 0.05 above) on a reduced
    plate: D is diagonal in the modes by construction, and the round-off of the two eigen-solves
    (K φ = ω² M φ for D, M v = μ K v for the basis) leaves off-diagonal terms ~1e-10 of the
    diagonal — the 1e-10 acceptance bound sent such models to the per-harmonic LU (the 20–200 Hz
    instrument-panel sweep: 1570 dense solves, 327 s of 675 s). Accepted, the modal condensation
    equals the factorization's to the same round-off."""
    reduced = plate_reduced("none")
    zeta = np.where(np.arange(reduced.dof_count) < 10, 0.03, 0.05)
    model = make_linear_model(reduced.mass, modal_damping(reduced.mass, reduced.stiffness, zeta),
                              reduced.stiffness)
    basis = modal_basis(model)
    assert basis is not None
    projected = basis.modes.T @ model.damping @ basis.modes
    off = np.abs(projected - np.diag(np.diag(projected)))
    roundoff = (off / np.sqrt(np.outer(basis.damping, basis.damping))).max()
    assert 1e-12 < roundoff and 10 * roundoff < MODAL_DAMPING_TOLERANCE     # measured 9.2e-11
    G = sp.csr_matrix(np.eye(3, model.dof_count))
    for omega in (2 * np.pi * 37.0, 2 * np.pi * 151.0):
        compare_paths(model, G, omega)


def test_single_dof_closed_form():
    """m ü + c u̇ + k u: C_k = 1 / (k − (kω)² m + i kω c) per harmonic (cos/sin blocks)."""
    m, c, k = 0.7, 0.9, 1.3e3
    model = make_linear_model([[m]], [[c]], [[k]])
    omega = 25.0
    F = np.zeros((2 * H + 1, 1))
    F[1, 0] = 2.0
    cond = condense(model, sp.csr_matrix([[1.0]]), F, omega, modal=modal_basis(model))
    assert cond.modal is not None
    order = np.arange(1, H + 1)
    z = 1.0 / (k - (order * omega) ** 2 * m + 1j * order * omega * c)
    np.testing.assert_allclose(cond.compliance[0, 0], 1.0 / k, rtol=1e-12)
    np.testing.assert_allclose(cond.compliance[2 * order - 1, 2 * order - 1], z.real, rtol=1e-12)
    np.testing.assert_allclose(cond.compliance[2 * order - 1, 2 * order], z.imag, rtol=1e-12)
    np.testing.assert_allclose(cond.linear_response[1:3, 0], [2.0 * z[0].real, -2.0 * z[0].imag],
                               rtol=1e-12)


def test_dynamic_stiffness_matrix_reuses_its_pattern():
    """S(ω) from the cached Kronecker parts acts like the harmonic-by-harmonic product S(ω) ũ
    (cos rows K u_c − k²ω² M u_c + kω D u_s, sin rows … − kω D u_c) at several ω."""
    from sarfe.hbm.dynamic_stiffness import apply_dynamic_stiffness, dynamic_stiffness_matrix

    for model in (chain(damping="dashpot"), chain(damping="rayleigh")):
        U = np.random.default_rng(2).normal(size=(2 * H + 1, model.dof_count))
        for omega in (3.0, 17.3, 40.0):
            S = dynamic_stiffness_matrix(model, omega, H)
            np.testing.assert_allclose(S @ U.ravel(), apply_dynamic_stiffness(model, omega, U).ravel(),
                                       rtol=1e-13, atol=1e-12 * np.abs(S).max())


def test_non_proportional_damping_falls_back():
    model = chain(damping="dashpot")
    assert modal_basis(model) is None
    assert cached_modal_basis(model) is None and cached_modal_basis(model) is None
    G = sp.csr_matrix(np.eye(2, 6))
    F = excitation(6)
    auto = condense(model, G, F, 17.3)
    direct = condense(model, G, F, 17.3, modal=False)
    assert auto.modal is None
    np.testing.assert_array_equal(auto.compliance, direct.compliance)


def test_auto_uses_the_cached_basis_and_singular_points():
    model = chain(damping="none")
    G = sp.csr_matrix(np.eye(1, 6))
    F = excitation(6)
    assert condense(model, G, F, 17.3).modal is None      # first condensation: factorized
    first = condense(model, G, F, 19.0)
    assert first.modal is not None and cached_modal_basis(model) is first.modal.basis
    assert condense(model, G, F, 21.0).modal.basis is first.modal.basis
    # undamped resonance of harmonic 1: singular on both paths
    omega_1 = first.modal.basis.natural_frequencies[0]
    assert condense(model, G, F, omega_1) is None
    assert condense(model, G, F, omega_1, modal=False) is None


def nlvib03(H03=21):
    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    model = make_linear_model(np.eye(2), 0.03 * K, K)
    contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]], 1.0, 100.0)
    F = np.zeros((2 * H03 + 1, 2))
    F[1, 1] = 0.1
    return model, contacts, F


def test_solutions_unchanged(monkeypatch):
    """NLvib example 03 (sweep through the folds) and a friction point on the reduced plate: the
    modal path gives the factorization path's solutions to solver tolerance."""
    model, contacts, F = nlvib03()
    options = ContinuationOptions(max_step=0.3, solver=SolverOptions(stability=False))
    modal = continuation(model, contacts, F, 0.5, 0.8, 21, 1024, options=options)
    plate = plate_reduced("modal")
    G = sp.csr_matrix(np.eye(3, plate.dof_count))
    friction = make_contact_set(G, ["squeak"], [0], [[1, -1]], -1e-5, 5e4,
                                tangential_stiffness=2e4, friction_coefficient=0.3, normal_load=0.5)
    Fp = np.zeros((2 * H + 1, plate.dof_count))
    Fp[1, 0] = 1.0
    Fp[1, 1] = 1.0
    point = solve_frequency(plate, friction, Fp, 2 * np.pi * 40.0, H, 128)

    original = linear.condense
    monkeypatch.setattr(linear, "cached_modal_basis", lambda model: None)
    direct = continuation(model, contacts, F, 0.5, 0.8, 21, 1024, options=options)
    point_direct = solve_frequency(plate, friction, Fp, 2 * np.pi * 40.0, H, 128)
    assert linear.condense is original
    assert len(modal) == len(direct)
    for a, b in zip(modal, direct):
        assert abs(a.omega - b.omega) < 1e-8
        assert relative(a.displacement, b.displacement) < 1e-7
    assert point.converged and point_direct.converged
    assert relative(point.displacement, point_direct.displacement) < 1e-7


@pytest.mark.slow
@pytest.mark.parametrize("name", ["lumped_rattle", "squeak_rig", "instrument_panel", "door_trim"])
def test_shipped_cases_unchanged(name, monkeypatch):
    """Each shipped case (defaults: estimate and stability on) with the modal path and with the
    factorization forced: same points, ERP power and contact amplitudes to 10⁻⁴ relative, same
    stability verdicts. (The door trim differs by ~10⁻⁵ at 80 Hz, where a squeak spot sticks the
    whole period and the periodic solution is not unique; elsewhere 10⁻¹² or better. The rattle
    rig, a 193-point sweep, was compared once by hand: see docs/performance.md.)"""
    from pathlib import Path

    from sarfe.pipeline import load_case, solve_case

    path = Path(__file__).resolve().parents[2] / "cases" / f"{name}.yaml"
    modal = solve_case(load_case(path), write=False).summary["points"]
    monkeypatch.setattr(linear, "cached_modal_basis", lambda model: None)
    direct = solve_case(load_case(path), write=False).summary["points"]
    assert len(modal) == len(direct)
    for a, b in zip(modal, direct):
        assert a["frequency_hz"] == pytest.approx(b["frequency_hz"], rel=1e-9)
        assert a["erp"]["power_W"] == pytest.approx(b["erp"]["power_W"], rel=1e-4)
        assert a.get("stable") == b.get("stable")
        # (no normal DOF: the normal amplitude is None or NaN)
        amplitude_a, amplitude_b = (np.nan_to_num(np.array(
            [c.get("normal_amplitude_m") or 0.0 for c in p["contacts"]], dtype=float))
            for p in (a, b))
        assert np.abs(amplitude_a - amplitude_b).max() <= 1e-4 * max(np.abs(amplitude_b).max(), 1e-30)


def test_low_rank_update_equals_the_dense_solve():
    """(Z_k + Gᵀ diag(k_r + i kω c_r) G)⁻¹ f_k by Woodbury on the modal Z_k⁻¹ (the linearized
    contacts of a Newton start and of the onset's rest state) equals the dense solve of the
    updated matrices, at the mean and at harmonics across resonances."""
    from sarfe.hbm.modal import updated_solve

    model = plate_reduced("modal")
    basis = modal_basis(model)
    n = model.dof_count
    G = np.eye(3, n)
    rng = np.random.default_rng(4)
    k_rows, c_rows = np.array([2e4, 0.0, 5e3]), np.array([0.0, 3.0, 1.0])
    orders = np.array([0, 1, 2, 5])
    omega = 2 * np.pi * 41.0
    loads = rng.normal(size=(orders.size, n)) + 1j * rng.normal(size=(orders.size, n))
    z = updated_solve(basis, G, k_rows, c_rows, orders, omega, loads)
    K = model.stiffness + G.T @ np.diag(k_rows) @ G
    D = model.damping + G.T @ np.diag(c_rows) @ G
    for i, k in enumerate(orders):
        w = k * omega
        direct = np.linalg.solve(K - w * w * model.mass + 1j * w * D, loads[i])
        assert relative(z[i], direct) < 1e-10
