"""Converged points of a shipped case, for tests that compare two stability methods on them."""
import numpy as np


def shipped_case_points(name, max_harmonics=5, count=5):
    """The case ``cases/<name>.yaml`` at its own settings with H ≤ ``max_harmonics``: up to
    ``count`` of its frequencies (or points spread over its sweep band), each solved cold.
    Returns (nl, H, [(frequency [Hz], converged HarmonicSolution)]); nl's excitation is truncated
    to the 2H+1 rows of H (at the case's own H the solver rejected it and no point converged)."""
    from dataclasses import replace
    from sarfe.pipeline import build_linear_model, load_case, nonlinear_model
    from sarfe.pipeline.solve.points import solve_point, solver_options

    case = load_case(f"cases/{name}.yaml")
    nl = nonlinear_model(case, build_linear_model(case, progress=False))
    H = min(case.data["solver"]["harmonics"], max_harmonics)
    nl = replace(nl, excitation=nl.excitation[:2 * H + 1])
    N = case.data["solver"]["samples_per_period"]
    options, _ = solver_options(case)
    excitation = case.data["excitation"]
    if "sweep" in excitation:
        a, b = excitation["sweep"]["start_hz"], excitation["sweep"]["end_hz"]
        freqs = list(np.linspace(a, b, count))
    else:
        freqs = list(excitation["frequency_hz"])
    points = []
    for f in freqs[:count]:
        s = solve_point(nl, 2 * np.pi * f, H, N, options, None)
        if s.converged:
            points.append((f, s))
    return nl, H, points


def full_hill(model, contacts, F, s):
    """The full Hill method at a converged point ``s`` (the reference the other stability methods
    are compared with) → (StabilityResult, the point's Evaluation, its ContactOperator)."""
    from sarfe.hbm.residual import Problem, full_residual
    from sarfe.hbm.stability.select import contact_damping
    from sarfe.hbm.stability.hill import hill_stability
    from sarfe.hbm.stability.contact_terms import ContactOperator

    problem = Problem(model, contacts, F, s.harmonics, s.samples_per_period)
    ev = full_residual(problem, s.displacement.ravel(), s.omega)
    op = ContactOperator(problem, s.displacement, s.omega, ev.forces)
    full = hill_stability(model, s.omega, s.harmonics, ev.jacobian,
                          contact_damping=contact_damping(problem, ev.forces), operator=op)
    return full, ev, op
