"""Issue-15 performance targets not measured elsewhere: P1 (cases/door_trim_p1.yaml: door trim
5 mm, 12 contact pairs — 8 rattle, 4 squeak — H = 15, a continuation sweep 40 → 80 Hz reported at
≈ 200 points, default options), P4 (HBM seconds per point vs FE size and vs contact pairs × H, with
fitted exponents), the audible study and HBM vs the built-in time integrator.

Every run is a whole ``sarfe solve`` process (OPENBLAS/OMP/MKL_NUM_THREADS=1) bounded by a timeout,
timed for wall time and peak RSS (``/usr/bin/time``-free: ru_maxrss of that child, read with
os.wait4); per-stage timings come from its summary.json (``timings_s``) and, for a run that times
out, from the time stamps of its stage lines on stderr. P1 runs the whole sweep for real; only
when it does not finish in its timeout the 200-point figure is an EXTRAPOLATION (labelled so) from
the P4 5 mm run: linear stage + outputs once, plus 200 × (HBM + estimate + postprocess s / point).

Parts: ``python benchmarks/pipeline/bench_door_trim.py [p4sizes,p1,p4grid,hbm_vs_time,audible]`` (default
p4sizes,p1,p4grid); parts
not run keep their previous results from door_trim.json, marked with the date of that run.
Writes benchmarks/results/door_trim.md and .json. SARFE_BENCH_BUDGET_S bounds the whole script
(default 3600 s). The machine load (other jobs share the 2 cores) is sampled and written.
"""
import dataclasses
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, child_env, read_results, tree_pss_gb, write_results  # noqa: E402

import numpy as np
import yaml

BUDGET_S = float(os.environ.get("SARFE_BENCH_BUDGET_S", 3600))
T0 = time.perf_counter()


def left():
    return BUDGET_S - (time.perf_counter() - T0)


def door_case(mesh_m, frequencies, solver, reduction=None):
    case = yaml.safe_load((ROOT / "cases" / "door_trim.yaml").read_text())
    case["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    case["excitation"]["frequency_hz"] = list(frequencies)
    case["solver"] = solver
    if reduction:
        case["reduction"] = reduction
    return case


def run_case(case, timeout):
    """Whole `sarfe solve` process: dict(wall_s, peak_rss_gb, timed_out, exit, summary, stages)."""
    import threading

    timeout = max(5.0, min(timeout, left()))
    work = pathlib.Path(tempfile.mkdtemp(prefix="bench_door_"))
    (work / "case.yaml").write_text(yaml.safe_dump(case))
    env = child_env()
    cmd = [sys.executable, "-m", "sarfe.cli", "solve", str(work / "case.yaml"), "--output",
           str(work / "out")]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)
    stages, tail = [], []

    def read():   # stage lines "sarfe: <stage> …" with their time since start
        for raw in proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            tail.append(line)
            if line.startswith("sarfe: "):
                stages.append((round(time.perf_counter() - start, 2), line[7:60]))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    timed_out, status, usage = False, None, None
    peak_pss = 0.0                         # tree PSS: the forked workers share the model
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        peak_pss = max(peak_pss, tree_pss_gb(proc.pid) or 0.0)
        if time.perf_counter() - start > timeout:
            os.killpg(proc.pid, 9)
            _, status, usage = os.wait4(proc.pid, 0)
            timed_out = True
            break
        time.sleep(0.2)
    wall = time.perf_counter() - start
    reader.join(timeout=5)
    proc.returncode = os.waitstatus_to_exitcode(status)
    summary = None
    path = work / "out" / "summary.json"
    if path.exists():
        summary = json.loads(path.read_text())
    return {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime,
            "peak_rss_gb": usage.ru_maxrss / 1024 ** 2, "peak_tree_pss_gb": peak_pss,
            "timed_out": timed_out,
            "exit": proc.returncode, "stderr_tail": "\n".join(tail[-4:])[-400:],
            "summary": summary, "stages": stages, "load_average": os.getloadavg()}


def point_rows(summary):
    return [{"f_hz": p["frequency_hz"], "dba": p["erp"]["level_dba"], "converged": p["converged"],
             "stable": p["stable"], "iterations": p["iterations"],
             "error_estimate": p.get("error_estimate")} for p in summary["points"]]


P1_CASE = ROOT / "cases" / "door_trim_p1.yaml"
P4_FREQUENCIES = [60.0, 67.0, 80.0]   # f_max 80 Hz: the P1 cutoff (1.5 · H · f_max)


def p1_case(mesh_m=None, frequencies=None, harmonics=None, spots=None):
    """cases/door_trim_p1.yaml as data (read as sarfe reads it), optionally changed."""
    from sarfe.case.read import read_yaml

    case = read_yaml(P1_CASE)[0]
    gen = case["model"]["fe"]["generator"]
    if mesh_m is not None:
        gen["mesh_size_m"] = mesh_m
    if frequencies is not None:
        case["excitation"].pop("sweep", None)
        case["excitation"]["frequency_hz"] = list(frequencies)
        case["solver"].pop("continuation", None)
        # P4's "HBM s/point" is Newton + Hill stability of one process: with workers the stability
        # streams to another process and hbm_s holds Newton only
        case["solver"]["workers"] = 1
    if harmonics is not None:
        case["solver"]["harmonics"] = harmonics
    if spots is not None:               # (rattle, squeak): the first of each kind in the case
        rattle, squeak = spots
        gen["params"] = {"rattle_spots": max(rattle, 4), "squeak_spots": max(squeak, 2)}
        from sarfe.mesh.generators.door_trim import RATTLE_SPOTS, SQUEAK_SPOTS
        template = {c["type"]: c for c in case["contacts"]}
        names = [n for n, _ in RATTLE_SPOTS[:rattle]] + [n for n, _ in SQUEAK_SPOTS[:squeak]]
        case["contacts"] = [dict(template["rattle" if i < rattle else "squeak"], name=n,
                                 between=[f"contact_{n}_a", f"contact_{n}_b"])
                            for i, n in enumerate(names)]
    return case


def run_record(r, **extra):
    """The numbers of one run kept in the results."""
    s = r["summary"]
    out = dict(extra, **{k: r.get(k) for k in ("wall_s", "cpu_s", "peak_rss_gb",
                                               "peak_tree_pss_gb", "timed_out", "exit",
                                               "stages", "load_average")})
    if s:
        t = s["timings_s"]
        n = len(s["points"])
        out.update(timings_s=t, points_n=n, model={k: s["model"].get(k) for k in (
            "free_dofs", "modes", "reduced_dofs", "boundary_dofs", "cutoff_hz")},
            contacts=len(s["contacts"]), hbm_s_per_point=t.get("hbm_s", 0) / max(n, 1),
            per_point_s=(t.get("hbm_s", 0) + t.get("error_estimate_s", 0)
                         + t.get("postprocess_s", 0) + t.get("point_work_s", 0)) / max(n, 1),
            workers=s.get("workers"),
            converged=sum(bool(p["converged"]) for p in s["points"]),
            stable=sum(p["stable"] is True for p in s["points"]),
            loudest=(s.get("worst") or {}).get("erp_level_dba"),
            sweep_complete=s.get("sweep_complete"))
        out["points"] = point_rows(s) if n <= 10 else None
    else:
        out["stderr_tail"] = r["stderr_tail"]
    return out


def p1(timeout=900.0):
    """The whole P1 sweep for real, bounded by ``timeout``."""
    r = run_case(p1_case(), timeout)
    return run_record(r, case="cases/door_trim_p1.yaml", timeout_s=timeout)


def p4_sizes():
    """HBM s/point vs FE size: 15, 10, 5 mm, 12 pairs, H = 15, listed frequencies."""
    res = {"frequencies_hz": P4_FREQUENCIES, "sizes": []}
    for mesh_m in (0.015, 0.010, 0.005):
        r = run_case(p1_case(mesh_m, P4_FREQUENCIES), 1200.0)
        res["sizes"].append(run_record(r, mesh_m=mesh_m, pairs=12, harmonics=15))
    res["fit_size"] = fit([(g["model"]["free_dofs"],), g.get("hbm_s_per_point")]
                          for g in res["sizes"] if g.get("model"))
    return res


def p4_grid():
    """HBM s/point vs contact pairs (6, 12, 18) × H (5, 15) on the 15 mm mesh."""
    res = {"frequencies_hz": P4_FREQUENCIES, "grid": []}
    for spots in ((4, 2), (8, 4), (12, 6)):
        for H in (5, 15):
            if left() < 120:
                break
            r = run_case(p1_case(0.015, P4_FREQUENCIES, H, spots), 600.0)
            res["grid"].append(run_record(r, mesh_m=0.015, pairs=sum(spots), harmonics=H))
    res["fit_grid"] = fit([(g["pairs"], g["harmonics"]), g.get("hbm_s_per_point")]
                          for g in res["grid"])
    return res


def fit(rows):
    """Least-squares exponents of s = c · Π x_i^b_i (log-linear) over rows [(x...), s]."""
    rows = [(x, y) for x, y in rows if y and y > 0]
    if len(rows) < 2:
        return None
    X = np.array([[1.0, *np.log(np.asarray(x, dtype=float))] for x, _ in rows])
    y = np.log([y for _, y in rows])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return [float(c) for c in coef[1:]]


def audible():
    res = {"mesh_m": 0.010, "f_hz": 67.0, "vs_H": [], "vs_cutoff": [], "balanced": None}
    base = {"stability": False, "error_estimate": False}
    for H in (3, 5, 10, 15, 20, 30):
        if left() < 150:
            break
        N = max(64, 1 << int(np.ceil(np.log2(4 * H + 1))))
        r = run_case(door_case(0.010, [67.0], {**base, "harmonics": H, "samples_per_period": N}), 90)
        s = r["summary"]
        res["vs_H"].append({"harmonics": H, "samples": N, "wall_s": r["wall_s"],
                            "timed_out": r["timed_out"],
                            "dba": s["points"][0]["erp"]["level_dba"] if s else None,
                            "converged": s["points"][0]["converged"] if s else None,
                            "hbm_s": s["timings_s"]["hbm_s"] if s else None,
                            "cutoff_hz": s["model"].get("cutoff_hz") if s else None,
                            "modes": s["model"].get("modes") if s else None})
    done = [row for row in res["vs_H"] if row["dba"] is not None and row["converged"]]
    # the cutoff study at H = 10: 2x / 4x the default cutoff at H = 20 (2010 Hz, 689 modes) did
    # not finish in 150 s
    top = [row for row in done if row["harmonics"] == 10]
    H_top, N_top = 10, 64
    cutoff = top[0]["cutoff_hz"] if top else None   # the default cutoff at H = 10, read back
    for factor in (2, 4) if cutoff else ():
        if left() < 100:
            break
        r = run_case(door_case(0.010, [67.0], {**base, "harmonics": H_top, "samples_per_period": N_top},
                               {"cutoff_hz": factor * cutoff}), 150)
        s0 = r["summary"]
        res["vs_cutoff"].append({"factor": factor, "cutoff_hz": factor * cutoff,
                                 "harmonics": H_top, "wall_s": r["wall_s"],
                                 "modes": s0["model"].get("modes") if s0 else None,
                                 "dba": s0["points"][0]["erp"]["level_dba"] if s0 else None})
    if left() > 60:
        r = run_case(door_case(0.010, [67.0], {"accuracy": "balanced"}), 120)
        s = r["summary"]
        res["balanced"] = {"wall_s": r["wall_s"], "timed_out": r["timed_out"],
                           "dba": s["points"][0]["erp"]["level_dba"] if s else None,
                           "solver": s.get("solver") if s else None,
                           "accuracy": s.get("accuracy") if s else None,
                           "timings_s": s["timings_s"] if s else None}
    return res


def hbm_vs_time():
    from sarfe.hbm.time_integration import integrate_time
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.solve.points import solve_point, solver_options

    case = load_case(ROOT / "cases" / "rattle_rig.yaml")
    stage = build_linear_model(case, progress=False)
    nl = nonlinear_model(case, stage)
    options, _ = solver_options(case)
    H = case.data["solver"]["harmonics"]
    N = case.data["solver"]["samples_per_period"]
    freqs = np.linspace(24.0, 40.0, 10)
    omegas = 2 * np.pi * freqs

    def first(U):
        U = np.asarray(U)
        return U[1] - 1j * U[2]

    F = np.asarray(nl.excitation)                  # (2H+1, n) at the case's H: pad to H = 30
    F30 = np.zeros((61, F.shape[1]))
    F30[:F.shape[0]] = F
    ref_nl = dataclasses.replace(nl, excitation=F30)
    ref = [first(solve_point(ref_nl, w, 30, 1024, options, None).displacement) for w in omegas]

    def errs(Us):
        return [float(np.linalg.norm(first(U) - r) / np.linalg.norm(r)) for U, r in zip(Us, ref)]

    out = {"model_dofs": int(F.shape[1]), "frequencies_hz": freqs.tolist(), "hbm_scan": [],
           "time": []}
    target = 1e-2
    for H in (case.data["solver"]["harmonics"], 15, 20):     # the cheapest H within 1 %
        NH = max(N, 1 << int(np.ceil(np.log2(8 * H))))
        FH = np.zeros((2 * H + 1, F.shape[1]))
        FH[:min(F.shape[0], 2 * H + 1)] = F[:2 * H + 1]
        nlH = dataclasses.replace(nl, excitation=FH)
        start = time.perf_counter()
        sols = [solve_point(nlH, w, H, NH, options, None) for w in omegas]
        t = time.perf_counter() - start
        e = errs([s.displacement for s in sols])
        out["hbm_scan"].append({"harmonics": H, "samples": NH, "s": t, "error": max(e),
                                "errors": e, "converged": sum(bool(s.converged) for s in sols)})
        if max(e) <= target:
            break
    out["hbm"] = out["hbm_scan"][-1]
    t_hbm = out["hbm"]["s"]
    target = max(target, out["hbm"]["error"])
    for steps in (64, 128, 256, 512, 1024):
        if left() < 60:
            break
        start = time.perf_counter()
        rs = [integrate_time(nl.model, nl.contacts, nl.excitation, w, H, steps_per_period=steps,
                             steady_tolerance=1e-6) for w in omegas]
        t = time.perf_counter() - start
        e = errs([r.displacement_harmonics for r in rs])
        out["time"].append({"steps_per_period": steps, "s": t, "error": max(e), "errors": e,
                            "periods": [int(r.periods) for r in rs],
                            "steady": sum(bool(r.steady) for r in rs)})
        if max(e) <= target:
            break
    ok = [row for row in out["time"] if row["error"] <= target]
    out["target_error"] = target
    out["ratio"] = ok[0]["s"] / t_hbm if ok else None
    return out


def fmt(x, spec=".1f"):
    return "-" if x is None else format(x, spec)


def stage_of(run):
    """How far a run got: its last stage line and when it started [s]."""
    stages = run.get("stages") or []
    return f"{stages[-1][1]} (from {stages[-1][0]:.0f} s)" if stages else "-"


def p1_lines(e, p4):
    t = e.get("timings_s") or {}
    L = ["", "## P1: cases/door_trim_p1.yaml — 5 mm, 12 pairs (8 rattle + 4 squeak), H = 15, sweep "
         "40 → 80 Hz (max_step 0.05: ≈ 200 reported points), default options, mesh → VTU", "",
         "The whole sweep, one `sarfe solve` process (mesh from the cache after the first run; "
         "the cache is what `sarfe solve` uses). Target ≤ 60 s, ≤ 4 GB.", "",
         "| points | converged | wall s | CPU s | peak RSS GB | tree PSS GB | linear stage s | "
         "HBM s | estimate s | post s | point work s | outputs s | reached |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
         f"| {e.get('points_n', '-')} | {e.get('converged', '-')} | {e['wall_s']:.1f}"
         f"{' (TIMEOUT)' if e['timed_out'] else ''} | {e.get('cpu_s', 0):.1f} | "
         f"{e['peak_rss_gb']:.2f} | {fmt(e.get('peak_tree_pss_gb'), '.2f')} | "
         f"{fmt(t.get('linear_stage_s'))} | {fmt(t.get('hbm_s'))} | {fmt(t.get('error_estimate_s'))} | "
         f"{fmt(t.get('postprocess_s'))} | {fmt(t.get('point_work_s'))} | {fmt(t.get('outputs_s'))} | "
         f"{'done' if e.get('summary_ok', e.get('points_n')) else stage_of(e)} |", "",
         "HBM s: the sweep (Newton; with workers the Hill stability of its points streams to one "
         "worker meanwhile); point work s (with workers): the Hill stability left, the error "
         "estimates (one pool) and then the point records (a second pool) on the workers (`post s` on one process); "
         f"workers: {e.get('workers')}.", ""]
    L.append(f"Stage lines (s since start): {e.get('stages')}; load average during the run "
             f"{fmt(e['load_average'][0], '.1f')}.")
    five = next((g for g in (p4 or {}).get("sizes", []) if g["mesh_m"] == 0.005 and g.get("timings_s")),
                None)
    sweep_start = next((t for t, line in e.get("stages") or [] if line.startswith("sweep")), None)
    if sweep_start is not None:
        L += ["", f"The sweep (HBM) started {sweep_start:.0f} s after launch: checks + mesh + linear "
              "stage took that long in this run."]
    if e["timed_out"] and five:
        once = five["wall_s"] - five["per_point_s"] * five["points_n"]
        if sweep_start is not None:    # this run's own linear stage + the P4 run's outputs
            once = sweep_start + five["timings_s"].get("outputs_s", 0)
        L += ["", f"EXTRAPOLATED (fallback, the real sweep did not finish in {e['timeout_s']:.0f} s): "
              f"once {once:.1f} s (until the sweep started in this run, else the P4 5 mm run's linear "
              f"stage {five['timings_s']['linear_stage_s']:.1f} s; outputs of the P4 5 mm run "
              f"{five['timings_s'].get('outputs_s', 0):.1f} s) + 200 × {five['per_point_s']:.2f} s/point "
              f"(HBM + estimate + postprocess of the P4 5 mm run, {five['points_n']} listed points) "
              f"= {once + 200 * five['per_point_s']:.0f} s; peak RSS of that run "
              f"{five['peak_rss_gb']:.2f} GB (its points are listed frequencies, each with its own "
              "error estimate; a sweep estimates every 8th point)."]
    return L


def p4_lines(p4):
    L = ["", "## P4: HBM seconds per point (summary.json hbm_s / points: Newton + Hill stability; "
         f"listed frequencies {P4_FREQUENCIES} Hz, default options)", "",
         "| mesh | pairs | H | free DOFs | reduced DOFs | HBM s/point | estimate s | linear stage s | "
         "wall s | CPU s | peak RSS GB | converged |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for g in p4.get("sizes", []) + p4.get("grid", []):
        if not g:
            continue
        t, m = g.get("timings_s") or {}, g.get("model") or {}
        L.append(f"| {g['mesh_m'] * 1000:.0f} mm | {g['pairs']} | {g['harmonics']} | "
                 f"{m.get('free_dofs', '-')} | {m.get('reduced_dofs', '-')} | "
                 f"{fmt(g.get('hbm_s_per_point'), '.2f')} | {fmt(t.get('error_estimate_s'))} | "
                 f"{fmt(t.get('linear_stage_s'))} | {g['wall_s']:.1f}{' (TIMEOUT)' if g['timed_out'] else ''}"
                 f" | {g.get('cpu_s', 0):.1f} | {g['peak_rss_gb']:.2f} | "
                 f"{g.get('converged', '-')}/{g.get('points_n', '-')} |")
    fs, fg = p4.get("fit_size"), p4.get("fit_grid")
    L += ["", f"Fitted exponents: HBM s/point ∝ free_DOFs^{fmt(fs[0] if fs else None, '.2f')} "
          "(target: flat within 20 % over 15/10/5 mm); ∝ pairs^"
          f"{fmt(fg[0] if fg else None, '.2f')} · H^{fmt(fg[1] if fg else None, '.2f')} "
          "(target: roughly linear in pairs × H)."]
    return L


def write(results):
    write_results("door_trim", results, default=str)
    L = ["# Door trim P1, P4, audible study, HBM vs time integration (issue 15)", "",
         f"Machine: {platform.platform()}, {os.cpu_count()} cores shared with other jobs (other "
         f"helpers ran in parallel: load average at start {results['load_average']}, at the end "
         f"{results.get('load_average_end', '-')}); OPENBLAS/OMP/MKL_NUM_THREADS=1; every "
         f"`sarfe solve` a whole process, peak RSS = that process's ru_maxrss, CPU s = its user + "
         f"system time (what one core of a quiet machine would take, the stage columns are wall). Bench wall "
         f"{results['wall_s']:.0f} s. Wall seconds under this load are up to ~3× a quiet "
         "machine's.", ""]
    for name, date in (results.get("kept_from") or {}).items():
        L.append(f"- `{name}`: kept from the run of {date} (not rerun this time).")
    for note in results.get("notes") or []:      # added by hand to the .json, kept on rewrite
        L.append(f"- Note: {note}")
    p4 = {**(results.get("p4sizes") or {}), **(results.get("p4grid") or {})}
    if results.get("p1"):
        L += p1_lines(results["p1"], p4)
    if p4:
        L += p4_lines(p4)
    for name in ("p1", "p4sizes", "p4grid", "audible", "hbm_vs_time"):
        if results.get(name + "_error"):
            L += ["", f"{name} failed: {results[name + '_error']}"]
    if results.get("audible"):
        L += audible_lines(results["audible"])
    if results.get("hbm_vs_time"):
        L += hbm_lines(results["hbm_vs_time"])
    write_results("door_trim", markdown=L)


def audible_lines(a):
    L = []
    L += ["", f"## Audible: door trim {a['mesh_m'] * 1000:.0f} mm, {a['f_hz']:g} Hz, stability and "
          "estimate off", "", "| H | N | H·f Hz | dB(A) | Δ to finest | converged | HBM s | wall s |",
          "|---|---|---|---|---|---|---|---|"]
    good = [r for r in a["vs_H"] if r["dba"] is not None and r["converged"]]
    finest = good[-1]["dba"] if good else None
    for r in a["vs_H"]:
        d = None if r["dba"] is None or finest is None else r["dba"] - finest
        L.append(f"| {r['harmonics']} | {r['samples']} | {r['harmonics'] * a['f_hz']:.0f} | "
                 f"{fmt(r['dba'], '.2f')} | {fmt(d, '+.2f')} | {r['converged']} | "
                 f"{fmt(r['hbm_s'])} | {r['wall_s']:.1f}{' (timeout)' if r['timed_out'] else ''} |")
    within = [r["harmonics"] for r in good if abs(r["dba"] - finest) <= 0.5]
    first_ok = next((r["harmonics"] for r in good
                     if all(abs(q["dba"] - finest) <= 0.5 for q in good if q["harmonics"] >= r["harmonics"])),
                    None)
    L += ["", f"Smallest H from which every finer H is within 0.5 dB(A) of the finest: {first_ok} "
          f"(H·f = {fmt(None if first_ok is None else first_ok * a['f_hz'], '.0f')} Hz); within: {within}.", ""]
    if a["vs_cutoff"]:
        ten = [r for r in good if r["harmonics"] == 10]
        base = ten[0]["dba"] if ten else None
        L += [f"Cutoff study at H = 10; default cutoff {ten[0]['cutoff_hz'] if ten else '-'} Hz "
              f"({ten[0]['modes'] if ten else '-'} modes).", "",
              "| cutoff | modes | dB(A) | Δ to default cutoff (same H) | wall s |", "|---|---|---|---|---|"]
        for r in a["vs_cutoff"]:
            d = None if r["dba"] is None or base is None else r["dba"] - base
            L.append(f"| {r['factor']}× ({r['cutoff_hz']:.0f} Hz) | {r['modes']} | {fmt(r['dba'], '.2f')} | "
                     f"{fmt(d, '+.2f')} | {r['wall_s']:.1f} |")
    b = a.get("balanced")
    if b:
        d = None if b["dba"] is None or finest is None else b["dba"] - finest
        L += ["", f"`solver.accuracy: balanced` (resolution auto, estimate and stability on): "
              f"{fmt(b['dba'], '.2f')} dB(A) ({fmt(d, '+.2f')} vs finest), wall {b['wall_s']:.1f} s, "
              f"timings {json.dumps({k: round(v, 2) for k, v in (b['timings_s'] or {}).items()})}; "
              f"solver {json.dumps(b['solver'])[:300]}"]
    return L


def hbm_lines(h):
    L = []
    if h:
        L += ["", "## HBM vs time integration, rattle rig reduced model, 10 points 24–40 Hz", "",
              f"{h['model_dofs']} reduced DOFs. Reference: HBM H = 30, N = 1024 (padded excitation). "
              "Error = max over the 10 points of ‖Û₁ − Û₁,ref‖ / ‖Û₁,ref‖. The HBM H is the "
              "cheapest of (case H, 15, 20) within 1 % of the reference (chosen against the "
              "reference, not by the run's own estimate).", "",
              "| HBM H | N | s (10 points) | error | converged |", "|---|---|---|---|---|"]
        for r in h["hbm_scan"]:
            L.append(f"| {r['harmonics']} | {r['samples']} | {r['s']:.2f} | {r['error']:.1e} | "
                     f"{r['converged']}/10 |")
        L += ["", "| time int. steps/period | s (10 points) | error | steady | periods |",
              "|---|---|---|---|---|"]
        for r in h["time"]:
            L.append(f"| {r['steps_per_period']} | {r['s']:.2f} | {r['error']:.1e} | "
                     f"{r['steady']}/10 | {r['periods']} |")
        L += ["", f"Ratio time integration / HBM at error ≤ {h['target_error']:.1e}: "
              f"{fmt(h['ratio'], '.1f')}× (target ≥ 20×)."]
    return L


def main():
    parts = (sys.argv[1] if len(sys.argv) > 1 else "p4sizes,p1,p4grid").split(",")
    results = {"load_average": " ".join(f"{x:.1f}" for x in os.getloadavg()),
               "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "kept_from": {}}
    old = read_results("door_trim")
    if old is not None:         # parts not rerun keep their earlier numbers, marked
        for name in ("p1", "p4sizes", "p4grid", "audible", "hbm_vs_time"):
            if name not in parts and old.get(name) and not (name == "p1" and isinstance(old[name], list)):
                results.setdefault("notes", old.get("notes", []))
                results[name] = old[name]
                results["kept_from"][name] = ((old.get("kept_from") or {}).get(name)
                                              or old.get("date_utc", "an earlier run"))
    functions = {"p1": p1, "p4sizes": p4_sizes, "p4grid": p4_grid, "hbm_vs_time": hbm_vs_time,
                 "audible": audible}
    for name in parts:
        try:
            results[name] = functions[name]()
        except Exception as exc:    # a failing part is reported, the others still run
            results[name] = None
            results[name + "_error"] = repr(exc)
        results["wall_s"] = time.perf_counter() - T0
        results["load_average_end"] = " ".join(f"{x:.1f}" for x in os.getloadavg())
        write(results)
        print(name, "done", f"{results['wall_s']:.0f} s", flush=True)


if __name__ == "__main__":
    main()
