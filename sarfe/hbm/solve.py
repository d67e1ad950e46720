r"""Periodic solution at one frequency: R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e = 0 by Newton.

Steps of :func:`solve_frequency`:
1. validate the inputs (shapes, H, N; the model and contacts were validated when built);
2. first guess: the linear response with every contact linearized at u = 0 by its law (closed
   contacts as their springs, dashpots and preload, tangent elements stuck as springs k_t,
   :func:`sarfe.hbm.laws.linearization`), unless ``initial`` is given;
   if Newton fails from it, homotopies provide the start, tried in turn: the contact stiffness
   (k_n·s, k_t·s, s stepped from s₀ ≤ 10⁻⁴ to 1 in log s) and then the excitation level (f̃_e·s,
   s stepped 0 → 1), each with adaptive steps warm-started by the previous one and capped at
   ``max_homotopy_iterations`` Newton iterations; ``iterations`` counts all of them;
3. Newton on the contact rows only (dynamic compliance condensation, :mod:`sarfe.hbm.dynamic_stiffness`) when
   that system is smaller, else — or when some S_k(ω) is singular — on all DOFs (sparse LU);
4. recovery of all DOFs, the residual of the full equation of motion relative to ‖f̃_e‖, the
   stability of the orbit (:func:`sarfe.hbm.stability.stability`: Hill's method or the
   contact-row count, per ``options.stability_method``).

Harmonic sets (:mod:`sarfe.hbm.harmonic_set`): with ``harmonic_set`` = 'odd' or a list of orders,
Newton's unknowns and equations are the kept coefficient rows only (dropped rows held at zero);
the final evaluation (4.) runs on all rows: its kept rows give ``residual_norm``, its dropped rows
the estimate η (``dropped_content``), the Hill stability uses the full-set Jacobian. With 'auto'
the odd set is solved first and the point is re-solved with all orders (from the odd solution)
when η > ``harmonic_set_tolerance``; a point whose ``initial`` solution had η above the tolerance
goes to all orders directly (a sweep keeps the set its previous point needed).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from sarfe.hbm import laws
from sarfe.hbm.aft import default_slider_start
from sarfe.hbm.dynamic_stiffness import (condense, dynamic_stiffness_matrix, from_complex,
                                         recover_displacement, to_complex)
from sarfe.hbm.harmonic_set import (AUTO_CANDIDATE, coefficient_rows, dropped_content, expand_rows,
                                    harmonic_set_orders)
from sarfe.hbm.harmonics import check_harmonics, derivative_matrix, time_samples
from sarfe.hbm.modal import cached_modal_basis, updated_solve
from sarfe.hbm.newton import SingularJacobian, newton, solve_linear
from sarfe.hbm.residual import Problem, condensed_residual, full_residual, kept_rows
from sarfe.hbm.solution import HarmonicSolution, SolverOptions
from sarfe.hbm.stability import stability, stability_method
from sarfe.hbm.stability.deferred import defer, deferring

CHORD_STEPS = True       # fixed-ω Newton reuses its LU while it contracts (sarfe.hbm.newton)


def make_problem(model, contacts, excitation, harmonics, samples_per_period, options=None,
                 harmonic_set=None):
    """Validate and bundle the inputs (raises ValueError naming the parameter).

    harmonic_set: None | 'all' | 'odd' | list of orders (not 'auto', which :func:`solve_frequency`
    resolves)."""
    options = options or SolverOptions()
    check_harmonics(harmonics, samples_per_period)
    n = model.dof_count
    F = np.asarray(excitation, dtype=float)
    if F.shape != (2 * harmonics + 1, n):
        raise ValueError(f"excitation must have shape (2H+1, n_dof) = ({2 * harmonics + 1}, {n}), "
                         f"got {F.shape}")
    if not np.all(np.isfinite(F)):
        raise ValueError("excitation has non-finite entries")
    if contacts.gap_map.shape[1] != n:
        raise ValueError(f"contacts.gap_map has {contacts.gap_map.shape[1]} columns, "
                         f"the model has {n} DOFs")
    return Problem(model, contacts, F, int(harmonics), int(samples_per_period),
                   options.friction_tolerance, options.friction_pass_cap,
                   harmonic_set_orders(harmonic_set, harmonics))


def check_omega(omega, name="omega"):
    """Raise ValueError naming ``name`` unless ω [rad/s] is a finite frequency > 0."""
    if not np.isfinite(omega) or omega <= 0:
        raise ValueError(f"{name} must be a finite frequency > 0 [rad/s], got {omega!r}")


def coefficient_row_count(problem):
    """Number of kept coefficient rows (2H+1 for the full set)."""
    rows = kept_rows(problem)
    return 2 * problem.harmonics + 1 if rows is None else rows.size


def condensed_size(problem):
    return coefficient_row_count(problem) * problem.contacts.row_count


def wants_condensation(problem, options) -> bool:
    """'auto': condense when the dense condensed system is clearly smaller than the full one:
    P_c = (2H+1) n_rows ≤ max_condensed_size and n_rows < n_dof (dense model), or P_c ≤ ¼ of the
    full size (sparse model, whose full Jacobian is sparse and cheap to factorize)."""
    if options.condensation == "auto":
        size = condensed_size(problem)
        if size > options.max_condensed_size:
            return False
        if sp.issparse(problem.model.stiffness):
            return 4 * problem.contacts.row_count <= problem.model.dof_count
        return problem.contacts.row_count < problem.model.dof_count
    return bool(options.condensation)


def contact_row_springs(contacts) -> np.ndarray:
    """Spring of every row of G [N/m]: the law's normal spring on normal rows (also where open),
    the stuck tangent spring k_t on tangent rows (:func:`sarfe.hbm.laws.linearization`)."""
    c = contacts
    normal, tangent = laws.linearization(c)
    springs = np.zeros(c.row_count)
    has_n = c.normal_row >= 0
    springs[c.normal_row[has_n]] = normal.spring[has_n]
    for col in range(2):
        present = c.tangent_rows[:, col] >= 0
        springs[c.tangent_rows[present, col]] = tangent[present]
    return springs


def linearized_rows(contacts, normal_force=None):
    """(spring, dashpot [N s/m], preload [N]) per row of G of the contacts linearized at u = 0:
    normal rows of contacts closed at u = 0 carry their law's spring, dashpot and preload (the
    preload of a contact without a normal row has no row), tangent rows the stuck spring k_t
    (less κ λ_n on a curved partner, :func:`sarfe.hbm.laws.tangent_springs`; λ_n the static
    ``normal_force`` (n_c,) [N] when given, else λ_n(0))."""
    c = contacts
    normal, tangent = laws.linearization(c)
    springs, dashpots, preload = np.zeros(c.row_count), np.zeros(c.row_count), np.zeros(c.row_count)
    has_n = c.normal_row >= 0
    closed = has_n & normal.closed
    springs[c.normal_row[closed]] = normal.spring[closed]
    dashpots[c.normal_row[closed]] = normal.dashpot[closed]
    preload[c.normal_row[has_n]] = normal.preload[has_n]
    tangent_rows = laws.tangent_springs(c, normal, tangent, normal_force)
    for col in range(2):
        present = c.tangent_rows[:, col] >= 0
        springs[c.tangent_rows[present, col]] = tangent_rows[present, col]
    return springs, dashpots, preload


def linearized_guess(problem, omega) -> np.ndarray:
    """ũ of the linear system with the contacts linearized at u = 0 (see module docstring):
    (S(ω) + (I⊗G)ᵀ (I⊗k + ω∇⊗c) (I⊗G)) ũ = f̃_e − Gᵀ p in row 0. On a curved partner the
    tangent springs include the geometric stiffness −κ λ_n at the static normal force λ_n
    (a first pass gives the static state)."""
    c = problem.contacts
    rows_k, rows_c, preload = linearized_rows(c)
    if laws.curvatures(c) is None:
        return _linearized_solve(problem, omega, rows_k, rows_c, preload)
    U = _linearized_solve(problem, omega, rows_k, rows_c, preload)
    normal, _ = laws.linearization(c)
    w0 = np.asarray(c.gap_map @ U[0])[np.maximum(c.normal_row, 0)]
    static = normal.preload + normal.spring * w0
    rows_k = linearized_rows(c, static)[0]
    return _linearized_solve(problem, omega, rows_k, rows_c, preload)


def _linearized_solve(problem, omega, rows_k, rows_c, preload):
    """:func:`linearized_guess` with the given row springs, dashpots and preloads."""
    c, H, n = problem.contacts, problem.harmonics, problem.model.dof_count
    G = c.gap_map
    if not sp.issparse(problem.model.stiffness):
        return _linearized_guess_dense(problem, omega, rows_k, rows_c, preload)
    GG = sp.kron(sp.identity(2 * H + 1), G, format="csr")
    A = dynamic_stiffness_matrix(problem.model, omega, H) + GG.T @ sp.diags(
        np.tile(rows_k, 2 * H + 1)) @ GG
    if np.any(rows_c):
        A = A + sp.kron(sp.csr_matrix(omega * derivative_matrix(H)),
                        G.T @ sp.diags(rows_c) @ G, format="csr")
    F = problem.excitation.copy()
    F[0] -= G.T @ preload
    rows = kept_rows(problem)
    b = F.ravel()
    if rows is not None:     # A is block diagonal over the harmonics: keep the kept blocks
        keep = (rows[:, None] * n + np.arange(n)).ravel()
        A, b = A.tocsr()[keep][:, keep], b[keep]
    try:
        return expand_rows(solve_linear(A, b), rows, H, n)
    except SingularJacobian:
        return np.zeros((2 * H + 1, n))


def _linearized_guess_dense(problem, omega, rows_k, rows_c, preload):
    """:func:`linearized_guess` of a dense model, harmonic by harmonic (the system is block
    diagonal over the orders): K_l u₀ = f̃_e,0 − Gᵀp and (K_l − (kω)² M + i kω D_l) Û_k =
    F_kc − i F_ks, u_kc = Re Û_k, u_ks = −Im Û_k, with K_l = K + Gᵀ diag(k) G, D_l = D +
    Gᵀ diag(c) G; orders without excitation (or not kept) are zero. Zero where singular."""
    H, n = problem.harmonics, problem.model.dof_count
    G = sp.csr_matrix(problem.contacts.gap_map)
    F = problem.excitation.copy()
    F[0] -= G.T @ preload
    rows = kept_rows(problem)
    kept = np.ones(2 * H + 1, bool) if rows is None else np.isin(np.arange(2 * H + 1), rows)
    U = np.zeros((2 * H + 1, n))
    basis = cached_modal_basis(problem.model)
    rhs = to_complex(F)
    orders = np.flatnonzero(kept[np.r_[0, 2 * np.arange(1, H + 1) - 1]] & np.any(rhs != 0, axis=1))
    if basis is not None and not basis.singular(orders, float(omega)):
        # the modal Z_k⁻¹ and a low-rank update: no dense solve (an undamped resonance of the
        # model without its contacts — Z_k singular — takes the dense solve below)
        try:
            z = np.zeros((H + 1, n), dtype=complex)
            with np.errstate(all="ignore"):
                z[orders] = updated_solve(basis, G.toarray(), rows_k, rows_c, orders,
                                          float(omega), rhs[orders])
            if np.all(np.isfinite(z)):
                return from_complex(z)
        except np.linalg.LinAlgError:
            pass
    # the dense K_l, D_l, M only here (the modal path above needs none: 3 n² copies a call)
    dense = (lambda a: a.toarray() if sp.issparse(a) else np.asarray(a, dtype=float))  # noqa: E731
    K = dense(problem.model.stiffness) + dense(G.T @ sp.diags(rows_k) @ G)
    D = dense(problem.model.damping) + dense(G.T @ sp.diags(rows_c) @ G)
    M = dense(problem.model.mass)
    try:
        if kept[0] and np.any(F[0]):
            U[0] = np.linalg.solve(K, F[0])
        for k in range(1, H + 1):
            rhs = F[2 * k - 1] - 1j * F[2 * k]
            if not (kept[2 * k - 1] and np.any(rhs)):
                continue
            w = k * float(omega)
            Uk = np.linalg.solve(K - w * w * M + 1j * w * D, rhs)
            U[2 * k - 1], U[2 * k] = Uk.real, -Uk.imag
    except np.linalg.LinAlgError:
        return np.zeros((2 * H + 1, n))
    return U if np.all(np.isfinite(U)) else np.zeros((2 * H + 1, n))


def make_evaluator(problem, condensed, omega_derivative=True):
    """evaluate(x, ω, jacobian, slider) for the condensed or full residual; condensation cached per ω.
    ``omega_derivative`` False: a Newton at fixed ω, the condensed ∂R/∂ω is not formed.

    Returns (evaluate, to_x, to_displacement) where to_x maps ũ → x and to_displacement maps an
    evaluation at ω to ũ (2H+1, n). None if condensation was asked but S_k(ω) is singular at ω.
    """
    n = problem.model.dof_count
    G = problem.contacts.gap_map
    rows = kept_rows(problem)

    def kept(X):
        X = np.asarray(X)
        return (X if rows is None else X[rows]).ravel()

    if not condensed:
        def evaluate(x, omega, jacobian, slider):
            return full_residual(problem, x, omega, slider, jacobian)

        def to_displacement(x, omega, evaluation):
            return expand_rows(x, rows, problem.harmonics, n)

        return evaluate, kept, to_displacement
    cache = {}

    def condensation(omega):
        if omega not in cache:
            cache.clear()
            cache[omega] = condense(problem.model, G, problem.excitation, omega,
                                    problem.harmonic_orders)
        if cache[omega] is None:
            raise SingularJacobian(f"S_k(ω) singular at ω = {omega:g}")
        return cache[omega]

    def evaluate(x, omega, jacobian, slider):
        return condensed_residual(problem, condensation(omega), x, slider, jacobian,
                                  omega_derivative)

    def to_displacement(x, omega, evaluation):
        return recover_displacement(condensation(omega), evaluation.forces.force)

    return evaluate, lambda U: kept(np.asarray(G @ np.asarray(U).T).T), to_displacement


def initial_slider(problem, U):
    r = np.asarray(problem.contacts.gap_map @ U.T).T
    return default_slider_start(problem.contacts, time_samples(r, problem.samples_per_period))


def slider_acceptor(state):
    """accept(evaluation) for Newton: keep the last periodic slider state (reported, passed on).

    The friction forces are a function of the unknowns alone (the slider gauge of
    :mod:`sarfe.hbm.laws.jenkins`): the slider start is not a hidden state, so the residual never
    changes between Newton iterations and no evaluation is redone (returns False)."""
    def accept(evaluation):
        state["slider"] = evaluation.forces.slider_end
        return False
    return accept


def harmonic_set_label(problem) -> str:
    """'all' | 'odd' | 'orders' for the set of ``problem``."""
    orders = problem.harmonic_orders
    if orders is None:
        return "all"
    odd = harmonic_set_orders("odd", problem.harmonics)
    return "odd" if odd is not None and np.array_equal(orders, odd) else "orders"


def kept_residual_norm(problem, ev) -> float:
    """‖R‖/‖f̃_e‖ of a full-residual evaluation ``ev`` on the kept coefficient rows of ``problem``
    (all rows for the full harmonic set): what ``full_tolerance`` is compared with."""
    R = ev.residual.reshape(-1, problem.model.dof_count)
    rows = kept_rows(problem)
    return float(np.linalg.norm(R if rows is None else R[rows]) / ev.reference)


def finalize(problem, omega, U, converged, reason, iterations, slider, options) -> HarmonicSolution:
    """Residual on all DOFs and all harmonic rows, contact fields, Hill stability → HarmonicSolution
    (inside a :func:`sarfe.hbm.stability.deferred.deferred_stability` block the stability is recorded as a
    job, ``stability_job``, and computed later).

    residual_norm: the kept rows; dropped_content: η of the dropped rows (for the full set: of the
    rows outside the odd set, what 'auto' would drop)."""
    full = replace(problem, harmonic_orders=None)
    # the contact Jacobian only for a stability computed here: not for a point that did not
    # converge, nor for one whose stability is deferred (:func:`sarfe.hbm.stability.deferred.stability_of`
    # evaluates it again; the forces, states and residual do not depend on it: 2.8 instead of
    # 4.6 ms a point at P1)
    in_place = options.stability and converged and not deferring()
    with np.errstate(all="ignore"):     # ∂R/∂ũ on all DOFs only for the full Hill method
        ev = full_residual(full, U.ravel(), omega, slider, jacobian=in_place,
                           assemble=stability_method(full, options) == "full")
    residual = kept_residual_norm(problem, ev)
    G = problem.contacts.gap_map
    f_nl = np.asarray(G.T @ ev.forces.force.T).T
    rows = kept_rows(problem)
    candidate = rows if rows is not None else coefficient_rows(
        harmonic_set_orders(AUTO_CANDIDATE, problem.harmonics))
    with np.errstate(all="ignore"):
        eta = dropped_content(f_nl, problem.excitation, candidate)
    if not np.isfinite(residual):
        converged, reason = False, "non-finite residual"
    elif converged and residual > options.full_tolerance:
        converged = False
        reason = f"full residual {residual:.3g} above full_tolerance {options.full_tolerance:g}"
    stable, exponent, note, job = None, float("nan"), "", None
    if converged and options.stability:
        job = defer(full, omega, U, slider, options)    # recorded for later (sarfe.hbm.stability.deferred)
        if job is None:
            result = stability(full, omega, U, ev, options)
            stable, exponent, note = result.stable, result.leading, result.note
    orders = problem.harmonic_orders
    return HarmonicSolution(
        omega=float(omega), harmonics=problem.harmonics,
        samples_per_period=problem.samples_per_period, displacement=U,
        contact_displacement=np.asarray(G @ U.T).T, contact_force=ev.forces.force,
        contact_force_time=ev.forces.force_time, contact_state=ev.forces.state,
        converged=bool(converged), reason=reason, iterations=int(iterations),
        residual_norm=residual, friction_passes=int(ev.forces.friction_passes),
        stable=stable, floquet_exponent=exponent, stability_note=note,
        harmonic_orders=None if orders is None else tuple(int(k) for k in orders),
        harmonic_set=harmonic_set_label(problem), dropped_content=eta, stability_job=job)


def solve_frequency(model, contacts, excitation, omega, harmonics, samples_per_period,
                    initial=None, options=None, harmonic_set=None) -> HarmonicSolution:
    """Periodic solution at one ω [rad/s] (see module docstring).

    excitation f̃_e (2H+1, n_dof) [N]; initial: a HarmonicSolution or ũ (2H+1, n_dof) [m].
    harmonic_set: None | 'all' | 'odd' | 'auto' | list of orders; when given it replaces
    ``options.harmonic_set``. The returned solution has converged=False and a ``reason`` when
    Newton did not converge.
    """
    options = options or SolverOptions()
    if harmonic_set is not None:
        options = replace(options, harmonic_set=harmonic_set)
    auto = isinstance(options.harmonic_set, str) and options.harmonic_set == "auto"
    problem = make_problem(model, contacts, excitation, harmonics, samples_per_period, options,
                           None if auto else options.harmonic_set)
    check_omega(omega)
    U0 = None
    if initial is not None:
        U0 = np.asarray(getattr(initial, "displacement", initial), dtype=float)
        if U0.shape != problem.excitation.shape:
            raise ValueError(f"initial displacement must have shape {problem.excitation.shape}")
    if auto:
        return solve_auto(problem, omega, U0, options,
                          getattr(initial, "dropped_content", float("nan")))
    if U0 is None:
        return solve_from(problem, omega, linearized_guess(problem, omega), options, homotopy=True)
    return solve_from(problem, omega, U0, options)


def auto_needs_full_set(previous_content, options) -> bool:
    """'auto': go to all orders directly when the previous point's η exceeded the tolerance."""
    return bool(previous_content > options.harmonic_set_tolerance)


def solve_auto(problem, omega, U0, options, previous_content=float("nan"), slider=None):
    """harmonic_set='auto' at one ω: the odd set, re-solved with all orders (``problem``, full set)
    from the odd solution when its η > harmonic_set_tolerance or it did not converge. U0 None:
    linearized guess with homotopy."""
    tolerance = options.harmonic_set_tolerance
    note = f"auto: previous point needed all orders (η {previous_content:.3g} > {tolerance:g})"
    if not auto_needs_full_set(previous_content, options):
        reduced = replace(problem, harmonic_orders=harmonic_set_orders(AUTO_CANDIDATE,
                                                                       problem.harmonics))
        start = linearized_guess(reduced, omega) if U0 is None else U0
        solution = solve_from(reduced, omega, start, options, slider, homotopy=U0 is None)
        if solution.converged and solution.dropped_content <= tolerance:
            return solution
        if solution.converged:
            U0 = solution.displacement
            note = (f"auto: odd set rejected, dropped content η {solution.dropped_content:.3g} "
                    f"> {tolerance:g}")
        else:
            note = f"auto: odd set did not converge ({solution.reason})"
    start = linearized_guess(problem, omega) if U0 is None else U0
    solution = solve_from(problem, omega, start, options, slider, homotopy=U0 is None)
    return replace(solution, reason=f"{solution.reason} ({note})")


COLD_START_HOMOTOPIES = ("contact_stiffness", "excitation")
"""Homotopies tried in turn when Newton fails from the linearized guess (see :func:`_homotopy`).
Contact stiffness first: on the rattle rig it needs 82–97 Newton iterations where the excitation
path needs 330–340, and it reaches branches the excitation path misses; same solutions where both
converge (``benchmarks/results/accuracy.md``)."""

SOFT_CONTACT_SCALE = 1e-4
"""Largest start of the contact-stiffness homotopy: k_n, k_t × 10⁻⁴ (see :func:`soft_contact_scale`)."""


def soft_contact_scale(problem) -> float:
    """Start s₀ of the contact-stiffness homotopy: every scaled contact spring at most 10⁻² of the
    structure's stiffness on its row, k·s₀ ≤ 10⁻² Σ_j G_rj² K_jj, and s₀ ≤ :data:`SOFT_CONTACT_SCALE`."""
    c = problem.contacts
    K = problem.model.stiffness
    diagonal = np.abs(K.diagonal() if sp.issparse(K) else np.diag(K))
    structure = np.asarray(c.gap_map.multiply(c.gap_map) @ diagonal).ravel()
    spring = contact_row_springs(c)
    loaded = (spring > 0) & (structure > 0)
    if not np.any(loaded):
        return SOFT_CONTACT_SCALE
    return float(min(SOFT_CONTACT_SCALE, 1e-2 * np.min(structure[loaded] / spring[loaded])))


def scaled_contacts(problem, scale):
    """The problem with every contact spring scaled (the laws' ``scaled`` parameters: k_n·s, k_t·s,
    dashpots, force tables; gaps, μ, N0 unchanged)."""
    return replace(problem, contacts=problem.contacts.scaled(scale))


def _homotopy(problem, omega, options, kind):
    """March a parameter s to 1, each Newton solve warm-started by the previous one.

    kind 'excitation': f̃_e·s, s: 0 → 1 in adaptive steps (0.25 first, ×1.5 on success, ½ on
    failure, give up below 10⁻³). kind 'contact_stiffness': k_n·s and k_t·s, s: s₀ → 1
    (:func:`soft_contact_scale`) in adaptive steps of log s (×10 first; the exponent step ×1.5 on
    success, ½ on failure, give up below 10⁻³ decades) — the soft-contact solution is close to the
    linear one and the path follows the stable branch a stiff contact reaches by impacts, which
    the excitation path can miss. At most ``options.max_homotopy_iterations`` Newton iterations.
    Returns (ũ, NewtonResult, slider) of the last converged step, the Newton iterations spent and
    whether s reached 1 — then that step solved ``problem`` itself (at(1) is ``problem``).
    """
    if kind == "excitation":
        def at(s):
            return replace(problem, excitation=s * problem.excitation)

        def advance(s, h):
            return min(1.0, s + h)
        position, step = 0.0, 0.25
    else:
        def at(s):
            return scaled_contacts(problem, s)

        def advance(s, h):
            return min(1.0, s * 10.0 ** h)
        position, step = soft_contact_scale(problem), 1.0
    smallest = 1e-3
    steps = replace(options, max_iterations=min(options.max_iterations, 20))
    start = at(position)
    current, result, current_slider = _newton(start, omega, linearized_guess(start, omega), steps)
    spent = result.iterations
    if not result.converged:
        return current, result, current_slider, spent, False
    while position < 1.0 and step >= smallest and spent < options.max_homotopy_iterations:
        target = advance(position, step)
        U_t, result_t, slider_t = _newton(at(target), omega, current, steps, current_slider)
        spent += result_t.iterations
        if result_t.converged:
            position, current, result, current_slider = target, U_t, result_t, slider_t
            step *= 1.5
        else:
            step *= 0.5
    return current, result, current_slider, spent, position >= 1.0


def solve_from(problem, omega, U0, options, slider=None, homotopy=False) -> HarmonicSolution:
    """The periodic solution of ``problem`` (:func:`make_problem`) at ω [rad/s] by Newton from
    ũ = U0 (2H+1, n_dof) [m] (condensed when useful, full as fallback), ``slider``: the slider
    start (None: from U0); with ``homotopy``, a failed start is retried from the end of each of
    :data:`COLD_START_HOMOTOPIES` in turn until Newton converges; then polished and finalized
    (:func:`finalize`: residual on all rows, stability). ``iterations`` of the result counts every
    Newton iteration spent, homotopy steps included."""
    U, result, slider = _newton(problem, omega, U0, options, slider)
    iterations = result.iterations
    if homotopy and not result.converged:
        for kind in COLD_START_HOMOTOPIES:
            U_h, result_h, slider_h, spent, reached = _homotopy(problem, omega, options, kind)
            iterations += spent
            if reached:                 # its last step converged on ``problem`` itself
                U, result, slider = U_h, result_h, slider_h
                break
        else:
            result = replace(result, reason=f"{result.reason} (cold start: linearized guess, "
                             f"then homotopies in {' and '.join(COLD_START_HOMOTOPIES)})")
    if result.converged and wants_condensation(problem, options):
        U, result, slider, spent = _polish(problem, omega, U, result, slider, options)
        iterations += spent
    return finalize(problem, omega, U, result.converged, result.reason, iterations,
                    slider, options)


POLISH_MARGIN = 0.1
""":func:`_polish` aims the condensed residual at this share of what ``full_tolerance`` needs."""


def _polish(problem, omega, U, result, slider, options):
    r"""Tighten a converged condensed Newton until the full residual meets ``full_tolerance``.

    The condensed tolerance is relative to ‖r̃_lin‖ [m], the full one to ‖f̃_e‖ [N]; they differ
    by the contact stiffness: the recovered ũ has G ũ = r̃ − R_c(r̃), so its full residual is
    ≈ ‖Gᵀ ∂λ̃/∂r̃ R_c‖ / ‖f̃_e‖, up to k_n ‖R_c‖ / ‖f̃_e‖ (on the rattle rig, k_n = 2·10⁵ N/m,
    a condensed 10⁻⁹ leaves 1.2·10⁻⁶ > 10⁻⁶ at H ≥ 40). When the full residual ρ (one AFT
    evaluation without Jacobian) is above ``full_tolerance`` ρ_f, Newton goes on from r̃ with the
    tolerance × ``POLISH_MARGIN``·ρ_f/ρ (one or two more steps; the same solution, closer).
    Returns (ũ, NewtonResult, slider, Newton iterations spent)."""
    full = replace(problem, harmonic_orders=None)
    with np.errstate(all="ignore"):
        ev = full_residual(full, U.ravel(), omega, slider, jacobian=False)
    residual = kept_residual_norm(problem, ev)
    if not np.isfinite(residual) or residual <= options.full_tolerance:
        return U, result, slider, 0
    tighter = replace(options, tolerance=options.tolerance * POLISH_MARGIN
                      * options.full_tolerance / residual)
    U2, result2, slider2 = _newton(problem, omega, U, tighter, slider)
    if not result2.converged:        # keep the first solution (finalize reports its residual)
        return U, result, slider, result2.iterations
    return U2, result2, slider2, result2.iterations


def _newton(problem, omega, U0, options, slider=None):
    state = {"slider": initial_slider(problem, U0) if slider is None else slider}
    accept = slider_acceptor(state)
    result = None
    for condensed in ((True, False) if wants_condensation(problem, options) else (False,)):
        evaluate, to_x, to_displacement = make_evaluator(problem, condensed, False)
        try:
            result = newton(lambda x, jac: evaluate(x, omega, jac, state["slider"]), to_x(U0),
                            options, x_scale=np.linalg.norm(to_x(U0)), accept=accept,
                            chord=CHORD_STEPS)
        except SingularJacobian:
            continue            # S_k(ω) singular: fall back to the full residual
        break
    return to_displacement(result.x, omega, result.evaluation), result, state["slider"]


def newton_from(model, contacts, excitation, U, omega, harmonics, samples_per_period,
                options=None):
    """Newton at a fixed ω [rad/s] from a given ũ (2H+1, n) [m] on the (H, N) problem — the
    re-solve of a nearby solution (e.g. one of another H, N or model, resized), with none of
    :func:`solve_frequency`'s fallbacks (no homotopy, no full-DOF retry, no polish, no stability).

    All harmonic orders 0…H (``options.harmonic_set`` is not used). Condensed on the contact rows
    when there are any (x = G ũ; one condensation S_k(ω)⁻¹ Gᵀ serves every iteration; ũ recovered
    from the contact forces at the end), else on all DOFs; chord steps (:func:`sarfe.hbm.newton.
    newton`); the friction slider starts from ũ. ``options``: :class:`SolverOptions` as given
    (tolerance, max_iterations, line_search_steps; the caller sets its own budget).

    excitation f̃_e (2H+1, n) [N]. Returns (ũ' (2H+1, n) [m], NewtonResult): ũ' at the last
    accepted iterate, converged or not (the caller judges ``result.converged`` and
    ``result.residual_norm``), None when the residual at ũ is not finite. Raises
    :class:`sarfe.hbm.newton.SingularJacobian` when some S_k(ω) or the Jacobian is singular and
    ValueError (naming the parameter) for inputs of the wrong shape."""
    options = options or SolverOptions()
    problem = make_problem(model, contacts, excitation, harmonics, samples_per_period, options)
    U = np.asarray(U, dtype=float)
    evaluate, to_x, to_displacement = make_evaluator(problem, contacts.row_count > 0, False)
    state = {"slider": initial_slider(problem, U)}
    result = newton(lambda x, jacobian: evaluate(x, omega, jacobian, state["slider"]), to_x(U),
                    options, accept=slider_acceptor(state), chord=True)
    if result.evaluation is None:
        return None, result
    U_new = np.asarray(to_displacement(result.x, omega, result.evaluation))
    return U_new.reshape(U.shape), result
