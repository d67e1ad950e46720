"""One σ = 0 block Lanczos (sarfe/reduction/lanczos.py): old tree against this one.

Writes benchmarks/results/lanczos_unified.md and .json. The old tree is ``git archive`` of a ref
(default: the merge base of HEAD and main) unpacked in a temporary directory; every run is a
fresh Python process (one BLAS thread) with that tree or this one first on the path, and the
runs alternate A B A B so that a shared machine's load hits both alike. CPU: the
``normal_modes_cpu`` stage timing of Craig–Bampton (process time of the mode search).

Models (door trim generator, the shipped cases' materials and groups):
  demo          cases/door_trim.yaml (14 mm, H = 10, default cutoff 1.0·H·f_max = 800 Hz)
  trim15        cases/door_trim_p1.yaml at mesh_size_m 0.015 (H = 15, cutoff 1.0·H·f_max)
  trim10_capped cases/door_trim_p1.yaml at 0.010 with run 0's cap forced to 240 columns
                (_SLICE_COLUMNS, _SLICE_ENTRIES = 0; one process): run 0 then spectrum slicing
  trim40_dense  door trim p1 at 40 mm, every mode ≤ cutoff against a dense eigh (θ of L⁻¹ M L⁻ᵀ)
  trim40        the same model without the dense reference (CPU only)
Paths: "default" (what the pipeline runs: run 0 capped at max(480, 8e7/n) columns, which on
these meshes finds every mode), "uncapped" (_SLICE_COLUMNS = 10⁹: the one uncapped σ = 0 run,
old: _block_lanczos_modes' own loop, new: the wrapper over shifted_block_lanczos), "modes60"
(mode_count = 60, no cutoff: the uncapped run too).

Usage: python benchmarks/linear/bench_lanczos_unified.py [--old-ref REF] [--repeats 2] [--only m:p,…]
       python benchmarks/linear/bench_lanczos_unified.py --variants   (new tree: block size, partial)
       python benchmarks/linear/bench_lanczos_unified.py --report     (rewrite the .md from the .json)
"""
from __future__ import annotations

import argparse
import functools
import importlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import THREADS, ROOT, read_results, write_results  # noqa: E402

import numpy as np

PYTHON = sys.executable
ENV = dict(os.environ, **THREADS, MPLBACKEND="Agg")     # no PYTHONPATH: the worker picks its tree
MODELS = {"demo": ("cases/door_trim.yaml", None), "trim15": ("cases/door_trim_p1.yaml", 0.015),
          "trim10_capped": ("cases/door_trim_p1.yaml", 0.010),
          "trim40_dense": ("cases/door_trim_p1.yaml", 0.040),
          "trim40": ("cases/door_trim_p1.yaml", 0.040)}


def _worker(tree, model, path_kind, variant):
    """In a fresh process: build the model's linear stage with ``tree``'s sarfe; print JSON."""
    sys.path.insert(0, tree)
    cb = importlib.import_module("sarfe.reduction.craig_bampton")
    try:        # the mode search's own module since issue 28; older trees kept it in craig_bampton
        modes = importlib.import_module("sarfe.reduction.fixed_interface_modes")
    except ImportError:
        modes = cb

    captured = {}
    craig_bampton = cb.craig_bampton

    def capture(stiffness, mass, *args, **kwargs):      # K_ff, M_ff for the dense reference
        captured.update(stiffness=stiffness, mass=mass)
        if model == "trim10_capped":
            kwargs["workers"] = 1                       # one process: the capped run 0 alone
        return craig_bampton(stiffness, mass, *args, **kwargs)

    cb.craig_bampton = capture       # before the pipeline imports it
    if path_kind in ("uncapped", "modes60", "solve_uncapped"):
        modes._SLICE_COLUMNS = 10 ** 9
    if model == "trim10_capped":
        modes._SLICE_COLUMNS, modes._SLICE_ENTRIES = 240, 0
    if variant:                                   # new tree only: the wrapper's knobs
        knobs = json.loads(variant)
        lanczos = importlib.import_module("sarfe.reduction.lanczos")
        if "partial" in knobs:
            modes.shifted_block_lanczos = functools.partial(lanczos.shifted_block_lanczos,
                                                            partial=knobs["partial"])
        if "block_size" in knobs:
            modes._block_lanczos_modes = functools.partial(modes._block_lanczos_modes,
                                                           block_size=knobs["block_size"])
    from sarfe.case.read import load_case, read_yaml
    from sarfe.pipeline import build_linear_model

    case_path, size = MODELS[model]
    data, _ = read_yaml(os.path.join(ROOT, case_path))
    if size is not None:
        data["model"]["fe"]["generator"]["mesh_size_m"] = size
    if path_kind == "modes60":
        data.setdefault("reduction", {})["mode_count"] = 60
    case = load_case(data, base_dir=os.path.join(ROOT, "cases"))
    if path_kind.startswith("solve"):          # the whole demo: its dB(A) per point
        from sarfe.pipeline import solve_case

        with tempfile.TemporaryDirectory() as folder:
            rows = solve_case(case, output_dir=pathlib.Path(folder) / "out").rows
        print("RESULT " + json.dumps({"model": model, "path": path_kind,
                                      "erp_dba": [row["erp_dba"] for row in rows]}))
        return
    stage = build_linear_model(case)
    reduced = stage.reduced
    out = {"tree": tree, "sarfe": importlib.import_module("sarfe").__file__, "model": model, "path": path_kind, "variant": variant,
           "n_interior": int(len(reduced.interior_dofs)),
           "frequencies_hz": reduced.mode_frequencies_hz.tolist(),
           "normal_modes_cpu_s": reduced.timings["normal_modes_cpu"],
           "operator_applications": int(reduced.timings["operator_applications"]),
           "slicing": "slicing" in reduced.timings}
    if model == "trim40_dense":
        out["dense_frequencies_hz"] = _dense_frequencies(captured, reduced)
    print("RESULT " + json.dumps(out))


def _dense_frequencies(captured, reduced):
    """The lowest n_m + 5 frequencies [Hz] of K_ii φ = ω² M_ii φ, dense: θ = 1/ω² are the
    eigenvalues of L⁻¹ M_ii L⁻ᵀ (K_ii = L Lᵀ), accurate to ε·θ_max. (The generalized
    ``scipy.linalg.eigh(K_ii, M_ii)`` is not: it missed the first mode of the 40 mm door trim
    by 1.7e-7 relative, K_ii's drilling and membrane stiffness making it ill-conditioned.)"""
    import scipy.linalg as sla

    interior = reduced.interior_dofs
    k_ii = captured["stiffness"].tocsr()[interior][:, interior].toarray()
    m_ii = captured["mass"].tocsr()[interior][:, interior].toarray()
    lower = sla.cholesky(k_ii, lower=True)
    half = sla.solve_triangular(lower, m_ii, lower=True)
    whole = sla.solve_triangular(lower, half.T, lower=True)
    theta = sla.eigh(0.5 * (whole + whole.T), eigvals_only=True)[::-1]
    return (1.0 / np.sqrt(theta[:len(reduced.mode_frequencies_hz) + 5]) / (2 * np.pi)).tolist()


def _run(tree, model, path_kind, variant=""):
    command = [PYTHON, __file__, "--worker", tree, model, path_kind, variant]
    done = subprocess.run(command, env=ENV, capture_output=True, text=True, cwd=ROOT)
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    if not lines:
        raise RuntimeError(f"{model} {path_kind} in {tree}: {done.stderr[-2000:]}")
    return json.loads(lines[-1][7:])


def _old_tree(ref):
    target = pathlib.Path(tempfile.mkdtemp(prefix="sarfe-old-"))
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref], capture_output=True,
                             check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive, check=True)
    return str(target)


def _relative(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return None
    return float(np.max(np.abs(a - b) / np.abs(b))) if len(a) else 0.0


def compare(old, new, plan, repeats):
    rows = []
    for model, path_kind in plan:
        runs = {"old": [], "new": []}
        for _ in range(1 if model == "trim40_dense" or path_kind.startswith("solve")
                       else repeats):                         # A B A B
            runs["old"].append(_run(old, model, path_kind))
            runs["new"].append(_run(new, model, path_kind))
        a, b = runs["old"][0], runs["new"][0]
        if path_kind.startswith("solve"):
            row = {"model": model, "path": path_kind, "erp_dba_old": a["erp_dba"],
                   "erp_dba_new": b["erp_dba"],
                   "max_abs_dba_diff": float(np.max(np.abs(np.subtract(a["erp_dba"],
                                                                      b["erp_dba"]))))}
            rows.append(row)
            print(json.dumps(row), flush=True)
            continue
        row = {"model": model, "path": path_kind, "n_interior": a["n_interior"],
               "modes_old": len(a["frequencies_hz"]), "modes_new": len(b["frequencies_hz"]),
               "max_rel_frequency_diff": _relative(b["frequencies_hz"], a["frequencies_hz"]),
               "applications_old": a["operator_applications"],
               "applications_new": b["operator_applications"],
               "cpu_old_s": [r["normal_modes_cpu_s"] for r in runs["old"]],
               "cpu_new_s": [r["normal_modes_cpu_s"] for r in runs["new"]],
               "slicing": [a["slicing"], b["slicing"]]}
        if "dense_frequencies_hz" in a:
            dense = np.asarray(a["dense_frequencies_hz"])
            for side, run in (("old", a), ("new", b)):
                found = np.asarray(run["frequencies_hz"])
                row[f"max_rel_vs_dense_{side}"] = _relative(found, dense[:len(found)])
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def variants(new, repeats):
    rows = []
    plan = [("trim15", "uncapped"), ("demo", "uncapped"), ("trim15", "modes60")]
    # (the convergence test relative to the largest θ — old _block_lanczos_modes' — was a knob
    # "scale" of shifted_block_lanczos at commit 410e40d, removed once measured)
    knob_sets = [{"block_size": 12}, {"block_size": 16}, {"block_size": 12, "partial": False}]
    reference = {}
    for model, path_kind in plan:
        for _ in range(repeats):
            for knobs in knob_sets:
                run = _run(new, model, path_kind, json.dumps(knobs))
                key = (model, path_kind)
                reference.setdefault(key, run["frequencies_hz"])
                row = {"model": model, "path": path_kind, **knobs,
                       "modes": len(run["frequencies_hz"]),
                       "applications": run["operator_applications"],
                       "cpu_s": run["normal_modes_cpu_s"],
                       "max_rel_vs_first": _relative(run["frequencies_hz"], reference[key])}
                rows.append(row)
                print(json.dumps(row), flush=True)
    return rows


def report(results):
    """benchmarks/results/lanczos_unified.md from the JSON (old vs new rows, then the variants)."""
    lines = ["# One σ = 0 block Lanczos: old vs new (benchmarks/linear/bench_lanczos_unified.py)", "",
             f"Old tree: `{results.get('old_ref', '?')}` (git archive); new: this tree. Fresh "
             "process per run, one BLAS thread, A B A B; CPU = Craig–Bampton's "
             "`normal_modes_cpu` (process time of the mode search), median of the runs.", "",
             "| model | path | n_i | modes old/new | max rel Δf old→new | solves old/new | "
             "CPU old [s] | CPU new [s] | Δ CPU |", "|---|---|---|---|---|---|---|---|---|"]
    for key, row in results.get("compare", {}).items():
        if "erp_dba_old" in row:
            continue
        old, new = np.median(row["cpu_old_s"]), np.median(row["cpu_new_s"])
        diff = row["max_rel_frequency_diff"]
        lines.append(f"| {row['model']} | {row['path']} | {row['n_interior']} | "
                     f"{row['modes_old']}/{row['modes_new']} | "
                     f"{'—' if diff is None else f'{diff:.1e}'} | "
                     f"{row['applications_old']}/{row['applications_new']} | {old:.3f} "
                     f"({len(row['cpu_old_s'])}) | {new:.3f} | {100 * (new / old - 1):+.1f} % |")
    dense = [row for row in results.get("compare", {}).values() if "max_rel_vs_dense_new" in row]
    for row in dense:
        lines += ["", f"{row['model']}: every mode ≤ cutoff against the dense reference "
                      f"(θ of L⁻¹ M_ii L⁻ᵀ): old {row['max_rel_vs_dense_old']:.1e}, new "
                      f"{row['max_rel_vs_dense_new']:.1e} relative in frequency."]
    for key, row in results.get("compare", {}).items():
        if "erp_dba_old" in row:
            lines += ["", f"{key} (whole `solve_case` of the demo): ERP dB(A) per point old "
                          f"{[round(v, 9) for v in row['erp_dba_old']]}, new "
                          f"{[round(v, 9) for v in row['erp_dba_new']]}: max |Δ| = "
                          f"{row['max_abs_dba_diff']:.1e} dB."]
    if results.get("variants"):
        lines += ["", "## Variants of the uncapped σ = 0 run (new tree)", "",
                  "| model | path | knobs | modes | solves | CPU [s] | max rel Δf vs first |",
                  "|---|---|---|---|---|---|---|"]
        for row in results["variants"]:
            knobs = {k: v for k, v in row.items() if k in ("block_size", "scale", "partial")}
            lines.append(f"| {row['model']} | {row['path']} | {knobs} | {row['modes']} | "
                         f"{row['applications']} | {row['cpu_s']:.3f} | "
                         f"{row['max_rel_vs_first']:.1e} |")
    lines += [""] + results.get("notes", [])
    write_results("lanczos_unified", markdown=lines)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        _worker(*sys.argv[2:6])
        return
    parser = argparse.ArgumentParser()
    parser.add_argument("--old-ref", default=None)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--variants", action="store_true")
    parser.add_argument("--only", default=None, help="comma-separated model:path pairs")
    parser.add_argument("--report", action="store_true", help="only rewrite the .md")
    args = parser.parse_args()
    results = read_results("lanczos_unified", {})
    if args.report:
        report(results)
        return
    if args.variants:
        results["variants"] = variants(str(ROOT), args.repeats)
    else:
        ref = args.old_ref or subprocess.run(["git", "-C", str(ROOT), "merge-base", "HEAD", "main"],
                                             capture_output=True, text=True,
                                             check=True).stdout.strip()
        plan = [("demo", "default"), ("demo", "uncapped"), ("trim15", "default"),
                ("trim15", "uncapped"), ("trim15", "modes60"), ("trim10_capped", "default"),
                ("trim40_dense", "uncapped"), ("demo", "solve_default"),
                ("demo", "solve_uncapped")]
        if args.only:
            plan = [tuple(item.split(":")) for item in args.only.split(",")]
        old = _old_tree(ref)
        results["old_ref"] = ref
        results.setdefault("compare", {})
        for row in compare(old, str(ROOT), plan, args.repeats):
            results["compare"][f"{row['model']}:{row['path']}"] = row
    write_results("lanczos_unified", results)
    report(results)


if __name__ == "__main__":
    main()
