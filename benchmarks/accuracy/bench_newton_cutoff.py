"""Issue 30 item 1, the Newton cutoff of ``resolution: auto`` (sarfe.pipeline.solve.case_accuracy.
rule_cutoff_hz: max(1 kHz, 1.5 · 5 · f_max), not 1.5 · H · f_max): the dB(A) level and the
estimate's modal term (sarfe.accuracy.modal_truncation, in the ±) at one loud point per case, for
the Craig–Bampton cutoffs 1, 1.5, 2, 3 kHz at the H the search chooses there.

Per (case, frequency, H, N) of SPECS and cutoff: one whole `sarfe solve` process (resolution
fixed, the cutoff given, defaults otherwise: residual vectors, stability, estimate), its CPU
seconds, modes, dB(A), ± and modal term; the change of the dB(A) to the largest cutoff, set against
the modal term at the smaller one (does the term bracket it?).

Usage: python benchmarks/accuracy/bench_newton_cutoff.py. Writes benchmarks/results/
newton_cutoff.md and .json.
"""
import json
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, machine_line, read_case, run_timed, write_case, write_results  # noqa: E402

CUTOFFS_HZ = (1000.0, 1500.0, 2000.0, 3000.0)
SPECS = (   # case, frequency [Hz], H, N: the door trim's headline point at the H auto chose
            # (cases/door_trim.yaml), the instrument panel sweep's loudest point at its H = 18
    ("cases/door_trim.yaml", 67.0, 14, 128),
    ("cases/instrument_panel_sweep.yaml", 65.3, 18, 512),
)


def one_run(case, frequency_hz, harmonics, samples, cutoff_hz, folder) -> dict:
    """One whole process at the cutoff → {cutoff_hz, cpu_s, modes, dba, pm_db, modal_db}."""
    data = read_case(case)
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [frequency_hz]
    data.setdefault("solver", {}).update(harmonics=harmonics, samples_per_period=samples,
                                         resolution="fixed")
    data.setdefault("reduction", {})["cutoff_hz"] = cutoff_hz
    path = write_case(data, ROOT / case)
    out = pathlib.Path(folder) / f"{pathlib.Path(case).stem}_{cutoff_hz:.0f}"
    try:
        _, cpu, _ = run_timed([sys.executable, "-m", "sarfe", "solve", str(path), "--output",
                               str(out), "--force", "--quiet"])
    finally:
        path.unlink()
    summary = json.loads((out / "summary.json").read_text())
    point, estimate = summary["points"][0], summary["points"][0].get("error_estimate") or {}
    return {"cutoff_hz": cutoff_hz, "cpu_s": cpu, "modes": summary["model"].get("modes"),
            "dba": point["erp"]["level_dba"], "pm_db": abs(estimate.get("erp_db", float("nan"))),
            "modal_db": abs(estimate.get("modal_db", float("nan")))}


def main():
    results, lines = [], ["# Newton cutoff (issue 30 item 1): dB(A) and the modal term vs cutoff", "",
                          machine_line(), ""]
    with tempfile.TemporaryDirectory() as folder:
        for case, f_hz, H, N in SPECS:
            runs = [one_run(case, f_hz, H, N, c, folder) for c in CUTOFFS_HZ]
            results.append({"case": case, "frequency_hz": f_hz, "harmonics": H, "runs": runs})
            ref = runs[-1]["dba"]
            lines += [f"## {case}, {f_hz} Hz, H = {H}, N = {N} (H·f = {H * f_hz:.0f} Hz)", "",
                      "| cutoff Hz | modes | CPU s | dB(A) | Δ to the largest | ± dB | modal term dB |",
                      "|---|---|---|---|---|---|---|"]
            lines += [f"| {r['cutoff_hz']:.0f} | {r['modes']} | {r['cpu_s']:.1f} | {r['dba']:.4f} | "
                      f"{r['dba'] - ref:+.4f} | {r['pm_db']:.3f} | {r['modal_db']:.5f} |"
                      for r in runs]
            lines.append("")
    write_results("newton_cutoff", results, lines)


if __name__ == "__main__":
    main()
