"""Tabulated force–deflection law (optional Jenkins friction): the penalty law as a straight table,
describing function of a stiffening curve vs closed form, the spline, Jacobians in every state,
HBM vs time integration, Hill vs time integration, the case file (pairs and CSV)."""
import math

import numpy as np
import pytest
import scipy.sparse as sp
from law_checks import aft_errors, step_error

from sarfe.hbm import make_contact_set, make_linear_model, solve_frequency
from sarfe.hbm.aft import contact_forces, jacobian_matrix
from sarfe.hbm.laws import tabulated
from sarfe.hbm.time_integration import integrate_time


def table(points, interpolation="linear", **friction):
    parameters = {k: v[None] for k, v in tabulated.curve_table(points, interpolation).items()}
    return dict(parameters, **friction)


def test_straight_table_is_the_penalty_law():
    """A straight line through the origin with slope k reproduces rattle (k, same gap) to 1e-12:
    forces and Jacobian, open, impacting and closed, both interpolations."""
    G = sp.csr_matrix([[1.0]])
    R = np.zeros((7, 1))
    R[0], R[1], R[4] = 1e-4, 3e-3, 5e-4
    for interpolation in ("linear", "monotone_spline"):
        for gap in (5.0, 2e-4, -5.0):
            line = make_contact_set(G, ["tabulated"], [0], [[-1, -1]], gap, parameters=table(
                [[0.0, 0.0], [1e-3, 50.0], [2e-3, 100.0], [4e-3, 200.0]], interpolation))
            penalty = make_contact_set(G, ["rattle"], [0], [[-1, -1]], gap, 5e4)
            a, b = contact_forces(line, R, 256), contact_forces(penalty, R, 256)
            scale = max(np.abs(b.force).max(), 1e-300)
            assert np.abs(a.force - b.force).max() <= 1e-12 * max(scale, 5e4 * 3e-3)
            Ja = jacobian_matrix(a.blocks, 1, 3, dense=True)
            Jb = jacobian_matrix(b.blocks, 1, 3, dense=True)
            assert np.abs(Ja - Jb).max() <= 1e-12 * 5e4
            assert np.array_equal(a.state, b.state)


def test_describing_function_of_a_stiffening_curve():
    """Bilinear curve (k1 to δ1, then k2) at w = a cos θ, g = 0: λ = k1 max(0, x) +
    (k2 − k1) max(0, x − δ1), and (1/π)∫ k max(0, a cos θ − e) cos θ dθ =
    (k/π)[a(φ + sin φ cos φ) − 2e sin φ], φ = arccos(e/a)."""
    k1, k2, d1, a = 1e4, 5e4, 1e-3, 3e-3
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["tabulated"], [0], [[-1, -1]], 0.0,
                                parameters=table([[0, 0], [d1, k1 * d1], [2 * d1, k1 * d1
                                                                            + k2 * d1]]))
    R = np.zeros((3, 1))
    R[1] = a

    def term(k, e):
        phi = math.acos(e / a)
        return k / math.pi * (a * (phi + math.sin(phi) * math.cos(phi)) - 2 * e * math.sin(phi))
    force = contact_forces(contacts, R, 2 ** 14).force
    assert force[1, 0] == pytest.approx(term(k1, 0.0) + term(k2 - k1, d1), rel=1e-6)
    assert abs(force[2, 0]) < 1e-9 * abs(force[1, 0])          # no dissipation


def test_monotone_spline_is_scipy_pchip_and_linear_beyond():
    from scipy.interpolate import PchipInterpolator

    points = np.array([[0, 0], [0.5e-3, 2.0], [1e-3, 10.0], [2e-3, 60.0], [3e-3, 80.0]])
    p = table(points, "monotone_spline")
    p["force_scale"] = np.ones(1)
    delta = np.linspace(1e-6, 3e-3, 97)[:, None]
    force, slope = tabulated.curve_force(p, delta)
    spline = PchipInterpolator(points[:, 0], points[:, 1])
    assert np.abs(force[:, 0] - spline(delta[:, 0])).max() < 1e-12 * 80
    assert np.abs(slope[:, 0] - spline.derivative()(delta[:, 0])).max() < 1e-9 * 8e4
    beyond, _ = tabulated.curve_force(p, np.array([[4e-3]]))
    assert beyond[0, 0] == pytest.approx(80.0 + 1e-3 * float(spline.derivative()(3e-3)))
    assert tabulated.static_deflection(p, np.array([10.0]))[0] == pytest.approx(1e-3, rel=1e-12)


def friction_contact(directions=1, gap=-2e-4):
    G = sp.csr_matrix(np.eye(3))
    tangent = [[1, -1]] if directions == 1 else [[1, 2]]
    return make_contact_set(G, ["tabulated"], [0], tangent, gap, parameters=table(
        [[0, 0], [1e-4, 1.0], [3e-4, 8.0], [6e-4, 20.0]], "monotone_spline",
        tangential_stiffness=3e4, friction_coefficient=0.4))


@pytest.mark.parametrize("state, gap", [("open", 5e-3), ("closed", -1e-3), ("impacting", 1e-4)])
def test_normal_jacobian_in_every_state(state, gap):
    contacts = make_contact_set(sp.csr_matrix([[1.0]]), ["tabulated"], [0], [[-1, -1]], gap,
                                parameters=table([[0, 0], [1e-4, 1.0], [3e-4, 8.0]],
                                                 "monotone_spline"))
    R = np.zeros((7, 1))
    R[0], R[1], R[2], R[3] = 1e-5, 2e-4, 1e-4, 3e-5
    jac, omega, _ = aft_errors(contacts, R, 256, 3.0)
    assert jac < 1e-6 and omega == 0.0
    assert step_error(contacts, np.array([gap + 5e-5]), np.array([gap]), np.zeros(1),
                      np.zeros((0, 2)), 1e-3) < 1e-6


@pytest.mark.parametrize("state, amplitude", [("stick", 1e-6), ("slip", 1e-3)])
@pytest.mark.parametrize("directions", [1, 2])
def test_friction_jacobian_in_stick_and_slip(state, amplitude, directions):
    contacts = friction_contact(directions)
    R = np.zeros((7, 3))
    R[0, 0], R[1, 0], R[1, 1], R[2, 1], R[1, 2] = 1e-4, 5e-5, amplitude, 0.3 * amplitude, \
        0.5 * amplitude * (directions == 2)
    jac, omega, _ = aft_errors(contacts, R, 128, 2.0)
    assert jac < 1e-5 and omega == 0.0
    slider = np.zeros((1, 2)) if state == "stick" else np.array([[-3e-3, 1e-3]])
    r = np.array([4e-4, 1e-6, 5e-7 if directions == 2 else 0.0])
    assert step_error(contacts, r, r, np.zeros(3), slider, 1e-3) < 1e-6


def squeak_model(harmonics):
    """3 DOF: driven mass x0 – spring – part with tangential DOF x1 and normal DOF x2, pressed on
    a measured stiffening pad (0.2 mm overclosure) with friction μ = 0.4, k_t = 3e4 N/m; the
    normal DOF is shaken too, so the slip limit varies over the period. 12 Hz."""
    M = np.diag([1.0, 0.3, 0.3])
    K = np.array([[2e4, -1e4, 0.0], [-1e4, 1e4, 0.0], [0.0, 0.0, 2e4]])
    model = make_linear_model(M, 2e-4 * K + 2.0 * M, K)
    G = sp.csr_matrix([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
    contacts = make_contact_set(G, ["tabulated"], [0], [[1, -1]], -2e-4, parameters=table(
        [[0, 0], [1e-4, 2.0], [2e-4, 6.0], [4e-4, 20.0]], "monotone_spline",
        tangential_stiffness=3e4, friction_coefficient=0.4))
    F = np.zeros((2 * harmonics + 1, 3))
    F[1, 0], F[1, 2], F[2, 2] = 15.0, 3.0, 1.0
    return model, contacts, F


def first_harmonic(U):
    return U[1] - 1j * U[2]


@pytest.mark.parametrize("frequency", [12.0, pytest.param(20.0, marks=pytest.mark.slow)])
def test_hbm_matches_time_integration_and_hill(frequency):
    """HBM at H = 15 within 0.5 % of Newmark (1024 steps, Richardson, from the H = 30 solution);
    Hill says stable and Newmark stays on the orbit; the contact slips part of the period."""
    omega = 2 * np.pi * frequency
    model, contacts, F = squeak_model(30)
    reference = solve_frequency(model, contacts, F, omega, 30, 2048)
    run = integrate_time(model, contacts, F, omega, 30, 1024, initial=reference, richardson=True)
    assert run.steady
    target = first_harmonic(run.displacement_harmonics)
    model, contacts, F = squeak_model(15)
    solution = solve_frequency(model, contacts, F, omega, 15, 2048)
    assert solution.converged and solution.stable is True
    error = np.abs(first_harmonic(solution.displacement) - target).max() / np.abs(target).max()
    assert error < 5e-3
    assert 0.0 < np.mean(solution.contact_state == 2) < 1.0


CASE = {
    "name": "pad",
    "model": {"matrices": {"mass": [[0.3, 0.0], [0.0, 0.3]],
                           "stiffness": [[2e4, 0.0], [0.0, 1e4]]}},
    "damping": {"modal_zeta": 0.02},
    "contacts": [{"name": "pad", "type": "tabulated", "normal_dof": 0, "tangential_dofs": [1],
                  "preload_N": 6.0, "curve": [[1e-4, 2.0], [2e-4, 6.0], [4e-4, 20.0]],
                  "interpolation": "monotone_spline", "tangential_stiffness_N_m": 3e4,
                  "friction_coefficient": 0.4}],
    "excitation": {"forces": [{"dof": 1, "force_N": 1.0}], "frequency_hz": [20.0]},
    "solver": {"harmonics": 5, "samples_per_period": 256, "error_estimate": False},
}


def test_case_file_pairs_csv_and_preload(tmp_path):
    """Pairs in the case and the same curve in a CSV give the same contact; preload_N sets the
    overclosure from the curve: F(−g − C λ) = 6 N with the static compliance C = 1/2e4."""
    import copy

    from sarfe.case.errors import CaseError
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model

    case = load_case(CASE)
    nl = nonlinear_model(case, build_linear_model(case))
    assert nl.contacts.gap[0] == pytest.approx(-(2e-4 + 6.0 / 2e4), rel=1e-12)
    (tmp_path / "pad.csv").write_text("deflection_m,force_N\n1e-4,2.0\n2e-4,6.0\n4e-4,20.0\n")
    from_file = copy.deepcopy(CASE)
    del from_file["contacts"][0]["curve"]
    from_file["contacts"][0]["curve_file"] = "pad.csv"
    import yaml
    path = tmp_path / "pad.yaml"
    path.write_text(yaml.safe_dump(from_file))
    case_file = load_case(path)
    nl_file = nonlinear_model(case_file, build_linear_model(case_file))
    for key in ("curve_breakpoints", "curve_coefficients"):
        assert np.array_equal(nl.contacts.parameters[key], nl_file.contacts.parameters[key])
    bad = copy.deepcopy(CASE)
    bad["contacts"][0]["curve"] = [[1e-4, 2.0], [2e-4, 1.0]]
    with pytest.raises(CaseError, match=r"contacts\[0\]\.curve: forces must not decrease"):
        load_case(bad)
    half = copy.deepcopy(CASE)
    del half["contacts"][0]["friction_coefficient"]
    with pytest.raises(CaseError, match="friction_coefficient: missing required key"):
        load_case(half)


def test_preload_above_a_plateau_is_an_input_error_and_a_rising_curve_extends_linearly():
    """A curve ending flat at 1 N cannot carry 2 N: the case names contacts[0].preload_N and its
    line; the law itself refuses (no 1e300 m deflection). A rising last piece (slope k) carries
    any force on the docs' linear extension: δ = δ_S + (P − F_S)/k exactly."""
    import copy

    from sarfe.case.errors import CaseError
    from sarfe.pipeline import load_case

    plateau = copy.deepcopy(CASE)
    plateau["contacts"][0]["curve"] = [[0, 0], [1e-3, 1.0], [2e-3, 1.0]]
    plateau["contacts"][0]["preload_N"] = 2.0
    with pytest.raises(CaseError, match=r"contacts\[0\]\.preload_N: 2 N is above the curve's "
                                        r"largest force 1 N"):
        load_case(plateau)
    for interpolation in ("linear", "monotone_spline"):
        flat = table([[0, 0], [1e-3, 1.0], [2e-3, 1.0]], interpolation, force_scale=np.ones(1))
        with pytest.raises(ValueError, match="above the largest force 1 N"):
            tabulated.static_deflection(flat, np.array([2.0]))
        below = tabulated.static_deflection(flat, np.array([0.5]))
        assert tabulated.curve_force(flat, below[None])[0][0, 0] == pytest.approx(0.5, rel=1e-9)
    rising = table([[0, 0], [1e-3, 10.0], [2e-3, 30.0]], force_scale=np.ones(1))  # slope 2e4 N/m
    assert tabulated.static_deflection(rising, np.array([70.0]))[0] == pytest.approx(
        2e-3 + 40.0 / 2e4, rel=1e-9)
    silent = copy.deepcopy(CASE)
    silent["contacts"][0]["curve"] = [[0, 0], [1e-3, 0.0]]
    with pytest.raises(CaseError, match=r"contacts\[0\]\.curve: all forces are 0"):
        load_case(silent)


@pytest.mark.parametrize("text", [
    "# pad, measured 2026\ndeflection_m,force_N\n1e-4,2.0\n2e-4,6.0\n4e-4,20.0\n",
    "deflection_m,force_N  # header\n# comment\n1e-4,2.0\n2e-4,6.0\n\n4e-4,20.0\n",
    "# only comments, no header\n1e-4,2.0\n2e-4,6.0\n4e-4,20.0\n"])
def test_curve_file_comments_and_one_header(tmp_path, text):
    """'#' comments anywhere and one header line (docs/case-file.md) give the same curve as the
    pairs in the case; a second non-numeric line is an error naming the file's line."""
    path = tmp_path / "pad.csv"
    path.write_text(text)
    points = tabulated.read_curve_file(path)
    assert np.allclose(points, [[1e-4, 2.0], [2e-4, 6.0], [4e-4, 20.0]], rtol=1e-15)
    path.write_text(text + "5e-4,abc\n")
    with pytest.raises(tabulated.LawInputError, match=r"pad.csv line \d+: not two numbers"):
        tabulated.read_curve_file(path)
