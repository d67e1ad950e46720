"""``solver.workers`` 1 vs 2 on one case: wall, CPU (solving process and its workers), peak memory.

    python benchmarks/pipeline/bench_workers.py [CASE.yaml] [--runs 2] [--band START END]

Runs ``solve_case`` of the case (written results included) in a fresh process per run, in the
order 1 2 1 2 … (other jobs share the machine: alternating spreads their load over both), every
process with OPENBLAS/OMP/MKL_NUM_THREADS=1. Per run: wall time; CPU seconds of the solving
process (RUSAGE_SELF) and of its workers (RUSAGE_CHILDREN); peak RSS of each (ru_maxrss: a
worker's RSS counts the pages it shares with the parent); the peak of the summed proportional set
size (PSS, /proc/<pid>/smaps_rollup of the process and its live workers, sampled every 0.2 s: the
memory the run really holds, shared pages counted once); the stage timings of summary.json; the
load average around the run. The per-point fields of summary.json are compared between the runs
(relative 1e-12; timing fields excluded). Writes benchmarks/results/workers.json and the section
"Two processes" at the end of benchmarks/results/point_cost.md (replaced when present).
Default case: /work/notes/p1_15mm.yaml if present, else cases/door_trim.yaml.
"""
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ENV, RESULTS, ROOT, write_results  # noqa: E402

SECTION = "## Two processes: `solver.workers` 1 vs 2"


def one_run(case_path, workers, band, out):
    """In a fresh process: solve the case with ``workers`` and print the measurements as JSON."""
    import resource
    import threading

    from sarfe.case.read import load_case, read_yaml
    from sarfe.pipeline import solve_case

    data = read_yaml(case_path)[0]
    data.setdefault("solver", {})["workers"] = int(workers)
    if band:
        data["excitation"]["sweep"] = {"start_hz": band[0], "end_hz": band[1]}
    case = load_case(data, base_dir=pathlib.Path(case_path).resolve().parent)
    peak = {"pss_kb": 0}
    stop = threading.Event()

    def pss_kb(pid):
        try:
            with open(f"/proc/{pid}/smaps_rollup") as stream:
                return next(int(line.split()[1]) for line in stream if line.startswith("Pss:"))
        except (OSError, StopIteration):
            return 0

    def children():
        pids = []
        for task in pathlib.Path("/proc/self/task").iterdir():
            try:
                pids += (task / "children").read_text().split()
            except OSError:
                pass
        return pids

    def sample():
        while not stop.wait(0.2):
            total = pss_kb("self") + sum(pss_kb(pid) for pid in children())
            peak["pss_kb"] = max(peak["pss_kb"], total)

    thread = threading.Thread(target=sample, daemon=True)
    thread.start()
    load_before = os.getloadavg()[0]
    start = time.perf_counter()
    result = solve_case(case, output_dir=pathlib.Path(out) / "result", force=True)
    wall = time.perf_counter() - start
    stop.set()
    thread.join()
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = json.loads((pathlib.Path(out) / "result" / "summary.json").read_text())
    print(json.dumps({
        "workers": int(workers), "wall_s": wall,
        "cpu_parent_s": own.ru_utime + own.ru_stime, "cpu_workers_s": kids.ru_utime + kids.ru_stime,
        "maxrss_parent_mb": own.ru_maxrss / 1024, "maxrss_worker_mb": kids.ru_maxrss / 1024,
        "peak_pss_total_mb": peak["pss_kb"] / 1024,
        "load_before": load_before, "load_after": os.getloadavg()[0],
        "points": len(result.summary["points"]), "timings_s": summary["timings_s"],
        "summary_points": summary["points"]}))


def differences(a, b, path="", rtol=1e-12):
    """Paths where two summary.json fragments differ beyond ``rtol`` (timing fields skipped)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for key in sorted(set(a) | set(b)):
            if key == "seconds":
                continue
            if key not in a or key not in b:
                out.append(f"{path}/{key} missing")
            else:
                out += differences(a[key], b[key], f"{path}/{key}", rtol)
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path} length {len(a)} vs {len(b)}"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{path}[{i}]",
                                                                              rtol)]
    if isinstance(a, float) and isinstance(b, float):
        same = a == b or (math.isnan(a) and math.isnan(b)) or \
            abs(a - b) <= rtol * max(abs(a), abs(b))
        return [] if same else [f"{path}: {a!r} vs {b!r}"]
    return [] if a == b else [f"{path}: {a!r} vs {b!r}"]


def write_section(case_path, band, runs, diffs):
    def row(r):
        t = r["timings_s"]
        return (f"| {r['workers']} | {r['wall_s']:.1f} | {r['cpu_parent_s']:.1f} | "
                f"{r['cpu_workers_s']:.1f} | {t.get('hbm_s', float('nan')):.1f} | "
                f"{t.get('stability_s', 0.0):.1f} | {t.get('error_estimate_s', float('nan')):.1f} | "
                f"{t.get('postprocess_s', float('nan')) - t.get('error_estimate_s', 0.0):.1f} | "
                f"{t.get('outputs_s', float('nan')):.1f} | {r['maxrss_parent_mb']:.0f} | "
                f"{r['maxrss_worker_mb']:.0f} | {r['peak_pss_total_mb']:.0f} | "
                f"{r['load_before']:.1f}–{r['load_after']:.1f} |")

    lines = [SECTION, "",
             f"`benchmarks/pipeline/bench_workers.py` on `{case_path}`"
             + (f" (band {band[0]}–{band[1]} Hz)" if band else "") + f", {runs[0]['points']} "
             "points, whole `solve_case` per fresh process, runs in the order 1 2 1 2, "
             "OPENBLAS/OMP/MKL_NUM_THREADS=1, "
             f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. CPU: the solving process "
             "and its workers (RUSAGE_CHILDREN); RSS: ru_maxrss of the solving process and the "
             "largest worker (shared pages count in both); PSS: peak of the summed proportional "
             "set size of the process and its live workers (shared pages once). hbm includes the "
             "deferred stability (its own column); records = postprocess − estimate. Load: "
             "1-minute load average before–after (other jobs share the 2 cores).", "",
             "| workers | wall s | CPU solve s | CPU workers s | hbm s | stability s | "
             "estimate s | records s | outputs s | RSS solve MB | RSS worker MB | PSS total MB | "
             "load |", "|" + "---|" * 13]
    lines += [row(r) for r in runs]
    lines += ["", "Per-point fields of summary.json between the runs (relative 1e-12, timing "
              f"fields skipped): {'identical' if not diffs else f'{len(diffs)} differences'}."]
    lines += [f"- {d}" for d in diffs[:10]]
    path = RESULTS / "point_cost.md"
    text = path.read_text() if path.exists() else ""
    if SECTION in text:
        text = text[:text.index(SECTION)].rstrip() + "\n"
    path.write_text(text.rstrip() + "\n\n" + "\n".join(lines) + "\n")


def main(argv):
    if argv and argv[0] == "--one":
        band = [float(x) for x in argv[3:5]] if len(argv) > 4 else None
        return one_run(argv[1], argv[2], band, argv[-1])
    notes = pathlib.Path("/work/notes/p1_15mm.yaml")
    case_path = next((a for a in argv if a.endswith(".yaml")),
                     str(notes if notes.exists() else ROOT / "cases" / "door_trim.yaml"))
    repeats = int(argv[argv.index("--runs") + 1]) if "--runs" in argv else 2
    band = ([float(argv[argv.index("--band") + 1]), float(argv[argv.index("--band") + 2])]
            if "--band" in argv else None)
    runs = []
    for _ in range(repeats):
        for workers in (1, 2):
            with tempfile.TemporaryDirectory() as out:
                command = [sys.executable, __file__, "--one", case_path, str(workers)]
                command += [str(b) for b in band] if band else []
                done = subprocess.run(command + [out], env=ENV, capture_output=True, text=True,
                                      check=True)
            run = json.loads(done.stdout.strip().splitlines()[-1])
            runs.append(run)
            print(f"workers {workers}: wall {run['wall_s']:.1f} s, CPU {run['cpu_parent_s']:.1f} + "
                  f"{run['cpu_workers_s']:.1f} s, PSS {run['peak_pss_total_mb']:.0f} MB, "
                  f"load {run['load_before']:.1f}", flush=True)
        write(case_path, band, runs)      # after every pair: a stopped run keeps its results


def write(case_path, band, runs):
    diffs = []
    for r in runs[1:]:
        diffs += differences(runs[0]["summary_points"], r["summary_points"])
    plain = [{k: v for k, v in r.items() if k != "summary_points"} for r in runs]
    write_results("workers", {"case": case_path, "band": band, "runs": plain, "differences": diffs[:50]})
    write_section(case_path, band, plain, diffs)


if __name__ == "__main__":
    main(sys.argv[1:])
