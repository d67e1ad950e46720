"""sarfe side by side with the peer HBM code pyHarm (pyharm-os 1.2.2) → results/peer.md and peer.json.

Problems (whole processes, OPENBLAS_NUM_THREADS=1, runs alternated A B A B):
1. NLvib example 03 (2-DOF, unilateral spring k = 100, gap 1; H = 21, N = 1024; Ω 0.8 → 0.5);
2. the 1-DOF Jenkins oscillator (m = k = k_t = μ = N0 = 1, c = 0.02, F = 0.5; Ω 0.5 → 2.0; H = 7,
   N = 256).
sarfe runs `sarfe solve` on benchmarks/peer/{nlvib03,jenkins}.yaml with its defaults (per-point
error estimate and Hill stability on) and with both off; the peer runs
benchmarks/peer/pyharm_problems.py in its own venv (arc-length steps ds = 0.04 for example 03 —
187 points, as in FACTS.md — and 0.025 for Jenkins, ≈ 250 points). Reported: wall and CPU
seconds (median), the ratios sarfe/peer against the issue-13 targets (≤ 0.3× with defaults, ≤ 0.1×
without; Jenkins ≤ 0.3×), and the peak (amplitude of the first harmonic of the forced DOF, and Ω)
of each curve plus the largest difference of the curves on their common single-valued range.
Then the breakdown of one more run of each sarfe variant: CPU seconds per stage
(benchmarks/peer/stage_breakdown.py), and the import floors: an interpreter that imports numpy +
scipy.sparse/linalg (what any sarfe run needs) and the peer's ``import pyHarm``.

The peer venv: $SARFE_PEER_VENV, else benchmarks/.peer-venv (created on first use:
`python3 -m venv` + `pip install pyharm-os==1.2.2`; git-ignored). Its first run compiles numba
kernels into a cache (~40 s): each problem is run once untimed first.

Run: python benchmarks/peer/bench_peer.py [--repeats 3]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import BENCHMARKS, ENV, ROOT, machine, run_timed, write_results  # noqa: E402

import numpy as np

PEER = BENCHMARKS / "peer"
PEER_VERSION = "pyharm-os==1.2.2"
STAGE_ROWS = ("start", "imports", "sweep (continuation, all points)", "  of which Hill stability",
              "error estimates", "point records (ERP, baseline, contributions)",
              "figures (incl. matplotlib import)", "report.html", "response.h5 (incl. h5py import)",
              "summary.json", "solve_case (all stages)", "process total")
TARGETS = {"nlvib03": {"defaults": 0.3, "bare": 0.1}, "jenkins": {"defaults": 0.3, "bare": 0.3}}
PEER_NAMES = {"nlvib03": "example03", "jenkins": "jenkins"}
PEER_STEPS = {"nlvib03": 0.04, "jenkins": 0.025}


def peer_python() -> pathlib.Path:
    venv = pathlib.Path(os.environ.get("SARFE_PEER_VENV", BENCHMARKS / ".peer-venv"))
    python = venv / "bin" / "python"
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", PEER_VERSION], check=True)
    return python


def peer_command(python, problem):
    return [str(python), str(PEER / "pyharm_problems.py"), PEER_NAMES[problem],
            "--step", str(PEER_STEPS[problem])]


def sarfe_case(problem, variant, directory):
    """The case file of a variant ('defaults' | 'bare' = no error estimate, no stability)."""
    source = PEER / f"{problem}.yaml"
    if variant == "defaults":
        return source
    text = source.read_text()
    text = text.replace("solver:\n", "solver:\n  error_estimate: false\n  stability: false\n", 1)
    path = pathlib.Path(directory) / f"{problem}_{variant}.yaml"
    path.write_text(text)
    return path


def sarfe_curve(output):
    import h5py
    with h5py.File(pathlib.Path(output) / "response.h5") as f:
        u = f["excitation/displacement_m"][:, :, 0]
        omega = f["omega_rad_s"][:]
        stable = f["status/stable"][:]
    return omega, np.hypot(u[:, 1], u[:, 2]), stable


def curve_difference(omega_sarfe, amp_sarfe, omega_peer, amp_peer):
    """Largest |a_sarfe − a_peer| / max a_peer at sarfe's points, the peer's (denser) curve
    interpolated linearly; None when either curve folds (Ω not monotone)."""
    def monotone(omega):
        step = np.sign(np.diff(omega))
        return np.all(step == step[0]) if step.size else True
    if not (monotone(omega_sarfe) and monotone(omega_peer)):
        return None
    order = np.argsort(omega_peer)
    op, ap = omega_peer[order], amp_peer[order]
    inside = (omega_sarfe >= op[0]) & (omega_sarfe <= op[-1])
    return float(np.abs(np.interp(omega_sarfe[inside], op, ap) - amp_sarfe[inside]).max()
                 / amp_peer.max())


def stage_breakdown(case, output):
    """{stage: CPU s} of one more whole ``sarfe solve`` (benchmarks/peer/stage_breakdown.py)."""
    done = subprocess.run([sys.executable, str(PEER / "stage_breakdown.py"), str(case), "-o",
                           str(output)], env=ENV, cwd=ROOT, capture_output=True, text=True)
    if done.returncode not in (0, 3):
        return {"error": done.stderr[-500:]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def import_floor(python, code, directory, runs=3):
    """Median CPU s of an interpreter that runs ``code`` (imports only) in ``directory`` (pyHarm
    writes a log folder where it is imported)."""
    return statistics.median(run_timed([str(python), "-c", code], cwd=directory)[1]
                             for _ in range(runs))


def run_problem(problem, python, repeats, directory):
    cases = {v: sarfe_case(problem, v, directory) for v in ("defaults", "bare")}
    run_timed(peer_command(python, problem), cwd=directory)    # warm-up: numba compiles its cache
    times = {"peer": [], "defaults": [], "bare": []}
    peer_out = None
    for _ in range(repeats):                               # A B A B ...
        wall, cpu, out = run_timed(peer_command(python, problem), cwd=directory)   # its logs there
        times["peer"].append((wall, cpu))
        peer_out = json.loads(out.strip().splitlines()[-1])
        for variant, case in cases.items():
            output = pathlib.Path(directory) / f"{problem}_{variant}_out"
            wall, cpu, _ = run_timed([sys.executable, "-m", "sarfe.cli", "solve", str(case),
                                  "-o", str(output), "--quiet"], cwd=ROOT)
            times[variant].append((wall, cpu))
    omega, amplitude, stable = sarfe_curve(pathlib.Path(directory) / f"{problem}_defaults_out")
    peak = int(amplitude.argmax())
    peer_omega, peer_amp = np.array(peer_out["omega"]), np.array(peer_out["amplitude"])
    row = {"problem": problem, "repeats": repeats,
           "peer": {"points": peer_out["points"], "peak_amplitude": peer_out["peak_amplitude"],
                    "peak_omega": peer_out["peak_omega"]},
           "sarfe": {"points": int(omega.size), "peak_amplitude": float(amplitude[peak]),
                     "peak_omega": float(omega[peak]),
                     "unstable_points": int(np.sum(stable == 0))},
           "curve_difference": curve_difference(omega, amplitude, peer_omega, peer_amp)}
    row["breakdown"] = {variant: stage_breakdown(case, pathlib.Path(directory) / f"{problem}_{variant}_b")
                        for variant, case in cases.items()}
    for key, values in times.items():
        row[f"{key}_wall_s"] = statistics.median(v[0] for v in values)
        row[f"{key}_cpu_s"] = statistics.median(v[1] for v in values)
        row[f"{key}_wall_all_s"] = [round(v[0], 3) for v in values]
    for variant in ("defaults", "bare"):
        row[f"ratio_{variant}_wall"] = row[f"{variant}_wall_s"] / row["peer_wall_s"]
        row[f"ratio_{variant}_cpu"] = row[f"{variant}_cpu_s"] / row["peer_cpu_s"]
        row[f"target_{variant}"] = TARGETS[problem][variant]
    return row


def write(results):
    write_results("peer", results, indent=2)
    lines = ["# sarfe vs the peer HBM code pyHarm (pyharm-os 1.2.2)", "",
             f"Machine: {results['machine']}, {results['cpu_count']} cores, load average at start "
             f"{results['load_average'][0]:.2f}; OPENBLAS_NUM_THREADS=1; whole processes, median of "
             f"{results['repeats']} alternated runs after one untimed peer warm-up (numba cache).",
             "'defaults' = sarfe with its per-point error estimate and Hill stability; 'bare' = "
             "both off.", "",
             "| problem | peer s (CPU) | sarfe defaults s (CPU) | ratio | target | sarfe bare s (CPU) "
             "| ratio | target |", "|---|---|---|---|---|---|---|---|"]
    for r in results["problems"]:
        lines.append(
            f"| {r['problem']} | {r['peer_wall_s']:.2f} ({r['peer_cpu_s']:.2f}) | "
            f"{r['defaults_wall_s']:.2f} ({r['defaults_cpu_s']:.2f}) | "
            f"{r['ratio_defaults_wall']:.2f}× ({r['ratio_defaults_cpu']:.2f}×) | ≤ {r['target_defaults']}× | "
            f"{r['bare_wall_s']:.2f} ({r['bare_cpu_s']:.2f}) | "
            f"{r['ratio_bare_wall']:.2f}× ({r['ratio_bare_cpu']:.2f}×) | ≤ {r['target_bare']}× |")
    lines += ["", "| problem | peer points | peer peak (Ω) | sarfe points | sarfe peak (Ω) | "
              "curve difference |", "|---|---|---|---|---|---|"]
    for r in results["problems"]:
        p, s = r["peer"], r["sarfe"]
        diff = "folds: peaks only" if r["curve_difference"] is None else f"{r['curve_difference']:.2%}"
        lines.append(f"| {r['problem']} | {p['points']} | {p['peak_amplitude']:.5f} "
                     f"({p['peak_omega']:.5f}) | {s['points']} | {s['peak_amplitude']:.5f} "
                     f"({s['peak_omega']:.5f}) | {diff} |")
    floors = results.get("import_floor_cpu_s", {})
    lines += ["", "## Where a sarfe run's time goes (CPU s of one run, stages inclusive)", "",
              "| stage | " + " | ".join(f"{r['problem']} {v}" for r in results["problems"]
                                        for v in ("defaults", "bare")) + " |",
              "|---|" + "---|" * (2 * len(results["problems"]))]
    for stage in STAGE_ROWS:
        cells = []
        for r in results["problems"]:
            for variant in ("defaults", "bare"):
                value = r["breakdown"][variant].get(stage.strip())
                cells.append("-" if value is None else f"{value:.2f}")
        lines.append(f"| {stage.replace('  ', '&nbsp;&nbsp;')} | " + " | ".join(cells) + " |")
    lines += ["", f"Import floors (CPU s, median of 3): python + numpy + scipy.sparse/linalg "
              f"{floors.get('numpy_scipy', float('nan')):.2f}; the peer's `import pyHarm` "
              f"{floors.get('peer', float('nan')):.2f}."]
    lines += ["", "Peak = largest first-harmonic amplitude among the computed points (a coarse "
              "sweep samples the peak below its true value). Curve difference = max |a_sarfe − "
              "a_peer| / max a_peer at sarfe's points, the peer's denser curve interpolated "
              "(single-valued curves only)."]
    write_results("peer", markdown=lines)
    print("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args, _ = parser.parse_known_args()   # run_all.py passes its own arguments
    results = {**machine(), "repeats": args.repeats, "peer_version": PEER_VERSION}
    try:
        python = peer_python()
    except (subprocess.CalledProcessError, OSError) as error:
        results["error"] = f"pyharm-os could not be installed: {error}"
        write_results("peer", results, indent=2)
        print(results["error"])
        return
    with tempfile.TemporaryDirectory() as directory:
        results["problems"] = [run_problem(p, python, args.repeats, directory)
                               for p in ("nlvib03", "jenkins")]
        results["import_floor_cpu_s"] = {
            "numpy_scipy": import_floor(sys.executable, "import numpy, scipy.sparse, scipy.linalg",
                                        directory),
            "peer": import_floor(python, "import numpy; from pyHarm.Maestro import Maestro",
                                 directory)}
    write(results)


if __name__ == "__main__":
    main()
