"""Issue 29: the radiated level over a mesh ladder, before and after the contact kinematics from
the geometry (partner-surface normals, points by shape functions, forces on the faces ±t/2).

Two ladders, as a user would run them (``sarfe solve`` of the shipped case with only
``model.fe.generator.mesh_size_m`` and the frequency changed, everything else the case's own):

- squeak rig (cases/squeak_rig.yaml) at 50 Hz, mesh 12 → 4 mm (reference: 2 mm);
- door trim (cases/door_trim.yaml) at 67 Hz, mesh 14 → 5 mm (reference: 3.5 mm).

Each row: dB(A) at the frequency, the run's own ± (error_estimate.erp_db: harmonics, aliasing,
modes — no mesh term yet, issue 29 item 4), nodes, CPU s. "before" runs a second sarfe tree (the
main branch, SARFE_BEFORE_TREE, default /work/main) on the same case files; "after" this tree.

Usage (each solve one child process, one BLAS thread):
  python benchmarks/accuracy/bench_mesh_convergence.py [after|before|both] [squeak_rig|door_trim ...]
        → benchmarks/results/mesh_convergence.{json,md} (rows already measured are kept; a run of
          one tree or one ladder adds its rows)
Environment: SARFE_BEFORE_TREE, SARFE_MESHCONV_STORE (scratch folder, default /tmp/meshconv).
"""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import (CASES, ROOT, child_env, machine_line, read_case, read_results,  # noqa: E402
                      run_timed, write_case, write_results)

BEFORE_TREE = pathlib.Path(os.environ.get("SARFE_BEFORE_TREE", "/work/main"))
STORE = pathlib.Path(os.environ.get("SARFE_MESHCONV_STORE", "/tmp/meshconv"))
NAME = "mesh_convergence"

#: case → (frequency [Hz], ladder mesh sizes [m], reference mesh size [m])
LADDERS = {
    "squeak_rig": (50.0, (0.012, 0.010, 0.009, 0.008, 0.007, 0.006, 0.005, 0.004), 0.002),
    "door_trim": (67.0, (0.014, 0.010, 0.007, 0.005), 0.0035),
}


def variant(case: str, frequency_hz: float, mesh_m: float) -> dict:
    """The shipped case with only the mesh size and the frequency changed."""
    data = read_case(CASES / f"{case}.yaml")
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [frequency_hz]
    return data


def solve(tree: pathlib.Path, case: str, frequency_hz: float, mesh_m: float) -> dict:
    """One ``sarfe solve`` of the variant with ``tree`` on PYTHONPATH → its row."""
    STORE.mkdir(parents=True, exist_ok=True)
    path = write_case(variant(case, frequency_hz, mesh_m), CASES / f"{case}.yaml", STORE)
    out = STORE / f"{tree.name}-{case}-{mesh_m * 1e3:g}mm"
    try:
        wall, cpu, _ = run_timed([sys.executable, "-m", "sarfe", "solve", str(path), "--output",
                                  str(out), "--force", "--quiet"], env=child_env(tree),
                                 cwd=tree)   # (python -m puts the cwd first on sys.path)
    finally:
        path.unlink()
    summary = json.loads((out / "summary.json").read_text())
    point = summary["points"][0]
    return {"case": case, "tree": str(tree), "mesh_m": mesh_m, "frequency_hz": frequency_hz,
            "level_dba": point["erp"]["level_dba"],
            "pm_db": (point.get("error_estimate") or {}).get("erp_db"),
            "converged": point["converged"], "nodes": summary["model"].get("nodes"),
            "warnings": summary.get("warnings", []), "wall_s": wall, "cpu_s": cpu}


def commit(tree: pathlib.Path) -> str:
    done = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True)
    return done.stdout.strip()


def markdown(rows: list) -> list:
    lines = ["# Mesh convergence of the radiated level (issue 29)", "",
             "`python benchmarks/accuracy/bench_mesh_convergence.py both` — " + machine_line(), "",
             "dB(A) at one frequency per mesh size, ± the run's own estimate (harmonics, aliasing,",
             "modes; no mesh term yet). before = main (node pairs, one node's mesh normal,",
             "forces at the mid-surface), after = contacts from the geometry.", ""]
    for case, (frequency_hz, ladder, reference) in LADDERS.items():
        lines += [f"## {case} at {frequency_hz:g} Hz", "",
                  "| mesh [mm] | before dB(A) | ± | after dB(A) | ± | after − reference |",
                  "|---|---|---|---|---|---|"]
        found = {(r["tree_label"], r["mesh_m"]): r for r in rows if r["case"] == case}
        ref = found.get(("after", reference))
        for mesh_m in (*ladder, reference):
            cells = [f"{mesh_m * 1e3:g}" + (" (ref)" if mesh_m == reference else "")]
            for label in ("before", "after"):
                r = found.get((label, mesh_m))
                cells += ([f"{r['level_dba']:.2f}", f"{r['pm_db'] or 0:.2f}"] if r else ["–", "–"])
            r = found.get(("after", mesh_m))
            cells.append(f"{r['level_dba'] - ref['level_dba']:+.2f}" if r and ref else "–")
            lines.append("| " + " | ".join(cells) + " |")
        for label in ("before", "after"):
            levels = [found[(label, m)]["level_dba"] for m in ladder if (label, m) in found]
            if len(levels) > 1:
                jumps = [abs(b - a) for a, b in zip(levels, levels[1:])]
                lines.append(f"\n{label}: largest step between neighbouring meshes "
                             f"{max(jumps):.2f} dB, spread {max(levels) - min(levels):.2f} dB")
        lines.append("")
    return lines


def main(argv) -> None:
    which = argv[0] if argv else "both"
    cases = argv[1:] or list(LADDERS)
    trees = {"before": BEFORE_TREE, "after": ROOT}
    labels = ["before", "after"] if which == "both" else [which]
    for case in cases:
        frequency_hz, ladder, reference = LADDERS[case]
        for label in labels:
            meshes = ladder + ((reference,) if label == "after" else ())
            for mesh_m in meshes:
                row = solve(trees[label], case, frequency_hz, mesh_m)
                row.update(tree_label=label, commit=commit(trees[label]))
                rows = read_results(NAME, default={"rows": []})["rows"]   # (another run's rows)
                rows = [r for r in rows if (r["case"], r["tree_label"], r["mesh_m"]) !=
                           (case, label, mesh_m)] + [row]
                print(f"{case} {label} {mesh_m * 1e3:g} mm: {row['level_dba']:.2f} "
                      f"± {row['pm_db'] or 0:.2f} dB(A) ({row['cpu_s']:.0f} s CPU)", flush=True)
                write_results(NAME, {"rows": rows}, markdown(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
