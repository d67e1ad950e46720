r"""The stability of a converged periodic orbit: :func:`stability`, the one entry point, picks the
method of ``SolverOptions.stability_method`` and returns its :class:`StabilityResult`.

    'full'          Hill's quadratic eigenproblem (s² M̃ + s D̃ + ∂R/∂ũ) p̃ = 0 on all DOFs
                    (:mod:`sarfe.hbm.stability.hill`), with the friction memory 𝒥(s) refined;
    'condensed'     the same Hill problem on a bounded Ritz basis (:mod:`sarfe.hbm.stability.condensed`);
    'contact_rows'  the zeros of det(I + C(s) 𝒥(s)) right of −ε counted by the argument principle on
                    the contact rows (:mod:`sarfe.hbm.stability.rows`), located where there are any,
                    checked at the coarser contact coupling H' = ⌊3H/4⌋
                    (:mod:`sarfe.hbm.stability.trust`); the Ritz method where the count cannot
                    locate its zeros;
    'auto'          contact_rows for a model with contacts and a modal basis, else full up to 3000
                    Hill rows (:func:`sarfe.hbm.stability.trust.auto_method`).

Called by :func:`sarfe.hbm.solve.finalize` for every converged point, or later for a recorded
point by :func:`sarfe.hbm.stability.deferred.stability_of` (the same inputs: ``problem`` with all
harmonic rows, ω [rad/s], ũ (2H+1, n_dof) [m], the full-residual evaluation ``ev`` with its AFT
forces, the SolverOptions).
"""
from __future__ import annotations

from dataclasses import replace

import scipy.sparse as sp

from sarfe.hbm.aft import jacobian_matrix
from sarfe.hbm.stability.condensed import condensed_stability
from sarfe.hbm.stability.contact_terms import ContactOperator
from sarfe.hbm.stability.hill import hill_stability
from sarfe.hbm.stability.rows import contact_row_counts
from sarfe.hbm.stability.trust import auto_method, checked
from sarfe.hbm.stability.trust import check_harmonics as checked_harmonics


def contact_damping(problem, forces):
    """(I⊗G)ᵀ E diag(∂λ/∂ṙ) Φ (I⊗G) (sparse) of the rate-dependent laws, or None: the velocity
    terms of the contact forces in Hill's damping matrix (:mod:`sarfe.hbm.stability.hill`)."""
    if not forces.damping_blocks:
        return None
    G, H = problem.contacts.gap_map, problem.harmonics
    GG = sp.kron(sp.identity(2 * H + 1), G, format="csr")
    return (GG.T @ jacobian_matrix(forces.damping_blocks, G.shape[0], H) @ GG).tocsr()


def stability_method(problem, options) -> str:
    """'full' | 'condensed' | 'contact_rows' (see :class:`SolverOptions`): 'auto' is the contact-row
    count (:mod:`sarfe.hbm.stability.rows`) for every model with contacts and a modal basis, else
    the full Hill method up to 3000 Hill rows (:func:`sarfe.hbm.stability.trust.auto_method`)."""
    method = options.stability_method
    return auto_method(problem) if method == "auto" else method


def stability(problem, omega, U, ev, options):
    """StabilityResult (stable True | False | None, leading max Re s [1/s], note, exponents) of the
    converged orbit ũ = U (2H+1, n_dof) [m] at ω [rad/s] of ``problem`` (all harmonic rows), by
    ``options.stability_method`` (module docstring); ``ev``: its full-residual evaluation (the AFT
    forces; ∂R/∂ũ on all DOFs assembled where the method is 'full')."""
    operator = ContactOperator(problem, U, omega, ev.forces)
    method = stability_method(problem, options)
    if method == "contact_rows":
        result, zeros, coarse = contact_row_counts(
            problem.model, problem.contacts, omega, problem.harmonics, ev.forces, operator,
            tolerance=options.stability_tolerance,
            check_harmonics=checked_harmonics(problem.harmonics))
        if result is None:
            result = condensed_stability(problem.model, problem.contacts, omega, problem.harmonics,
                                         ev.forces, operator, tolerance=options.stability_tolerance)
            if zeros and result.stable is True:   # the count is exact, the Ritz basis truncated
                return replace(result, stable=None, note=(
                    f"the contact-row count finds {zeros} Floquet exponent(s) right of "
                    f"−1e-4·ω that the Ritz basis does not locate (it says {result.leading:.3g} 1/s)"))
        # the verdict at H stands where the count at a coarser contact coupling agrees
        return checked(result, zeros, coarse, problem)
    if method == "condensed":
        return condensed_stability(problem.model, problem.contacts, omega, problem.harmonics,
                                   ev.forces, operator, tolerance=options.stability_tolerance)
    return hill_stability(problem.model, omega, problem.harmonics, ev.jacobian,
                          options.stability_tolerance,
                          contact_damping=contact_damping(problem, ev.forces), operator=operator)

