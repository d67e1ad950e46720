"""Contact pruning benchmark (solver.prune_contacts) → benchmarks/results/pruning.md and .json.

Wall time of the frequency points (summary.json timings_s.hbm_s: screening + HBM + check +
restore) with pruning on and off, same linear stage, and how far the results differ:

1. instrument_panel (shipped, five listed frequencies): the two front rattle spots stay open.
2. door_trim (shipped, four listed frequencies): one of four rattle spots stays open.
   Both also with solver.stability false: Hill stability of every point costs the same with or
   without the dropped contacts and dominates their HBM time.
3. lumped_rattle (shipped 3-DOF sweep 30 → 90 Hz) with two extra rattle contacts, a 5 mm stop that
   stays open and a clip preloaded by 50 N that stays closed.

Listed frequencies: same ω, so the ERP levels are compared point by point. Sweeps: the pruned
continuation takes its own adaptive points on the same curve; the peak ERP is compared.

Part ``screen`` (issue 15 P1): the cost of the screening pass alone on the P1 door trim
(cases/door_trim_p1.yaml: 12 pairs, H = 15, 40 → 80 Hz) at 15, 10 and 5 mm, and on every shipped
case: the direct solves of model size per ω (``screen_contacts(..., modal=False)``, the code
before the contact-row pass) against the contact-row pass (modal compliance + Woodbury update of
the linearized contacts), cold (the modal basis computed, as in ``sarfe solve``) and warm (basis
cached); the decisions of both and the largest clearance difference.

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/engine/bench_pruning.py [cases,screen]  (default both; a
part not run keeps its previous results from pruning.json)
"""
import copy
import dataclasses
import json
import os
import pathlib
import platform
import sys
import time
import warnings

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import CASES, read_results, write_results  # noqa: E402

import numpy as np  # noqa: E402

from sarfe.pipeline import build_linear_model, load_case, solve_case  # noqa: E402



def lumped_with_extra_contacts():
    case = load_case(CASES / "lumped_rattle.yaml")
    data = copy.deepcopy(case.data)
    data["contacts"] += [
        {"name": "far_stop", "type": "rattle", "normal_dof": {"dof": 2}, "gap_m": 5.0e-3,
         "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5},
        {"name": "clip", "type": "rattle", "normal_dof": {"dof": 1, "relative_to": 2},
         "preload_N": 50.0, "normal_stiffness_N_m": 1.0e6, "tolerance_m": 2e-5}]
    data["name"] = "lumped_rattle_extra_contacts"
    return load_case(data, base_dir=case.base_dir)


def run(case, stage, prune):
    data = copy.deepcopy(case.data)
    data["solver"]["prune_contacts"] = prune
    data["solver"]["workers"] = 1      # the process time then counts all the work
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = time.process_time()
        result = solve_case(load_case(data, base_dir=case.base_dir), linear_stage=stage,
                            write=False)
    return result, time.process_time() - start


def without_stability(case):
    """The case with solver.stability false: Hill stability (an eigenvalue problem of size
    2(2H+1)n per point, independent of the contacts) dominates the FE cases' HBM time."""
    data = copy.deepcopy(case.data)
    data["solver"]["stability"] = False
    data["name"] = f"{case.name}_stability_off"
    return load_case(data, base_dir=case.base_dir)


def hbm_cpu(case, stage, prune, repeats):
    """Best-of-``repeats`` CPU time [s] of the frequency points alone (screening, HBM, check and
    restore: :func:`sarfe.pipeline.solve.pruned_points.solve_points_pruned`)."""
    from sarfe.pipeline.model.nonlinear_model import nonlinear_model
    from sarfe.pipeline.solve.pruned_points import solve_points_pruned

    data = copy.deepcopy(case.data)
    data["solver"]["prune_contacts"] = prune
    data["solver"]["workers"] = 1
    case = load_case(data, base_dir=case.base_dir)
    nl = nonlinear_model(case, stage)
    best = float("inf")
    for _ in range(repeats):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start = time.process_time()
            solve_points_pruned(case.config.solver, case.config.excitation, nl)
            best = min(best, time.process_time() - start)
    return best


def compare(case, stage=None, repeats=0):
    stage = stage or build_linear_model(case)
    pruned, t_pruned = run(case, stage, True)
    full, t_full = run(case, stage, False)
    report = pruned.summary["contact_pruning"]
    levels = [np.array([p["erp"]["level_db"] for p in r.summary["points"]]) for r in (pruned, full)]
    same_points = len(levels[0]) == len(levels[1]) and all(
        a.omega == b.omega for a, b in zip(pruned.solutions, full.solutions))
    row = {"case": case.name, "points": [len(levels[0]), len(levels[1])],
           "hbm_s": [pruned.summary["timings_s"]["hbm_s"], full.summary["timings_s"]["hbm_s"]],
           "solve_case_cpu_s": [t_pruned, t_full],
           "decisions": {c["name"]: c["decision"] for c in report["contacts"]},
           "pairs": report["pairs"], "nonlinear_pairs": report["nonlinear_pairs"],
           "applied": report["applied"], "fallback": report["fallback"],
           "all_converged": [pruned.summary["all_converged"], full.summary["all_converged"]],
           "same_points": same_points,
           "peak_level_db": [float(levels[0].max()), float(levels[1].max())]}
    if same_points:
        row["max_level_difference_db"] = float(np.abs(levels[0] - levels[1]).max())
        row["max_displacement_difference_rel"] = max(
            float(np.abs(a.displacement[1:] - b.displacement[1:]).max()
                  / np.abs(b.displacement).max()) for a, b in zip(pruned.solutions, full.solutions))
    if repeats:
        row["hbm_cpu_best_s"] = [hbm_cpu(case, stage, True, repeats),
                                 hbm_cpu(case, stage, False, repeats)]
    print(json.dumps(row), flush=True)
    return row, stage


def door_trim_p1(mesh_m):
    from sarfe.case.read import read_yaml

    data = read_yaml(CASES / "door_trim_p1.yaml")[0]
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["name"] = f"door_trim_p1_{mesh_m * 1e3:g}mm"
    return load_case(data, base_dir=CASES)


def best_of(repeats, run):
    """(result of the last run, best wall time [s] of ``repeats`` runs)."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return result, best


def screen_row(case, repeats=3):
    """The screening pass of ``case`` as ``sarfe solve`` runs it (its frequencies and margin):
    direct solves vs the contact-row pass (cold: a fresh model object, the modal basis computed;
    warm: cached)."""
    import scipy.sparse as sp

    import sarfe.hbm.pruning as pruning
    from sarfe.pipeline.model.nonlinear_model import nonlinear_model
    from sarfe.pipeline.solve.pruned_points import pruning_options, screening_frequencies

    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        stage = build_linear_model(case)
    linear_s = time.perf_counter() - start
    nl = nonlinear_model(case, stage)
    margin = pruning_options(case.config.solver)[1]
    (omegas, frequencies_s) = best_of(1, lambda: screening_frequencies(case.config.excitation, nl))
    F = np.asarray(nl.excitation)
    screen = (lambda model, modal: pruning.screen_contacts(model, nl.contacts, F, omegas, margin,
                                                           modal=modal))
    counted = []
    solve = pruning._solve
    pruning._solve = lambda A, b: (counted.append(A.shape[0]), solve(A, b))[1]
    try:
        direct, direct_s = best_of(repeats, lambda: screen(nl.model, False))
        direct_solves = len(counted) // repeats
        counted.clear()
        cold, cold_s = best_of(repeats, lambda: screen(dataclasses.replace(nl.model), True))
        modal_solves = len(counted) // repeats
        warm_model = dataclasses.replace(nl.model)
        screen(warm_model, True)
        warm, warm_s = best_of(repeats, lambda: screen(warm_model, True))
    finally:
        pruning._solve = solve
    finite = [(a.clearance, b.clearance) for a, b in zip(direct, cold)
              if np.isfinite(a.clearance)]
    row = {"case": case.name, "linear_stage_s": linear_s, "dofs": int(nl.model.dof_count),
           "dense": not sp.issparse(nl.model.stiffness), "pairs": int(nl.contacts.count),
           "contact_rows": int(nl.contacts.row_count), "frequencies": int(len(omegas)),
           "natural_frequencies_s": frequencies_s,
           "direct": {"solves": direct_solves, "size": int(nl.model.dof_count), "s": direct_s},
           "contact_rows_pass": {"model_solves": modal_solves, "cold_s": cold_s, "warm_s": warm_s},
           "same_decisions": [d.decision for d in direct] == [d.decision for d in cold]
           == [d.decision for d in warm],
           "decisions": {k: sum(d.decision == k for d in cold)
                         for k in ("open", "closed", "nonlinear")},
           "max_clearance_difference": max((abs(a - b) for a, b in finite), default=0.0)}
    print(json.dumps(row), flush=True)
    return row


def screen_rows():
    rows = [screen_row(door_trim_p1(mesh)) for mesh in (0.015, 0.010, 0.005)]
    for name in ("lumped_rattle", "squeak_rig", "rattle_rig", "rattle_rig_deck", "door_trim",
                 "instrument_panel"):
        rows.append(screen_row(load_case(CASES / f"{name}.yaml")))
    return rows


def screen_lines(screen):
    lines = ["## The screening pass alone (part `screen`, issue 15 P1)", "",
             f"Machine: {screen['machine']}", "",
             "The screen as `sarfe solve` runs it (the case's frequencies: a sweep's 201-point "
             "grid plus the linearized natural frequencies in the band; its margin). Direct: one solve "
             "of model size per ω and loaded order (plus the static one) — the code before. "
             "Contact rows: the modal compliance of the model at the contact rows with the "
             "linearized contacts' springs and dashpots as a Woodbury update, vectorized over ω "
             "(`sarfe.hbm.pruning.contact_row_responses`); cold: the model's modal basis computed "
             "(then cached on the model: the sweep's condensations reuse it), warm: cached. Wall "
             "time, best of 3, one BLAS thread. Clearance difference: largest |Δ| of the screened "
             "quantity (relative to |g|) between the direct and the contact-row pass.", "",
             "| case | reduced DOFs (dense) | pairs / rows | ω | direct: solves × size, s "
             "| contact rows: model solves, cold s, warm s | speed-up (cold) | decisions "
             "(open/closed/nonlinear) | same | max clearance diff |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in screen["rows"]:
        d, m = r["direct"], r["contact_rows_pass"]
        lines.append(
            f"| {r['case']} | {r['dofs']} ({'dense' if r['dense'] else 'sparse'}) | {r['pairs']} / "
            f"{r['contact_rows']} | {r['frequencies']} | {d['solves']} × {d['size']}, "
            f"{d['s']:.3f} | {m['model_solves']}, {m['cold_s']:.3f}, {m['warm_s']:.4f} | "
            f"{d['s'] / m['cold_s']:.1f}× | {r['decisions']['open']}/{r['decisions']['closed']}/"
            f"{r['decisions']['nonlinear']} | {r['same_decisions']} | "
            f"{r['max_clearance_difference']:.1e} |")
    return lines


def machine_line():
    load = os.getloadavg()[0]
    return (f"{platform.platform()}, {os.cpu_count()} cores, load average at start {load:.1f} "
            "(shared machine: timings are upper bounds). One BLAS thread.")


def main():
    parts = (sys.argv[1] if len(sys.argv) > 1 else "cases,screen").split(",")
    previous = read_results("pruning", {})
    machine = previous.get("machine", "")
    rows = previous.get("rows", [])
    screen = previous.get("screen")
    if "cases" in parts:
        machine = machine_line()
        rows = []
        for name in ("instrument_panel", "door_trim"):
            case = load_case(CASES / f"{name}.yaml")
            row, stage = compare(case)
            rows += [row, compare(without_stability(case), stage, repeats=3)[0]]
        rows.append(compare(lumped_with_extra_contacts(), repeats=2)[0])
    if "screen" in parts:
        screen = {"machine": machine_line(), "date": time.strftime("%Y-%m-%d"),
                  "rows": screen_rows()}
    write_results("pruning", {"machine": machine, "rows": rows, "screen": screen}, indent=2)
    lines = ["# Contact pruning benchmark (solver.prune_contacts)", "", f"Machine: {machine}", "",
             "Pruned / full contact set, the linear stage shared. HBM wall: `timings_s.hbm_s` of "
             "summary.json (screening + HBM + check + restore). CPU: process time of the whole "
             "solve_case (one BLAS thread; robust to the machine's load, unlike wall time). "
             "Level differences: same ω, ERP level in dB; displacement: harmonics ≥ 1, relative "
             "to the peak. With stability on, Hill stability of every point (the same eigenvalue "
             "problems with or without the dropped contacts) is most of the HBM time. HBM CPU best "
             "of n: the frequency points alone (screening + HBM + check + restore), best of 3 "
             "(FE, stability off) or 2 (lumped) runs. `solver.workers: 1` (one process: its CPU "
             "time is all the work). Sweeps: each run's continuation takes its own points, so "
             "the peak ERP of the two is sampled at different ω.", "",
             "| case | pairs kept / all | screened open or closed | points | HBM wall pruned / "
             "full [s] | solve_case CPU pruned / full [s] | HBM CPU best of n, pruned / full [s] "
             "| peak ERP pruned / full [dB] | max level diff [dB] | max displacement diff |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        linear = ", ".join(f"{k} {v}" for k, v in r["decisions"].items() if v != "nonlinear")
        kept = f"{r['nonlinear_pairs']} / {r['pairs']}" + (" (fallback)" if r["fallback"] else "")
        diff = (f"{r['max_level_difference_db']:.1e}" if r["same_points"] else "— (own ω)")
        disp = (f"{r['max_displacement_difference_rel']:.1e}" if r["same_points"] else "—")
        lines.append(f"| {r['case']} | {kept} | {linear or '—'} | {r['points'][0]} / "
                     f"{r['points'][1]} | {r['hbm_s'][0]:.2f} / {r['hbm_s'][1]:.2f} | "
                     f"{r['solve_case_cpu_s'][0]:.2f} / {r['solve_case_cpu_s'][1]:.2f} | "
                     + (f"{r['hbm_cpu_best_s'][0]:.2f} / {r['hbm_cpu_best_s'][1]:.2f} | "
                        if "hbm_cpu_best_s" in r else "— | ") +
                     f"{r['peak_level_db'][0]:.3f} / {r['peak_level_db'][1]:.3f} | {diff} | "
                     f"{disp} |")
    if screen:
        lines += [""] + screen_lines(screen)
    write_results("pruning", markdown=lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
