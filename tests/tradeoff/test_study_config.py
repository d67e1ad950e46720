"""The study runner reads the case through its typed config (``case.config``): the frequency grid
of a sweep, the ERP air data (level ∝ 10 log10(ρ c)), and H, N and the knob levels."""
import numpy as np
import pytest

from sarfe.pipeline import build_linear_model, load_case
from sarfe.tradeoff.study import erp_levels, frequency_grid, knob_levels

CASE = {
    "name": "tiny",
    "model": {"matrices": {"mass": [[1.0]], "stiffness": [[1.0e5]]}},
    "damping": {"modal_zeta": 0.02},
    "contacts": [{"name": "stop", "type": "rattle", "normal_dof": {"dof": 0}, "gap_m": 1.0e-3,
                  "normal_stiffness_N_m": 1.0e5}],
    "excitation": {"forces": [{"dof": 0, "force_N": 1.0}],
                   "sweep": {"start_hz": 30.0, "end_hz": 70.0}},
    "solver": {"harmonics": 3},
    "erp": {"dofs": [0], "areas_m2": [0.05]},
}


def test_grid_air_data_and_knobs_come_from_the_config():
    case = load_case(CASE)
    assert np.allclose(frequency_grid(case, points=5), [30.0, 40.0, 50.0, 60.0, 70.0])
    stage = build_linear_model(case)
    levels = knob_levels(case, stage, ["harmonics", "samples"])
    n = case.config.solver.samples_per_period                    # default N of H = 3: 64
    assert n == 64 and [v for _, v in levels["harmonics"]] == [2, 3, 6, 12]
    assert [v for _, v in levels["samples"]] == [32, 64, 128, 512]
    U = np.zeros((7, 1))
    U[1, 0] = 1e-4
    omega = 2 * np.pi * 50.0
    level, _ = erp_levels(case, stage, U, omega)
    # ERP = ½ ρ c S |v̂|² (v̂ = ω û, amplitude) → the level rises by 10 log10(2 ρ c / ρ c) dB for twice the density
    heavy = load_case({**CASE, "erp": {**CASE["erp"], "rho_kg_m3": 2 * case.config.erp.rho_kg_m3}})
    assert erp_levels(heavy, stage, U, omega)[0] - level == pytest.approx(10 * np.log10(2), abs=1e-9)
    power = 0.5 * case.config.erp.rho_kg_m3 * case.config.erp.c_m_s * 0.05 * (omega * 1e-4) ** 2
    assert level == pytest.approx(10 * np.log10(power / case.config.erp.reference_power_W), abs=1e-9)
