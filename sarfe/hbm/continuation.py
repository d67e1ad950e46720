r"""Frequency sweep by pseudo-arclength continuation of R(x, ω) = 0, through folds.

Scaled unknowns z = (x / x_s, ω / ω_s), x_s = ‖x‖ of the first point, ω_s = |ω_end − ω_start|.
From a solution z_i with unit tangent t_i (null vector of ∂R/∂z, found from the bordered system

    [[∂R/∂x · x_s, ∂R/∂ω · ω_s], [t_{i−1}ᵀ]] t = [0, 1],   t ← t / ‖t‖,

oriented like t_{i−1}, so the tangent stays defined at folds where ∂R/∂x is singular):

    predictor  z_p = z_i + Δs t_i
    corrector  R(z) = 0,  t_iᵀ (z − z_p) = 0     (Newton on the bordered system, line search)

Δs adapts: ×``step_growth`` when the corrector needed ≤ ``target_iterations`` iterations, ×½ when
it needed more or failed (retry), stop below ``min_step``. A corrector that lands farther than 3 Δs
from z_i (branch jumping) counts as failed. The last point is solved at exactly ω_end. x is the
condensed contact-row vector or all DOFs (see :mod:`sarfe.hbm.solve`); the linear solution with
contacts linearized at u = 0 is the first guess.

Corners. With N AFT samples a penalty or friction force is piecewise linear in ũ, so the branch is
piecewise smooth with a corner wherever one sample enters or leaves contact. Near a fold, where
∂R/∂x is nearly singular, one more sample in contact turns the branch by up to ~90° (tangents of
neighbouring pieces at 87° on cases/lumped_rattle.yaml, N = 256), and neither corrector reaches the
next piece: Δs shrinks to ``min_step`` over near-identical points. The corners are an artefact of
the sampling (N = 1024 has no fold there at all: the "fold" at N = 256 is itself an artefact), so
the sweep backs up ``BACKUP`` points (they may lie on the artefact), re-solves there with 2N and
goes on with 2N (up to 16 N; the point's ``reason`` says so). A turn of ω at a corner (on
cases/rattle_rig.yaml at N = 256 the sweep turned at 31.4 Hz and ran back down its own branch; at
N = 1024 it goes on to the true fold at 33.6 Hz) is checked the same way once: where ω turns and consecutive secants z_{i+1} − z_i, z_i − z_{i−1} meet
at more than ~80° (cosine < ``COS_CORNER``; measured: 0.02 and −0.07 at the two artefacts, 0.36–1.0
at the true folds of the shipped cases and NLvib example 03, which the adaptive step passes
gradually) — and, once a sweep has met one corner, at every turn of ω — the sweep backs up and goes
on with 2N; a turn within ``FOLD_DISTANCE`` of the band of a checked one is taken as a fold. A new point closer than ``REPORT_DISTANCE`` (scaled) to the
last one replaces it rather than adding a near-duplicate row.

Extremes (hard contacts k_n ≥ 10⁹ N/m, stick springs k_t ≥ 10⁹ N/m, tiny gaps or damping; measured
on cases/lumped_rattle.yaml with one parameter changed, docs/hbm.md "At the extremes"):

- A re-solve with 2N reorients along the secant of the two points before it *with the old N*
  (across N the jump of x can outweigh the step: with k_t = 10⁹ N/m the sweep ran back down its
  own branch from 63.9 Hz to the band start).
- Physical corners. Where the panel first touches (grazing) a hard contact turns the branch at
  ~110° within a length no N resolves (10⁹ N/m: 111° at N = 512 … 16384). A stall within
  ``FOLD_DISTANCE`` of a point where N was already raised steps past the corner
  (:func:`sarfe.hbm.arclength.corner_step`, the point's ``reason`` says so) instead of raising N again; so does a
  stall once N is at :func:`most_samples`. From then on the tangent is oriented along the
  last secant (at a corner crossed within one step, t_i oriented like t_{i−1} points back).
- Unresolved contact forces. Each accepted point's residual with 2N samples is measured (one AFT
  evaluation); above ``ALIASING_LIMIT`` the point is re-solved with 2N, 4N, … until it is below
  ``ALIASING_TARGET`` (≤ :func:`most_samples`) and the sweep goes on with that N (measured
  largest values along the shipped sweeps: 2.6·10⁻³ lumped_rattle, 6.3·10⁻³ rattle_rig; 0.075
  with k_n = 10⁹ N/m at N = 256). Stalls (and, once a corner was stepped past or N raised for
  this, turns) raise N up to :func:`most_samples`: ``MAX_STALL_FACTOR`` × N, or more while
  N × (contact rows) ≤ ``SAMPLE_BUDGET`` (an AFT evaluation costs ∝ N × rows: 13, 41, 85 ms
  with its Jacobian at N = 2¹⁴, 2¹⁶, 2¹⁷ on lumped_rattle's 2 rows, H = 7). So a lumped model
  may go to 2¹⁶ samples while an FE case with many contacts keeps 64 × N. k_n = 10¹¹ N/m on
  lumped_rattle needs N = 2¹⁵ past 66 Hz (at 2¹⁴ each sample entering a 1 kN impact of 27
  samples turns the branch by ~92° and the sweep crawled from corner to corner at 68.7 Hz).
- Unresolved energy balance (light damping). The AFT's error in the contacts' work per period
  grows like k_n ‖r̃‖² / N² (:mod:`sarfe.hbm.energy_balance`); a lightly damped peak is set by
  the damping's work, so N is raised as above also where the work changes with 2N by more than
  ``ENERGY_LIMIT`` of the dissipated energy (until ``ENERGY_TARGET``). With modal ζ = 10⁻⁴ at
  N = 256 the sampled rattle contact's spurious input balanced the damping at any amplitude: the
  branch climbed to metres at 79.478 Hz, a resonance finer sampling does not have.
- Scale. x_s follows the response: when ‖x‖ leaves [x_s / ``RESCALE``, ``RESCALE`` x_s] it is
  reset to ‖x‖ (z, t rescaled), so a step is a share of the response also on a resonance that
  climbs decades (with x_s of the first point the ζ = 10⁻⁴ sweep took ~470 points for 1 → 5.5 mm).
- Stiff contacts: a point whose full residual misses ``full_tolerance`` (≈ k_n ‖R_c‖ / ‖f̃_e‖) is
  tightened at its ω by the fixed-frequency Newton and its polish (:mod:`sarfe.hbm.solve`).
- Closed loops: a new point within ``RETRACE_SHARE`` of its step of the path through the earlier
  points. Gap 10⁻⁷ m (31.2 Hz), ζ = 10⁻⁴ (54.3 Hz): unchecked, the sweep circles one loop of H = 7
  solutions again and again (the time integration is not periodic there). The sweep leaves it
  (≤ ``LOOP_LIMIT`` times) by a new continuation from fixed ω past the farthest ω reached
  (:func:`continuation`'s ``leave_loop``); that point's ``reason`` says so (``LEFT_LOOP``).
- Sampled folds (light damping): once N was raised for the energy balance, a step that turns ω
  back is checked by :func:`sarfe.hbm.sampled_folds.step_over`: where the branch goes on past the
  farthest ω of the last points (solved at fixed ω from the travel's secant), the turn was a
  zig-zag of the N-sample branch and the sweep goes on from there (``STEPPED_FOLD`` in the
  reason); else it follows the fold. ζ = 10⁻⁴: turns at 55.22 Hz (N = 2048) … 79.4 Hz.
- Stops that name the knob: more than ``CORNER_LIMIT`` corners within ``FOLD_DISTANCE`` (raise
  solver.samples_per_period), or a loop that cannot be left (raise solver.harmonics; at
  :func:`most_samples`: the contact is not resolved).

Band edge. A branch that turns back past ω_start is stopped there: the last point is solved at
exactly ω_start and its ``reason`` says why (no points outside the band).

Harmonic sets (``harmonic_set`` or ``options.solver.harmonic_set``, :mod:`sarfe.hbm.harmonic_set`):
x holds the kept coefficient rows only. With 'auto' the sweep starts on the odd set (unless the
first point needs all orders) and switches to all orders for the rest of the sweep at the first
point whose estimate η exceeds ``harmonic_set_tolerance``: that point is re-solved with all orders
and the tangent is carried over (dropped components zero).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from sarfe.hbm.arclength import (band_edge, corner_step, corrector, rescaled, switch_set,
                                 tangent)
from sarfe.hbm.energy_balance import energy_error
from sarfe.hbm.newton import SingularJacobian
from sarfe.hbm.residual import kept_rows
from sarfe.hbm.sampled_folds import TRAVEL_BASE, TRAVEL_POINTS, step_over, stepped_note
from sarfe.hbm.solution import ContinuationOptions
from sarfe.hbm.solve import (check_omega, finalize, initial_slider, linearized_guess, make_evaluator,
                             make_problem, slider_acceptor, solve_auto, solve_from,
                             wants_condensation)

REPORT_DISTANCE = 1e-4   # scaled arclength below which a new point replaces the last one reported
MAX_SAMPLES_FACTOR = 16  # N may be raised to 16× the requested one at turns of ω (docstring)
MAX_STALL_FACTOR = 64    # … and to 64× at stalled steps and unresolved contact forces,
SAMPLE_BUDGET = 2 ** 17  # … or further while N × contact rows stays within this (most_samples)
BACKUP = 3               # points dropped before re-solving with 2N at a corner or turn
FOLD_DISTANCE = 0.05     # a turn of ω this close (share of the band) to a checked one is a fold
COS_CORNER = 0.2         # ω turns with consecutive secants at more than ~80°: a corner, checked
CORNER_LIMIT = 12        # corners stepped past within FOLD_DISTANCE of each other: a crawl, stop
RETRACE_SKIP = 3         # a new point near the path of the earlier points but these: came back
RETRACE_SHARE = 0.1      # … within this share of its step
LOOP_LIMIT = 3           # closed loops the sweep leaves by a new start past them (docstring)
LOOP_EXIT = (0.25, 0.5, 1.0, 2.0)   # … at these shares of initial_step past the loop's farthest ω
LEFT_LOOP = "left a closed loop of solutions"   # in the reason of the new start past a loop
ALIASING_LIMIT = 2e-2    # residual of a point with 2N samples above which N is doubled (docstring)
ALIASING_TARGET = 5e-3   # … until it is below this (a margin: the contact hardens along the branch)
ENERGY_LIMIT = 2e-1      # contacts' work error with 2N / dissipated energy above which N is doubled
ENERGY_TARGET = 5e-2     # … until it is below this (sarfe.hbm.energy_balance, docstring)
RESCALE = 10.0           # x_s follows ‖x‖ when it leaves [x_s / RESCALE, RESCALE x_s] (docstring)


def most_samples(samples_per_period, row_count):
    """The most AFT samples per period a sweep raises N to at stalled steps and unresolved
    contact forces: N · 2^k, the larger of ``MAX_STALL_FACTOR`` × N and the most with
    N · 2^k × ``row_count`` ≤ ``SAMPLE_BUDGET`` (the AFT's cost, ∝ samples × contact rows)."""
    N = int(samples_per_period) * MAX_STALL_FACTOR
    while 2 * N * max(int(row_count), 1) <= SAMPLE_BUDGET:
        N *= 2
    return N


def continuation(model, contacts, excitation, omega_start, omega_end, harmonics,
                 samples_per_period, options=None, progress=None, harmonic_set=None,
                 stop_when=None, band_start=None, loops_left=None, guess=None):
    """Sweep ω from ω_start to ω_end [rad/s] (either direction) → list of HarmonicSolution.

    progress(done, total): called after each point with done = covered fraction of the range
    (0…1) and total = 1.0. Points are in continuation order (ω is not monotonic past folds).
    harmonic_set: None | 'all' | 'odd' | 'auto' | list of orders, replaces
    ``options.solver.harmonic_set`` when given.
    stop_when(point) → bool: called with each new reported point (not the first); True ends the
    sweep there, as complete (a sweep by need stops a branch that is linear again:
    :mod:`sarfe.pipeline.solve.by_need`). band_start [rad/s]: where a branch turning back is
    stopped (default ω_start; a sweep by need starts inside the band and follows a fold back
    past its own start). loops_left: closed loops the sweep may leave (None: LOOP_LIMIT); guess
    (2H+1, n_dof) [m]: the first point's Newton start (None: the linearized guess; either way
    with the homotopies of :func:`sarfe.hbm.solve.solve_from` when it fails).
    A failed sweep returns the points found so far; the last one's ``reason`` says why it stopped.
    """
    options = options or ContinuationOptions()
    loops_left = LOOP_LIMIT if loops_left is None else loops_left
    so = options.solver
    if harmonic_set is not None:
        so = replace(so, harmonic_set=harmonic_set)
    auto = isinstance(so.harmonic_set, str) and so.harmonic_set == "auto"
    corrector_options = replace(so, max_iterations=min(so.max_iterations,
                                                        options.corrector_iterations),
                                line_search_steps=min(so.line_search_steps, 3))
    full_problem = make_problem(model, contacts, excitation, harmonics, samples_per_period, so,
                                None if auto else so.harmonic_set)
    check_omega(omega_start, "omega_start")
    check_omega(omega_end, "omega_end")
    if omega_start == omega_end:
        raise ValueError("omega_start and omega_end must differ")
    direction = np.sign(omega_end - omega_start)
    span = abs(omega_end - omega_start)
    state = {"slider": None}
    first = (solve_auto(full_problem, omega_start, guess, so) if auto else
             solve_from(full_problem, omega_start, linearized_guess(full_problem, omega_start)
                        if guess is None else guess, so, homotopy=True))
    solutions = [first]
    if not first.converged:
        return solutions
    problem = replace(full_problem, harmonic_orders=None if first.harmonic_orders is None else
                      np.asarray(first.harmonic_orders))

    def escalate(point, guess):
        """'auto': re-solve a point of the odd set whose η is above the tolerance with all orders."""
        if not (auto and problem.harmonic_orders is not None and point.converged
                and point.dropped_content > so.harmonic_set_tolerance):
            return None
        full = solve_from(full_problem, point.omega, guess, so, state["slider"])
        return replace(full, reason=f"{full.reason} (auto: odd set rejected, dropped content "
                                    f"η {point.dropped_content:.3g} > "
                                    f"{so.harmonic_set_tolerance:g}; all orders from here on)")

    condensed = wants_condensation(problem, so)
    evaluate, to_x, to_displacement = make_evaluator(problem, condensed)
    state["slider"] = initial_slider(problem, first.displacement)
    accept = slider_acceptor(state)
    x, omega = to_x(first.displacement), float(omega_start)
    x_scale = max(np.linalg.norm(x), 1e-300)
    z = np.append(x / x_scale, omega / span)
    previous = np.zeros_like(z)
    previous[-1] = direction
    step = options.initial_step

    most = most_samples(samples_per_period, problem.contacts.row_count)
    inner = {}
    refined_at = []                 # ω where a turn was checked with 2N
    physical = False                # a corner stayed after raising N: orientation by secants
    extreme = False                 # a corner was stepped past or N raised for aliasing
    corners_at = []                 # ω of the corners stepped past
    light = False                   # N was raised for the energy balance: sampled folds checked

    def refine_samples(limit):
        """(k, point k re-solved with 2N — 4N, … when that fails) after backing up BACKUP points
        (or none), or (0, None) when no re-solve up to ``limit`` samples converges."""
        N_fine = 2 * problem.samples_per_period
        while N_fine <= limit:
            fine = replace(problem, samples_per_period=N_fine)
            for k in dict.fromkeys((max(0, len(solutions) - 1 - BACKUP), len(solutions) - 1)):
                point = solve_from(fine, solutions[k].omega, solutions[k].displacement, so, None)
                if point.converged:
                    return k, point
            N_fine *= 2
        return 0, None

    def evaluate_z(zz, jacobian):
        e = evaluate(zz[:-1] * x_scale, zz[-1] * span, jacobian, state["slider"])
        if jacobian:
            inner["z"], inner["ev"] = zz, e
        return e

    def pass_corner(t):
        """:func:`corner_step` at z, travelling along the secant from the point before (t_i at
        the first point: at a corner crossed within a step, t_i oriented like t_{i−1} may point
        back), with spheres of radius ≤ that secant's length."""
        direction_z, radius = t, options.initial_step
        if len(solutions) > 1:
            before = solutions[-2]
            secant = z - np.append(to_x(before.displacement) / x_scale, before.omega / span)
            size = np.linalg.norm(secant)
            if size > 0:
                direction_z, radius = secant / size, min(radius, size)
        for r in (options.initial_step, 4 * options.initial_step):   # across a sawtooth
            result = corrector(evaluate_z, z, z + r * direction_z, direction_z, r, x_scale, span,
                               corrector_options, accept)
            if result is not None:
                d = result.x - z
                return result, float(d @ direction_z / np.linalg.norm(d))
        return corner_step(evaluate_z, z, direction_z, radius, x_scale, span, corrector_options,
                           accept)

    fine_evaluator = {}

    def aliasing(N, zz):
        """‖R(x)‖ / reference of the point zz (solved with N AFT samples) evaluated with 2N
        samples: how far the contact forces move when the sampling is refined."""
        N_fine = 2 * N
        if fine_evaluator.get("key") != (N_fine, condensed, id(problem)):
            fine_evaluator["key"] = (N_fine, condensed, id(problem))
            fine_evaluator["evaluate"] = make_evaluator(
                replace(problem, samples_per_period=N_fine), condensed, False)[0]
        with np.errstate(all="ignore"):
            e = fine_evaluator["evaluate"](zz[:-1] * x_scale, zz[-1] * span, False,
                                           state["slider"])
        return float(np.linalg.norm(e.residual) / e.reference), e.forces.force

    def unresolved(N, zz, U, force):
        """(residual with 2N samples, energy error of the contacts' work with 2N samples, see
        :func:`sarfe.hbm.energy_balance.energy_error`) of the point zz solved with N samples (its
        displacement U, contact force λ̃ ``force``)."""
        aliased, force_fine = aliasing(N, zz)
        return aliased, energy_error(problem.model, problem.contacts.gap_map, U,
                                     zz[-1] * span, force, force_fine)

    def resolve_aliasing(result):
        """The accepted point re-solved with 2N, 4N, … (≤ most_samples)
        until its residual with twice its N is ≤ ALIASING_TARGET (or the cap), or None."""
        omega_new = result.x[-1] * span
        U = displacement_of(result)
        N_fine, point = problem.samples_per_period, None
        while 2 * N_fine <= most:
            N_fine *= 2
            fine = replace(problem, samples_per_period=N_fine)
            trial = solve_from(fine, omega_new, U, so, None)
            if not trial.converged:
                break
            point, U = trial, trial.displacement
            zz = np.append(to_x(U) / x_scale, omega_new / span)
            if 2 * N_fine > most:
                break
            aliased, energy = unresolved(N_fine, zz, U, trial.contact_force)
            if aliased <= ALIASING_TARGET and energy <= ENERGY_TARGET:
                break
        return point

    def solve_past(omega, base):
        """The point solved at fixed ω (≤ ω_end) from the last one, started on the secant from
        the earlier point ``base`` (at a fold ∂R/∂x is singular), and its z."""
        omega = omega_end if direction * (omega - omega_end) > 0 else omega
        last = solutions[-1]
        reach = (omega - last.omega) / (last.omega - base.omega)
        point = solve_from(problem, omega, last.displacement + reach * (last.displacement
                                                                        - base.displacement),
                           so, state["slider"])
        return point, np.append(to_x(point.displacement) / x_scale, omega / span)

    def travel():
        """(z_i − z_k, point k) for the latest earlier point k at least TRAVEL_BASE away (or the
        farthest of the last TRAVEL_POINTS): the direction of travel beyond the last micro-steps."""
        d, base = np.zeros_like(z), None
        for base in reversed(solutions[-TRAVEL_POINTS:-1]):
            d = z - np.append(to_x(base.displacement) / x_scale, base.omega / span)
            if np.linalg.norm(d) >= TRAVEL_BASE:
                break
        return d, base

    trail = {}
    recovered = {}

    def displacement_of(result):
        """ũ (2H+1, n) of an accepted corrector ``result``, recovered once: the aliasing check,
        its re-solve and the reported point share it (condensed: one modal recovery, not two)."""
        key = recovered.get("key", (None, None, None))
        if key[0] is not result or key[1] is not to_displacement or key[2] != x_scale:
            recovered["key"] = (result, to_displacement, x_scale)
            recovered["U"] = to_displacement(result.x[:-1] * x_scale, result.x[-1] * span,
                                             result.evaluation)
        return recovered["U"]

    def retraces(zz, length):
        """Does zz lie within RETRACE_SHARE × the step ``length`` of the path through the reported
        points before the last RETRACE_SKIP ones: the sweep came back onto its own branch (a
        closed loop, or a wrong turn at a corner that runs back along it)?"""
        earlier = solutions[:-RETRACE_SKIP]
        if len(earlier) < 2 or length <= 0:
            return False
        key = (x_scale, condensed)
        if trail.get("key") != key:
            trail.clear()
            trail["key"] = key
        for s in earlier:       # z of each reported point once (not each call: O(points²));
            if trail.get(id(s), (None,))[0] is not s:      # the point held: its id stays its own
                trail[id(s)] = (s, np.append(to_x(s.displacement) / x_scale, s.omega / span))
        Z = np.array([trail[id(s)][1] for s in earlier])
        a, b = Z[:-1], Z[1:]
        ab = b - a
        share = np.clip(np.einsum("ij,ij->i", zz - a, ab)
                        / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
        gap = np.linalg.norm(a + share[:, None] * ab - zz, axis=1)
        return bool(gap.min() < RETRACE_SHARE * length)

    def came_back(omega):
        """The stop reason of a sweep that came back onto its own branch, naming the knob."""
        N, H = problem.samples_per_period, problem.harmonics
        if 2 * N > most:
            return (f"the branch came back onto itself near {omega / (2 * np.pi):.5g} Hz at "
                    f"N = {N}, the most samples the sweep raises N to ({most // samples_per_period}"
                    " × solver.samples_per_period): the contact forces are not resolved — raise "
                    "solver.samples_per_period, or soften the contact (its stiffness)")
        return (f"the branch came back onto itself near {omega / (2 * np.pi):.5g} Hz (a closed "
                f"loop of solutions at H = {H}, N = {N}): raise solver.harmonics")

    def crawling(omega):
        """The stop reason of a sweep that meets a corner every few steps, naming the knob."""
        N = problem.samples_per_period
        capped = 2 * N > most
        return (f"more than {CORNER_LIMIT} corners of the branch within "
                f"{FOLD_DISTANCE * span / (2 * np.pi):.3g} Hz of {omega / (2 * np.pi):.5g} Hz "
                f"at N = {N}" + (f", the most samples the sweep raises N to ("
                                 f"{most // samples_per_period} × solver.samples_per_period)"
                                 if capped else "")
                + " (the sampled contact forces switch a sample at a time): raise "
                "solver.samples_per_period" + (", or soften the contact (its stiffness)"
                                               if capped else ""))

    def leave_loop(omega_back):
        """The sweep went on from fixed ω past the loop (module docstring), or None."""
        far = max(solutions, key=lambda s: direction * s.omega)
        for share in LOOP_EXIT if loops_left > 0 else ():
            omega_r = far.omega + direction * share * options.initial_step * span
            done = float(direction * (omega_r - omega_start) / span)
            if done >= 1.0:
                return None
            onward = continuation(
                model, contacts, excitation, omega_r, omega_end, harmonics, samples_per_period,
                replace(options, max_points=options.max_points - len(solutions)), progress and
                (lambda d, t: progress(done + (1 - done) * d, 1.0)), harmonic_set, stop_when,
                omega_start if band_start is None else band_start, loops_left - 1, far.displacement)
            if onward[0].converged:
                onward[0] = replace(onward[0], reason=(
                    f"{onward[0].reason} ({LEFT_LOOP} at H = {problem.harmonics}, N = "
                    f"{problem.samples_per_period}: the branch came back onto itself near "
                    f"{omega_back / (2 * np.pi):.5g} Hz; the sweep went on from here, solved at "
                    f"fixed ω past the loop's farthest {far.omega / (2 * np.pi):.5g} Hz)"))
                return solutions + onward
        return None

    def stop(reason):
        last = solutions[-1]
        solutions[-1] = replace(last, reason=f"{last.reason}; sweep stopped: {reason}")
        return solutions

    while True:
        try:
            ev = inner["ev"] if inner.get("z") is z else evaluate_z(z, True)
            t = tangent(ev, x_scale, span, previous)
        except SingularJacobian:
            if condensed:   # S_k(ω) singular on the way: continue on all DOFs
                condensed = False
                evaluate, to_x, to_displacement = make_evaluator(problem, False)
                x = to_x(solutions[-1].displacement)
                x_scale = max(np.linalg.norm(x), 1e-300)
                z = np.append(x / x_scale, solutions[-1].omega / span)
                continue
            return stop("singular bordered Jacobian (tangent)")
        refined = None                 # point k re-solved with 2N (stalled step or turn of ω)
        corner = None                  # cosine of a corner stepped past (corner_step)
        while True:
            predicted = z + step * t
            result = corrector(evaluate_z, z, predicted, t, step, x_scale, span,
                               corrector_options, accept)
            if result is None and step <= 0.01 * options.initial_step:
                # a corner of the (nonsmooth) branch: the hyperplane may miss it, the sphere
                # ‖z − z_i‖ = Δs intersects it
                result = corrector(evaluate_z, z, predicted, None, step, x_scale, span,
                                   corrector_options, accept)
            if result is not None:
                break
            step *= 0.5
            if step < options.min_step:
                omega_i = z[-1] * span
                persists = any(abs(omega_i - w) < FOLD_DISTANCE * span for w in refined_at)
                physical = physical or persists
                passed = None
                if persists:   # 2N did not remove a corner here: a corner of the branch itself
                    passed = pass_corner(t)
                if passed is None:
                    refined_at.append(omega_i)
                    k, refined = refine_samples(most)
                    if refined is None and not persists:
                        passed = pass_corner(t)
                if passed is not None:
                    (result, corner), refined = passed, None
                    step = np.linalg.norm(result.x - z)
                    extreme = True
                    corners_at.append(omega_i)
                    if sum(abs(omega_i - w) < FOLD_DISTANCE * span for w in corners_at) > \
                            CORNER_LIMIT:
                        return stop(crawling(omega_i))
                elif refined is None:
                    return stop(f"step below min_step {options.min_step:g} near ω = "
                                f"{omega_i:.6g} (N = {problem.samples_per_period})")
                break
        if (light and refined is None and len(solutions) > 1
                and direction * (result.x[-1] - z[-1]) < 0):
            far = direction * max(direction * s.omega for s in solutions[-TRAVEL_POINTS:]) / span
            d, base = travel()                                    # ω turns: the sampling's?
            over = step_over(lambda omega: solve_past(omega, base), z, d, span, direction, far)
            if over is not None:
                point, z_over, share = over
                solutions.append(replace(point, reason=point.reason + stepped_note(
                    z[-1] * span, point.omega, share, span, problem.samples_per_period)))
                previous = (z_over - z) / np.linalg.norm(z_over - z)
                step = min(options.initial_step, max(step, np.linalg.norm(z_over - z)))
                z = z_over
                inner.clear()
                if point.omega == omega_end:
                    return solutions
                continue
        if refined is None and corner is None and len(solutions) > 1:
            omega_i = z[-1] * span
            z_prev = np.append(to_x(solutions[-2].displacement) / x_scale,
                               solutions[-2].omega / span)
            ahead, behind = result.x - z, z - z_prev
            sharp = ahead @ behind < COS_CORNER * np.linalg.norm(ahead) * np.linalg.norm(behind)
            turned = behind[-1] * ahead[-1] < 0 and (sharp or refined_at)
            if turned and not any(abs(omega_i - w) < FOLD_DISTANCE * span for w in refined_at):
                refined_at.append(omega_i)      # ω turns at a corner: checked with 2N
                k, refined = refine_samples(most if extreme else
                                            MAX_SAMPLES_FACTOR * samples_per_period)
        why = "a stalled step or a turn of ω, checked with finer AFT sampling"
        if refined is None and problem.samples_per_period < most:
            aliased, energy = unresolved(
                problem.samples_per_period, result.x,
                displacement_of(result),
                result.evaluation.forces.force)
            if aliased > ALIASING_LIMIT or energy > ENERGY_LIMIT:   # contact forces not resolved
                refined = resolve_aliasing(result)
                if refined is not None:
                    k, extreme = len(solutions), True
                    light = light or energy > ENERGY_LIMIT
                    why = (f"with {problem.samples_per_period} samples the residual of this point "
                           f"at twice as many was {aliased:.2g} (limit {ALIASING_LIMIT:g}), the "
                           f"contacts' work per period changed by {energy:.2g} of the dissipated "
                           f"energy (limit {ENERGY_LIMIT:g}): the contact forces were not "
                           "resolved")
        if refined is not None:        # continue with 2N from the re-solved point k
            problem = replace(problem, samples_per_period=refined.samples_per_period)
            full_problem = replace(full_problem, samples_per_period=refined.samples_per_period)
            evaluate, to_x, to_displacement = make_evaluator(problem, condensed)
            state["slider"] = initial_slider(problem, refined.displacement)
            replaced = (np.append(to_x(solutions[k].displacement) / x_scale,
                                  solutions[k].omega / span) if k < len(solutions) else result.x)
            del solutions[k:]
            solutions.append(replace(refined, reason=f"{refined.reason} (N raised to "
                                     f"{refined.samples_per_period} here: {why})"))
            z = np.append(to_x(refined.displacement) / x_scale, refined.omega / span)
            if k > 0:               # orientation: the secant from the point before, both
                before = solutions[k - 1]      # with the old N (across N, the change of x with
                previous = replaced - np.append(to_x(before.displacement) / x_scale,  # N can
                                                before.omega / span)                  # dominate)
                previous /= max(np.linalg.norm(previous), 1e-300)
            else:
                previous = np.zeros_like(z)
                previous[-1] = direction
            inner.clear()
            step = options.initial_step
            continue
        z_new = result.x
        omega_new = z_new[-1] * span
        if retraces(z_new, np.linalg.norm(z_new - z)):
            return leave_loop(omega_new) or stop(came_back(omega_new))
        U_new = displacement_of(result)
        if direction * (omega_new - omega_end) >= 0:      # passed the end: solve at ω_end exactly
            fraction = (omega_end - z[-1] * span) / (omega_new - z[-1] * span)
            U_prev = solutions[-1].displacement
            guess = U_prev + fraction * (U_new - U_prev)
            last = solve_from(problem, omega_end, guess, so, state["slider"])
            solutions.append(escalate(last, last.displacement) or last)
            if progress is not None:
                progress(1.0, 1.0)
            return solutions
        point = finalize(problem, omega_new, U_new, True, "converged", result.iterations,
                         state["slider"], so)
        if not point.converged and "above full_tolerance" in point.reason:
            # a stiff contact: the corrector's tolerance on the contact rows leaves a full
            # residual ≈ k_n ‖R_c‖ / ‖f̃_e‖ above full_tolerance — tightened at this ω by the
            # fixed-frequency Newton and its polish (sarfe.hbm.solve)
            polished = solve_from(problem, omega_new, U_new, so, state["slider"])
            if polished.converged:
                point = replace(polished, iterations=result.iterations + polished.iterations,
                                reason=f"{polished.reason} (tightened at fixed ω: {point.reason})")
                U_new = polished.displacement
                z_new = np.append(to_x(U_new) / x_scale, omega_new / span)
        if corner is not None:
            point = replace(point, reason=f"{point.reason} (a corner of the branch passed by a "
                            f"sphere step: the piece ahead at {np.degrees(np.arccos(corner)):.0f}° "
                            f"from the tangent, N = {problem.samples_per_period})")
        full = escalate(point, U_new)
        if full is not None:           # continue with all orders from the re-solved point
            if not full.converged:
                solutions.append(full)
                return stop("the point re-solved with all orders did not converge")
            rows_from, old_scale, was_condensed = kept_rows(problem), x_scale, condensed
            problem = full_problem
            condensed = wants_condensation(problem, so)
            evaluate, to_x, to_displacement = make_evaluator(problem, condensed)
            x = to_x(full.displacement)
            x_scale = max(np.linalg.norm(x), 1e-300)
            if condensed == was_condensed:
                width = problem.contacts.row_count if condensed else problem.model.dof_count
                t = switch_set(t, rows_from, problem.harmonics, width, old_scale, x_scale)
            else:                      # other unknowns: restart the orientation along ω
                t = np.zeros(x.size + 1)
                t[-1] = direction
            z_new = np.append(x / x_scale, full.omega / span)
            point = full
        edge = omega_start if band_start is None else band_start
        if direction * (omega_new - edge) < 0:            # turned back out of the band
            return band_edge(problem, solutions, point, edge, so, state["slider"])
        if full is not None or np.linalg.norm(z_new - z) >= REPORT_DISTANCE:
            solutions.append(point)     # (a step shrunk to a corner adds no reported point)
        else:
            solutions[-1] = point
        if progress is not None:
            progress(float(np.clip(direction * (omega_new - omega_start) / span, 0, 1)), 1.0)
        if stop_when is not None and stop_when(solutions[-1]):
            return solutions
        if len(solutions) >= options.max_points:
            return stop(f"max_points {options.max_points} reached")
        if (physical or extreme) and full is None:
            t = (z_new - z) / np.linalg.norm(z_new - z)    # orientation past corners: the secant
        previous, z = t, z_new
        size = np.linalg.norm(z[:-1])
        if not 1.0 / RESCALE <= size <= RESCALE:   # the response left a decade of x_s: x_s ← ‖x‖
            x_scale *= size
            z, previous = rescaled(z, size), rescaled(previous, size)
            previous /= np.linalg.norm(previous)
        if result.iterations <= options.target_iterations:
            step = min(step * options.step_growth, options.max_step)
        else:
            step = max(step * 0.5, options.min_step)
