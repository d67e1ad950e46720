"""Two or more Floquet exponents right of −ε: the contact-row count locates them
(sarfe.hbm.stability.zeros) instead of handing over to the Ritz method. Against closed forms (an
analytic det with known zeros and poles; linear oscillators whose contact linearization — a
negative contact stiffness or dashpot — makes them diverge or flutter) and the full Hill method's
eigenvalues (NLvib example 03 through its period-doubling region)."""
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.hbm.harmonics import derivative_matrix
from sarfe.hbm.model import make_linear_model
from sarfe.hbm.stability.contour import upper_contour, winding_count
from sarfe.hbm.stability.rows import contact_row_counts
from sarfe.hbm.stability.zeros import located_zeros, power_sums, roots_of_power_sums
from tests.hbm.stability.test_stability_rows import sweep03  # noqa: F401  (the NLvib 03 sweep fixture)


def test_roots_of_power_sums_are_the_numbers():
    """Newton's identities: the power sums of {0.3 + 0.4i, 0.3 − 0.4i, −0.5, 0.1} give them back."""
    z = np.array([0.3 + 0.4j, 0.3 - 0.4j, -0.5, 0.1])
    sums = [np.sum(z ** j).real for j in range(z.size + 1)]
    found = roots_of_power_sums(sums)
    assert np.sort_complex(found) == pytest.approx(np.sort_complex(z), abs=1e-12)


def test_power_sums_of_a_finely_sampled_contour():
    """∮ w^j d log f / 2πi over the upper half (mirror for the lower) of a box around the zeros
    of f = (s − 1 − 2i)(s − 1 + 2i)(s − 0.5) e^{s/3}/(s + 4) (the pole outside): Σ z^j."""
    z = np.array([1 + 2j, 1 - 2j, 0.5])
    top, left, right = 3.0, -0.5, 3.0
    nodes = np.concatenate([right + 1j * top * np.linspace(0, 1, 400),
                            np.linspace(right, left, 400)[1:] + 1j * top,
                            left + 1j * top * np.linspace(1, 0, 400)[1:]])
    logs = np.log((nodes[:, None] - z[None]).prod(axis=1) / (nodes + 4)) + nodes / 3
    sums = power_sums(nodes, logs, np.zeros(0, complex), 0.0, 1.0, 3)
    assert sums == pytest.approx([np.sum(z ** j).real for j in range(4)], abs=1e-4)


@pytest.mark.parametrize("zeros", [
    [0.5 + 30j, 0.5 - 30j],                                   # a complex pair (flutter)
    [2.0, 17.0],                                              # two real (divergence)
    [20.0 + 49.8j, 20.0 - 49.8j, 0.003],                      # a pair at the strip's top, a real
    [1e-3 + 49.9j, 1e-3 - 49.9j, 5.0 + 10j, 5.0 - 10j],       # near the top edge, and a pair
])
def test_located_zeros_of_an_analytic_determinant(zeros):
    """det f(s) = Π (s − z_k) e^{−s/40} / Π (s − p_j) with the poles p_j of a lightly damped
    structure left of −ε (their shifts by ±imω, as det F has): counted on the count's contour,
    then every zero right of −ε located from the count's samples to 10⁻⁹ relative — also zeros
    1.5 % of the strip from its top edge (period doubling), beside a pole just left of −ε — in
    ≤ 40 further evaluations (23–30 here)."""
    omega, epsilon = 100.0, 1e-2
    top, X = 0.505 * omega, 2e3
    modes = np.array([30.0, 75.0, 160.0, 410.0])
    structure = np.concatenate([-0.02 * modes + 1j * modes, -0.02 * modes - 1j * modes])
    poles = (structure[:, None] - 1j * omega * np.arange(-3, 4)[None]).ravel()
    z = np.array(zeros, complex)
    calls = []

    def log_det(s):
        s = np.asarray(s, complex)
        calls.append(s.size)
        return (np.log(s[:, None] - z[None]).sum(axis=1) - s / 40
                - np.log(s[:, None] - poles[None]).sum(axis=1))

    samples = {}

    def sampled(s):
        v = log_det(s)
        samples.update(zip(np.asarray(s).tolist(), v.tolist()))
        return v

    count, evaluations = winding_count(sampled, upper_contour(epsilon, X, top, poles))
    assert count == pytest.approx(z.size, abs=1e-6)
    calls.clear()
    found = located_zeros(log_det, samples, z.size, epsilon, top, X, poles)
    assert found is not None
    located = np.concatenate([found, found[found.imag != 0].conj()])
    assert np.sort_complex(located) == pytest.approx(np.sort_complex(z), rel=1e-9, abs=1e-9)
    assert sum(calls) <= 40


def test_located_zeros_refuses_an_incomplete_set():
    """A count that claims one zero more than there is (here: told 3 for a pair): None, not a
    verdict on the zeros it did find."""
    omega, epsilon, top, X = 100.0, 1e-2, 50.5, 2e3
    z = np.array([0.5 + 30j, 0.5 - 30j])

    def log_det(s):
        s = np.asarray(s, complex)
        return np.log(s[:, None] - z[None]).sum(axis=1) - np.log(s + 40.0 + 0j)

    samples = {}
    nodes = upper_contour(epsilon, X, top, np.array([-40.0 + 0j]))
    samples.update(zip(nodes.tolist(), log_det(nodes).tolist()))
    winding_count(lambda s: _kept(samples, log_det, s), nodes)
    assert located_zeros(log_det, samples, 3, epsilon, top, X) is None


def _kept(samples, log_det, s):
    v = log_det(s)
    samples.update(zip(np.asarray(s).tolist(), v.tolist()))
    return v


def linear_contact_oscillators(stiffness, contact_stiffness, contact_damping, omega, harmonics,
                               mass=1.0, damping=0.02):
    """Uncoupled oscillators m ẍ_i + c ẋ_i + k_i x_i = −λ_i with one contact row each whose law is
    linear, λ_i = k_c,i x_i + c_c,i ẋ_i (as seen by Hill: the AFT Jacobian k_c I + c_c ω ∇, the
    dashpot block c_c I). Hill's exponents are exactly the roots of
    m s² + (c + c_c,i) s + k_i + k_c,i = 0 shifted by i m ω. Returns (model, contacts, forces)."""
    k = np.asarray(stiffness, float)
    n, P = k.size, 2 * harmonics + 1
    model = make_linear_model(mass * np.eye(n), damping * np.eye(n), np.diag(k))
    contacts = SimpleNamespace(row_count=n, gap_map=sp.csr_matrix(np.eye(n)))
    nabla = derivative_matrix(harmonics)
    kc, cc = np.asarray(contact_stiffness, float), np.asarray(contact_damping, float)
    rows = np.arange(n)[:, None]
    blocks = kc[:, None, None] * np.eye(P)[None] + cc[:, None, None] * omega * nabla[None]
    forces = SimpleNamespace(blocks=[(rows, blocks)],
                             damping_blocks=[(rows, cc[:, None, None] * np.eye(P)[None])])
    return model, contacts, forces


def oscillator_exponents(k, kc, cc, mass=1.0, damping=0.02):
    """Roots of m s² + (c + c_c) s + k + k_c = 0 for each oscillator (2n,) complex."""
    return np.concatenate([np.roots([mass, damping + c, ki + kci])
                           for ki, kci, c in zip(k, kc, cc)])


@pytest.mark.parametrize("k, kc, cc, zeros", [
    ([1.0], [0.0], [-0.06], 2),                   # negative contact damping: a pair, Re s = 0.02
    ([1.0, 4.0], [-2.0, -8.0], [0.0, 0.0], 2),    # negative net stiffness: two real, s ≈ 0.99, 1.99
    ([1.0, 1.69], [-1.5, 0.0], [0.0, -0.1], 3),   # one real (divergence) and a pair (flutter)
    ([1.0, 2.25], [-1.5, 0.0], [0.0, -0.1], 5),   # … the pair at 1.5 = ω/2: its shift −iω too
])
def test_linear_oscillators_verdict_and_leading_exponent_in_closed_form(k, kc, cc, zeros):
    """Two or three exponents right of −ε, located by the count (no Ritz method, no eigen-solve):
    'unstable' with the leading exponent the closed form's max Re s to 10⁻⁸, the counted number
    that of the roots in the half-strip, and every one of them among the reported exponents."""
    omega, H = 3.0, 3
    model, contacts, forces = linear_contact_oscillators(k, kc, cc, omega, H)
    exact = oscillator_exponents(k, kc, cc)
    exact = (exact[:, None] + 1j * omega * np.arange(-H, H + 1)[None]).ravel()
    in_strip = exact[(exact.real > -1e-4 * omega) & (np.abs(exact.imag) < 0.505 * omega)]
    assert in_strip.size == zeros
    for _ in range(2):                              # (the modal basis is cached from the 2nd call)
        result, counted, _ = contact_row_counts(model, contacts, omega, H, forces)
    assert counted == zeros
    assert result is not None and result.stable is False
    assert result.leading == pytest.approx(exact.real.max(), rel=1e-8)
    for z in in_strip:
        assert np.abs(result.exponents - z).min() <= 1e-8 * abs(z)


def test_linear_oscillator_within_the_uncertain_band_is_not_decided():
    """A pair at Re s = 10⁻⁶ 1/s (c + c_c = −2·10⁻⁶), inside ±10⁻⁴·ω of 0: located, and the verdict
    is the full method's for such a leading exponent — None with the band named."""
    omega, H = 3.0, 3
    model, contacts, forces = linear_contact_oscillators([1.0], [0.0], [-0.020002], omega, H)
    for _ in range(2):
        result, counted, _ = contact_row_counts(model, contacts, omega, H, forces)
    assert counted == 2
    assert result.stable is None and "within" in result.note
    assert result.leading == pytest.approx(1e-6, rel=1e-6)


def test_example03_two_exponents_right_of_the_axis_equal_the_full_method(sweep03):
    """NLvib example 03 (H = 11, N = 512): at every point where the count finds two or more
    exponents right of −ε (a complex pair near Im s = ω/2: the period-doubling region near the
    peak) the count decides by itself, with the full Hill method's verdict and its leading
    in-strip exponent to 10⁻⁶ (relative to max(1, |Re s|))."""
    from sarfe.hbm.stability.rows import contact_row_count
    from tests.hbm.shipped_points import full_hill

    model, contacts, F, sols = sweep03
    checked = 0
    for s in sols:
        full, ev, op = full_hill(model, contacts, F, s)
        result, zeros = contact_row_count(model, contacts, s.omega, s.harmonics, ev.forces, op)
        if not zeros or zeros < 2:
            continue
        assert result is not None, s.omega
        strip = full.exponents[np.abs(full.exponents.imag) <= 0.505 * s.omega]
        assert result.stable is full.stable, (s.omega, result, full.leading)
        assert result.leading == pytest.approx(strip.real.max(), rel=1e-6, abs=1e-6)
        checked += 1
    assert checked >= 3
