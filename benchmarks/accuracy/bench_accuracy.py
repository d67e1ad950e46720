"""Accuracy benchmark → benchmarks/results/accuracy.md (+ .json).

1. HBM vs the built-in time integrator at equal accuracy (1 % and 0.1 % first-harmonic amplitude at
   the contacts, against a fine HBM reference checked by time integration): wall-time ratio.
   HBM: the accuracy search a run makes (:func:`sarfe.accuracy.resolve.resolve_accuracy` at that
   frequency from H = 2, N = 32: screening solve, H ladder, N doubling) and the solve at the H, N
   it chooses (cold, the cost of the whole adaptive choice). Time integration: steps per period
   doubled from 128 until the error is below the target (cost of the successful run only, started from the linear
   periodic solution as ``integrate_time`` does by default).
2. Cost vs H and vs the number of contacts (lumped chains) with fitted exponents t ∝ H^p, t ∝ n_c^q.
3. The error estimate the pipeline reports (``stage_error_estimate``) vs the true error on every
   shipped case (cases/*.yaml, 2–3 frequencies incl. one near resonance), at the case's H, N and two
   coarser settings, against a reference with much higher H, N and (FE) 3× the reduction cutoff:
   first-harmonic contact amplitude and ERP level, bracketed yes/no, ratio estimate / true.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/accuracy/bench_accuracy.py [--quick]``;
``--estimates-only [--cache DIR]`` runs part 3 alone (parts 1, 2 kept from results/accuracy.json;
the solutions pickled in DIR and reused, so a change of the estimator re-runs in a minute);
``--no-estimates`` runs parts 1, 2 alone (part 3 kept).
"""
from __future__ import annotations

import argparse
import os
import pickle
import platform
import sys
import time
import warnings
from pathlib import Path
import pathlib

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, read_results, write_results  # noqa: E402

import numpy as np

warnings.simplefilter("ignore")


def _contact_amplitudes(contacts, U):
    G = contacts.gap_map
    if G.shape[0] == 0:
        return np.hypot(U[1], U[2])
    return np.hypot(G @ U[1], G @ U[2])


def amplitude_error(contacts, U, U_ref):
    a, b = _contact_amplitudes(contacts, U), _contact_amplitudes(contacts, U_ref)
    return float(np.max(np.abs(a - b)) / max(b.max(), 1e-300))


def load_problem(name):
    """(label, model, contacts, excitation (2·40+1, n), erp_map, erp_areas, modal_dofs, frequencies)."""
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.accuracy.measures import resize_harmonics

    if name.startswith("lumped_chain"):
        from sarfe.tradeoff.lumped import lumped_problem

        p = lumped_problem(3, rattle_dofs=(0, 2), gap=1e-3, penalty_ratio=10.0, zeta=0.02,
                           force=10.0, squeak_dofs=(1,), harmonics=40)
        return dict(label="lumped 3-mass chain (2 rattle + 1 squeak)", model=p.model,
                    contacts=p.contacts, excitation=p.excitation, erp_map=None, erp_areas=None,
                    modal=None, frequencies_hz=[12.0, 16.0, 40.0])
    case = load_case(ROOT / "cases" / f"{name}.yaml")
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    modal = (np.arange(int(stage.info.get("boundary_dofs", 0)), stage.dof_count)
             if stage.kind == "fe" else None)
    exc = case.data["excitation"]
    freqs = (list(exc["frequency_hz"]) if "frequency_hz" in exc else
             list(np.linspace(exc["sweep"]["start_hz"], exc["sweep"]["end_hz"], 17)))
    return dict(label=name, model=nl.model, contacts=nl.contacts,
                excitation=resize_harmonics(nl.excitation, 40), erp_map=stage.erp_map,
                erp_areas=stage.erp_areas, modal=modal, frequencies_hz=freqs)


def reference(prob, omega, H=40, N=4096, initial=None):
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.accuracy.measures import resize_harmonics

    return solve_frequency(prob["model"], prob["contacts"], resize_harmonics(prob["excitation"], H),
                           omega, H, N, initial=None if initial is None else
                           resize_harmonics(initial, H), options=SolverOptions(stability=False))


def nonlinear_points(prob, count=2):
    """Frequencies where a stepped HBM sweep (H = 5, N = 128, warm starts) converges with an active
    contact (force > 0), each with its H = 40, N = 4096 reference (started from it)."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.accuracy.measures import resize_harmonics

    found, previous = [], None
    F = resize_harmonics(prob["excitation"], 5)
    for f in prob["frequencies_hz"]:
        omega = 2 * np.pi * f
        s = solve_frequency(prob["model"], prob["contacts"], F, omega, 5, 128, initial=previous,
                            options=SolverOptions(stability=False))
        previous = s if s.converged else None
        if s.converged and np.abs(s.contact_force_time).max() > 0:
            found.append((f, s))
    out = []
    # the most strongly nonlinear points first (largest contact force)
    for f, s in sorted(found, key=lambda x: -np.abs(x[1].contact_force_time).max()):
        ref = reference(prob, 2 * np.pi * f, initial=s.displacement)
        if ref.converged:
            out.append((f, ref))
        if len(out) >= count:
            break
    return out


# ------------------------------------------------------------------------------------ part 1
def hbm_vs_time(prob, f, ref, targets=(1e-2, 1e-3), max_steps=4096):
    from sarfe.accuracy.estimate import EstimateProblem
    from sarfe.accuracy.measures import resize_harmonics
    from sarfe.accuracy.resolve import resolve_accuracy
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.hbm.time_integration import integrate_time

    omega = 2 * np.pi * f
    rows = []
    for target in targets:
        clock = time.perf_counter()
        problem = EstimateProblem(prob["model"], prob["contacts"], prob["excitation"],
                                  prob["erp_map"], prob["erp_areas"])
        res = resolve_accuracy(problem, {"amplitude_rel": target}, [f], 2, 32, start_harmonics=2,
                               start_samples=32, max_points_tuned=1)
        H, N = res["harmonics"], res["samples_per_period"]
        chosen = solve_frequency(prob["model"], prob["contacts"],
                                 resize_harmonics(prob["excitation"], H), omega, H, N,
                                 options=SolverOptions(stability=False))
        t_hbm = time.perf_counter() - clock
        e_hbm = amplitude_error(prob["contacts"], resize_harmonics(chosen.displacement, 40),
                                ref.displacement)
        fixed = hbm_smallest_sufficient(prob, omega, ref, target)
        steps, t_ti, e_ti, ok = 128, float("nan"), float("nan"), False
        while steps <= max_steps:
            clock = time.perf_counter()
            r = integrate_time(prob["model"], prob["contacts"], resize_harmonics(prob["excitation"], 3),
                               omega, 40, steps_per_period=steps, max_periods=400)
            t_ti = time.perf_counter() - clock
            e_ti = amplitude_error(prob["contacts"], r.displacement_harmonics, ref.displacement)
            if r.steady and e_ti <= target:
                ok = True
                break
            steps *= 2
        rows.append({"case": prob["label"], "frequency_hz": f, "target": target,
                     "hbm_H": H, "hbm_N": N, "hbm_met": res["met"] and chosen.converged,
                     "hbm_s": t_hbm, "hbm_error": e_hbm, "ti_steps": steps if ok else None,
                     "ti_s": t_ti, "ti_error": e_ti, "ti_met": ok,
                     "ratio_ti_over_hbm": t_ti / t_hbm if ok else None, **fixed,
                     "ratio_ti_over_hbm_fixed": t_ti / fixed["hbm_fixed_s"]
                     if ok and fixed["hbm_fixed_H"] else None})
        print(f"  {prob['label']} {f:.1f} Hz target {target:g}: HBM H={H} "
              f"N={N} {t_hbm:.2f}s err {e_hbm:.1e} | TI {steps} steps "
              f"{t_ti:.2f}s err {e_ti:.1e} | HBM fixed H={fixed['hbm_fixed_H']} "
              f"{fixed['hbm_fixed_s']:.2f}s err {fixed['hbm_fixed_error']:.1e}", flush=True)
    return rows


HARMONIC_LADDER = (2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)


def hbm_smallest_sufficient(prob, omega, ref, target):
    """HBM measured the way the time integrator is: the smallest H of HARMONIC_LADDER (N = 16H, at
    least 64) whose cold-start solve meets the target against the reference; the cost of that solve
    only."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.accuracy.measures import resize_harmonics

    for H in HARMONIC_LADDER:
        N = max(64, 16 * H)
        clock = time.perf_counter()
        s = solve_frequency(prob["model"], prob["contacts"], resize_harmonics(prob["excitation"], H),
                            omega, H, N, options=SolverOptions(stability=False))
        seconds = time.perf_counter() - clock
        error = amplitude_error(prob["contacts"], resize_harmonics(s.displacement, 40),
                                ref.displacement) if s.converged else float("nan")
        if s.converged and error <= target:
            return {"hbm_fixed_H": H, "hbm_fixed_N": N, "hbm_fixed_s": seconds,
                    "hbm_fixed_error": error, "hbm_fixed_iterations": int(s.iterations)}
    return {"hbm_fixed_H": None, "hbm_fixed_N": None, "hbm_fixed_s": float("nan"),
            "hbm_fixed_error": float("nan"), "hbm_fixed_iterations": None}


# ------------------------------------------------------------------------------------ part 2
def _fit(x, y):
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    return float(np.polyfit(x, y, 1)[0])


def cost_scaling(quick=False):
    """Seconds per Newton iteration (warm solve from 0.8 × the converged solution, best of 2) of
    chains with a rattle contact on every mass: vs H (8 contacts) and vs n_c (H = 5, N = 128)."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.accuracy.measures import resize_harmonics
    from sarfe.tradeoff.lumped import lumped_problem

    options = SolverOptions(stability=False)
    omega = 2 * np.pi * 14.0

    def per_iteration(n, H, N):
        p = lumped_problem(n, coupling=1e4, rattle_dofs=tuple(range(n)), gap=1e-3, harmonics=H,
                           force_all=True, force=10.0)
        s0 = solve_frequency(p.model, p.contacts, p.excitation, omega, H, N, options=options)
        if not s0.converged:
            return None
        best, its = np.inf, 0
        for _ in range(2):
            clock = time.perf_counter()
            s = solve_frequency(p.model, p.contacts, p.excitation, omega, H, N,
                                initial=0.8 * s0.displacement, options=options)
            elapsed = time.perf_counter() - clock
            if s.iterations and elapsed / s.iterations < best:
                best, its = elapsed / s.iterations, s.iterations
        active = int(np.count_nonzero(np.abs(s0.contact_force_time).max(axis=0) > 0))
        return {"seconds_per_iteration": best, "iterations": its, "active_contacts": active,
                "condensed_unknowns": (2 * H + 1) * p.contacts.row_count}

    by_h = []
    for H in ([2, 4, 8, 16, 32] if quick else [2, 4, 8, 16, 32, 64]):
        N = max(64, 2 ** int(np.ceil(np.log2(8 * H))))
        r = per_iteration(8, H, N)
        if r:
            by_h.append(dict(r, H=H, N=N))
            print(f"  H={H} N={N}: {r['seconds_per_iteration'] * 1e3:.1f} ms/iteration "
                  f"({r['active_contacts']} active)", flush=True)
    by_c = []
    for n in ([1, 2, 4, 8, 16, 32] if quick else [1, 2, 4, 8, 16, 32, 64]):
        r = per_iteration(n, 5, 128)
        if r:
            by_c.append(dict(r, contacts=n))
            print(f"  contacts={n}: {r['seconds_per_iteration'] * 1e3:.1f} ms/iteration "
                  f"({r['active_contacts']} active)", flush=True)
    big_h = [r for r in by_h if r["H"] >= 4]
    big_c = [r for r in by_c if r["contacts"] >= 4]
    return {"by_harmonics": by_h, "by_contacts": by_c,
            "exponent_harmonics": _fit([r["H"] for r in big_h],
                                       [r["seconds_per_iteration"] for r in big_h])
            if len(big_h) > 2 else None,
            "exponent_contacts": _fit([r["contacts"] for r in big_c],
                                      [r["seconds_per_iteration"] for r in big_c])
            if len(big_c) > 2 else None}


# ------------------------------------------------------------------------------------ part 3
# Shipped cases: the estimate the pipeline reports (stage_error_estimate) at the case's H, N and
# at coarser ones, against a converged reference (much higher H, N; FE: 3× the reduction cutoff).
SHIPPED = {   # frequencies: 1–3 points incl. one near resonance, solved in this order (warm starts)
    "lumped_rattle": dict(frequencies_hz=[40.0, 48.0, 55.0], coarser=[(3, 64), (5, 128)],
                          reference=(40, 4096)),
    "rattle_rig": dict(frequencies_hz=[30.0, 32.0], coarser=[(3, 64), (5, 128)],
                       reference=(40, 2048)),
    "squeak_rig": dict(frequencies_hz=[100.0, 150.0], coarser=[(1, 16), (2, 32)],
                       reference=(24, 1024)),
    "door_trim": dict(frequencies_hz=[52.0, 67.0], coarser=[(2, 32), (3, 32)],
                      reference=(24, 1024)),
    "instrument_panel": dict(frequencies_hz=[56.0, 58.0], coarser=[(2, 32), (3, 32)],
                             reference=(24, 1024)),
}
CUTOFF_FACTOR = 3.0     # reference reduction cutoff / the case's (at the case's H)


def shipped_case(name, frequencies_hz, harmonics, samples_per_period, cutoff_hz=None):
    """Case (sarfe.case.read.Case) of cases/<name>.yaml at the given frequencies, H, N (FE: cutoff)."""
    from sarfe.pipeline import load_case

    data = load_case(ROOT / "cases" / f"{name}.yaml").data
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = list(frequencies_hz)
    data["solver"].update(harmonics=int(harmonics), samples_per_period=int(samples_per_period),
                          prune_contacts=False, error_estimate=False, stability=False)
    data["solver"].pop("accuracy", None)
    if cutoff_hz is not None:
        data["reduction"] = dict(data.get("reduction", {}), cutoff_hz=float(cutoff_hz))
    return load_case(data)


def solve_setting(case):
    """(stage, nl, solutions) of a case: sarfe's linear stage, nonlinear model and stepped points."""
    from sarfe.pipeline import build_linear_model, nonlinear_model
    from sarfe.pipeline.solve.points import solve_points

    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    return stage, nl, solve_points(case.config.solver, case.config.excitation, nl)


def raise_harmonics(nl, solution, harmonics, samples_per_period):
    """Warm-started solves with H raised a step at a time up to ``harmonics`` → (highest converged
    solution, the one before it). A step tries H ×1.25, ×1.4, ×1.6 with N = samples_per_period and
    N/2 (impacts converge on some paths only); when none converges the climb ends there
    ((None, None) when the first step fails)."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.accuracy.measures import resize_harmonics

    options = SolverOptions(stability=False, max_iterations=100)
    H, previous, chain = int(solution.harmonics), solution, []
    while H < harmonics:
        tries = sorted({min(harmonics, max(H + 2, int(round(f * H)))) for f in (1.25, 1.4, 1.6)})
        s = None
        for H_next in tries:
            for N in (samples_per_period, samples_per_period // 2):
                s = solve_frequency(nl.model, nl.contacts, resize_harmonics(nl.excitation, H_next),
                                    solution.omega, H_next, N,
                                    initial=resize_harmonics(previous.displacement, H_next),
                                    options=options)
                if s.converged:
                    break
            if s.converged:
                break
        if not s.converged:
            break
        H = int(s.harmonics)
        chain.append(s)
        previous = s
    if not chain:
        return None, None
    return chain[-1], (chain[-2] if len(chain) > 1 else solution)


def true_errors(stage, solution, ref_stage, ref):
    """(relative first-harmonic amplitude error at the contact rows, the larger ERP level error of
    dB and dB(A) [dB]) of
    ``solution`` against ``ref`` (each with its own stage's ERP map: the models may differ)."""
    from sarfe.accuracy.measures import erp_proxy

    def amplitudes(s):
        R = np.asarray(s.contact_displacement)
        return np.hypot(R[1], R[2])

    a, b = amplitudes(solution), amplitudes(ref)
    rel = float(np.max(np.abs(a - b)) / max(b.max(), 1e-300))
    levels = []
    for weighted in (False, True):   # the estimate bounds the larger of the dB and dB(A) errors
        p = erp_proxy(solution.displacement, solution.omega, stage.erp_map, stage.erp_areas,
                       weighted)
        q = erp_proxy(ref.displacement, ref.omega, ref_stage.erp_map, ref_stage.erp_areas,
                       weighted)
        levels.append(float(abs(10 * np.log10(p / q))) if p > 0 and q > 0 else float("nan"))
    return rel, max(levels)


def shipped_solutions(name, spec):
    """Solutions of one shipped case at its own, coarser and reference settings (picklable dict)."""
    from sarfe.pipeline import load_case
    from sarfe.pipeline.model.cutoff import default_cutoff_hz

    base = load_case(ROOT / "cases" / f"{name}.yaml")
    H0, N0 = base.data["solver"]["harmonics"], base.data["solver"]["samples_per_period"]
    freqs = spec["frequencies_hz"]
    out = {"name": name, "settings": []}
    for H, N in [(H0, N0)] + list(spec["coarser"]):
        clock = time.perf_counter()
        stage, nl, sols = solve_setting(shipped_case(name, freqs, H, N))
        out["settings"].append({"H": H, "N": N, "case_setting": (H, N) == (H0, N0), "stage": stage,
                                "nl": nl, "solutions": sols,
                                "seconds": time.perf_counter() - clock})
        print(f"  H={H} N={N}: {time.perf_counter() - clock:.1f} s, converged "
              f"{[bool(s.converged) for s in sols]}", flush=True)
    fe = out["settings"][0]["stage"].kind == "fe"
    cutoff = CUTOFF_FACTOR * default_cutoff_hz(shipped_case(name, freqs, H0, N0)) if fe else None
    H_ref, N_ref = spec["reference"]
    clock = time.perf_counter()
    stage, nl, sols = solve_setting(shipped_case(name, freqs, H0, N0, cutoff))
    refs = [raise_harmonics(nl, s, H_ref, N_ref) if s.converged else (None, None) for s in sols]
    out["reference"] = {"H": H_ref, "N": N_ref, "cutoff_hz": cutoff, "stage": stage, "nl": nl,
                        "solutions": [r for r, _ in refs], "previous": [p for _, p in refs],
                        "seconds": time.perf_counter() - clock}
    print(f"  reference H={H_ref} N={N_ref} cutoff {cutoff}: {time.perf_counter() - clock:.1f} s, "
          f"converged {[r is not None for r, _ in refs]}", flush=True)
    return out


def shipped_table(solved):
    """Rows: case, f, setting, estimate (the pipeline's stage_error_estimate), true error."""
    from sarfe.pipeline.solve.case_accuracy import stage_error_estimate

    rows = []
    ref = solved["reference"]
    for setting in solved["settings"]:
        stage, nl = setting["stage"], setting["nl"]
        for j, s in enumerate(setting["solutions"]):
            r, r_prev = ref["solutions"][j], ref["previous"][j]
            row = {"case": solved["name"], "frequency_hz": float(s.omega / (2 * np.pi)),
                   "H": setting["H"], "N": setting["N"], "case_setting": setting["case_setting"],
                   "modes": stage.info.get("modes"),
                   "residual_vectors": stage.info.get("residual_vectors"),
                   "converged": bool(s.converged), "reference": r is not None,
                   "reference_H": None if r is None else int(r.harmonics)}
            if not (s.converged and r is not None):
                rows.append(row)
                continue
            active = bool(np.abs(s.contact_force_time).max() > 0)
            e = stage_error_estimate(s, stage, nl)
            true_rel, true_db = true_errors(stage, s, ref["stage"], r)
            floor_rel, floor_db = true_errors(ref["stage"], r_prev, ref["stage"], r) \
                if r_prev is not None else (float("nan"), float("nan"))
            row.update(active=active, estimate_rel=e.amplitude_rel, true_rel=true_rel,
                       estimate_db=e.erp_db, true_db=true_db, harmonics_rel=e.harmonics_rel,
                       aliasing_rel=e.aliasing_rel, modal_rel=e.modal_rel,
                       harmonics_db=e.harmonics_db, aliasing_db=e.aliasing_db, modal_db=e.modal_db,
                       reference_floor_rel=floor_rel, reference_floor_db=floor_db,
                       estimate_s=e.seconds, notes=list(e.notes))
            row["brackets_rel"] = bool(true_rel <= e.amplitude_rel)
            row["brackets_db"] = bool(true_db <= e.erp_db)
            row["ratio_rel"] = e.amplitude_rel / true_rel if true_rel > 0 else float("inf")
            row["ratio_db"] = e.erp_db / true_db if true_db > 0 else float("inf")
            rows.append(row)
    return rows


def markdown(data):
    lines = ["# Accuracy: HBM vs time integration, cost scaling, error estimates", "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, load average "
             f"{data['load_average']} at the start (shared: timings are noisy; ratios matter). "
             f"Parts 1, 2: {data.get('parts_1_2_created', data['created'])}, load "
             f"{data.get('parts_1_2_load_average', data['load_average'])}; part 3: "
             f"{data.get('part_3_created', data['created'])}.",
             ""]
    lines += ["## 1. HBM vs time integration at equal accuracy", "",
              "Error = max over contact rows of |Δa₁| / max a₁ (first-harmonic amplitude) against an "
              "H = 40, N = 4096 HBM reference. Time integration (TI) = the first run (128, 256, … "
              "steps per period, from the linear periodic response) whose error meets the target, "
              "its cost only. HBM at equal accuracy, measured the same way = the smallest H of "
              f"{', '.join(map(str, HARMONIC_LADDER))} (N = 16H ≥ 64, cold start) whose error meets "
              "the target, its cost only. HBM adaptive = the accuracy search a run makes "
              "(`resolve_accuracy` at that frequency from H = 2, N = 32: screening solve, H ladder "
              "judged by the change to the next rung, N doubling; no reference) plus the solve at "
              "the H, N it chooses, every solve included.", "",
              "| case | f [Hz] | target | TI steps | TI s | TI error | HBM H | HBM s | HBM error "
              "| **TI / HBM** | adaptive H, N | adaptive s | adaptive error | TI / adaptive |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["hbm_vs_time"]:
        ratio = f"{r['ratio_ti_over_hbm']:.2f}" if r["ratio_ti_over_hbm"] else "TI missed"
        fixed = (f"{r['ratio_ti_over_hbm_fixed']:.2f}" if r.get("ratio_ti_over_hbm_fixed")
                 else "-")
        lines.append(f"| {r['case']} | {r['frequency_hz']:.1f} | {r['target']:g} | "
                     f"{r['ti_steps'] or '-'} | {r['ti_s']:.2f} | {r['ti_error']:.1e} | "
                     f"{r.get('hbm_fixed_H') or '-'} | {r.get('hbm_fixed_s', float('nan')):.2f} | "
                     f"{r.get('hbm_fixed_error', float('nan')):.1e} | **{fixed}** | "
                     f"{r['hbm_H']}, {r['hbm_N']}{'' if r['hbm_met'] else ' (not met)'} | "
                     f"{r['hbm_s']:.2f} | {r['hbm_error']:.1e} | {ratio} |")
    lines += ["", "## 2. Cost vs H and vs number of contacts", ""]
    sc = data["scaling"] or {"by_harmonics": [], "by_contacts": [], "exponent_harmonics": None,
                             "exponent_contacts": None}
    lines += ["Time per Newton iteration (residual by AFT + analytic Jacobian + linear solve), chain "
              "with a rattle contact on every mass (gap 1 mm, k_n = 10 k, 10 N on every mass, 14 Hz).",
              "", "| H | N | ms / iteration | active contacts | condensed unknowns |",
              "|---|---|---|---|---|"]
    lines += [f"| {r['H']} | {r['N']} | {1e3 * r['seconds_per_iteration']:.2f} | "
              f"{r['active_contacts']} of 8 | {r['condensed_unknowns']} |" for r in sc["by_harmonics"]]
    if sc["exponent_harmonics"] is not None:
        lines += ["", f"Fitted t ∝ H^p (H ≥ 4, 8 contacts, N ≈ 8H): **p = "
                  f"{sc['exponent_harmonics']:.2f}**", ""]
    lines += ["| contacts (= DOFs) | ms / iteration | active | condensed unknowns |",
              "|---|---|---|---|"]
    lines += [f"| {r['contacts']} | {1e3 * r['seconds_per_iteration']:.2f} | {r['active_contacts']} "
              f"| {r['condensed_unknowns']} |" for r in sc["by_contacts"]]
    if sc["exponent_contacts"] is not None:
        lines += ["", f"Fitted t ∝ n_c^q (n_c ≥ 4, H = 5, N = 128): **q = "
                  f"{sc['exponent_contacts']:.2f}**", ""]
    lines += shipped_markdown(data.get("estimates", []))
    if data.get("notes"):
        lines += ["## Notes", ""] + [f"- {n}" for n in data["notes"]] + [""]
    return "\n".join(lines)


def shipped_markdown(rows):
    def num(x, f=".1e"):
        return "-" if x is None or not np.isfinite(x) else format(x, f)

    lines = ["## 3. Error estimate vs true error on the shipped cases", "",
             "estimate = what the pipeline reports per point (`stage_error_estimate`: "
             "amplitude_rel, erp_db); true = against a reference at much higher H, N and, for FE "
             "cases, 3× the reduction cutoff (the case's cutoff at its own H; coarser H gives "
             "fewer modes, as in a run). Amplitude: max over contact rows of |Δa₁| / max a₁ "
             "(first-harmonic amplitude); ERP: |ΔL| [dB] of the ERP summed over harmonics. "
             "ratio = estimate / true (≥ 1: bracketed). ref H: the highest H the reference reached "
             "(raised ×1.25 a step); floor: its amplitude / ERP change over that last step. "
             "* = the case's own H, N. Parts: raw changes H → H', N → 2N and the modal part (4) "
             "(sarfe/accuracy/estimate.py).", "",
             "| case | f [Hz] | H, N | modes + RV | amp. estimate | amp. true | ratio | "
             "ERP est. [dB] | ERP true [dB] | ratio | H, N, modal parts (amp.) | ref H, floor | "
             "bracketed |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    done = [r for r in rows if "true_rel" in r]
    for r in done:
        modes = "-" if r["modes"] is None else f"{r['modes']} + {r['residual_vectors']}"
        ok = ("yes" if r["brackets_rel"] and r["brackets_db"] else
              "amp. NO" if not r["brackets_rel"] and r["brackets_db"] else
              "ERP NO" if r["brackets_rel"] else "NO")
        lines.append(
            f"| {r['case']} | {r['frequency_hz']:.1f} | {r['H']}, {r['N']}"
            f"{'*' if r['case_setting'] else ''} | {modes} | "
            f"{num(r['estimate_rel'])} | {num(r['true_rel'])} | {num(r['ratio_rel'], '.1f')} | "
            f"{num(r['estimate_db'], '.2g')} | {num(r['true_db'], '.2g')} | "
            f"{num(r['ratio_db'], '.1f')} | {num(r['harmonics_rel'])}, {num(r['aliasing_rel'])}, "
            f"{num(r['modal_rel'])} | {r['reference_H']}: {num(r['reference_floor_rel'])}, "
            f"{num(r['reference_floor_db'], '.2g')} dB | {ok} |")
    missing = [r for r in rows if "true_rel" not in r]
    n_rel = sum(r["brackets_rel"] for r in done)
    n_db = sum(r["brackets_db"] for r in done)
    lines += ["", f"Bracketed: amplitude {n_rel} of {len(done)} rows, ERP {n_db} of {len(done)}."]
    if done:
        ratios = [r["ratio_rel"] for r in done if np.isfinite(r["ratio_rel"])]
        ratios_db = [r["ratio_db"] for r in done if np.isfinite(r["ratio_db"])]
        if ratios:
            lines.append(f"Ratio estimate / true: amplitude median {np.median(ratios):.1f} "
                         f"(range {min(ratios):.2g}–{max(ratios):.2g}), ERP median "
                         f"{np.median(ratios_db):.1f} (range {min(ratios_db):.2g}–"
                         f"{max(ratios_db):.2g}).")
    for r in missing:
        lines.append(f"- {r['case']} {r['frequency_hz']:.1f} Hz H = {r['H']}: not compared "
                     f"(converged {r['converged']}, reference {r['reference']})")
    return lines + [""]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer points")
    parser.add_argument("--cases", default="lumped_chain,rattle_rig,squeak_rig",
                        help="part 1 (HBM vs time integration)")
    parser.add_argument("--shipped", default=",".join(SHIPPED), help="part 3 (shipped cases)")
    parser.add_argument("--estimates-only", action="store_true",
                        help="run part 3 only; parts 1, 2 are kept from results/accuracy.json")
    parser.add_argument("--cache", default=None,
                        help="directory for part 3's solutions (pickles reused when present)")
    parser.add_argument("--no-estimates", action="store_true",
                        help="run parts 1, 2 only; part 3 is kept from results/accuracy.json")
    parser.add_argument("--no-scaling", action="store_true")
    parser.add_argument("--no-time", action="store_true", help="skip HBM vs time integration")
    args = parser.parse_args(argv)
    data = {"created": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "load_average": [round(x, 1) for x in os.getloadavg()],
            "hbm_vs_time": [], "scaling": None, "estimates": [], "notes": []}
    previous = read_results("accuracy") if (args.estimates_only or args.no_estimates) else {}
    if args.estimates_only:           # parts 1, 2 kept
        for key in ("hbm_vs_time", "scaling", "notes"):
            data[key] = previous.get(key)
        data["notes"] = [n for n in data["notes"] or [] if not n.startswith("Estimate misses")]
        data["parts_1_2_created"] = previous.get("parts_1_2_created", previous.get("created"))
        data["parts_1_2_load_average"] = previous.get("parts_1_2_load_average",
                                                      previous.get("load_average"))
    else:
        data["parts_1_2_created"] = data["created"]
        data["parts_1_2_load_average"] = data["load_average"]
        for name in args.cases.split(",") if not args.no_time else []:
            print(f"{name}:", flush=True)
            prob = load_problem(name)
            points = nonlinear_points(prob, count=1)
            if points:
                data["hbm_vs_time"] += hbm_vs_time(prob, *points[0])
        if not args.no_scaling:
            print("scaling:", flush=True)
            data["scaling"] = cost_scaling(args.quick)
    data["part_3_created"] = data["created"]
    if args.no_estimates:             # part 3 kept
        data["estimates"] = previous.get("estimates", [])
        data["part_3_created"] = previous.get("part_3_created", previous.get("created"))
        args.shipped = ""
    for name in filter(None, args.shipped.split(",")):
        print(f"{name}:", flush=True)
        cached = Path(args.cache) / f"{name}.pkl" if args.cache else None
        if cached is not None and cached.exists():
            solved = pickle.loads(cached.read_bytes())
        else:
            solved = shipped_solutions(name, SHIPPED[name])
            if cached is not None:
                cached.parent.mkdir(parents=True, exist_ok=True)
                cached.write_bytes(pickle.dumps(solved))
        rows = shipped_table(solved)
        for r in rows:
            if "true_rel" in r:
                print(f"  {r['frequency_hz']:.1f} Hz H={r['H']} N={r['N']}: amp {r['estimate_rel']:.2e}"
                      f" vs {r['true_rel']:.2e}, ERP {r['estimate_db']:.3g} vs {r['true_db']:.3g} dB "
                      f"(H {r['harmonics_rel']:.1e}, N {r['aliasing_rel']:.1e}, modal "
                      f"{r['modal_rel']:.1e})", flush=True)
        data["estimates"] += rows
    write_results("accuracy", data)
    print(f"wrote {write_results('accuracy', markdown=markdown(data))}")


if __name__ == "__main__":
    main()
