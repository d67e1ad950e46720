"""Point records by chunks (one product with the ERP map for several points and their linear
baselines) and the map fields: closed forms on a lumped model, the chunk against one point at a
time, the quarter-period excursion against the whole-period sampling."""
import math

import numpy as np
import pytest

from sarfe.results.vtk import excursion_amplitude, period_samples
from sarfe.pipeline import load_case, solve_case

from tests.pipeline.post.test_linear_baseline import C, F0, F1, K0, K1, K_N, K_T, M0, M1, lumped_case

FREQUENCIES = [20.0, 30.0, 45.0, 52.0, 60.0, 75.0, 90.0, 110.0, 130.0, 150.0, 170.0]  # 2 chunks


def _case():
    """tests/pipeline/post/test_linear_baseline.py's two DOFs (a stuck squeak spot and an open far stop on DOF 0,
    a preloaded clip on DOF 1) at 11 frequencies, ERP areas 0.05 and 0.03 m², one process."""
    case = lumped_case(FREQUENCIES, areas_m2=(0.05, 0.03))
    case["name"] = "records"
    case["solver"]["workers"] = 1
    return case


@pytest.fixture(scope="module")
def solved():
    from sarfe.pipeline.model.linear_stage import build_linear_model
    from sarfe.pipeline.model.nonlinear_model import nonlinear_model

    case = load_case(_case())
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    result = solve_case(case, linear_stage=stage, write=False)
    return case, stage, nl, result


def test_chunked_records_give_every_point_its_closed_form_erp(solved):
    """Across two chunks, each point's ERP is ½ρc Σ_k Σ_i A_i (kω)²|w_k,i|² of its own harmonics
    and its linear baseline's is the closed form of two uncoupled oscillators (the squeak spot's
    k_t and the clip's k_n kept), to 1e-9: no point takes another's rows of the shared product."""
    case, _, _, result = solved
    erp = result.summary["case_data"]["erp"]
    kappa = 0.5 * erp["rho_kg_m3"] * erp["c_m_s"] * erp["radiation_loss_factor"]
    areas = np.array([0.05, 0.03])
    assert len(result.summary["points"]) == len(FREQUENCIES)
    for point, solution, f in zip(result.summary["points"], result.solutions, FREQUENCIES):
        w = 2 * math.pi * f
        U = np.asarray(solution.displacement)
        k = np.arange(1, (U.shape[0] - 1) // 2 + 1)
        nodal = kappa * np.sum(((k * w) ** 2)[:, None] * (U[1::2] ** 2 + U[2::2] ** 2) * areas)
        assert point["erp"]["power_W"] == pytest.approx(nodal, rel=1e-9)
        x0 = F0 / abs(K0 + K_T - M0 * w * w + 1j * C * w)
        x1 = F1 / abs(K1 + K_N - M1 * w * w + 1j * C * w)
        linear = kappa * w * w * (0.05 * x0 ** 2 + 0.03 * x1 ** 2)
        assert point["linear"]["erp_power_W"] == pytest.approx(linear, rel=1e-9)


def test_a_chunk_equals_its_points_one_at_a_time(solved):
    """point_records of all points at once equals point_record point by point (powers, levels,
    baseline, contributions) to 1e-12 relative."""
    from sarfe.pipeline.post.records import point_record, point_records

    case, stage, nl, result = solved
    points = [(i, s, None) for i, s in enumerate(result.solutions)]
    together = point_records(case.config, stage, nl, points)
    for (i, s, _), chunked in zip(points, together):
        alone = point_record(case.config, stage, nl, i, s, None)
        np.testing.assert_allclose(chunked[2].power, alone[2].power, rtol=1e-12, atol=0)
        for key in ("power_W", "level_db", "level_dba"):
            assert chunked[0]["erp"][key] == pytest.approx(alone[0]["erp"][key], rel=1e-12)
        assert chunked[0]["linear"]["erp_power_W"] == pytest.approx(
            alone[0]["linear"]["erp_power_W"], rel=1e-12)
        shares = [c["share_a"] for c in chunked[0]["contributions"].get("sources", [])]
        np.testing.assert_allclose(shares, [c["share_a"] for c in
                                            alone[0]["contributions"].get("sources", [])],
                                   rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("samples", [64, 90, 240])
def test_quarter_period_excursion_equals_the_whole_period_sampling(samples):
    """max_j |u(θ_j) − U0| from the quarter period [0, π/2] (n a multiple of 4: the orbit
    θ, −θ, π ± θ) or the whole grid (90) equals the dense sampling to round-off; a single odd
    harmonic a cos 3θ + b sin 3θ gives √(a² + b²) where the grid hits its peak."""
    rng = np.random.default_rng(7)
    U = rng.standard_normal((2 * 7 + 1, 300)) / np.arange(1, 16)[:, None]
    whole = np.abs(period_samples(U, samples) - U[0]).max(axis=0)
    np.testing.assert_allclose(excursion_amplitude(U, samples), whole, rtol=1e-13, atol=0)
    W = np.zeros((7, 2))
    W[0] = 4.0
    W[5], W[6] = [3.0, 0.0], [4.0, -2.0]       # order 3: 3 cos 3θ + 4 sin 3θ, and −2 sin 3θ
    np.testing.assert_allclose(excursion_amplitude(W, 4096), [5.0, 2.0], rtol=1e-6)
