"""Issue 30 item 1 for a fixed H: the default Craig–Bampton cutoff capped at the Newton cutoff,
min(1.0 · H · f_max, max(1 kHz, 1.5 · 5 · f_max)) (sarfe.pipeline.model.cutoff.default_cutoff_hz),
against larger cutoffs, at points whose harmonics reach past the cap.

Per (case, mesh, H, N, frequencies) of SPECS: one reduction per cutoff (in this process), then
one HBM point per frequency (stability and estimate off); the dB(A) and the contact rows'
first-harmonic amplitudes (relative to the largest) against the largest cutoff, and at the cap the
per-point estimate's modal term (sarfe.accuracy.modal_truncation; the ± adds ERP_FLOOR_DB and
AMPLITUDE_FLOOR on top): does it bracket the change? (An accuracy study: its times are not
measured — a linear stage may come from sarfe's stage cache.)

Usage: python benchmarks/accuracy/bench_capped_cutoff.py. Writes benchmarks/results/
capped_cutoff.md and .json.
"""
import pathlib
import sys
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, machine_line, write_results  # noqa: E402

from sarfe.accuracy.estimate import AMPLITUDE_FLOOR, ERP_FLOOR_DB  # noqa: E402
from sarfe.accuracy.measures import first_harmonic_amplitude  # noqa: E402
from sarfe.accuracy.modal_truncation import modal_truncation_estimate  # noqa: E402
from sarfe.hbm import SolverOptions, solve_frequency  # noqa: E402
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model  # noqa: E402
from sarfe.pipeline.post.records import point_erp  # noqa: E402
from sarfe.pipeline.solve.case_accuracy import accuracy_problem  # noqa: E402

SPECS = (   # case, mesh [m] (None: the case's), H, N, frequencies [Hz], cutoffs [Hz] (cap first)
    # door_trim_p1 at 10 mm: its band 40-80 Hz (harmonics to 1.2 kHz, cap 1 kHz; 1.2 kHz is
    # the spectral rule's default)
    ("door_trim_p1", 0.01, 15, 256, (44.05, 56.0, 65.6, 72.0, 80.0), (1000.0, 1200.0, 2400.0)),
    # the same swept to 200 Hz (the shaker band: harmonics to 3 kHz, cap 1.5 kHz)
    ("door_trim_p1", 0.01, 15, 256, (30.0, 65.6, 100.0, 150.0, 200.0), (1500.0, 3000.0, 4500.0)),
    # stick-slip radiating at high harmonics (H = 32 to 150 Hz: 4.8 kHz; cap 1125 Hz)
    ("squeak_rig", None, 32, 256, (50.0, 100.0, 150.0), (1125.0, 2400.0, 4800.0, 9600.0)),
)


def point_case(name, mesh, H, N, frequencies, cutoff):
    data = load_case(ROOT / "cases" / f"{name}.yaml").data
    data.pop("case_data", None)
    if mesh is not None:
        data["model"]["fe"]["generator"]["mesh_size_m"] = mesh
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = list(frequencies)
    data["solver"] = {"harmonics": H, "samples_per_period": N, "stability": False,
                      "error_estimate": False}
    data["reduction"] = {"cutoff_hz": cutoff}
    return load_case(data, base_dir=ROOT / "cases")


def points(name, mesh, H, N, frequencies, cutoff, estimate):
    """{cutoff_hz, modes, rows: [{frequency_hz, converged, dba, amplitude_m, modal_*}]}."""
    case = point_case(name, mesh, H, N, frequencies, cutoff)
    stage = build_linear_model(case)
    nl = nonlinear_model(case, stage)
    rows = []
    for f in frequencies:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = solve_frequency(nl.model, nl.contacts, nl.excitation, 2 * np.pi * f, H, N,
                                options=SolverOptions(stability=False))
        erp, _ = point_erp(case.config.erp, stage, s.displacement, s.omega)
        a = first_harmonic_amplitude(nl.contacts, s.displacement)
        row = {"frequency_hz": f, "converged": bool(s.converged),
               "dba": float(erp.level_total_a_db), "amplitude_m": a.tolist()}
        if estimate:
            p = accuracy_problem(stage, nl)
            m = modal_truncation_estimate(s, p.model, p.contacts, p.excitation, p.modal_dofs,
                                          p.residual_dofs, p.erp_map, p.erp_areas, None, a.max())
            row.update(modal_rel=float(m.amplitude_rel), modal_db=float(m.erp_db))
        rows.append(row)
    return {"cutoff_hz": cutoff, "modes": int(len(stage.mode_frequencies_hz)), "rows": rows}


def main():
    results = []
    lines = ["# Capped default cutoff (issue 30 item 1, fixed H): min(H f_max, Newton cutoff)", "",
             machine_line(), "",
             "Change = to the largest cutoff; amp = max over contact rows of |Δa₁| / max a₁. "
             f"Bracketed: modal term + floor ({ERP_FLOOR_DB} dB, {AMPLITUDE_FLOOR:g}) ≥ change.", ""]
    for name, mesh, H, N, frequencies, cutoffs in SPECS:
        runs = [points(name, mesh, H, N, frequencies, c, c == cutoffs[0]) for c in cutoffs]
        results.append({"case": name, "mesh_m": mesh, "harmonics": H, "samples": N,
                        "runs": runs})
        ref = runs[-1]["rows"]
        lines += [f"## {name}, mesh {mesh or 'as shipped'} m, H = {H}, N = {N}", "",
                  "| cutoff Hz | modes | f Hz | dB(A) | Δ dB | amp | modal dB | "
                  "modal amp | bracketed |", "|---|---|---|---|---|---|---|---|---|"]
        for run in runs:
            for row, r0 in zip(run["rows"], ref):
                a, a0 = np.asarray(row["amplitude_m"]), np.asarray(r0["amplitude_m"])
                d_db = row["dba"] - r0["dba"]
                amp = float(np.max(np.abs(a - a0)) / max(a0.max(), 1e-300))
                row.update(change_db=d_db, change_rel=amp)
                if "modal_db" in row:
                    ok = (row["modal_db"] + ERP_FLOOR_DB >= abs(d_db)
                          and row["modal_rel"] + AMPLITUDE_FLOOR >= amp)
                    extra = f"{row['modal_db']:.4f} | {row['modal_rel']:.1e} | {'yes' if ok else 'NO'}"
                else:
                    extra = "- | - | -"
                lines.append(f"| {run['cutoff_hz']:.0f} | {run['modes']} | "
                             f"{row['frequency_hz']:g} | {row['dba']:.4f} | {d_db:+.4f} | "
                             f"{amp:.1e} | {extra} |")
        lines.append("")
    write_results("capped_cutoff", results, lines)


if __name__ == "__main__":
    main()
