"""A curved contact partner (sarfe.hbm.laws.curvature): the normal force follows the slide.

Physics asserted: the penetration w − g − ½ Σ κ_i q_i² of two curved surfaces under a relative
slide (closed forms of the imposed-motion AFT in the stuck and sliding limits, the 2nd harmonic
k_n κ a²/4 of a harmonic slide, no variation for a circular slide over a sphere), the exact AFT
Jacobian (finite differences), the HBM periodic response against the independent Newmark time
integration, and Hill's operator at s → 0 equal to the AFT Jacobian with the coupling.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm import harmonics as hm
from sarfe.hbm.aft import contact_forces, jacobian_matrix
from sarfe.hbm.contacts import make_contact_set
from sarfe.hbm.laws import LawInputError, law
from sarfe.hbm.laws.curvature import prepare
from sarfe.hbm.residual import Problem, full_residual
from sarfe.hbm.stability.contact_terms import ContactOperator
from sarfe.hbm.stability.perturbation import perturbation_check
from sarfe.hbm.time_integration import integrate_time
from tests.hbm.stability.test_stability import friction_chain
from tests.hbm.test_hbm_vs_time import squeak_model

K_N, K_T, DELTA0 = 1e4, 5e3, 1e-4          # N/m, N/m, m (static penetration at q = 0)


def imposed(kappa, q_of_theta, mu, two_d=False, H=6, N=256):
    """AFT of one squeak contact (rows: w, q1[, q2]) at w ≡ 0, gap −δ0 and the slide q(θ)."""
    rows = 3 if two_d else 2
    contacts = make_contact_set(sp.identity(rows, format="csr"), ["squeak"], [0],
                                [[1, 2]] if two_d else [[1, -1]], gap=-DELTA0,
                                normal_stiffness=K_N, tangential_stiffness=K_T,
                                friction_coefficient=mu,
                                parameters={"partner_curvature_1": kappa[0],
                                            "partner_curvature_2": kappa[1]})
    theta = 2 * np.pi * np.arange(N) / N
    r = np.zeros((N, rows))
    r[:, 1:] = q_of_theta(theta)
    R = hm.harmonic_coefficients(r, H)
    return contact_forces(contacts, R, N), theta, hm.time_samples(R, N)


@pytest.mark.parametrize("radius", [0.05, -0.05])
def test_stuck_slide_normal_force_closed_form(radius):
    """Stuck (μ large): λ_n = k_n (δ0 − κ q²/2), λ_t = k_t q − κ q λ_n; a convex partner (R > 0)
    unloads the contact as it slides, a concave one loads it; 2nd harmonic −k_n κ a²/4."""
    kappa, a = 1.0 / radius, 1e-3
    out, theta, r = imposed((kappa, 0.0), lambda t: a * np.cos(t)[:, None], mu=100.0)
    q = r[:, 1]
    normal = K_N * (DELTA0 - 0.5 * kappa * q * q)
    assert np.all(out.state == 1)
    assert np.abs(out.force_time[:, 0] - normal).max() <= 1e-10 * K_N * DELTA0
    tangential = K_T * q - kappa * q * normal
    assert np.abs(out.force_time[:, 1] - tangential).max() <= 1e-10 * K_T * a
    # harmonics of λ_n: mean k_n (δ0 − κa²/4), cos 2θ −k_n κ a²/4, nothing else
    assert out.force[0, 0] == pytest.approx(K_N * (DELTA0 - kappa * a * a / 4), rel=1e-10)
    assert out.force[3, 0] == pytest.approx(-K_N * kappa * a * a / 4, rel=1e-10)
    assert np.abs(np.delete(out.force[:, 0], [0, 3])).max() <= 1e-10 * K_N * DELTA0
    assert np.sign(out.force[3, 0]) == -np.sign(radius)


def test_sliding_limit_friction_follows_the_normal_force():
    """Sliding (μ small, the slider slips almost all period): during slip λ_t − (−κqλ_n) is
    ±μ λ_n with λ_n = k_n (δ0 − κq²/2), so the friction force also carries the 2nd harmonic."""
    kappa, a, mu = 1.0 / 0.02, 1e-3, 0.05
    out, theta, r = imposed((kappa, 0.0), lambda t: a * np.cos(t)[:, None], mu=mu)
    q = r[:, 1]
    normal = K_N * (DELTA0 - 0.5 * kappa * q * q)
    slip = out.state[:, 0] == 2
    assert slip.mean() > 0.9
    friction = out.force_time[:, 1] + kappa * q * normal
    assert np.abs(np.abs(friction[slip]) - mu * normal[slip]).max() <= 1e-10 * mu * K_N * DELTA0


def test_circular_slide_over_a_sphere_keeps_the_approach():
    """A slide on the circle |q| = a over a sphere: q₁² + q₂² = a² constant, λ_n constant
    k_n (δ0 − κa²/2); over a cylinder (κ₂ = 0) it varies at 2θ as for a 1-D slide."""
    kappa, a = 1.0 / 0.05, 1e-3
    circle = lambda t: a * np.column_stack([np.cos(t), np.sin(t)])  # noqa: E731
    sphere, _, _ = imposed((kappa, kappa), circle, mu=100.0, two_d=True)
    assert np.abs(sphere.force_time[:, 0] - K_N * (DELTA0 - 0.5 * kappa * a * a)).max() \
        <= 1e-10 * K_N * DELTA0
    cylinder, _, _ = imposed((kappa, 0.0), circle, mu=100.0, two_d=True)
    assert cylinder.force[3, 0] == pytest.approx(-K_N * kappa * a * a / 4, rel=1e-10)


@pytest.mark.parametrize("amplitude, mu", [(1.5e-2, 0.3), (2e-3, 0.6), (2e-3, 50.0)])
def test_aft_jacobian_matches_finite_differences(amplitude, mu):
    """1-D and 2-D curved contacts (convex, concave, cylinder) and a flat one, in slip,
    stick–slip, separation and stick: the analytic AFT Jacobian to 1e-8 of central
    differences (the slide moves the normal force, its tangential components and the slip limit)."""
    rng = np.random.default_rng(3)
    H, N = 4, 64
    contacts = make_contact_set(
        sp.identity(7, format="csr"), ["squeak"] * 3, [0, 2, 5], [[1, -1], [3, 4], [6, -1]],
        gap=-2e-3, normal_stiffness=1e3, tangential_stiffness=2e3, friction_coefficient=mu,
        parameters={"partner_curvature_1": [40.0, -30.0, 0.0],
                    "partner_curvature_2": [0.0, 25.0, 0.0]})
    X = 1e-3 * rng.standard_normal((2 * H + 1, 7)) / (1 + np.arange(2 * H + 1))[:, None]
    X[0, [0, 2, 5]] = 0.0
    X[1, [1, 3, 6]] += amplitude
    X[2, 4] += 0.7 * amplitude
    J = jacobian_matrix(contact_forces(contacts, X, N).blocks, 7, H, dense=True)
    h, flat = 1e-8, X.ravel()
    J_fd = np.zeros_like(J)
    for c in range(flat.size):
        e = np.zeros_like(flat)
        e[c] = h
        plus = contact_forces(contacts, (flat + e).reshape(X.shape), N, jacobian=False).force
        minus = contact_forces(contacts, (flat - e).reshape(X.shape), N, jacobian=False).force
        J_fd[:, c] = (plus - minus).ravel() / (2 * h)
    assert np.abs(J - J_fd).max() <= 1e-8 * np.abs(J_fd).max()


def curved_squeak_model(H, radius):
    """The 3-DOF lumped squeak model of tests/hbm/test_hbm_vs_time.py (driven mass x0 – spring –
    part with tangential DOF x1 and normal DOF x2; k_n = 4e4 N/m, 0.2 mm overclosure,
    k_t = 3e4 N/m, μ = 0.4, 12 Hz) without the constant load and the normal DOF's shaking,
    rubbing on a curved partner of radius R: stick–slip."""
    model, flat, _, omega = squeak_model(H)
    contacts = make_contact_set(flat.gap_map, ["squeak"], [0], [[1, -1]], gap=-2e-4,
                                normal_stiffness=4e4, tangential_stiffness=3e4,
                                friction_coefficient=0.4,
                                parameters={"partner_curvature_1": 1.0 / radius})
    F = np.zeros((2 * H + 1, 3))
    F[1, 0] = 15.0
    return model, contacts, F, omega


def curved_chain(two_d, kappa, omega):
    """The friction chain of tests/hbm/stability/test_stability.py on a curved partner κ (κ₁, κ₂)
    at ``omega``, H = 7, N = 256: (model, contacts, F, solution, Problem, full residual)."""
    model, flat = friction_chain(two_d)
    contacts = make_contact_set(flat.gap_map, ["squeak"], [0], flat.tangent_rows, -0.05, 5.0, 3.0,
                                0.3, 0.8, parameters={"partner_curvature_1": kappa[0],
                                                      "partner_curvature_2": kappa[1]})
    H, N = 7, 256
    F = np.zeros((2 * H + 1, 4))
    F[1, 2], F[2, 3] = 0.3, 0.2
    s = solve_frequency(model, contacts, F, omega, H, N)
    assert s.converged
    problem = Problem(model, contacts, F, H, N)
    return model, contacts, F, s, problem, full_residual(problem, s.displacement.ravel(), omega)


@pytest.mark.parametrize("radius, H", [(0.05, 18), (-0.05, 12)])
def test_hbm_matches_newmark_time_integration(radius, H):
    """The periodic response (all DOFs, harmonics 0–3) and the normal force's 2nd harmonic of
    HBM against Newmark (512 steps per period; Richardson with 1024 moves it by 3e-4) within
    1 %; the 2nd harmonic is
    there because of the curvature (the flat partner's normal DOF is not driven at 2ω).
    Measured against the Richardson reference: convex (the pad lifts off part of the period)
    7e-6 / 0.16 % at H = 18 (at H = 12 the 2nd harmonic is 0.96 % off: truncation), concave
    (slips 92 % of the period) 2e-4 / 0.02 % at H = 12."""
    model, contacts, F, omega = curved_squeak_model(H, radius)
    hbm = solve_frequency(model, contacts, F, omega, H, 512)
    assert hbm.converged
    reference = integrate_time(model, contacts, F, omega, H, steps_per_period=512, initial=hbm)
    assert reference.steady
    U, U_ref = hbm.displacement[:7], reference.displacement_harmonics[:7]
    assert np.abs(U - U_ref).max() <= 1e-2 * np.abs(U_ref).max()
    L, L_ref = np.asarray(hbm.contact_force), reference.contact_force_harmonics
    second = np.hypot(L[3, 0], L[4, 0])
    second_ref = np.hypot(L_ref[3, 0], L_ref[4, 0])
    assert second == pytest.approx(second_ref, rel=1e-2)
    assert second > 1e-2 * abs(L[0, 0])                      # a real 2nd harmonic
    flat = solve_frequency(*curved_squeak_model(H, 1e9)[:2], F, omega, H, 512)
    assert np.hypot(*np.asarray(flat.contact_force)[3:5, 0]) < 1e-2 * second


@pytest.mark.parametrize("two_d", [False, True])
def test_hill_operator_at_zero_is_the_aft_jacobian(two_d):
    """𝒥(s) → the AFT Jacobian as s → 0 with the curved coupling (normal rows' slide columns,
    the tangential components of λ_n, the slip limit moving with q): the correction vanishes."""
    _, _, _, s, problem, ev = curved_chain(two_d, (2.0, -1.5), 0.8)
    op = ContactOperator(problem, s.displacement, s.omega, ev.forces)
    assert op.has_memory
    assert abs(op.correction(1e-9)).max() < 1e-6 * abs(ev.jacobian).max()
    assert abs(op.correction(0.05)).max() > 1e-3 * abs(ev.jacobian).max()


def test_case_key_partner_radius():
    """partner_radius_m: one radius (both directions), two (null = flat), signs kept; 0 and a
    contact without a normal DOF are rejected naming the key."""
    assert prepare({"partner_radius_m": 0.05}) == pytest.approx(
        {"partner_curvature_1": 20.0, "partner_curvature_2": 20.0})
    assert prepare({"partner_radius_m": [-0.1, None]}) == pytest.approx(
        {"partner_curvature_1": -10.0, "partner_curvature_2": 0.0})
    assert prepare({}) == {}
    with pytest.raises(LawInputError, match="non-zero") as error:
        prepare({"partner_radius_m": 0.0})
    assert error.value.key == "partner_radius_m"
    with pytest.raises(LawInputError, match="normal DOF"):
        prepare({"partner_radius_m": 0.05, "tangential_dofs": [1]})
    assert "partner_radius_m" in law("squeak").keys()


def test_contact_dynamics_dissipation_balances_the_input_work():
    """On a curved partner the tangent rows also carry the normal force's components −κ q λ_n
    (conservative with the normal row); contact_dynamics' dissipated energy (the slider's
    Coulomb work) = the excitation's input work − viscous losses (periodic energy balance)."""
    from types import SimpleNamespace

    from sarfe.hbm.time_integration import period_work
    from sarfe.pipeline.post.contact_dynamics import contact_dynamics

    H = 15
    model, contacts, F, omega = curved_squeak_model(H, -0.05)
    s = solve_frequency(model, contacts, F, omega, H, 2048)
    assert s.converged
    nl = SimpleNamespace(contacts=contacts, groups=[("pad", "squeak", np.array([0]))])
    (record,) = contact_dynamics(s, nl)
    input_work, viscous, rows = period_work(s.displacement, F, np.asarray(model.damping),
                                            s.contact_displacement, s.contact_force, omega)
    # 2e-4 measured; the rows' force taken as the friction force would be 4.7e-3 off
    assert record["dissipated_energy_J"] == pytest.approx(input_work - viscous, rel=1e-3)
    assert record["slip_distance_m"] > 0


@pytest.mark.parametrize("curvature", [2.0, -2.0])
def test_hill_verdict_matches_the_time_integrators_monodromy(curvature):
    """A 4-mass friction chain (tests/hbm/stability/test_stability.py, ω = 0.4: stick–slip and
    stable on a flat partner) on a curved partner: Hill's verdict (the contact operator with the
    coupling) equals that of the Newmark period map's monodromy (the same law in time
    integration). Convex (κ = 2): the normal force's tangential component −κ q λ_n softens the
    contact, the orbit slips 79 % of the period and is unstable (exponent +0.57, matched);
    concave (κ = −2): stiffer, stuck all period, stable (the integrator's neutral slider
    direction, rate 0, carries no exponent to compare)."""
    model, contacts, F, s, _, _ = curved_chain(False, (curvature, 0.0), 0.4)
    assert np.mean(np.asarray(s.contact_state) == 2) == pytest.approx(0.79 if curvature > 0 else 0.0,
                                                                      abs=0.02)
    check = perturbation_check(model, contacts, F, s, steps_per_period=256, newton_steps=1)
    assert s.stable is check.stable
    full = solve_frequency(model, contacts, F, 0.4, 7, 256, initial=s,
                           options=SolverOptions(stability_method="full"))
    assert full.stable is check.stable
    assert s.stable is (curvature < 0)
    if curvature > 0:
        assert full.floquet_exponent == pytest.approx(check.rate, rel=0.4)


def test_case_file_partner_radius_reaches_the_solver():
    """partner_radius_m in a matrices case: the solved point equals the directly built curved model
    (the key becomes κ = 1/R), its contact indicators report the friction part (|λ_t| ≤ μ λ_n),
    and a radius on a contact without a normal DOF is an input error naming the key."""
    from sarfe.case.errors import CaseError
    from sarfe.pipeline import load_case, solve_case

    H = 12
    model, contacts, F, omega = curved_squeak_model(H, -0.05)
    M, K = np.diag([1.0, 0.3, 0.3]), np.array([[2e4, -1e4, 0.0], [-1e4, 1e4, 0.0], [0.0, 0.0, 2e4]])
    case = {
        "name": "curved",
        "model": {"matrices": {"mass": M.tolist(), "stiffness": K.tolist(),
                               "damping": (2e-4 * K + 2.0 * M).tolist()}},
        "contacts": [{"name": "pad", "type": "squeak", "normal_dof": 2, "tangential_dofs": [1],
                      "gap_m": -2e-4, "normal_stiffness_N_m": 4e4,
                      "tangential_stiffness_N_m": 3e4, "friction_coefficient": 0.4,
                      "partner_radius_m": -0.05}],
        "excitation": {"forces": [{"dof": 0, "force_N": 15.0}], "frequency_hz": [12.0]},
        "solver": {"harmonics": H, "samples_per_period": 512, "error_estimate": False,
                   "stability": False, "workers": 1},
        "erp": {"dofs": [2], "areas_m2": [0.01]},
    }
    result = solve_case(load_case(case), write=False)
    direct = solve_frequency(model, contacts, F, omega, H, 512)
    U = np.asarray(result.solutions[0].displacement)
    assert np.abs(U - direct.displacement).max() <= 1e-8 * np.abs(direct.displacement).max()
    (record,) = result.summary["points"][0]["contacts"]
    # it slips at the normal force's peak: μ λ_n,max (the rows' force there is 2 % above)
    assert record["peak_friction_force_N"] <= 0.4 * record["peak_normal_force_N"] * (1 + 1e-9)
    assert record["peak_friction_force_N"] == pytest.approx(0.4 * record["peak_normal_force_N"],
                                                            rel=1e-3)
    bad = dict(case, contacts=[dict(case["contacts"][0], preload_N=2.0)])
    del bad["contacts"][0]["normal_dof"], bad["contacts"][0]["gap_m"]
    del bad["contacts"][0]["normal_stiffness_N_m"]
    with pytest.raises(CaseError, match="partner_radius_m"):
        load_case(bad)


@pytest.mark.parametrize("radius", [0.05, -0.05])
def test_small_motion_is_the_linear_rest_structure(radius):
    """At a small excitation the contact sticks and the curved partner acts as the tangential
    spring k_t − κ λ_n,s (the geometric stiffness at the static normal force λ_n,s = k_n δ0
    shared with the normal DOF's spring 2e4: 8/3 N): the HBM response equals the linearized rest
    structure (the cold start and the pipeline's linear baseline,
    :func:`sarfe.hbm.solve.linearized_guess`) and the closed form of the stuck chain to 1e-6."""
    from sarfe.hbm.solve import linearized_guess, make_problem

    H = 3
    model, contacts, F, omega = curved_squeak_model(H, radius)
    F = 1e-3 * F
    hbm = solve_frequency(model, contacts, F, omega, H, 64)
    assert hbm.converged and np.all(np.asarray(hbm.contact_state) == 1)
    linear = linearized_guess(make_problem(model, contacts, F, H, 4 * H + 1), omega)
    U = np.asarray(hbm.displacement)
    assert np.abs(U[1:3] - linear[1:3]).max() <= 1e-6 * np.abs(linear[1:3]).max()
    # closed form: x0, x1 (masses 1, 0.3; K of the chain) with k_t − κ λ_n,s on x1
    static = 4e4 * 2e-4 * 2e4 / (4e4 + 2e4)
    K = np.array([[2e4, -1e4], [-1e4, 1e4]])
    stiffness = K + np.diag([0.0, 3e4 - static / radius])
    Z = stiffness - omega ** 2 * np.diag([1.0, 0.3]) + 1j * omega * (2e-4 * K + 2.0 * np.diag(
        [1.0, 0.3]))
    x = np.linalg.solve(Z, np.array([F[1, 0], 0.0]))               # u_c − i u_s
    assert np.abs(U[1, :2] - x.real).max() <= 1e-6 * np.abs(x).max()
    assert np.abs(U[2, :2] + x.imag).max() <= 1e-6 * np.abs(x).max()
    # the geometric stiffness is seen: without it x1 differs by ~ κ λ_n,s / k_t
    flat = np.linalg.solve(K + np.diag([0.0, 3e4]) - omega ** 2 * np.diag([1.0, 0.3])
                           + 1j * omega * (2e-4 * K + 2.0 * np.diag([1.0, 0.3])),
                           np.array([F[1, 0], 0.0]))
    assert abs(flat[1] - x[1]) > 1e-3 * abs(x[1])


def test_pruning_keeps_an_open_contact_that_the_slide_closes():
    """Open at rest (gap 0.1 mm) on a concave partner: the slide closes it (κ q²/2 > g) although
    the normal motion alone never would, so the screen keeps it; on a convex partner the slide
    only opens it further and the screen may drop it (the flat rule)."""
    from sarfe.hbm.pruning import NONLINEAR, OPEN, screen_contacts

    H = 5
    decisions = {}
    for radius in (-0.05, 0.05):
        model, curved, F, omega = curved_squeak_model(H, radius)
        contacts = make_contact_set(curved.gap_map, ["squeak"], [0], [[1, -1]], gap=1e-4,
                                    normal_stiffness=4e4, tangential_stiffness=3e4,
                                    friction_coefficient=0.4,
                                    parameters={"partner_curvature_1": 1.0 / radius})
        (decisions[radius],) = screen_contacts(model, contacts, F, [omega])
        if radius < 0:
            s = solve_frequency(model, contacts, F, omega, H, 256)
            assert s.converged and np.any(np.asarray(s.contact_state) != 0)   # it does close
    assert decisions[-0.05].decision == NONLINEAR
    assert decisions[0.05].decision == OPEN


@pytest.mark.parametrize("radius", [0.05, -0.05])
def test_stuck_normal_force_second_harmonic_closed_form(radius):
    """Dynamic stuck limit of the lumped model: the slide q = a_c cos ωt + a_s sin ωt moves the
    surface by κq²/2, whose 2nd harmonic S₂ = (κ/2)((a_c² − a_s²)/2 − i a_c a_s) drives the
    normal DOF (mass 0.3, spring 2e4, damping of the chain) through k_n:
    λ_n,2 = −k_n S₂ / (1 + k_n / Z_n(2ω)), Z_n(Ω) = 2e4 − 0.3 Ω² + iΩ c — the HBM's 2nd harmonic of
    the normal force within 1e-6 (measured 4e-8; higher orders in κq)."""
    H = 6
    model, contacts, F, omega = curved_squeak_model(H, radius)
    s = solve_frequency(model, contacts, 0.1 * F, omega, H, 256)
    assert s.converged and np.all(np.asarray(s.contact_state) == 1)
    R, L = np.asarray(s.contact_displacement), np.asarray(s.contact_force)
    a_c, a_s = R[1, 1], R[2, 1]
    S2 = 0.5 / radius * ((a_c ** 2 - a_s ** 2) / 2 - 1j * a_c * a_s)
    Omega = 2 * omega
    Zn = 2e4 - 0.3 * Omega ** 2 + 1j * Omega * (2e-4 * 2e4 + 2.0 * 0.3)
    closed = -4e4 * S2 / (1 + 4e4 / Zn)
    assert abs((L[3, 0] - 1j * L[4, 0]) - closed) <= 1e-6 * abs(closed)
