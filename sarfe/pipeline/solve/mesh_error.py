r"""The mesh term of a run's ± (issue 29 item 4): the loudest point re-solved on two generated
meshes of √2 and 2 times the element size, the three levels L_h, L_√2h, L_2h (dB and dB(A)) turned
into a grid convergence index (:func:`sarfe.accuracy.mesh_refinement.mesh_gci`, (2) there):

    monotone, observed p = ln(ε₃₂/ε₂₁)/ln √2 in [1, 2]:  mesh_db = 1.25·|L_√2h − L_h| / (√2^p − 1)
    monotone, p outside [1, 2] (pre-asymptotic): 1.25·ΔM;       oscillatory: 3·ΔM

(ΔM the range of the three levels; Roache's Fs = 1.25 for three meshes, Eça & Hoekstra's 3·ΔM
where the levels oscillate; the larger of the dB and dB(A) estimates). Where the middle mesh
fails (or its contacts are on another branch) the two meshes h, 2h give Richardson with p = 1
stated, |L_h − L_2h| / (2 − 1) ((1) there, method 'two meshes').

Each re-solve: one linear stage built on the coarser mesh (the case's reduction rule and cutoff,
so the modal basis covers the same band) and one Newton solve of the harmonic balance at the
loudest point's ω, H, N, started from the linear response to the fine point's contact forces
(same contact rows), else from the linear response. Where the 2h mesh's contacts are in a
different state at ω (one closes, the other does not: the mesh moved the contact onset, e.g. a
rattle near its fold) the level change is no estimate: the term is "not estimated" with that
reason. The term is measured at the loudest point and added to every estimated point's ERP bound
(``error_estimate.mesh_db``, ``erp_db`` includes it): the headline carries it where it was
measured; elsewhere it stands for the mesh error of the run. Cost: the two re-solves (≈ ¼ and ½
of the fine mesh's DOFs), ``timings_s.mesh_error_s``. Their linear stages do not depend on the
loudest point: with two or more workers (``solver.workers``) :func:`start_coarse_levels` builds
them on one background process forked before the fine linear stage, on the core the fine stage
and the one-core sweep leave idle, and only the two Newton solves are left after the sweep
(``timings_s.mesh_error_build_s`` / ``mesh_error_solve_s``: the background's seconds); with one
worker they are built after the sweep in this process. Both paths compute the same numbers.

Only generated meshes (``model.fe.generator``) have a coarser mesh to build: for decks, given
meshes and matrices models the term is "not estimated" and said so (``solver.mesh_error``:
'auto' = on for generator meshes, true = required, false = off).
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import time
import warnings

import numpy as np

from sarfe.accuracy.mesh_refinement import (MESH_GCI_RATIO, MESH_ORDER, mesh_gci,
                                             mesh_richardson)
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.time_integration import linear_harmonic_response
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.post.records import loudest_point, point_erp
from sarfe.util.workers import Background, map_points, release_memory, worker_count


def mesh_error_reason(case) -> str | None:
    """Why the mesh term is not estimated for ``case`` (None: it is): switched off, or no
    generated mesh to coarsen (deck, given mesh, matrices)."""
    setting = case.config.solver.mesh_error
    if setting is False:
        return "not estimated (solver.mesh_error: false)"
    fe = case.config.model.fe
    if fe is None:
        return "not estimated (a matrices model has no mesh)"
    if fe.source != "generator" or not (fe.generator.mesh_size_m or 0) > 0:
        return (f"not estimated (a {fe.source} mesh: no coarser mesh to re-solve on; the level's "
                "mesh error is not in the ±)")
    return None


def touches(solution) -> bool:
    """Whether any contact carries force over the period (max |λ(t)| > 0)."""
    force = np.asarray(solution.contact_force_time, dtype=float)
    return bool(force.size and np.max(np.abs(force)) > 0.0)


def coarse_start(nl_coarse, solution, H):
    """Starting ũ (2H+1, n_c) on the coarser model: the linear response to f̃_e − Gᵀλ̃ of the fine
    point's contact forces λ̃ when the contact rows match, else None (the linear guess)."""
    lam = np.asarray(solution.contact_force, dtype=float)
    if lam.ndim != 2 or lam.shape[1] != nl_coarse.contacts.row_count or lam.shape[0] != 2 * H + 1:
        return None
    F = nl_coarse.excitation - np.asarray(nl_coarse.contacts.gap_map.T @ lam.T).T
    return linear_harmonic_response(nl_coarse.model, F, solution.omega)


def coarse_model(case, mesh_size_m):
    """The linear stage and nonlinear model of ``case`` on a generated mesh of ``mesh_size_m``
    (the case's reduction rule and cutoff) → (stage, nl). Raises what building them raises."""
    coarse = case.with_generator(mesh_size_m=mesh_size_m)
    stage = build_linear_model(coarse)
    return stage, nonlinear_model(coarse, stage)


def resolve_on(case, stage, nl, fine, mesh_size_m):
    """The fine point ``fine`` (a HarmonicSolution) re-solved on the coarser model ``stage``,
    ``nl`` (:func:`coarse_model` of ``mesh_size_m``): one Newton solve at its ω, H, N,
    warm-started by :func:`coarse_start` → {'mesh_size_m', 'level_db', 'level_dba',
    'converged', 'touching', 'nodes', 'reason'}."""
    solver = case.config.solver
    H, N = int(fine.harmonics), int(fine.samples_per_period)
    options = SolverOptions(tolerance=solver.tolerance, max_iterations=solver.max_iterations,
                            stability=False, harmonic_set=solver.harmonic_set)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = coarse_start(nl, fine, H)
        s = solve_frequency(nl.model, nl.contacts, nl.excitation, fine.omega, H, N,
                            initial=start, options=options)
        if not s.converged and start is not None:
            s = solve_frequency(nl.model, nl.contacts, nl.excitation, fine.omega, H, N,
                                options=options)
    erp, _ = point_erp(case.config.erp, stage, s.displacement, s.omega)
    return {"mesh_size_m": float(mesh_size_m), "level_db": float(erp.level_total_db),
            "level_dba": float(erp.level_total_a_db), "converged": bool(s.converged),
            "touching": touches(s), "nodes": int(stage.info.get("nodes", 0)),
            "reason": getattr(s, "reason", "")}


def resolve_coarser(case, fine, mesh_size_m):
    """The fine point ``fine`` re-solved on a generated mesh of ``mesh_size_m``: one linear stage
    (:func:`coarse_model`) and one Newton solve (:func:`resolve_on`). Raises what building the
    mesh or the model raises."""
    return resolve_on(case, *coarse_model(case, mesh_size_m), fine, mesh_size_m)


def failed_run(mesh_size_m, error) -> dict:
    """The record of a coarser level that could not be built or solved."""
    return {"mesh_size_m": mesh_size_m, "failed": f"{type(error).__name__}: {error}"}


def coarse_sizes(case, ratio=MESH_GCI_RATIO) -> tuple:
    """The coarser mesh sizes (r²h, r·h) [m] of the mesh term, the coarsest first."""
    h = float(case.config.model.fe.generator.mesh_size_m)
    return (ratio ** 2 * h, ratio * h)


def slim_stage(stage):
    """``stage`` with what :func:`resolve_on` reads after :func:`coarse_model` (the ERP map and
    areas, ``info``) and without the mesh and the reduction basis (the full-space Craig–Bampton
    shapes, n_full × n_r: the bulk of a stage), for a background process that holds it."""
    return dataclasses.replace(stage, mesh=None, reduced=None)


def start_coarse_levels(case, ratio=MESH_GCI_RATIO):
    """Start building the mesh term's coarser models now, on one background process
    (:class:`sarfe.util.workers.Background`), or None where the term is not due (error estimate
    or mesh term off, no generated mesh) or the case has one worker (``solver.workers``: the
    serial path builds them after the sweep). The coarser linear stages do not depend on the
    sweep: started before the fine linear stage (this process still small at the fork), they are
    built on the core the fine stage and the one-core sweep leave idle; after the sweep
    :func:`mesh_error_term` sends the loudest point there and gets the re-solves back (the same
    computation as on the serial path: same models, same start, one BLAS thread)."""
    solver = case.config.solver
    if not solver.error_estimate or mesh_error_reason(case) is not None \
            or worker_count(solver.workers) < 2:
        return None
    sizes = coarse_sizes(case, ratio)

    def prepare():          # the coarsest first: it decides whether the middle one is used
        built = {}
        for size in sizes:
            clock = time.perf_counter()
            try:
                stage, nl = coarse_model(case, size)
                built[size] = (slim_stage(stage), nl)
            except Exception as error:  # an estimate must not break a solve
                built[size] = error
            built[size, "build_s"] = time.perf_counter() - clock
        release_memory()     # it waits through the sweep: hold the models, not the build's heap
        return built

    return Background(prepare, functools.partial(_resolve_built, case))


def _resolve_built(case, built, message):
    """A :class:`Background` answer: the fine point re-solved on each prepared coarser model
    ({size: run record}, :func:`resolve_on`; a size not prepared is built here), each record with
    the seconds its model took to build ('build_s', in the background) and to solve ('solve_s')."""
    sizes, fine = message
    runs = {}
    for size in sizes:
        clock = time.perf_counter()
        try:
            model = built.get(size)
            if model is None:
                model = coarse_model(case, size)
            if isinstance(model, Exception):
                raise model
            runs[size] = resolve_on(case, *model, fine, size)
        except Exception as error:      # an estimate must not break a solve
            runs[size] = failed_run(size, error)
        runs[size].update(build_s=built.get((size, "build_s"), 0.0),
                          solve_s=time.perf_counter() - clock)
    return runs


def mesh_error_term(case, points, solutions, ratio=MESH_GCI_RATIO, background=None) -> dict:
    """The mesh term (module docstring) of a solved case: ``points`` the summary's point records,
    ``solutions`` their HarmonicSolutions → {'estimated', 'reason', 'mesh_db', 'method',
    'convergence', 'order', 'order_used', 'safety_factor', 'ratio', 'mesh_size_m',
    'coarse_mesh_sizes_m', 'coarse_levels_db', 'coarse_levels_dba', 'coarse_mesh_size_m' (the
    coarsest), 'coarse_level_db', 'coarse_level_dba', 'coarse_converged', 'coarse_nodes',
    'frequency_hz', 'level_db', 'level_dba', 'seconds'}. A failure (coarser mesh not built, Newton
    not converged) is reported as not estimated, never raised; where only the middle mesh fails,
    the two meshes h, 2h give (1) of :mod:`sarfe.accuracy.mesh_refinement` (method 'two meshes').
    ``background``: :func:`start_coarse_levels` of this case (its coarser models already built
    there; closed here), else the levels are built now."""
    with background if background is not None else contextlib.nullcontext():
        return _mesh_error_term(case, points, solutions, ratio, background)


def _mesh_error_term(case, points, solutions, ratio, background):
    clock = time.perf_counter()
    out = {"estimated": False, "mesh_db": float("nan"), "order": float("nan"),
           "ratio": float(ratio), "reason": mesh_error_reason(case)}
    if out["reason"] is not None:
        return out
    j = loudest_point(points)
    if j is None:
        out["reason"] = "not estimated (no converged, not unstable point)"
        return out
    fine = solutions[j]
    h = float(case.config.model.fe.generator.mesh_size_m)
    out.update(mesh_size_m=h, frequency_hz=points[j]["frequency_hz"],
               level_db=points[j]["erp"]["level_db"], level_dba=points[j]["erp"]["level_dba"])
    def run(size):
        try:
            return resolve_coarser(case, fine, size)
        except Exception as error:  # an estimate must not break a solve
            return failed_run(size, error)

    # the coarser models built in the background during the sweep (start_coarse_levels), else
    # the two coarser meshes at once on the case's workers (the coarsest, 2h, decides whether
    # the middle one is used); one process: the coarsest first, the middle only if it converged
    sizes = coarse_sizes(case, ratio)
    runs = background.ask((sizes, fine)) if background is not None else None
    answered = isinstance(runs, dict)
    if not answered:                         # no background, or its worker died
        workers = min(worker_count(case.config.solver.workers), len(sizes))
        runs = dict(zip(sizes, map_points(run, sizes, workers))) if workers > 1 else {}
    if not runs:
        runs[sizes[0]] = run(sizes[0])
        if "failed" not in runs[sizes[0]] and runs[sizes[0]]["converged"]:
            runs[sizes[1]] = run(sizes[1])
    coarsest = runs[ratio ** 2 * h]
    middle = runs.get(ratio * h, {"mesh_size_m": ratio * h, "failed": "not solved"})
    runs = [middle, coarsest]
    if answered:     # timings_s (popped by the caller): the background's seconds
        out["timings_s"] = {f"mesh_error_{k}": sum(r.get(k, 0.0) for r in runs)
                            for k in ("build_s", "solve_s")}
    out.update(coarse_mesh_size_m=coarsest["mesh_size_m"],
               coarse_mesh_sizes_m=[r["mesh_size_m"] for r in runs],
               coarse_levels_db=[r.get("level_db") for r in runs],
               coarse_levels_dba=[r.get("level_dba") for r in runs],
               coarse_level_db=coarsest.get("level_db"), coarse_level_dba=coarsest.get("level_dba"),
               coarse_converged=coarsest.get("converged"), coarse_nodes=coarsest.get("nodes"),
               seconds=time.perf_counter() - clock)
    size_mm = f"{1e3 * coarsest['mesh_size_m']:.3g} mm"
    if "failed" in coarsest:
        out["reason"] = f"not estimated (the {size_mm} mesh failed: {coarsest['failed']})"
        return out
    if not coarsest["converged"]:
        out["reason"] = (f"not estimated (the re-solve on the {size_mm} mesh did not converge: "
                         f"{coarsest['reason']})")
        return out
    fine_touching = touches(fine)
    if coarsest["touching"] != fine_touching:   # one mesh's contacts close at ω, the other's do not
        out["reason"] = (f"not estimated: at {out['frequency_hz']:.2f} Hz the {size_mm} mesh's "
                         f"contacts {'do not close' if fine_touching else 'close'} "
                         f"({coarsest['level_dba']:.1f} against {out['level_dba']:.1f} dB(A)): "
                         "another branch, its level change is no Richardson estimate (the mesh "
                         "moves the contact onset; refine the mesh or compare the sweeps with "
                         "`sarfe study --knobs mesh`)")
        return out
    if "failed" in middle or not middle["converged"] or middle["touching"] != fine_touching:
        mesh_db = max(mesh_richardson(out[k], coarsest[k], MESH_ORDER, ratio ** 2)
                      for k in ("level_db", "level_dba"))
        out.update(method="two meshes", order=MESH_ORDER, order_used=MESH_ORDER,
                   convergence=None, safety_factor=float("nan"),
                   middle_reason=middle.get("failed") or "not converged or another branch")
    else:
        gci = max((mesh_gci([out[k], middle[k], coarsest[k]], ratio)
                   for k in ("level_db", "level_dba")), key=lambda g: g["mesh_db"])
        mesh_db = gci["mesh_db"]
        out.update(method="three meshes", **{k: v for k, v in gci.items() if k != "mesh_db"})
    out.update(estimated=bool(np.isfinite(mesh_db)), mesh_db=float(mesh_db), reason=None)
    return out


def with_mesh_term(points, rows, term) -> None:
    """Add the mesh term to every point's estimate (``mesh_db``; ``erp_db`` += it, keeping its
    sign convention of a bound) and the table's ±dB; nothing when it was not estimated."""
    if not term.get("estimated"):
        return
    m = float(term["mesh_db"])
    for point, row in zip(points, rows):
        e = point.get("error_estimate")
        if not isinstance(e, dict) or "failed" in e or "erp_db" not in e:
            continue
        e["mesh_db"] = m
        e["erp_db"] = abs(float(e["erp_db"])) + m
        row["erp_error_db"] = e["erp_db"]


def mesh_checked(check: dict | None, term: dict, case) -> dict | None:
    """The run's accuracy check (:func:`sarfe.pipeline.solve.case_accuracy.accuracy_check`) with
    the mesh term's failure counted: where the term was due (a generated mesh, on) but could not be
    estimated, the budget is not 'met' and the warning says why."""
    if check is None or term.get("estimated") or mesh_error_reason(case) is not None:
        return check
    check = dict(check, met=False)
    check["warning"] = ((check["warning"] + "; ") if check.get("warning") else "accuracy: ") + \
        f"mesh error {term.get('reason') or 'not estimated'}"
    return check


def mesh_line(term: dict | None) -> str | None:
    """Console / report line of the mesh term: 'mesh: ±0.42 dB (…)' or 'mesh: not estimated (…)'."""
    if not term:
        return None
    if not term.get("estimated"):
        return f"mesh error: {term.get('reason') or 'not estimated'}"
    sizes = " / ".join(f"{1e3 * m:.3g}" for m in term.get("coarse_mesh_sizes_m", [])
                       if m is not None)
    levels = " / ".join(f"{v:.1f}" for v in term.get("coarse_levels_dba", []) if v is not None)
    head = (f"mesh error: ±{term['mesh_db']:.2f} dB (in the ±): loudest point "
            f"{term['frequency_hz']:.2f} Hz re-solved on {sizes} mm meshes: {levels} dB(A) against "
            f"{term['level_dba']:.1f} at {1e3 * term['mesh_size_m']:.3g} mm; ")
    kind = term.get("convergence")
    if term.get("method") == "two meshes":
        how = (f"Richardson from the {1e3 * term['coarse_mesh_size_m']:.3g} mm mesh with p = "
               f"{term['order']:g} (stated; the middle mesh: {term.get('middle_reason')})")
    elif kind == "monotone":
        how = f"GCI, monotone, observed p = {term['order']:.2f}, Fs = {term['safety_factor']:g}"
    elif kind == "pre-asymptotic":
        how = (f"GCI, monotone but observed p = {term['order']:.2f} not in [1, 2] "
               "(pre-asymptotic): "
               f"Fs = {term['safety_factor']:g} × the levels' range {term['range_db']:.2f} dB")
    elif kind == "oscillatory":
        how = (f"GCI, the levels oscillate: Fs = {term['safety_factor']:g} × their range "
               f"{term['range_db']:.2f} dB")
    else:
        how = "the three levels agree"
    return head + how + f"; {term.get('seconds', 0.0):.1f} s"


__all__ = ["mesh_error_reason", "touches", "coarse_start", "coarse_model", "resolve_on", "slim_stage",
           "resolve_coarser", "failed_run", "coarse_sizes", "start_coarse_levels", "mesh_error_term",
           "with_mesh_term", "mesh_checked", "mesh_line"]
