"""Hill stability per point: full Hill eigen-solve vs the contact-row condensed roots
→ benchmarks/results/stability.md and stability.json.

Door trim (cases/door_trim.yaml) at a 10 mm mesh, H = 5, N = 64, points at 40/52/67/80/95 Hz solved
without stability; then per point (a) the frozen full Hill problem as main had it (ARPACK
shift-invert for the exponents nearest 0 of the 2(2H+1)n-order matrix) and (b) the condensed
method (:mod:`sarfe.hbm.stability.condensed`: Hill on a bounded Ritz basis). Verdicts and leading exponents side by side. Also the squeak rig (H = 3, N = 128):
full (with the friction-memory refinement) vs condensed.

Section "contact rows" (``--rows``, issue 15 P1): the contact-row count
(:mod:`sarfe.hbm.stability.rows`, the default above 3000 Hill rows) per point of the P1 door trim
(cases/door_trim_p1.yaml: 12 pairs, H = 15) at a 15 mm mesh, 60 → 65 Hz, continuation step 0.04:
the sweep solved without stability, then per point the count's CPU time, its det F evaluations
and the LU order (2H+1)|R|; the verdict of every point. → results/stability_rows.json.

Section "sweep" (``--sweep``, issue 15 P1, session hilltrack): the whole P1 sweep at 15 mm
(cases/door_trim_p1.yaml, 40 → 80 Hz, its own continuation: ≈ 206 points) solved with the default
options, Hill stability deferred (:mod:`sarfe.hbm.stability.deferred`) and then computed per point in this
process as the workers compute it (``stability_of``): per point the CPU time, the det F
evaluations of the count (contour) and of the real-zero search, the path (zeros counted, Ritz
hand-over), verdict and leading exponent. → results/stability_sweep.json (its verdicts are what
a before/after comparison checks: ``--compare OLD.json NEW.json``).

Section "truth" (``--truth``, session hilltrust): the verdicts against the time integrator's
monodromy (:func:`sarfe.hbm.stability.perturbation.perturbation_check`) over the whole sweep of
cases/rattle_rig.yaml (H = 10, N = 256, defaults): per point the full Hill method, the contact-row
count at H alone and the default (``auto``: the count checked at ⌊3H/4⌋,
:mod:`sarfe.hbm.stability.trust`) with their CPU times; the integrator at 1024 steps per period on
every point where full and count differ plus every 6th other one, at 2048 steps where its
verdict disagrees with the count or the default label (and where an earlier run left one), and
at 4096 where both disagree with the default label. An
integrator verdict counts as truth only where its shooting closed the orbit (periodicity ≤ 10⁻³)
and the verdicts at all its step counts agree. Integrator results are
kept in results/stability_truth.json and reused by reruns (keyed by frequency and steps).

Section "zeros" (``--zeros POINTS.pkl``, session hillzeros): on captured orbits
(benchmarks/tools/stability_counts.py capture) the points where the count finds two or more exponents
right of −ε: the default verdict with the zeros located (sarfe/hbm/stability/zeros.py) and its
CPU, the Ritz hand-over it replaces, and the full nonlinear Hill problem on all reduced DOFs
started at the located leading exponent. → results/stability_zeros.json.

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/engine/bench_stability.py [--skip-full] [--rows] [--sweep]
[--truth] [--zeros POINTS.pkl …]
"""
import json
import os
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import RESULTS, ROOT, write_results  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from sarfe.hbm.residual import Problem, full_residual  # noqa: E402
from sarfe.hbm.stability.select import contact_damping  # noqa: E402
from sarfe.hbm.stability.hill import hill_stability  # noqa: E402
from sarfe.hbm.stability.condensed import condensed_stability  # noqa: E402
from sarfe.hbm.stability.contact_terms import ContactOperator  # noqa: E402
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model  # noqa: E402
from sarfe.pipeline.solve.points import solve_point, solver_options  # noqa: E402


def case_at(path, mesh=None, harmonics=None, samples=None, sweep=None, solver=None):
    """The case file ``path`` loaded through an edited temporary copy next to it: the generator's
    mesh size ``mesh`` [m], solver.harmonics / samples_per_period, another sweep band
    {start_hz, end_hz}, further solver keys; stability off unless ``solver`` says otherwise."""
    path = pathlib.Path(path)
    data = yaml.safe_load(open(ROOT / path))
    if mesh:
        data["model"]["fe"]["generator"]["mesh_size_m"] = mesh
    if harmonics:
        data["solver"]["harmonics"] = harmonics
    if samples:
        data["solver"]["samples_per_period"] = samples
    if sweep is not None:
        data["excitation"]["sweep"] = sweep
    data["solver"]["stability"] = False
    data["solver"].update(solver or {})
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


def rows_cost(path="cases/door_trim_p1.yaml", mesh=0.015, band=(60.0, 65.0)):
    """Per point of a P1 sweep: CPU s of contact_row_stability, det F evaluations, LU order."""
    import sarfe.hbm.stability.rows as rows_module
    from sarfe.hbm import continuation
    from sarfe.hbm.modal import cached_modal_basis
    from sarfe.pipeline.solve.points import solver_options

    case = case_at(path, mesh, sweep={"start_hz": band[0], "end_hz": band[1]},
                   solver={"continuation": {"initial_step": 0.04, "max_step": 0.04}})
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    H, N = case.data["solver"]["harmonics"], case.data["solver"]["samples_per_period"]
    _, cont = solver_options(case)
    sols = [s for s in continuation(nl.model, nl.contacts, nl.excitation, 2 * np.pi * band[0],
                                    2 * np.pi * band[1], H, N, options=cont) if s.converged]
    cached_modal_basis(nl.model)
    counted, orders = [], []
    original_count, original_init = rows_module.winding_counts, rows_module.ContactRowDeterminant.__init__

    def count(*args, **kwargs):
        out = original_count(*args, **kwargs)
        counted.append(out[1])
        return out

    def init(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        orders.append(self.size)

    rows_module.winding_counts, rows_module.ContactRowDeterminant.__init__ = count, init
    points = []
    try:
        for s in sols:
            problem = Problem(nl.model, nl.contacts, nl.excitation, H, s.samples_per_period)
            ev = full_residual(problem, s.displacement.ravel(), s.omega)
            op = ContactOperator(problem, s.displacement, s.omega, ev.forces)
            t = time.process_time()
            r = rows_module.contact_row_stability(nl.model, nl.contacts, s.omega, H, ev.forces, op)
            points.append(dict(frequency_hz=s.omega / (2 * np.pi), cpu_s=time.process_time() - t,
                               evaluations=counted[-1] if counted else 0,
                               lu_order=orders[-1] if orders else 0,
                               verdict=None if r is None else r.stable))
    finally:
        rows_module.winding_counts, rows_module.ContactRowDeterminant.__init__ = \
            original_count, original_init
    return {"case": f"{path} at {mesh * 1e3:g} mm, {band[0]:g}-{band[1]:g} Hz, H = {H}, N = {N}",
            "reduced_dofs": nl.model.dof_count, "contact_rows": nl.contacts.row_count,
            "points": points}


def sweep_cost(path="cases/door_trim_p1.yaml", mesh=0.015):
    """Per point of the whole P1 sweep at ``mesh``: the deferred Hill stability computed serially,
    with its det F evaluations by phase (module docstring)."""
    import sarfe.hbm.stability.select as solve_module
    import sarfe.hbm.stability.rows as rows_module
    from sarfe.hbm.stability.deferred import deferred_stability, pending, stability_of
    from sarfe.pipeline.solve.pruned_points import solve_points_pruned

    case = case_at(path, mesh, solver={"stability": True})
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    with deferred_stability() as jobs:
        solutions, _ = solve_points_pruned(case.config.solver, case.config.excitation, nl)
    jobs = [jobs[i] for i in pending(solutions)]

    phase, counts = ["contour"], {}
    original_ld = rows_module.ContactRowDeterminant.log_determinants
    original_zero, original_ritz = rows_module.real_zero, solve_module.condensed_stability
    original_count = solve_module.contact_row_counts

    def log_determinants(self, s, *args, **kwargs):
        counts[phase[0]] = counts.get(phase[0], 0) + np.atleast_1d(s).size
        return original_ld(self, s, *args, **kwargs)

    def real_zero(*args, **kwargs):
        phase[0] = "real_zero"
        try:
            return original_zero(*args, **kwargs)
        finally:
            phase[0] = "contour"

    def contact_row_counts(*args, **kwargs):
        out = original_count(*args, **kwargs)
        counts["zeros"], counts["check_zeros"] = out[1], out[2]
        return out

    def ritz(*args, **kwargs):
        counts["ritz"] = True
        return original_ritz(*args, **kwargs)

    rows_module.ContactRowDeterminant.log_determinants = log_determinants
    rows_module.real_zero, solve_module.condensed_stability = real_zero, ritz
    solve_module.contact_row_counts = contact_row_counts
    points = []
    try:
        for job in jobs:
            counts.clear()
            t = time.process_time()
            r = stability_of(job)
            points.append(dict(frequency_hz=job.omega / (2 * np.pi), cpu_s=time.process_time() - t,
                               contour_evaluations=counts.get("contour", 0),
                               real_zero_evaluations=counts.get("real_zero", 0),
                               zeros=counts.get("zeros"), check_zeros=counts.get("check_zeros"),
                               ritz=counts.get("ritz", False),
                               verdict=r.stable, leading=r.leading, note=r.note))
    finally:
        rows_module.ContactRowDeterminant.log_determinants = original_ld
        rows_module.real_zero, solve_module.condensed_stability = original_zero, original_ritz
        solve_module.contact_row_counts = original_count
    H = case.data["solver"]["harmonics"]
    return {"case": f"{path} at {mesh * 1e3:g} mm, its sweep, H = {H}, defaults",
            "reduced_dofs": nl.model.dof_count, "contact_rows": nl.contacts.row_count,
            "load_average": os.getloadavg()[0], "points": points}


def sweep_lines(res):
    pts = res["points"]
    cpu = np.array([p["cpu_s"] for p in pts])
    contour = np.array([p["contour_evaluations"] for p in pts])
    paths = {}
    for p in pts:
        key = "Ritz" if p["ritz"] else f"{p['zeros']} zeros"
        paths[key] = paths.get(key, 0) + 1
    verdicts = {}
    for p in pts:
        verdicts[str(p["verdict"])] = verdicts.get(str(p["verdict"]), 0) + 1
    ritz = cpu[[p["ritz"] for p in pts]]
    return [SWEEP_HEADER, "",
            f"{res['case']}: {res['reduced_dofs']} reduced DOFs, {res['contact_rows']} contact "
            f"rows, {len(pts)} points (load average {res['load_average']:.1f} at the end). CPU per "
            f"point (process time): mean {cpu.mean():.3f} s, median {np.median(cpu):.3f} s, max "
            f"{cpu.max():.3f} s, total {cpu.sum():.1f} s (Ritz points {ritz.sum():.1f} s); det F "
            f"evaluations per point (contour) mean {contour.mean():.1f} (min {contour.min()}, max "
            f"{contour.max()}), real-zero search {sum(p['real_zero_evaluations'] for p in pts)} in "
            f"all; paths {paths}; verdicts {verdicts}.", ""]


def compare_sweeps(old, new):
    """Points whose verdict, count or leading exponent (10⁻⁴ relative) differ between two
    results/stability_sweep.json files of the same sweep."""
    a, b = (json.loads(pathlib.Path(p).read_text())["points"] for p in (old, new))
    assert len(a) == len(b), "not the same sweep"
    differ = [i for i, (x, y) in enumerate(zip(a, b))
              if x["verdict"] != y["verdict"] or x["zeros"] != y["zeros"]
              or abs(x["leading"] - y["leading"]) > 1e-4 * abs(x["leading"])]
    print(f"{len(a)} points, {len(differ)} differences: {differ}")
    return differ


SWEEP_HEADER = "## The whole P1 sweep at 15 mm, per point (issue 15 P1, session hilltrack)"


def rows_lines(res):
    pts = res["points"]
    cpu = np.array([p["cpu_s"] for p in pts])
    ev = np.array([p["evaluations"] for p in pts])
    verdicts = {str(v): sum(1 for p in pts if str(p["verdict"]) == str(v)) for v in
                {p["verdict"] for p in pts}}
    return [ROWS_HEADER, "",
            f"{res['case']}: {res['reduced_dofs']} reduced DOFs, {res['contact_rows']} contact rows, "
            f"{len(pts)} points. CPU per point (process time, this run): mean {cpu.mean():.3f} s, "
            f"median {np.median(cpu):.3f} s, max {cpu.max():.3f} s; det F evaluations per point "
            f"mean {ev.mean():.1f} (min {ev.min()}, max {ev.max()}); LU order "
            f"{sorted({p['lu_order'] for p in pts})}; verdicts {verdicts} (None: handed over to "
            "the Ritz method).", ""]


ROWS_HEADER = "## Contact-row count per point (issue 15 P1)"

# measured in session "hillfast" (not regenerated by this script): see docs/performance.md
ROWS_BEFORE_AFTER = """Before → after (session hillfast, the same 46 converged points of cases/door_trim_p1.yaml at
15 mm, 60 → 65 Hz, continuation step 0.04, H = 15, N = 256; 589 reduced DOFs, 19 contact rows,
15 loaded: LU order 465; 38.2 det F evaluations per point, unchanged): see docs/performance.md
("Hill stability on the contact rows") for the per-point numbers and the machine load."""


# measured in session hilltrack (not regenerated by this script): see docs/performance.md
SWEEP_BEFORE_AFTER = """Before → after (session hilltrack; main and the branch alternated,
A B A B, on the same 71 points of this sweep — every 3rd and the three that are not 'no zero' —,
CPU s per point at load ≈ 1): 0.545 / 0.538 → 0.345 / 0.341; no-zero points 0.307 → 0.270 s
(contour evaluations 38.8 → 37.8, 7.17 → 6.51 ms each); the one-zero point 1.21 → 0.49 s
(real-zero search 116 → 17 evaluations); the two Ritz points 8.2 → 2.7 s. P1 at 5 mm
(solve_case, 2 workers, load 1.4–1.7): Hill stability 39.1 → 29.7 s wall, verdicts and exponents
of its 204 points equal. Verdicts, zero counts and leading exponents of all 206 points of this
sweep equal (leading to 2e-6). Details: docs/performance.md ("Hill stability along the P1
sweep")."""


def write_rows_section(lines):
    """Replace the contact-row section of results/stability.md (keep the sections before it and
    the sweep section after it)."""
    path = RESULTS / "stability.md"
    text = path.read_text() if path.exists() else ""
    head = text.split(ROWS_HEADER)[0].rstrip("\n")
    tail = SWEEP_HEADER + text.split(SWEEP_HEADER, 1)[1] if SWEEP_HEADER in text else ""
    path.write_text((head + "\n\n" if head else "") + "\n".join(lines + [ROWS_BEFORE_AFTER, ""])
                    + ("\n" + tail if tail else ""))


def write_sweep_section(lines):
    """Replace the sweep section of results/stability.md (keep everything before it)."""
    path = RESULTS / "stability.md"
    text = path.read_text() if path.exists() else ""
    head, _, rest = text.partition(SWEEP_HEADER)
    head = head.rstrip("\n")
    tail = "## " + rest.split("\n## ", 1)[1] if "\n## " in rest else ""   # (the truth sections)
    path.write_text((head + "\n\n" if head else "") + "\n".join(lines + [SWEEP_BEFORE_AFTER, ""])
                    + ("\n" + tail if tail else ""))


TRUTH_HEADER = "## Verdicts against time integration: the rattle rig's whole sweep (session hilltrust)"
TRUTH_PERIODICITY = 1e-3     # shooting residual above which the integrator's verdict is no truth


def truth_study(path="cases/rattle_rig.yaml", every=6):
    """The rattle rig's sweep with the default options (stability deferred), then per point the
    labels of three stability paths and, on the selected points, the integrator's verdict."""
    from sarfe.hbm.stability.deferred import deferred_stability, stability_of
    from sarfe.hbm.stability.perturbation import perturbation_check
    from sarfe.pipeline.solve.pruned_points import solve_points_pruned
    from dataclasses import replace

    case = case_at(path, solver={"stability": True})
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    with deferred_stability() as jobs:
        solutions, _ = solve_points_pruned(case.config.solver, case.config.excitation, nl)
    saved = RESULTS / "stability_truth.json"
    cache = {}

    def read_saved():             # (re-read before each integration: another run may fill it)
        if saved.exists():
            for p in json.loads(saved.read_text())["points"]:
                for key, value in p.get("time_integration", {}).items():
                    cache[(round(p["frequency_hz"], 6), int(key))] = value
    import sarfe.hbm.stability.select as trust     # (its bound name 'checked' is patched)

    def label(job, method, check=True):
        original = trust.checked
        if not check:
            trust.checked = lambda result, *args, **kwargs: result
        try:
            t = time.process_time()
            r = stability_of(replace(job, options=replace(job.options, stability_method=method)))
            return dict(stable=r.stable, leading=r.leading, note=r.note,
                        cpu_s=time.process_time() - t)
        finally:
            trust.checked = original

    points = []
    for s in solutions:
        job = jobs[s.stability_job]
        points.append(dict(frequency_hz=s.omega / (2 * np.pi), full=label(job, "full"),
                           count=label(job, "contact_rows", check=False),
                           auto=label(job, "auto")))
        print(points[-1]["frequency_hz"], {k: points[-1][k]["stable"] for k in
                                            ("full", "count", "auto")}, flush=True)
    differ = [i for i, p in enumerate(points) if p["full"]["stable"] != p["count"]["stable"]]
    others = [i for i in range(len(points)) if i not in differ][::every]
    for i in sorted(differ + others):
        p, s = points[i], solutions[i]
        p["time_integration"] = {}
        read_saved()
        for steps in (1024, 2048, 4096):
            key = (round(p["frequency_hz"], 6), steps)
            seen = {r["stable"] for r in p["time_integration"].values()}
            if steps == 2048 and key not in cache and all(
                    p[m]["stable"] in (None, *seen) for m in ("count", "auto")):
                continue              # (the full method's own disagreements: where cached)
            if steps == 4096 and (len(seen) > 1 or p["auto"]["stable"] in (None, *seen)):
                continue              # only where 1024 and 2048 agree against a default label
            if key not in cache:
                t = time.process_time()
                c = perturbation_check(nl.model, nl.contacts, nl.excitation, s,
                                       steps_per_period=steps)
                cache[key] = dict(stable=c.stable, rate=c.rate, periodicity=c.periodicity,
                                  cpu_s=time.process_time() - t)
            p["time_integration"][str(steps)] = cache[key]
        print(p["frequency_hz"], p["time_integration"], flush=True)
    H = case.data["solver"]["harmonics"]
    return {"case": f"{path}, H = {H}, N = {case.data['solver']['samples_per_period']}, defaults",
            "reduced_dofs": nl.model.dof_count, "contact_rows": nl.contacts.row_count,
            "load_average": os.getloadavg()[0], "points": points}


def truth_study_nlvib03():
    """NLvib example 03 (H = 21, N = 1024; tests/hbm/test_solver.py's model), its continuation
    0.5 → 0.8 with the default options (stability deferred): per point the three labels and the
    integrator at 1024 and 2048 steps per period on every point (2 DOFs: cheap)."""
    from dataclasses import replace
    from sarfe.hbm import ContinuationOptions, continuation
    from sarfe.hbm.stability.deferred import deferred_stability, stability_of
    from sarfe.hbm.stability.perturbation import perturbation_check
    import sarfe.hbm.stability.select as trust     # (its bound name 'checked' is patched)
    sys.path.insert(0, str(ROOT))
    from tests.hbm.test_solver import H03, N03, example03

    model, contacts, F = example03()
    with deferred_stability() as jobs:
        solutions = continuation(model, contacts, F, 0.5, 0.8, H03, N03,
                                 options=ContinuationOptions(max_step=0.3))
    points = []
    for s in solutions:
        job = jobs[s.stability_job]
        p = dict(frequency_hz=s.omega / (2 * np.pi), omega=s.omega)
        for name, method, check in (("full", "full", True), ("count", "contact_rows", False),
                                    ("auto", "auto", True)):
            original = trust.checked
            if not check:
                trust.checked = lambda result, *args, **kwargs: result
            try:
                t = time.process_time()
                r = stability_of(replace(job, options=replace(job.options,
                                                              stability_method=method)))
                p[name] = dict(stable=r.stable, leading=r.leading, note=r.note,
                               cpu_s=time.process_time() - t)
            finally:
                trust.checked = original
        p["time_integration"] = {}
        for steps in (1024, 2048):
            c = perturbation_check(model, contacts, F, s, steps_per_period=steps)
            p["time_integration"][str(steps)] = dict(stable=c.stable, rate=c.rate,
                                                    periodicity=c.periodicity)
        points.append(p)
        print(p["omega"], {k: p[k]["stable"] for k in ("full", "count", "auto")},
              p["time_integration"], flush=True)
    return {"case": f"NLvib example 03, H = {H03}, N = {N03}, continuation 0.5 → 0.8 rad/s",
            "reduced_dofs": 2, "contact_rows": 1, "load_average": os.getloadavg()[0],
            "points": points}


def truth_of(p):
    """The integrator's verdict at a point (True/False), or None when not computed or not
    converged (shooting residual above ``TRUTH_PERIODICITY``, or 1024 and 2048 steps differ)."""
    runs = p.get("time_integration") or {}
    if not runs or any(r["periodicity"] > TRUTH_PERIODICITY for r in runs.values()):
        return None
    verdicts = {r["stable"] for r in runs.values()}
    return verdicts.pop() if len(verdicts) == 1 else None


def truth_lines(res):
    pts = res["points"]
    sym = {True: "stable", False: "unstable", None: "uncertain"}
    lines = [TRUTH_HEADER, "",
             f"{res['case']}: {res['reduced_dofs']} reduced DOFs, {res['contact_rows']} contact "
             f"row(s), {len(pts)} points (load average {res['load_average']:.1f} at the end). "
             "full: the Hill eigenproblem on all reduced DOFs (2n smallest |Im s| + the strip); "
             "count: the contact-row count at H (Ritz method where it finds ≥ 2 zeros), no check; "
             "auto: the default — the count checked at ⌊3H/4⌋ (sarfe/hbm/stability/trust.py). "
             "TI: the integrator's monodromy (perturbation_check) at 1024 steps per period, "
             "2048 where it disagrees with count or auto (or cached), 4096 where both disagree "
             "with auto; 'n.c.': "
             f"shooting residual > {TRUTH_PERIODICITY:g} or the step counts disagree (no truth).",
             ""]
    for m in ("full", "count", "auto"):
        cpu = np.array([p[m]["cpu_s"] for p in pts])
        counts = {sym[v]: sum(1 for p in pts if p[m]["stable"] is v) for v in (True, False, None)}
        tally = {"agree": 0, "uncertain": 0, "contradict": 0}
        for p in pts:
            t = truth_of(p)
            if t is None:
                continue
            v = p[m]["stable"]
            tally["agree" if v is t else "uncertain" if v is None else "contradict"] += 1
        lines.append(f"- {m}: {counts} over the sweep; CPU {cpu.sum():.1f} s "
                     f"({1e3 * cpu.mean():.1f} ms per point); against converged TI: {tally}")
    checked_points = [p for p in pts if p.get("time_integration")]
    lines += ["", f"{len(checked_points)} points with the integrator, "
              f"{sum(truth_of(p) is not None for p in checked_points)} with a converged verdict:", "",
              "| f [Hz] | full (max Re s) | count (max Re s) | auto | TI 1024 rate [1/s] "
              "(periodicity) | TI 2048 / 4096 rate | truth |", "|---|---|---|---|---|---|---|"]
    for p in checked_points:
        ti = p["time_integration"]
        rate2 = " / ".join(f"{ti[k]['rate']:+.3g}" for k in ("2048", "4096") if k in ti) or "-"
        lines.append(
            f"| {p['frequency_hz']:.3f} | {sym[p['full']['stable']]} ({p['full']['leading']:.3g}) "
            f"| {sym[p['count']['stable']]} ({p['count']['leading']:.3g}) | "
            f"{sym[p['auto']['stable']]} | {ti['1024']['rate']:+.3g} "
            f"({ti['1024']['periodicity']:.1e}) | "
            f"{rate2} | "
            f"{'n.c.' if truth_of(p) is None else sym[truth_of(p)]} |")
    return lines + [""]


def write_truth_nlvib_section(lines):
    """The NLvib 03 truth table under its own header (after the rattle rig's)."""
    lines = [NLVIB_HEADER] + lines[1:]
    path = RESULTS / "stability.md"
    text = path.read_text() if path.exists() else ""
    head, _, rest = text.partition(NLVIB_HEADER)
    tail = "## " + rest.split("\n## ", 1)[1] if rest and "\n## " in rest else ""
    path.write_text(head.rstrip("\n") + "\n\n" + "\n".join(lines) + ("\n" + tail if tail else ""))


NLVIB_HEADER = "## Verdicts against time integration: NLvib example 03 (session hilltrust)"


def write_truth_section(lines):
    """Replace (or append) the truth section of results/stability.md."""
    path = RESULTS / "stability.md"
    text = path.read_text() if path.exists() else ""
    head, _, rest = text.partition(TRUTH_HEADER)
    tail = ""
    if rest and "\n## " in rest:
        tail = "## " + rest.split("\n## ", 1)[1]
    path.write_text(head.rstrip("\n") + "\n\n" + "\n".join(lines) + ("\n" + tail if tail else ""))


ZEROS_HEADER = "## Two or more zeros right of −ε, located (issue 15 P1, session hillzeros)"


def zeros_study(points_paths):
    """Per captured point (benchmarks/tools/stability_counts.py capture) where the count finds two or
    more exponents right of −ε: the default verdict (the zeros located,
    sarfe/hbm/stability/zeros.py) and its CPU, the same with the locator stubbed to fail (the
    Ritz method of the hand-over, as before), and the full nonlinear Hill problem on all reduced
    DOFs started at the located leading exponent (refine_exponent: the full method's own secant
    iteration on T(s); its ARPACK selection, the exponents nearest 0, misses a pair near
    Im s = ω/2 on P1)."""
    import pickle
    import types
    import scipy.sparse as sp
    import sarfe.hbm.stability.select as solve_module
    import sarfe.hbm.stability.rows as rows_module
    from sarfe.hbm.aft import jacobian_matrix
    from sarfe.hbm.dynamic_stiffness import dynamic_stiffness_matrix
    from sarfe.hbm.stability.hill import _hill, refine_exponent
    from sarfe.hbm.stability.trust import check_harmonics

    records = []
    for path in points_paths:
        with open(path, "rb") as f:
            records += pickle.load(f)
    points = []
    for problem, omega, U, forces, options in records:
        op = ContactOperator(problem, U, omega, forces)
        _, zeros, _ = rows_module.contact_row_counts(
            problem.model, problem.contacts, omega, problem.harmonics, forces, op,
            tolerance=options.stability_tolerance,
            check_harmonics=check_harmonics(problem.harmonics))
        if not zeros or zeros < 2:
            continue
        ev = types.SimpleNamespace(forces=forces, jacobian=None)
        labels = {}
        for name in ("located", "ritz"):
            original = rows_module.leading_zeros
            if name == "ritz":
                rows_module.leading_zeros = lambda *args, **kwargs: None
            try:
                t = time.process_time()
                r = solve_module.stability(problem, omega, U, ev, options)
                labels[name] = dict(stable=r.stable, leading=r.leading, note=r.note,
                                    cpu_s=time.process_time() - t, exponents=r.exponents)
            finally:
                rows_module.leading_zeros = original
        lead = labels["located"]["exponents"]
        lead = lead[np.argmax(lead.real)]
        lead = lead.conjugate() if lead.imag < 0 else lead
        H, G = problem.harmonics, problem.contacts.gap_map
        GG = sp.kron(sp.identity(2 * H + 1), G, format="csr")
        jacobian = (sp.csr_matrix(dynamic_stiffness_matrix(problem.model, omega, H))
                    + GG.T @ jacobian_matrix(forces.blocks, G.shape[0], H) @ GG
                    + op.correction(0.0).real)
        Mt, Dt = _hill(problem.model, omega, H, contact_damping(problem, forces))
        t = time.process_time()
        full, converged = refine_exponent(Mt, Dt, jacobian, op, lead, dense=False)
        for label in labels.values():
            label.pop("exponents")
        points.append(dict(frequency_hz=omega / (2 * np.pi), zeros=zeros,
                           reduced_dofs=problem.model.dof_count, **labels,
                           located_exponent=[lead.real, lead.imag],
                           full_exponent=[full.real, full.imag], full_converged=bool(converged),
                           full_cpu_s=time.process_time() - t))
        print(points[-1], flush=True)
    return {"case": ", ".join(str(p) for p in points_paths),
            "load_average": os.getloadavg()[0], "points": points}


def zeros_lines(res):
    lines = [ZEROS_HEADER, "",
             f"Captured orbits {res['case']} (load {res['load_average']:.1f}; CPU seconds per "
             "point). located: the default (the zeros "
             "right of −ε located from the count's samples); Ritz: the same with the locator "
             "stubbed to fail (the hand-over before this session); full: the nonlinear Hill "
             "problem on all reduced DOFs started at the located leading exponent.", "",
             "| f [Hz] | reduced DOFs | zeros | located: verdict (leading) | CPU | Ritz: verdict "
             "(leading) | CPU | located exponent | full exponent (converged) | full CPU |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for p in res["points"]:
        a, b = p["located"], p["ritz"]
        z, w = complex(*p["located_exponent"]), complex(*p["full_exponent"])
        lines.append(f"| {p['frequency_hz']:.4f} | {p['reduced_dofs']} | {p['zeros']} | {a['stable']} "
                     f"({a['leading']:.4g}) | {a['cpu_s']:.2f} | {b['stable']} ({b['leading']:.4g}) "
                     f"| {b['cpu_s']:.2f} | {z:.4f} | {w:.4f} ({p['full_converged']}) | "
                     f"{p['full_cpu_s']:.0f} |")
    return lines


def write_zeros_section(lines):
    """Replace (or append at the end) the zeros section of results/stability.md."""
    path = RESULTS / "stability.md"
    text = path.read_text() if path.exists() else ""
    head, _, rest = text.partition(ZEROS_HEADER)
    tail = "## " + rest.split("\n## ", 1)[1] if "\n## " in rest else ""
    path.write_text(head.rstrip("\n") + "\n\n" + "\n".join(lines) + "\n" + ("\n" + tail if tail else ""))


def main():
    if "--compare" in sys.argv:
        i = sys.argv.index("--compare")
        compare_sweeps(sys.argv[i + 1], sys.argv[i + 2])
        return
    if "--zeros" in sys.argv:          # --zeros POINTS.pkl … (benchmarks/tools/stability_counts.py capture)
        res = zeros_study(sys.argv[sys.argv.index("--zeros") + 1:])
        write_results("stability_zeros", res, default=str)
        write_zeros_section(zeros_lines(res))
        print("\n".join(zeros_lines(res)))
        return
    for flag, run, name, write, table in (
            ("--sweep", sweep_cost, "stability_sweep", write_sweep_section, sweep_lines),
            ("--rows", rows_cost, "stability_rows", write_rows_section, rows_lines),
            ("--truth-nlvib03", truth_study_nlvib03, "stability_truth_nlvib03",
             write_truth_nlvib_section, truth_lines),
            ("--truth", truth_study, "stability_truth", write_truth_section, truth_lines)):
        if flag in sys.argv:
            res = run()
            write_results(name, res, default=str)
            write(table(res))
            print("\n".join(table(res)))
            return
    skip_full = "--skip-full" in sys.argv
    results = [compare("squeak_rig", "cases/squeak_rig.yaml", [50.0, 100.0, 150.0]),
               compare("door_trim 10 mm H=5", "cases/door_trim.yaml", [40.0, 52.0, 67.0, 80.0, 95.0],
                       full=not skip_full, mesh=0.01, harmonics=5)]
    write_results("stability", results, default=str)
    lines = ["# Hill stability per point: full vs condensed (contact rows)", "",
             "Main (frozen): the Hill eigenproblem on all reduced DOFs with the Newton Jacobian as main had it. "
             "Full: the Hill eigenproblem on all reduced DOFs (dense or ARPACK shift-invert as on main, "
             "plus the friction-memory refinement of the leading exponents). "
             "Condensed: the same Hill problem on a Ritz basis of the averaged linearization's modes "
             "up to 2(H+1)ω (10 … 40) + the contacts' static responses, friction memory included "
             "(sarfe/hbm/stability/condensed.py).", ""]
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
    write_results("stability", markdown=lines)
    saved = RESULTS / "stability_rows.json"
    if saved.exists():                  # keep the contact-row section of the last --rows run
        write_rows_section(rows_lines(json.loads(saved.read_text())))
    saved = RESULTS / "stability_sweep.json"
    if saved.exists():                  # and the sweep section of the last --sweep run
        write_sweep_section(sweep_lines(json.loads(saved.read_text())))


if __name__ == "__main__":
    main()
