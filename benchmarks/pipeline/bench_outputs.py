"""Cost of the result files per point and per run on the 5 mm door trim (issue 15, P1) →
results/outputs.md|json.

The P1 mesh (cases/door_trim_p1.yaml: door_trim generator, 5 mm, 8 rattle + 4 squeak spots;
34,359 nodes, 67,950 triangles, 24,100 radiating skin nodes) from the mesh cache, H = 15, with
synthetic fields of the sizes a P1 point has (normal-displacement harmonics (31, 24,100) with a
1/k spectrum, the ERP of them, nodal translation harmonics (31, 34,359, 3) for the loudest
point, 12 contact pairs' fields; 757 reduced DOFs, N = 256 for response.h5). The writers are the
real ones; only the solve is left out, so the seconds are those of the output stage alone.

Timed, in a fresh process per source tree (``--before TREE``: e.g. a ``git archive`` of main,
the same script runs against it so the two columns are the same work):

1. per point: the ERP point arrays (``erp_point_data``) of an ordinary point and of the loudest
   (with the nodal displacement), one ``write_erp_vtu`` of those arrays;
2. a sweep's ERP map series, ``--points`` maps (default 200, P1's count): ``write_erp_sweep`` with
   the point arrays built as the pipeline builds them (before: a generator, which the old writer
   turned into a list of all maps; now: a function j → arrays, serial and on 2 worker processes),
   seconds per point and the peak resident memory the series added;
3. per run: the 24-frame deflection animation and response.h5 of ``--points`` points;
4. ``--whole``: the real pipeline on the P1 model, ``sarfe.pipeline.solve_case`` of
   cases/door_trim_p1.yaml with ``--points`` listed frequencies 40, 40.1, … Hz, 30 fixed-interface
   modes (the output stage does not depend on the modes), stability and estimate off,
   ``solver.workers: 2``, every output file: wall and CPU (the solving process and its children:
   the map workers, the render child) of ``write_outputs``, and the peak RSS of the run. The
   files of both trees are compared (every VTU array, response.h5, summary.json points). Without
   ``--whole`` the last whole-run numbers are kept from results/outputs.json.

Each number is the fastest of ``--repeats`` runs (the machine is shared). Files go to a
temporary directory (≈ 1.1 GB for 200 maps) removed afterwards.

5. ``--records CASE [CASE …]``: the point records and the result files of real solves
   (``solve_case`` of each case with ``solver.workers: 1``, so all of it runs in one process and
   its CPU seconds are exact): CPU and wall of ``point_records`` (ERP, contributions, linear
   baseline, map fields), ``write_outputs`` and ``write_summary_json``, per tree, the trees run
   in turn (A B A B with ``--repeats`` 2); the fastest CPU of the repeats. The result folders
   of the trees are compared file by file (benchmarks/tools/compare_outputs.py). Saved in
   results/outputs_records.json and shown as the last section of outputs.md.

Run: python benchmarks/pipeline/bench_outputs.py [--before TREE [--before-commit C]] [--points 200]
     [--repeats 3] [--whole]   (--whole: ≈ 2 min per tree on a quiet machine)
     python benchmarks/pipeline/bench_outputs.py --records CASE.yaml … --before TREE [--repeats 1]
"""
import argparse
import json
import os
import pathlib
import platform
import resource
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, child_env, cpu_seconds, peak_rss_gb, read_results, write_results  # noqa: E402
from tools.compare_outputs import compare_folders  # noqa: E402

H = 15
SAMPLES = 256
REDUCED_DOFS = 757
PAIRS = 12


def _best(function, repeats):
    """{"s": fastest wall, "cpu_s": smallest CPU} [s] of ``repeats`` calls (CPU of this process:
    what carries over from a loaded machine; the writers here are single-threaded)."""
    walls, cpus = [], []
    for _ in range(repeats):
        cpu, clock = time.process_time(), time.perf_counter()
        function()
        walls.append(time.perf_counter() - clock)
        cpus.append(time.process_time() - cpu)
    return {"s": min(walls), "cpu_s": min(cpus)}


def child(points, repeats, workdir):
    """The measurements in this process (sarfe imported from PYTHONPATH); prints one JSON line."""
    import inspect
    from types import SimpleNamespace

    import numpy as np

    import sarfe
    from sarfe.erp import equivalent_radiated_power, nodal_areas
    from sarfe import results as outputs
    from sarfe.results.vtk import contact_point_values
    from sarfe.mesh.cache import cached_mesh

    mesh = cached_mesh("door_trim", 0.005, rattle_spots=8, squeak_spots=4)
    skin = mesh.triangles[mesh.element_groups["skin"]]
    nodes = np.unique(skin)
    n = mesh.n_nodes
    areas = nodal_areas(mesh.points, skin)[nodes]
    rng = np.random.default_rng(15)
    spectrum = 1.0 / np.repeat(np.arange(1, H + 1), 2)
    shapes = [np.vstack([rng.standard_normal(nodes.size) * 1e-4,
                         rng.standard_normal((2 * H, nodes.size)) * 1e-5 * spectrum[:, None]])
              for _ in range(4)]
    omegas = 2 * np.pi * np.linspace(40.0, 80.0, points)
    erps = [equivalent_radiated_power(shapes[j], omegas[j % points], areas) for j in range(4)]
    translations = rng.standard_normal((2 * H + 1, n, 3)) * 1e-5
    markers = np.zeros(n, np.int32)
    pair_a = rng.choice(n, PAIRS, replace=False)
    pair_b = rng.choice(n, PAIRS, replace=False)
    loudest = points // 2

    def point_data(j, displacement=None):
        force = contact_point_values(n, pair_a, pair_b, rng.random(PAIRS))
        motion = contact_point_values(n, pair_a, pair_b, rng.random(PAIRS) * 1e-4)
        return outputs.erp_point_data(n, erps[j % 4], shapes[j % 4], omegas[(j % 4) % points],
                                      displacement=displacement, radiating_nodes=nodes,
                                      contact_marker=markers, contact_force=force,
                                      contact_displacement=motion)

    result = {"sarfe": str(pathlib.Path(sarfe.__file__).parent.parent), "nodes": int(n),
              "triangles": int(mesh.n_triangles), "radiating_nodes": int(nodes.size),
              "points": points}
    result["point_data_s"] = _best(lambda: point_data(1), repeats)
    result["point_data_loudest_s"] = _best(lambda: point_data(loudest, translations), repeats)
    data = point_data(1)
    outputs.write_erp_vtu(workdir / "warm.vtu", mesh.points, mesh.triangles, data)
    result["write_vtu_s"] = _best(lambda: outputs.write_erp_vtu(
        workdir / "one.vtu", mesh.points, mesh.triangles, data,
        field_data={"frequency_hz": 60.0, "point_index": 1}), repeats)
    result["vtu_bytes"] = (workdir / "one.vtu").stat().st_size

    frequencies = omegas / (2 * np.pi)
    loudest_data = point_data(loudest, translations)

    def series_data(j):
        return loudest_data if j == loudest else point_data(j)

    takes_function = "workers" in inspect.signature(outputs.write_erp_sweep).parameters
    variants = {"serial": 1, "2 workers": 2} if takes_function else {"serial": 1}
    result["series"] = {}
    for label, workers in variants.items():
        rss_before = peak_rss_gb()

        def run():
            if takes_function:
                outputs.write_erp_sweep(workdir / "erp", mesh.points, mesh.triangles, series_data,
                                        frequencies, workers=workers)
            else:   # the old writer: the pipeline passed a generator, the writer listed it
                outputs.write_erp_sweep(workdir / "erp", mesh.points, mesh.triangles,
                                        (series_data(j) for j in range(points)), frequencies)
        walls, cpus = [], []
        for _ in range(repeats):
            cpu, clock = cpu_seconds(), time.perf_counter()
            run()
            walls.append(time.perf_counter() - clock)
            cpus.append(cpu_seconds() - cpu)
        size = sum(f.stat().st_size for f in (workdir / "erp").glob("*.vtu"))
        result["series"][label] = {"s": min(walls), "s_per_point": min(walls) / points,
                                   "cpu_s": min(cpus), "bytes": size,
                                   "peak_rss_added_gb": peak_rss_gb() - rss_before}

    result["animation_s"] = _best(lambda: outputs.write_deflection_animation(
        workdir / "animation", mesh.points, mesh.triangles, translations, omega=omegas[loudest],
        point_data={"contact_marker": markers}), repeats)
    rows = 3 * PAIRS
    solutions = [SimpleNamespace(
        omega=omegas[j], harmonics=H, samples_per_period=SAMPLES, converged=True, stable=True,
        displacement=rng.standard_normal((2 * H + 1, REDUCED_DOFS)) * 1e-5,
        contact_displacement=rng.standard_normal((2 * H + 1, rows)) * 1e-5,
        contact_force=rng.standard_normal((2 * H + 1, rows)),
        contact_force_time=rng.standard_normal((SAMPLES, rows)),
        contact_state=rng.integers(0, 3, (SAMPLES, PAIRS)).astype(np.int8)) for j in range(points)]
    result["response_h5_s"] = _best(lambda: outputs.write_response_h5(
        workdir / "response.h5", solutions, excitation=np.ones((2 * H + 1, REDUCED_DOFS)),
        erp=[erps[j % 4] for j in range(points)], radiating_nodes=nodes), repeats)
    result["response_h5_bytes"] = (workdir / "response.h5").stat().st_size
    print(json.dumps(result))


def whole_case(points) -> dict:
    """cases/door_trim_p1.yaml with ``points`` listed frequencies and a small modal basis."""
    import yaml

    data = yaml.safe_load((ROOT / "cases" / "door_trim_p1.yaml").read_text())
    data["name"] = "door_trim_p1_outputs"
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [round(40.0 + 0.1 * j, 1) for j in range(points)]
    data["reduction"] = {"mode_count": 30}
    data["solver"] = {"harmonics": 15, "stability": False, "error_estimate": False, "workers": 2}
    return data


def whole_child(case_path, out):
    """Solve the case, timing ``write_outputs`` (wall, CPU of this process and of its waited
    children); prints one JSON line."""
    import sarfe.pipeline.run as solve
    from sarfe.pipeline import load_case, solve_case

    write_outputs, record = solve.write_outputs, {}

    def children_cpu():
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    def timed(*args, **kwargs):
        children, cpu, clock = children_cpu(), time.process_time(), time.perf_counter()
        written = write_outputs(*args, **kwargs)
        record.update(outputs_wall_s=time.perf_counter() - clock,
                      outputs_cpu_s=time.process_time() - cpu,
                      outputs_children_cpu_s=children_cpu() - children)
        return written

    solve.write_outputs = timed
    result = solve_case(load_case(case_path).data, output_dir=out)
    record.update(points=len(result.summary["points"]), timings_s=result.summary["timings_s"],
                  peak_rss_gb=peak_rss_gb(), load_average=os.getloadavg()[0])
    print(json.dumps(record))


def measure_whole(trees, points):
    """{label: whole-run record} of each tree, and the largest difference of their files."""
    import yaml

    records = {}
    with tempfile.TemporaryDirectory(prefix="bench_outputs_whole_") as work:
        work = pathlib.Path(work)
        case = work / "case.yaml"
        case.write_text(yaml.safe_dump(whole_case(points)))
        for label, tree in trees.items():
            env = child_env(tree)
            done = subprocess.run([sys.executable, __file__, "--whole-child", str(case),
                                   str(work / label)], env=env, capture_output=True, text=True)
            if done.returncode:
                raise RuntimeError(f"whole run on {tree} failed:\n{done.stderr[-3000:]}")
            records[label] = json.loads(done.stdout.strip().splitlines()[-1])
        if len(trees) == 2:
            records["difference"] = compare_results(*(work / label for label in trees))
    return records


def compare_results(a, b) -> dict:
    """Largest relative difference of every VTU point array of two result folders (each array
    against its own largest magnitude), whether the PVDs, response.h5 datasets and the points of
    summary.json agree."""
    import h5py
    import numpy as np
    import pyvista as pv

    worst, where = 0.0, None
    files = sorted(p.relative_to(a) for p in a.rglob("*.vtu"))
    for name in files:
        first, second = pv.read(a / name), pv.read(b / name)
        assert set(first.point_data) == set(second.point_data), name
        assert np.array_equal(first.points, second.points), name
        for key in first.point_data:
            x, y = first.point_data[key], second.point_data[key]
            assert x.dtype == y.dtype and x.shape == y.shape, (name, key)
            d = float(np.abs(x - y).max() / max(np.abs(x).max(), 1e-300))
            if d > worst:
                worst, where = d, f"{name}: {key}"
    pvd_same = all((a / p.relative_to(a)).read_text() == (b / p.relative_to(a)).read_text()
                   for p in a.rglob("*.pvd"))
    h5_differ = []
    with h5py.File(a / "response.h5") as fa, h5py.File(b / "response.h5") as fb:
        def visit(name, item):
            if isinstance(item, h5py.Dataset):
                x, y = item[()], fb[name][()]
                same = (np.allclose(x, y, rtol=1e-12, atol=0, equal_nan=True)
                        if x.dtype.kind in "fc" else np.array_equal(x, y))
                if not same:
                    h5_differ.append(name)
        fa.visititems(visit)
    points = [json.loads((d / "summary.json").read_text())["points"] for d in (a, b)]
    return {"vtu_files": len(files), "vtu_worst_relative": worst, "vtu_worst_at": where,
            "pvd_identical": pvd_same, "h5_differing": h5_differ,
            "summary_points_identical": points[0] == points[1]}


def records_child(case_path, out):
    """Solve ``case_path`` with ``solver.workers: 1`` timing the point records and the writers
    (CPU of this process: with one worker everything runs here); prints one JSON line."""
    import sarfe.results as io_outputs
    import sarfe.pipeline.run as solve
    from sarfe.case.read import read_yaml
    from sarfe.pipeline import load_case, solve_case

    record = {}

    def timed(name, function):
        def run(*args, **kwargs):
            cpu, clock = time.process_time(), time.perf_counter()
            value = function(*args, **kwargs)
            record[f"{name}_cpu_s"] = time.process_time() - cpu
            record[f"{name}_wall_s"] = time.perf_counter() - clock
            return value
        return run

    solve.point_records = timed("records", solve.point_records)
    solve.write_outputs = timed("write_outputs", solve.write_outputs)
    io_outputs.write_summary_json = timed("summary_json", io_outputs.write_summary_json)
    data, _ = read_yaml(case_path)
    data.setdefault("solver", {})["workers"] = 1
    case = load_case(data, base_dir=pathlib.Path(case_path).resolve().parent)
    clock = time.perf_counter()
    result = solve_case(case, output_dir=out, force=True)
    record.update(points=len(result.summary["points"]), total_wall_s=time.perf_counter() - clock,
                  load_average=os.getloadavg()[0])
    print(json.dumps(record))


def measure_records(cases, trees, repeats) -> dict:
    """{case name: {tree label: fastest record of records_child, "difference": compare}}."""
    out = {}
    with tempfile.TemporaryDirectory(prefix="bench_records_") as work:
        work = pathlib.Path(work)
        for case in cases:
            case = pathlib.Path(case).resolve()
            runs = {label: [] for label in trees}
            for _ in range(repeats):
                for label, tree in trees.items():        # A B A B: the same load for both
                    env = child_env(tree)
                    done = subprocess.run([sys.executable, __file__, "--records-child",
                                           str(case), str(work / label)], env=env,
                                          capture_output=True, text=True, cwd=case.parent)
                    if done.returncode:
                        raise RuntimeError(f"{case} on {tree} failed:\n{done.stderr[-3000:]}")
                    runs[label].append(json.loads(done.stdout.strip().splitlines()[-1]))
            entry = {label: min(r, key=lambda x: x["records_cpu_s"] + x["write_outputs_cpu_s"])
                     for label, r in runs.items()}
            if len(trees) == 2:
                report = compare_folders(*(work / label for label in trees))
                entry["difference"] = {"files": report.files, "same": not report.failed(),
                                       "worst": report.worst, "problems": report.problems}
            out[case.stem] = entry
    return out


def records_report(records) -> list:
    lines = ["", "## Point records and result files of real solves (`--records`)", "",
             "`solve_case` with `solver.workers: 1` (everything in one process, exact CPU); "
             "`point_records`: ERP, contributions, linear baseline, contact indicators, map "
             "fields of every point; `write_outputs`: VTU maps, animation, response.h5, PNGs, "
             "report; summary.json apart. CPU s (wall s); fastest of the A/B repeats.", "",
             "| case | tree | points | records | write_outputs | summary.json | records ms/point "
             "| load |", "|---|---|---|---|---|---|---|---|"]
    both = lambda r, k: f"{r[k + '_cpu_s']:.2f} ({r[k + '_wall_s']:.2f})"  # noqa: E731
    notes = records.get("_notes", [])         # measured by hand (stage_cpu.py): markdown lines
    records = {case: entry for case, entry in records.items() if not case.startswith("_")}
    for case, entry in records.items():
        for label, r in entry.items():
            if label == "difference":
                continue
            lines.append(f"| {case} | {label} | {r['points']} | {both(r, 'records')} | "
                         f"{both(r, 'write_outputs')} | {both(r, 'summary_json')} | "
                         f"{1e3 * r['records_cpu_s'] / r['points']:.1f} | "
                         f"{r['load_average']:.1f} |")
    for case, entry in records.items():
        d = entry.get("difference")
        if d:
            worst = "; ".join(f"{k} {v[0]:.1e} ({v[1]})" for k, v in sorted(d["worst"].items()))
            lines.append(f"\n{case}: {d['files']} files compared, "
                         f"{'same within 1e-12' if d['same'] else 'DIFFERENT'}: {worst}"
                         + (f"; problems: {d['problems']}" if d["problems"] else ""))
    return lines + ([""] + notes if notes else [])


def measure(tree, points, repeats):
    env = child_env(tree)
    with tempfile.TemporaryDirectory(prefix="bench_outputs_") as work:
        done = subprocess.run([sys.executable, __file__, "--child", work, "--points", str(points),
                               "--repeats", str(repeats)], env=env, capture_output=True, text=True)
    if done.returncode:
        raise RuntimeError(f"bench child on {tree} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _commit(tree):
    done = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True)
    return done.stdout.strip() or None


def report(runs, points, repeats):
    cols = [c for c in runs if c != "whole" and isinstance(runs[c], dict)]
    ms = lambda v: f"{1e3 * v:.1f}"  # noqa: E731
    both = lambda v: f"{ms(v['cpu_s'])} ({ms(v['s'])})"  # noqa: E731
    lines = ["# Output stage on the 5 mm door trim (issue 15, P1)", "",
             f"Machine: {platform.platform()}, 2 shared cores, one BLAS thread; load average at the "
             f"end {runs.get('load_average', os.getloadavg()[0]):.1f}. Fastest of {repeats} runs per number, fresh process "
             "per tree. Mesh of cases/door_trim_p1.yaml (5 mm): "
             f"{runs[cols[-1]]['nodes']} nodes, {runs[cols[-1]]['triangles']} triangles, "
             f"{runs[cols[-1]]['radiating_nodes']} radiating; H = {H}; synthetic fields of a "
             f"P1 point's sizes (benchmarks/pipeline/bench_outputs.py). Trees: "
             + ", ".join(f"{c} = {runs[c]['sarfe']} ({runs[c].get('commit')})" for c in cols)
             + ".", "",
             "## Per point [ms CPU (wall)]", "",
             "| step | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    for key, label in (("point_data_s", "ERP point arrays (`erp_point_data`), ordinary point"),
                       ("point_data_loudest_s", "the same at the loudest point (with the nodal "
                        "displacement, 240 samples of (34k, 3))"),
                       ("write_vtu_s", "one `write_erp_vtu` (22 arrays, appended raw + LZ4)")):
        lines.append(f"| {label} | " + " | ".join(both(runs[c][key]) for c in cols) + " |")
    lines.append("| VTU size [MB] | " + " | ".join(f"{runs[c]['vtu_bytes'] / 1e6:.2f}"
                                                   for c in cols) + " |")
    lines += ["", f"## A sweep's ERP map series: {points} maps (`write_erp_sweep`, point arrays "
              "built per map as the pipeline does)", "",
              "| tree | variant | wall s | wall ms per point | CPU s (incl. workers) | CPU ms per "
              "point | MB on disk | peak RSS added GB |", "|---|---|---|---|---|---|---|---|"]
    for c in cols:
        for label, row in runs[c]["series"].items():
            lines.append(f"| {c} | {label} | {row['s']:.2f} | {ms(row['s_per_point'])} | "
                         f"{row['cpu_s']:.2f} | {ms(row['cpu_s'] / points)} | "
                         f"{row['bytes'] / 1e6:.0f} | {row['peak_rss_added_gb']:.2f} |")
    lines += ["", "## Per run [s CPU (wall)]", "", "| file | " + " | ".join(cols) + " |",
              "|---|" + "---|" * len(cols)]
    sec = lambda v: f"{v['cpu_s']:.2f} ({v['s']:.2f})"  # noqa: E731
    lines.append("| animation/deflection.pvd, 24 frames | "
                 + " | ".join(sec(runs[c]["animation_s"]) for c in cols) + " |")
    lines.append(f"| response.h5, {points} points | "
                 + " | ".join(f"{sec(runs[c]['response_h5_s'])}, "
                              f"{runs[c]['response_h5_bytes'] / 1e6:.0f} MB" for c in cols) + " |")
    whole = runs.get("whole")
    if whole:
        trees = [c for c in whole if c not in ("difference", "note")]
        lines += ["", f"## The whole pipeline: {whole[trees[-1]]['points']} points on the P1 "
                  "model (`--whole`)", "",
                  "`solve_case` of cases/door_trim_p1.yaml with listed frequencies 40, 40.1, … Hz, "
                  "30 modes, stability and estimate off, `solver.workers: 2`, every output file. "
                  "`write_outputs`: wall, CPU of the solving process, CPU of its children (map "
                  "workers, render child); peak RSS of the run."
                  + (f" {whole['note']}" if whole.get("note") else ""), "",
                  "| tree | outputs wall s | CPU s (process + children) | CPU ms per point | "
                  "run peak RSS GB | load average |", "|---|---|---|---|---|---|"]
        for c in trees:
            r = whole[c]
            cpu = r["outputs_cpu_s"] + r["outputs_children_cpu_s"]
            lines.append(f"| {c} | {r['outputs_wall_s']:.1f} | {cpu:.1f} "
                         f"({r['outputs_cpu_s']:.1f} + {r['outputs_children_cpu_s']:.1f}) | "
                         f"{1e3 * cpu / r['points']:.0f} | {r['peak_rss_gb']:.2f} | "
                         f"{r['load_average']:.1f} |")
        d = whole.get("difference")
        if d:
            lines += ["", f"Files compared: {d['vtu_files']} VTU, largest relative difference of "
                      f"a point array {d['vtu_worst_relative']:.1e} ({d['vtu_worst_at']}); PVDs "
                      f"identical: {d['pvd_identical']}; response.h5 datasets differing: "
                      f"{d['h5_differing'] or 'none'}; summary.json points identical: "
                      f"{d['summary_points_identical']}."]
    saved = read_results("outputs_records")
    if saved is not None:
        lines += records_report(saved)
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", help="source tree of the 'before' column (e.g. main)")
    parser.add_argument("--before-commit", help="commit of --before when it is no git checkout")
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--whole", action="store_true", help="also the whole pipeline (section 4)")
    parser.add_argument("--records", nargs="+", metavar="CASE",
                        help="the records and files of these cases' solves (section 5) only")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--whole-child", nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--records-child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.records_child:
        records_child(*args.records_child)
        return
    if args.records:
        trees = {"before": pathlib.Path(args.before).resolve()} if args.before else {}
        records = measure_records(args.records, {**trees, "now": ROOT}, args.repeats)
        write_results("outputs_records", {**read_results("outputs_records", {}), **records})
        print("\n".join(records_report(records)))
        runs = read_results("outputs")
        if runs is not None:
            write_results("outputs", markdown=report(runs, runs["now"]["points"],
                                                     runs.get("repeats", 3)))
        return
    if args.child:
        child(args.points, args.repeats, pathlib.Path(args.child))
        return
    if args.whole_child:
        whole_child(*args.whole_child)
        return
    kept = (read_results("outputs") or {}).get("whole")
    runs = {}
    if args.before:
        runs["before"] = measure(pathlib.Path(args.before).resolve(), args.points, args.repeats)
        runs["before"]["commit"] = args.before_commit or _commit(args.before)
    runs["now"] = measure(ROOT, args.points, args.repeats)
    runs["now"]["commit"] = _commit(ROOT)
    if args.whole:
        trees = {"before": pathlib.Path(args.before).resolve()} if args.before else {}
        runs["whole"] = measure_whole({**trees, "now": ROOT}, args.points)
    elif kept:
        runs["whole"] = dict(kept, note="(kept from an earlier run: not rerun this time)")
    runs["load_average"] = os.getloadavg()[0]     # (kept for the report when regenerated)
    write_results("outputs", runs)
    print(write_results("outputs", markdown=report(runs, args.points, args.repeats)).read_text())


if __name__ == "__main__":
    main()
