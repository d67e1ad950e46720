"""Shipped cases at a given H, N and their converged references, for the tests that compare an
estimate with the true error (tests/accuracy/test_estimate.py, test_modal_truncation.py)."""
import warnings
from pathlib import Path

import numpy as np

from sarfe.accuracy.measures import erp_proxy, resize_harmonics
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
from sarfe.pipeline.solve.points import solve_points

CASES = Path(__file__).resolve().parents[2] / "cases"


def case_setting(name, frequencies_hz, H, N, cutoff_hz=None):
    """Stage, nonlinear model and stepped solutions of cases/<name>.yaml at H, N (FE: cutoff)."""
    data = load_case(CASES / f"{name}.yaml").data
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = list(frequencies_hz)
    data["solver"].update(harmonics=H, samples_per_period=N, prune_contacts=False,
                          error_estimate=False, stability=False)
    if cutoff_hz is not None:
        data["reduction"] = dict(data.get("reduction", {}), cutoff_hz=cutoff_hz)
    case = load_case(data)
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return stage, nl, solve_points(case.config.solver, case.config.excitation, nl)


def raise_to(nl, solution, H, N):
    """Reference: H raised in steps of ×1.5 from a converged solution (warm starts)."""
    current = solution
    while current.harmonics < H:
        h = min(H, max(current.harmonics + 2, int(round(1.5 * current.harmonics))))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            current = solve_frequency(nl.model, nl.contacts, resize_harmonics(nl.excitation, h),
                                      solution.omega, h, N,
                                      initial=resize_harmonics(current.displacement, h),
                                      options=SolverOptions(stability=False, max_iterations=100))
        assert current.converged, (h, current.reason)
    return current


def true_errors(stage, s, ref_stage, ref):
    """(max |Δa₁| / max a₁ over the contact rows, the larger of |ΔL_ERP| and |ΔL_ERP,A| [dB]);
    each with its own ERP map."""
    a = np.hypot(*np.asarray(s.contact_displacement)[1:3])
    b = np.hypot(*np.asarray(ref.contact_displacement)[1:3])
    db = []
    for weighted in (False, True):      # the estimate bounds the larger of dB and dB(A)
        p = erp_proxy(s.displacement, s.omega, stage.erp_map, stage.erp_areas, weighted)
        q = erp_proxy(ref.displacement, ref.omega, ref_stage.erp_map, ref_stage.erp_areas,
                      weighted)
        db.append(abs(10 * np.log10(p / q)))
    return float(np.max(np.abs(a - b)) / b.max()), float(max(db))
