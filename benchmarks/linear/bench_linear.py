"""Linear side of the door trim: mesh → shell K, M → Craig–Bampton; and the sparse solver choice.

Writes benchmarks/results/linear.md and linear.json. Every case runs in a fresh Python process so
that peak memory (ru_maxrss) belongs to that case alone.

Usage: python benchmarks/linear/bench_linear.py [--quick | --report | --p1]
  --quick: 10 mm only, no solver comparison; --report: rewrite linear.md from linear.json;
  --p1: only the P1 linear stage (issue 15: cases/door_trim_p1.yaml, 5 mm, default cutoff 1.25·H·f_max = 1.5 kHz,
  468 fixed-interface modes by spectrum slicing; 1.8 kHz and 612 before) on one core (taskset) and on two, kept in
  linear.json under "p1" and reported in its own section of linear.md.

Geometry: ``sarfe.mesh.generators.door_trim.generate(mesh_size=...)`` when it exists; otherwise a
stand-in of the same size class — a cylindrically curved 1.0 m × 0.65 m ABS panel (R = 1.2 m,
2.5 mm) on a structured triangle mesh, point-clamped at 12 clips — and the report says so.
Door trim: thickness per part (carrier 2.5, ribs 1.5, bosses 2, pocket 2 mm), ABS-like E = 2.2 GPa,
ν = 0.35, ρ = 1050 kg/m³; all 6 DOFs of the clip nodes fixed; boundary = x, y, z translations of the
contact_* and excite_* nodes (14 nodes, 42 DOFs). Stand-in: 12 contact nodes (36 DOFs).
60 fixed-interface modes + residual vectors (the default block Lanczos), then the same modes by ARPACK.
"""
from __future__ import annotations

import json
import os
import pathlib
import platform
import resource
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, peak_rss_gb, read_results, write_results  # noqa: E402

import numpy as np


THICKNESS, YOUNG, POISSON, DENSITY = 2.5e-3, 2.2e9, 0.35, 1050.0
MODE_COUNT = 60
BOUNDARY_NODES = 12
MESH_SIZES_MM = (10, 5)
SOLVERS = ("pardiso", "cholespy", "superlu")
PART_THICKNESS = {"part_carrier": 2.5e-3, "part_ribs": 1.5e-3, "part_bosses": 2.0e-3, "part_map_pocket": 2.0e-3}


def stand_in_panel(mesh_size):
    """Curved panel (points, triangles, clip nodes, contact nodes) with edge length ≈ mesh_size."""
    length, width, radius = 1.0, 0.65, 1.2
    nx, ny = int(round(length / mesh_size)), int(round(width / mesh_size))
    s, y = np.meshgrid(np.linspace(0, length, nx + 1), np.linspace(0, width, ny + 1), indexing="ij")
    angle = (s - length / 2) / radius
    points = np.column_stack([(radius * np.sin(angle)).ravel(), y.ravel(), (radius * (1 - np.cos(angle))).ravel()])
    index = np.arange(len(points)).reshape(nx + 1, ny + 1)
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])

    def nearest(fractions):
        return index[np.rint(fractions[:, 0] * nx).astype(int), np.rint(fractions[:, 1] * ny).astype(int)]

    clip_fractions = np.array([[0.05, 0.05], [0.5, 0.05], [0.95, 0.05], [0.05, 0.95], [0.5, 0.95], [0.95, 0.95],
                               [0.05, 0.5], [0.95, 0.5], [0.3, 0.05], [0.7, 0.95], [0.3, 0.95], [0.7, 0.05]])
    rng = np.random.default_rng(7)
    contact_fractions = 0.15 + 0.7 * rng.random((BOUNDARY_NODES, 2))
    return points, triangles, nearest(clip_fractions), nearest(contact_fractions), THICKNESS


def door_trim_panel(mesh_size):
    """Door trim from the project generator: (points, triangles, clip nodes, contact nodes)."""
    from sarfe.mesh.generators import door_trim

    mesh = door_trim.generate(mesh_size=mesh_size)
    groups = mesh.node_groups
    clips = np.unique(np.concatenate([np.asarray(v) for k, v in groups.items() if k.startswith(("clip_", "clamp_"))]))
    contact = np.unique(np.concatenate([np.asarray(v) for k, v in groups.items()
                                        if k.startswith(("contact_", "excite_"))]))
    contact = np.setdiff1d(contact, clips)
    if len(contact) > 20:  # ≤ 60 boundary DOFs
        contact = contact[np.linspace(0, len(contact) - 1, 20).astype(int)]
    thickness = np.full(len(mesh.triangles), THICKNESS)
    for name, value in PART_THICKNESS.items():
        if name in mesh.element_groups:
            thickness[np.asarray(mesh.element_groups[name])] = value
    return mesh.points, mesh.triangles, clips, contact, thickness


def run_case(mesh_size_mm, solvers):
    """One mesh size in this process: stage timings, sizes, peak memory; solver comparison."""
    from sarfe.fe import shell_matrices
    from sarfe.reduction import craig_bampton, free_dof_positions, free_dofs_system, node_dofs

    mesh_size = mesh_size_mm / 1000
    out = {"mesh_size_mm": mesh_size_mm}
    clock, cpu0 = time.perf_counter(), time.process_time()
    try:
        points, triangles, clips, contact, thickness = door_trim_panel(mesh_size)
        out["geometry"] = "door_trim generator"
    except ImportError:
        points, triangles, clips, contact, thickness = stand_in_panel(mesh_size)
        out["geometry"] = "stand-in curved panel 1.0 x 0.65 m (door_trim generator not available)"
    out["mesh_s"] = time.perf_counter() - clock
    out["mesh_cpu_s"] = time.process_time() - cpu0
    out["nodes"], out["triangles"] = len(points), len(triangles)

    clock = time.perf_counter()
    stiffness, mass = shell_matrices(points, triangles, thickness, YOUNG, POISSON, DENSITY)
    fixed = node_dofs(clips, range(6))
    k_ff, m_ff, free = free_dofs_system(stiffness, mass, fixed)
    out["assembly_s"] = time.perf_counter() - clock
    out["assembly_cpu_s"] = time.process_time() - cpu0 - out["mesh_cpu_s"]
    out["free_dofs"], out["nnz"] = k_ff.shape[0], int(k_ff.nnz)
    boundary = free_dof_positions(node_dofs(contact, (0, 1, 2)), free, stiffness.shape[0])
    out["boundary_dofs"] = len(boundary)
    del stiffness, mass

    clock, cpu = time.perf_counter(), time.process_time()
    reduced = craig_bampton(k_ff, m_ff, boundary, mode_count=MODE_COUNT, eigensolver="block",
                            residual_vectors=True, free_dofs=free, total_dof_count=6 * len(points))
    out["craig_bampton_s"] = time.perf_counter() - clock
    out["craig_bampton_cpu_s"] = time.process_time() - cpu
    out["linear_total_cpu_s"] = out["mesh_cpu_s"] + out["assembly_cpu_s"] + out["craig_bampton_cpu_s"]
    out["cb_stages_s"] = reduced.timings
    out["solver"] = reduced.solver
    out["modes"] = reduced.mode_count
    out["highest_mode_hz"] = float(reduced.mode_frequencies_hz[-1])
    out["lowest_mode_hz"] = float(reduced.mode_frequencies_hz[0])
    out["operator_applications"] = reduced.timings.get("operator_applications")
    out["linear_total_s"] = out["mesh_s"] + out["assembly_s"] + out["craig_bampton_s"]
    out["peak_rss_gb"] = peak_rss_gb()
    out["residual_vectors"] = reduced.residual_vector_count
    # the same reduction with ARPACK (single-vector shift-invert Lanczos) for comparison
    clock = time.perf_counter()
    arpack = craig_bampton(k_ff, m_ff, boundary, mode_count=MODE_COUNT, eigensolver="arpack")
    out["arpack_craig_bampton_s"] = time.perf_counter() - clock
    out["arpack_normal_modes_s"] = arpack.timings["normal_modes"]
    out["arpack_normal_modes_cpu_s"] = arpack.timings["normal_modes_cpu"]
    out["arpack_operator_columns"] = arpack.timings["operator_applications"]
    out["block_vs_arpack_max_frequency_difference"] = float(
        np.abs(arpack.mode_frequencies_hz / reduced.mode_frequencies_hz - 1).max())
    del arpack
    out["solver_comparison"] = {}
    if solvers:
        interior = reduced.interior_dofs
        import scipy.sparse as sp

        path = f"/tmp/sarfe_bench_kii_{mesh_size_mm}mm_{os.getpid()}.npz"
        sp.save_npz(path, k_ff[interior][:, interior].tocsr(), compressed=False)
        del reduced, k_ff, m_ff
        import gc

        gc.collect()
        for solver in solvers:
            out["solver_comparison"][solver] = _child(["--solver", path, solver])
        os.remove(path)
    return out


P1_CASE = ROOT / "cases" / "door_trim_p1.yaml"


def _tree_memory_gb():
    """(RSS, PSS, PSS of this process alone) summed over this process and its children [GB]
    (/proc smaps_rollup; PSS splits shared pages — K, M after fork, a mapped modes file —
    between the processes that map them)."""
    me = os.getpid()
    pids = [me]
    try:
        pids += [int(p) for p in open(f"/proc/{me}/task/{me}/children").read().split()]
    except OSError:
        pass
    rss = pss = own = 0.0
    for pid in pids:
        try:
            for line in open(f"/proc/{pid}/smaps_rollup"):
                if line.startswith("Rss:"):
                    rss += int(line.split()[1]) / 1e6
                elif line.startswith("Pss:"):
                    pss += int(line.split()[1]) / 1e6
                    own += int(line.split()[1]) / 1e6 if pid == me else 0.0
        except OSError:
            pass
    return rss, pss, own


def _slicing_files_gb():
    """Bytes [GB] in the spectrum-slicing files: found vectors waiting on disk (page cache, not
    process memory; sarfe-modes-* in the temporary directory) and, before, the worker's
    /dev/shm file (memory, though in no process's PSS)."""
    import glob
    import tempfile

    paths = glob.glob(os.path.join(tempfile.gettempdir(), "sarfe-modes-*")) + \
        glob.glob("/dev/shm/sarfe-slices-*")
    total = 0
    for path in paths:
        try:
            total += os.path.getsize(path)
        except OSError:
            pass
    return total / 1e9


def run_p1():
    """The P1 case's linear stage in this process (mesh from the cache): wall, CPU of this
    process and its children, peak memory of the process tree (sampled every 0.1 s), the
    spectrum-slicing record and the frequencies."""
    import threading

    from sarfe.pipeline.model.linear_stage import build_linear_model

    peak = {"rss": 0.0, "pss": 0.0, "pss_self": 0.0, "files": 0.0, "files_max": 0.0}
    stop = threading.Event()

    def watch():
        while not stop.wait(0.1):
            rss, pss, own = _tree_memory_gb()
            files = _slicing_files_gb()
            peak["rss"], peak["files_max"] = max(peak["rss"], rss), max(peak["files_max"], files)
            if pss > peak["pss"]:        # the peak's split between this process and the worker
                peak.update(pss=pss, pss_self=own, files=files)

    threading.Thread(target=watch, daemon=True).start()
    load = os.getloadavg()[0]
    clock, cpu = time.perf_counter(), time.process_time()
    stage = build_linear_model(str(P1_CASE))
    wall, own_cpu = time.perf_counter() - clock, time.process_time() - cpu
    stop.set()
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    timings = stage.reduced.timings
    return {"cores": len(os.sched_getaffinity(0)), "load_average": round(load, 1), "wall_s": wall,
            "cpu_s": own_cpu, "children_cpu_s": children.ru_utime + children.ru_stime,
            "peak_rss_self_gb": peak_rss_gb(), "peak_rss_children_gb": children.ru_maxrss / 1e6,
            "peak_tree_rss_gb": peak["rss"], "peak_tree_pss_gb": peak["pss"],
            "peak_pss_self_gb": peak["pss_self"], "slicing_files_at_peak_gb": peak["files"],
            "slicing_files_max_gb": peak["files_max"],
            "stage_s": stage.timings, "free_dofs": stage.info["free_dofs"],
            "modes": stage.info["modes"], "residual_vectors": stage.info["residual_vectors"],
            "cutoff_hz": stage.info["cutoff_hz"],
            "cb_s": {k: v for k, v in timings.items() if k != "slicing"},
            "slicing": timings.get("slicing"),
            "frequencies_hz": stage.reduced.mode_frequencies_hz.tolist()}


def p1_lines(p1, memory=None):
    """linear.md's section on the P1 linear stage (one core vs two; rows 3+ carry a ``note``) and,
    with ``memory`` (linear.json "p1_memory"), what is alive at the two-process peak."""
    lines = ["", f"## P1 linear stage (issue 15): door trim 5 mm, cutoff {p1[0]['cutoff_hz'] / 1e3:.2f} kHz, one core vs two", "",
             "`sarfe.pipeline.model.linear_stage.build_linear_model(cases/door_trim_p1.yaml)` in a fresh process "
             "(mesh from the cache), pinned to one core with taskset or free on two; MKL/OpenBLAS one "
             "thread per process. CPU = this process + the slicing worker. Peak memory of the process "
             "tree sampled every 0.1 s: RSS summed (counts pages shared by the two processes twice) "
             "and PSS summed (shared pages split), with its split this process / worker at the peak "
             "sample where recorded. Modes: below the split (this process: run 0 and its "
             "chain) / above it (the worker); wait: wall seconds this process idled at the join.", "",
             "| row | cores | load avg | wall [s] | CPU [s] (worker) | Craig–Bampton modes [s] wall (CPU) | shifts (this / worker) "
             "| modes (this / worker) | wait [s] | peak tree RSS [GB] | peak tree PSS [GB] (this / worker) | modes | max rel. frequency difference to row 1 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    reference = np.asarray(p1[0]["frequencies_hz"])
    for index, run in enumerate(p1, start=1):
        slicing = run["slicing"] or {}
        upper = slicing.get("upper") or {}
        frequencies = np.asarray(run["frequencies_hz"])
        difference = np.abs(frequencies / reference - 1).max() if len(frequencies) == len(reference) else float("nan")
        split = slicing.get("split_count")
        share = f"{split} / {run['modes'] - split}" if split is not None else f"{run['modes']} / 0"
        wait = slicing.get("join_wait_s")
        own = run.get("peak_pss_self_gb")
        split_pss = "" if own is None or not upper else \
            f" ({own:.2f} / {run['peak_tree_pss_gb'] - own:.2f})"
        lines.append(
            f"| {index} | {run['cores']} | {run['load_average']} | {run['wall_s']:.1f} | {run['cpu_s'] + run['children_cpu_s']:.1f} "
            f"({run['children_cpu_s']:.1f}) | {run['cb_s']['normal_modes']:.1f} ({run['cb_s']['normal_modes_cpu']:.1f}) "
            f"| {len(slicing.get('shifts', []))} / {len(upper.get('shifts', []))} | {share} "
            f"| {'—' if wait is None else f'{wait:.1f}'} "
            f"| {run['peak_tree_rss_gb']:.2f} | {run['peak_tree_pss_gb']:.2f}{split_pss} | {run['modes']} | {difference:.1e} |")
    one, two = p1[0], p1[1]
    lines += ["", f"Rows 1, 2 (this code): the worker counts N(λ_c) and places the split by count, "
              f"N(λ_s) ≈ (N(λ_c) + lead)/2 with lead = 0.2 per column of run 0's cap (run 0's head start: it "
              f"finds its modes cheaper than the shifted runs), from one or two inertia counts. Wall "
              f"{one['wall_s']:.0f} s on one core → {two['wall_s']:.0f} s on two (load {one['load_average']} / "
              f"{two['load_average']}); CPU of this process {one['cpu_s']:.0f} → {two['cpu_s']:.0f} s, the "
              f"worker's {two['children_cpu_s']:.0f} s beside it; this process idled "
              f"{(two['slicing'] or {}).get('join_wait_s', float('nan')):.1f} s at the join. Peak tree PSS "
              f"{two['peak_tree_pss_gb']:.2f} GB on two processes, {one['peak_tree_pss_gb']:.2f} GB on one "
              f"(budget 4 GB for the whole run); the vectors found so far wait on disk while both slice, "
              f"up to {two.get('slicing_files_max_gb', float('nan')):.2f} GB in the files (page cache, not "
              "process memory). Rows measured on a shared machine: compare CPU seconds and "
              "rows run one after the other. The earlier tables (60 modes, no slicing) are unchanged "
              "code paths and still hold."]
    for index, run in enumerate(p1[2:], start=3):
        lines += ["", f"Row {index}: {run.get('note', 'a rerun')} (load {run['load_average']}): wall "
                  f"{run['wall_s']:.0f} s, CPU {run['cpu_s']:.0f} s here + {run['children_cpu_s']:.0f} s in the "
                  f"worker, peak tree PSS {run['peak_tree_pss_gb']:.2f} GB."]
    if memory:
        lines += ["", "### What is alive at the two-process peak (P1 memory)", "", memory["note"], "",
                  "| " + " | ".join(memory["columns"]) + " |", "|" + "---|" * len(memory["columns"])]
        lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in memory["rows"]]
        lines += [""] + memory.get("after", [])
    return lines


def profile_lines(profile, title="Where the P1 fixed-interface modes' time goes (instrumented, one process)"):
    """linear.md's breakdown of the P1 Craig–Bampton modes by operation: ``profile`` (stored in
    linear.json under "p1_profile" by an instrumented run — wrappers timing each call of the
    named functions, one process, cutoff 1.8 kHz — and under "p1_split_profile" for the two
    processes before and after the split by count) holds {"note", "runs": {label: {item:
    [calls, CPU s, columns]}}}."""
    runs = profile["runs"]
    items = list(dict.fromkeys(k for run in runs.values() for k in run))
    lines = ["", f"### {title}", "",
             profile["note"], "",
             "| item | " + " | ".join(f"{label}: calls, CPU [s]" for label in runs) + " |",
             "|---|" + "---|" * len(runs)]
    for item in items:
        cells = []
        for run in runs.values():
            calls, cpu, columns = run.get(item, (0, 0.0, 0))
            cells.append(f"{calls}, {cpu:.1f}" + (f" ({columns} columns)" if columns else "") if calls else "—")
        lines.append(f"| {item} | " + " | ".join(cells) + " |")
    return lines


def _vm_gb():
    """(current RSS, peak RSS) of this process [GB] from /proc/self/status."""
    fields = dict(line.split(":", 1) for line in open("/proc/self/status") if line.startswith(("VmRSS", "VmHWM")))
    return int(fields["VmRSS"].split()[0]) / 1e6, int(fields["VmHWM"].split()[0]) / 1e6


def run_solver(path, solver):
    """Factorize K_ii from ``path`` with one backend: wall and CPU times, factor memory, residual."""
    import scipy.sparse as sp

    from sarfe.reduction import factorize

    matrix = sp.load_npz(path).tocsr()
    rhs = np.random.default_rng(0).standard_normal((matrix.shape[0], 36))
    rss_before, _ = _vm_gb()
    clock, cpu = time.perf_counter(), time.process_time()
    factor = factorize(matrix, solver=solver)
    factor_s, factor_cpu_s = time.perf_counter() - clock, time.process_time() - cpu
    rss_after, peak = _vm_gb()
    clock, cpu = time.perf_counter(), time.process_time()
    for column in range(5):
        factor.solve(rhs[:, column])
    one_s, one_cpu_s = (time.perf_counter() - clock) / 5, (time.process_time() - cpu) / 5
    clock, cpu = time.perf_counter(), time.process_time()
    block = factor.solve(rhs)
    block_s, block_cpu_s = time.perf_counter() - clock, time.process_time() - cpu
    residual = np.linalg.norm(matrix @ block - rhs) / np.linalg.norm(rhs)
    return {"factor_s": factor_s, "factor_cpu_s": factor_cpu_s, "one_solve_s": one_s, "one_solve_cpu_s": one_cpu_s,
            "block36_solve_s": block_s, "block36_solve_cpu_s": block_cpu_s,
            "per_rhs_in_block_cpu_s": block_cpu_s / rhs.shape[1], "factor_entries": factor.factor_entries,
            "factor_memory_gb": rss_after - rss_before, "peak_rss_gb": peak, "relative_residual": float(residual)}


def _child(arguments, pin=None):
    command = [sys.executable, str(pathlib.Path(__file__).resolve()), *arguments]
    if pin is not None:
        command = ["taskset", "-c", pin, *command]
    done = subprocess.run(command, capture_output=True, text=True, timeout=1800)
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit {done.returncode}"}
    return json.loads(done.stdout.strip().splitlines()[-1])


LICENCES = {
    "pardiso": "pypardiso BSD-3 + Intel MKL (Intel Simplified Software Licence, proprietary, redistributable)",
    "cholespy": "BSD-3 (bundles CHOLMOD: LGPL-2.1+ Cholesky module; reference BLAS/LAPACK)",
    "superlu": "SciPy BSD-3 (SuperLU: BSD-style)",
}
WHEELS = {
    "pardiso": "yes: pypardiso + mkl wheels (~700 MB), x86-64 only",
    "cholespy": "yes: small wheels, Linux/macOS/Windows",
    "superlu": "yes: part of SciPy",
}


def _stored():
    return read_results("linear")


def write_report(cases, quick, p1=None):
    lines = ["# Linear side: door trim mesh → shell K, M → Craig–Bampton", "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores shared with other jobs "
             f"(load average at start {cases[0].get('load_average', '?')}); "
             f"MKL/OpenBLAS threads = {os.environ.get('MKL_NUM_THREADS', 'default')}/"
             f"{os.environ.get('OPENBLAS_NUM_THREADS', 'default')}. "
             f"{cases[0]['boundary_dofs']} boundary DOFs (translations), {MODE_COUNT} fixed-interface modes "
             f"+ {cases[0].get('residual_vectors', 0)} residual modes; first table: the default (block shift-invert "
             "Lanczos, 16-column multi-RHS solves on the one K_ii factor, residual vectors), second: the same "
             "modes by ARPACK (eigsh σ = 0, OPinv = that factor).", "",
             f"Geometry: {cases[0]['geometry']}.", "",
             "| mesh | nodes | free DOFs | nnz(K) | mesh [s] | assembly [s] | factorize K_ii [s] | constraint modes [s] "
             "| fixed-interface modes [s] | K_ii⁻¹ applications | projection [s] | CB total [s] | **linear total [s]** (CPU) "
             "| peak RSS [GB] | modes [Hz] |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        s = c["cb_stages_s"]
        lines.append(
            f"| {c['mesh_size_mm']} mm | {c['nodes']} | {c['free_dofs']} | {c['nnz']} | {c['mesh_s']:.2f} "
            f"| {c['assembly_s']:.2f} | {s['factorization']:.2f} ({c['solver']}) | {s['constraint_modes']:.2f} "
            f"| {s['normal_modes']:.2f} | {c['operator_applications']} | {s['projection'] + s['partition']:.2f} "
            f"| {c['craig_bampton_s']:.2f} | **{c['linear_total_s']:.1f}** ({c['linear_total_cpu_s']:.1f}) | {c['peak_rss_gb']:.2f} "
            f"| {c['lowest_mode_hz']:.1f} … {c['highest_mode_hz']:.1f} |")
    lines += ["", "CPU seconds per stage (one process, single-threaded BLAS/MKL): "
              + "; ".join(f"{c['mesh_size_mm']} mm: mesh {c['mesh_cpu_s']:.1f}, assembly {c['assembly_cpu_s']:.1f}, "
                          f"Craig–Bampton {c['craig_bampton_cpu_s']:.1f} (factorize {c['cb_stages_s']['factorization_cpu']:.1f}, "
                          f"constraint modes {c['cb_stages_s']['constraint_modes_cpu']:.1f}, fixed-interface modes "
                          f"{c['cb_stages_s']['normal_modes_cpu']:.1f}, residual modes "
                          f"{c['cb_stages_s'].get('residual_modes_cpu', 0.0):.1f}, partition + projection "
                          f"{c['cb_stages_s']['partition_cpu'] + c['cb_stages_s']['projection_cpu']:.1f})"
                          for c in cases) + "."]
    lines += ["", "The fixed-interface modes by ARPACK instead (`eigensolver=\"arpack\"`):", "",
              "| mesh | fixed-interface modes [s] block → ARPACK | same, CPU [s] | K_ii⁻¹ columns block → ARPACK "
              "| CB total [s] block → ARPACK | max rel. frequency difference |", "|---|---|---|---|---|---|"]
    for c in cases:
        lines.append(f"| {c['mesh_size_mm']} mm | {c['cb_stages_s']['normal_modes']:.2f} → {c['arpack_normal_modes_s']:.2f} "
                     f"| {c['cb_stages_s']['normal_modes_cpu']:.2f} → {c['arpack_normal_modes_cpu_s']:.2f} "
                     f"| {c['operator_applications']} → {c['arpack_operator_columns']} "
                     f"| {c['craig_bampton_s']:.2f} → {c['arpack_craig_bampton_s']:.2f} "
                     f"| {c['block_vs_arpack_max_frequency_difference']:.1e} |")
    lines += ["", "Goal (issue #3): the whole linear side of the door trim under 30 s on this 2-core machine. "
              + "; ".join(f"{c['mesh_size_mm']} mm: {c['linear_total_cpu_s']:.1f} s CPU "
                          f"({'met' if c['linear_total_cpu_s'] < 30 else 'missed'}), {c['linear_total_s']:.1f} s wall"
                          for c in cases) + ". CPU seconds are what a quiet machine shows single-threaded; "
              "wall seconds include the other jobs' load."]
    if not quick:
        lines += ["", "## Sparse direct solvers on K_ii (SPD), each in a fresh process", "",
                  "Times are wall (CPU) seconds; CPU time is what a quiet machine would show with one thread. "
                  "Factor memory = RSS held after factorization minus before.", "",
                  "| mesh | solver | factorize [s] | one solve [s] | 36-RHS block [s] (CPU per RHS) | factor entries "
                  "| factor memory [GB] | residual | licence | pip wheels |", "|---|---|---|---|---|---|---|---|---|---|"]
        for c in cases:
            for name, r in c["solver_comparison"].items():
                if "error" in r:
                    lines.append(f"| {c['mesh_size_mm']} mm | {name} | failed: {r['error']} | | | | | | | |")
                    continue
                entries = f"{r['factor_entries'] / 1e6:.1f} M" if r["factor_entries"] else "n/a"
                lines.append(
                    f"| {c['mesh_size_mm']} mm | {name} | {r['factor_s']:.2f} ({r['factor_cpu_s']:.2f}) "
                    f"| {r['one_solve_s']:.3f} ({r['one_solve_cpu_s']:.3f}) "
                    f"| {r['block36_solve_s']:.2f} ({r['per_rhs_in_block_cpu_s']:.4f}) | {entries} "
                    f"| {r['factor_memory_gb']:.2f} | {r['relative_residual']:.1e} | {LICENCES[name]} | {WHEELS[name]} |")
    lines += ["", "## What dominates", ""]
    for c in cases:
        stages = {"mesh (gmsh)": c["mesh_cpu_s"], "assembly": c["assembly_cpu_s"],
                  **{f"CB {k[:-4].replace('_', ' ').replace('normal modes', 'fixed-interface modes (Lanczos)')}": v for k, v in c["cb_stages_s"].items() if k.endswith("_cpu")}}
        top = max(stages, key=stages.get)
        total = sum(stages.values())
        lines.append(f"- {c['mesh_size_mm']} mm: {top} takes {stages[top]:.1f} of {total:.1f} CPU s "
                     f"({100 * stages[top] / total:.0f} %); wall time under the shared load was "
                     f"{c['linear_total_s'] / max(c['linear_total_cpu_s'], 1e-9):.1f}× the CPU time.")
    previous = _stored()
    profile = previous.get("p1_profile") if isinstance(previous, dict) else None
    split_profile = previous.get("p1_split_profile") if isinstance(previous, dict) else None
    memory = previous.get("p1_memory") if isinstance(previous, dict) else None
    # measured by hand (A/B runs, cProfile; linear.json "p1_lanczos": the section's lines)
    lanczos = previous.get("p1_lanczos") if isinstance(previous, dict) else None
    # the same for the idle cores, run 0 and block size (branch lanczos2): "p1_lanczos2"
    lanczos2 = previous.get("p1_lanczos2") if isinstance(previous, dict) else None
    if p1 is None and isinstance(previous, dict):
        p1 = previous.get("p1")
    if p1:
        lines += p1_lines(p1, memory)
    if split_profile:
        lines += profile_lines(split_profile, "The two-process split, per process (instrumented, "
                                              "before and after the split by count)")
    if profile:
        lines += profile_lines(profile)
    if lanczos:
        lines += [""] + list(lanczos)
    if lanczos2:
        lines += [""] + list(lanczos2)
    write_results("linear", markdown=lines)
    data = {"cases": cases, "p1": p1, "p1_profile": profile, "p1_split_profile": split_profile,
            "p1_memory": memory, "p1_lanczos": lanczos,
            "p1_lanczos2": lanczos2} if p1 or profile or split_profile else cases
    write_results("linear", data)
    print("\n".join(lines))


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "--case":
        print(json.dumps(run_case(int(sys.argv[2]), [s for s in sys.argv[3].split(",") if s]), default=float))
        return
    if len(sys.argv) >= 2 and sys.argv[1] == "--solver":
        print(json.dumps(run_solver(sys.argv[2], sys.argv[3]), default=float))
        return
    if len(sys.argv) >= 2 and sys.argv[1] == "--p1-case":
        print(json.dumps(run_p1(), default=float))
        return
    if len(sys.argv) >= 2 and sys.argv[1] in ("--report", "--p1"):  # (re)write linear.md
        stored = _stored()
        cases = stored["cases"] if isinstance(stored, dict) else stored
        p1 = None
        if sys.argv[1] == "--p1":       # one core (taskset), then two
            p1 = [_child(["--p1-case"], pin="0"), _child(["--p1-case"])]
            if any("error" in run for run in p1):
                sys.exit(f"P1 linear stage failed: {[run.get('error') for run in p1]}")
            earlier = stored.get("p1") if isinstance(stored, dict) else None
            for run in earlier or []:      # kept below the new rows, each with its note
                if not run.get("note"):
                    run["note"] = (f"the previous --p1 run ({run['cores']} "
                                   f"core{'s' if run['cores'] > 1 else ''})")
            p1 += earlier or []
        write_report(cases, quick=not cases[0].get("solver_comparison"), p1=p1)
        return
    quick = "--quick" in sys.argv
    from sarfe.reduction import available_solvers

    solvers = "" if quick else ",".join(s for s in SOLVERS if s in available_solvers())
    cases = []
    for size in MESH_SIZES_MM[:1] if quick else MESH_SIZES_MM:
        load = os.getloadavg()[0]
        result = _child(["--case", str(size), solvers])
        if "error" in result:
            sys.exit(f"{size} mm case failed: {result['error']}")
        result["load_average"] = round(load, 1)
        cases.append(result)
        print(f"{size} mm: linear total {result['linear_total_s']:.1f} s", flush=True)
    write_report(cases, quick)


if __name__ == "__main__":
    main()
