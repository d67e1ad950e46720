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
3. per run: the 24-frame deflection animation and response.h5 of ``--points`` points.

Each number is the fastest of ``--repeats`` runs (the machine is shared). Files go to a
temporary directory (≈ 1.1 GB for 200 maps) removed afterwards.

Run: python benchmarks/bench_outputs.py [--before TREE [--before-commit C]] [--points 200]
     [--repeats 3]
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

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
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


def _cpu_s():
    """User + system CPU seconds of this process and its finished children (the map's workers)."""
    own, children = (resource.getrusage(who) for who in (resource.RUSAGE_SELF,
                                                         resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _peak_rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def child(points, repeats, workdir):
    """The measurements in this process (sarfe imported from PYTHONPATH); prints one JSON line."""
    import inspect
    from types import SimpleNamespace

    import numpy as np

    import sarfe
    from sarfe.erp import equivalent_radiated_power, nodal_areas
    from sarfe.io import outputs
    from sarfe.io.outputs.vtk import contact_point_values
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
    erps = [equivalent_radiated_power(shapes[j % 4], omegas[j], areas) for j in range(4)]
    translations = rng.standard_normal((2 * H + 1, n, 3)) * 1e-5
    markers = np.zeros(n, np.int32)
    pair_a = rng.choice(n, PAIRS, replace=False)
    pair_b = rng.choice(n, PAIRS, replace=False)
    loudest = points // 2

    def point_data(j, displacement=None):
        force = contact_point_values(n, pair_a, pair_b, rng.random(PAIRS))
        motion = contact_point_values(n, pair_a, pair_b, rng.random(PAIRS) * 1e-4)
        return outputs.erp_point_data(n, erps[j % 4], shapes[j % 4], omegas[j],
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
        rss_before = _peak_rss_gb()

        def run():
            if takes_function:
                outputs.write_erp_sweep(workdir / "erp", mesh.points, mesh.triangles, series_data,
                                        frequencies, workers=workers)
            else:   # the old writer: the pipeline passed a generator, the writer listed it
                outputs.write_erp_sweep(workdir / "erp", mesh.points, mesh.triangles,
                                        (series_data(j) for j in range(points)), frequencies)
        walls, cpus = [], []
        for _ in range(repeats):
            cpu, clock = _cpu_s(), time.perf_counter()
            run()
            walls.append(time.perf_counter() - clock)
            cpus.append(_cpu_s() - cpu)
        size = sum(f.stat().st_size for f in (workdir / "erp").glob("*.vtu"))
        result["series"][label] = {"s": min(walls), "s_per_point": min(walls) / points,
                                   "cpu_s": min(cpus), "bytes": size,
                                   "peak_rss_added_gb": _peak_rss_gb() - rss_before}

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


def measure(tree, points, repeats):
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MPLBACKEND="Agg")
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
    cols = list(runs)
    ms = lambda v: f"{1e3 * v:.1f}"  # noqa: E731
    both = lambda v: f"{ms(v['cpu_s'])} ({ms(v['s'])})"  # noqa: E731
    lines = ["# Output stage on the 5 mm door trim (issue 15, P1)", "",
             f"Machine: {platform.platform()}, 2 shared cores, one BLAS thread; load average at the "
             f"end {os.getloadavg()[0]:.1f}. Fastest of {repeats} runs per number, fresh process "
             "per tree. Mesh of cases/door_trim_p1.yaml (5 mm): "
             f"{runs[cols[-1]]['nodes']} nodes, {runs[cols[-1]]['triangles']} triangles, "
             f"{runs[cols[-1]]['radiating_nodes']} radiating; H = {H}; synthetic fields of a "
             f"P1 point's sizes (benchmarks/bench_outputs.py). Trees: "
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
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", help="source tree of the 'before' column (e.g. main)")
    parser.add_argument("--before-commit", help="commit of --before when it is no git checkout")
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.points, args.repeats, pathlib.Path(args.child))
        return
    runs = {}
    if args.before:
        runs["before"] = measure(pathlib.Path(args.before).resolve(), args.points, args.repeats)
        runs["before"]["commit"] = args.before_commit or _commit(args.before)
    runs["now"] = measure(ROOT, args.points, args.repeats)
    runs["now"]["commit"] = _commit(ROOT)
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    (out / "outputs.json").write_text(json.dumps(runs, indent=1) + "\n")
    (out / "outputs.md").write_text(report(runs, args.points, args.repeats))
    print((out / "outputs.md").read_text())


if __name__ == "__main__":
    main()
