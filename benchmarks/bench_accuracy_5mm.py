"""Issue 15: P1's accuracy check at 5 mm — the per-point error estimate against the truth.

P1 (cases/door_trim_p1.yaml: 5 mm, H = 15, 40–80 Hz) at a few points in 58–64 Hz and one quiet
point (45 Hz), solved point by point (warm-started steps, stability off):

- truth: H = 15 (N = 256) and H = 30 (N = 512) on one large Craig–Bampton basis (``truth``,
  cutoff TRUTH_CUTOFF_HZ); the true H error of H = 15 is its change to H = 30 there;
- the defaults at cutoff_margin 1.0 and 1.25 (cutoff 1.2 / 1.5 kHz = margin · 15 · 80 Hz), H = 15
  with the pipeline's per-point estimate (``stage_error_estimate``: its harmonics, aliasing and
  modal parts), and H' = 30 on the same basis (what the estimate's harmonics part re-solves): the
  true cutoff error is the change of H = 15 on that basis against H = 15 on the truth basis.

What is kept per solution (so that comparisons across bases need no stage): the contact
displacements G ũ (2H+1, rows) (boundary coordinates: the same rows on every basis) and the
ERP proxy per harmonic p_k = (kω)² Σ_s a_s |w_{s,k}|² through that basis' own ERP map, plus the
basis' fixed-interface, residual-vector and reduced-system frequencies.

Usage (each stage one process; the truth's stage is large — run it niced in the background):
  python benchmarks/bench_accuracy_5mm.py solve LABEL CUTOFF_HZ [--truth] → /tmp/acc5/LABEL.pkl
  python benchmarks/bench_accuracy_5mm.py report → benchmarks/results/accuracy_5mm.md and .json
"""
from __future__ import annotations

import json
import os
import pickle
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results"
STORE = Path(os.environ.get("SARFE_ACC5_STORE", "/tmp/acc5"))
FREQUENCIES_HZ = (45.0, 58.5, 60.0, 60.74, 61.5, 62.3, 63.0)
HARMONICS, SAMPLES = 15, 256
TRUTH_HARMONICS, TRUTH_SAMPLES = 30, 512
F_MAX_HZ = 80.0                       # P1's sweep end: the cutoff rule's f_max
MESH_M = float(os.environ.get("SARFE_ACC5_MESH_M", "0.005"))


def p1_case(cutoff_hz, mesh_m=MESH_M):
    """P1 at the listed points with an explicit cutoff (the default rule would take f_max from the
    list, not 80 Hz), H = 15, stability and estimate off (the estimate is called here)."""
    from sarfe.io.case import load_case

    data = load_case(ROOT / "cases" / "door_trim_p1.yaml").data
    data.pop("case_data", None)
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = list(FREQUENCIES_HZ)
    data["solver"] = {"harmonics": HARMONICS, "samples_per_period": SAMPLES, "stability": False,
                      "error_estimate": False}
    data["reduction"] = {"cutoff_hz": float(cutoff_hz)}
    return load_case(data, base_dir=ROOT / "cases")


def cpu_seconds():
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def solve_at(nl, H, N, frequencies_hz, starts=None):
    """Warm-started stepped solves at H, N (start: ``starts[i]`` resized when given, else the
    previous point) → solutions."""
    from sarfe.accuracy.estimates import resize_harmonics
    from sarfe.hbm import SolverOptions, solve_frequency

    options = SolverOptions(stability=False)
    F = resize_harmonics(nl.excitation, H)
    out, previous = [], None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i, f in enumerate(frequencies_hz):
            guess = previous if starts is None else resize_harmonics(starts[i].displacement, H)
            s = solve_frequency(nl.model, nl.contacts, F, 2 * np.pi * f, H, N, initial=guess,
                                options=options)
            if not s.converged and guess is not None:
                s = solve_frequency(nl.model, nl.contacts, F, 2 * np.pi * f, H, N,
                                    options=options)
            out.append(s)
            previous = s.displacement if s.converged else None
    return out


def record(stage, nl, s):
    from sarfe.accuracy.estimates import _harmonic_powers

    return {"frequency_hz": float(s.omega / (2 * np.pi)), "converged": bool(s.converged),
            "harmonics": int(s.harmonics), "samples": int(s.samples_per_period),
            "contact": np.asarray(nl.contacts.gap_map @ np.asarray(s.displacement).T).T,
            "powers": _harmonic_powers(s.displacement, s.omega, stage.erp_map, stage.erp_areas),
            "contact_force": np.asarray(s.contact_force)}


def light(stage):
    """The stage without its mesh and full-space basis (what the estimate needs), picklable."""
    reduced = stage.reduced
    info = dict(stage.info)
    if reduced is not None:
        info["residual_frequencies_hz"] = np.asarray(reduced.residual_frequencies_hz)
    return replace(stage, reduced=None, mesh=None, info=info)


def system_frequencies_hz(nl):
    import scipy.linalg

    dense = (lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float))
    values = scipy.linalg.eigh(dense(nl.model.stiffness), dense(nl.model.mass), eigvals_only=True)
    return np.sqrt(np.clip(values, 0.0, None)) / (2 * np.pi)


def solve(label, cutoff_hz, truth=False):
    from sarfe.pipeline import build_linear_model, nonlinear_model
    from sarfe.pipeline.accuracy import stage_error_estimate

    STORE.mkdir(parents=True, exist_ok=True)
    case = p1_case(cutoff_hz)
    clock, cpu = time.perf_counter(), cpu_seconds()
    stage = build_linear_model(case)
    timing = {"stage_wall_s": time.perf_counter() - clock, "stage_cpu_s": cpu_seconds() - cpu}
    stage = light(stage)
    nl = nonlinear_model(case, stage)
    print(f"{label}: {stage.info.get('modes')} modes, {stage.dof_count} reduced DOFs, "
          f"stage {timing['stage_wall_s']:.0f} s wall, {timing['stage_cpu_s']:.0f} s CPU",
          flush=True)
    with open(STORE / f"{label}_stage.pkl", "wb") as handle:
        pickle.dump({"stage": stage, "nl": nl}, handle, protocol=5)
    out = {"label": label, "cutoff_hz": float(cutoff_hz), "modes": int(stage.info.get("modes", 0)),
           "reduced_dofs": int(stage.dof_count),
           "mode_frequencies_hz": np.asarray(stage.mode_frequencies_hz),
           "residual_frequencies_hz": stage.info.get("residual_frequencies_hz"),
           "system_frequencies_hz": system_frequencies_hz(nl), **timing}
    cpu = cpu_seconds()
    base = solve_at(nl, HARMONICS, SAMPLES, FREQUENCIES_HZ)
    out["h15_cpu_s"] = cpu_seconds() - cpu
    out["h15"] = [record(stage, nl, s) for s in base]
    print(f"{label}: H = 15 solved ({out['h15_cpu_s']:.0f} s CPU)", flush=True)
    cpu = cpu_seconds()
    fine = solve_at(nl, TRUTH_HARMONICS, TRUTH_SAMPLES if truth else SAMPLES, FREQUENCIES_HZ,
                    starts=base)
    out["h30_cpu_s"] = cpu_seconds() - cpu
    out["h30"] = [record(stage, nl, s) for s in fine]
    print(f"{label}: H = 30 solved ({out['h30_cpu_s']:.0f} s CPU)", flush=True)
    with open(STORE / f"{label}.pkl", "wb") as handle:
        pickle.dump(out, handle)
    with open(STORE / f"{label}_solutions.pkl", "wb") as handle:
        pickle.dump({"h15": base, "h30": fine}, handle, protocol=5)
    if not truth:
        estimates, cpu = [], cpu_seconds()
        for s in base:
            estimates.append(stage_error_estimate(s, stage, nl).as_dict() if s.converged else None)
        out["estimate_cpu_s"] = cpu_seconds() - cpu
        out["estimates"] = estimates
        print(f"{label}: estimates ({out['estimate_cpu_s']:.0f} s CPU)", flush=True)
    with open(STORE / f"{label}.pkl", "wb") as handle:
        pickle.dump(out, handle)


# ------------------------------------------------------------------------------------ report
def amplitudes(contact):
    """First-harmonic… H-th amplitudes of the contact rows: (H, rows) from (2H+1, rows)."""
    contact = np.asarray(contact)
    return np.hypot(contact[1::2], contact[2::2])


def a1_change(contact, reference):
    """The estimate's amplitude measure: max over rows of |Δ a₁| / max a₁ of ``reference``."""
    a, b = amplitudes(contact)[0], amplitudes(reference)[0]
    return float(np.max(np.abs(a - b)) / max(b.max(initial=0.0), 1e-300))


def level_change_db(powers, reference, frequency_hz):
    """The estimate's ERP measure: the larger (in magnitude) of the level changes of Σ p_k and of
    the A-weighted Σ p_k [dB], of ``powers`` against ``reference``."""
    from sarfe.erp.weighting import a_weighting_db

    out = []
    for weighted in (False, True):
        levels = []
        for p in (powers, reference):
            p = np.asarray(p, dtype=float)
            if weighted:
                k = np.arange(1, p.size + 1)
                p = p * 10.0 ** (np.asarray(a_weighting_db(k * frequency_hz)) / 10.0)
            levels.append(10 * np.log10(p.sum()))
        out.append(levels[0] - levels[1])
    return float(max(out, key=abs))


def load(label):
    with open(STORE / f"{label}.pkl", "rb") as handle:
        return pickle.load(handle)


def point_rows(truth, bases):
    """Per point: true H error, true cutoff error, the estimate's parts, the basis' own H change."""
    from sarfe.accuracy.estimates import RICHARDSON, harmonics_richardson

    rows = []
    for i, f in enumerate(FREQUENCIES_HZ):
        t15, t30 = truth["h15"][i], truth["h30"][i]
        row = {"frequency_hz": f, "converged": bool(t15["converged"] and t30["converged"]),
               "true_h_rel": a1_change(t15["contact"], t30["contact"]),
               "true_h_db": level_change_db(t15["powers"], t30["powers"], f)}
        for label, base in bases.items():
            b15, b30 = base["h15"][i], base["h30"][i]
            e = (base.get("estimates") or [None] * len(FREQUENCIES_HZ))[i] or {}
            out = {"converged": bool(b15["converged"] and b30["converged"]),
                   "true_cutoff_rel": a1_change(b15["contact"], t15["contact"]),
                   "true_cutoff_db": level_change_db(b15["powers"], t15["powers"], f),
                   "true_total_rel": a1_change(b15["contact"], t30["contact"]),
                   "true_total_db": level_change_db(b15["powers"], t30["powers"], f),
                   "basis_h_rel": a1_change(b15["contact"], b30["contact"]),
                   "basis_h_db": level_change_db(b15["powers"], b30["powers"], f),
                   "h30_vs_truth_rel": a1_change(b30["contact"], t30["contact"])}
            if e:
                factor = harmonics_richardson(e["harmonics"], e["extended_harmonics"])
                out.update(extended_harmonics=e["extended_harmonics"], richardson=factor,
                           harmonics_rel=e["harmonics_rel"], harmonics_db=e["harmonics_db"],
                           harmonics_part_rel=factor * e["harmonics_rel"],
                           harmonics_part_db=factor * abs(e["harmonics_db"]),
                           aliasing_part_rel=RICHARDSON * e["aliasing_rel"],
                           aliasing_part_db=RICHARDSON * abs(e["aliasing_db"]),
                           modal_rel=e["modal_rel"], modal_db=e["modal_db"],
                           amplitude_rel=e["amplitude_rel"], erp_db=e["erp_db"],
                           notes=list(e.get("notes", ())))
            row[label] = out
        rows.append(row)
    return rows


def harmonic_rows(truth, bases, index):
    """Per harmonic k of the H' = 30 solutions at point ``index``: the largest contact amplitude
    (max over rows) [m] and the ERP proxy p_k on each basis."""
    out = []
    for k in range(1, TRUTH_HARMONICS + 1):
        row = {"k": k, "hz": k * FREQUENCIES_HZ[index]}
        for label, data in {"truth": truth, **bases}.items():
            r30 = data["h30"][index]
            row[label] = {"contact_m": float(amplitudes(r30["contact"])[k - 1].max()),
                          "power": float(r30["powers"][k - 1])}
        out.append(row)
    return out


def report(labels=("m100", "m125")):
    truth = load("truth")
    bases = {label: load(label) for label in labels}
    res = {"frequencies_hz": list(FREQUENCIES_HZ), "mesh_m": MESH_M,
           "bases": {label: {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                             for k, v in data.items() if k not in ("h15", "h30", "estimates")}
                     for label, data in {"truth": truth, **bases}.items()},
           "points": point_rows(truth, bases),
           "harmonics": {f"{FREQUENCIES_HZ[i]:g}": harmonic_rows(truth, bases, i)
                         for i in range(len(FREQUENCIES_HZ))}}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "accuracy_5mm.json").write_text(json.dumps(res, indent=1, default=float))
    return res


if __name__ == "__main__":
    command = sys.argv[1]
    if command == "solve":
        solve(sys.argv[2], float(sys.argv[3]), "--truth" in sys.argv)
    elif command == "report":
        report()
    else:
        raise SystemExit(__doc__)
