"""Hill stability per point: full Hill eigen-solve vs the contact-row condensed roots
→ benchmarks/results/stability.md and stability.json.

Door trim (cases/door_trim.yaml) at a 10 mm mesh, H = 5, N = 64, points at 40/52/67/80/95 Hz solved
without stability; then per point (a) the frozen full Hill problem as main had it (ARPACK
shift-invert for the exponents nearest 0 of the 2(2H+1)n-order matrix) and (b) the condensed
method (:mod:`sarfe.hbm.stability_condensed`: Hill on a bounded Ritz basis). Verdicts and leading exponents side by side. Also the squeak rig (H = 3, N = 128):
full (with the friction-memory refinement) vs condensed.

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_stability.py [--skip-full]
"""
import json
import os
import pathlib
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from sarfe.hbm.residual import Problem, full_residual  # noqa: E402
from sarfe.hbm.solve import contact_damping  # noqa: E402
from sarfe.hbm.stability import hill_stability  # noqa: E402
from sarfe.hbm.stability_condensed import condensed_stability  # noqa: E402
from sarfe.hbm.stability_contacts import ContactOperator  # noqa: E402
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model  # noqa: E402
from sarfe.pipeline.points import solve_point, solver_options  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent


def case_at(path, mesh=None, harmonics=None, samples=None):
    data = yaml.safe_load(open(ROOT / path))
    if mesh:
        data["model"]["fe"]["generator"]["mesh_size_m"] = mesh
    if harmonics:
        data["solver"]["harmonics"] = harmonics
    if samples:
        data["solver"]["samples_per_period"] = samples
    data["solver"]["stability"] = False
    tmp = tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False, dir=ROOT / path.parent)
    yaml.safe_dump(data, tmp)
    tmp.close()
    try:
        return load_case(tmp.name)
    finally:
        os.unlink(tmp.name)


def compare(label, path, frequencies, full=True, **settings):
    case = case_at(pathlib.Path(path), **settings)
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    H, N = case.data["solver"]["harmonics"], case.data["solver"]["samples_per_period"]
    options, _ = solver_options(case)
    rows = []
    for f in frequencies:
        s = solve_point(nl, 2 * np.pi * f, H, N, options, None)
        if not s.converged:
            continue
        problem = Problem(nl.model, nl.contacts, nl.excitation, H, N)
        ev = full_residual(problem, s.displacement.ravel(), s.omega)
        op = ContactOperator(problem, s.displacement, s.omega, ev.forces)
        row = {"frequency_hz": f, "hill_order": 2 * (2 * H + 1) * nl.model.dof_count}
        t = time.perf_counter()
        r = hill_stability(nl.model, s.omega, H, ev.jacobian,
                           contact_damping=contact_damping(problem, ev.forces))
        row.update(main_s=time.perf_counter() - t, main_stable=r.stable, main_leading=r.leading)
        if full:
            t = time.perf_counter()
            r = hill_stability(nl.model, s.omega, H, ev.jacobian,
                               contact_damping=contact_damping(problem, ev.forces), operator=op)
            row.update(full_s=time.perf_counter() - t, full_stable=r.stable, full_leading=r.leading)
        t = time.perf_counter()
        r = condensed_stability(nl.model, nl.contacts, s.omega, H, ev.forces, op)
        row.update(condensed_s=time.perf_counter() - t, condensed_stable=r.stable,
                   condensed_leading=r.leading, condensed_note=r.note)
        rows.append(row)
        print(label, row, flush=True)
    return {"case": label, "reduced_dofs": nl.model.dof_count, "contact_rows": nl.contacts.row_count,
            "H": H, "N": N, "points": rows}


def main():
    skip_full = "--skip-full" in sys.argv
    results = [compare("squeak_rig", "cases/squeak_rig.yaml", [50.0, 100.0, 150.0]),
               compare("door_trim 10 mm H=5", "cases/door_trim.yaml", [40.0, 52.0, 67.0, 80.0, 95.0],
                       full=not skip_full, mesh=0.01, harmonics=5)]
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "stability.json").write_text(json.dumps(results, indent=1, default=str))
    lines = ["# Hill stability per point: full vs condensed (contact rows)", "",
             "Main (frozen): the Hill eigenproblem on all reduced DOFs with the Newton Jacobian as main had it. "
             "Full: the Hill eigenproblem on all reduced DOFs (dense or ARPACK shift-invert as on main, "
             "plus the friction-memory refinement of the leading exponents). "
             "Condensed: the same Hill problem on a Ritz basis of the averaged linearization's modes "
             "up to 2(H+1)ω (10 … 40) + the contacts' static responses, friction memory included "
             "(sarfe/hbm/stability_condensed.py).", ""]
    for res in results:
        lines += [f"## {res['case']}: {res['reduced_dofs']} reduced DOFs, {res['contact_rows']} "
                  f"contact rows, H = {res['H']}, N = {res['N']}", "",
                  "| f [Hz] | Hill order | main (frozen) [s] | main verdict (max Re s) | full [s] | "
                  "full verdict (max Re s) | condensed [s] | condensed verdict (max Re s) |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in res["points"]:
            full = (f"{r['full_s']:.2f} | {r['full_stable']} ({r['full_leading']:.4g})"
                    if "full_s" in r else "- | -")
            main = f"{r['main_s']:.2f} | {r['main_stable']} ({r['main_leading']:.4g})"
            lines.append(f"| {r['frequency_hz']:g} | {r['hill_order']} | {main} | {full} | "
                         f"{r['condensed_s']:.2f} | {r['condensed_stable']} "
                         f"({r['condensed_leading']:.4g}) |")
        lines.append("")
    (HERE / "results" / "stability.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
