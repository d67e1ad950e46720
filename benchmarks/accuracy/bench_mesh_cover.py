"""Issue 29: does every mesh of the two ladders lie within its OWN reported ± of the converged
reference? The ± includes the mesh term (sarfe.pipeline.solve.mesh_error: the loudest point
re-solved on coarser generated meshes, Richardson). The ladders are those of
bench_mesh_convergence.py, run as a user would (``sarfe solve`` of the shipped case with only
``model.fe.generator.mesh_size_m`` and the frequency changed, everything else the case's own
defaults, the mesh term on):

- squeak rig at 50 Hz, 12 → 4 mm; door trim at 67 Hz, 14 → 5 mm;
- reference: tests/cases/data/mesh_convergence_reference.json (fine mesh, how it was made beside it).

Per mesh: level dB(A), the whole ± (``error_estimate.erp_db``), its mesh term (``mesh_db``), the
other terms (harmonics, aliasing, modes: ± − mesh term), |level − reference|, covered (yes/no), the
coarser meshes' levels and the mesh term's seconds (``timings_s.mesh_error_s``) against the run's.

Usage (each solve one child process, one BLAS thread; run it under ``nice -n 10``):
  python benchmarks/accuracy/bench_mesh_cover.py [squeak_rig|door_trim ...] [--mesh MM ...]
        → benchmarks/results/mesh_cover.{json,md} (rows already measured are kept; rows of an
          earlier estimate, ``label`` ≠ LABEL, are shown in a table of their own)
Environment: SARFE_MESHCOVER_STORE (scratch folder, default /tmp/meshcover).
"""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))       # bench_mesh_convergence
from benchlib import CASES, ROOT, child_env, machine_line, read_results, run_timed  # noqa: E402
from benchlib import write_case, write_results  # noqa: E402
from bench_mesh_convergence import variant  # noqa: E402

STORE = pathlib.Path(os.environ.get("SARFE_MESHCOVER_STORE", "/tmp/meshcover"))
NAME = "mesh_cover"
LABEL = "three meshes (GCI)"     # the estimate measured by this tree (rows of others are kept)
REFERENCE = json.loads((ROOT / "tests" / "cases" / "data" / "mesh_convergence_reference.json")
                       .read_text())
#: case → (frequency [Hz], ladder mesh sizes [m]) — the ladders of the slow test
#: tests/cases/test_mesh_convergence.py
LADDERS = {
    "squeak_rig": (50.0, (0.012, 0.010, 0.009, 0.008, 0.007, 0.006, 0.005, 0.004)),
    "door_trim": (67.0, (0.014, 0.010, 0.007, 0.005)),
}


def solve(case: str, frequency_hz: float, mesh_m: float) -> dict:
    """One ``sarfe solve`` of the variant (mesh term on, the case's defaults) → its row."""
    STORE.mkdir(parents=True, exist_ok=True)
    path = write_case(variant(case, frequency_hz, mesh_m), CASES / f"{case}.yaml", STORE)
    out = STORE / f"{case}-{mesh_m * 1e3:g}mm"
    try:
        wall, cpu, _ = run_timed([sys.executable, "-m", "sarfe", "solve", str(path), "--output",
                                  str(out), "--force", "--quiet"], env=child_env(ROOT), cwd=ROOT)
    finally:
        path.unlink()
    summary = json.loads((out / "summary.json").read_text())
    point, term = summary["points"][0], summary.get("mesh_error") or {}
    e = point.get("error_estimate") or {}
    ref = REFERENCE[case]["level_dba"]
    level, pm = point["erp"]["level_dba"], abs(float(e.get("erp_db", float("nan"))))
    mesh_db = e.get("mesh_db")
    return {"label": LABEL, "case": case, "mesh_m": mesh_m, "frequency_hz": frequency_hz, "level_dba": level,
            "pm_db": pm, "mesh_db": mesh_db,
            "other_db": pm - mesh_db if mesh_db is not None else pm,
            "parts_db": {k: e.get(k) for k in ("harmonics_db", "aliasing_db", "modal_db")},
            "reference_dba": ref, "error_db": abs(level - ref), "covered": abs(level - ref) <= pm,
            "mesh_error": {k: v for k, v in term.items() if k != "line"}, "line": term.get("line"),
            "converged": point["converged"], "nodes": summary["model"].get("nodes"),
            "mesh_error_s": float(summary["timings_s"].get("mesh_error_s", 0.0)),
            "total_s": float(summary["timings_s"]["total_s"]), "wall_s": wall, "cpu_s": cpu,
            "machine": machine_line(), "commit": subprocess.run(
                ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                text=True).stdout.strip()}


def markdown(rows: list) -> list:
    labels = [LABEL] + sorted({r.get("label") for r in rows} - {LABEL})
    lines = HEAD[:]
    for label in labels:
        lines += [f"# Estimate: {label}", ""] + tables([r for r in rows if r.get("label") == label])
    return lines


HEAD = ["# Every mesh within its own ± of the converged reference (issue 29)", "",
        "`nice -n 10 python benchmarks/accuracy/bench_mesh_cover.py` — the shipped case with "
        "only the mesh size and the frequency changed, the mesh term on (defaults). "
        "± = the run's whole `error_estimate.erp_db`; mesh = its mesh term; other = harmonics "
        "+ aliasing + modes; error = |level − reference| (tests/cases/data/"
        "mesh_convergence_reference.json). Load average per row (2 cores shared).", "",
        "Findings (2026-11-28): with the two-mesh estimate (h, 2h, p = 1 stated) the squeak rig at "
        "10 mm was not covered (± 0.57 against 0.79: its 20 mm level happened to agree with 10 mm's, "
        "30.15 / 30.13, while the ladder oscillates by ±0.15–0.3 dB from mesh to mesh). With three "
        "meshes (h, √2h, 2h; Roache's GCI, Fs = 1.25 with the observed p in [1, 2], else 1.25 × "
        "the levels' range, 3 × it where they oscillate; sarfe.accuracy.mesh_refinement) every "
        "mesh of both ladders is covered. Of 12 meshes, 2 converge monotonically with p in [1, 2] "
        "(squeak 6 mm p = 1.77, door 5 mm p = 1.63), 4 oscillate (squeak 10 / 9 / 8 / 7 mm), 6 "
        "have p outside [1, 2] (door 14 / 10 / 7 mm, squeak 12 / 5 / 4 mm: not in the asymptotic "
        "range); the estimate over-reports there, by up to 5× (squeak 8 mm: mesh term 2.35 "
        "against an error of 0.69). At squeak 6 and 4 mm the mesh term alone (0.49, 0.36) is "
        "just below the error (0.54, 0.40; about 0.19 dB of it is H = 32 against the "
        "reference's H = 48, the harmonics term's share): the whole ± (0.72, 0.83) covers. Cost: the "
        "middle mesh has about twice the 2h mesh's DOFs, so the term costs ≈ 3× before; the "
        "door trim's 5 mm run went from 66 to 90 CPU s, the shipped door_trim from 18.2 to 21.3 "
        "CPU s and the squeak rig from 7.3 to 8.3 (benchmarks/results/mesh_error.md).", ""]


def tables(rows: list) -> list:
    lines = []
    for case, (frequency_hz, ladder) in LADDERS.items():
        ref = REFERENCE[case]
        lines += [f"### {case} at {frequency_hz:g} Hz (reference {ref['level_dba']:.2f} dB(A) at "
                  f"{ref['mesh_m'] * 1e3:g} mm)", "",
                  "| mesh [mm] | dB(A) | ± [dB] | mesh term | other | error | covered | coarser "
                  "meshes dB(A) | convergence, p | mesh s | run s | CPU s | load | commit |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        found = {r["mesh_m"]: r for r in rows if r["case"] == case}
        for mesh_m in ladder:
            r = found.get(mesh_m)
            if r is None:
                lines.append(f"| {mesh_m * 1e3:g} | – | | | | | not measured | | | | | | | |")
                continue
            t = r["mesh_error"]
            coarse = " / ".join(f"{1e3 * m:g} mm {v:.2f}" for m, v in zip(
                t.get("coarse_mesh_sizes_m", [t.get("coarse_mesh_size_m")]),
                t.get("coarse_levels_dba", [t.get("coarse_level_dba")])) if m and v is not None)
            load = r["machine"].split("load average ")[1].split(";")[0]
            mesh = f"{r['mesh_db']:.2f}" if r["mesh_db"] is not None else "not estimated"
            lines.append(f"| {mesh_m * 1e3:g} | {r['level_dba']:.2f} | {r['pm_db']:.2f} | {mesh} "
                         f"| {r['other_db']:.2f} | {r['error_db']:.2f} | "
                         f"{'yes' if r['covered'] else '**no**'} | {coarse} | "
                         f"{t.get('convergence') or t.get('method') or 'stated'} "
                         f"{t.get('order') if t.get('order') is not None else float('nan'):.2f} "
                         f"| {r['mesh_error_s']:.1f} | "
                         f"{r['total_s']:.1f} | {r['cpu_s']:.0f} | {load} | {r['commit']} |")
        lines += [""] + [f"- {m * 1e3:g} mm: {found[m]['line']}" for m in ladder if m in found] + [""]
    return lines


def main(argv) -> None:
    meshes = [float(a) * 1e-3 for a in argv[argv.index("--mesh") + 1:]] if "--mesh" in argv else None
    cases = [a for a in (argv[:argv.index("--mesh")] if meshes else argv)] or list(LADDERS)
    for case in cases:
        frequency_hz, ladder = LADDERS[case]
        for mesh_m in ladder:
            if meshes and not any(abs(mesh_m - m) < 1e-9 for m in meshes):
                continue
            row = solve(case, frequency_hz, mesh_m)
            rows = [r for r in read_results(NAME, default={"rows": []})["rows"]
                    if (r.get("label"), r["case"], r["mesh_m"]) != (LABEL, case, mesh_m)] + [row]
            print(f"{case} {mesh_m * 1e3:g} mm: {row['level_dba']:.2f} ± {row['pm_db']:.2f} "
                  f"(mesh {row['mesh_db']}) error {row['error_db']:.2f} covered {row['covered']} "
                  f"({row['cpu_s']:.0f} s CPU, mesh {row['mesh_error_s']:.1f} s)", flush=True)
            write_results(NAME, {"rows": rows}, markdown(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
