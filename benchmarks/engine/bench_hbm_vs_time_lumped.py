"""Wall time of harmonic balance vs time integration at equal accuracy of the first harmonic.

Lumped stand-ins for the rattle and squeak rigs (the case-file rigs come later): the 2-DOF rattle
chain and the 3-DOF squeak model of tests/hbm/test_hbm_vs_time.py. Accuracy = max over DOFs of
|û₁ − û₁,ref| / max |û₁,ref| (complex first-harmonic amplitude). Reference: time integration with
2048 steps per period, Richardson-extrapolated with 4096 (started from an H = 30 HBM solution).

For each target (1 %, 0.1 %) the cheapest setting that reaches it is timed (best of 3):
HBM over H × N (solve_frequency from its own linear guess; the fastest of the first six settings
that reach the target), time integration over the step count (cold start from the linear periodic
solution, as a user would run it without HBM; steady-state tolerance = target / 100; the fastest of
the first three step counts that reach the target), with and without Richardson extrapolation.

Writes benchmarks/results/hbm_vs_time_lumped.md and .json (the case rigs: bench_hbm_vs_time.py).
"""
import importlib.util
import os
import pathlib
import platform
import time
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, write_results  # noqa: E402

import numpy as np

import sarfe.hbm as hbm
from sarfe.hbm.time_integration import integrate_time

_spec = importlib.util.spec_from_file_location(
    "hbm_vs_time_models", ROOT / "tests" / "hbm" / "test_hbm_vs_time.py")
models = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(models)

TARGETS = (1e-2, 1e-3)
HBM_GRID = [(H, N) for H in (1, 2, 3, 4, 5, 7, 10, 15, 20) for N in (64, 128, 256, 512, 1024)
            if N >= 4 * H + 1]
TI_STEPS = (32, 64, 128, 256, 512, 1024)


def error(U, reference):
    a, b = U[1] - 1j * U[2], reference[1] - 1j * reference[2]
    return float(np.abs(a - b).max() / np.abs(b).max())


def best_time(run, repeats=3):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def study(name):
    build = models.MODELS[name]
    model, contacts, F, omega = build(30)
    start = hbm.solve_frequency(model, contacts, F, omega, 30, 2048)
    reference = integrate_time(model, contacts, F, omega, 30, steps_per_period=2048,
                               richardson=True, initial=start, steady_tolerance=1e-9)
    U_ref = reference.displacement_harmonics
    rows = {"model": name, "reference_periods": reference.periods, "hbm": [], "time": []}

    for H, N in HBM_GRID:          # accuracy scan (one run each), timing only for the chosen ones
        model, contacts, F, omega = build(H)
        s = hbm.solve_frequency(model, contacts, F, omega, H, N)
        rows["hbm"].append({"harmonics": H, "samples": N, "converged": bool(s.converged),
                            "error": error(s.displacement, U_ref) if s.converged else None})
    for richardson in (False, True):
        for steps in TI_STEPS:
            model, contacts, F, omega = build(1)
            r = integrate_time(model, contacts, F, omega, 1, steps_per_period=steps,
                               richardson=richardson, steady_tolerance=1e-6)
            rows["time"].append({"steps_per_period": steps, "richardson": richardson,
                                 "steady": r.steady, "periods": r.periods,
                                 "error": error(r.displacement_harmonics, U_ref[:3])})

    rows["targets"] = []
    for target in TARGETS:
        entry = {"target": target}
        ok = [row for row in rows["hbm"] if row["converged"] and row["error"] <= target]
        if ok:
            timed = []
            for row in ok[:6]:     # grid is ordered by cost (H, then N): time the first few
                model, contacts, F, omega = build(row["harmonics"])
                seconds, s = best_time(lambda: hbm.solve_frequency(
                    model, contacts, F, omega, row["harmonics"], row["samples"]))
                timed.append((seconds, row))
            seconds, row = min(timed, key=lambda item: item[0])
            entry["hbm"] = {**row, "seconds": seconds}
        for richardson in (False, True):
            key = "time_richardson" if richardson else "time"
            ok = [row for row in rows["time"] if row["richardson"] == richardson
                  and row["steady"] and row["error"] <= target]
            if not ok:
                continue
            timed = []
            model, contacts, F, omega = build(1)
            for row in ok[:3]:     # ordered by step count: time the first few, keep the fastest
                seconds, r = best_time(lambda: integrate_time(
                    model, contacts, F, omega, 1, steps_per_period=row["steps_per_period"],
                    richardson=richardson, steady_tolerance=target / 100), repeats=2)
                timed.append({**row, "seconds": seconds, "periods": r.periods,
                              "error": error(r.displacement_harmonics, U_ref[:3])})
            entry[key] = min(timed, key=lambda item: item["seconds"])
        rows["targets"].append(entry)
    return rows


def markdown(results, meta):
    lines = ["# HBM vs time integration: wall time at equal first-harmonic accuracy", "",
             "Lumped stand-ins (`tests/hbm/test_hbm_vs_time.py`: 2-DOF rattle chain at 10 Hz, "
             "3-DOF squeak model at 12 Hz), not the case-file rigs. Error = max |û₁ − û₁,ref| / "
             "max |û₁,ref|; reference = time integration 2048 steps/period + Richardson (4096).",
             "HBM: `solve_frequency` from its linear guess, cheapest (H, N) reaching the target, "
             "best of 3 (fastest of the first 6 qualifying settings). Time integration: cold start "
             "from the linear periodic solution, steady_tolerance = target/100, best of 2 (fastest "
             "of the first 3 qualifying step counts). Error of the timed run in brackets.", "",
             f"Machine: {meta['machine']}; load average at start {meta['load']}; "
             "2 cores shared with other jobs, so absolute times are noisy — the ratio is measured "
             "back to back in one process.", "",
             "| model | target | HBM (H, N) | HBM [s] | time int. steps/period (periods) | time int. [s] "
             "| ratio time/HBM | + Richardson steps (periods) | [s] | ratio |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for rows in results:
        for entry in rows["targets"]:
            h = entry.get("hbm")
            t = entry.get("time")
            tr = entry.get("time_richardson")
            cell_h = f"H={h['harmonics']}, N={h['samples']} (err {h['error']:.1e})" if h else "—"
            sec_h = f"{h['seconds']:.3f}" if h else "—"

            def cells(x):
                if not x:
                    return "—", "—", "—"
                ratio = f"{x['seconds'] / h['seconds']:.0f}×" if h else "—"
                return (f"{x['steps_per_period']} ({x['periods']}; err {x['error']:.1e})",
                        f"{x['seconds']:.2f}", ratio)

            lines.append(f"| {rows['model']} | {entry['target']:.1%} | {cell_h} | {sec_h} | "
                         + " | ".join(cells(t)) + " | " + " | ".join(cells(tr)) + " |")
    lines += ["", "## Accuracy scans", ""]
    for rows in results:
        lines.append(f"### {rows['model']}")
        lines.append("")
        lines.append("HBM first-harmonic error (rows H, columns N; `x` = not converged):")
        lines.append("")
        Ns = sorted({r["samples"] for r in rows["hbm"]})
        lines.append("| H | " + " | ".join(str(n) for n in Ns) + " |")
        lines.append("|---|" + "---|" * len(Ns))
        for H in sorted({r["harmonics"] for r in rows["hbm"]}):
            cells = []
            for n in Ns:
                match = [r for r in rows["hbm"] if r["harmonics"] == H and r["samples"] == n]
                if not match:
                    cells.append("")
                else:
                    e = match[0]["error"]
                    cells.append("x" if e is None else f"{e:.1e}")
            lines.append(f"| {H} | " + " | ".join(cells) + " |")
        lines.append("")
        lines.append("Time integration error vs steps per period (cold start, tolerance 1e-6):")
        lines.append("")
        lines.append("| steps/period | error | periods | + Richardson error | periods |")
        lines.append("|---|---|---|---|---|")
        for steps in TI_STEPS:
            a = [r for r in rows["time"] if r["steps_per_period"] == steps and not r["richardson"]][0]
            b = [r for r in rows["time"] if r["steps_per_period"] == steps and r["richardson"]][0]
            lines.append(f"| {steps} | {a['error']:.1e} | {a['periods']} | {b['error']:.1e} | "
                         f"{b['periods']} |")
        lines.append("")
    return "\n".join(lines) + "\n"


def main():
    meta = {"machine": f"{platform.machine()} {os.cpu_count()} cores, Python {platform.python_version()}",
            "load": " ".join(f"{x:.1f}" for x in os.getloadavg())}
    results = []
    for name in ("rattle", "squeak"):
        start = time.perf_counter()
        results.append(study(name))
        print(f"{name}: {time.perf_counter() - start:.0f} s", flush=True)
    write_results("hbm_vs_time_lumped", {"meta": meta, "results": results})
    print(write_results("hbm_vs_time_lumped", markdown=markdown(results, meta)).read_text())


if __name__ == "__main__":
    main()
