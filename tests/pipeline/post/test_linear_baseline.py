"""The linear baseline describes the same structure as the nonlinear run: preloaded contacts stay
as linear springs at their static state (closed: k_n; stuck friction: k_t), open ones are removed
— closed form on a lumped model."""
import math

import pytest

from sarfe.pipeline import solve_case

M0, K0, M1, K1, C = 0.2, 2.0e4, 0.5, 5.0e4, 4.0
K_T, K_N, F0, F1 = 1.0e4, 1.0e5, 1.0, 2.0


def lumped_case(frequencies_hz, areas_m2=(0.05, 0.05)):
    """DOF 0: a squeak spot (constant normal load 5 N, k_t) and a rattle stop 1 m away (open);
    DOF 1: a rattle contact preloaded with 2 N (closed at rest). Own damping matrix C·I; ERP on
    both DOFs with ``areas_m2``. (Also the model of tests/erp/test_point_records.py.)"""
    return {
        "name": "baseline",
        "model": {"matrices": {"mass": [[M0, 0.0], [0.0, M1]], "stiffness": [[K0, 0.0], [0.0, K1]],
                               "damping": [[C, 0.0], [0.0, C]]}},
        "contacts": [
            {"name": "squeak_spot", "type": "squeak", "tangential_dofs": [0], "preload_N": 5.0,
             "tangential_stiffness_N_m": K_T, "friction_coefficient": 0.5},
            {"name": "far_stop", "type": "rattle", "normal_dof": 0, "gap_m": 1.0,
             "normal_stiffness_N_m": 1.0e6},
            {"name": "clip", "type": "rattle", "normal_dof": 1, "preload_N": 2.0,
             "normal_stiffness_N_m": K_N},
        ],
        "excitation": {"forces": [{"dof": 0, "force_N": F0}, {"dof": 1, "force_N": F1}],
                       "frequency_hz": list(frequencies_hz)},
        "solver": {"harmonics": 3, "samples_per_period": 64, "error_estimate": False,
                   "stability": False},
        "erp": {"dofs": [0, 1], "areas_m2": list(areas_m2)},
    }


@pytest.mark.parametrize("frequency_hz", [20.0, 45.0, 60.0])
def test_baseline_keeps_preloaded_contacts_as_springs(frequency_hz):
    result = solve_case(lumped_case([frequency_hz]), write=False)
    point = result.summary["points"][0]
    erp = result.summary["case_data"]["erp"]
    w = 2 * math.pi * frequency_hz
    x0 = F0 / abs(K0 + K_T - M0 * w * w + 1j * C * w)      # stuck squeak spot: k_t kept
    x1 = F1 / abs(K1 + K_N - M1 * w * w + 1j * C * w)      # preloaded clip: k_n kept
    power = 0.5 * erp["rho_kg_m3"] * erp["c_m_s"] * erp["radiation_loss_factor"] * 0.05 * (
        (w * x0) ** 2 + (w * x1) ** 2)
    assert point["linear"]["erp_power_W"] == pytest.approx(power, rel=1e-9)
    clip = next(c for c in point["linear"]["contacts"] if c["name"] == "clip")
    assert clip["normal_amplitude_m"] == pytest.approx(x1, rel=1e-9)
