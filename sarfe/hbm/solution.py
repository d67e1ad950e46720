r"""Options of the harmonic-balance solver and its result: one periodic solution at one ω.

All fields follow docs/design.md; SI units. Harmonic arrays use the convention of
:mod:`sarfe.hbm.harmonics` (rows 0, 1c, 1s, …, Hc, Hs).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SolverOptions:
    """Newton solver of R(ũ, ω) = S(ω) ũ + f̃_nl(ũ) − f̃_e = 0 at fixed ω.

    tolerance: converged when the residual of the iterated system is ≤ tolerance × its reference
        (‖f̃_e‖ uncondensed, ‖G S⁻¹ f̃_e‖ when condensed) **and** the residual of the full equation of
        motion on all DOFs, ‖S ũ + f̃_nl − f̃_e‖ / ‖f̃_e‖, is ≤ ``full_tolerance``.
    step_tolerance: also converged when the scaled Newton step ‖Δ‖/max(‖x‖, x_ref) falls below it
        while the residual is ≤ √tolerance (nonsmooth laws can stall at round-off).
    max_iterations: Newton iteration cap (a point hitting it is returned with converged=False).
    max_homotopy_iterations: cap on the Newton iterations of one cold-start homotopy (contact
        stiffness, then excitation level) when Newton fails from the linearized guess.
    line_search_steps: backtracking halvings of the step (α = 1, ½, …) on ‖R‖.
    condensation: 'auto' | True | False. Eliminate the linear DOFs through the dynamic compliance
        G S_k⁻¹ Gᵀ (Newton on the contact rows only). 'auto' condenses when that system is smaller
        than the full one and at most ``max_condensed_size`` unknowns.
    stability: compute Hill stability of the converged solution.
    stability_method: 'full' (the Hill eigenproblem on all DOFs, :mod:`sarfe.hbm.stability.hill`),
        'condensed' (Hill on a bounded Ritz basis, :mod:`sarfe.hbm.stability.condensed`),
        'contact_rows' (the exponents right of the axis counted on the contact rows,
        :mod:`sarfe.hbm.stability.rows`; the Ritz method where two or more are found; the verdict
        None where the count with the contact coupling at ⌊3H/4⌋ disagrees,
        :mod:`sarfe.hbm.stability.trust`) or 'auto': contact_rows for a model with contacts and a
        modal basis, else full up to 3000 Hill rows 2(2H+1)n.
    friction_tolerance, friction_pass_cap: 2-D slider march, stop when the slider state repeats to
        friction_tolerance × (max |q| + max ρ), at most friction_pass_cap periods.
    harmonic_set: None | 'all' | 'odd' | 'auto' | a list of orders: the harmonic orders solved for
        (the others held at zero, :mod:`sarfe.hbm.harmonic_set`). 'auto' solves the odd set and
        re-solves with all orders when the dropped-content estimate η exceeds
        ``harmonic_set_tolerance`` (relative force in the dropped orders; default 1 %, the
        'balanced' accuracy budget).
    """

    tolerance: float = 1e-9
    full_tolerance: float = 1e-6
    step_tolerance: float = 1e-12
    max_iterations: int = 50
    max_homotopy_iterations: int = 400
    line_search_steps: int = 8
    condensation: object = "auto"
    max_condensed_size: int = 2000
    stability: bool = True
    stability_tolerance: float = 1e-6
    stability_method: str = "auto"
    friction_tolerance: float = 1e-12
    friction_pass_cap: int = 50
    harmonic_set: object = None
    harmonic_set_tolerance: float = 1e-2


@dataclass(frozen=True)
class ContinuationOptions:
    """Pseudo-arclength continuation in ω (scaled arclength s, see :mod:`sarfe.hbm.continuation`).

    Unknowns are scaled as (x / x_scale, ω / |ω_end − ω_start|) with x_scale = ‖x‖ of the first
    point; the step Δs is a length in those units (Δs = 1 covers the whole range in ω).
    initial_step, min_step, max_step: Δs bounds. The step grows by ``step_growth`` when the corrector
    needed ≤ ``target_iterations`` iterations and shrinks by half when it needed more or failed.
    max_points: cap on the number of points returned (the sweep then stops, last point flagged in
    its reason). corrector_iterations: Newton cap of one corrector (a failed corrector halves Δs;
    the corrector also uses at most 3 line-search halvings). solver: SolverOptions of the correctors.
    Why 6 and 10 (were 4 and 5): the 12-pair door trim (15 mm, H = 15, 40 → 80 Hz, default case
    settings) crawled with 4 / 5 — its squeak correctors needed 3–5 iterations at any Δs — and
    stopped at max_points 2000 inside 40–45 Hz. The cause was a wrong Jacobian of stuck 2-D
    sliders (Newton converged linearly; fixed in :mod:`sarfe.hbm.laws.jenkins`); since then the
    band takes 105 points with 6 / 10 and 116 with 4 / 5, so 6 / 10 stay (the shipped cases and
    the continuation tests pass with either; rattle rig 367 → 363 points, complete either way).
    The defaults are those of a library call; ``sarfe solve`` always passes the case's
    ``solver.continuation`` (defaults in :class:`sarfe.case.config.ContinuationConfig`, max_step 0.1).
    """

    initial_step: float = 0.02
    min_step: float = 1e-6
    max_step: float = 0.25
    step_growth: float = 1.5
    target_iterations: int = 6
    max_points: int = 2000
    corrector_iterations: int = 10
    solver: SolverOptions = SolverOptions()


@dataclass(frozen=True)
class HarmonicSolution:
    """One periodic solution at frequency ω (fields as in docs/design.md).

    omega [rad/s]; harmonics H; samples_per_period N;
    displacement (2H+1, n_dof) [m] on all kept DOFs (recovered after condensation);
    contact_displacement (2H+1, n_rows) [m] r̃ = G ũ; contact_force (2H+1, n_rows) [N] λ̃;
    contact_force_time (N, n_rows) [N]; contact_state (N, n_c) int8 (0 open/separated,
    1 closed-or-stick, 2 slip); converged, reason, iterations,
    residual_norm = ‖S ũ + Gᵀλ̃ − f̃_e‖ / ‖f̃_e‖ on all DOFs; friction_passes (periods marched by
    the friction law in the last evaluation); stable (None if not computed); floquet_exponent
    [1/s] = largest real part of the kept Floquet exponents (nan if not computed);
    harmonic_orders: the orders solved for (tuple; None = all 0 … H), the others are zero;
    harmonic_set: 'all' | 'odd' | 'orders' — the set used; dropped_content: the estimate η of what
    the orders outside the set (outside the odd set, for an 'auto' solution that used all orders)
    carry, see :func:`sarfe.hbm.harmonic_set.dropped_content` (nan if not computed).
    Residual_norm and stability: residual of the kept rows; Hill stability of the full set.
    stability_note: why ``stable`` is None although stability was computed, or how the verdict was
    reached without a located leading exponent (``floquet_exponent`` NaN with the bound the
    contact-row count gives, a linear point, a verdict inferred from neighbours; '' otherwise).
    method: how the point was obtained — 'harmonic balance' (the Newton solve), 'linear' (exact
    solution without nonlinear contacts) or 'time integration' (the stand-in for a point whose
    engine call raised: iterations = periods integrated, residual_norm = periodicity error).
    stability_job: while the Hill stability is deferred (:mod:`sarfe.hbm.stability.deferred`), the index of
    its recorded job (``stable`` None until filled in); None otherwise.
    """

    omega: float
    harmonics: int
    samples_per_period: int
    displacement: np.ndarray
    contact_displacement: np.ndarray
    contact_force: np.ndarray
    contact_force_time: np.ndarray
    contact_state: np.ndarray
    converged: bool
    reason: str
    iterations: int
    residual_norm: float
    friction_passes: int = 0
    stable: object = None
    floquet_exponent: float = float("nan")
    harmonic_orders: tuple = None
    harmonic_set: str = "all"
    dropped_content: float = float("nan")
    stability_note: str = ""
    method: str = "harmonic balance"
    stability_job: int | None = None

    def amplitude(self, dof: int, harmonic: int = 1) -> float:
        """Amplitude √(u_kc² + u_ks²) of harmonic k of one DOF [m] (k = 0: the mean)."""
        if harmonic == 0:
            return float(abs(self.displacement[0, dof]))
        return float(np.hypot(self.displacement[2 * harmonic - 1, dof],
                              self.displacement[2 * harmonic, dof]))
