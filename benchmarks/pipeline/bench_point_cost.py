"""HBM seconds per point vs FE size and vs contact pairs × H (issue 15, P4) → results/point_cost.md|json.

1. FE size: cases/door_trim.yaml (4 rattle + 2 squeak contacts) at mesh 15, 10 and 5 mm, H = 5,
   N = 64, frequencies 40, 60, 80 Hz, error estimate and Hill stability off (Newton + recovery +
   ERP only). Whole `sarfe solve` processes (OPENBLAS_NUM_THREADS=1); per point =
   (hbm_s + postprocess_s) / points from summary.json → timings_s, beside the linear stage and
   the reduced model size; the sizes are run in turn ``--repeats`` times (15 10 5 15 10 5) and the
   fastest run of each size is reported (all runs in the JSON). The 5 mm run (≈ 200k DOF; mesh + Craig–Bampton dominate, ~2–4 min) is
   skipped with --quick; the whole bench stays under 10 min with it on this 2-core machine.
2. Lumped chain (:func:`chain_problem`: coupled unit oscillators, each against a stop that closes):
   seconds per point and per Newton iteration of a 5-frequency stepped sweep (each point from
   the previous one; the first is a cold start), stability off, vs pairs (1 … 64, H = 5) and vs
   H (3 … 20, 8 pairs). Exponents p of t ∝ x^p by least squares in log–log.

3. Condensation path on the 10 mm door trim's reduced model (in process): seconds per
   ``condense`` call (factorization per harmonic vs the modal path, and the one-off modal basis)
   at H = 5 and 15, and seconds per point (3 stepped frequencies, stability off) with each path.

4. Door trim sweep at H = 15 (15 mm mesh; the reduced model and the per-point cost do not depend
   on the FE size, section 1), a continuation 55 → 70 Hz (initial step 5 % of the band) capped at
   ``--sweep-points`` points and completed point by point (steps of 5 % of the band), in process
   on one linear stage: seconds per point all-in (HBM incl. stability + estimate +
   postprocess, from ``timings_s``) with the defaults (estimate and stability on) and with both
   off; and per point of that sweep (every 6th) the stability alone by the Ritz-basis method
   (the 'auto' method before issue 15's contact-row count) and by the contact-row count
   ('auto' now), with their verdicts.

5. Stages of a door-trim point, before vs after (``--stages BEFORE_TREE``): the 12-pair door trim
   of cases/door_trim_p1.yaml at 15 mm, H = 15, continuation 60 → 65 Hz at max_step 0.04, error
   estimate on, Hill stability off (another stage, timed elsewhere), whole `sarfe solve`
   processes of this tree and of BEFORE_TREE (e.g. a checkout of main) in turn (A B A B …):
   timings_s per stage (hbm, estimate, postprocess, outputs) and per point, and points per Hz.

Run: python benchmarks/pipeline/bench_point_cost.py [--quick] [--sweep-only] [--stages TREE]
(--sweep-only / --stages: that section alone, the others kept from results/point_cost.json)
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ENV, ROOT, machine, read_results, write_results  # noqa: E402

import numpy as np  # noqa: E402

import scipy.sparse as sp  # noqa: E402

from sarfe.hbm import (SolverOptions, make_contact_set, make_linear_model,  # noqa: E402
                       solve_frequency)

MESH_SIZES_M = (0.015, 0.010, 0.005)
FREQUENCIES_HZ = (40.0, 60.0, 80.0)


def door_case(mesh_size, directory):
    text = (ROOT / "cases" / "door_trim.yaml").read_text()
    text = text.replace("mesh_size_m: 0.015", f"mesh_size_m: {mesh_size}")
    text = text.replace("frequency_hz: [40.0, 52.0, 67.0, 80.0]",
                        f"frequency_hz: {list(FREQUENCIES_HZ)}")
    text = text.replace("  harmonics: 3\n", "  harmonics: 5\n  error_estimate: false\n"
                        "  stability: false\n")
    path = pathlib.Path(directory) / f"door_{mesh_size * 1e3:g}mm.yaml"
    path.write_text(text)
    return path


def door_point_cost(mesh_size, directory):
    case = door_case(mesh_size, directory)
    output = pathlib.Path(directory) / f"out_{mesh_size * 1e3:g}mm"
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "sarfe.cli", "solve", str(case), "-o", str(output),
                           "--quiet"], env=ENV, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode not in (0, 3):
        raise RuntimeError(f"door trim {mesh_size} m failed: {done.stderr[-2000:]}")
    summary = json.loads((output / "summary.json").read_text())
    t, model, points = summary["timings_s"], summary["model"], summary["points"]
    count = len(points)
    return {"mesh_size_m": mesh_size, "free_dofs": model["free_dofs"],
            "reduced_dofs": model["reduced_dofs"], "points": count,
            "nonlinear_pairs": (summary.get("contact_pruning") or {}).get("nonlinear_pairs"),
            "newton_iterations": int(sum(p["iterations"] for p in points)),
            "linear_stage_s": t["linear_stage_s"], "hbm_s": t["hbm_s"],
            "postprocess_s": t["postprocess_s"], "outputs_s": t["outputs_s"],
            "seconds_per_point": (t["hbm_s"] + t["postprocess_s"]) / count,
            "process_wall_s": wall}


def chain_problem(pairs, harmonics, force=1.0, normal_stiffness=10.0):
    """``pairs`` unit masses on ground springs (1.2 N/m minus the couplings) coupled by 0.1 N/m
    springs, D = 0.03 K, each against a stop (gap 1 m, k_n = ``normal_stiffness``); force
    ``force``·(1 + 0.2 sin j) on mass j. Stepped through Ω = 0.5 … 0.6 every stop closes."""
    n = pairs
    coupling = 0.1 * np.ones(max(n - 1, 0))
    diagonal = 1.2 * np.ones(n)
    if n > 1:
        diagonal[[0, -1]] -= 0.1
    else:
        diagonal[:] = 1.0
    K = sp.diags([diagonal, -coupling, -coupling], [0, 1, -1], format="csr")
    model = make_linear_model(sp.identity(n, format="csr"), 0.03 * K, K)
    rows = np.arange(pairs)
    G = sp.csr_matrix((np.ones(pairs), (rows, rows)), shape=(pairs, n))
    contacts = make_contact_set(G, ["rattle"] * pairs, rows, -np.ones((pairs, 2)), 1.0,
                                normal_stiffness)
    N = max(128, 1 << int(np.ceil(np.log2(8 * harmonics))))
    F = np.zeros((2 * harmonics + 1, n))
    F[1] = force * (1 + 0.2 * np.sin(np.arange(n)))
    return model, contacts, F, N


def chain_point_cost(pairs, harmonics, points=5, repeat=3):
    model, contacts, F, N = chain_problem(pairs, harmonics)
    options = SolverOptions(stability=False)
    omegas = np.linspace(0.5, 0.6, points)
    best = None
    for _ in range(repeat):
        start = time.perf_counter()
        previous, converged, iterations = None, 0, 0
        for omega in omegas:
            solution = solve_frequency(model, contacts, F, omega, harmonics, N, initial=previous,
                                       options=options)
            converged += solution.converged
            iterations += solution.iterations
            previous = solution.displacement if solution.converged else None
        elapsed = time.perf_counter() - start
        if best is None or elapsed < best[0]:
            best = (elapsed, converged, iterations)
    elapsed, converged, iterations = best
    return {"pairs": pairs, "harmonics": harmonics, "samples": N, "dofs": model.dof_count,
            "unknowns": (2 * harmonics + 1) * contacts.row_count, "converged": int(converged),
            "newton_iterations": int(iterations), "seconds_per_point": float(elapsed / points),
            "seconds_per_iteration": float(elapsed / max(iterations, 1))}


def condensation_paths(directory, mesh_size=0.010):
    """Section 3 of the module docstring."""
    import sarfe.hbm.dynamic_stiffness as linear
    from sarfe.hbm.modal import modal_basis
    from sarfe.pipeline import load_case
    from sarfe.pipeline.model.linear_stage import build_linear_model
    from sarfe.pipeline.model.nonlinear_model import nonlinear_model

    case = load_case(door_case(mesh_size, directory))
    nl = nonlinear_model(case, build_linear_model(case))
    model, contacts = nl.model, nl.contacts
    start = time.perf_counter()
    basis = modal_basis(model)
    out = {"mesh_size_m": mesh_size, "reduced_dofs": model.dof_count,
           "contact_rows": contacts.row_count, "modal_basis_s": time.perf_counter() - start,
           "modal_applies": basis is not None, "condense": []}
    if basis is None:
        return out
    omega = 2 * np.pi * 60.0
    for H in (5, 15):
        F = np.zeros((2 * H + 1, model.dof_count))
        F[1], F[2] = nl.excitation_amplitude.real, -nl.excitation_amplitude.imag
        row = {"harmonics": H}
        for name, modal in (("factorization", False), ("modal", basis)):
            times = []
            for _ in range(3):
                t0 = time.perf_counter()
                linear.condense(model, contacts.gap_map, F, omega, modal=modal)
                times.append(time.perf_counter() - t0)
            row[f"{name}_s"] = min(times)
        out["condense"].append(row)
    options = SolverOptions(stability=False)
    H, N = 5, 64
    original = linear.cached_modal_basis
    for name, chooser in (("factorization", lambda m: None), ("modal", original)):
        linear.cached_modal_basis = chooser
        try:
            start, previous = time.perf_counter(), None
            for f in FREQUENCIES_HZ:
                s = solve_frequency(model, contacts, nl.excitation, 2 * np.pi * f, H, N,
                                    initial=previous, options=options)
                previous = s.displacement if s.converged else None
            out[f"{name}_seconds_per_point"] = (time.perf_counter() - start) / len(FREQUENCIES_HZ)
        finally:
            linear.cached_modal_basis = original
    return out


def door_sweep_cost(directory, mesh_size=0.015, harmonics=15, points=20):
    """Section 4 of the module docstring."""
    from sarfe.hbm.residual import Problem, full_residual
    from sarfe.hbm.stability.condensed import condensed_stability
    from sarfe.hbm.stability.contact_terms import ContactOperator
    from sarfe.hbm.stability.rows import contact_row_stability
    from sarfe.case.read import read_yaml
    from sarfe.pipeline import load_case
    from sarfe.pipeline.model.linear_stage import build_linear_model
    from sarfe.pipeline.model.nonlinear_model import nonlinear_model
    from sarfe.pipeline.run import solve_case

    data = read_yaml(door_case(mesh_size, directory))[0]
    data["excitation"].pop("frequency_hz")
    data["excitation"]["sweep"] = {"start_hz": 55.0, "end_hz": 70.0}
    runs = {}
    stage = None
    for label, on in (("defaults", True), ("stability and estimate off", False)):
        data["solver"] = {"harmonics": harmonics, "stability": on, "error_estimate": on,
                          "continuation": {"max_points": points, "initial_step": 0.05}}
        case = load_case(data, base_dir=ROOT / "cases")
        if stage is None:
            start = time.perf_counter()
            stage = build_linear_model(case)
            linear_s = time.perf_counter() - start
        start = time.perf_counter()
        result = solve_case(case, linear_stage=stage, write=False)
        wall = time.perf_counter() - start
        t, pts = result.summary["timings_s"], result.summary["points"]
        per = (t["hbm_s"] + t.get("error_estimate_s", 0.0) + t["postprocess_s"]) / len(pts)
        runs[label] = {"points": len(pts), "wall_s": wall, "hbm_s": t["hbm_s"],
                       "estimate_s": t.get("error_estimate_s", 0.0),
                       "postprocess_s": t["postprocess_s"], "seconds_per_point": per,
                       "newton_iterations": int(sum(p["iterations"] for p in pts)),
                       "stable": [p["stable"] for p in pts]}
        if not on:
            solutions = result.solutions
    nl_model = nonlinear_model(case, stage)
    compare = []
    for s in [s for s in solutions if s.converged][::6]:
        problem = Problem(nl_model.model, nl_model.contacts, nl_model.excitation[:2 * harmonics + 1],
                          harmonics, s.samples_per_period)
        ev = full_residual(problem, s.displacement.ravel(), s.omega, assemble=False)
        operator = ContactOperator(problem, s.displacement, s.omega, ev.forces)
        row = {"frequency_hz": s.omega / (2 * np.pi)}
        for name, method in (("ritz", condensed_stability), ("contact_rows", contact_row_stability)):
            start = time.perf_counter()
            out = method(nl_model.model, nl_model.contacts, s.omega, harmonics, ev.forces, operator)
            row[f"{name}_s"] = time.perf_counter() - start
            row[f"{name}_stable"] = None if out is None else out.stable
            row[f"{name}_leading"] = None if out is None else float(out.leading)
        compare.append(row)
    return {"mesh_size_m": mesh_size, "harmonics": harmonics, "reduced_dofs": stage.dof_count,
            "contact_rows": nl_model.contacts.row_count, "linear_stage_s": linear_s, "runs": runs,
            "stability": compare}


STAGE_CASE_OVERRIDES = {"mesh_size_m": 0.015, "sweep": {"start_hz": 60.0, "end_hz": 65.0},
                        "continuation": {"initial_step": 0.04, "max_step": 0.04}}


def stage_case(directory):
    """cases/door_trim_p1.yaml at 15 mm, 60 → 65 Hz, max_step 0.04, stability off (section 5)."""
    import yaml

    case = yaml.safe_load((ROOT / "cases" / "door_trim_p1.yaml").read_text())
    case["model"]["fe"]["generator"]["mesh_size_m"] = STAGE_CASE_OVERRIDES["mesh_size_m"]
    case["excitation"]["sweep"] = dict(STAGE_CASE_OVERRIDES["sweep"])
    case["solver"]["continuation"] = dict(STAGE_CASE_OVERRIDES["continuation"])
    case["solver"]["stability"] = False
    path = pathlib.Path(directory) / "door_trim_stages.yaml"
    path.write_text(yaml.safe_dump(case, sort_keys=False))
    return path


def stage_costs(tree, case_path, directory):
    """One `sarfe solve` process of the code in ``tree``: its timings_s, points, Newton
    iterations, frequency span and the tree's git commit."""
    out = pathlib.Path(directory) / f"out_{abs(hash((str(tree), time.time())))}"
    env = dict(ENV, PYTHONPATH=str(tree))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "sarfe.cli", "solve", str(case_path), "-o", str(out),
                    "--force", "--quiet"], env=env, check=False, capture_output=True, cwd=directory)
    wall = time.perf_counter() - start
    summary = json.loads((out / "summary.json").read_text())
    t = summary["timings_s"]
    points = summary["points"]
    f = [p["frequency_hz"] for p in points]
    marker = pathlib.Path(tree) / "COMMIT"          # an exported tree (git archive) names it
    commit = marker.read_text().strip() if marker.exists() else subprocess.run(
        ["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
        capture_output=True, text=True).stdout.strip()
    return {"tree": str(tree), "commit": commit, "process_wall_s": wall, "points": len(points),
            "newton_iterations": int(sum(p["iterations"] for p in points)),
            "points_per_hz": len(points) / max(max(f) - min(f), 1e-9),
            "linear_stage_s": t.get("linear_stage_s", float("nan")), "hbm_s": t["hbm_s"],
            "estimate_s": t.get("error_estimate_s", 0.0),
            "postprocess_s": t["postprocess_s"] - t.get("error_estimate_s", 0.0),
            "outputs_s": t.get("outputs_s", float("nan")),
            "per_point_s": (t["hbm_s"] + t["postprocess_s"] + t.get("outputs_s", 0.0))
            / max(len(points), 1)}


def stages_before_after(before_tree, repeats=2):
    """Section 5: alternated runs of ``before_tree`` and this tree; the fastest of each kept."""
    runs = {"before": [], "after": []}
    with tempfile.TemporaryDirectory() as directory:
        case = stage_case(directory)
        for _ in range(repeats):
            for label, tree in (("before", before_tree), ("after", ROOT)):
                runs[label].append(stage_costs(tree, case, directory))
    best = {label: min(r, key=lambda x: x["per_point_s"]) for label, r in runs.items()}
    return {"case": "cases/door_trim_p1.yaml with " + json.dumps(STAGE_CASE_OVERRIDES)
            + ", stability off", "load_average_end": os.getloadavg(), "best": best,
            "all_runs": runs}


def exponent(x, t):
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(t, float)), 1)[0])


def write(results):
    write_results("point_cost", results, indent=2)
    lines = ["# HBM seconds per point vs FE size and vs contact pairs × H (issue 15, P4)", "",
             f"Machine: {results['machine']}, {results['cpu_count']} cores, load average at start "
             f"{results['load_average'][0]:.2f}; OPENBLAS_NUM_THREADS=1. Bench wall "
             f"{results['bench_wall_s']:.0f} s.", "",
             "## Door trim (H = 5, N = 64, 3 frequencies, estimate and stability off)", "",
             f"Fastest of {len(results['door_trim_all_seconds_per_point'])} alternated runs per "
             f"size; all runs, s / point: {results['door_trim_all_seconds_per_point']}.", "",
             "| mesh | free DOFs | reduced DOFs | nonlinear pairs | Newton its | linear stage s | "
             "HBM s | post s | s / point | process s |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in results["door_trim"]:
        lines.append(f"| {r['mesh_size_m'] * 1e3:g} mm | {r['free_dofs']} | {r['reduced_dofs']} | "
                     f"{r['nonlinear_pairs']} | {r['newton_iterations']} | "
                     f"{r['linear_stage_s']:.1f} | {r['hbm_s']:.2f} | {r['postprocess_s']:.2f} | "
                     f"{r['seconds_per_point']:.3f} | {r['process_wall_s']:.1f} |")
    door = results["door_trim"]
    if len(door) > 1:
        per = np.array([r["seconds_per_point"] for r in door])
        lines += ["", f"Spread of s / point over the mesh sizes: max/min = {per.max() / per.min():.2f} "
                  f"(target: flat within 20 %, i.e. ≤ 1.2); exponent vs free DOFs "
                  f"{exponent([r['free_dofs'] for r in door], per):.2f}."]
    lines += ["", "## Lumped chain (coupled oscillators against stops, 5-point stepped sweep, stability off)", "",
              "| pairs | H | N | DOFs | unknowns | converged | Newton its | s / point | ms / iteration |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in results["chain_pairs"] + results["chain_harmonics"]:
        lines.append(f"| {r['pairs']} | {r['harmonics']} | {r['samples']} | {r['dofs']} | "
                     f"{r['unknowns']} | {r['converged']}/5 | {r['newton_iterations']} | "
                     f"{r['seconds_per_point']:.4f} | {1e3 * r['seconds_per_iteration']:.2f} |")
    lines += ["", f"Fitted exponents, per point: t ∝ pairs^{results['exponent_pairs']:.2f} (H = 5), "
              f"t ∝ H^{results['exponent_harmonics']:.2f} (8 pairs; N grows with H); per Newton "
              f"iteration: pairs^{results['exponent_pairs_iteration']:.2f}, "
              f"H^{results['exponent_harmonics_iteration']:.2f}. The iteration counts vary with "
              "the problem (cold start, homotopy), so the per-iteration exponents isolate the cost "
              "of one residual + Jacobian + solve."]
    c = results.get("condensation")
    if c:
        lines += ["", f"## Condensation path, door trim {c['mesh_size_m'] * 1e3:g} mm "
                  f"({c['reduced_dofs']} reduced DOFs, {c['contact_rows']} contact rows)", "",
                  f"Modal basis (eigh + Cholesky, once per model): {c['modal_basis_s']:.3f} s.", "",
                  "| H | condense, factorization s | condense, modal s |", "|---|---|---|"]
        lines += [f"| {r['harmonics']} | {r['factorization_s']:.4f} | {r['modal_s']:.4f} |"
                  for r in c["condense"]]
        if "modal_seconds_per_point" in c:
            lines += ["", f"Seconds per point (H = 5, N = 64, stability off, in process): "
                      f"factorization {c['factorization_seconds_per_point']:.3f}, "
                      f"modal {c['modal_seconds_per_point']:.3f}."]
    d = results.get("door_sweep")
    if d:
        lines += ["", f"## Door trim sweep at H = {d['harmonics']} ({d['mesh_size_m'] * 1e3:g} mm, "
                  f"{d['reduced_dofs']} reduced DOFs, {d['contact_rows']} contact rows), "
                  "55 → 70 Hz continuation, in process"
                  + (f"; load average at its end {d['load_average'][0]:.1f}"
                     if d.get("load_average") else ""), "",
                  "| options | points | Newton its | HBM s | estimate s | post s | s / point all-in |",
                  "|---|---|---|---|---|---|---|"]
        for label, r in d["runs"].items():
            lines.append(f"| {label} | {r['points']} | {r['newton_iterations']} | {r['hbm_s']:.2f} | "
                         f"{r['estimate_s']:.2f} | {r['postprocess_s']:.2f} | "
                         f"{r['seconds_per_point']:.3f} |")
        lines += ["", "Stability alone per point (the same converged points): Ritz basis (the "
                  "'auto' method before) vs the contact-row count ('auto' now; None = handed over "
                  "to the Ritz method).", "",
                  "| f Hz | Ritz s | Ritz verdict (leading 1/s) | contact rows s | contact rows verdict |",
                  "|---|---|---|---|---|"]
        for r in d["stability"]:
            lines.append(f"| {r['frequency_hz']:.2f} | {r['ritz_s']:.2f} | {r['ritz_stable']} "
                         f"({r['ritz_leading']:.3f}) | {r['contact_rows_s']:.2f} | "
                         f"{r['contact_rows_stable']} |")
    profile = results.get("profile")
    if profile:          # wall-clock sampling profiles of a door-trim sweep (written by hand)
        lines += ["", "## Where a door-trim point's time goes (H = 15, defaults; sampled wall clock)",
                  "", profile["setup"], "", "| share of the solve | before | after |",
                  "|---|---|---|"]
        lines += [f"| {name} | {before} | {after} |" for name, before, after in profile["rows"]]
        lines += [""] + profile["notes"]
    st = results.get("stages")
    if st:
        lines += ["", "## Stages of a door-trim point, before vs after (issue 15, task pointfast)",
                  "",
                  f"{st['case']}; whole `sarfe solve` processes alternated (before, after, before, "
                  f"after), fastest of each; load average at the end "
                  f"{st['load_average_end'][0]:.1f} "
                  "(2 shared cores: absolute seconds are inflated, compare the columns).", "",
                  "| code | points | points / Hz | Newton its | HBM s | estimate s | post s | "
                  "outputs s | s / point (HBM + estimate + post + outputs) |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for label in ("before", "after"):
            r = st["best"][label]
            lines.append(f"| {label} ({r['commit']}) | {r['points']} | {r['points_per_hz']:.1f} | "
                         f"{r['newton_iterations']} | {r['hbm_s']:.2f} | {r['estimate_s']:.2f} | "
                         f"{r['postprocess_s']:.2f} | {r['outputs_s']:.2f} | "
                         f"{r['per_point_s']:.3f} |")
        for note in st.get("notes", []):
            lines += ["", note]
    write_results("point_cost", markdown=lines)
    print("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="skip the 5 mm door trim")
    parser.add_argument("--repeats", type=int, default=2, help="door-trim runs per size, alternated")
    parser.add_argument("--sweep-only", action="store_true",
                        help="section 4 only; the others kept from results/point_cost.json")
    parser.add_argument("--sweep-points", type=int, default=20)
    parser.add_argument("--stages", metavar="BEFORE_TREE",
                        help="section 5 alone against the code in BEFORE_TREE (e.g. main)")
    args, _ = parser.parse_known_args()   # run_all.py passes its own arguments
    start = time.perf_counter()
    if args.stages:
        results = read_results("point_cost")
        results["stages"] = stages_before_after(pathlib.Path(args.stages).resolve())
        write(results)
        return
    if args.sweep_only:
        results = read_results("point_cost")
        with tempfile.TemporaryDirectory() as directory:
            results["door_sweep"] = door_sweep_cost(directory, points=args.sweep_points)
        results["door_sweep"]["load_average"] = os.getloadavg()
        write(results)
        return
    results = machine()
    sizes = MESH_SIZES_M[:-1] if args.quick else MESH_SIZES_M
    with tempfile.TemporaryDirectory() as directory:
        runs = [[door_point_cost(size, directory) for size in sizes]       # 15 10 5 15 10 5
                for _ in range(args.repeats)]
        results["door_trim"] = [min(same, key=lambda r: r["seconds_per_point"])
                                for same in zip(*runs)]
        results["door_trim_all_seconds_per_point"] = [[r["seconds_per_point"] for r in run]
                                                      for run in runs]
        results["condensation"] = condensation_paths(directory)
    results["chain_pairs"] = [chain_point_cost(p, 5) for p in (1, 4, 16, 64)]
    results["chain_harmonics"] = [chain_point_cost(8, h) for h in (3, 5, 10, 20)]
    results["exponent_pairs"] = exponent([r["pairs"] for r in results["chain_pairs"]],
                                         [r["seconds_per_point"] for r in results["chain_pairs"]])
    results["exponent_harmonics"] = exponent(
        [r["harmonics"] for r in results["chain_harmonics"]],
        [r["seconds_per_point"] for r in results["chain_harmonics"]])
    results["exponent_pairs_iteration"] = exponent(
        [r["pairs"] for r in results["chain_pairs"]],
        [r["seconds_per_iteration"] for r in results["chain_pairs"]])
    results["exponent_harmonics_iteration"] = exponent(
        [r["harmonics"] for r in results["chain_harmonics"]],
        [r["seconds_per_iteration"] for r in results["chain_harmonics"]])
    with tempfile.TemporaryDirectory() as directory:
        results["door_sweep"] = door_sweep_cost(directory, points=args.sweep_points)
    results["bench_wall_s"] = time.perf_counter() - start
    write(results)


if __name__ == "__main__":
    main()
