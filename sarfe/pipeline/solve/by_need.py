r"""A sweep by need: linear points where every contact stays linear, the continuation only where a
contact closes, opens or slips (issue 30).

1. Screen: the linearized model's contact-row response over the band on a grid (the pruning
   screen's: :data:`sarfe.pipeline.solve.pruned_points.SWEEP_GRID_POINTS` points plus the
   linearized natural frequencies inside the band); a grid point is *linear* when every contact
   keeps its linearized state (open, closed, stuck) over the whole period with the margin m
   (``solver.prune_margin``: the dynamic part amplified by 1/(1 − m),
   :func:`sarfe.hbm.linear_points.screen_linear`).
2. Nonlinear stretches: each run of grid points that are not linear, from the linear grid point
   before it (ω_a; the band's start when the run starts there) to the linear grid point after it
   (ω_b; the band's end).
3. The walk, in the sweep's direction. A linear stretch gives linear points
   (:func:`sarfe.hbm.linear_points.linear_point`: the linearized response, accepted only when the
   laws' own AFT keeps every contact in its state at every sample and the full residual is within
   ``full_tolerance`` — the harmonic-balance solution itself, no Newton, no Hill) at its grid
   points, at the midpoints of grid intervals over which the response ``measure`` changes by more
   than LEVEL_STEP_DB (recursively, REFINE_DEPTH times), and at each maximum of ``measure`` located
   to PEAK_XTOL of its frequency (bounded golden section on the exact linear response: the
   resonance peaks of the linear curve are points). A nonlinear stretch gives the continuation
   (:func:`sarfe.hbm.continuation`) from ω_a, whose first point is the linear one, stopped at the
   first reported point past ω_b that is linear with the margin: a branch that folds back
   below ω_b is followed through its folds until it is linear again (the stop hook of the
   continuation), and :func:`sarfe.pipeline.solve.points.finish_sweep` repairs its points as in a
   whole-band sweep. A linear grid point whose exact check fails is solved by Newton
   (:func:`sarfe.pipeline.solve.points.solve_point`) from the previous point.

Exactness: a linear point is a solution of the same equations as a Newton point (checked per
point, not assumed from the screen); where no grid point is linear, or a stretch's continuation
stops (a branch that turns back out of the band: the whole-band continuation from the band's start
passes such folds), the sweep is the plain continuation (:func:`sweep_by_need` returns None).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sarfe.accuracy.measures import erp_proxy
from sarfe.case.config import ExcitationConfig, SolverConfig
from sarfe.hbm import continuation
from sarfe.hbm.linear_points import (linear_displacements, linear_point, linear_with_margin,
                                     screen_linear)
from sarfe.pipeline.model.nonlinear_model import NonlinearModel
from sarfe.pipeline.solve.points import (STOPPED, TIME_INTEGRATION, finish_sweep, in_band,
                                         solve_point, solve_points, solver_options)
from sarfe.util.progress import bar as progress_bar

LINEAR_POINTS = 51      # a linear stretch's base points: this many over the band (+ its ω_n)
LEVEL_STEP_DB = 1.0     # a linear grid interval whose ends differ by more gets a midpoint
REFINE_DEPTH = 3        # … at most this many times (8 sub-intervals)
PEAK_XTOL = 1e-5        # a linear peak's frequency to this share of itself


def nonlinear_stretches(linear: np.ndarray) -> list:
    """[(a, b)] grid indices of each run of non-linear grid points (``linear`` (n,) bool): a the
    linear index before the run (0 when it starts the grid), b the one after (n − 1 at the end)."""
    out, i, n = [], 0, linear.size
    while i < n:
        if linear[i]:
            i += 1
            continue
        j = i
        while j < n and not linear[j]:
            j += 1
        out.append((max(i - 1, 0), min(j, n - 1)))
        i = j
    return out


def default_measure(nl):
    """measure(ũ, ω): Σ_k (kω)² ‖r̃_k‖² of the contact rows (the response a sweep's peaks are
    located on when the case gives no ERP map)."""
    G = nl.contacts.gap_map

    def measure(U, omega):
        R = np.asarray(G @ np.asarray(U).T).T
        k = np.repeat(np.arange((R.shape[0] + 1) // 2), 2)[1:]
        return float(np.sum((k[:, None] * omega * R) ** 2))
    return measure


BY_NEED_FAILED = "sweep by need failed"     # in the reasons of a sweep that fell back


def erp_measure(stage):
    """measure(ũ, ω) = the ERP proxy Σ_k (kω)² Σ_s a_s |w_{s,k}|² of a stage with an ERP map
    (:func:`sarfe.accuracy.measures.erp_proxy`: the level a user reads), None without one."""
    erp_map = getattr(stage, "erp_map", None)
    if erp_map is None or not erp_map.shape[0]:
        return None
    return lambda U, omega: erp_proxy(U, omega, erp_map, stage.erp_areas)


def points_by_need(solver: SolverConfig, excitation: ExcitationConfig, nl: NonlinearModel, grid,
                   natural=(), measure=None, progress=False) -> list:
    """HarmonicSolution per point: a sweep with contacts by need (:func:`sweep_by_need`, when
    ``solver.continuation.linear_points``) on the screening ``grid`` [rad/s] with the linearized
    natural frequencies ``natural`` [rad/s]; the plain
    :func:`sarfe.pipeline.solve.points.solve_points` otherwise, where no grid point is linear, or
    (said in every point's reason) when the walk raised."""
    if excitation.sweep is None or not nl.contacts.count or \
            not solver.continuation.linear_points:
        return solve_points(solver, excitation, nl, progress=progress)
    start, end = (2 * np.pi * excitation.sweep.start_hz, 2 * np.pi * excitation.sweep.end_hz)
    options, cont_options = solver_options(solver)
    bar = progress_bar(progress, "sweep (% of the range)", 100, "%")
    failed = None
    try:
        solutions = sweep_by_need(nl, start, end, solver.harmonics, solver.samples_per_period,
                                  options, cont_options, grid, solver.prune_margin, natural,
                                  measure,
                                  (lambda done: bar.update(max(0, int(round(100 * done)) - bar.n)))
                                  if bar is not None else None)
    except Exception as error:      # the whole-band continuation instead, said in the reasons
        solutions, failed = None, f"{BY_NEED_FAILED} ({type(error).__name__}: {error})"
    finally:
        if bar is not None:
            bar.close()
    if solutions is None:
        solutions = solve_points(solver, excitation, nl, progress=progress)
        if failed:
            solutions = [dataclasses.replace(s, reason=f"{s.reason} ({failed})")
                         for s in solutions]
        return solutions
    return in_band(solutions, start, end)


def fallback_warning(solutions) -> str | None:
    """One warning line when the sweep by need raised and the band was solved as one whole-band
    continuation instead (:func:`points_by_need`: the error is in every point's reason), else
    None. The points solve the same equations; the walk's time was spent for nothing."""
    reason = next((str(s.reason) for s in solutions if BY_NEED_FAILED in str(s.reason)), None)
    if reason is None:
        return None
    cause = reason[reason.index(BY_NEED_FAILED):-1]        # the reason ends "(<cause>)"
    return (f"{cause}: the band was solved as one whole-band continuation instead (the same "
            "equations, without the linear stretches: slower); please report it")


def sweep_by_need(nl, start, end, H, N, options, cont_options, grid, margin, natural=(),
                  measure=None, progress=None):
    """HarmonicSolutions of a sweep from ω ``start`` to ``end`` [rad/s] by need (module
    docstring), or None when no grid point is linear (then the plain continuation is the sweep).
    ``grid``: the screening frequencies [rad/s] (ascending); ``margin``: m of the screen;
    ``natural``: the linearized natural frequencies [rad/s] (base points of the linear stretches);
    ``measure(ũ, ω)`` → float: the response whose linear peaks and steps are refined (default
    :func:`default_measure`); ``options``: the points' SolverOptions, ``cont_options`` the
    continuation's; ``progress(fraction)`` of the band covered."""
    model, contacts, F = nl.model, nl.contacts, nl.excitation
    direction = np.sign(end - start)
    lo, hi = sorted((start, end))
    grid = np.asarray(grid, dtype=float)
    grid = np.unique(np.concatenate([[start], grid[(grid >= lo) & (grid <= hi)], [end]]))
    grid = grid[::-1] if direction < 0 else grid
    linear = screen_linear(model, contacts, F, grid, N, margin)
    if not np.any(linear):
        return None
    natural = np.asarray(natural, dtype=float)
    base = np.unique(np.concatenate([np.linspace(lo, hi, LINEAR_POINTS),
                                     natural[(natural > lo) & (natural < hi)]]))
    base = base[::-1] if direction < 0 else base
    measure = measure or default_measure(nl)
    span = abs(end - start)
    solutions, previous = [], None
    at = None              # ω the walk has reached (None: the band's start, not yet taken)

    def ahead(omega):
        return at is None or direction * (omega - at) > 1e-12 * span

    def add_linear(upto, inclusive):
        """linear points at the base points from the walk's position up to ``upto``"""
        nonlocal previous
        omegas = [w for w in base if ahead(w) and direction * (upto - w) > 0]
        if at is None:
            omegas = [start] + [w for w in omegas if w != start]
        if inclusive and ahead(upto):
            omegas.append(upto)
        if omegas:
            points = linear_stretch(nl, omegas, H, N, options, measure, previous)
            solutions.extend(points)
            previous = next((p for p in reversed(points) if p.converged
                             and p.method != TIME_INTEGRATION), previous)

    for a, b in nonlinear_stretches(linear):
        if not ahead(grid[b]):
            continue        # the last branch went on past this stretch (a hardening branch
            #                 reaches beyond the linearized screen's next linear grid point)
        begin = grid[a] if ahead(grid[a]) else at
        if a > 0 and ahead(begin):
            add_linear(begin, False)
        stop_at = grid[b]

        def stop_when(point, stop_at=stop_at):
            return (direction * (point.omega - stop_at) >= 0
                    and linear_with_margin(contacts, point.contact_displacement,
                                           point.samples_per_period, point.omega, margin))
        branch = list(continuation(model, contacts, F, begin, end, H, N, options=cont_options,
                                   stop_when=stop_when, band_start=start, loops_left=0))
        if any(STOPPED in str(p.reason) for p in branch):
            return None     # a stretch's branch stopped (e.g. turned back out of the band, or
            #                 came back onto itself: not left here): the whole-band continuation,
            #                 which starts where the plain sweep does
        if solutions and branch and abs(branch[0].omega - solutions[-1].omega) <= 1e-12 * span:
            branch = branch[1:]              # the walk's last point again
        reached = branch[-1].omega if branch else begin
        target = reached if direction * (reached - stop_at) >= 0 else stop_at
        branch = finish_sweep(nl, branch, begin, target, H, N, options,
                              cont_options.initial_step) if branch else branch
        solutions.extend(branch)
        previous = next((p for p in reversed(branch) if p.converged
                         and p.method != TIME_INTEGRATION), previous)
        # where the branch ended (past ω_b, linear again; or the band's end), not its fold tip:
        # the linear branch beside a fold's upper branch is walked as linear points
        at = branch[-1].omega if branch else stop_at
        if progress is not None:
            progress(min(1.0, abs(at - start) / span))
    if ahead(end):
        add_linear(end, True)
    if progress is not None:
        progress(1.0)
    return solutions


def linear_stretch(nl, omegas, H, N, options, measure, previous) -> list:
    """The points of a linear stretch at ``omegas`` [rad/s] (in walk order), refined (module
    docstring, 3): linear points, or Newton points from ``previous`` where the exact check
    fails."""
    model, contacts, F = nl.model, nl.contacts, nl.excitation
    omegas = np.asarray(omegas, dtype=float)
    U = linear_displacements(model, contacts, F, omegas)
    values = np.array([measure(u, w) for u, w in zip(U, omegas)])
    extra = []
    for i in range(omegas.size - 1):
        extra += _refined(nl, omegas[i], omegas[i + 1], values[i], values[i + 1], measure,
                          REFINE_DEPTH)
    for i in range(1, omegas.size - 1):
        if values[i] >= values[i - 1] and values[i] >= values[i + 1] and values[i] > 0:
            extra.append(_peak(nl, omegas[i - 1], omegas[i + 1], measure))
    direction = np.sign(omegas[-1] - omegas[0]) or 1.0
    every = np.unique(np.concatenate([omegas, extra]))
    every = every[np.argsort(direction * every)]
    U_all = linear_displacements(model, contacts, F, every)
    points = []
    for u, w in zip(U_all, every):
        point = linear_point(model, contacts, F, w, H, N, u, options)
        if point is None:            # the screen's margin missed it: Newton from the last point
            point = solve_point(nl, float(w), H, N, options, previous)
        points.append(point)
        if point.converged and point.method != TIME_INTEGRATION:
            previous = point
    return points


def _level(value):
    return 10 * np.log10(max(value, 1e-300))


def _refined(nl, w0, w1, v0, v1, measure, depth) -> list:
    """Midpoints [rad/s] of [w0, w1] while the linear response's level changes by more than
    LEVEL_STEP_DB over an interval (``depth`` bisections at most)."""
    if depth <= 0 or abs(_level(v1) - _level(v0)) <= LEVEL_STEP_DB:
        return []
    mid = 0.5 * (w0 + w1)
    u = linear_displacements(nl.model, nl.contacts, nl.excitation, [mid])[0]
    vm = measure(u, mid)
    return ([mid] + _refined(nl, w0, mid, v0, vm, measure, depth - 1)
            + _refined(nl, mid, w1, vm, v1, measure, depth - 1))


def _peak(nl, w0, w1, measure) -> float:
    """ω [rad/s] of the maximum of the linear response's ``measure`` in [w0, w1]."""
    from scipy.optimize import minimize_scalar   # heavy (tests/test_imports.py): on use only

    lo, hi = sorted((w0, w1))

    def minus(w):
        u = linear_displacements(nl.model, nl.contacts, nl.excitation, [w])[0]
        return -measure(u, w)
    found = minimize_scalar(minus, bounds=(lo, hi), method="bounded",
                            options={"xatol": PEAK_XTOL * lo})
    return float(found.x)


__all__ = ["LEVEL_STEP_DB", "REFINE_DEPTH", "PEAK_XTOL", "BY_NEED_FAILED", "fallback_warning",
           "nonlinear_stretches", "default_measure", "erp_measure", "points_by_need",
           "sweep_by_need", "linear_stretch"]
