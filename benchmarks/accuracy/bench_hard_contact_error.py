"""Is the ± honest at a hard contact? (issue 29) lumped_rattle with the rattle contact's
normal_stiffness_N_m = 10¹⁰ N/m, the full `sarfe solve` path (estimates on, stability off), against
the sub-stepped Newmark orbit started from the points; and the impact-resolution indicator ρ(H')
(sarfe.accuracy.contact_resolution) over the continued branches of k_n = 10⁶ (the shipped case),
10⁷, 10⁸ and 10¹⁰ N/m.

    python benchmarks/accuracy/bench_hard_contact_error.py  → results/hard_contact_error.{json,md}
"""
from __future__ import annotations

import pathlib
import sys
import time
import warnings

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
import benchlib  # noqa: E402

import numpy as np  # noqa: E402

from sarfe.accuracy.contact_resolution import RESOLUTION_LIMIT, contact_resolution  # noqa: E402
from sarfe.accuracy.estimate import highest_natural_frequency_hz  # noqa: E402
from sarfe.accuracy.harmonic_truncation import reach_harmonics  # noqa: E402
from sarfe.case.read import load_case  # noqa: E402
from sarfe.hbm.continuation import continuation  # noqa: E402
from sarfe.hbm.time_integration import integrate_time  # noqa: E402
from sarfe.pipeline import solve_case  # noqa: E402
from sarfe.pipeline.model.linear_stage import build_linear_model  # noqa: E402
from sarfe.pipeline.model.nonlinear_model import nonlinear_model  # noqa: E402
from sarfe.pipeline.solve.points import solver_options  # noqa: E402

CASE = benchlib.CASES / "lumped_rattle.yaml"


def near_frequencies(solutions, closes, frequencies_hz):
    """Per frequency [Hz], the point of ``closes`` nearest to it up to the branch's fold."""
    f = np.array([s.omega / (2 * np.pi) for s in solutions])
    fold = max(closes, key=lambda k: f[k])
    upper = [k for k in closes if k <= fold]
    return [min(upper, key=lambda k: abs(f[k] - target)) for target in frequencies_hz]


def case_data(normal_stiffness):
    data = load_case(CASE).data
    data["contacts"][0]["normal_stiffness_N_m"] = float(normal_stiffness)
    data["solver"].update(stability=False)
    return data


def indicator_over_branch(normal_stiffness) -> dict:
    """ρ(H') at every point of the continued 30 → 90 Hz branch (no estimates)."""
    case = load_case(case_data(normal_stiffness), base_dir=CASE.parent)
    nl = nonlinear_model(case, build_linear_model(case))
    _, options = solver_options(case.config.solver)
    points = continuation(nl.model, nl.contacts, nl.excitation, 2 * np.pi * 30, 2 * np.pi * 90,
                          case.config.solver.harmonics, case.config.solver.samples_per_period,
                          options=options)
    top = highest_natural_frequency_hz(nl.model)
    rows = []
    for p in points:
        r = contact_resolution(p, nl.model, nl.contacts, nl.excitation,
                               reach_harmonics(p.harmonics, p.omega, top))
        rows.append((p.omega / (2 * np.pi), r.ratio, r.impact_duration_s))
    rows = np.array(rows)
    impacting = rows[rows[:, 1] > 0]
    return {"normal_stiffness_N_m": normal_stiffness, "points": len(points),
            "impacting": int(len(impacting)),
            "rho_max": float(impacting[:, 1].max()) if len(impacting) else 0.0,
            "rho_min": float(impacting[:, 1].min()) if len(impacting) else 0.0,
            "flagged": int(np.sum(impacting[:, 1] > RESOLUTION_LIMIT)),
            "impact_duration_us": float(1e6 * np.nanmin(impacting[:, 2])) if len(impacting)
            else None}


def hard_case() -> dict:
    clock, cpu = time.perf_counter(), benchlib.cpu_seconds()
    data = case_data(1e10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = solve_case(data, write=False)
    wall, cpu = time.perf_counter() - clock, benchlib.cpu_seconds() - cpu
    summary, solutions = result.summary, result.solutions
    case = load_case(data, base_dir=CASE.parent)
    nl = nonlinear_model(case, build_linear_model(case))
    force = [np.asarray(s.contact_force_time)[:, 0] for s in solutions]    # panel_bracket
    closes = [k for k, s in enumerate(solutions)
              if s.converged and force[k].max() > 0 and force[k].min() == 0]
    estimates = [summary["points"][k]["error_estimate"] for k in closes]
    compared = []
    for k in near_frequencies(solutions, closes, (71.54, 75.56)):
        point, e = solutions[k], summary["points"][k]["error_estimate"]
        ref = integrate_time(nl.model, nl.contacts, nl.excitation, point.omega, point.harmonics,
                             steps_per_period=2048, richardson=True, initial=point,
                             max_periods=40)
        a = point.displacement[1] - 1j * point.displacement[2]
        b = ref.displacement_harmonics[1] - 1j * ref.displacement_harmonics[2]
        compared.append({"index": int(k), "frequency_hz": float(point.omega / (2 * np.pi)),
                         "error_vs_newmark": float(np.abs(a - b).max() / np.abs(b).max()),
                         "reported_amplitude_rel": e["amplitude_rel"],
                         "rho": e.get("contact_resolution", {}).get("ratio"),
                         "time_checked": "time_check" in e})
    return {"wall_s": wall, "cpu_s": cpu, "points": len(solutions),
            "impacting": len(closes),
            "impacting_flagged": int(sum((e.get("contact_resolution") or {}).get("resolved") is False
                                         for e in estimates)),
            "impacting_finite": int(sum(np.isfinite(e["amplitude_rel"]) for e in estimates)),
            "impact_check": summary.get("impact_check"), "worst": {
                k: summary["worst"].get(k) for k in ("index", "frequency_hz", "erp_level_dba",
                                                     "erp_error_db", "error_note")},
            "warning": (summary["accuracy_check"] or {}).get("warning"),
            "timings_s": summary["timings_s"], "compared": compared}


def main():
    indicator = [indicator_over_branch(k) for k in (1e6, 1e7, 1e8, 1e10)]
    hard = hard_case()
    lines = ["# The ± at a hard contact (lumped_rattle, k_n = 10¹⁰ N/m; issue 29)", "",
             benchlib.machine_line(), "",
             "Indicator ρ(H') = max_c k_c |C_H',cc| over the impacting points of the continued "
             "branch (H = 7, H' = 14; flagged: ρ > 4):", "",
             "| k_n [N/m] | points | impacting | ρ min … max | flagged | τ_c [µs] |",
             "|---|---|---|---|---|---|"]
    for r in indicator:
        lines.append(f"| {r['normal_stiffness_N_m']:.0e} | {r['points']} | {r['impacting']} | "
                     f"{r['rho_min']:.3g} … {r['rho_max']:.3g} | {r['flagged']} | "
                     f"{r['impact_duration_us']:.3g} |")
    lines += ["", f"`sarfe solve` path at 10¹⁰ N/m: {hard['points']} points, "
              f"{hard['impacting']} impacting, of them {hard['impacting_flagged']} without a bound "
              f"from the harmonics and {hard['impacting_finite']} with a finite ± (the headline's, "
              f"by time integration); {hard['wall_s']:.0f} s wall, {hard['cpu_s']:.0f} CPU s.", "",
              "| f [Hz] | error vs Newmark (first harmonic, all DOFs) | reported amplitude ± | ρ |",
              "|---|---|---|---|"]
    for c in hard["compared"]:
        shown = c["reported_amplitude_rel"]
        shown = "none (no bound, reason said)" if not np.isfinite(shown) else f"{100 * shown:.3g} %"
        lines.append(f"| {c['frequency_hz']:.2f} | {100 * c['error_vs_newmark']:.3g} % | {shown} "
                     f"| {c['rho']:.3g} |")
    check = hard["impact_check"]
    if check and "failed" not in check:
        lines += ["", f"Headline: {hard['worst']['erp_level_dba']:.1f} ± "
                  f"{hard['worst']['erp_error_db']:.2f} dB(A) at {check['frequency_hz']:.2f} Hz "
                  f"({hard['worst']['error_note']}): first harmonic {100 * check['amplitude_rel']:.3g} %"
                  f", ERP {check['erp_db']:.3g} dB against the time integration ({check['periods']}"
                  f" periods, N = {check['steps_per_period']}, {check['seconds']:.0f} s)."]
    lines += ["", f"Warning: {hard['warning']}"]
    benchlib.write_results("hard_contact_error", {"indicator": indicator, "hard": hard,
                                                  **benchlib.machine()}, lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
