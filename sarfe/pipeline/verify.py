r"""``sarfe verify``: one frequency point of a case, harmonic balance against time integration.

Compared, each with its own tolerance (a row per comparison, printed by the CLI):

- every harmonic k = 1 … H of the response on all kept DOFs: ‖Ũ_k^HBM − Ũ_k^TI‖ / ‖Ũ_1^TI‖
  (relative to the first harmonic, so a small harmonic is judged by what it adds to the motion;
  k = 1 is the plain relative error) ≤ ``tolerance``;
- the first-harmonic normal amplitude of each named contact and of the largest DOF ≤ ``tolerance``;
- the ERP total [W] (relative) ≤ ``tolerance`` and its level in dB(A) (absolute) ≤ ``tolerance_db``;
- the stability verdict: Hill's ``stable`` against the time integrator's own verdict
  (:func:`sarfe.hbm.stability.perturbation.perturbation_check`: the monodromy of the period map around
  the orbit, i.e. whether perturbations of the orbit decay or grow over a period);
  a Hill verdict of None (uncertain) is reported, not counted as a disagreement.

The time integration of the response starts independently from the linear periodic solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sarfe.case.config import ErpConfig, SolverConfig
from sarfe.hbm.stability.perturbation import perturbation_check
from sarfe.hbm.time_integration import integrate_time
from sarfe.pipeline.post.records import point_erp
from sarfe.pipeline.solve.points import solve_point, solver_options


@dataclass(frozen=True)
class Comparison:
    """label; hbm and time: the two values (floats, or text for the stability verdict); difference
    (relative, or dB, or None); tolerance (same unit); unit of difference/tolerance; agree."""

    label: str
    hbm: object
    time: object
    difference: object
    tolerance: object
    unit: str
    agree: bool


def _relative(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def verify_point(solver: SolverConfig, erp: ErpConfig, stage, nl, omega, tolerance=0.05,
                 tolerance_db=0.5):
    """(hbm solution, time response, perturbation check, [Comparison]) at ω [rad/s].

    solver, erp: the case's sections (``case.config.solver``, ``case.config.erp``): H, N and the
    Newton options of the HBM point, the air and reference of the ERP rows."""
    H, N = solver.harmonics, solver.samples_per_period
    options, _ = solver_options(solver)
    hbm = solve_point(nl, omega, H, N, options, None)
    steps = max(512, 4 * N)
    tim = integrate_time(nl.model, nl.contacts, nl.excitation, omega, H, steps_per_period=steps)
    U_h, U_t = np.asarray(hbm.displacement), np.asarray(tim.displacement_harmonics)
    rows = []
    first = max(np.linalg.norm(U_t[1:3]), 1e-300)
    for k in range(1, H + 1):
        diff = np.linalg.norm(U_h[2 * k - 1:2 * k + 1] - U_t[2 * k - 1:2 * k + 1]) / first
        rows.append(Comparison(f"harmonic {k}: ‖Ũ_k‖ [m]", float(np.linalg.norm(U_h[2 * k - 1:2 * k + 1])),
                               float(np.linalg.norm(U_t[2 * k - 1:2 * k + 1])), diff, tolerance,
                               "rel. to ‖Ũ_1‖", diff <= tolerance))
    for name, _, idx in nl.groups:
        nr = nl.contacts.normal_row[idx]
        nr = nr[nr >= 0]
        if nr.size:
            G = nl.contacts.gap_map[nr]
            a_h = float(np.hypot(G @ U_h[1], G @ U_h[2]).max())
            a_t = float(np.hypot(G @ U_t[1], G @ U_t[2]).max())
            diff = _relative(a_h, a_t) if a_t > 1e-15 else 0.0
            rows.append(Comparison(f"contact {name} normal, 1st harmonic [m]", a_h, a_t, diff,
                                   tolerance, "rel.", diff <= tolerance))
    amp_h, amp_t = np.hypot(U_h[1], U_h[2]), np.hypot(U_t[1], U_t[2])
    j = int(np.argmax(amp_h))
    diff = _relative(amp_h[j], amp_t[j]) if amp_t[j] > 1e-15 else 0.0
    rows.append(Comparison(f"largest DOF ({j}), 1st harmonic [m]", float(amp_h[j]),
                           float(amp_t[j]), diff, tolerance, "rel.", diff <= tolerance))
    erp_h, _ = point_erp(erp, stage, U_h, omega)
    erp_t, _ = point_erp(erp, stage, U_t, omega)
    p_h, p_t = float(erp_h.power_total), float(erp_t.power_total)
    diff = _relative(p_h, p_t) if p_t > 0 else 0.0
    rows.append(Comparison("ERP total [W]", p_h, p_t, diff, tolerance, "rel.", diff <= tolerance))
    a_h, a_t = float(erp_h.level_total_a_db), float(erp_t.level_total_a_db)
    diff = abs(a_h - a_t) if np.isfinite(a_h) and np.isfinite(a_t) else 0.0
    rows.append(Comparison("ERP total [dB(A)]", a_h, a_t, diff, tolerance_db, "dB",
                           diff <= tolerance_db))
    check = None
    if hbm.converged:
        check = perturbation_check(nl.model, nl.contacts, nl.excitation, hbm,
                                   steps_per_period=max(512, 4 * N))
        verdict = {True: "stable", False: "unstable", None: "uncertain"}[hbm.stable]
        note = getattr(hbm, "stability_note", "")
        exponent = (f"{hbm.floquet_exponent:.3g} 1/s" if np.isfinite(hbm.floquet_exponent)
                    else "not located")     # a stable count bounds it: the note says where
        rows.append(Comparison(
            f"stability (Hill {exponent} vs time int. {check.rate:.3g} 1/s)"
            + (f" [{note}]" if note else ""), verdict, "stable" if check.stable else "unstable",
            None, None, "", hbm.stable is None or hbm.stable == check.stable))
    return hbm, tim, check, rows


def format_rows(rows) -> list[str]:
    """Console lines: label, HBM, time integration, difference ≤ tolerance, verdict."""
    width = max(len(r.label) for r in rows)
    lines = [f"{'quantity':<{width}}  {'HBM':>11}  {'time int.':>11}  {'difference':>24}  ok"]
    for r in rows:
        value = lambda v: f"{v:11.4e}" if isinstance(v, float) else f"{str(v):>11}"  # noqa: E731
        if r.difference is None:
            diff = f"{'(verdicts)':>24}"
        elif r.unit == "dB":
            diff = f"{r.difference:6.2f} dB ≤ {r.tolerance:g} dB".rjust(24)
        else:
            diff = f"{100 * r.difference:6.2f} % ≤ {100 * r.tolerance:g} %".rjust(24)
        lines.append(f"{r.label:<{width}}  {value(r.hbm)}  {value(r.time)}  {diff}  "
                     f"{'yes' if r.agree else 'NO'}")
    return lines
