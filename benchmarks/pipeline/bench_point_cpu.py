"""CPU seconds of the stages after the linear stage, of two sarfe trees, from one linear stage
(issue 15, task pointcpu) → results/point_cpu.md|json.

    python benchmarks/pipeline/bench_point_cpu.py CASE.yaml STAGE.pkl TREE_A TREE_B [--runs 2]
    python benchmarks/pipeline/bench_point_cpu.py --build CASE.yaml STAGE.pkl      (the stage, once)
    python benchmarks/pipeline/bench_point_cpu.py          (``make bench``: P1 with workers 1 and stability
                                                   off, its stage built in a temporary folder,
                                                   this tree, and $SARFE_BASELINE first if set)

The linear stage (42 s at P1) is built once and pickled (``--build``); each run is a fresh
process of one tree (``PYTHONPATH=TREE``) that loads it and calls ``solve_case(case,
linear_stage=…)`` with everything in that process (give a case with ``solver: {workers: 1}``),
so the CPU of a stage is the process CPU time (user + system, ``time.process_time``) spent in it:
the sweep (``solve_points_pruned``), the error estimates, the point records, the result files
(``write_outputs``) and summary.json. Runs alternate A B A B …; the table gives each stage's
fastest run per tree and the load average at the start of every run (the machine is shared:
compare runs at similar load only).
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import RESULTS, ROOT, child_env, read_case  # noqa: E402

NOTES = "## Where the CPU goes (cProfile, hand-written)"

STAGES = {        # stage name: (module, function) wrapped in sarfe.pipeline.run's namespace
    "sweep": "solve_points_pruned",
    "Hill stability": "serial_stability",       # by need, after a serial sweep (workers 1)
    "error estimates": "error_estimates",
    "point records": "point_records",
    "result files": "write_outputs",
}

CHILD = r"""
import json, pickle, sys, time
import sarfe.pipeline.run as S
import sarfe.results as O
cpu = {}
def timed(name, f):
    def run(*a, **k):
        c = time.process_time()
        try:
            return f(*a, **k)
        finally:
            cpu[name] = cpu.get(name, 0.0) + time.process_time() - c
    return run
for name, attr in STAGES.items():
    setattr(S, attr, timed(name, getattr(S, attr)))
O.write_summary_json = timed("summary.json", O.write_summary_json)
stage = pickle.load(open(sys.argv[2], "rb"))
c, w = time.process_time(), time.perf_counter()
S.solve_case(sys.argv[1], linear_stage=stage, output_dir=sys.argv[3], force=True)
cpu["total after the linear stage"] = time.process_time() - c
print(json.dumps({"cpu_s": cpu, "wall_s": time.perf_counter() - w}))
"""


def run_tree(tree, case, stage, output):
    env = child_env(tree)
    code = f"STAGES = {STAGES!r}\n" + CHILD
    load = os.getloadavg()
    done = subprocess.run([sys.executable, "-c", code, str(case), str(stage), str(output)],
                          env=env, capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result["load"] = [round(x, 2) for x in load]
    return result


def build(case, stage):
    import pickle

    from sarfe.pipeline import build_linear_model, load_case

    with open(stage, "wb") as f:
        pickle.dump(build_linear_model(load_case(case)), f, protocol=5)


def default_run():
    """``make bench`` (no arguments): P1 (cases/door_trim_p1.yaml) in one process with stability
    off, its linear stage built once in a temporary folder; this tree, after $SARFE_BASELINE."""
    import yaml

    case = read_case("cases/door_trim_p1.yaml")
    case.setdefault("solver", {}).update(workers=1, stability=False)
    trees = [t for t in (os.environ.get("SARFE_BASELINE"), str(ROOT)) if t]
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "p1_one_process.yaml"
        case_text = yaml.safe_dump(case, sort_keys=False)
        path.write_text(case_text)
        stage = pathlib.Path(folder) / "stage.pkl"
        subprocess.run([sys.executable, str(pathlib.Path(__file__).resolve()), "--build",
                        str(path), str(stage)], check=True,
                       env=child_env())
        main([str(path), str(stage), *trees])


def main(argv=None):
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", action="store_true")
    parser.add_argument("case")
    parser.add_argument("stage")
    parser.add_argument("trees", nargs="*")
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--out", default=str(RESULTS / "point_cpu"))
    args = parser.parse_args(argv)
    if args.build:
        build(args.case, args.stage)
        return
    trees = [pathlib.Path(t).resolve() for t in args.trees]
    runs = {str(t): [] for t in trees}
    for i in range(args.runs):
        for t in trees:
            with tempfile.TemporaryDirectory() as folder:      # the result files: not kept
                result = run_tree(t, args.case, args.stage, pathlib.Path(folder) / "out")
            runs[str(t)].append(result)
            print(t.name, i, json.dumps(result), flush=True)
    names = list(STAGES) + ["summary.json", "total after the linear stage"]
    lines = ["# CPU seconds of the stages after the linear stage (issue 15, pointcpu)", "",
             f"`benchmarks/pipeline/bench_point_cpu.py` on `{pathlib.Path(args.case).name}`, one prebuilt "
             "linear stage, everything in one process (workers 1), one BLAS thread; runs "
             f"alternated, {args.runs} per tree, fastest per stage. Load averages at the start of "
             "each run: " + "; ".join(f"{pathlib.Path(t).name}: " + ", ".join(
                 str(r["load"][0]) for r in rs) for t, rs in runs.items()) + ".", "",
             "| stage | " + " | ".join(pathlib.Path(t).name for t in runs) + " |",
             "|---|" + "---|" * len(runs)]
    for name in names:
        lines.append(f"| {name} | " + " | ".join(
            f"{min(r['cpu_s'].get(name, float('nan')) for r in rs):.2f}" for rs in runs.values())
            + " |")
    out = pathlib.Path(args.out)
    out.with_suffix(".json").write_text(json.dumps(runs, indent=2))
    md = out.with_suffix(".md")
    kept = ""       # the hand-written profile notes after NOTES are kept across runs
    if md.exists() and NOTES in md.read_text():
        kept = "\n" + NOTES + md.read_text().split(NOTES, 1)[1]
    md.write_text("\n".join(lines) + "\n" + kept)
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) == 1:
        default_run()
    else:
        main()
