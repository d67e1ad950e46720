r"""The mesh term of a run's ± (issue 29 item 4): the loudest point re-solved on a generated mesh
of twice the element size, Richardson-extrapolated (:mod:`sarfe.accuracy.mesh_refinement`, (1))

    mesh_db = max(|L_h − L_2h|, |L_A,h − L_A,2h|) / (2^p − 1),   p = MESH_ORDER (stated)

One linear stage built on the coarser mesh (the case's reduction rule and cutoff, so the modal
basis covers the same band) and one Newton solve of the harmonic balance at the loudest point's
ω, H, N, started from the linear response to the fine point's contact forces (same contact
rows), else from the linear response. Where the two meshes' contacts are in different states at ω
(one closes, the other does not: the mesh moved the contact onset, e.g. a rattle near its fold)
the level change is no Richardson estimate: the term is "not estimated" with that reason. The term is measured at the loudest point and added to every
estimated point's ERP bound (``error_estimate.mesh_db``, ``erp_db`` includes it): the headline
carries it where it was measured; elsewhere it stands for the mesh error of the run.

Only generated meshes (``model.fe.generator``) have a coarser mesh to build: for decks, given
meshes and matrices models the term is "not estimated" and said so (``solver.mesh_error``:
'auto' = on for generator meshes, true = required, false = off).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from sarfe.accuracy.mesh_refinement import MESH_ORDER, MESH_RATIO, mesh_richardson
from sarfe.hbm import SolverOptions, solve_frequency
from sarfe.hbm.time_integration import linear_harmonic_response
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.pipeline.post.records import loudest_point, point_erp


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


def mesh_error_term(case, points, solutions, ratio=MESH_RATIO, order=MESH_ORDER) -> dict:
    """The mesh term (module docstring) of a solved case: ``points`` the summary's point records,
    ``solutions`` their HarmonicSolutions → {'estimated', 'reason', 'mesh_db', 'order', 'ratio',
    'mesh_size_m', 'coarse_mesh_size_m', 'frequency_hz', 'level_db', 'level_dba',
    'coarse_level_db', 'coarse_level_dba', 'coarse_converged', 'coarse_nodes', 'seconds'}.
    A failure (coarser mesh not built, Newton not converged) is reported as not estimated, never
    raised."""
    clock = time.perf_counter()
    out = {"estimated": False, "mesh_db": float("nan"), "order": float(order),
           "ratio": float(ratio), "reason": mesh_error_reason(case)}
    if out["reason"] is not None:
        return out
    j = loudest_point(points)
    if j is None:
        out["reason"] = "not estimated (no converged, not unstable point)"
        return out
    fine = solutions[j]
    h = float(case.config.model.fe.generator.mesh_size_m)
    solver = case.config.solver
    out.update(mesh_size_m=h, coarse_mesh_size_m=ratio * h, frequency_hz=points[j]["frequency_hz"],
               level_db=points[j]["erp"]["level_db"], level_dba=points[j]["erp"]["level_dba"])
    try:
        coarse = case.with_generator(mesh_size_m=ratio * h)
        stage = build_linear_model(coarse)
        nl = nonlinear_model(coarse, stage)
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
    except Exception as error:  # an estimate must not break a solve
        out.update(reason=f"not estimated (the {1e3 * ratio * h:.3g} mm mesh failed: "
                   f"{type(error).__name__}: {error})", seconds=time.perf_counter() - clock)
        return out
    erp, _ = point_erp(case.config.erp, stage, s.displacement, s.omega)
    out.update(coarse_level_db=float(erp.level_total_db), coarse_level_dba=float(erp.level_total_a_db),
               coarse_converged=bool(s.converged), coarse_nodes=int(stage.info.get("nodes", 0)),
               seconds=time.perf_counter() - clock)
    if not s.converged:
        out["reason"] = (f"not estimated (the re-solve on the {1e3 * ratio * h:.3g} mm mesh did "
                         f"not converge: {getattr(s, 'reason', '')})")
        return out
    touching = (touches(fine), touches(s))
    if touching[0] != touching[1]:      # one mesh's contacts close at ω, the other's do not
        out["reason"] = (f"not estimated: at {out['frequency_hz']:.2f} Hz the "
                         f"{1e3 * ratio * h:.3g} mm mesh's contacts "
                         f"{'do not close' if touching[0] else 'close'} "
                         f"({out['coarse_level_dba']:.1f} against {out['level_dba']:.1f} dB(A)): "
                         "another branch, its level change is no Richardson estimate (the mesh "
                         "moves the contact onset; refine the mesh or compare the sweeps with "
                         "`sarfe study --knobs mesh`)")
        return out
    mesh_db = max(mesh_richardson(out["level_db"], out["coarse_level_db"], order, ratio),
                  mesh_richardson(out["level_dba"], out["coarse_level_dba"], order, ratio))
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
    return (f"mesh error: ±{term['mesh_db']:.2f} dB (in the ±): loudest point {term['frequency_hz']:.2f}"
            f" Hz re-solved on a {1e3 * term['coarse_mesh_size_m']:.3g} mm mesh: "
            f"{term['coarse_level_dba']:.1f} dB(A) against {term['level_dba']:.1f} at "
            f"{1e3 * term['mesh_size_m']:.3g} mm, Richardson with p = {term['order']:g} (stated); "
            f"{term.get('seconds', 0.0):.1f} s")


__all__ = ["mesh_error_reason", "touches", "coarse_start", "mesh_error_term", "with_mesh_term",
           "mesh_checked", "mesh_line"]
