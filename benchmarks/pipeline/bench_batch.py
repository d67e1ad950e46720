"""Batch benchmark: a 200-variant tolerance study at one frequency on 1 and on 2 Dask workers.

Measures the total wall time per worker count, the speed-up 1 → 2 workers, and checks that the
linear stage (mesh, FE, Craig–Bampton) is computed once per run and that both runs give the same
table. Uses the door trim case if its single-frequency solve works, else the next case that does
(rattle rig, then the lumped panel) — the report says which and why.

Usage: python benchmarks/pipeline/bench_batch.py [--samples 200] [--case door_trim|rattle_rig|lumped_rattle]
Writes benchmarks/results/batch.md and batch.json.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, read_results, write_results  # noqa: E402

import pandas as pd  # noqa: E402

from sarfe.batch import run_study  # noqa: E402
from sarfe.batch.store import read_records  # noqa: E402

# name: (frequency [Hz], parameters) — a tolerance study: gaps, friction, stiffness, excitation level
CASES = {
    "door_trim": (52.0, {
        "contacts[type=rattle].gap_m": {"distribution": "truncated_normal", "mean": 5.0e-4, "std": 1.0e-4,
                                        "low": 2.0e-4, "high": 8.0e-4},
        "contacts[type=squeak].friction_coefficient": {"distribution": "uniform", "low": 0.25, "high": 0.45},
        "excitation.base_acceleration.amplitude_m_s2": {"distribution": "lognormal", "median": 10.0, "log_std": 0.2},
    }),
    "rattle_rig": (30.0, {
        "contacts[name=tip].normal_stiffness_N_m": {"distribution": "lognormal", "median": 2.0e5, "log_std": 0.3},
        "excitation.forces[0].force_N": {"distribution": "lognormal", "median": 0.05, "log_std": 0.2},
    }),
    "lumped_rattle": (40.0, {
        "contacts[name=panel_bracket].gap_m": {"distribution": "truncated_normal", "mean": 1.5e-4, "std": 5.0e-5,
                                               "low": 8.0e-5, "high": 3.0e-4},
        "contacts[name=seal].friction_coefficient": {"distribution": "uniform", "low": 0.3, "high": 0.5},
        "excitation.base_acceleration.amplitude_m_s2": {"distribution": "lognormal", "median": 3.0, "log_std": 0.2},
    }),
}


def write_study(folder: pathlib.Path, case: str, samples: int, seed: int = 7) -> pathlib.Path:
    frequency, parameters = CASES[case]
    study = {
        "name": f"bench_{case}",
        "base_case": str(ROOT / "cases" / f"{case}.yaml"),
        "overrides": {"excitation.sweep": None, "excitation.frequency_hz": [frequency]},
        "variations": {"monte_carlo": {"samples": samples, "seed": seed, "parameters": parameters}},
    }
    path = folder / f"bench_{case}_{samples}.yaml"
    path.write_text(json.dumps(study, indent=1))  # JSON is YAML
    return path


def probe(folder: pathlib.Path, case: str, limit_s: float) -> str | None:
    """None if two variants of ``case`` solve in process within ``limit_s`` each, else why not."""
    if not (ROOT / "cases" / f"{case}.yaml").is_file():
        return "case file missing"
    try:
        table = run_study(write_study(folder, case, 2, seed=99), workers=0, output_dir=folder / f"probe_{case}")
    except Exception as error:  # noqa: BLE001 — any failure means: use another case
        return f"{type(error).__name__}: {error}"
    failed = table[table["status"] == "failed"]
    if len(failed):
        return str(failed["error"].iloc[0])[:300]
    slowest = max(r.get("elapsed_s", 0.0) for r in read_records(folder / f"probe_{case}").values())
    if slowest > limit_s:
        return f"one variant took {slowest:.0f} s (> {limit_s:.0f} s): 200 variants do not fit"
    return None


def run(folder, study, workers):
    start = time.perf_counter()
    table = run_study(study, workers=workers, output_dir=folder / f"workers_{workers}", cache_linear_stages=False)
    wall = time.perf_counter() - start
    run_stats = table.attrs["summary"]["run"]
    elapsed = [r.get("elapsed_s", 0.0) for r in read_records(folder / f"workers_{workers}").values()]
    return table, {
        "workers": workers, "wall_s": wall, "linear_stages_built": run_stats["linear_stages_built"],
        "linear_models": run_stats["linear_models"], "linear_build_s": run_stats["linear_build_s"],
        "cluster_start_s": run_stats["cluster_start_s"], "solve_phase_s": run_stats["solve_phase_s"],
        "variants": run_stats["variants"], "failed": run_stats["failed"],
        "variant_solve_mean_s": sum(elapsed) / max(len(elapsed), 1),
        "variant_solve_sum_s": sum(elapsed),
        "load_average_1min_at_end": os.getloadavg()[0],
    }


def compare(first: pd.DataFrame, second: pd.DataFrame) -> dict:
    """How two result tables of the same study differ: statuses, and the largest ERP difference."""
    if list(first["variant_id"]) != list(second["variant_id"]):
        return {"same_rows": False}
    out = {"same_rows": True, "same_status": bool((first["status"] == second["status"]).all())}
    for column in ("erp_db", "erp_dba"):
        if column in first and column in second:
            delta = (pd.to_numeric(first[column]) - pd.to_numeric(second[column])).abs()
            out[f"max_abs_diff_{column}"] = float(delta.max())
            out[f"rows_over_0.01dB_{column}"] = int((delta > 0.01).sum())
    numeric = [c for c in first.columns if pd.api.types.is_float_dtype(first[c]) and c in second]
    out["columns_not_bitwise_equal"] = [c for c in numeric if not first[c].equals(second[c])]
    return out


def markdown(report: dict) -> list[str]:
    """The section of batch.md for one benchmark run."""
    runs, case, samples = report["runs"], report["case"], report["samples"]
    lines = [
        f"## {case}, {samples} variants",
        "",
        f"{samples}-variant Monte Carlo tolerance study of **{case}** at {report['frequency_hz']:g} Hz "
        "(one frequency point per variant; varied: " + ", ".join(f"`{p}`" for p in report["parameters"])
        + "), LocalCluster with 1 and with 2 worker processes (one thread each), linear-stage disk "
        "cache off so that each run builds it.",
        "",
    ]
    if report["cases_not_used"]:
        lines += ["Cases not used: " + "; ".join(f"{k}: {v}" for k, v in report["cases_not_used"].items()), ""]
    lines += [
        "| workers | total [s] | cluster start [s] | linear stages built | linear build [s] | variants [s] "
        "| mean per variant on a worker [s] | failed |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        phase = r["solve_phase_s"] - r["linear_build_s"]
        lines.append(f"| {r['workers']} | {r['wall_s']:.1f} | {r['cluster_start_s']:.1f} | {r['linear_stages_built']} "
                     f"(of {r['linear_models']} linear model) | {r['linear_build_s']:.1f} | {phase:.1f} "
                     f"| {r['variant_solve_mean_s']:.3f} | {r['failed']} |")
    lines += [
        "",
        f"- speed-up 1 → 2 workers: **{report['speedup_total']:.2f}×** total, "
        f"{report['speedup_variant_phase']:.2f}× in the variant phase (after cluster start and linear build)",
        f"- linear part computed once per run: {all(r['linear_stages_built'] == 1 for r in runs)}",
        f"- 1-worker and 2-worker tables bitwise identical: {report['tables_identical']}",
    ]
    difference = report.get("difference_1_vs_2_workers")
    if difference and not report["tables_identical"]:
        lines.append(f"  (same variants and statuses: {difference.get('same_rows')}/{difference.get('same_status')}; "
                     f"max |ΔERP| {difference.get('max_abs_diff_erp_db', float('nan')):.2e} dB, rows differing by "
                     f"more than 0.01 dB: {difference.get('rows_over_0.01dB_erp_db')}; the HBM solves are not "
                     "bitwise reproducible across processes, e.g. FFTW plans depend on array alignment)")
    if report["erp_db"]:
        e = report["erp_db"]
        lines.append(f"- max ERP per variant: {e['min']:.1f} … {e['max']:.1f} dB (median {e['median']:.1f})")
    lines += [
        f"- machine: {report['machine']['cpus']} CPUs shared with other jobs; 1-min load average "
        f"{report['machine']['load_average_1min_before']:.1f} before, {runs[-1]['load_average_1min_at_end']:.1f} "
        "at the end (on a loaded machine a speed-up well below 2 is expected)",
        "",
    ]
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--case", choices=list(CASES), default=None)
    parser.add_argument("--probe-limit-s", type=float, default=10.0,
                        help="largest single-variant time for a case to be used (default 10 s)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="sarfe_bench_batch_") as tmp:
        folder = pathlib.Path(tmp)
        skipped = {}
        for case in ([args.case] if args.case else list(CASES)):
            reason = probe(folder, case, args.probe_limit_s)
            if reason is None:
                break
            skipped[case] = reason
            print(f"{case}: not used ({reason})", flush=True)
        else:
            print("no case works", file=sys.stderr)
            return 1
        frequency, parameters = CASES[case]
        study = write_study(folder, case, args.samples)
        load_before = os.getloadavg()[0]
        runs, tables = [], []
        for workers in (1, 2):
            print(f"{case}: {args.samples} variants on {workers} worker(s)…", flush=True)
            table, numbers = run(folder, study, workers)
            tables.append(table)
            runs.append(numbers)
            print(json.dumps(numbers), flush=True)
        identical = tables[0].equals(tables[1])
        difference = compare(tables[0], tables[1])
        levels = tables[0].groupby("variant_id")["erp_db"].max() if "erp_db" in tables[0] else pd.Series([], dtype=float)

    speedup = runs[0]["wall_s"] / runs[1]["wall_s"]
    variant_phase = [r["solve_phase_s"] - r["linear_build_s"] for r in runs]
    report = {
        "case": case, "cases_not_used": skipped, "samples": args.samples, "frequency_hz": frequency,
        "parameters": parameters, "runs": runs, "speedup_total": speedup,
        "speedup_variant_phase": variant_phase[0] / variant_phase[1],
        "tables_identical": bool(identical), "difference_1_vs_2_workers": difference,
        "erp_db": {"min": float(levels.min()), "median": float(levels.median()), "max": float(levels.max())}
        if len(levels) else {},
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "load_average_1min_before": load_before},
    }
    try:
        previous = read_results("batch", {})
        reports = ({f"{previous['case']}_{previous['samples']}": previous} if "case" in previous
                   else previous.get("runs_by_case", {}))
    except (ValueError, AttributeError, KeyError):
        reports = {}
    reports[f"{case}_{args.samples}"] = report
    write_results("batch", {"runs_by_case": reports}, indent=2)
    text = "\n".join(["# Batch benchmark (`benchmarks/pipeline/bench_batch.py`)", ""]
                     + [line for r in reports.values() for line in markdown(r)])
    write_results("batch", markdown=text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
