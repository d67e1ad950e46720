"""Where the wall time of a ``sarfe solve`` goes, stage by stage, and how busy the cores are.

    python benchmarks/tools/stage_cpu.py CASE.yaml [OUT.json]
    python benchmarks/tools/stage_cpu.py --table LABEL=OUT.json …     (markdown of saved runs)

Runs ``sarfe solve CASE --output <tmp>`` (the sarfe of this tree, or of $SARFE_ROOT) (one BLAS thread per process) and samples, every 0.1 s,
the CPU seconds of the whole process tree (user + system of the live processes plus what the
waited-for children used, /proc/<pid>/stat) and its PSS (/proc/<pid>/smaps_rollup, the forked
workers sharing the model copy-on-write count once; a sample during which a process started or
ended is dropped: a fork between two reads counts the shared pages up to twice). Each stage runs from its stage line
(``sarfe: <stage> …`` on stderr) to the next; per stage it prints the wall seconds, the tree CPU
seconds, the mean busy cores (CPU / wall; 2.0 = both cores of the P1 machine) and the peak tree
PSS. The idle core-seconds of a 2-core machine are 2 × wall − CPU. On a loaded machine the
cores are shared with other jobs, so busy < 2 there is partly the other jobs' share: note the
load average (printed) next to the numbers.
"""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, child_env, process_tree, tree_cpu_seconds, tree_pss_gb  # noqa: E402

TREE = pathlib.Path(os.environ.get("SARFE_ROOT") or ROOT)     # the sarfe that runs


def run(case, out_dir=None) -> dict:
    out_dir = pathlib.Path(out_dir or tempfile.mkdtemp(prefix="stage_cpu_")).resolve()
    env = child_env(TREE)
    cmd = [sys.executable, "-m", "sarfe.cli", "solve", str(pathlib.Path(case).resolve()),
           "--output", str(out_dir / "out"), "--force"]
    load_start = os.getloadavg()
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            cwd=TREE)          # (python -m puts the current folder first)
    lines = []

    def read():
        for raw in proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            if line.startswith("sarfe: ") and not line.startswith("sarfe: warning"):
                lines.append((time.perf_counter() - start, line[7:70]))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    samples = []            # (t, cpu, pss)
    while proc.poll() is None:
        pids = process_tree(proc.pid)
        pss = tree_pss_gb(proc.pid)
        samples.append((time.perf_counter() - start, tree_cpu_seconds(pids, proc.pid),
                        0.0 if pss is None else pss))
        time.sleep(0.1)
    wall = time.perf_counter() - start
    usage = os.times()
    reader.join(timeout=5)
    cpu_total = usage.children_user + usage.children_system
    samples.append((wall, cpu_total, 0.0))
    bounds = [(t, name) for t, name in lines] + [(wall, "end")]
    stages = []
    for (t0, name), (t1, _) in zip(bounds, bounds[1:]):
        inside = [s for s in samples if t0 <= s[0] <= t1]
        before = [s for s in samples if s[0] <= t0]
        c0 = before[-1][1] if before else 0.0
        c1 = inside[-1][1] if inside else c0
        stages.append({"stage": name, "start_s": round(t0, 2), "wall_s": round(t1 - t0, 2),
                       "cpu_s": round(c1 - c0, 2),
                       "busy_cores": round((c1 - c0) / max(t1 - t0, 1e-9), 2),
                       "peak_pss_gb": round(max((s[2] for s in inside), default=0.0), 2)})
    return {"case": str(case), "exit": proc.returncode, "wall_s": round(wall, 2),
            "cpu_s": round(cpu_total, 2), "peak_pss_gb": round(max(s[2] for s in samples), 2),
            "load_average_start": load_start, "load_average_end": os.getloadavg(),
            "stages": stages}


def table(label, result) -> list[str]:
    """Markdown lines of one run: a heading with the totals and load, the stage table."""
    lines = [f"### {label}", "",
             f"`{result['case']}`: exit {result['exit']}, wall {result['wall_s']} s, CPU "
             f"{result['cpu_s']} s, peak tree PSS {result['peak_pss_gb']} GB; load average "
             f"{', '.join(f'{x:.1f}' for x in result['load_average_start'])} at the start, "
             f"{', '.join(f'{x:.1f}' for x in result['load_average_end'])} at the end.", "",
             "| stage | start s | wall s | CPU s | busy cores | peak PSS GB |",
             "|---|---|---|---|---|---|"]
    for s in result["stages"]:
        lines.append(f"| {s['stage']} | {s['start_s']:.1f} | {s['wall_s']:.1f} | {s['cpu_s']:.1f} "
                     f"| {s['busy_cores']:.2f} | {s['peak_pss_gb']:.2f} |")
    return lines + [""]


def main():
    if sys.argv[1] == "--table":        # --table LABEL=run.json …  → markdown on stdout
        for arg in sys.argv[2:]:
            label, path = arg.split("=", 1)
            print("\n".join(table(label, json.loads(pathlib.Path(path).read_text()))))
        return
    result = run(sys.argv[1])
    print(f"{result['case']}: exit {result['exit']}, wall {result['wall_s']} s, CPU "
          f"{result['cpu_s']} s, peak tree PSS {result['peak_pss_gb']} GB; load average "
          f"{result['load_average_start']} → {result['load_average_end']}")
    print(f"{'stage':58s} {'start':>7s} {'wall':>7s} {'CPU':>7s} {'cores':>5s} {'PSS GB':>6s}")
    for s in result["stages"]:
        print(f"{s['stage']:58s} {s['start_s']:7.1f} {s['wall_s']:7.1f} {s['cpu_s']:7.1f} "
              f"{s['busy_cores']:5.2f} {s['peak_pss_gb']:6.2f}")
    if len(sys.argv) > 2:
        pathlib.Path(sys.argv[2]).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
