"""Accuracy benchmark → benchmarks/results/accuracy.md (+ .json).

1. HBM vs the built-in time integrator at equal accuracy (1 % and 0.1 % first-harmonic amplitude at
   the contacts, against a fine HBM reference checked by time integration): wall-time ratio.
   HBM: :func:`sarfe.study.accuracy.choose_resolution` from H = 2, N = 32 (cold, the cost of the
   whole adaptive loop, estimates included). Time integration: steps per period doubled from 128
   until the error is below the target (cost of the successful run only, started from the linear
   periodic solution as ``integrate_time`` does by default).
2. Cost vs H and vs the number of contacts (lumped chains) with fitted exponents t ∝ H^p, t ∝ n_c^q.
3. A-posteriori estimate vs true error (fine reference) on the shipped cases.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_accuracy.py [--quick]``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results"
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
    from sarfe.study.accuracy import resize_harmonics

    if name.startswith("lumped_chain"):
        from sarfe.study.lumped import lumped_problem

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
    from sarfe.study.accuracy import resize_harmonics

    return solve_frequency(prob["model"], prob["contacts"], resize_harmonics(prob["excitation"], H),
                           omega, H, N, initial=None if initial is None else
                           resize_harmonics(initial, H), options=SolverOptions(stability=False))


def nonlinear_points(prob, count=2):
    """Frequencies where a stepped HBM sweep (H = 5, N = 128, warm starts) converges with an active
    contact (force > 0), each with its H = 40, N = 4096 reference (started from it)."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.study.accuracy import resize_harmonics

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
    from sarfe.hbm import SolverOptions
    from sarfe.hbm.time_integration import integrate_time
    from sarfe.study.accuracy import choose_resolution, resize_harmonics

    omega = 2 * np.pi * f
    rows = []
    for target in targets:
        clock = time.perf_counter()
        res = choose_resolution({"amplitude_rel": target}, prob["model"], prob["contacts"],
                                prob["excitation"], omega, harmonics=2, samples_per_period=32,
                                erp_map=prob["erp_map"], erp_areas=prob["erp_areas"],
                                modal_dofs=None, options=SolverOptions(stability=False))
        t_hbm = time.perf_counter() - clock
        e_hbm = amplitude_error(prob["contacts"], resize_harmonics(res.solution.displacement, 40),
                                ref.displacement)
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
                     "hbm_H": res.harmonics, "hbm_N": res.samples_per_period, "hbm_met": res.met,
                     "hbm_s": t_hbm, "hbm_error": e_hbm, "ti_steps": steps if ok else None,
                     "ti_s": t_ti, "ti_error": e_ti, "ti_met": ok,
                     "ratio_ti_over_hbm": t_ti / t_hbm if ok else None})
        print(f"  {prob['label']} {f:.1f} Hz target {target:g}: HBM H={res.harmonics} "
              f"N={res.samples_per_period} {t_hbm:.2f}s err {e_hbm:.1e} | TI {steps} steps "
              f"{t_ti:.2f}s err {e_ti:.1e}", flush=True)
    return rows


# ------------------------------------------------------------------------------------ part 2
def _fit(x, y):
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    return float(np.polyfit(x, y, 1)[0])


def cost_scaling(quick=False):
    """Seconds per Newton iteration (warm solve from 0.8 × the converged solution, best of 2) of
    chains with a rattle contact on every mass: vs H (8 contacts) and vs n_c (H = 5, N = 128)."""
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.study.accuracy import resize_harmonics
    from sarfe.study.lumped import lumped_problem

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
def estimate_table(prob, points, levels=((2, 32), (3, 64), (5, 128), (9, 256), (15, 512))):
    from sarfe.hbm import SolverOptions, solve_frequency
    from sarfe.study.accuracy import estimate_errors, resize_harmonics
    from sarfe.study.accuracy import _change

    rows = []
    for f, ref in points:
        omega = 2 * np.pi * f
        for H, N in levels:
            F = resize_harmonics(prob["excitation"], H)
            s = solve_frequency(prob["model"], prob["contacts"], F, omega, H, N,
                                initial=resize_harmonics(ref.displacement, H),
                                options=SolverOptions(stability=False))
            if not s.converged:
                continue
            e = estimate_errors(s, prob["model"], prob["contacts"], F, erp_map=prob["erp_map"],
                                erp_areas=prob["erp_areas"], modal_dofs=None)
            true_rel, true_db = _change(prob["contacts"], resize_harmonics(s.displacement, 40),
                                        ref.displacement, omega, prob["erp_map"], prob["erp_areas"])
            brackets = bool(true_rel <= e.amplitude_rel and
                            (true_rel >= e.amplitude_rel / 30 or e.amplitude_rel < 1e-6))
            rows.append({"case": prob["label"], "frequency_hz": f, "H": H, "N": N,
                         "estimate_rel": e.amplitude_rel, "true_rel": true_rel,
                         "estimate_db": e.erp_db, "true_db": abs(true_db),
                         "harmonics_rel": e.harmonics_rel, "aliasing_rel": e.aliasing_rel,
                         "tail": e.displacement_tail, "brackets": brackets,
                         "estimate_s": e.seconds})
    return rows


def markdown(data):
    lines = ["# Accuracy: HBM vs time integration, cost scaling, error estimates", "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, load average "
             f"{data['load_average']} at the start (shared: timings are noisy; ratios matter). "
             f"{data['created']}", ""]
    lines += ["## 1. HBM vs time integration at equal accuracy", "",
              "Error = max over contact rows of |Δa₁| / max a₁ (first-harmonic amplitude) against an "
              "H = 40, N = 4096 HBM reference. HBM time = the whole adaptive loop "
              "(`choose_resolution` from H = 2, N = 32, estimates included); time integration = "
              "the first run (128, 256, … steps per period) whose error meets the target.", "",
              "| case | f [Hz] | target | HBM H, N | HBM s | HBM error | TI steps | TI s | TI error "
              "| TI / HBM |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["hbm_vs_time"]:
        ratio = f"{r['ratio_ti_over_hbm']:.1f}" if r["ratio_ti_over_hbm"] else "TI missed"
        lines.append(f"| {r['case']} | {r['frequency_hz']:.1f} | {r['target']:g} | "
                     f"{r['hbm_H']}, {r['hbm_N']}{'' if r['hbm_met'] else ' (not met)'} | "
                     f"{r['hbm_s']:.2f} | {r['hbm_error']:.1e} | {r['ti_steps'] or '-'} | "
                     f"{r['ti_s']:.2f} | {r['ti_error']:.1e} | {ratio} |")
    lines += ["", "## 2. Cost vs H and vs number of contacts", ""]
    sc = data["scaling"]
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
    lines += ["## 3. Estimate vs true error", "",
              "estimate = `estimate_errors(...).amplitude_rel` (SAFETY = 2 included); true = against "
              "H = 40, N = 4096. 'brackets' = true ≤ estimate ≤ 30 × true (or both < 1e-6).", "",
              "| case | f [Hz] | H | N | estimate | true | est. dB | true dB | H part | N part | "
              "brackets |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["estimates"]:
        lines.append(f"| {r['case']} | {r['frequency_hz']:.1f} | {r['H']} | {r['N']} | "
                     f"{r['estimate_rel']:.1e} | {r['true_rel']:.1e} | {r['estimate_db']:.2e} | "
                     f"{r['true_db']:.2e} | {r['harmonics_rel']:.1e} | {r['aliasing_rel']:.1e} | "
                     f"{'yes' if r['brackets'] else 'NO'} |")
    n_ok = sum(r["brackets"] for r in data["estimates"])
    lines += ["", f"Bracketed: {n_ok} of {len(data['estimates'])} rows.", ""]
    if data.get("notes"):
        lines += ["## Notes", ""] + [f"- {n}" for n in data["notes"]] + [""]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer points")
    parser.add_argument("--cases", default="lumped_chain,lumped_rattle,rattle_rig,squeak_rig")
    parser.add_argument("--no-scaling", action="store_true")
    parser.add_argument("--no-time", action="store_true", help="skip HBM vs time integration")
    parser.add_argument("--json-out", default=None, help="write this part's JSON only")
    parser.add_argument("--merge", nargs="*", default=None, help="merge part JSONs → accuracy.md")
    args = parser.parse_args(argv)
    if args.merge is not None:
        parts = [json.loads(Path(p).read_text()) for p in args.merge]
        data = dict(parts[0])
        for key in ("hbm_vs_time", "estimates", "notes"):
            data[key] = [x for part in parts for x in part.get(key, [])]
        data["scaling"] = next(p["scaling"] for p in parts if p.get("scaling"))
        data["load_average"] = [p["load_average"] for p in parts]
        (RESULTS / "accuracy.json").write_text(json.dumps(data, indent=1, default=float))
        (RESULTS / "accuracy.md").write_text(markdown(data))
        print(f"wrote {RESULTS / 'accuracy.md'}")
        return
    data = {"created": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "load_average": [round(x, 1) for x in os.getloadavg()],
            "hbm_vs_time": [], "estimates": [], "notes": []}
    for name in args.cases.split(","):
        print(f"{name}:", flush=True)
        try:
            prob = load_problem(name)
        except Exception as exc:  # a case that does not build is reported, not fatal
            data["notes"].append(f"{name}: not run ({type(exc).__name__}: {exc})")
            continue
        points = nonlinear_points(prob, count=1 if args.quick else 2)
        if not points:
            data["notes"].append(f"{name}: no frequency with a converged cold solve and an "
                                 "active contact among " + ", ".join(f"{f:.1f}" for f in
                                                                    prob["frequencies_hz"]) + " Hz")
            continue
        print(f"  points: {[round(f, 2) for f, _ in points]}", flush=True)
        data["estimates"] += estimate_table(prob, points)
        print(f"  estimates: {len(data['estimates'])} rows", flush=True)
        if name in ("lumped_chain", "rattle_rig", "squeak_rig") and not args.no_time:
            data["hbm_vs_time"] += hbm_vs_time(prob, *points[0])
    if not args.no_scaling:
        print("scaling:", flush=True)
        data["scaling"] = cost_scaling(args.quick)
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(data, indent=1, default=float))
        return
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "accuracy.json").write_text(json.dumps(data, indent=1, default=float))
    (RESULTS / "accuracy.md").write_text(markdown(data))
    print(f"wrote {RESULTS / 'accuracy.md'}")


if __name__ == "__main__":
    main()
