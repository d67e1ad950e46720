"""Issue 15, the Craig–Bampton cutoff: which cutoff Newton needs and which the ERP needs, measured
on the door trim of cases/door_trim_p1.yaml (12 contact pairs: 8 rattle, 4 squeak), H = 15.

Per cutoff c = factor · H · f_max (factors 0.25 … 2.0, f_max = 80 Hz; the default rule is 1.5):

1. the linear stage is built (mesh from the cache, assembly, reduction: seconds, modes);
2. the frequencies (40, 50, 60, 70, 80 Hz and the loudest point of a 1 Hz screening at H = 15 on
   the finest stage) are solved in turn, each warm-started from the previous one (stability and
   estimate off, N = 256 = the case default at H = 15): seconds per point (the first solve of a
   stage, which factorizes once and whose successor builds the modal basis, counted apart);
3. each point is compared with the finest cutoff's: max relative change of the contact-row
   displacement and force harmonics (all k ≥ 1, relative to the largest harmonic amplitude of the
   finest), of the first-harmonic contact amplitude a₁ (the estimate's measure), of the radiating
   surface's normal displacement harmonics (the response), the ERP level dB / dB(A) and the ERP
   per harmonic (max |ΔL_k| over harmonics within 30 dB of the strongest);
4. the error estimate's modal-truncation part (sarfe.accuracy.modal_truncation, (4)–(5): the top 1/20
   and 1/5 of the modes left out, re-solved, extrapolated with the decay fitted from both) at the
   same point, set against the measured change (does it bracket it?);
5. the split: the point's contact forces λ̃ from the smaller basis, the displacement recovered on
   the finest basis, ũ_k = Z_k⁻¹ (f̃_k − Gᵀ λ̃_k) (sarfe.hbm.dynamic_stiffness.recover_displacement), compared
   with the finest in the same measures — "only the recovery and ERP need the high modes".

Usage: python benchmarks/accuracy/bench_cutoff.py [mesh_mm[:factor,factor,...] ...] (default 10 with all
factors; the largest factor given is the reference). Writes
benchmarks/results/cutoff.md and .json (one section per mesh; earlier meshes kept from the json).
"""
import os
import pathlib
import platform
import sys
import time
import warnings

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, read_results, write_results  # noqa: E402

import numpy as np

HARMONICS = 15
SAMPLES = 256
FACTORS = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0)
FREQUENCIES_HZ = (40.0, 50.0, 60.0, 70.0, 80.0)
SCREEN_HZ = np.arange(40.0, 80.5, 1.0)
BAND_DB = 30.0      # per-harmonic ERP compared where within this of the strongest harmonic


def door_case(mesh_m, factor):
    from sarfe.case.read import load_case

    data = load_case(ROOT / "cases" / "door_trim_p1.yaml").data
    data.pop("case_data", None)
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    f_max = data["excitation"]["sweep"]["end_hz"]
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [f_max]       # f_max of the rule stays 80 Hz
    data["solver"] = {"harmonics": HARMONICS, "samples_per_period": SAMPLES, "stability": False,
                      "error_estimate": False}
    data["reduction"] = {"cutoff_hz": factor * HARMONICS * f_max}
    return load_case(data, base_dir=ROOT / "cases")


def harmonics_complex(X):
    """(2H+1, n) real → (H, n) complex of the orders k ≥ 1 (cos − i sin)."""
    X = np.asarray(X, dtype=float)
    return X[1::2] - 1j * X[2::2]


def rel_change(X, X_ref):
    """max |X_k − X_ref,k| over k ≥ 1 and columns / max |X_ref,k|."""
    A, B = harmonics_complex(X), harmonics_complex(X_ref)
    scale = np.abs(B).max(initial=0.0)
    return float(np.abs(A - B).max(initial=0.0) / scale) if scale > 0 else float("nan")


def first_harmonic_rel(R, R_ref):
    a, b = np.abs(harmonics_complex(R)[0]), np.abs(harmonics_complex(R_ref)[0])
    return float(np.abs(a - b).max(initial=0.0) / b.max(initial=1e-300))


def erp_of(case, stage, U, omega):
    from sarfe.pipeline.post.records import point_erp as _erp

    erp, W = _erp(case.config.erp, stage, U, omega)
    return erp, W


def compare(case, stage, U, U_ref, s, s_ref, omega):
    erp, W = erp_of(case, stage, U, omega)
    erp_ref, W_ref = erp_of(case, stage, U_ref, omega)
    p, p_ref = np.asarray(erp.power), np.asarray(erp_ref.power)
    strong = p_ref >= p_ref.max() * 10 ** (-BAND_DB / 10)
    per_h = 10 * np.log10(p[strong] / p_ref[strong])
    out = {"response_rel": rel_change(W, W_ref),
           "dba": float(erp.level_total_a_db), "d_dba": float(erp.level_total_a_db
                                                              - erp_ref.level_total_a_db),
           "d_db": float(erp.level_total_db - erp_ref.level_total_db),
           "erp_W": float(erp.power_total),
           "max_harmonic_db": float(np.abs(per_h).max(initial=0.0)),
           "harmonic_db": [float(x) for x in 10 * np.log10(np.where(p_ref > 0, p / np.where(
               p_ref > 0, p_ref, 1), 1))]}
    if s is not None:
        out.update(contact_rel=rel_change(s.contact_displacement, s_ref.contact_displacement),
                   force_rel=rel_change(s.contact_force, s_ref.contact_force),
                   a1_rel=first_harmonic_rel(s.contact_displacement, s_ref.contact_displacement))
    return out


def modal_estimate(stage, nl, solution):
    """The per-point estimate's modal part (4)–(5): (modal_rel, modal_db, seconds) or NaNs."""
    from sarfe.accuracy.measures import first_harmonic_amplitude
    from sarfe.accuracy.modal_truncation import modal_truncation_estimate
    from sarfe.pipeline.solve.case_accuracy import accuracy_problem

    problem = accuracy_problem(stage, nl)
    clock = time.perf_counter()
    a_ref = np.max(first_harmonic_amplitude(problem.contacts, solution.displacement),
                   initial=0.0) or None
    modal = modal_truncation_estimate(solution, problem.model, problem.contacts,
                                      problem.excitation, problem.modal_dofs,
                                      problem.residual_dofs, problem.erp_map, problem.erp_areas,
                                      None, a_ref)
    return modal.amplitude_rel, modal.erp_db, time.perf_counter() - clock


def solve_points(nl, frequencies_hz):
    """Stepped warm-started solves → (solutions, seconds per solve)."""
    from sarfe.hbm import SolverOptions, solve_frequency

    options = SolverOptions(stability=False)
    out, seconds, previous = [], [], None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for f in frequencies_hz:
            clock = time.perf_counter()
            s = solve_frequency(nl.model, nl.contacts, nl.excitation, 2 * np.pi * f, HARMONICS,
                                SAMPLES, initial=previous, options=options)
            if not s.converged and previous is not None:
                s = solve_frequency(nl.model, nl.contacts, nl.excitation, 2 * np.pi * f,
                                    HARMONICS, SAMPLES, options=options)
            seconds.append(time.perf_counter() - clock)
            out.append(s)
            previous = s.displacement if s.converged else None
    return out, seconds


def study(mesh_m, factors=FACTORS):
    from sarfe.hbm.dynamic_stiffness import condense, recover_displacement
    from sarfe.pipeline import build_linear_model, nonlinear_model

    stages = {}
    for factor in sorted(factors, reverse=True):        # the finest first: the reference
        case = door_case(mesh_m, factor)
        clock = time.perf_counter()
        stage = build_linear_model(case)
        seconds = time.perf_counter() - clock
        stages[factor] = (case, stage, nonlinear_model(case, stage), seconds)
        print(f"{mesh_m * 1e3:.0f} mm, {factor} H f_max: {stage.info['modes']} modes, "
              f"stage {seconds:.1f} s", flush=True)
    ref_case, ref_stage, ref_nl, _ = stages[max(factors)]
    screen, _ = solve_points(ref_nl, SCREEN_HZ)
    levels = [erp_of(ref_case, ref_stage, s.displacement, s.omega)[0].level_total_a_db
              if s.converged else -np.inf for s in screen]
    loudest = float(SCREEN_HZ[int(np.argmax(levels))])
    frequencies = sorted(set(FREQUENCIES_HZ) | {loudest})
    print(f"loudest screening point {loudest:g} Hz ({max(levels):.2f} dB(A))", flush=True)
    solved = {f: solve_points(stages[f][2], frequencies) for f in stages}
    ref_solutions = solved[max(factors)][0]
    rows = []
    for factor in sorted(stages):
        case, stage, nl, stage_s = stages[factor]
        solutions, seconds = solved[factor]
        entry = {"factor": factor, "cutoff_hz": factor * HARMONICS * 80.0,
                 "modes": int(stage.info["modes"]), "residual_vectors":
                 int(stage.info["residual_vectors"]), "reduced_dofs": int(stage.dof_count),
                 "stage_s": stage_s, "reduction_s": float(stage.timings.get("reduction_s", 0)),
                 "first_point_s": seconds[0], "point_s": float(np.median(seconds[1:])),
                 "points": []}
        for s, s_ref in zip(solutions, ref_solutions):
            f = float(s.omega) / (2 * np.pi)
            point = {"frequency_hz": f, "converged": bool(s.converged and s_ref.converged),
                     "iterations": int(s.iterations)}
            if point["converged"]:
                point.update(compare_across(case, stage, ref_stage, s, s_ref))
                if factor != max(factors):
                    rel, db, est_s = modal_estimate(stage, nl, s)
                    point.update(modal_rel=rel, modal_db=db, estimate_s=est_s)
                    # split: λ̃ of this basis, displacement recovered on the finest basis
                    cond = condense(ref_nl.model, ref_nl.contacts.gap_map,
                                    ref_nl.excitation, float(s.omega))
                    U_split = recover_displacement(cond, s.contact_force)
                    split = compare(ref_case, ref_stage, U_split, s_ref.displacement, None, None,
                                    float(s.omega))
                    point["split"] = {k: split[k] for k in ("response_rel", "d_dba", "d_db",
                                                            "max_harmonic_db", "dba")}
                else:
                    rel, db, est_s = modal_estimate(stage, nl, s)
                    point.update(modal_rel=rel, modal_db=db, estimate_s=est_s)
            entry["points"].append(point)
        rows.append(entry)
        print(f"  {factor}: " + ", ".join(
            f"{p['frequency_hz']:.0f} Hz a1 {p.get('a1_rel', np.nan):.1e} dBA "
            f"{p.get('d_dba', np.nan):+.3f} est {p.get('modal_rel', np.nan):.1e}/"
            f"{p.get('modal_db', np.nan):.3f}" for p in entry["points"]), flush=True)
    return {"mesh_m": mesh_m, "loudest_hz": loudest, "frequencies_hz": frequencies,
            "screen_dba": [float(x) for x in levels], "rows": rows}


def compare_across(case, stage, ref_stage, s, s_ref):
    """compare() for solutions on different stages: each displacement through its own ERP map
    (same radiating nodes), the contact rows shared (boundary coordinates)."""
    erp, W = erp_of(case, stage, s.displacement, s.omega)
    erp_ref, W_ref = erp_of(case, ref_stage, s_ref.displacement, s_ref.omega)
    p, p_ref = np.asarray(erp.power), np.asarray(erp_ref.power)
    strong = p_ref >= p_ref.max() * 10 ** (-BAND_DB / 10)
    per_h = 10 * np.log10(p[strong] / p_ref[strong])
    return {"response_rel": rel_change(W, W_ref),
            "dba": float(erp.level_total_a_db),
            "d_dba": float(erp.level_total_a_db - erp_ref.level_total_a_db),
            "d_db": float(erp.level_total_db - erp_ref.level_total_db),
            "erp_W": float(erp.power_total), "erp_W_ref": float(erp_ref.power_total),
            "max_harmonic_db": float(np.abs(per_h).max(initial=0.0)),
            "harmonic_db": [float(x) for x in 10 * np.log10(p / np.where(p_ref > 0, p_ref, 1.0)
                                                             .clip(1e-300))],
            "contact_rel": rel_change(s.contact_displacement, s_ref.contact_displacement),
            "force_rel": rel_change(s.contact_force, s_ref.contact_force),
            "a1_rel": first_harmonic_rel(s.contact_displacement, s_ref.contact_displacement)}


def main(meshes_mm):
    res = read_results("cutoff", {})
    res.setdefault("meshes", {})
    for spec in meshes_mm:
        mm, _, factors = str(spec).partition(":")
        mm = float(mm)
        factors = tuple(float(x) for x in factors.split(",")) if factors else FACTORS
        clock = time.perf_counter()
        load = " ".join(f"{x:.1f}" for x in os.getloadavg())
        out = study(mm / 1000.0, factors)
        out.update(wall_s=time.perf_counter() - clock, load_average=load,
                   machine=f"{platform.platform()}, {os.cpu_count()} cores")
        res["meshes"][f"{mm:g}" if factors == FACTORS or mm == 5 else str(spec)] = out
        write_results("cutoff", res)
    write_md(res)


def write_md(res):
    from sarfe.accuracy.estimate import AMPLITUDE_FLOOR, ERP_FLOOR_DB

    L = ["# Craig–Bampton cutoff: what Newton needs, what the ERP needs (issue 15)", "",
         "Door trim of cases/door_trim_p1.yaml (12 pairs: 8 rattle, 4 squeak), H = 15, N = 256, "
         "base 10 m/s², modal ζ 3 %; cutoff = factor · H · f_max (f_max = 80 Hz; the rule's default "
         "factor 1.5). Reference: the finest cutoff of each mesh. Script: "
         "benchmarks/accuracy/bench_cutoff.py (OPENBLAS_NUM_THREADS=1).", "",
         "Columns: max over the points of — a₁: first-harmonic contact amplitude change "
         "(relative to the largest a₁; the estimate's measure); r̃: contact-row displacement "
         "harmonics, all k; λ̃: contact-force harmonics, all k; w̃: radiating normal "
         "displacement harmonics (the response); ΔdB(A), ΔdB: ERP level; ΔL_k: ERP per harmonic "
         "(within 30 dB of the strongest); est a₁ / dB: the per-point estimate's modal part at "
         "the worst point of each measure (brackets: modal part + the estimate's resolution floor "
         "1e-4 / 0.01 dB ≥ the measured a₁ / max(|ΔdB|, |ΔdB(A)|) at every point); split: "
         "λ̃ from this basis, ũ recovered on the finest basis.", ""]
    for mm, m in res["meshes"].items():
        factors = ", ".join(f"{r['factor']:g}" for r in m["rows"])
        L += [f"## {m['mesh_m'] * 1e3:g} mm, factors {factors} (wall {m['wall_s']:.0f} s, load average at start "
              f"{m['load_average']}; {m['machine']})", "",
              f"Points: {', '.join(f'{f:g}' for f in m['frequencies_hz'])} Hz; loudest of the "
              f"1 Hz screening at H = 15 on the finest stage: {m['loudest_hz']:g} Hz. Reference: "
              f"factor {max(r['factor'] for r in m['rows']):g}.", "",
              "| factor | cutoff Hz | modes (+res) | stage s | 1st pt s | s/pt | a₁ | r̃ | λ̃ | w̃ "
              "| ΔdB(A) | ΔdB | ΔL_k dB | est a₁ | est dB | brackets a₁ / dB | split w̃ | "
              "split ΔdB(A) | split ΔL_k |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in m["rows"]:
            pts = [p for p in r["points"] if p["converged"]]
            mx = (lambda key: max((abs(p[key]) for p in pts if key in p), default=float("nan")))
            worst = (lambda key: max(pts, key=lambda p: abs(p.get(key, 0.0))) if pts else {})
            sp = [p["split"] for p in pts if "split" in p]
            # bracket: the modal part plus the estimate's resolution floor (added to every
            # estimate of a point with an active contact) ≥ the measured change, at every point
            br_a = all(p.get("modal_rel", np.nan) + AMPLITUDE_FLOOR >= p["a1_rel"] for p in pts)
            br_d = all(p.get("modal_db", np.nan) + ERP_FLOOR_DB >= max(abs(p["d_db"]),
                                                                       abs(p["d_dba"]))
                       for p in pts)
            fin = r["factor"] == max(x["factor"] for x in m["rows"])
            L.append(
                f"| {r['factor']:g} | {r['cutoff_hz']:.0f} | {r['modes']} (+{r['residual_vectors']})"
                f" | {r['stage_s']:.1f} | {r['first_point_s']:.2f} | {r['point_s']:.3f} | "
                + ("ref | ref | ref | ref | ref | ref | ref" if fin else
                   f"{mx('a1_rel'):.1e} | {mx('contact_rel'):.1e} | {mx('force_rel'):.1e} | "
                   f"{mx('response_rel'):.1e} | {mx('d_dba'):.3f} | {mx('d_db'):.3f} | "
                   f"{mx('max_harmonic_db'):.3f}")
                + f" | {worst('a1_rel').get('modal_rel', np.nan):.1e} | "
                  f"{worst('d_dba').get('modal_db', np.nan):.3f} | "
                + ("-" if fin else f"{'yes' if br_a else 'NO'} / {'yes' if br_d else 'NO'}")
                + " | " + ("-" if not sp else
                           f"{max(s['response_rel'] for s in sp):.1e} | "
                           f"{max(abs(s['d_dba']) for s in sp):.3f} | "
                           f"{max(s['max_harmonic_db'] for s in sp):.3f}")
                + (" | - | -" if not sp else "") + " |")
        L += ["", "Per point (factor: frequency Hz → a₁ change / estimate a₁, ΔdB(A) / "
              "estimate dB, dB(A)):", ""]
        for r in m["rows"]:
            L.append(f"- {r['factor']:g}: " + "; ".join(
                f"{p['frequency_hz']:.0f} → {p.get('a1_rel', np.nan):.1e} / "
                f"{p.get('modal_rel', np.nan):.1e}, {p.get('d_dba', np.nan):+.3f} / "
                f"{p.get('modal_db', np.nan):.3f}, {p.get('dba', np.nan):.2f}"
                for p in r["points"]))
        L.append("")
    L += res.get("notes", [])
    write_results("cutoff", markdown=L)


if __name__ == "__main__":
    if sys.argv[1:] == ["--md"]:       # rewrite the .md from the .json (notes edited there)
        write_md(read_results("cutoff"))
    else:
        main(sys.argv[1:] or ["10"])
