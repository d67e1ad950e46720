"""Frequency points of a case: the HBM engine per listed frequency or a continuation sweep,
with the fallbacks that keep every point reported (exact linear solution without contacts; a
retry from a short time integration; a stopped continuation completed point by point).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from sarfe.accuracy.target import parse_accuracy
from sarfe.case.config import ContinuationConfig, ExcitationConfig, SolverConfig
from sarfe.hbm import ContinuationOptions, SolverOptions, continuation, solve_frequency
from sarfe.hbm.continuation import LEFT_LOOP
from sarfe.hbm.sampled_folds import STEPPED_FOLD
from sarfe.hbm.harmonics import harmonic_coefficients
from sarfe.hbm.residual import nonlinear_force
from sarfe.hbm.solution import HarmonicSolution
from sarfe.hbm.time_integration import integrate_time, linear_harmonic_response
from sarfe.pipeline.model.nonlinear_model import NonlinearModel
from sarfe.util.progress import bar as progress_bar


def solver_options(solver: SolverConfig):
    """(SolverOptions, ContinuationOptions) from the ``solver`` section (:class:`SolverConfig`; a
    Case is also taken, for callers that hold only the case). The tolerance of
    ``harmonic_set: auto`` is the amplitude budget of ``solver.accuracy`` (default 'balanced')."""
    if not isinstance(solver, SolverConfig):
        solver = solver.config.solver
    options = SolverOptions(tolerance=solver.tolerance, max_iterations=solver.max_iterations,
                            stability=solver.stability, harmonic_set=solver.harmonic_set,
                            harmonic_set_tolerance=parse_accuracy(
                                solver.accuracy_or_default).amplitude_budget())
    cont = solver.continuation
    return options, ContinuationOptions(initial_step=cont.initial_step, min_step=cont.min_step,
                                        max_step=cont.max_step, max_points=cont.max_points,
                                        solver=options)


TIME_INTEGRATION = "time integration"     # HarmonicSolution.method of a time-integration stand-in


def time_integration_point(model, contacts, excitation, omega, harmonics, samples_per_period,
                           initial=None, max_periods=400):
    """A HarmonicSolution (``method='time integration'``) from time integration: the start guess of a retry
    (``max_periods`` small, the state need not be steady) or the stand-in for a point whose
    engine call raised."""
    steps = max(int(samples_per_period), 256)
    response = integrate_time(model, contacts, excitation, omega, harmonics,
                              steps_per_period=steps, max_periods=max_periods, initial=initial)
    return HarmonicSolution(
        omega=float(omega), harmonics=int(harmonics), samples_per_period=steps,
        displacement=response.displacement_harmonics,
        contact_displacement=harmonic_coefficients(response.contact_displacement, harmonics),
        contact_force=response.contact_force_harmonics,
        contact_force_time=response.contact_force,
        contact_state=response.contact_state,
        converged=bool(response.steady),
        reason="time integration reached a periodic state" if response.steady
        else "time integration did not reach a periodic state",
        iterations=int(response.periods), residual_norm=float(response.periodicity_error),
        friction_passes=0, stable=None, floquet_exponent=float("nan"), method=TIME_INTEGRATION)


def linear_solution(nl: NonlinearModel, omega, H, N):
    """The exact periodic solution of a model without contacts, as a HarmonicSolution."""
    U = linear_harmonic_response(nl.model, nl.excitation, omega)
    rows, count = nl.contacts.row_count, nl.contacts.count
    return HarmonicSolution(
        omega=float(omega), harmonics=int(H), samples_per_period=int(N), displacement=U,
        contact_displacement=np.zeros((2 * H + 1, rows)), contact_force=np.zeros((2 * H + 1, rows)),
        contact_force_time=np.zeros((N, rows)), contact_state=np.zeros((N, count), dtype=np.int8),
        converged=True, reason="linear model (no contacts): exact solution", iterations=0,
        residual_norm=0.0, method="linear")


GUESS_STEPS = 256
"""Fewest Newmark steps per period of the time-integration start guess of :func:`solve_point`."""


GUESS_REFINEMENTS = 1
GUESS_REFINEMENT_FACTOR = 8
"""A time-integration guess from which Newton fails is integrated on with 8× the steps (once): near
grazing impacts Newton at high H needs a start within ~0.05 % (rattle rig 33.47 Hz, H = 160: fails
from the 512- and 1024-step orbits, 0.7–3 % off; converges in 3 iterations from 4096 steps)."""


def guess_steps(H):
    """Steps per period of a time-integration start guess: the power of two ≥ max(2H+1,
    :data:`GUESS_STEPS`) — a start for Newton, not a result, so not the AFT's N (at H = 160,
    N = 8192 the guess at N steps cost 13 s of a 15 s rattle-rig sweep; at 512 steps 0.9 s)."""
    return max(GUESS_STEPS, 1 << int(2 * H).bit_length())


def solve_point(nl, omega, H, N, options, previous):
    """One HBM point; on failure retry from the engine's cold start, then once from a short time
    integration (its end state).

    Starts, in turn, until one converges: ``previous`` (warm start, when given); the engine's cold
    start (linearized guess, then its homotopies: :func:`sarfe.hbm.solve_frequency` without
    ``initial``), when a warm start failed — tens of Newton iterations, where the time integration
    costs up to 40 periods of time steps (on the door trim 0.16 s against 3.7 s); the end state
    of at most 40 periods of time integration (:func:`guess_steps` per period) started on
    ``previous`` — the orbit a slow sweep carries over from the previous frequency — or, without
    it, on the linear periodic solution; if Newton fails from it, the integration goes on from
    its end state with :data:`GUESS_REFINEMENT_FACTOR` × the steps and Newton is tried again.
    An engine exception or a point that still fails is returned with ``converged=False`` and the
    reason (the time-integration state stands in when the engine raised), never dropped.
    """
    contacts = nl.contacts
    if not contacts.count:
        return linear_solution(nl, omega, H, N)
    error = None
    try:
        solution = solve_frequency(nl.model, contacts, nl.excitation, omega, H, N, initial=previous,
                             options=options)
    except Exception as exc:  # an engine failure must not lose the other points
        solution, error = None, exc
    if solution is not None and (solution.converged or not contacts.count):
        return solution
    if previous is not None:
        try:
            cold = solve_frequency(nl.model, contacts, nl.excitation, omega, H, N, options=options)
            if cold.converged:
                return dataclasses.replace(
                    cold, iterations=cold.iterations + (solution.iterations if solution else 0),
                    reason=f"{cold.reason} (cold start after the warm start failed: "
                           f"{solution.reason if solution else error})")
        except Exception:
            pass
    guess = previous
    for refine in range(GUESS_REFINEMENTS + 1):
        steps = guess_steps(H) * GUESS_REFINEMENT_FACTOR ** refine
        guess = time_integration_point(nl.model, contacts, nl.excitation, omega, H, steps,
                                       initial=guess, max_periods=40)
        try:
            retry = solve_frequency(nl.model, contacts, nl.excitation, omega, H, N,
                                    initial=guess.displacement, options=options)
            if retry.converged:
                return dataclasses.replace(
                    retry, reason=f"{retry.reason} (started from {guess.iterations} periods of "
                                  f"time integration, {steps} steps/period)")
        except Exception:
            pass
    if solution is None:        # HarmonicSolution is frozen: a new one, reported not converged
        return dataclasses.replace(
            guess, converged=False,
            reason=(f"HBM engine failed ({type(error).__name__}: {error}); values are the "
                    "time-integration state after 40 periods"))
    return solution


STOPPED = "sweep stopped:"        # in the reason of the point where a continuation stopped
POINT_BY_POINT = "point-by-point after the continuation stopped"
CONTINUATION_FAILED = "point-by-point: the continuation failed"


def in_band(solutions, start, end):
    """The solutions whose ω lies in the requested band [start, end] [rad/s] (either order; a
    relative 10⁻⁹ of the band's width of round-off allowed): points outside it are no results."""
    lo, hi = sorted((start, end))
    slack = 1e-9 * (hi - lo)
    return [s for s in solutions if lo - slack <= float(s.omega) <= hi + slack]


def sweep_status(excitation: ExcitationConfig, continuation: ContinuationConfig,
                 solutions) -> dict:
    """How a sweep was solved → {'complete', 'reason', 'covered', 'note'} (None without a sweep).

    complete: one continuation from start to end, no stop and no point-by-point fallback.
    covered: the band is still covered by converged points — the lowest and highest converged
    frequencies are the band's ends (10⁻³ of its width) and no gap between neighbouring converged
    frequencies is wider than the continuation's largest step (``max_step`` of the band).
    reason: one line saying what happened (None when complete).
    note: one line naming the closed loops of solutions the continuation left and the folds of
    the sampled branch it stepped over (None if none)."""
    if excitation.sweep is None:
        return {"complete": None, "reason": None, "covered": None, "note": None}
    start, end = excitation.sweep.start_hz, excitation.sweep.end_hz
    lo, hi = sorted((start, end))
    span = hi - lo
    reasons = [str(s.reason) for s in solutions]
    freqs = np.sort([float(s.omega) / (2 * np.pi) for s in solutions if s.converged])
    max_gap = continuation.max_step * span
    covered = bool(freqs.size and freqs[0] <= lo + 1e-3 * span and freqs[-1] >= hi - 1e-3 * span
                   and np.max(np.diff(freqs), initial=0.0) <= max_gap * (1 + 1e-9))
    stopped = next((i for i, r in enumerate(reasons) if STOPPED in r), None)
    fallback = sum(POINT_BY_POINT in r or CONTINUATION_FAILED in r for r in reasons)
    reached = bool(solutions) and abs(float(solutions[-1].omega) / (2 * np.pi) - end) <= 1e-3 * span
    left = [f"{float(s.omega) / (2 * np.pi):.2f}" for s in solutions if LEFT_LOOP in str(s.reason)]
    note = (f"the continuation {LEFT_LOOP} (H = {solutions[0].harmonics} truncation) "
            f"{len(left)} time(s) and went on from a point solved at fixed frequency past it, at "
            f"{', '.join(left)} Hz (see those points' reason)") if left else None
    stepped = [f"{float(s.omega) / (2 * np.pi):.2f}" for s in solutions
               if STEPPED_FOLD in str(s.reason)]
    if stepped:                 # zig-zags of the sampled branch (sarfe.hbm.sampled_folds)
        over = (f"the continuation {STEPPED_FOLD} {len(stepped)} time(s) (a turn of ω that the AFT "
                f"sampling makes, the branch going on past it; the zig-zag is not reported), "
                f"going on from a point solved at fixed frequency at {', '.join(stepped[:6])}"
                + (f" and {len(stepped) - 6} more" if len(stepped) > 6 else "") + " Hz")
        note = over if note is None else f"{note}; {over}"
    if stopped is None and not fallback and reached:
        return {"complete": True, "reason": None, "covered": covered, "note": note}
    if any(CONTINUATION_FAILED in r for r in reasons):
        what = reasons[0].split(CONTINUATION_FAILED, 1)[1].strip(" ()")
        text = f"the continuation failed ({what}); {fallback} point(s) solved point by point"
    elif stopped is not None:
        where = float(solutions[stopped].omega) / (2 * np.pi)
        why = reasons[stopped].split(STOPPED, 1)[1].strip()
        text = (f"the continuation stopped at {where:.2f} Hz ({why})"
                + (f"; {fallback} point(s) solved point by point from there" if fallback else ""))
    else:
        text = "the sweep did not reach the end of its band"
    text = (f"sweep not complete: {text}; "
            + ("the band is still covered by converged points" if covered
               else "the band is NOT covered by converged points (exit code 3)"))
    return {"complete": False, "reason": text, "covered": covered, "note": note}


def finish_sweep(nl, solutions, start, end, H, N, options, step):
    """Repair a continuation result: a point whose corrector failed is re-solved at its fixed ω
    (starting from it); a sweep that stopped before ``end`` is completed point by point
    (natural-parameter steps of ``step``·|end − start| from the last converged point). Such points
    say so in their ``reason``."""
    if not solutions:
        return solutions
    for i, solution in enumerate(solutions):  # polish corrector failures at fixed ω
        if not solution.converged:
            retry = solve_point(nl, float(solution.omega), H, N, options, solution)
            if retry.converged:
                solutions[i] = dataclasses.replace(
                    retry, reason=f"{retry.reason} (re-solved at fixed frequency after the "
                                  f"continuation corrector stopped: {solution.reason})")
    span = abs(end - start)
    last = solutions[-1].omega
    if abs(last - end) <= 1e-3 * span:
        return solutions
    if (end - last) * (end - start) < 0:   # past the end (e.g. turned back): nothing to add
        return solutions
    count = max(2, int(math.ceil(abs(end - last) / (step * span))) + 1)
    previous = next((s for s in reversed(solutions) if s.converged), None)
    for omega in np.linspace(last, end, count)[1:]:
        solution = solve_point(nl, float(omega), H, N, options, previous)
        solution = dataclasses.replace(solution, reason=f"{solution.reason} ({POINT_BY_POINT})")
        solutions.append(solution)
        if solution.converged and solution.method != TIME_INTEGRATION:
            previous = solution
    return solutions


def common_samples(nl, solutions):
    """Solutions with one N: a continuation raises N at corners of its branch (sarfe.hbm.
    continuation), but the result files hold one time grid (applied after the error estimates,
    which use the N each point was solved with). Points solved with fewer samples get
    their contact time histories (force, state) re-sampled by the AFT at the largest N used
    (harmonics unchanged; the ``reason`` says so)."""
    largest = max((int(s.samples_per_period) for s in solutions), default=0)
    out = []
    for s in solutions:
        N = int(s.samples_per_period)
        if N == largest or s.method == TIME_INTEGRATION or not nl.contacts.count:
            out.append(s)
            continue
        _, _, forces = nonlinear_force(nl.contacts, s.displacement, largest, jacobian=False)
        out.append(dataclasses.replace(
            s, samples_per_period=largest, contact_force_time=forces.force_time,
            contact_state=forces.state,
            reason=f"{s.reason} (solved with N = {N}; time histories at N = {largest})"))
    return out


def solve_points(solver: SolverConfig, excitation: ExcitationConfig, nl: NonlinearModel,
                 progress=False):
    """HarmonicSolution per frequency point (listed frequencies in order, or a continuation)."""
    H, N = solver.harmonics, solver.samples_per_period
    options, cont_options = solver_options(solver)
    contacts = nl.contacts
    failed = ""
    if excitation.sweep is not None:
        start, end = (2 * np.pi * excitation.sweep.start_hz, 2 * np.pi * excitation.sweep.end_hz)
        if contacts.count:
            # the bar counts percent of the frequency range covered (so tqdm estimates the time left)
            bar = progress_bar(progress, "sweep (% of the range)", 100, "%")
            try:
                solutions = list(continuation(nl.model, contacts, nl.excitation, start, end, H, N,
                                           options=cont_options,
                                           progress=(lambda done, total: bar.update(
                                               max(0, int(round(100 * done)) - bar.n)))
                                           if bar is not None else None))
                return in_band(finish_sweep(nl, solutions, start, end, H, N, options,
                                            solver.continuation.initial_step), start, end)
            except Exception as error:  # fall back to a point-by-point sweep (said in reasons)
                failed = f"{CONTINUATION_FAILED} ({type(error).__name__}: {error})"
            finally:
                if bar is not None:
                    bar.close()
        count = min(max(2, int(round(1.0 / solver.continuation.initial_step)) + 1), 101)
        omegas = np.linspace(start, end, count)
    else:
        omegas = 2 * np.pi * np.asarray(excitation.frequency_hz, dtype=float)
    solutions, previous = [], None
    bar = progress_bar(progress, "frequencies", len(omegas), "point")
    try:
        for omega in omegas:
            solution = solve_point(nl, float(omega), H, N, options, previous)
            if failed:
                solution = dataclasses.replace(solution, reason=f"{solution.reason} ({failed})")
            solutions.append(solution)
            previous = solution if solution.converged and \
                solution.method != TIME_INTEGRATION else None
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return solutions
