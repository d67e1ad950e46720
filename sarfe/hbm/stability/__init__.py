r"""sarfe.hbm.stability — is a converged periodic orbit stable? One entry point:

    result = stability(problem, omega, U, ev, options)     # StabilityResult(stable, leading, note, …)

A perturbation e^{st} p(θ) of the orbit obeys T(s) p̃ = (s² M̃ + s D̃ + S(ω) + (I⊗G)ᵀ 𝒥(s) (I⊗G)) p̃
= 0; the orbit is stable when every Floquet exponent s has Re s ≤ tolerance·ω (uncertain within
±10⁻⁴ω of 0).

Modules:
    select         :func:`stability` — the method of ``SolverOptions.stability_method``
    hill           Hill's eigenproblem on all DOFs (the 'full' method), StabilityResult, verdict
    condensed      the same Hill problem on a bounded Ritz basis (the 'condensed' method)
    contact_terms  the contact term 𝒥(s) of Hill's operator (AFT Jacobian, Jenkins memory at s)
    march          the compiled (numba) linearized slider march of 2-D Jenkins elements at many s
    rows           the contact-row count: zeros of det(I + C(s) 𝒥(s)) right of −ε, no eigen-solve
    determinant    det F(s) = det(I + C(s) 𝒥(s)) on the loaded contact rows, at many s at once
    contour        the argument principle: the half-strip's contour and the winding count along it
    zeros          locating the zeros the count found (a real one by its sign change; several by
                   Delves–Lyness power sums and Muller's method)
    trust          the default ('auto') method and its check at the coarser coupling H' = ⌊3H/4⌋
    deferred       stability recorded during a sweep and computed later (on worker processes)
    perturbation   an independent check: the monodromy of the time integrator's period map
"""
from sarfe.hbm.stability.select import stability, stability_method

__all__ = ["stability", "stability_method"]
