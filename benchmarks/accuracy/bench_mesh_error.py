"""Issue 29 item 4, the mesh term of the ±: every shipped case solved as a user would
(``sarfe solve CASE.yaml``, whole process, defaults) and, from its summary.json: the mesh term
(``mesh_error``: the loudest point re-solved on a 2× coarser generated mesh, Richardson with the
stated p, sarfe.pipeline.solve.mesh_error), its cost (``timings_s.mesh_error_s`` against the rest of
the run: the % it adds), the headline ± with and without it, and whether the run meets its own
budget (``accuracy_check.met``, the mesh term included). tests/cases/test_case_grades.py reads the
result: a shipped case not stating why it is screening grade must be listed here as meeting it.

Usage: python benchmarks/accuracy/bench_mesh_error.py [case ...] (default: every cases/*.yaml;
cases not named keep their earlier entry). Writes benchmarks/results/mesh_error.json and .md.
"""
import json
import pathlib
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import CASES, ROOT, machine_line, read_results, run_timed, write_results  # noqa: E402


def measure(name: str) -> dict:
    with tempfile.TemporaryDirectory(prefix="bench-mesh-") as tmp:
        out = pathlib.Path(tmp) / name
        wall, cpu, _ = run_timed([sys.executable, "-m", "sarfe", "solve", str(CASES / f"{name}.yaml"),
                                  "--output", str(out), "--force", "--quiet"], cwd=ROOT)
        s = json.loads((out / "summary.json").read_text())
    mesh, check, worst = s.get("mesh_error") or {}, s.get("accuracy_check") or {}, s.get("worst") or {}
    t = s["timings_s"]
    mesh_s = float(t.get("mesh_error_s", 0.0))
    total = float(t["total_s"])
    mesh_db = mesh.get("mesh_db") if mesh.get("estimated") else None
    bound = worst.get("erp_error_db")
    return {"case": name, "wall_s": wall, "cpu_s": cpu, "total_s": total, "mesh_error_s": mesh_s,
            "cost_percent": 100.0 * mesh_s / max(total - mesh_s, 1e-9),
            "mesh_estimated": bool(mesh.get("estimated")), "mesh_db": mesh_db,
            "mesh_reason": mesh.get("reason"), "mesh_line": mesh.get("line"),
            "headline_dba": worst.get("erp_level_dba"), "headline_pm_db": bound,
            "headline_pm_without_mesh_db": None if bound is None or mesh_db is None
            else bound - mesh_db,
            "budget": check.get("target"), "met": check.get("met"), "warning": check.get("warning"),
            "exit_code": s["exit_code"],
            "commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                     capture_output=True, text=True).stdout.strip()}


def main(names):
    data = read_results("mesh_error", default={}) or {}
    rows = data.setdefault("cases", {})
    for name in names:
        rows[name] = measure(name)
        print(json.dumps(rows[name]), flush=True)
    data["machine"] = machine_line()
    num = (lambda v, f: "-" if v is None else format(v, f))  # noqa: E731
    lines = ["# The mesh term of the ± on the shipped cases (issue 29 item 4)", "",
             f"{data['machine']}. `sarfe solve cases/CASE.yaml` at the defaults, whole process "
             "(benchmarks/accuracy/bench_mesh_error.py).", "",
             "| case | headline dB(A) | ± [dB] | of which mesh [dB] | ± without mesh | budget | met "
             "| mesh s | run s | cost % | commit |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, r in sorted(rows.items()):
        lines.append(f"| {name} | {num(r['headline_dba'], '.1f')} | {num(r['headline_pm_db'], '.2f')} "
                     f"| {num(r['mesh_db'], '.2f') if r['mesh_estimated'] else 'not estimated'} "
                     f"| {num(r['headline_pm_without_mesh_db'], '.2f')} | {r['budget']} | {r['met']} "
                     f"| {r['mesh_error_s']:.2f} | {r['total_s']:.1f} | {r['cost_percent']:.1f} "
                     f"| {r['commit']} |")
    lines += ["", "Mesh lines (as printed):", ""] + [
        f"- {name}: {r['mesh_line']}" for name, r in sorted(rows.items())]
    write_results("mesh_error", data, lines)


if __name__ == "__main__":
    main(sys.argv[1:] or sorted(p.stem for p in CASES.glob("*.yaml")))
