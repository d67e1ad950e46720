"""Issue 30 item 5: the full instrument panel at ≈ 1 M DOF, from mesh to report — wall time, peak
memory and the dominant stage of one whole ``sarfe solve`` per mesh size, and the scaling
t ∝ DOF^a fitted over the sizes measured.

The case is cases/instrument_panel_sweep.yaml (the shaker-test panel: one rattle + one squeak
spot, 1 g, every solver knob at its default: resolution auto, accuracy balanced, mesh error auto)
with the generator's ``mesh_size_m`` set for a target DOF count (DOFs ∝ h⁻², calibrated on the
shipped 15 mm mesh: 26 292 DOFs) and the 20–200 Hz sweep replaced by ONE frequency, 65.3 Hz, the
loudest point of the shipped sweep (issue 30: 108.0 dB(A) at 65.3 Hz). Each size runs as

    nice -n 10 timeout T /usr/bin/time -v python -m sarfe solve CASE --output DIR --force

with a fresh mesh cache (the mesh is generated in the run, as a user's first run does), one BLAS
thread. Peak RSS: GNU time's "Maximum resident set size" (the largest single process); the tree's
peak PSS (forked workers counted once) is sampled every 0.5 s, and the run is stopped when it
passes ``--max-gb``. Stage seconds: summary.json ``timings_s`` plus the stage lines on stderr
(``sarfe: linear stage: mesh …``), time-stamped as they arrive; the dominant stage is the longest of
the stderr stages. ``--profile`` samples the child's Python stack every 0.2 s (a small sampling
profiler in the child; py-spy is not installed, and cProfile's dump is lost when the run is
stopped) and lists the hot functions of the run.

    python benchmarks/pipeline/bench_large_panel.py                     ladder 3e4,1e5,3e5 (default)
    python benchmarks/pipeline/bench_large_panel.py --dofs 1e6 --profile --keep
    python benchmarks/pipeline/bench_large_panel.py --dofs 0            nothing measured (skip; the
                                                                        .md rewritten from the .json)

``--keep`` keeps the sizes of the previous results/large_panel.json not measured now.
Writes benchmarks/results/large_panel.json and .md.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
import benchlib  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402

CASE = benchlib.CASES / "instrument_panel_sweep.yaml"
FREQUENCY_HZ = 65.3                  # the loudest point of the shipped 20-200 Hz sweep
H0_M, DOFS0 = 0.015, 26292           # the shipped mesh and its total DOFs (summary.json)
PROFILE_WRAPPER = """
import collections, json, sys, threading, time
from sarfe.cli import main
out = sys.argv.pop(1)
main_id = threading.get_ident()
own, cum, n = collections.Counter(), collections.Counter(), [0]
def name(code):
    return code.co_filename.rsplit('/', 1)[-1] + ':' + str(code.co_firstlineno) + '(' + code.co_name + ')'
def sample():
    last = time.monotonic()
    while True:
        time.sleep(0.2)
        frame = sys._current_frames().get(main_id)
        if frame is None:
            continue
        n[0] += 1
        own[name(frame.f_code)] += 1
        seen = set()
        while frame is not None:
            seen.add(name(frame.f_code))
            frame = frame.f_back
        cum.update(seen)
        if time.monotonic() - last > 5:
            last = time.monotonic()
            with open(out + '.tmp', 'w') as f:
                json.dump({'samples': n[0], 'interval_s': 0.2, 'own': own.most_common(40),
                           'cumulative': cum.most_common(80)}, f)
            import os; os.replace(out + '.tmp', out)
threading.Thread(target=sample, daemon=True).start()
sys.exit(main(sys.argv[1:]))
"""


def mesh_size_for(dofs: float, runs=()) -> float:
    """Generator mesh size [m] for a target DOF count: DOFs = c · h^-p fitted over the measured
    ``runs`` (two or more; the generator's fixed-size features make p < 2), else p = 2 through
    the shipped 15 mm mesh."""
    pts = [(r["mesh_size_m"], r["total_dofs"]) for r in runs if r.get("total_dofs")]
    if len(pts) >= 2:
        x, y = np.log(np.array(pts, dtype=float)).T
        slope, icpt = np.polyfit(x, y, 1)
        return round(float(np.exp((np.log(dofs) - icpt) / slope)), 5)
    return round(H0_M * (DOFS0 / dofs) ** 0.5, 5)


def case_for(mesh_m: float, work: pathlib.Path) -> pathlib.Path:
    """The shipped case at ``mesh_m`` and one frequency, written to ``work``/case.yaml."""
    data = benchlib.read_case(CASE)
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [FREQUENCY_HZ]
    path = work / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def parse_time_v(text: str) -> dict:
    """Wall, CPU and peak RSS from GNU ``time -v`` output."""
    out = {}
    for key, name in (("Maximum resident set size (kbytes)", "peak_rss_gb"),
                      ("User time (seconds)", "user_s"), ("System time (seconds)", "system_s"),
                      ("Elapsed (wall clock) time (h:mm:ss or m:ss)", "time_wall_s"),
                      ("Exit status", "exit_status")):
        m = re.search(re.escape(key) + r": (.+)", text)
        if not m:
            continue
        value = m.group(1).strip()
        if name == "peak_rss_gb":
            out[name] = int(value) / 1e6
        elif name == "time_wall_s":
            parts = [float(p) for p in value.split(":")]
            out[name] = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
        else:
            out[name] = float(value)
    return out


def stage_seconds(stages, end_s) -> dict:
    """Seconds of each stderr stage line until the next (the last one until ``end_s``)."""
    out = {}
    for (t, name), nxt in zip(stages, [s[0] for s in stages[1:]] + [end_s]):
        key = re.sub(r"\s*….*$", "", name).strip()
        key = re.sub(r"\s*(\(| on \d).*$", "", key).strip()
        out[key] = round(out.get(key, 0.0) + nxt - t, 2)
    return out


def run(dofs: float, timeout_s: float, max_gb: float, profile: bool, root: pathlib.Path,
        runs=()) -> dict:
    """One whole ``sarfe solve`` at the mesh size for ``dofs`` (calibrated on ``runs``): the
    record of the run."""
    mesh_m = mesh_size_for(dofs, runs)
    work = root / f"h{mesh_m * 1e3:.2f}mm"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    case = case_for(mesh_m, work)
    python = [sys.executable]
    if profile:
        (work / "wrap.py").write_text(PROFILE_WRAPPER)
        python += [str(work / "wrap.py"), str(work / "profile.json")]
    else:
        python += ["-m", "sarfe"]
    cmd = ["nice", "-n", "10", "timeout", str(int(timeout_s)), "/usr/bin/time", "-v", "-o",
           str(work / "time.txt"), *python, "solve", str(case), "--output", str(work / "out"),
           "--force"]
    env = benchlib.child_env(SARFE_MESH_CACHE=str(work / "mesh_cache"))
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    stages, lines = [], []

    def read(stream):
        for raw in stream:
            line = raw.decode(errors="replace").rstrip()
            lines.append(line)
            if line.startswith("sarfe: ") and "…" in line:
                stages.append((round(time.perf_counter() - start, 2), line[7:90]))

    readers = [threading.Thread(target=read, args=(s,), daemon=True)
               for s in (proc.stdout, proc.stderr)]
    for r in readers:
        r.start()
    peak_pss, stopped = 0.0, None
    while proc.poll() is None:
        pss = benchlib.tree_pss_gb(proc.pid)
        peak_pss = max(peak_pss, pss or 0.0)
        if pss and pss > max_gb and stopped is None:
            stopped = f"memory: tree PSS {pss:.1f} GB > {max_gb:g} GB"
            os.killpg(proc.pid, signal.SIGTERM)
        time.sleep(0.5)
    wall = time.perf_counter() - start
    for r in readers:
        r.join(timeout=5)
    code = proc.returncode
    (work / "console.txt").write_text("\n".join(lines) + "\n")
    if code == 124 and stopped is None:
        stopped = f"timeout {timeout_s:.0f} s"
    rec = {"target_dofs": dofs, "mesh_size_m": mesh_m, "exit": code, "stopped": stopped,
           "wall_s": round(wall, 2), "peak_tree_pss_gb": round(peak_pss, 3),
           "stages_at_s": stages, "stage_s": stage_seconds(stages, wall),
           "load_average_end": os.getloadavg(), "profiled": profile}
    if (work / "time.txt").exists():
        rec.update(parse_time_v((work / "time.txt").read_text()))
    summary_path = work / "out" / "summary.json"
    if summary_path.exists() and stopped is None:
        s = json.loads(summary_path.read_text())
        m = s["model"]
        worst = s.get("worst") or {}
        rec.update(nodes=m.get("nodes"), total_dofs=m.get("total_dofs"),
                   free_dofs=m.get("free_dofs"), modes=m.get("modes"),
                   reduced_dofs=m.get("reduced_dofs"), cutoff_hz=m.get("cutoff_hz"),
                   harmonics=s["solver"].get("harmonics"),
                   samples=s["solver"].get("samples_per_period"),
                   timings_s={k: round(v, 2) for k, v in s["timings_s"].items()},
                   loudest_dba=worst.get("erp_level_dba"), loudest_pm_db=worst.get("erp_error_db"),
                   loudest_hz=worst.get("frequency_hz"),
                   written_mb=round(sum(p.stat().st_size for p in (work / "out").rglob("*")
                                        if p.is_file()) / 1e6, 1))
    else:
        rec["tail"] = lines[-6:]
    if rec["stage_s"]:
        rec["dominant_stage"] = max(rec["stage_s"], key=rec["stage_s"].get)
    if profile and (work / "profile.json").exists():
        rec["hot_functions"] = hot_functions(work / "profile.json")
    return rec


def hot_functions(path, n=15) -> dict:
    """The top ``n`` Python functions of the main process's stack samples (every 0.2 s, written
    every 5 s, so a stopped run keeps them): own (the innermost Python frame, which includes
    the C/BLAS code it calls) and cumulative (anywhere on the stack), as seconds."""
    data = json.loads(pathlib.Path(path).read_text())
    dt = data["interval_s"]
    return {"samples": data["samples"],
            "own": [{"function": f, "s": round(c * dt, 1)} for f, c in data["own"][:n]],
            "cumulative": [{"function": f, "s": round(c * dt, 1)} for f, c in data["cumulative"][:2 * n]]}


def fit(rows) -> float | None:
    """Exponent a of wall ∝ DOF^a (least squares in log-log) over completed runs."""
    pts = [(r["total_dofs"], r["wall_s"]) for r in rows if r.get("total_dofs") and not r["stopped"]]
    if len(pts) < 2:
        return None
    x, y = np.log(np.array(pts, dtype=float)).T
    return float(np.polyfit(x, y, 1)[0])


def fit_line(rows, key):
    pts = [(r["total_dofs"], r[key]) for r in rows
           if r.get("total_dofs") and not r["stopped"] and r.get(key)]
    if len(pts) < 2:
        return None
    x, y = np.log(np.array(pts, dtype=float)).T
    a, b = np.polyfit(x, y, 1)
    return float(a), float(b)


def fmt(x, spec=".1f"):
    return "-" if x is None else format(x, spec)


def markdown(results) -> list[str]:
    rows = sorted(results["runs"], key=lambda r: r["target_dofs"])
    L = ["# Full instrument panel at growing mesh density, mesh → report (issue 30 item 5)", "",
         benchlib.machine_line(), "",
         f"Case: `cases/instrument_panel_sweep.yaml` (1 rattle + 1 squeak spot, 1 g, every solver "
         f"knob at its default: resolution auto, accuracy balanced, mesh error auto) with "
         f"`model.fe.generator.mesh_size_m` set per row and the 20–200 Hz sweep replaced by ONE "
         f"frequency, {FREQUENCY_HZ} Hz (the loudest point of the shipped sweep). One whole "
         "`sarfe solve` per row under `nice -n 10 timeout … /usr/bin/time -v`, a fresh mesh cache "
         "(mesh generation is in the time), one BLAS thread, the machine shared with other "
         "engineers (load average in the last column). Peak RSS: GNU time (largest single "
         "process); tree PSS: sampled every 0.5 s (forked workers counted once).", "",
         "| h mm | nodes | DOFs | modes | H/N | wall s | CPU s | peak RSS GB | tree PSS GB | "
         "dominant stage (s) | loudest dB(A) | written MB | load | stopped |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        dom = r.get("dominant_stage")
        cpu = (r.get("user_s") or 0) + (r.get("system_s") or 0)
        L.append(f"| {r['mesh_size_m'] * 1e3:.2f} | {r.get('nodes', '-')} | "
                 f"{r.get('total_dofs', '~%d (target)' % r['target_dofs'])} | {r.get('modes', '-')} | "
                 f"{r.get('harmonics', '-')}/{r.get('samples', '-')} | {r['wall_s']:.0f} | {cpu:.0f} | "
                 f"{fmt(r.get('peak_rss_gb'), '.2f')} | {fmt(r.get('peak_tree_pss_gb'), '.2f')} | "
                 f"{dom} ({fmt(r['stage_s'].get(dom) if dom else None, '.0f')}) | "
                 f"{fmt(r.get('loudest_dba'), '.2f')} ± {fmt(r.get('loudest_pm_db'), '.2f')} | "
                 f"{fmt(r.get('written_mb'))} | {r['load_average_end'][0]:.1f} | "
                 f"{r['stopped'] or ('profiled' if r.get('profiled') else '-')} |")
    L += ["", "## Stage seconds per row", "",
          "From the time-stamped stage lines on stderr (each until the next), then summary.json "
          "`timings_s`.", ""]
    for r in rows:
        L.append(f"- {r['mesh_size_m'] * 1e3:.2f} mm: stages {json.dumps(r['stage_s'])}; "
                 f"timings_s {json.dumps(r.get('timings_s'))}")
    a = fit(rows)
    mem = fit_line(rows, "peak_rss_gb")
    L += ["", "## Scaling", ""]
    if a is not None:
        t = fit_line(rows, "wall_s")
        at = lambda c, d: float(np.exp(c[1]) * d ** c[0])          # noqa: E731
        L.append(f"Wall time ∝ DOF^{a:.2f} over the completed rows; extrapolated to 1 M DOF: "
                 f"{at(t, 1e6):.0f} s; peak RSS ∝ DOF^{fmt(mem[0] if mem else None, '.2f')}, "
                 f"extrapolated {fmt(at(mem, 1e6) if mem else None, '.1f')} GB at 1 M DOF.")
    done = [r for r in rows if r.get("total_dofs") and not r["stopped"]]
    if len(done) >= 2:
        a_, b_ = done[-2], done[-1]
        ratio = b_["total_dofs"] / a_["total_dofs"]
        L += ["", f"Per stage between the two largest completed rows ({a_['total_dofs']} → "
              f"{b_['total_dofs']} DOFs): exponent, and that stage extrapolated to 1 M DOF:", "",
              "| stage | s | s | exponent | s at 1 M DOF |", "|---|---|---|---|---|"]
        total = 0.0
        for key, t1 in b_["stage_s"].items():
            t0 = a_["stage_s"].get(key)
            if not t0 or t0 < 0.5 or t1 < 0.5:
                continue
            e = np.log(t1 / t0) / np.log(ratio)
            t = t1 * (1e6 / b_["total_dofs"]) ** max(e, 0.0)
            total += t
            L.append(f"| {key} | {t0:.1f} | {t1:.1f} | {e:.2f} | {t:.0f} |")
        L += ["", f"Sum of the stages extrapolated (stages under 0.5 s left out): {total:.0f} s."]
    for note in results.get("notes", []):
        L += ["", note]
    prof = [r for r in rows if r.get("hot_functions")]
    for r in prof:
        h = r["hot_functions"]
        L += ["", f"## Hot functions, {r['mesh_size_m'] * 1e3:.2f} mm ({h['samples']} stack samples of "
              "the main process every 0.2 s; own = innermost Python frame, including the C/BLAS "
              "code it calls; forked workers not sampled)", "",
              "| own (innermost) | s |", "|---|---|"]
        L += [f"| `{x['function']}` | {x['s']} |" for x in h["own"]]
        L += ["", "| cumulative (on the stack) | s |", "|---|---|"]
        L += [f"| `{x['function']}` | {x['s']} |" for x in h["cumulative"]]
    return L


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dofs", default="3e4,1e5,3e5",
                        help="target DOF counts, comma-separated (0: measure nothing)")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per run")
    parser.add_argument("--max-gb", type=float, default=20.0, help="stop a run above this PSS")
    parser.add_argument("--profile", action="store_true", help="sample the runs' Python stacks (hot functions)")
    parser.add_argument("--keep", action="store_true",
                        help="keep the previous results' sizes not measured now")
    args = parser.parse_args(argv)
    targets = [float(x) for x in args.dofs.split(",") if float(x) > 0]
    old = benchlib.read_results("large_panel") or {}
    if not targets:
        print("bench_large_panel: no size asked (--dofs 0): nothing measured"
              + ("; large_panel.md rewritten from large_panel.json" if old else ""))
        if old:
            benchlib.write_results("large_panel", markdown=markdown(old))
        return 0
    results = {"machine": benchlib.machine(), "case": str(CASE.relative_to(benchlib.ROOT)),
               "frequency_hz": FREQUENCY_HZ, "notes": old.get("notes", []), "runs": []}
    if args.keep:
        results["runs"] = [r for r in old.get("runs", [])
                           if all(abs(r["target_dofs"] - t) > 0.05 * t for t in targets)]
    root = pathlib.Path(tempfile.gettempdir()) / "sarfe_bench_large_panel"
    for dofs in targets:
        calibration = results["runs"] + [r for r in old.get("runs", []) if r not in results["runs"]]
        print(f"bench_large_panel: ~{dofs:.0f} DOF "
              f"(h = {mesh_size_for(dofs, calibration) * 1e3:.2f} mm) …", flush=True)
        rec = run(dofs, args.timeout, args.max_gb, args.profile, root, calibration)
        results["runs"].append(rec)
        print(f"  {rec.get('total_dofs')} DOF: {rec['wall_s']:.0f} s, "
              f"{fmt(rec.get('peak_rss_gb'), '.2f')} GB, dominant {rec.get('dominant_stage')}"
              f"{', stopped: ' + rec['stopped'] if rec['stopped'] else ''}", flush=True)
        results["scaling_exponent"] = fit(results["runs"])
        benchlib.write_results("large_panel", results, default=str)
        benchlib.write_results("large_panel", markdown=markdown(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
