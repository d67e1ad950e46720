"""Harmonic-balance engine benchmark → benchmarks/results/hbm.md and hbm.json.

1. NLvib example 03 full sweep (H = 21, N = 1024, Ω 0.5 → 0.8): wall time, points, peak, with and
   without Hill stability of every point.
2. Time per Newton iteration (one residual + analytic Jacobian + linear solve) on a lumped chain
   with 1, 10, 50, 200 rattle pairs (H = 10, N = 256), and with 10 pairs vs H = 5, 15, 40
   (N = 8H rounded up to a power of two, ≥ 128); squeak (1-D Jenkins) pairs for comparison.

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/engine/bench_hbm.py
"""
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import machine, write_results  # noqa: E402

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402

from sarfe.hbm import (ContinuationOptions, SolverOptions, continuation,  # noqa: E402
                       make_contact_set, make_linear_model)
from sarfe.hbm.newton import solve_linear  # noqa: E402
from sarfe.hbm.solve import (condensed_size, linearized_guess, make_evaluator,  # noqa: E402
                             make_problem, wants_condensation)


def example03():
    K = np.array([[1.0, -1.0], [-1.0, 2.0]])
    model = make_linear_model(np.eye(2), 0.03 * K, K)
    contacts = make_contact_set(sp.csr_matrix([[1.0, 0.0]]), ["rattle"], [0], [[-1, -1]], 1.0, 100.0)
    F = np.zeros((43, 2))
    F[1, 1] = 0.1
    return model, contacts, F


def sweep03(stability):
    model, contacts, F = example03()
    options = ContinuationOptions(solver=SolverOptions(stability=stability))
    start = time.perf_counter()
    sols = continuation(model, contacts, F, 0.5, 0.8, 21, 1024, options=options)
    elapsed = time.perf_counter() - start
    amplitude = np.array([s.amplitude(1) for s in sols])
    peak = int(amplitude.argmax())
    return {"stability": stability, "seconds": elapsed, "points": len(sols),
            "newton_iterations": int(sum(s.iterations for s in sols)),
            "all_converged": all(s.converged for s in sols),
            "peak_amplitude": float(amplitude[peak]), "peak_omega": float(sols[peak].omega),
            "unstable_points": int(sum(s.stable is False for s in sols))}


def chain_problem(pairs, harmonics, kind="rattle"):
    """Chain of n = 2·pairs + 2 unit masses/springs (damping 2 % of K), a contact between the masses
    of each pair (gap 0.01 m, k_n = 50 N/m), force 0.5 N at the middle mass."""
    n = 2 * pairs + 2
    K = sp.diags([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)], [0, 1, -1], format="csr")
    model = make_linear_model(sp.identity(n, format="csr"), 0.02 * K, K)
    a = 2 * np.arange(pairs) + 1
    rows = np.arange(pairs)
    if kind == "rattle":
        G = sp.csr_matrix((np.r_[np.ones(pairs), -np.ones(pairs)], (np.r_[rows, rows], np.r_[a, a + 1])),
                          shape=(pairs, n))
        contacts = make_contact_set(G, ["rattle"] * pairs, rows, -np.ones((pairs, 2)), 0.01, 50.0)
    else:   # squeak: normal row (a, a+1) and a tangent row on the same pair (1-D model)
        G = sp.vstack([
            sp.csr_matrix((np.r_[np.ones(pairs), -np.ones(pairs)], (np.r_[rows, rows], np.r_[a, a + 1])),
                          shape=(pairs, n)),
            sp.csr_matrix((np.ones(pairs), (rows, a)), shape=(pairs, n))]).tocsr()
        tangent = np.column_stack([rows + pairs, -np.ones(pairs, int)])
        contacts = make_contact_set(G, ["squeak"] * pairs, rows, tangent, -0.01, 50.0, 20.0, 0.3, 0.0)
    N = max(128, 1 << int(np.ceil(np.log2(8 * harmonics))))
    F = np.zeros((2 * harmonics + 1, n))
    F[1, n // 2] = 0.5
    return model, contacts, F, N


def newton_iteration_time(pairs, harmonics, kind="rattle", repeat=3):
    model, contacts, F, N = chain_problem(pairs, harmonics, kind)
    options = SolverOptions()
    problem = make_problem(model, contacts, F, harmonics, N, options)
    condensed = wants_condensation(problem, options)
    evaluate, to_x, _ = make_evaluator(problem, condensed)
    omega = 0.9
    x = to_x(linearized_guess(problem, omega))
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        ev = evaluate(x, omega, True, None)
        solve_linear(ev.jacobian, -ev.residual)
        times.append(time.perf_counter() - start)
    return {"kind": kind, "pairs": pairs, "harmonics": harmonics, "samples": N,
            "dofs": model.dof_count, "condensed": condensed,
            "unknowns": condensed_size(problem) if condensed else (2 * harmonics + 1) * model.dof_count,
            "full_unknowns": (2 * harmonics + 1) * model.dof_count,
            "seconds_per_iteration": float(min(times))}


def main():
    results = machine()
    results["example03"] = [sweep03(False), sweep03(True)]
    results["vs_contacts"] = [newton_iteration_time(p, 10) for p in (1, 10, 50, 200)]
    results["vs_contacts_squeak"] = [newton_iteration_time(p, 10, "squeak") for p in (1, 10, 50, 200)]
    results["vs_harmonics"] = [newton_iteration_time(10, h) for h in (5, 15, 40)]
    write_results("hbm", results, indent=2)
    lines = ["# HBM engine benchmark", "",
             f"Machine: {results['machine']}, {results['cpu_count']} cores, load average at start "
             f"{results['load_average'][0]:.1f} (shared machine: timings are upper bounds). One BLAS thread.",
             "", "## NLvib example 03 sweep (H = 21, N = 1024, Ω 0.5 → 0.8, default ContinuationOptions)", "",
             "| Hill stability | wall time [s] | points | Newton iterations | peak |a₂| | at Ω | unstable points |",
             "|---|---|---|---|---|---|---|"]
    for r in results["example03"]:
        lines.append(f"| {r['stability']} | {r['seconds']:.2f} | {r['points']} | {r['newton_iterations']} | "
                     f"{r['peak_amplitude']:.5f} | {r['peak_omega']:.5f} | {r['unstable_points']} |")
    lines += ["", "Reference (NLvib): peak ≈ 0.9374 at Ω ≈ 0.7512.", "",
              "## Time per Newton iteration (residual + analytic Jacobian + linear solve)", "",
              "| law | pairs | H | N | DOFs | condensed | unknowns (full) | ms / iteration |",
              "|---|---|---|---|---|---|---|---|"]
    for r in results["vs_contacts"] + results["vs_contacts_squeak"] + results["vs_harmonics"]:
        lines.append(f"| {r['kind']} | {r['pairs']} | {r['harmonics']} | {r['samples']} | {r['dofs']} | "
                     f"{r['condensed']} | {r['unknowns']} ({r['full_unknowns']}) | "
                     f"{1e3 * r['seconds_per_iteration']:.1f} |")
    write_results("hbm", markdown=lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
